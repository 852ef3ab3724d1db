//! The flash-size baseline: the same runtime, exit and panic handler as `kernels`, no kernel.
#![no_std]
#![no_main]

use raylane_fw::{entry, exit};

#[entry]
fn main() -> ! {
    exit(true)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    unsafe extern "C" {
        fn raylane_kernels_have_a_panic_path() -> !;
    }
    // SAFETY: never linked (see `kernels`).
    unsafe { raylane_kernels_have_a_panic_path() }
}
