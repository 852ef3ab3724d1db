//! The operation-count report: every kernel's multiplies, additions (subtractions included),
//! divisions, square roots and compares per lane per test, on a miss and on a hit, measured by
//! running the kernels with the op-counting lane `Counted<f32>` (see `raylane::opcount`), then
//! the study table of every published method beside raylane's own (`raylane_lab::study`): counts,
//! bytes and precomputation per primitive, accuracy per input class, and watertightness.
//!
//! ```text
//! cargo run --example opcount            # the two Markdown tables (docs/opcounts.md's)
//! cargo run --example opcount -- --csv   # the report as kernel,path,mul,add,div,sqrt,cmp
//! cargo run --example opcount -- --write # rewrites both tables of docs/opcounts.md (from root)
//! opcount --measure                       # the study's timed loops (scripts/count-study.sh)
//! ```
//!
//! The study table's instruction columns are not measured here: `scripts/count-study.sh` counts
//! them (callgrind on x86-64-v3, the QEMU plugin on a Cortex-M4F) and stores them in
//! `docs/study-insns.txt`, which this example reads.

// The study table's accuracy and watertightness come from the test suite's own harnesses,
// included here so that the example and the pin test measure with the same code.
#[allow(dead_code)]
#[path = "../tests/suite/kernels/watertight_no_leaks.rs"]
mod watertight_no_leaks;

#[allow(dead_code)]
#[path = "../tests/suite/kernels/op_count_study.rs"]
mod study;

/// Every study method (`raylane_lab::study::KERNELS`, in the registry's order) on both paths
/// (and its precomputation, if any), each one out-of-line call of `raylane_lab::study::repeat`
/// over 64 iterations and one over none, in 8 lanes, each call announced by a
/// `cfg SHAPE METHOD PATH UNITS N` line (`UNITS` tests or builds per iteration; under
/// callgrind, dump k is call k).
fn measure() {
    use raylane_lab::study::{self, KERNELS, PATHS, Path};
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    for k in KERNELS {
        let (shape, method) = (k.prim().name(), k.method().name());
        for (path, name) in PATHS {
            if path == Path::Precompute && !study::precomputes(k) {
                continue;
            }
            let units = study::units::<wide::f32x8>(k, path);
            for n in [64, 0] {
                writeln!(out, "cfg {shape} {method} {name} {units} {n}").expect("stdout");
                out.flush().expect("stdout");
                let done = study::repeat::<wide::f32x8>(
                    std::hint::black_box(k),
                    std::hint::black_box(path),
                    std::hint::black_box(n),
                );
                let miss = path == Path::Miss;
                assert_eq!(done, Some(if miss { 0 } else { (units * n) as u32 }));
            }
        }
    }
}

fn main() {
    if std::env::args().any(|a| a == "--measure") {
        return measure();
    }
    let csv = std::env::args().any(|a| a == "--csv");
    let write = std::env::args().any(|a| a == "--write");
    let mut out = String::new();
    raylane_lab::opcount::write_report(&mut out, &raylane_lab::opcount::table(), csv)
        .expect("a String accepts any text");
    print!("{out}");
    if csv {
        return;
    }
    let table = study::report();
    print!("\n{table}");
    if write {
        let doc = std::fs::read_to_string(DOC).expect("run from the repository root");
        let doc = replace_between(&doc, OPCOUNT_BEGIN, OPCOUNT_END, &out);
        let (start, stop) = study::doc_section(&doc);
        let doc = format!("{}{table}{}", &doc[..start], &doc[stop..]);
        std::fs::write(DOC, doc).expect("docs/opcounts.md is writable");
        eprintln!("wrote the op-count and study tables of {DOC}");
    }
}

/// The page that holds both tables, between their markers.
const DOC: &str = "docs/opcounts.md";
/// The markers around the op-count report (pinned by `tests/suite/docs/op_count_table.rs`).
const OPCOUNT_BEGIN: &str = "<!-- opcount:begin -->\n";
/// The end marker.
const OPCOUNT_END: &str = "<!-- opcount:end -->";

/// `doc` with the text between `begin` and `end` replaced by `text`.
fn replace_between(doc: &str, begin: &str, end: &str, text: &str) -> String {
    let start = doc
        .find(begin)
        .unwrap_or_else(|| panic!("{DOC} lacks the marker {begin:?}"))
        + begin.len();
    let stop = doc[start..]
        .find(end)
        .unwrap_or_else(|| panic!("{DOC} lacks the marker {end:?}"))
        + start;
    format!("{}{text}{}", &doc[..start], &doc[stop..])
}
