//! Executed instructions per ray–primitive test of every method of raylane's operation-count
//! study (`raylane_lab::study`), counted by QEMU's TCG plugin `targets/plugin/insncount.c`: run
//! `scripts/count-study.sh` (it builds this, runs it on mps2-an386 and stores the counts).
//!
//! Each method's timed loop ([`raylane_lab::study::repeat`], scalar `f32` lanes) runs between
//! [`study_begin`] and [`study_end`] once over 64 iterations and once over none, on the miss,
//! on the hit and on the precomputation (if any); the plugin prints one window per run.
//! Output (semihosting): one `cfg SHAPE METHOD PATH UNITS N` line per window, in window order
//! (the methods in the order of [`raylane_lab::study::KERNELS`], the registry's).
#![no_std]
#![no_main]

use core::hint::black_box;

use raylane_fw::semihosting::hprintln;
use raylane_fw::{entry, exit};
use raylane_lab::study::{KERNELS, PATHS, Path, precomputes, repeat, units};

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
    for k in KERNELS {
        let (shape, method) = (k.prim().name(), k.method().name());
        for (path, name) in PATHS {
            if path == Path::Precompute && !precomputes(k) {
                continue;
            }
            let units = units::<f32>(k, path);
            for n in [64usize, 0] {
                hprintln!("cfg {} {} {} {} {}", shape, method, name, units, n);
                study_begin();
                let done = repeat::<f32>(black_box(k), black_box(path), black_box(n));
                study_end();
                let miss = path == Path::Miss;
                ok &= done == Some(if miss { 0 } else { (units * n) as u32 });
            }
        }
    }
    exit(ok)
}
