//! Runs every vector file through every method at every lane width on the microcontroller,
//! comparing with the expectations as the host checker does, and prints the digests the host
//! computes with `cargo run --release --features vectors --example digest`.
//!
//! The cases (encoded by `build.rs`, see [`raylane_fw::Cases`]) are taken [`CHUNK`] at a time,
//! so that 16 KB of RAM (the micro:bit's) suffices; every method and width runs over each chunk
//! and folds it into its own digest, in case order. (Lanes are independent, so chunking changes
//! no result.)
//!
//! On the Cortex-M0 (`thumbv6m-none-eabi`, the micro:bit's 256 KB of flash) every case runs at
//! lane width 1 only: the vectors and the scalar runner fit, the packet widths do not.
//!
//! Output: `FILE METHOD ... N passed, M failed` per file and method (lane width 1; the other
//! widths must agree), `digest METHOD xLANES HEX` per method and width, the op-count report
//! measured on the target (`opcount KERNEL,PATH,MUL,ADD,DIV,SQRT,CMP`, as the host's
//! `cargo run --example opcount -- --csv`), then `N passed, M failed`. Exits non-zero on any
//! failure.
#![no_std]
#![no_main]

use raylane_fw::{entry, exit, semihosting::hprintln};
#[cfg(not(scalar_only))]
use raylane_lab::vectors::LANE_WIDTHS;
use raylane_lab::vectors::{self, Case, Digest, Method, Outcome, Tally};

raylane_fw::panic_exits!();

include!(concat!(env!("OUT_DIR"), "/files.rs"));

/// Cases per chunk: a multiple of the widest packet.
const CHUNK: usize = 32;
const METHODS: usize = Method::ALL.len();
/// Every lane width; on the Cortex-M0 (256 KB of flash) the scalar lane only.
#[cfg(not(scalar_only))]
const WIDTH_LIST: [usize; LANE_WIDTHS.len()] = LANE_WIDTHS;
#[cfg(scalar_only)]
const WIDTH_LIST: [usize; 1] = [1];
const WIDTHS: usize = WIDTH_LIST.len();

fn add(a: &mut Tally, b: Tally) {
    a.passed += b.passed;
    a.failed += b.failed;
    a.skipped += b.skipped;
}

#[entry]
fn main() -> ! {
    raylane_fw::paint_stack();
    let mut digests = [[Digest::new(); WIDTHS]; METHODS];
    let mut totals = [[Tally::default(); WIDTHS]; METHODS];
    let mut cases = [Case::default(); CHUNK];
    let mut out = [Outcome::default(); CHUNK];
    let mut ok = true;
    for (name, file) in FILES {
        let mut tallies = [[Tally::default(); WIDTHS]; METHODS];
        let mut pos = 0;
        loop {
            let mut n = 0;
            while n < CHUNK {
                let Some(c) = file.next(&mut pos) else { break };
                cases[n] = c;
                n += 1;
            }
            if n == 0 {
                break;
            }
            for (mi, &m) in Method::ALL.iter().enumerate() {
                for (wi, &lanes) in WIDTH_LIST.iter().enumerate() {
                    let d = &mut digests[mi][wi];
                    match vectors::check(m, lanes, &cases[..n], &mut out[..n], d) {
                        Some(t) => add(&mut tallies[mi][wi], t),
                        None => {
                            hprintln!("{} {} x{} ... cannot evaluate", name, m.name(), lanes);
                            ok = false;
                        }
                    }
                }
            }
        }
        if !file.done(pos) {
            hprintln!("{} ... cannot decode the case at byte {}", name, pos);
            ok = false;
        }
        for (mi, m) in Method::ALL.iter().enumerate() {
            let t = tallies[mi][0];
            let mark = if t.failed == 0 { "" } else { "  <- FAILED" };
            hprintln!(
                "{} {} ... {} passed, {} failed{}",
                name,
                m.name(),
                t.passed,
                t.failed,
                mark
            );
            for wi in 0..WIDTHS {
                add(&mut totals[mi][wi], tallies[mi][wi]);
            }
        }
    }
    let (mut passed, mut failed) = (0usize, 0usize);
    for (mi, m) in Method::ALL.iter().enumerate() {
        passed += totals[mi][0].passed;
        failed += totals[mi][0].failed;
        for (wi, lanes) in WIDTH_LIST.iter().enumerate() {
            let d = digests[mi][wi].value();
            hprintln!("digest {} x{} {:016x}", m.name(), lanes, d);
            if wi > 0 && (d != digests[mi][0].value() || totals[mi][wi] != totals[mi][0]) {
                hprintln!("{} x{} ... differs from x1  <- FAILED", m.name(), lanes);
                ok = false;
            }
        }
    }
    opcounts();
    hprintln!("vectors stack: {} B (peak)", raylane_fw::peak_stack());
    hprintln!("{} passed, {} failed", passed, failed);
    exit(ok && failed == 0)
}

/// The op-count report, measured here by the counting lane (on the Cortex-M0 with plain
/// atomic loads and stores): equal to the host's `opcount --csv`. Out of line, so that the
/// report's rows never share `main`'s frame with the vectors' buffers (the Cortex-M0 has
/// 16 KB of RAM).
#[inline(never)]
fn opcounts() {
    raylane_lab::opcount::each_row(|r| {
        let c = r.counts;
        hprintln!(
            "opcount {},{},{},{},{},{},{}",
            r.kernel,
            r.path,
            c.mul,
            c.add,
            c.div,
            c.sqrt,
            c.cmp
        );
    });
}
