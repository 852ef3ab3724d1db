//! Runs the focal benchmark loop `REPS` times, guarded or unguarded, for instruction counting:
//!
//! ```text
//! cargo build --release -p raylane-bench --example focal_ir
//! valgrind --tool=callgrind target/release/examples/focal_ir guarded 256 4   # (N, REPS)
//! ```
//!
//! Instructions per packet test = (count at REPS − count at 0) / REPS / (1536 packets · N).
use raylane::Ray8;
use raylane::sphere::FocalSphere;
use raylane::sphere::focal::{self, Focal, FocalUnguarded};
use raylane_bench::sphere_scene;
use std::hint::black_box;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let guarded = args.get(1).map(|s| s == "guarded").unwrap_or(true);
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(64);
    let reps: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let (cam, spheres) = sphere_scene(n, 7, 128, 96);
    let packets: Vec<Ray8> = (0..cam.height)
        .flat_map(|y| (0..cam.width).step_by(8).map(move |x| (x, y)))
        .map(|(x, y)| cam.row_packet(x, y))
        .collect();
    let cache: Vec<FocalSphere<f32>> = spheres
        .iter()
        .map(|s| {
            if guarded {
                FocalSphere::new(cam.eye, s)
            } else {
                FocalSphere::unguarded(cam.eye, s)
            }
        })
        .collect();
    let mut hits = 0u32;
    for _ in 0..reps {
        for p in &packets {
            hits += if guarded {
                focal::closest::<Focal, _>(black_box(p), &cache)
            } else {
                focal::closest::<FocalUnguarded, _>(black_box(p), &cache)
            }
            .mask
            .to_bitmask()
            .count_ones();
        }
    }
    println!("{hits}");
}
