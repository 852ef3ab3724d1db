//! The vendored Stanford bunny (`tests/data/bunny.bin`, 3,674 triangles) through a BVH
//! ([`raylane::bvh`]): loading, camera and a primary-ray render, row by row, shared by the
//! host's `render` example (`--scene bunny-fw`, a tree built in RAM) and the firmware
//! `targets/src/bin/bvh.rs` (the tree baked on the host, traced from flash), which
//! `scripts/test.sh` compares byte for byte at every packet width.
//!
//! Shading uses `+ − × ÷ √` and compares only, as the other demo scenes: Lambert's law under
//! one directional light with an ambient term, by the hit's geometric normal (facing the eye),
//! a gamma of 2, and a vertical gradient where rays miss.

use glam::Vec3;

use super::shade::to_rgb;
use raylane::camera::Pinhole;
use raylane::lane::Lane;
use raylane::query::Query;
use raylane::triangle::Triangle;

/// Triangles of the vendored bunny.
pub const TRIANGLES: usize = 3674;

/// The firmware's image size.
pub const SIZE: (u32, u32) = (64, 48);

/// Reads `bunny.bin` (u32 vertex count, u32 triangle count, f32 x, y, z per vertex, u16 ×3
/// per triangle, little-endian) into `out`; returns the number of triangles, or `None` when
/// the bytes are malformed (wrong length, an index out of range) or `out` is too short.
#[must_use]
pub fn load(bin: &[u8], out: &mut [Triangle]) -> Option<usize> {
    let u32_at = |o: usize| Some(u32::from_le_bytes(bin.get(o..o + 4)?.try_into().ok()?));
    let f32_at = |o: usize| Some(f32::from_le_bytes(bin.get(o..o + 4)?.try_into().ok()?));
    let (nv, nt) = (u32_at(0)? as usize, u32_at(4)? as usize);
    let base = nv.checked_mul(12)?.checked_add(8)?;
    if bin.len() != base.checked_add(nt.checked_mul(6)?)? || out.len() < nt {
        return None;
    }
    let vertex = |i: usize| {
        let o = 8 + 12 * i;
        (i < nv).then_some(())?;
        Some(Vec3::new(f32_at(o)?, f32_at(o + 4)?, f32_at(o + 8)?))
    };
    let index = |o: usize| Some(u16::from_le_bytes(bin.get(o..o + 2)?.try_into().ok()?) as usize);
    for (k, t) in out[..nt].iter_mut().enumerate() {
        let o = base + 6 * k;
        *t = Triangle::new(
            vertex(index(o)?)?,
            vertex(index(o + 2)?)?,
            vertex(index(o + 4)?)?,
        );
    }
    Some(nt)
}

/// The camera: 40° vertical field of view, from the front (+z), slightly above and to the
/// right, at 2.2 bounding radii from the centre of the triangles' bounding box.
#[must_use]
pub fn camera(tris: &[Triangle], width: u32, height: u32) -> Pinhole {
    camera_of(tris.iter().copied(), width, height)
}

/// [`camera`] for the triangles of any iterator (a baked tree's, on the device).
#[must_use]
pub fn camera_of(tris: impl Iterator<Item = Triangle>, width: u32, height: u32) -> Pinhole {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in tris {
        for p in [t.a(), t.b(), t.c()] {
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    if !(lo.cmple(hi).all()) {
        (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    }
    let centre = (lo + hi) * 0.5;
    let radius = (hi - lo).length() * 0.5;
    let dir = Vec3::new(0.25, 0.3, 1.0).normalize();
    Pinhole::look_at(
        centre + dir * (2.2 * radius),
        centre,
        Vec3::Y,
        40.0,
        width,
        height,
    )
}

/// The most pixels a row has.
pub const MAX_WIDTH: usize = 256;

/// Renders every primary ray of `cam` through `tree` (any set: a tree in RAM, a baked tree in
/// flash), `L` rays per packet (one lane: one [`Ray`](raylane::Ray) at a time), one row at a time: `row(y, rgb)` gets row `y` as RGB8 (so the
/// device needs no image buffer); returns the number of rays that hit, or `None` for rows
/// wider than [`MAX_WIDTH`].
pub fn render_rows<L: Lane<Scalar = f32>, Q: Query + ?Sized>(
    tree: &Q,
    cam: &Pinhole,
    mut row: impl FnMut(u32, &[u8]),
) -> Option<u32> {
    let w = cam.width as usize;
    if w > MAX_WIDTH {
        return None;
    }
    let light = Vec3::new(-1.0, 2.0, 1.5).normalize();
    let mut hits = 0;
    let mut rgb = [0u8; 3 * MAX_WIDTH];
    for y in 0..cam.height {
        let s = y as f32 / cam.height as f32;
        let sky = [0.16, 0.2, 0.28].map(|c| c * (1.0 - 0.5 * s));
        for x in (0..cam.width).step_by(L::LANES) {
            // One lane: the one-ray query (`closest(&Ray)`, what firmware calls); wider: the
            // packet query. The same answers, bit for bit.
            let found = (L::LANES > 1).then(|| tree.closest(&cam.row_packet::<L>(x, y)));
            let one = match found {
                None => tree.closest(&cam.row_packet::<f32>(x, y).ray(0)),
                Some(_) => None,
            };
            for i in 0..L::LANES.min((cam.width - x) as usize) {
                let hit = match &found {
                    Some(f) => f.lane(i),
                    None => one,
                };
                let c = match hit {
                    Some(hit) => {
                        hits += 1;
                        let k = 0.15 + 0.85 * hit.normal.dot(light).max(0.0);
                        [0.92 * k, 0.85 * k, 0.74 * k]
                    }
                    None => sky,
                };
                let at = 3 * (x as usize + i);
                if let Some(px) = rgb.get_mut(at..at + 3) {
                    px.copy_from_slice(&to_rgb(c));
                }
            }
        }
        row(y, &rgb[..3 * w]);
    }
    Some(hits)
}

/// [`render_rows`] into `rgb` (RGB8, row-major, `3 · width · height` bytes); `None` when
/// `rgb` has the wrong length.
pub fn render<L: Lane<Scalar = f32>, Q: Query + ?Sized>(
    tree: &Q,
    cam: &Pinhole,
    rgb: &mut [u8],
) -> Option<u32> {
    let (w, h) = (cam.width as usize, cam.height as usize);
    if rgb.len() != 3 * w * h {
        return None;
    }
    render_rows::<L, Q>(tree, cam, |y, row| {
        let at = 3 * w * y as usize;
        if let Some(out) = rgb.get_mut(at..at + row.len()) {
            out.copy_from_slice(row);
        }
    })
}
