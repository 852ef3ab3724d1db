//! The vector checker.
//!
//! ```text
//! cargo run --release --example check -- [--method NAME] [--lanes 1|4|8|16] [--emit] FILE...
//! ```
//!
//! Evaluates every case of the files with one method (default: the recommended general
//! method of each kind) at one lane width, cases batched into the lanes. Prints each failing
//! case (with its tolerance per value: relative for `t`, absolute for `u`, `v`, widened by the
//! line's recorded conditioning, see `raylane_lab::vectors::tolerance`), the number of cases
//! outside the method's documented limits, and a closing line
//! `N passed, M failed`; exits non-zero on any failure. With `--emit` it compares nothing and
//! prints one line per case, in file order: `miss` or the computed values (shortest round-trip
//! decimals), or `n/a` where the method does not apply to the line's kind. With
//! `--ignore-limits` every applicable case is compared, inside the method's limits or not
//! (to see where a method fails). `--list` prints the method names.

use std::process::ExitCode;

use raylane_lab::vectors::{self, Case, Kind, Method, Outcome, Verdict};

fn usage() -> ExitCode {
    let names: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
    eprintln!(
        "usage: check [--method {}] [--lanes 1|4|8|16] [--emit] [--ignore-limits] FILE...",
        names.join("|")
    );
    ExitCode::from(2)
}

/// The command line.
struct Options {
    /// The method asked for (`None`: the recommended one per kind).
    method: Option<Method>,
    lanes: usize,
    emit: bool,
    ignore_limits: bool,
    files: Vec<String>,
}

impl Options {
    /// Parses the arguments; `Err` is the exit code (usage, or `--list` done).
    fn parse() -> Result<Options, ExitCode> {
        let mut o = Options {
            method: None,
            lanes: 1,
            emit: false,
            ignore_limits: false,
            files: Vec::new(),
        };
        let mut args = std::env::args().skip(1);
        while let Some(a) = args.next() {
            match a.as_str() {
                "--method" => match args.next().as_deref().and_then(Method::from_name) {
                    Some(m) => o.method = Some(m),
                    None => return Err(usage()),
                },
                "--lanes" => match args.next().and_then(|s| s.parse().ok()) {
                    Some(n @ (1 | 4 | 8 | 16)) => o.lanes = n,
                    _ => return Err(usage()),
                },
                "--emit" => o.emit = true,
                "--list" => {
                    Method::ALL.iter().for_each(|m| println!("{}", m.name()));
                    return Err(ExitCode::SUCCESS);
                }
                "--ignore-limits" => o.ignore_limits = true,
                "-h" | "--help" => return Err(usage()),
                f => o.files.push(f.to_string()),
            }
        }
        if o.files.is_empty() {
            return Err(usage());
        }
        Ok(o)
    }

    /// The method for a kind: the one asked for, or the recommended one.
    fn pick(&self, k: Kind) -> Option<Method> {
        self.method.or(Method::recommended(k))
    }
}

/// A file's text and cases; `Err` is the exit code after the message.
fn load(file: &str) -> Result<(String, Vec<Case>), ExitCode> {
    let text = std::fs::read_to_string(file).map_err(|e| {
        eprintln!("{file}: {e}");
        ExitCode::from(2)
    })?;
    let mut cases: Vec<Case> = Vec::new();
    for (line, r) in vectors::cases(&text) {
        match r {
            Ok(c) => cases.push(c),
            Err(e) => {
                eprintln!("{file}:{line}: cannot parse ({e:?})");
                return Err(ExitCode::from(2));
            }
        }
    }
    Ok((text, cases))
}

/// Every case's outcome with its kind's method, the cases of each kind batched together.
fn evaluate(o: &Options, cases: &[Case]) -> Vec<Outcome> {
    let mut out = vec![Outcome::default(); cases.len()];
    for kind in [Kind::Sphere, Kind::Plane, Kind::Triangle] {
        let Some(m) = o.pick(kind) else { continue };
        let idx: Vec<usize> = (0..cases.len())
            .filter(|&i| cases[i].kind == kind)
            .collect();
        let sub: Vec<Case> = idx.iter().map(|&i| cases[i]).collect();
        let mut res = vec![Outcome::default(); sub.len()];
        vectors::evaluate(m, o.lanes, &sub, &mut res);
        for (k, &i) in idx.iter().enumerate() {
            out[i] = res[k];
        }
    }
    out
}

/// The counts over every file.
#[derive(Default)]
struct Report {
    passed: usize,
    failed: usize,
    skipped: Vec<(&'static str, usize)>,
}

impl Report {
    /// Compares (or with `--emit` prints) the outcomes of one file.
    fn file(&mut self, o: &Options, file: &str, text: &str, cases: &[Case], out: &[Outcome]) {
        let lines: Vec<&str> = text.lines().collect();
        for (c, got) in cases.iter().zip(out) {
            let Some(m) = o.pick(c.kind) else {
                if o.emit {
                    println!("n/a");
                } else {
                    bump(&mut self.skipped, "no method for this kind yet");
                }
                continue;
            };
            if o.emit {
                if got.applicable {
                    println!("{}", got.values)
                } else {
                    println!("n/a")
                }
                continue;
            }
            match verdict(o, m, c, got) {
                Verdict::Pass => self.passed += 1,
                Verdict::Fail => {
                    self.failed += 1;
                    let line = lines[c.line as usize - 1].trim();
                    print_failure(file, m, line, c, got);
                }
                Verdict::Skip(why) => bump(&mut self.skipped, why),
            }
        }
    }
}

/// The verdict on one case (every applicable case compared with `--ignore-limits`).
fn verdict(o: &Options, m: Method, c: &Case, got: &Outcome) -> Verdict {
    if o.ignore_limits && got.applicable {
        if vectors::matches(c, &got.values) {
            Verdict::Pass
        } else {
            Verdict::Fail
        }
    } else {
        vectors::compare(m, c, got)
    }
}

fn print_failure(file: &str, m: Method, line: &str, c: &Case, got: &Outcome) {
    let tol: Vec<String> = (0..c.expect.n as usize)
        .map(|k| format!("{:.1e}", vectors::tolerance(c, k)))
        .collect();
    println!(
        "FAIL {file}:{} [{}]: {line}\n     expected {}, got {} (tolerance {})",
        c.line,
        m.name(),
        c.expect,
        got.values,
        if tol.is_empty() {
            "-".to_string()
        } else {
            tol.join(" ")
        }
    );
}

fn main() -> ExitCode {
    let o = match Options::parse() {
        Ok(o) => o,
        Err(code) => return code,
    };
    let mut report = Report::default();
    for file in &o.files {
        let (text, cases) = match load(file) {
            Ok(x) => x,
            Err(code) => return code,
        };
        let out = evaluate(&o, &cases);
        report.file(&o, file, &text, &cases, &out);
    }
    if o.emit {
        return ExitCode::SUCCESS;
    }
    let label = o
        .method
        .map_or("recommended per kind".to_string(), |m| m.name().to_string());
    for (why, n) in &report.skipped {
        println!("{n} outside the limits of {label}: {why}");
    }
    println!("{} passed, {} failed", report.passed, report.failed);
    if report.failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

fn bump(v: &mut Vec<(&'static str, usize)>, why: &'static str) {
    match v.iter_mut().find(|(w, _)| *w == why) {
        Some((_, n)) => *n += 1,
        None => v.push((why, 1)),
    }
}
