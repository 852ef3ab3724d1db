//! Plücker-coordinate edge tests relative to the ray origin (Segura & Feito 1998; as in
//! Embree's `triangle_intersector_pluecker.h`).

use super::{Cull, TriangleKernel, TrianglePacket, resolve};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// Rafael J. Segura and Francisco R. Feito, "An Algorithm for Determining Intersection
/// Segment-Polygon in 3D", Computers & Graphics 22(5), 1998, pp. 587–592 (the signs of
/// tetrahedron volumes, i.e. Plücker side products), in the form Embree uses
/// (`kernels/geometry/triangle_intersector_pluecker.h`): the vertices are shifted so that the
/// ray starts at the origin, where the Plücker product of the ray with an edge `(p, q)`
/// reduces to a triple product `d·(p × q)`, computed as `d·((q − p) × (q + p))/2`.
///
/// ```text
/// v0 = A − o, v1 = B − o, v2 = C − o
/// U = d·((v2 − v0) × (v2 + v0))    edge CA, opposite B (weight of B)
/// V = d·((v0 − v1) × (v0 + v1))    edge AB, opposite C (weight of C)
/// W = d·((v1 − v2) × (v1 + v2))    edge BC, opposite A
/// den = d·N,  T = v0·N,  N = (v2 − v0) × (v0 − v1)  (= (B − A) × (C − A))
/// ```
///
/// A hit needs `U`, `V`, `W` all `≥ −ε` or all `≤ ε` with `ε = 2^-23·|U + V + W|`, as Embree
/// widens them (front faces: `≤ ε`), `den ≠ 0`, then `0 < T/den` inside the
/// interval with the division deferred (see [`triangle`](super)); `u = U/(U+V+W)`,
/// `v = V/(U+V+W)` as Embree normalises them, after clamping the three at zero (Embree does not
/// clamp; here the reported `u`, `v` keep `u, v ≥ 0`, `u + v ≤ 1`). Embree scales `den` and `T` by 2 (`twice`),
/// which cancels in `T/den` and is left out, and picks each component of `N` from the
/// better-conditioned of two cross products (`stable_triangle_normal`, 6 mul, 3 add, 3 cmp
/// more); here `N` is one cross product.
///
/// **Why the edges are consistent.** `v2 − v0` is exactly `−(v0 − v2)` and `v2 + v0` exactly
/// `v0 + v2`, so a neighbour sharing the edge computes exactly the negated product: an edge
/// test never leaks between two triangles that share it (the shifted vertices are the same
/// bits for both), although a ray through a shared edge or vertex may hit both. Around a
/// shared vertex the products of the edges that meet there are rounded values near zero, and
/// without the widening `ε` they can all exclude the ray: exact compares leaked 4 of the
/// 10,950 rays of `tests/suite/kernels/watertight_no_leaks.rs`; with `ε` the counts are in the study table.
///
/// **Claimed count.** None found. Embree's source states none (read for this study); the
/// study did not reach Segura and Feito's text (only its citation), so a tally there, if any,
/// is not checked. **Measured** per lane (pinned in `tests/suite/kernels/op_counts_pinned.rs`): miss 28 mul,
/// 44 add, 6 cmp; hit 41 mul, 53 add, 1 div, 20 cmp.
///
/// **Edge cases.** `den = 0` or `U + V + W = 0` is a miss; NaN fails every compare.
#[derive(Clone, Copy, Debug, Default)]
pub struct Plucker;

impl TriangleKernel for Plucker {
    const NAME: &'static str = "plucker";
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
        let d = ray.dir;
        // 1. Vertices relative to the origin, and the edges.
        let v0 = tri.a - ray.origin;
        let v1 = tri.b - ray.origin;
        let v2 = tri.c - ray.origin;
        let e0 = v2 - v0;
        let e1 = v0 - v1;
        let e2 = v1 - v2;
        // 2. Edge tests: the side of the ray against each edge.
        let u = d.dot(e0.cross(v2 + v0));
        let v = d.dot(e1.cross(v0 + v1));
        let w = d.dot(e2.cross(v1 + v2));
        // Embree widens both tests by eps = 2^-23·|U + V + W|, so that the rounded, nearly
        // zero products of the edges around a vertex cannot all exclude the ray.
        let sum = u + v + w;
        let eps = L::from_f32(f32::EPSILON) * sum.abs();
        let neps = -eps;
        let front = u.le(eps) & v.le(eps) & w.le(eps);
        let mut mask = if cull.back() {
            front
        } else {
            front | (u.ge(neps) & v.ge(neps) & w.ge(neps))
        };
        if mask.none() {
            return None;
        }
        // 3. Normal, denominator, distance numerator. The edge values get the sign of
        //    U + V + W folded in and are clamped at zero (the widening lets them reach −ε), so
        //    that u, v ≥ 0 and u + v ≤ 1 hold for the reported hit.
        let n = e0.cross(e1);
        let den = n.dot(d);
        let tn = v0.dot(n);
        let neg = sum.lt(zero);
        let dneg = den.lt(zero);
        // A function, not a let-bound closure, which may be left out of line (crate::simd).
        #[inline(always)]
        fn fold<L: Lane>(x: L, neg: L::Mask, zero: L) -> L {
            let x = L::select(neg, -x, x);
            L::select(x.lt(zero), zero, x)
        }
        let (us, vs, ws) = (fold(u, neg, zero), fold(v, neg, zero), fold(w, neg, zero));
        let asum = us + vs + ws;
        let ad = L::select(dneg, -den, den);
        mask = mask & ad.gt(zero) & asum.gt(zero);
        if mask.none() {
            return None;
        }
        // 4. The interval, the one division; u, v are deferred over U + V + W.
        let mut h = resolve(ray, mask, L::select(dneg, -tn, tn), us, vs, ad)?;
        h.w = L::select(h.mask, asum, L::from_f32(1.0));
        Some(h)
    }
}
