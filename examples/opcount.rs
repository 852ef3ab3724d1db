//! The operation-count report: every kernel's multiplies, additions (subtractions included),
//! divisions, square roots and compares per lane per test, on a miss and on a hit, measured by
//! running the kernels with the op-counting lane `Counted<f32>` (see `raylane::opcount`), then
//! the study table of every published method beside raylane's own (`raylane::study`): counts,
//! bytes and precomputation per primitive, accuracy per input class, and watertightness.
//!
//! ```text
//! cargo run --example opcount            # the two Markdown tables (the README's)
//! cargo run --example opcount -- --csv   # the report as kernel,path,mul,add,div,sqrt,cmp
//! cargo run --example opcount -- --write # rewrites the README's study table (from the root)
//! ```

// The study table's accuracy and watertightness come from the test suite's own harnesses,
// included here so that the example and the pin test measure with the same code.
#[allow(dead_code)]
#[path = "../tests/suite/watertight.rs"]
mod watertight;

#[allow(dead_code)]
#[path = "../tests/suite/study.rs"]
mod study;

fn main() {
    let csv = std::env::args().any(|a| a == "--csv");
    let write = std::env::args().any(|a| a == "--write");
    let mut out = String::new();
    raylane::opcount::write_report(&mut out, &raylane::opcount::table(), csv)
        .expect("a String accepts any text");
    print!("{out}");
    if csv {
        return;
    }
    let table = study::report();
    print!("\n{table}");
    if write {
        let readme = std::fs::read_to_string("README.md").expect("run from the repository root");
        let (start, stop) = study::readme_section(&readme);
        let new = format!("{}{table}{}", &readme[..start], &readme[stop..]);
        std::fs::write("README.md", new).expect("README.md is writable");
        eprintln!("wrote the README's study table");
    }
}
