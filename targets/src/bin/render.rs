//! Renders the demo's scene 4 (spheres, an icosahedron, a cube and a checkered plane) at
//! 64×48 with the scalar `f32` lane — the same `raylane_lab::demo` code, scene and camera as the
//! host's `render` example — and writes it to the host as a binary PPM through semihosting
//! file I/O, to `target/render.ppm` in this crate's directory (an absolute path fixed at build
//! time; the directory exists once the crate is built). `scripts/test.sh` compares the file
//! byte for byte with the host's render of the same scene and size at every packet width.
//!
//! Output: `render mix 64x48 x1: fnv1a HEX, N rays, N tests, N triangle tests saved` and
//! `wrote PATH (N bytes)`; exits non-zero when the frame cannot be set up or the file cannot
//! be written.
#![no_std]
#![no_main]

use raylane::triangle::FocalTriangle;
use raylane_fw::semihosting::{hprintln, nr, syscall};
use raylane_fw::{entry, exit};
use raylane_lab::demo::{self, Frame, Storage, scenes::Mix};
use raylane_lab::registry::Kernel;

raylane_fw::panic_exits!();

const W: u32 = Mix::FIRMWARE_SIZE.0;
const H: u32 = Mix::FIRMWARE_SIZE.1;
const PIXELS: usize = (W * H) as usize;

/// Where the image goes on the host (NUL-terminated for SYS_OPEN).
const PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/target/render.ppm\0");

/// Writes `parts` to a new host file at `path` (NUL-terminated): SYS_OPEN in "wb" mode,
/// SYS_WRITE (returns the number of bytes *not* written), SYS_CLOSE.
fn write_file(path: &str, parts: &[&[u8]]) -> bool {
    // SAFETY: semihosting calls with a valid NUL-terminated name and valid buffers; QEMU runs
    // with semihosting enabled (see .cargo/config.toml).
    let fd = unsafe {
        syscall!(
            OPEN,
            path.as_ptr(),
            nr::open::W_TRUNC_BINARY,
            path.len() - 1
        )
    } as isize;
    if fd == -1 {
        return false;
    }
    let mut ok = true;
    for p in parts {
        // SAFETY: as above; `p` is a valid buffer of `p.len()` bytes.
        ok &= unsafe { syscall!(WRITE, fd, p.as_ptr(), p.len()) } == 0;
    }
    // SAFETY: closes the handle opened above.
    ok &= unsafe { syscall!(CLOSE, fd) } == 0;
    ok
}

fn fail() -> ! {
    exit(false)
}

#[entry]
fn main() -> ! {
    raylane_fw::paint_stack();
    // The scene and its caches, in fixed-size arrays sized for scene 4.
    let mix = Mix::new();
    let mut spheres = [demo::empty_sphere(); Mix::SPHERES];
    let mut planes = [demo::empty_plane(); Mix::PLANES];
    let mut triangles = [FocalTriangle::never(); Mix::TRIANGLES];
    let storage = Storage {
        spheres: &mut spheres,
        planes: &mut planes,
        triangles: &mut triangles,
    };
    let frame = match Frame::<'_, 4>::new(mix.scene(), Mix::camera(W, H), Kernel::Focal, storage) {
        Ok(f) => f,
        Err(e) => {
            hprintln!("render mix ... cannot set up the frame ({:?})", e);
            fail();
        }
    };
    let mut rgb = [0u8; 3 * PIXELS];
    let stats = frame.render::<f32>(&mut rgb, None);
    hprintln!(
        "render mix {}x{} x1: fnv1a {:016x}, {} rays, {} tests, {} triangle tests saved",
        W,
        H,
        demo::fnv1a(&rgb),
        stats.rays,
        stats.tests(),
        stats.triangle_tests_saved
    );
    let mut head = [0u8; 32];
    let Some(n) = demo::ppm_header(W, H, &mut head) else {
        fail();
    };
    if !write_file(PATH, &[&head[..n], &rgb]) {
        hprintln!("render ... cannot write {}", PATH.trim_end_matches('\0'));
        fail();
    }
    hprintln!("render stack: {} B (peak)", raylane_fw::peak_stack());
    hprintln!(
        "wrote {} ({} bytes)",
        PATH.trim_end_matches('\0'),
        n + rgb.len()
    );
    exit(true)
}
