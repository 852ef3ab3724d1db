//! The focal guard's cost on general scenes: guarded vs unguarded focal caches, closest hit of
//! 8-ray packets of primary rays over N spheres (issue: within 10% of the unguarded speed).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raylane::Ray8;
use raylane::sphere::FocalSphere;
use raylane::sphere::focal::{self, Focal, FocalUnguarded};
use raylane_bench::sphere_scene;

fn bench(c: &mut Criterion) {
    for n in [16usize, 64, 256] {
        let (cam, spheres) = sphere_scene(n, 7, 128, 96);
        let packets: Vec<Ray8> = (0..cam.height)
            .flat_map(|y| (0..cam.width).step_by(8).map(move |x| (x, y)))
            .map(|(x, y)| cam.row_packet(x, y))
            .collect();
        let guarded: Vec<FocalSphere<f32>> = spheres
            .iter()
            .map(|s| FocalSphere::new(cam.eye, s))
            .collect();
        let unguarded: Vec<FocalSphere<f32>> = spheres
            .iter()
            .map(|s| FocalSphere::unguarded(cam.eye, s))
            .collect();
        let mut g = c.benchmark_group(format!("focal-guard/{n}"));
        g.throughput(Throughput::Elements((packets.len() * 8 * n) as u64));
        g.bench_function("unguarded", |b| {
            b.iter(|| {
                let mut hits = 0u32;
                for p in &packets {
                    hits += focal::closest::<FocalUnguarded, _>(black_box(p), &unguarded)
                        .mask
                        .to_bitmask()
                        .count_ones();
                }
                hits
            })
        });
        g.bench_function("guarded", |b| {
            b.iter(|| {
                let mut hits = 0u32;
                for p in &packets {
                    hits += focal::closest::<Focal, _>(black_box(p), &guarded)
                        .mask
                        .to_bitmask()
                        .count_ones();
                }
                hits
            })
        });
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
