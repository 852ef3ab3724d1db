//! Instructions per ray–primitive test, deterministic: every kernel at every lane width and in
//! both packet shapes, each frame one out-of-line call, run once over N = 64 primitives and
//! once over none; the difference divided by the tests is the cost of one test (per-ray setup
//! and the loop's entry and exit cancel out).
//!
//! ```text
//! count measure [KERNEL] run every configuration (of one kernel), one frame call each, printing one
//!                        `cfg KERNEL WIDTH SHAPE RAYS USED TESTS` line before each call
//!                        (under callgrind: one dump per call, see scripts/count-x86.sh)
//! count table FILE TITLE print the Markdown table from `cfg ... INSTRUCTIONS` lines
//! count ops              the op counts per test of every kernel on both ray sets
//! count digest           a digest of the scene's bits (the firmware prints the same)
//! count check PIN NEW    every count of the table NEW against the pinned table PIN: fails
//!                        (exit 1) when one rose more than 3 % above its pin, or is missing
//! ```
//!
//! The pins are `benches/counts/*.md` (the tables as `table` prints them); `scripts/test.sh`
//! recounts and checks them. A deliberate change updates the pin in the same commit.
//!
//! The scene: 64 spheres, triangles and planes, a 32 × 32 camera ([`Frame::with_image`]);
//! `coherent` is every primary ray, `miss` the primary rays whose lines clearly miss every
//! sphere and triangle (every test takes its kernel's miss path).
//!
//! The minimum beside each count is what the op count implies: (FP operations per test —
//! mul, add, div, sqrt and compares, counted with `Counted<f32>` on the same rays, each ray
//! on its own path — plus the primitive fields the miss path loads) / lanes.

use std::collections::BTreeMap;

use raylane::Lane;
use raylane_bench::{BenchKernel, Frame, Kernel, Lanes, Rays, Shape, frame_ops, with_width};

/// Primitives of each kind in the counted scene.
const N: usize = 64;
/// Its camera's side.
const SIDE: u32 = 32;
/// The ray sets.
const RAYS: [Rays; 2] = [Rays::Miss, Rays::Coherent];

fn frames() -> Vec<Frame> {
    RAYS.iter()
        .map(|&r| Frame::with_image(N, r, SIDE, SIDE))
        .collect()
}

/// The table's name of a kernel's shape: `query` (N rays × 1 primitive through the library's
/// `Query`), `loop` (the same shape through the lab's loop, for the kernel without a public
/// set) or `soa` (1 ray × N primitives, the lab's loop: the kernel alone).
fn shape_name(k: Kernel, s: Shape) -> &'static str {
    match s {
        Shape::Packets if k.has_query() => "query",
        Shape::Packets => "loop",
        Shape::Soa => "soa",
    }
}

/// The shapes in table order.
const SHAPES: [&str; 3] = ["query", "loop", "soa"];

fn measure_one<L: Lane<Scalar = f32>>(k: Kernel, shape: Shape, f: &Frame) {
    for used in [N, 0] {
        let lanes = Lanes::<L>::new(f, used);
        let tests = f.rays.len() * used;
        println!(
            "cfg {} {} {} {} {used} {tests}",
            k.name(),
            L::LANES,
            shape_name(k, shape),
            f.kind.name()
        );
        std::hint::black_box(raylane_bench::run(k, shape, f, &lanes));
    }
}

/// `count measure [KERNEL]`: every kernel, or the one named (for a closer look under a
/// profiler).
fn measure(only: Option<&str>) {
    for f in frames() {
        for k in Kernel::ALL {
            if only.is_some_and(|name| name != k.name()) {
                continue;
            }
            for w in raylane_bench::WIDTHS {
                for shape in [Shape::Packets, Shape::Soa] {
                    if shape == Shape::Soa && !k.has_soa() {
                        continue;
                    }
                    with_width!(w, L => measure_one::<L>(k, shape, &f));
                }
            }
        }
    }
}

/// FP operations (with compares) per test of each kernel on each ray set.
fn ops() -> BTreeMap<(String, String), (f64, raylane::opcount::OpCounts)> {
    let mut out = BTreeMap::new();
    for f in frames() {
        for k in Kernel::ALL {
            let c = frame_ops(k, &f, N).minus(&frame_ops(k, &f, 0));
            let per = (c.flops() + c.cmp) as f64 / f.tests() as f64;
            out.insert((k.name().to_string(), f.kind.name().to_string()), (per, c));
        }
    }
    out
}

fn table(file: &str, title: &str) {
    let text = std::fs::read_to_string(file).expect("readable input");
    // (kernel, width, shape, rays) -> (instructions at N, at 0, tests)
    let mut runs: BTreeMap<(String, usize, String, String), [u64; 3]> = BTreeMap::new();
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        if w.len() != 8 || w[0] != "cfg" {
            continue;
        }
        let key = (
            w[1].to_string(),
            w[2].parse().unwrap(),
            w[3].to_string(),
            w[4].to_string(),
        );
        let (used, tests, insns): (usize, u64, u64) = (
            w[5].parse().unwrap(),
            w[6].parse().unwrap(),
            w[7].parse().unwrap(),
        );
        let e = runs.entry(key).or_default();
        if used == 0 {
            e[1] = insns;
        } else {
            e[0] = insns;
            e[2] = tests;
        }
    }
    let ops = ops();
    let widths: Vec<usize> = {
        let mut w: Vec<usize> = runs.keys().map(|k| k.1).collect();
        w.sort();
        w.dedup();
        w
    };
    println!("\n## {title}\n");
    println!(
        "Executed instructions per ray–primitive test ((count over {N} primitives − count over \
         none) / tests), and in parentheses the minimum the op count implies: (FP operations \
         incl. compares + primitive loads) / lanes. {SIDE}×{SIDE} primary rays; `miss`: the {} \
         of them whose lines miss everything.\n",
        Frame::with_image(N, Rays::Miss, SIDE, SIDE).rays.len()
    );
    let mut head = String::from("| kernel | rays | shape | ops + loads per test |");
    let mut rule = String::from("| --- | --- | --- | ---: |");
    for w in &widths {
        head += &format!(" x{w} |");
        rule += " ---: |";
    }
    // The ratio for the 8-lane packets where they ran (x86), else for the one width (M4F).
    let ratio_w = if widths.contains(&8) { 8 } else { widths[0] };
    head += &format!(" x{ratio_w} ÷ minimum |");
    rule += " ---: |";
    println!("{head}\n{rule}");
    for k in Kernel::ALL {
        for rays in RAYS {
            for shape in SHAPES {
                let Some(&(per, _)) = ops.get(&(k.name().to_string(), rays.name().to_string()))
                else {
                    continue;
                };
                let need = per + k.miss_loads() as f64;
                let mut row = format!(
                    "| {} | {} | {shape} | {per:.2} + {} |",
                    k.name(),
                    rays.name(),
                    k.miss_loads()
                );
                let mut any = false;
                let mut ratio = None;
                for &w in &widths {
                    let key = (
                        k.name().to_string(),
                        w,
                        shape.to_string(),
                        rays.name().to_string(),
                    );
                    match runs.get(&key) {
                        Some(&[n, z, tests]) if tests > 0 => {
                            let got = (n as f64 - z as f64) / tests as f64;
                            let min = need / w as f64;
                            row += &format!(" {got:.2} ({min:.2}) |");
                            if w == ratio_w {
                                ratio = Some(got / min);
                            }
                            any = true;
                        }
                        _ => row += " — |",
                    }
                }
                row += &ratio.map_or(" — |".into(), |r| format!(" {r:.2} |"));
                if any {
                    println!("{row}");
                }
            }
        }
    }
}

fn print_ops() {
    println!("| kernel | rays | tests | mul | add | div | sqrt | cmp | per test |");
    println!("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for f in frames() {
        for k in Kernel::ALL {
            let c = frame_ops(k, &f, N).minus(&frame_ops(k, &f, 0));
            let t = f.tests() as f64;
            println!(
                "| {} | {} | {} | {:.2} | {:.2} | {:.3} | {:.3} | {:.2} | {:.2} |",
                k.name(),
                f.kind.name(),
                f.tests(),
                c.mul as f64 / t,
                c.add as f64 / t,
                c.div as f64 / t,
                c.sqrt as f64 / t,
                c.cmp as f64 / t,
                (c.flops() + c.cmp) as f64 / t
            );
        }
    }
}

/// A count may rise this much above its pin (deterministic counts; the margin covers
/// deliberate trade-offs too small to re-pin for).
const SLACK: f64 = 1.03;

/// The counts of a table `table` printed: (kernel, rays, shape, width) → instructions per test.
fn read_table(file: &str) -> BTreeMap<(String, String, String, String), f64> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{file}: {e}"));
    let mut widths: Vec<Option<String>> = Vec::new();
    let mut out = BTreeMap::new();
    for line in text.lines().filter(|l| l.starts_with('|')) {
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        if cells.first() == Some(&"kernel") {
            // The header: which columns are lane widths (`x8`, not `x8 ÷ minimum`).
            widths = cells
                .iter()
                .map(|c| {
                    (c.starts_with('x') && c[1..].chars().all(|d| d.is_ascii_digit()))
                        .then(|| c.to_string())
                })
                .collect();
            continue;
        }
        if cells.len() != widths.len() || cells.iter().all(|c| c.starts_with("--")) {
            continue;
        }
        for (cell, w) in cells.iter().zip(&widths) {
            let (Some(w), Some(n)) = (w, cell.split_whitespace().next()) else {
                continue;
            };
            if let Ok(n) = n.parse::<f64>() {
                let key = (
                    cells[0].to_string(),
                    cells[1].to_string(),
                    cells[2].to_string(),
                    w.clone(),
                );
                out.insert(key, n);
            }
        }
    }
    out
}

/// Checks every pinned count of `pin` against `new`; prints each failure and a summary.
fn check(pin: &str, new: &str) -> bool {
    let (pins, counts) = (read_table(pin), read_table(new));
    let mut bad = 0;
    let (mut lower, mut same) = (0, 0);
    for (key, &p) in &pins {
        let (k, rays, shape, w) = key;
        match counts.get(key) {
            None => {
                println!("MISSING  {k} {rays} {shape} {w}: pinned {p:.2}, not counted");
                bad += 1;
            }
            Some(&n) if n > p * SLACK => {
                println!(
                    "ROSE     {k} {rays} {shape} {w}: {n:.2} against the pin {p:.2} (+{:.1} %)",
                    (n / p - 1.0) * 100.0
                );
                bad += 1;
            }
            Some(&n) if n < p / SLACK => {
                println!(
                    "fell     {k} {rays} {shape} {w}: {n:.2} against the pin {p:.2} ({:.1} %): re-pin",
                    (n / p - 1.0) * 100.0
                );
                lower += 1;
            }
            Some(_) => same += 1,
        }
    }
    println!(
        "{pin}: {} counts pinned; {same} within 3 % of their pins, {lower} more than 3 % \
         below, {bad} above or missing",
        pins.len()
    );
    bad == 0
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("measure") => measure(args.get(1).map(String::as_str)),
        Some("table") => table(
            args.get(1).expect("count table FILE TITLE"),
            args.get(2).map_or("Instructions per test", String::as_str),
        ),
        Some("ops") => print_ops(),
        Some("check") => {
            let (Some(pin), Some(new)) = (args.get(1), args.get(2)) else {
                eprintln!("usage: count check PIN NEW");
                std::process::exit(2);
            };
            if !check(pin, new) {
                std::process::exit(1);
            }
        }
        Some("digest") => {
            for f in frames() {
                println!("scene {} {:016x}", f.kind.name(), raylane_bench::digest(&f));
            }
        }
        _ => {
            eprintln!(
                "usage: count measure [KERNEL] | table FILE TITLE | ops | digest | check PIN NEW"
            );
            std::process::exit(2);
        }
    }
}
