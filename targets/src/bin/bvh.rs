//! The vendored Stanford bunny (`tests/data/bunny.bin`, 3,674 triangles), baked on the host by
//! `build.rs` (`raylane::bvh::bake`), linked into flash (`raylane::include_baked!`) and opened
//! in place on the device (`Baked::open`: checked, not copied). It renders the bunny's primary
//! rays at 64×48 through the baked tree — the same `raylane_lab::demo::bunny` code, camera and
//! shading as the host's `render --scene bunny-fw` — with the scalar `f32` lane, and on every
//! board but the Cortex-M0 also with packets of 4, 8 and 16 rays (`wide`'s array fallback),
//! checks that every width gives the same bytes, and writes the image to the host as a binary
//! PPM through semihosting, row by row (no image buffer), to `target/bvh.ppm` in this crate's
//! directory. `scripts/test.sh` compares it byte for byte with the host's render.
//!
//! Each width's render runs once between the marker functions [`bvh_begin`] and [`bvh_end`]
//! (the TCG plugin's windows, `scripts/count-bvh.sh`: instructions per primary ray), then
//! again to hash (and at x1 to write) the image. RAM is measured by stack painting: the peak
//! of one `closest` query from `main` (the traversal's stack and frames), and of the whole
//! program.
//!
//! Output: `bvh bunny: baked …` (the tree's flash bytes), one `render bunny-fw 64x48 xN: fnv1a
//! HEX, N of N rays hit` line per width, `bvh stack: …`, `wrote PATH (N bytes)`; exits non-zero
//! when the tree does not open, the widths differ or the file cannot be written.
#![no_std]
#![no_main]

use core::hash::Hasher;
use core::hint::black_box;

use raylane::bvh::bake::Baked;
use raylane::{Lane, Pinhole, Query, Ray};
use raylane_fw::semihosting::hprintln;
use raylane_fw::{entry, exit};
use raylane_lab::demo::{self, bunny};

raylane_fw::panic_exits!();

/// The bunny, baked on the host at build time, in flash.
static TREE: &[u8] = raylane::include_baked!(concat!(env!("OUT_DIR"), "/bunny.rlbv"));

const W: u32 = bunny::SIZE.0;
const H: u32 = bunny::SIZE.1;

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

/// One width: a counted render, then one that hashes the rows (and passes them to `out`).
/// Prints the width's line; returns the image's FNV-1a.
#[inline(never)]
fn render<L: Lane<Scalar = f32>>(tree: &Baked, cam: &Pinhole, mut out: impl FnMut(&[u8])) -> u64 {
    bvh_begin();
    let counted = bunny::render_rows::<L, _>(tree, cam, |_, row| {
        black_box(row);
    });
    bvh_end();
    let mut h = fnv::FnvHasher::default();
    let hits = bunny::render_rows::<L, _>(tree, cam, |_, row| {
        h.write(row);
        out(row);
    });
    let (Some(hits), true) = (hits, hits == counted) else {
        exit(false)
    };
    let digest = h.finish();
    hprintln!(
        "render bunny-fw {}x{} x{}: fnv1a {:016x}, {} of {} rays hit",
        W,
        H,
        L::LANES,
        digest,
        hits,
        W * H
    );
    digest
}

/// One `closest` query, out of line (its stack is what a traversal needs).
#[inline(never)]
fn one_query(tree: &Baked, ray: &Ray) -> bool {
    black_box(tree.closest(black_box(ray))).is_some()
}

#[entry]
fn main() -> ! {
    raylane_fw::paint_stack();
    let tree = match Baked::open(TREE) {
        Ok(t) => t,
        Err(e) => {
            hprintln!("bvh bunny: {}", e);
            exit(false)
        }
    };
    let (nodes, tris, verts) = tree.bytes();
    hprintln!(
        "bvh bunny: baked {} triangles, {} nodes, depth {}: {} B in flash (nodes {}, triangles {}, vertices {})",
        tree.len(),
        tree.nodes().len(),
        tree.depth(),
        TREE.len(),
        nodes,
        tris,
        verts
    );
    let cam = bunny::camera_of(
        (0..tree.len()).filter_map(|i| tree.get(i)).map(|t| t.1),
        W,
        H,
    );
    // The stack of one query from here (its own frame and the traversal's).
    let before = raylane_fw::stack_touched();
    let sp = raylane_fw::stack_pointer();
    let hit = one_query(&tree, &cam.row_packet::<f32>(W / 2, H / 2).ray(0));
    let query_stack = sp.saturating_sub(raylane_fw::stack_touched().min(before));
    // x1, written to the host.
    let Some(fd) = raylane_fw::create(PATH) else {
        hprintln!("bvh ... cannot create {}", PATH.trim_end_matches('\0'));
        exit(false)
    };
    let mut head = [0u8; 32];
    let Some(k) = demo::ppm_header(W, H, &mut head) else {
        exit(false)
    };
    let mut ok = raylane_fw::write(fd, &head[..k]);
    let _one = render::<f32>(&tree, &cam, |row| ok &= raylane_fw::write(fd, row));
    ok &= raylane_fw::close(fd);
    // The packet widths, where the flash holds them.
    #[cfg(not(scalar_only))]
    {
        use raylane::wide::{f32x4, f32x8, f32x16};
        let same = render::<f32x4>(&tree, &cam, |_| {}) == _one
            && render::<f32x8>(&tree, &cam, |_| {}) == _one
            && render::<f32x16>(&tree, &cam, |_| {}) == _one;
        if !same {
            hprintln!("bvh bunny ... the packet widths' images differ from the scalar one");
            exit(false)
        }
    }
    hprintln!(
        "bvh stack: one query {} B, the whole program {} B (peak; a hit: {})",
        query_stack,
        raylane_fw::peak_stack(),
        hit
    );
    if !ok {
        hprintln!("bvh ... cannot write {}", PATH.trim_end_matches('\0'));
        exit(false)
    }
    hprintln!(
        "wrote {} ({} bytes)",
        PATH.trim_end_matches('\0'),
        k + (3 * W * H) as usize
    );
    exit(true)
}
