//! Every method's accuracy against the exact answers, per class of input: the tables of
//! `docs/accuracy.md`.
//!
//! ```text
//! cargo run --release --example accuracy [-- --lanes 1|4|8|16] [--write] [DIR]
//! ```
//!
//! Reads each class's vector file (`raylane_lab::vectors::accuracy::CLASSES`) from `DIR` (default
//! `tests/vectors`), runs every method of its kind, and prints the Markdown tables: the largest
//! relative `t` error and absolute `u`, `v` error against the exact answers, then the same over
//! each case's recorded conditioning. `tests/suite/kernels/accuracy_pinned.rs` pins this output
//! (`tests/suite/kernels/accuracy_pinned.md`, also the tables between the `accuracy` markers of
//! `docs/accuracy.md`); after a change to a kernel, `--write` rewrites both (run from the
//! repository root).

use std::process::ExitCode;

use raylane_lab::vectors::accuracy::{self, Class};
use raylane_lab::vectors::{Case, Method, Outcome};

fn main() -> ExitCode {
    let mut lanes = 1usize;
    let mut write = false;
    let mut dir = "tests/vectors".to_string();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--lanes" => match args.next().and_then(|s| s.parse().ok()) {
                Some(n @ (1 | 4 | 8 | 16)) => lanes = n,
                _ => {
                    eprintln!("usage: accuracy [--lanes 1|4|8|16] [--write] [DIR]");
                    return ExitCode::from(2);
                }
            },
            "--write" => write = true,
            d => dir = d.to_string(),
        }
    }
    let mut texts = Vec::new();
    for c in &accuracy::CLASSES {
        let path = format!("{dir}/{}.txt", c.file);
        match std::fs::read_to_string(&path) {
            Ok(t) => texts.push(t),
            Err(e) => {
                eprintln!("{path}: {e}");
                return ExitCode::from(2);
            }
        }
    }
    let mut cases = vec![Case::default(); 4096];
    let mut out = vec![Outcome::default(); 4096];
    let mut report = String::new();
    accuracy::write_report(&mut report, |m: Method, c: &Class| {
        let k = accuracy::CLASSES
            .iter()
            .position(|x| x == c)
            .expect("a class");
        accuracy::measure_text(m, lanes, &texts[k], &mut cases, &mut out)
            .unwrap_or_else(|| panic!("{dir}/{}.txt: cannot be read or evaluated", c.file))
    })
    .expect("a String accepts any text");
    print!("{report}");
    if write {
        if let Err(e) = write_pins(&report) {
            eprintln!("cannot write the pins: {e}");
            return ExitCode::FAILURE;
        }
        eprintln!(
            "wrote tests/suite/kernels/accuracy_pinned.md and the tables of docs/accuracy.md"
        );
    }
    ExitCode::SUCCESS
}

/// Writes the pinned tables and replaces those of `docs/accuracy.md` between its markers.
fn write_pins(report: &str) -> std::io::Result<()> {
    std::fs::write("tests/suite/kernels/accuracy_pinned.md", report)?;
    let doc = std::fs::read_to_string("docs/accuracy.md")?;
    let (begin, end) = ("<!-- accuracy:begin -->\n", "<!-- accuracy:end -->");
    let bad = || std::io::Error::other("docs/accuracy.md lacks the accuracy markers");
    let start = doc.find(begin).ok_or_else(bad)? + begin.len();
    let stop = start + doc[start..].find(end).ok_or_else(bad)?;
    let new = format!("{}{report}{}", &doc[..start], &doc[stop..]);
    std::fs::write("docs/accuracy.md", new)
}
