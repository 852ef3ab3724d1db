//! Executed instructions per ray–primitive test of every method of raylane's operation-count
//! study (`raylane::study`), counted by QEMU's TCG plugin `targets/plugin/insncount.c`: run
//! `scripts/count-study.sh` (it builds this, runs it on mps2-an386 and stores the counts).
//!
//! Each method's timed loop ([`raylane::study::repeat`], scalar `f32` lanes) runs between
//! [`study_begin`] and [`study_end`] once over 64 tests and once over none, on the miss and on
//! the hit; the plugin prints one window per run. Output (semihosting): one
//! `cfg SHAPE METHOD PATH 1 TESTS` line per window, in window order.
#![no_std]
#![no_main]

use core::hint::black_box;

use raylane::study::{METHODS, Path, Shape, repeat};
use raylane_fw::semihosting::hprintln;
use raylane_fw::{entry, exit};

raylane_fw::panic_exits!();

/// Start of a counted window (the plugin's `start=` address): out of line, with a body of its
/// own so that it is not merged with [`study_end`].
#[inline(never)]
#[unsafe(no_mangle)]
pub extern "C" fn study_begin() {
    // SAFETY: an assembler comment; no effect.
    unsafe {
        core::arch::asm!(
            "/* study_begin */",
            options(nomem, nostack, preserves_flags)
        )
    }
}

/// End of a counted window (the plugin's `stop=` address).
#[inline(never)]
#[unsafe(no_mangle)]
pub extern "C" fn study_end() {
    // SAFETY: an assembler comment; no effect.
    unsafe { core::arch::asm!("/* study_end */", options(nomem, nostack, preserves_flags)) }
}

#[entry]
fn main() -> ! {
    let mut ok = true;
    for (i, (shape, method)) in METHODS.iter().enumerate() {
        let shape = match shape {
            Shape::Triangle => "triangle",
            Shape::Sphere => "sphere",
        };
        for (path, name) in [(Path::Miss, "miss"), (Path::Hit, "hit")] {
            for n in [64usize, 0] {
                hprintln!("cfg {} {} {} 1 {}", shape, method, name, n);
                study_begin();
                let hits = repeat::<f32>(black_box(i), black_box(path), black_box(n));
                study_end();
                ok &= hits == Some(if path == Path::Hit { n as u32 } else { 0 });
            }
        }
    }
    exit(ok)
}
