//! `kernels` plus every kernel in 4-lane packets (`wide::f32x4`, plain arrays on Cortex-M):
//! the no-panic proof for the packet paths too. (Packets buy no speed without SIMD; their code
//! is reported separately from the scalar flash size.)
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
    every_kernel::<wide::f32x4>(&cam.row_packet(0, x(9) as u32 % 8), &ray);
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
