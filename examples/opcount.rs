//! The operation-count report: every kernel's multiplies, additions (subtractions included),
//! divisions, square roots and compares per lane per test, on a miss and on a hit, measured by
//! running the kernels with the op-counting lane `Counted<f32>` (see `raylane::opcount`).
//!
//! ```text
//! cargo run --example opcount            # a Markdown table (the README's)
//! cargo run --example opcount -- --csv   # kernel,path,mul,add,div,sqrt,cmp
//! ```

fn main() {
    let csv = std::env::args().any(|a| a == "--csv");
    let mut out = String::new();
    raylane::opcount::write_report(&mut out, &raylane::opcount::table(), csv)
        .expect("a String accepts any text");
    print!("{out}");
}
