//! Calls every kernel of raylane at the scalar lane (`f32`), as firmware uses them, for two
//! checks and one figure:
//!
//! * **No panic path.** The panic handler calls a function that exists nowhere, so this binary
//!   links only if no panic can be reached from any kernel (release, LTO).
//! * **Hardware square roots.** The disassembly must show `vsqrt.f32` (Cortex-M4F/M33) or
//!   `fsqrt.s` (RISC-V with F), and no software `sqrtf`.
//! * **Flash size**: `.text` of this binary minus `.text` of `empty` (same runtime).
#![no_std]
#![no_main]

use glam::Vec3;
use raylane::{Pinhole, Ray, RayPacket};
use raylane_fw::{entry, every_kernel, exit, v, x};

#[entry]
fn main() -> ! {
    let ray = Ray::new(v(11), v(13));
    let cam = Pinhole::look_at(v(0), v(5), Vec3::Y, 60.0, 8, 8);
    every_kernel::<f32>(&RayPacket::splat(&ray), &ray);
    every_kernel::<f32>(&cam.row_packet(x(9) as u32 % 8, 3), &ray);
    exit(true)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    unsafe extern "C" {
        /// Defined nowhere: linking fails if any panic path is left in the kernels.
        fn raylane_kernels_have_a_panic_path() -> !;
    }
    // SAFETY: never called (the link would have failed).
    unsafe { raylane_kernels_have_a_panic_path() }
}
