//! Runs the guard scene's frame `REPS` times, guarded or unguarded, for instruction counting:
//!
//! ```text
//! cargo build --release -p raylane-bench --example focal_ir
//! valgrind --tool=callgrind target/release/examples/focal_ir guarded 256 4   # (N, REPS)
//! ```
//!
//! Instructions per packet test = (count at REPS − count at 0) / REPS / (1536 packets · N).
use raylane::sphere::focal::{Focal, FocalUnguarded};
use raylane_bench::{GuardScene, guard_frame};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let guarded = args.get(1).is_none_or(|s| s == "guarded");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(64);
    let reps: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let s = GuardScene::new(n);
    let hits: u32 = (0..reps)
        .map(|_| {
            if guarded {
                guard_frame::<Focal>(&s.packets, &s.guarded)
            } else {
                guard_frame::<FocalUnguarded>(&s.packets, &s.unguarded)
            }
        })
        .sum();
    println!("{hits}");
}
