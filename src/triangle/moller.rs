//! Möller–Trumbore with the division deferred (as in Embree's `triangle_intersector_moeller`).

use super::{Cull, TriangleKernel, TrianglePacket, resolve};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// Möller & Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection" (JGT 2(1), 1997),
/// with the edge tests against the unscaled determinant.
///
/// With `e1 = B − A`, `e2 = C − A`, `s = o − A`, `p = d × e2`, `q = s × e1`:
///
/// ```text
/// det = e1·p            (= −d·N: front faces have det > 0)
/// U   = s·p             (= u·det, weight of B)
/// V   = d·q             (= v·det, weight of C)
/// T   = e2·q            (= t·det)
/// ```
///
/// With the sign of `det` folded into `U`, `V`, `T` (so `|det|` is the denominator), a hit
/// needs `U ≥ 0`, `V ≥ 0`, `U + V ≤ |det|`, `|det| > 0`, then `0 < T < t_max·|det|`; only then
/// one division `t = T/|det|`, and `u = U/|det|`, `v = V/|det|` once per ray for the winner
/// (see [`triangle`](super) on deferred division).
///
/// **Claimed count.** None found: the paper's abstract (the part the study reached) claims
/// storage and speed, not operations: "the plane equation need not be computed on the fly nor
/// be stored" and, "comparable in speed to previous methods", "the fastest ray/triangle
/// intersection routine for triangles which do not have precomputed plane equations".
/// **Operation count per lane** (measured by `examples/opcount.rs`):
/// `ops moller/miss: 21 mul, 22 add, 5 cmp`; a triangle behind the origin (no division)
/// `ops moller/behind: 24 mul, 24 add, 7 cmp`; `ops moller/hit: 25 mul, 24 add, 1 div, 12 cmp`.
///
/// **Limits.** Not watertight: the edge values of two triangles sharing an edge are computed
/// from different origins (`s = o − A` differs), so a ray through the edge can slip between
/// them or hit both (counts in `tests/watertight.rs`). **Edge cases.** `det = 0` (parallel
/// ray) is a miss; NaN anywhere fails the compares.
#[derive(Clone, Copy, Debug, Default)]
pub struct Moller;

impl TriangleKernel for Moller {
    const NAME: &'static str = "moller";
    type Rays<L: Lane> = ();

    #[inline(always)]
    fn prepare<L: Lane>(_: &RayPacket<L>) -> Self::Rays<L> {}

    #[inline(always)]
    fn maybe_intersect<L: Lane>(
        ray: &RayPacket<L>,
        _: &(),
        tri: &TrianglePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        let zero = L::from_f32(0.0);
        // 1. Edges from A and the determinant det = e1·(d × e2).
        let e1 = tri.b - tri.a;
        let e2 = tri.c - tri.a;
        let p = ray.dir.cross(e2);
        let det = e1.dot(p);
        // 2. Unscaled barycentrics: U = s·p (of B), V = d·(s × e1) (of C).
        let s = ray.origin - tri.a;
        let u = s.dot(p);
        let q = s.cross(e1);
        let v = ray.dir.dot(q);
        // 3. Edge tests against the unscaled determinant, its sign folded in.
        let back = det.lt(zero);
        let (us, vs) = (L::select(back, -u, u), L::select(back, -v, v));
        let ad = L::select(back, -det, det);
        let mut mask = us.ge(zero) & vs.ge(zero) & (us + vs).le(ad) & ad.gt(zero);
        if cull.back() {
            mask = mask.and_not(back);
        }
        if mask.none() {
            return None;
        }
        // 4. Distance numerator T = e2·q (= t·det); the interval, then the one division.
        let t = e2.dot(q);
        resolve(ray, mask, L::select(back, -t, t), us, vs, ad)
    }
}
