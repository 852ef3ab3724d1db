//! Badouel's ray–polygon test for triangles: the plane, then a 2-D test in a projection.

use super::precomputed::{PrecomputedKernel, cyclic, dominant, precomputed_triangle_kernel};
use super::{Cull, TrianglePacket};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// Didier Badouel, "An Efficient Ray-Polygon Intersection", Graphics Gems (1990), pp. 390–393.
///
/// Per triangle ([`precompute`](PrecomputedKernel::precompute)): the plane `N·x = N·A` with
/// `N = (B − A) × (C − A)`, the axis `k` of the largest `|N|` (the Gem's `i0`; the plane of
/// projection is spanned by the other two, `i1`, `i2`, in cyclic order) and the vertices'
/// coordinates on `i1`, `i2`. Per test:
///
/// ```text
/// t  = (N·A − N·o) / (N·d)                     the plane first, one division
/// p  = (o + t·d − A) on (i1, i2)                the hit point, relative to A, projected
/// β  = (e1 × p) / (e1 × e2)                     weight of C (e1 = B − A, e2 = C − A projected)
/// α  = (p × e2) / (e1 × e2)                     weight of B
/// ```
///
/// A hit needs `t_min < t < t_max`, then `0 ≤ β ≤ 1`, then `α ≥ 0`, `α + β ≤ 1`, each tested
/// as soon as it is known (the kernel returns when no lane is left). The Gem forms the second
/// weight from the first, `α = (u0 − β·u2)/u1`, with a branch for `u1 = 0`; lanes take the
/// branch-free 2-D Cramer form instead (one multiply more, no branch).
///
/// **Claimed count.** None found. The study searched the stored public pages and code for
/// the Gem's own figures and reached only its citation and one-line summaries (e.g.
/// Wikipedia's "a fast method"); its tally, if the Gem gives one, is not checked here.
/// **Measured** per lane (pinned in `tests/suite/kernels/op_counts_pinned.rs`): a triangle behind the origin
/// (the plane rejects) 6 mul, 5 add, 1 div, 2 cmp; a miss beyond edge BC and a hit 14 mul, 17
/// add, 3 div, 6 cmp; precomputation 9 mul, 11 add, 3 cmp. **Record:** 42 bytes (the plane, 16;
/// the two axes, 2 bytes as the Gem's `i1`, `i2`; six projected coordinates, 24).
///
/// **Limits.** Not watertight (the edges are tested in each triangle's own projection, after
/// the rounded `t`), and `t`, `u`, `v` carry the rounding of the stored plane. **Edge cases.**
/// `N·d = 0` makes `t` infinite or NaN: a miss; NaN anywhere fails every compare.
#[derive(Clone, Copy, Debug, Default)]
pub struct Badouel;

/// [`Badouel`]'s record per triangle lane.
#[derive(Clone, Copy, Debug)]
pub struct BadouelRecord<L: Lane> {
    n: V3<L>,
    nd: L,
    k: (L::Mask, L::Mask),
    a: [L; 2],
    b: [L; 2],
    c: [L; 2],
}

precomputed_triangle_kernel!(Badouel, "badouel");

impl PrecomputedKernel for Badouel {
    const BYTES: usize = 42;
    type Prim<L: Lane> = BadouelRecord<L>;

    #[inline(always)]
    fn precompute<L: Lane>(tri: &TrianglePacket<L>) -> BadouelRecord<L> {
        let n = (tri.b - tri.a).cross(tri.c - tri.a);
        let k = dominant(n);
        let on = |v: V3<L>| {
            let p = cyclic(k, v);
            [p.y, p.z]
        };
        BadouelRecord {
            n,
            nd: n.dot(tri.a),
            k,
            a: on(tri.a),
            b: on(tri.b),
            c: on(tri.c),
        }
    }

    #[inline(always)]
    fn test<L: Lane>(ray: &RayPacket<L>, r: &BadouelRecord<L>, cull: Cull) -> Option<LaneHit<L>> {
        let (zero, one) = (L::from_f32(0.0), L::from_f32(1.0));
        // 1. The plane: t = (N·A − N·o)/(N·d), strictly inside the interval. Front faces
        //    have N·d < 0.
        let den = r.n.dot(ray.dir);
        let t = (r.nd - r.n.dot(ray.origin)) / den;
        let mut mask = t.gt(ray.t_min) & t.lt(ray.t_max);
        if cull.back() {
            mask = mask & den.lt(zero);
        }
        if mask.none() {
            return None;
        }
        // 2. The hit point relative to A on the projection axes, and the projected edges.
        let (o, d) = (cyclic(r.k, ray.origin), cyclic(r.k, ray.dir));
        let pu = o.y + t * d.y - r.a[0];
        let pv = o.z + t * d.z - r.a[1];
        let (e1u, e1v) = (r.b[0] - r.a[0], r.b[1] - r.a[1]);
        let (e2u, e2v) = (r.c[0] - r.a[0], r.c[1] - r.a[1]);
        // 3. β, the weight of C, in [0, 1].
        let det = e1u * e2v - e1v * e2u;
        let beta = (e1u * pv - e1v * pu) / det;
        mask = mask & beta.ge(zero) & beta.le(one);
        if mask.none() {
            return None;
        }
        // 4. α, the weight of B: α ≥ 0 and α + β ≤ 1.
        let alpha = (pu * e2v - pv * e2u) / det;
        mask = mask & alpha.ge(zero) & (alpha + beta).le(one);
        Some(LaneHit::new(t, alpha, beta, mask))
    }
}
