//! Interleaved timing of guarded vs unguarded focal caches (min over rounds), a noise-robust
//! complement to the criterion bench: `cargo run --release -p raylane-bench --example focal_time`.
use std::hint::black_box;
use std::time::Instant;

use raylane::Ray8;
use raylane::sphere::FocalSphere;
use raylane::sphere::focal::{self, Focal, FocalUnguarded};
use raylane_bench::sphere_scene;

fn main() {
    for n in [16usize, 64, 256] {
        let (cam, spheres) = sphere_scene(n, 7, 128, 96);
        let packets: Vec<Ray8> = (0..cam.height)
            .flat_map(|y| (0..cam.width).step_by(8).map(move |x| (x, y)))
            .map(|(x, y)| cam.row_packet(x, y))
            .collect();
        let g: Vec<FocalSphere<f32>> = spheres
            .iter()
            .map(|s| FocalSphere::new(cam.eye, s))
            .collect();
        let u: Vec<FocalSphere<f32>> = spheres
            .iter()
            .map(|s| FocalSphere::unguarded(cam.eye, s))
            .collect();
        let (mut best_g, mut best_u) = (f64::MAX, f64::MAX);
        // Alternate which variant runs first in a round, so order effects cancel out.
        for round in 0..80 {
            for first in [round % 2 == 0, round % 2 == 1] {
                let t = Instant::now();
                let mut h = 0u32;
                if first {
                    for p in &packets {
                        h += focal::closest::<FocalUnguarded, _>(black_box(p), &u)
                            .mask
                            .to_bitmask()
                            .count_ones();
                    }
                } else {
                    for p in &packets {
                        h += focal::closest::<Focal, _>(black_box(p), &g)
                            .mask
                            .to_bitmask()
                            .count_ones();
                    }
                }
                black_box(h);
                let e = t.elapsed().as_secs_f64();
                if first {
                    best_u = best_u.min(e)
                } else {
                    best_g = best_g.min(e)
                }
            }
        }
        let tests = (packets.len() * 8 * n) as f64;
        println!(
            "n={n:3}: unguarded {:.0} Mtests/s, guarded {:.0} Mtests/s, guarded/unguarded time {:.3}",
            tests / best_u / 1e6,
            tests / best_g / 1e6,
            best_g / best_u
        );
    }
}
