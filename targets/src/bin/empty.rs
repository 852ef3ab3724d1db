//! The flash-size baseline: the same runtime, exit and panic handler as `kernels`, no kernel.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::debug;

#[entry]
fn main() -> ! {
    debug::exit(debug::EXIT_SUCCESS);
    // Not reached: the semihosting exit ends the QEMU run.
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    unsafe extern "C" {
        fn raylane_kernels_have_a_panic_path() -> !;
    }
    // SAFETY: never linked (see `kernels`).
    unsafe { raylane_kernels_have_a_panic_path() }
}
