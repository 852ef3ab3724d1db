//! Baldwin and Weber's test: an affine transform to the unit triangle, precomputed (2016).

use super::precomputed::{PrecomputedKernel, cyclic, dominant, precomputed_triangle_kernel};
use super::{Cull, TrianglePacket};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// Doug Baldwin and Michael Weber, "Fast Ray-Triangle Intersections by Coordinate
/// Transformation", Journal of Computer Graphics Techniques 5(3), 2016, pp. 39–49.
///
/// Per triangle, a 3×4 affine transform `M` that maps A to the origin, `B − A` to `(1, 0, 0)`,
/// `C − A` to `(0, 1, 0)` and the coordinate axis `k` of the largest `|N|` to `(0, 0, 1)`
/// (the paper's choice of free vector: it makes one column of `M` a unit column, and the
/// transform cheap and well conditioned). In cyclic coordinates `(k, k+1, k+2)`:
///
/// ```text
/// row 0 = (0,  e2[k+2], −e2[k+1]) / N_k     (x' = weight of B)
/// row 1 = (0, −e1[k+2],  e1[k+1]) / N_k     (y' = weight of C)
/// row 2 = (N_k, N[k+1], N[k+2]) / |N_k|     (z' = signed distance to the plane, scaled)
/// translation: −M·A
/// ```
///
/// stored as twelve floats in x, y, z order, as the paper stores them (its third row divides
/// by `N_k`; here by `|N_k|`, so that `z'` keeps the sign of `N·d` for culling). Per test, with
/// full rows (the stored zeros and ones are multiplied like the others, as in the paper's
/// general test, so the test needs no branch on `k`):
///
/// ```text
/// s = row2·o + m23,  e = row2·d,  t = −s/e     the plane, one division
/// p = o + t·d;  u = row0·p + m03,  v = row1·p + m13
/// ```
///
/// A hit needs `t_min < t < t_max`, then `u ≥ 0`, `v ≥ 0`, `u + v ≤ 1`.
///
/// **Claimed count.** None found: the study reached the paper's abstract and first page (JCGT
/// 5(3); a transcript at vdocument.in), which claim speed, not operations: "always faster
/// than the standard Möller and Trumbore algorithm, and faster than a highly tuned modern
/// version of it except at very high ray-triangle hit rates", "at the expense of precomputing
/// and storing a small amount of extra information for each triangle", and 1–6 % faster
/// images in a complete ray tracer. Any operation count in the body is not checked here.
/// **Measured** per lane (pinned in `tests/suite/kernels/op_counts_pinned.rs`): a triangle behind the origin 6
/// mul, 5 add, 1 div, 2 cmp; a miss beyond edge BC and a hit 15 mul, 15 add, 1 div, 5 cmp;
/// precomputation 22 mul, 15 add, 1 div, 3 cmp. **Record:** 48 bytes.
///
/// **Limits.** Not watertight; `M` is rounded once per triangle, so `t`, `u`, `v` carry its
/// rounding. **Edge cases.** A ray parallel to the plane (`e = 0`) gives an infinite or NaN
/// `t`: a miss. NaN fails every compare.
#[derive(Clone, Copy, Debug, Default)]
pub struct BaldwinWeber;

/// [`BaldwinWeber`]'s record per triangle lane: the rows of the affine transform.
#[derive(Clone, Copy, Debug)]
pub struct AffineRecord<L: Lane> {
    rows: [V3<L>; 3],
    w: [L; 3],
}

/// Back from cyclic coordinates `(k, k+1, k+2)` to `(x, y, z)` (no arithmetic).
#[inline(always)]
fn uncyclic<L: Lane>(k: (L::Mask, L::Mask), v: V3<L>) -> V3<L> {
    let s = |x: L, y: L, z: L| L::select(k.0, x, L::select(k.1, y, z));
    V3::new(s(v.x, v.z, v.y), s(v.y, v.x, v.z), s(v.z, v.y, v.x))
}

precomputed_triangle_kernel!(BaldwinWeber, "baldwin-weber");

impl PrecomputedKernel for BaldwinWeber {
    const BYTES: usize = 48;
    type Prim<L: Lane> = AffineRecord<L>;

    #[inline(always)]
    fn precompute<L: Lane>(tri: &TrianglePacket<L>) -> AffineRecord<L> {
        let (e1, e2) = (tri.b - tri.a, tri.c - tri.a);
        let n = e1.cross(e2);
        let k = dominant(n);
        let (n, e1, e2) = (cyclic(k, n), cyclic(k, e1), cyclic(k, e2));
        let zero = L::from_f32(0.0);
        let inv = L::from_f32(1.0) / n.x;
        let abs = inv.abs();
        // Indexed, not `array::map`, which may be left out of line (crate::simd).
        let rows = [
            uncyclic(k, V3::new(zero, e2.z * inv, -(e2.y * inv))),
            uncyclic(k, V3::new(zero, -(e1.z * inv), e1.y * inv)),
            uncyclic(k, V3::new(n.x * abs, n.y * abs, n.z * abs)),
        ];
        AffineRecord {
            rows,
            w: [
                -rows[0].dot(tri.a),
                -rows[1].dot(tri.a),
                -rows[2].dot(tri.a),
            ],
        }
    }

    #[inline(always)]
    fn test<L: Lane>(ray: &RayPacket<L>, m: &AffineRecord<L>, cull: Cull) -> Option<LaneHit<L>> {
        let (zero, one) = (L::from_f32(0.0), L::from_f32(1.0));
        // 1. The plane in transformed coordinates: t = −z'(o)/z'(d). Front faces: z'(d) < 0.
        let s = m.rows[2].dot(ray.origin) + m.w[2];
        let e = m.rows[2].dot(ray.dir);
        let t = -s / e;
        let mut mask = t.gt(ray.t_min) & t.lt(ray.t_max);
        if cull.back() {
            mask = mask & e.lt(zero);
        }
        if mask.none() {
            return None;
        }
        // 2. The hit point, transformed: its x', y' are the barycentrics of B and C.
        let p = ray.origin.along(ray.dir, t);
        let u = m.rows[0].dot(p) + m.w[0];
        let v = m.rows[1].dot(p) + m.w[1];
        mask = mask & u.ge(zero) & v.ge(zero) & (u + v).le(one);
        Some(LaneHit::new(t, u, v, mask))
    }
}
