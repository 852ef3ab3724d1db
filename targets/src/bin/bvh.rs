//! Builds the BVH of the vendored Stanford bunny (`tests/data/bunny.bin`, 3,674 triangles,
//! embedded) on the device, in stack storage sized by `bvh::needed`, renders its primary rays
//! at 64×48 through the tree with the scalar `f32` lane and with packets of 4, 8 and 16 rays
//! (`wide`'s array fallback) — the same `raylane_lab::demo::bunny` code, camera and shading as
//! the host's `render --scene bunny-fw` — checks that every width gives the same bytes, and
//! writes the image to the host as a binary PPM through semihosting file I/O, to
//! `target/bvh.ppm` in this crate's directory. `scripts/test.sh` compares it byte for byte with
//! the host's render at every packet width.
//!
//! The build and each width's render run between the marker functions [`bvh_begin`] and
//! [`bvh_end`], so the TCG plugin's windows (`targets/plugin`, `start=`/`stop=`) count the
//! executed instructions of each (window 1: build, windows 2–5: x1, x4, x8, x16).
//!
//! Output: `bvh bunny: N triangles, N nodes, N leaves, N B of tree storage (N B used), …`, `bvh stack storage: N B` (every array, on the stack), one
//! `render bunny-fw 64x48 xN: fnv1a HEX, N of N rays hit` line per width and
//! `wrote PATH (N bytes)`; exits non-zero when the build fails, the widths differ or the file
//! cannot be written.
#![no_std]
#![no_main]

use raylane_fw::entry;

raylane_fw::panic_exits!();

#[entry]
fn main() -> ! {
    device::run()
}

/// The micro:bit (Cortex-M0, 256 KB of flash, 16 KB of RAM) holds neither the tree nor the
/// mesh: there the binary only says so and fails.
#[cfg(scalar_only)]
mod device {
    use raylane_fw::exit;
    use raylane_fw::semihosting::hprintln;

    /// Says that this board is too small and exits with failure.
    pub fn run() -> ! {
        hprintln!("bvh: this board's flash and RAM cannot hold the bunny's BVH");
        exit(false)
    }
}

/// Everything but the micro:bit.
#[cfg(not(scalar_only))]
mod device {
    use raylane::bvh::{self, Node, Packed, Scratch, Tri4};
    use raylane::triangle::Triangle;
    use raylane::wide::{f32x4, f32x8, f32x16};
    use raylane::{Lane, Pinhole};
    use raylane_fw::exit;
    use raylane_fw::semihosting::{hprintln, nr, syscall};
    use raylane_lab::demo::{self, bunny};

    const W: u32 = bunny::SIZE.0;
    const H: u32 = bunny::SIZE.1;
    const PIXELS: usize = (W * H) as usize;
    const N: usize = bunny::TRIANGLES;
    const SIZES: bvh::Sizes = bvh::TriangleBvh::needed(N);

    /// Where the image goes on the host (NUL-terminated for SYS_OPEN).
    const PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/target/bvh.ppm\0");

    /// Start of a counted window (the plugin's `start=` address): out of line, with a body of its
    /// own so that it is not merged with [`bvh_end`].
    #[inline(never)]
    #[unsafe(no_mangle)]
    pub extern "C" fn bvh_begin() {
        // SAFETY: an assembler comment; no effect.
        unsafe { core::arch::asm!("/* bvh_begin */", options(nomem, nostack, preserves_flags)) }
    }

    /// End of a counted window (the plugin's `stop=` address).
    #[inline(never)]
    #[unsafe(no_mangle)]
    pub extern "C" fn bvh_end() {
        // SAFETY: an assembler comment; no effect.
        unsafe { core::arch::asm!("/* bvh_end */", options(nomem, nostack, preserves_flags)) }
    }

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

    /// One counted render at `L` lanes into `rgb`; prints its line, returns the rays that hit.
    #[inline(never)]
    fn render<L: Lane<Scalar = f32>>(
        tree: &bvh::TriangleBvh,
        cam: &Pinhole,
        rgb: &mut [u8],
    ) -> u32 {
        bvh_begin();
        let hits = bunny::render::<L>(tree, cam, rgb);
        bvh_end();
        let Some(hits) = hits else { exit(false) };
        hprintln!(
            "render bunny-fw {}x{} x{}: fnv1a {:016x}, {} of {} rays hit",
            W,
            H,
            L::LANES,
            demo::fnv1a(rgb),
            hits,
            PIXELS
        );
        hits
    }

    /// Loads, builds, renders at every width, compares and writes the image.
    pub fn run() -> ! {
        let mut tris = [Triangle::never(); N];
        let Some(n) = bunny::load(include_bytes!("../../../tests/data/bunny.bin"), &mut tris)
        else {
            hprintln!("bvh bunny ... cannot read tests/data/bunny.bin");
            exit(false)
        };
        let mut nodes = [Node::EMPTY; SIZES.nodes];
        let mut leaves = [<Tri4 as Packed>::EMPTY; SIZES.leaves];
        let mut scratch = [Scratch::default(); SIZES.scratch];
        bvh_begin();
        let built = bvh::Bvh::build(&tris[..n], &mut nodes, &mut leaves, &mut scratch);
        bvh_end();
        let tree = match built {
            Ok(t) => t,
            Err(e) => {
                hprintln!("bvh bunny ... build failed: {}", e);
                exit(false)
            }
        };
        hprintln!(
            "bvh bunny: {} triangles, {} nodes, {} leaves, {} B of tree storage ({} B used), {} B scratch, {} B triangles",
            n,
            tree.nodes().len(),
            tree.leaves().len(),
            SIZES.nodes * size_of::<Node>() + SIZES.leaves * size_of::<Tri4>(),
            size_of_val(tree.nodes()) + size_of_val(tree.leaves()),
            SIZES.scratch * size_of::<Scratch>(),
            size_of_val(&tris)
        );
        // Every array of this function, all on the stack (RAM beside .data and .bss).
        hprintln!(
            "bvh stack storage: {} B",
            size_of_val(&tris)
                + SIZES.nodes * size_of::<Node>()
                + SIZES.leaves * size_of::<Tri4>()
                + SIZES.scratch * size_of::<Scratch>()
                + 2 * 3 * PIXELS
        );
        let cam = bunny::camera(&tris[..n], W, H);
        let mut rgb = [0u8; 3 * PIXELS];
        let mut other = [0u8; 3 * PIXELS];
        render::<f32>(&tree, &cam, &mut rgb);
        render::<f32x4>(&tree, &cam, &mut other);
        let mut same = other == rgb;
        render::<f32x8>(&tree, &cam, &mut other);
        same &= other == rgb;
        render::<f32x16>(&tree, &cam, &mut other);
        same &= other == rgb;
        if !same {
            hprintln!("bvh bunny ... the packet widths' images differ from the scalar one");
            exit(false)
        }
        let mut head = [0u8; 32];
        let Some(k) = demo::ppm_header(W, H, &mut head) else {
            exit(false)
        };
        if !write_file(PATH, &[&head[..k], &rgb]) {
            hprintln!("bvh ... cannot write {}", PATH.trim_end_matches('\0'));
            exit(false)
        }
        hprintln!(
            "wrote {} ({} bytes)",
            PATH.trim_end_matches('\0'),
            k + rgb.len()
        );
        exit(true)
    }
}
