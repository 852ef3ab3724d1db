//! raylane's contenders in the BVH benchmark (`examples/scenes.rs`), over the same rays as
//! the peers of [`crate::bvh_peers`]:
//!
//! * brute force with bounding spheres: the mesh in parts of a few hundred triangles with a
//!   bounding sphere each ([`crate::parts`]), every part's sphere tested per packet, the
//!   triangles only of parts a lane may hit: `Watertight` for every kind of ray (closest and
//!   any), and the focal cache for the primary rays (built per eye, inside the timing);
//! * the reference tracer every contender is checked against: the same parts with the scalar
//!   `Watertight` kernel (exact brute force, with each hit's triangle index);
//! * raylane's BVH, once merged, plugs in next to these (see `examples/scenes.rs`).
//!
//! Every function returns the number of rays hit and, when `out` is given, pushes one answer
//! per ray (`(t, triangle)`; `(0, 0)` for an occluded shadow ray).

use std::hint::black_box;

use raylane::mesh::{FocalMesh, Mesh};
use raylane::sphere::{self, Robust, Sphere};
use raylane::triangle::{Cull, Watertight};
use raylane::{Lane, Mask, Ray, RayPacket};

use crate::meshes::Answers;

/// Triangles per part for a mesh of `n` triangles: about √n / 2, a power of two in
/// [16, 512], which balances the sphere tests (n / size per packet) against the triangles of
/// the parts hit.
pub fn part_size(n: usize) -> usize {
    ((n as f64).sqrt() / 2.0)
        .clamp(16.0, 512.0)
        .log2()
        .round()
        .exp2() as usize
}

/// Ray packets of `L::LANES` rays (the last one padded with rays that never hit).
pub fn packets<L: Lane<Scalar = f32>>(rays: &[Ray]) -> Vec<RayPacket<L>> {
    rays.chunks(L::LANES).map(RayPacket::from_rays).collect()
}

/// Closest hits over the parts with `Watertight`; `ids[p][i]` is the input index of triangle
/// `i` of part `p`.
#[inline(never)]
pub fn closest<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    meshes: &[Mesh],
    ids: &[Vec<u32>],
    rays: usize,
    mut out: Option<&mut Answers>,
) -> u32 {
    let mut n = 0;
    for p in packets {
        let mut r = *black_box(p);
        let mut best = [None; 16];
        let mut mask = L::Mask::splat(false);
        for (k, m) in meshes.iter().enumerate() {
            let h = m.closest::<Watertight, L>(&r, Cull::None);
            if h.mask.any() {
                r = r.shrink(h.mask, h.t);
                mask = mask | h.mask;
                if out.is_some() {
                    for (i, b) in best.iter_mut().enumerate().take(L::LANES) {
                        if let Some(rec) = h.lane(i) {
                            *b = Some((rec.t, ids[k][rec.index as usize]));
                        }
                    }
                }
            }
        }
        n += mask.bits().count_ones();
        if let Some(o) = out.as_deref_mut() {
            o.extend_from_slice(&best[..L::LANES]);
        }
    }
    if let Some(o) = out {
        o.truncate(rays);
    }
    n
}

/// Any hit over the parts with `Watertight` (lanes found occluded drop out of later parts).
#[inline(never)]
pub fn any<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    meshes: &[Mesh],
    rays: usize,
    mut out: Option<&mut Answers>,
) -> u32 {
    let mut n = 0;
    let gone = L::from_f32(f32::NEG_INFINITY);
    for p in packets {
        let mut r = *black_box(p);
        let live = r.valid();
        let mut occ = L::Mask::splat(false);
        for m in meshes {
            let h = m.any::<Watertight, L>(&r, Cull::None);
            if h.any() {
                occ = occ | h;
                if (occ | !live).all() {
                    break;
                }
                r = r.shrink(h, gone);
            }
        }
        n += occ.bits().count_ones();
        if let Some(o) = out.as_deref_mut() {
            o.extend((0..L::LANES).map(|i| occ.test(i).then_some((0.0, 0))));
        }
    }
    if let Some(o) = out {
        o.truncate(rays);
    }
    n
}

/// Closest hits of primary rays over focal parts (the caches are built by the caller, per
/// eye, inside the timing); `t` only (index 0).
pub fn focal_answers<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    meshes: &[FocalMesh],
    rays: usize,
) -> Answers {
    crate::parts::answers(packets, meshes, rays)
        .into_iter()
        .map(|t| t.map(|t| (t, 0)))
        .collect()
}

/// Brute force over spheres (`Robust`, packets over the slice).
#[inline(never)]
pub fn spheres_closest<L: Lane<Scalar = f32>>(
    packets: &[RayPacket<L>],
    spheres: &[Sphere],
    rays: usize,
    mut out: Option<&mut Answers>,
) -> u32 {
    let mut n = 0;
    for p in packets {
        let h = sphere::closest::<Robust, L>(black_box(p), spheres);
        n += h.mask.bits().count_ones();
        if let Some(o) = out.as_deref_mut() {
            o.extend((0..L::LANES).map(|i| h.lane(i).map(|r| (r.t, r.index))));
        }
    }
    if let Some(o) = out {
        o.truncate(rays);
    }
    n
}
