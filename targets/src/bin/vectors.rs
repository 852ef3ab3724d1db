//! Runs every vector file through every method at every lane width on the microcontroller,
//! comparing with the expectations as the host checker does, and prints the digests the host
//! computes with `cargo run --release --features vectors --example digest`.
//!
//! Output: `FILE METHOD ... N passed, M failed` per file and method (lane width 1; the other
//! widths must agree), `digest METHOD xLANES HEX` per method and width, then
//! `N passed, M failed`. Exits non-zero on any failure.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;
use raylane::vectors::{self, Case, Digest, LANE_WIDTHS, Method, Outcome, Tally};

include!(concat!(env!("OUT_DIR"), "/files.rs"));

/// Room for every case of every file.
const MAX_CASES: usize = 4096;

#[entry]
fn main() -> ! {
    // Parse every file once.
    let mut cases = [Case::default(); MAX_CASES];
    let mut bounds = [(0usize, 0usize); 32];
    let mut n = 0;
    let mut ok = true;
    for (k, (name, text)) in FILES.iter().enumerate() {
        match vectors::load(text, &mut cases[n..]) {
            Ok(m) => {
                bounds[k] = (n, n + m);
                n += m;
            }
            Err((line, e)) => {
                hprintln!("{}:{} ... cannot parse ({:?})", name, line, e);
                ok = false;
            }
        }
    }
    let mut out = [Outcome::default(); MAX_CASES];
    let (mut passed, mut failed) = (0usize, 0usize);
    for m in Method::ALL {
        let mut first: Option<(u64, [Tally; 32])> = None;
        for lanes in LANE_WIDTHS {
            let mut d = Digest::new();
            let mut tallies = [Tally::default(); 32];
            for (k, (name, _)) in FILES.iter().enumerate() {
                let (a, b) = bounds[k];
                let Some(t) = vectors::check(m, lanes, &cases[a..b], &mut out[a..b], &mut d) else {
                    hprintln!("{} {} x{} ... cannot evaluate", name, m.name(), lanes);
                    ok = false;
                    continue;
                };
                tallies[k] = t;
                if lanes == 1 {
                    let mark = if t.failed == 0 { "" } else { "  <- FAILED" };
                    hprintln!(
                        "{} {} ... {} passed, {} failed{}",
                        name,
                        m.name(),
                        t.passed,
                        t.failed,
                        mark
                    );
                    passed += t.passed;
                    failed += t.failed;
                }
            }
            hprintln!("digest {} x{} {:016x}", m.name(), lanes, d.value());
            match first {
                None => first = Some((d.value(), tallies)),
                Some((d1, t1)) if d1 != d.value() || t1 != tallies => {
                    hprintln!("{} x{} ... differs from x1  <- FAILED", m.name(), lanes);
                    ok = false;
                }
                Some(_) => {}
            }
        }
    }
    hprintln!("{} passed, {} failed", passed, failed);
    let success = ok && failed == 0;
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    // Not reached: the semihosting exit ends the QEMU run.
    loop {
        cortex_m::asm::wfi();
    }
}
