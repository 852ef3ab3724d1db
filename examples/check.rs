//! The vector checker.
//!
//! ```text
//! cargo run --release --example check -- [--method NAME] [--lanes 1|4|8|16] [--emit] FILE...
//! ```
//!
//! Evaluates every case of the files with one method (default: the recommended general
//! method of each kind) at one lane width, cases batched into the lanes. Prints each failing
//! case (with its tolerance per value: relative for `t`, absolute for `u`, `v`, widened by the
//! line's recorded conditioning, see `raylane::vectors::tolerance`), the number of cases
//! outside the method's documented limits, and a closing line
//! `N passed, M failed`; exits non-zero on any failure. With `--emit` it compares nothing and
//! prints one line per case, in file order: `miss` or the computed values (shortest round-trip
//! decimals), or `n/a` where the method does not apply to the line's kind. With
//! `--ignore-limits` every applicable case is compared, inside the method's limits or not
//! (to see where a method fails). `--list` prints the method names.

use std::process::ExitCode;

use raylane::vectors::{self, Case, Kind, Method, Outcome, Verdict};

fn usage() -> ExitCode {
    let names: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
    eprintln!(
        "usage: check [--method {}] [--lanes 1|4|8|16] [--emit] [--ignore-limits] FILE...",
        names.join("|")
    );
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let mut method: Option<Method> = None;
    let mut lanes = 1usize;
    let mut emit = false;
    let mut ignore_limits = false;
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--method" => match args.next().as_deref().and_then(Method::from_name) {
                Some(m) => method = Some(m),
                None => return usage(),
            },
            "--lanes" => match args.next().and_then(|s| s.parse().ok()) {
                Some(n @ (1 | 4 | 8 | 16)) => lanes = n,
                _ => return usage(),
            },
            "--emit" => emit = true,
            "--list" => {
                Method::ALL.iter().for_each(|m| println!("{}", m.name()));
                return ExitCode::SUCCESS;
            }
            "--ignore-limits" => ignore_limits = true,
            "-h" | "--help" => return usage(),
            f => files.push(f.to_string()),
        }
    }
    if files.is_empty() {
        return usage();
    }

    let (mut passed, mut failed) = (0usize, 0usize);
    let mut skipped: Vec<(&'static str, usize)> = Vec::new();
    for file in &files {
        let text = match std::fs::read_to_string(file) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("{file}: {e}");
                return ExitCode::from(2);
            }
        };
        let mut cases: Vec<Case> = Vec::new();
        for (line, r) in vectors::cases(&text) {
            match r {
                Ok(c) => cases.push(c),
                Err(e) => {
                    eprintln!("{file}:{line}: cannot parse ({e:?})");
                    return ExitCode::from(2);
                }
            }
        }
        // One method per kind: the one asked for, or the recommended one.
        let pick = |k: Kind| method.or(Method::recommended(k));
        let mut out = vec![Outcome::default(); cases.len()];
        for kind in [Kind::Sphere, Kind::Plane, Kind::Triangle] {
            let Some(m) = pick(kind) else { continue };
            let idx: Vec<usize> = (0..cases.len())
                .filter(|&i| cases[i].kind == kind)
                .collect();
            let sub: Vec<Case> = idx.iter().map(|&i| cases[i]).collect();
            let mut res = vec![Outcome::default(); sub.len()];
            vectors::evaluate(m, lanes, &sub, &mut res);
            for (k, &i) in idx.iter().enumerate() {
                out[i] = res[k];
            }
        }
        let lines: Vec<&str> = text.lines().collect();
        for (c, o) in cases.iter().zip(&out) {
            let Some(m) = pick(c.kind) else {
                if emit {
                    println!("n/a");
                } else {
                    bump(&mut skipped, "no method for this kind yet");
                }
                continue;
            };
            if emit {
                if o.applicable {
                    println!("{}", o.values)
                } else {
                    println!("n/a")
                }
                continue;
            }
            let verdict = if ignore_limits && o.applicable {
                if vectors::matches(c, &o.values) {
                    Verdict::Pass
                } else {
                    Verdict::Fail
                }
            } else {
                vectors::compare(m, c, o)
            };
            match verdict {
                Verdict::Pass => passed += 1,
                Verdict::Fail => {
                    failed += 1;
                    let tol: Vec<String> = (0..c.expect.n as usize)
                        .map(|k| format!("{:.1e}", vectors::tolerance(c, k)))
                        .collect();
                    println!(
                        "FAIL {file}:{} [{}]: {}\n     expected {}, got {} (tolerance {})",
                        c.line,
                        m.name(),
                        lines[c.line as usize - 1].trim(),
                        c.expect,
                        o.values,
                        if tol.is_empty() {
                            "-".to_string()
                        } else {
                            tol.join(" ")
                        }
                    );
                }
                Verdict::Skip(why) => bump(&mut skipped, why),
            }
        }
    }
    if emit {
        return ExitCode::SUCCESS;
    }
    let label = method.map_or("recommended per kind".to_string(), |m| m.name().to_string());
    for (why, n) in &skipped {
        println!("{n} outside the limits of {label}: {why}");
    }
    println!("{passed} passed, {failed} failed");
    if failed == 0 {
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
