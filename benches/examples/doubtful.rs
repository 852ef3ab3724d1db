//! How many ray–sphere tests of the benchmark scenes take each focal path (measured with the
//! counting lane: the f64 fallback is the only path with a division).
use raylane::opcount::{Counted, measure};
use raylane::sphere::FocalSphere;
use raylane::sphere::focal::{Focal, FocalKernel};
use raylane::{Mask, RayPacket};
use raylane_bench::GuardScene;
fn main() {
    for n in [16usize, 64, 256] {
        let GuardScene {
            cam,
            guarded: cache,
            ..
        } = GuardScene::new(n);
        let (mut tests, mut perp, mut doubtful, mut hits) = (0u64, 0u64, 0u64, 0u64);
        for y in 0..cam.height {
            for x in 0..cam.width {
                let p: RayPacket<f32> = cam.row_packet(x, y);
                let pc = RayPacket::<Counted<f32>>::splat(&p.ray(0));
                for e in &cache {
                    tests += 1;
                    let (r, c) = measure(|| Focal::roots(&pc, &FocalSphere::splat(e)));
                    hits += r.any().any() as u64;
                    perp += (c.mul > 4) as u64;
                    doubtful += (c.div > 0) as u64;
                }
            }
        }
        println!(
            "n={n}: tests {tests}, past the cheap test {perp} ({:.3}%), hits {hits}, doubtful {doubtful} ({:.4}% of tests, {:.2}% of hits)",
            100.0 * perp as f64 / tests as f64,
            100.0 * doubtful as f64 / tests as f64,
            100.0 * doubtful as f64 / hits.max(1) as f64
        );
    }
}
