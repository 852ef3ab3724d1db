//! Traces a ray through the mesh that build.rs baked, from flash, and prints the hit over
//! semihosting (QEMU, or a debugger attached to a real board).
#![no_std]
#![no_main]

use core::fmt::Display;
use core::hint::spin_loop;

use cortex_m as _; // the critical section cortex-m-semihosting needs
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use raylane::bvh::bake::Baked;
use raylane::glam::Vec3;
use raylane::{Query, Ray};

/// The tree build.rs baked, in flash, aligned for `Baked::open`.
static TREE: &[u8] = raylane::include_baked!(concat!(env!("OUT_DIR"), "/mesh.rlbv"));

#[entry]
fn main() -> ! {
    // One pass checks the bytes (an `OpenError`, never a panic, if they are not a valid tree),
    // then the tree is read in place: no copy, no allocator.
    let tree = match Baked::open(TREE) {
        Ok(tree) => tree,
        Err(e) => fail(e),
    };
    let ray = Ray::new(Vec3::new(0.25, 0.1, 5.0), Vec3::NEG_Z);
    match tree.closest(&ray) {
        Some(hit) => hprintln!("hit triangle {} at t = {}", hit.index, hit.t),
        None => fail("no hit"),
    }
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        spin_loop();
    }
}

/// Prints why and ends the run with a failure.
fn fail(why: impl Display) -> ! {
    hprintln!("{}", why);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        spin_loop();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        spin_loop();
    }
}
