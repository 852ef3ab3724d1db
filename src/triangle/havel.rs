//! Havel and Herout's test on three precomputed planes (2010).

use super::precomputed::{PrecomputedKernel, precomputed_triangle_kernel};
use super::{Cull, TrianglePacket, resolve};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// Jiří Havel and Adam Herout, "Yet Faster Ray-Triangle Intersection (Using SSE4)", IEEE TVCG
/// 16(3), 2010, pp. 434–438.
///
/// Per triangle, three planes (12 floats): the triangle's plane `n0 = (B − A) × (C − A)`,
/// `d0 = n0·A`, and two planes through the edges from A, perpendicular to the triangle and
/// scaled so that they measure the barycentrics: `n1 = (e2 × n0)/|n0|²`, `d1 = −n1·A` (weight of
/// B), `n2 = (n0 × e1)/|n0|²`, `d2 = −n2·A` (weight of C). Per test, everything scaled by the
/// determinant so that nothing is divided before the edges pass:
///
/// ```text
/// det = n0·d        T = d0 − n0·o        (= t·det)
/// P'  = det·o + T·d                      (= det·(o + t·d), the hit point scaled)
/// U   = n1·P' + d1·det   V = n2·P' + d2·det   W = det − U − V
/// ```
///
/// A hit needs `U`, `V`, `W` of one sign with `det` (the paper compares sign bits; here the
/// sign of `det` is folded in and the three tested `≥ 0`), `det ≠ 0`, then the interval and the
/// one division (see [`triangle`](super) on deferred division). Front faces have `det < 0`.
///
/// **Claimed count.** None found: the study reached the paper's abstract only (IEEE TVCG
/// 16(3), doi 10.1109/TVCG.2009.73), which claims speed, not operations: the method "—when
/// implemented on SSE4—outperforms the current state-of-the-art algorithms" and "allows both a
/// single ray and ray packet intersection calculation with the same precomputed data". Any
/// operation count in the paper's body is not checked here.
/// **Measured** per lane (pinned in `tests/suite/kernels/op_counts_pinned.rs`): miss 20 mul, 16 add, 5 cmp; hit
/// 21 mul, 16 add, 1 div, 12 cmp; behind the origin 20 mul, 16 add, 7 cmp; precomputation 36
/// mul, 23 add, 1 div. **Record:** 48 bytes.
///
/// **Limits.** Not watertight; the scaled planes are rounded once per triangle, and `U`, `V`
/// grow with the distance of the origin from the triangle (`P'` is formed before anything is
/// subtracted). **Edge cases.** `det = 0` is a miss; NaN fails every compare.
#[derive(Clone, Copy, Debug, Default)]
pub struct HavelHerout;

/// [`HavelHerout`]'s record per triangle lane: three planes.
#[derive(Clone, Copy, Debug)]
pub struct PlanesRecord<L: Lane> {
    n0: V3<L>,
    d0: L,
    n1: V3<L>,
    d1: L,
    n2: V3<L>,
    d2: L,
}

precomputed_triangle_kernel!(HavelHerout, "havel-herout");

impl PrecomputedKernel for HavelHerout {
    const BYTES: usize = 48;
    type Prim<L: Lane> = PlanesRecord<L>;

    #[inline(always)]
    fn precompute<L: Lane>(tri: &TrianglePacket<L>) -> PlanesRecord<L> {
        let (e1, e2) = (tri.b - tri.a, tri.c - tri.a);
        let n0 = e1.cross(e2);
        let inv = L::from_f32(1.0) / n0.length_squared();
        let n1 = e2.cross(n0).scale(inv);
        let n2 = n0.cross(e1).scale(inv);
        PlanesRecord {
            n0,
            d0: n0.dot(tri.a),
            n1,
            d1: -n1.dot(tri.a),
            n2,
            d2: -n2.dot(tri.a),
        }
    }

    #[inline(always)]
    fn test<L: Lane>(ray: &RayPacket<L>, r: &PlanesRecord<L>, cull: Cull) -> Option<LaneHit<L>> {
        let zero = L::from_f32(0.0);
        // 1. The determinant and the scaled distance.
        let det = r.n0.dot(ray.dir);
        let tn = r.d0 - r.n0.dot(ray.origin);
        // 2. The hit point scaled by det, and the scaled barycentrics.
        let p = ray.origin.scale(det) + ray.dir.scale(tn);
        let u = r.n1.dot(p) + r.d1 * det;
        let v = r.n2.dot(p) + r.d2 * det;
        let w = det - u - v;
        // 3. One sign with det (folded in), det ≠ 0.
        let front = det.lt(zero);
        let sgn = |x: L| L::select(front, -x, x);
        let ad = sgn(det);
        let (us, vs) = (sgn(u), sgn(v));
        let mut mask = us.ge(zero) & vs.ge(zero) & sgn(w).ge(zero) & ad.gt(zero);
        if cull.back() {
            mask = mask & front;
        }
        if mask.none() {
            return None;
        }
        // 4. The interval, then the one division.
        resolve(ray, mask, sgn(tn), us, vs, ad)
    }
}
