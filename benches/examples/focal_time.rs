//! Interleaved timing of guarded vs unguarded focal caches (min over rounds), a noise-robust
//! complement to the criterion bench: `cargo run --release -p raylane-bench --example focal_time`.
use std::hint::black_box;
use std::time::Instant;

use raylane::sphere::focal::{Focal, FocalUnguarded};
use raylane_bench::{GuardScene, guard_frame};

fn main() {
    for n in [16usize, 64, 256] {
        let s = GuardScene::new(n);
        let (mut best_g, mut best_u) = (f64::MAX, f64::MAX);
        // Alternate which variant runs first in a round, so order effects cancel out.
        for round in 0..80 {
            for unguarded in [round % 2 == 0, round % 2 == 1] {
                let t = Instant::now();
                black_box(if unguarded {
                    guard_frame::<FocalUnguarded>(&s.packets, &s.unguarded)
                } else {
                    guard_frame::<Focal>(&s.packets, &s.guarded)
                });
                let e = t.elapsed().as_secs_f64();
                if unguarded {
                    best_u = best_u.min(e)
                } else {
                    best_g = best_g.min(e)
                }
            }
        }
        let tests = s.tests() as f64;
        println!(
            "n={n:3}: unguarded {:.0} Mtests/s, guarded {:.0} Mtests/s, guarded/unguarded time {:.3}",
            tests / best_u / 1e6,
            tests / best_g / 1e6,
            best_g / best_u
        );
    }
}
