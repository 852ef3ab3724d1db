//! Digests of every method at every lane width over every vector file, for comparing targets.
//!
//! ```text
//! cargo run --release --features vectors --example digest [-- DIR]   # default tests/vectors
//! ```
//!
//! Prints `digest METHOD xLANES HEX` (FNV-1a over the bits of every computed result, files in
//! name order, cases in file order) and `tally METHOD N passed, M failed`. The firmware under
//! `targets/` prints the same lines; equal lines mean bit-identical results.

use std::process::ExitCode;

use raylane_lab::vectors::{self, Case, Digest, LANE_WIDTHS, Method, Outcome, Tally};

fn main() -> ExitCode {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "tests/vectors".into());
    let mut names: Vec<_> = match std::fs::read_dir(&dir) {
        Ok(d) => d
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "txt"))
            .collect(),
        Err(e) => {
            eprintln!("{dir}: {e}");
            return ExitCode::from(2);
        }
    };
    names.sort();
    let mut files: Vec<Vec<Case>> = Vec::new();
    for p in &names {
        let text = std::fs::read_to_string(p).expect("readable vector file");
        let mut buf = vec![
            vectors::parse_line("plane 0 0 0 1 0 0 1 0 0 1 0 0 -> 1", 0)
                .unwrap()
                .unwrap();
            4096
        ];
        match vectors::load(&text, &mut buf) {
            Ok(n) => files.push(buf[..n].to_vec()),
            Err((line, e)) => {
                eprintln!("{}:{line}: {e:?}", p.display());
                return ExitCode::from(2);
            }
        }
    }
    let mut failed = 0;
    for m in Method::ALL {
        let mut total = Tally::default();
        for lanes in LANE_WIDTHS {
            let mut d = Digest::new();
            let mut t = Tally::default();
            for cases in &files {
                let mut out = vec![Outcome::default(); cases.len()];
                let r =
                    vectors::check(m, lanes, cases, &mut out, &mut d).expect("a supported width");
                t.passed += r.passed;
                t.failed += r.failed;
            }
            println!("digest {} x{lanes} {:016x}", m.name(), d.value());
            total = t;
            failed += t.failed;
        }
        println!(
            "tally {} {} passed, {} failed",
            m.name(),
            total.passed,
            total.failed
        );
    }
    if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
