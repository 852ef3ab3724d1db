//! Kensler and Shirley's optimised 3-D test (2006).

use super::{Cull, TriangleKernel, TrianglePacket};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// Andrew Kensler and Peter Shirley, "Optimizing Ray-Triangle Intersection via Automated
/// Search", IEEE Symposium on Interactive Ray Tracing 2006, pp. 33–38: the single-ray test
/// their search and hand optimisation arrived at, from the vertices alone.
///
/// With `e0 = B − A`, `e1 = A − C`, the normal `n = e1 × e0` (`= (B − A) × (C − A)`),
/// `c = A − o` and `r = d × c`, all three unknowns share one reciprocal:
///
/// ```text
/// k = 1/(n·d)        u = (r·e1)·k  (weight of B)   v = (r·e0)·k  (weight of C)
/// t = (n·c)·k
/// ```
///
/// A hit needs `u ≥ 0`, `v ≥ 0`, `u + v ≤ 1` (tested first), then `t_min < t < t_max`. Front
/// faces have `n·d < 0`.
///
/// **Claimed count.** None found: the study reached the paper's first page only (abstract:
/// the search's first fitness function "counts operations", the second benchmarks), not the
/// counts of the test it arrived at. Embree's `triangle_intersector_moeller.h` claims its own
/// Möller–Trumbore variant "is similar to the fastest one of the paper". Not checked here.
/// **Measured** per lane (pinned in `tests/suite/kernels/op_counts_pinned.rs`): miss 23 mul, 22 add, 1 div, 3
/// cmp; hit 27 mul, 24 add, 1 div, 5 cmp.
///
/// **Limits.** Not watertight (`c` differs between triangles that share an edge), and the
/// reciprocal rounds once more than a division. **Edge cases.** `n·d = 0` makes `k` infinite and
/// `u`, `v` infinite or NaN: a miss. NaN fails every compare.
#[derive(Clone, Copy, Debug, Default)]
pub struct KenslerShirley;

impl TriangleKernel for KenslerShirley {
    const NAME: &'static str = "kensler-shirley";
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
        let (zero, one) = (L::from_f32(0.0), L::from_f32(1.0));
        // 1. Edges, normal, and the one reciprocal.
        let e0 = tri.b - tri.a;
        let e1 = tri.a - tri.c;
        let n = e1.cross(e0);
        let c = tri.a - ray.origin;
        let den = n.dot(ray.dir);
        let k = one / den;
        // 2. Barycentrics from r = d × c.
        let r = ray.dir.cross(c);
        let u = r.dot(e1) * k;
        let v = r.dot(e0) * k;
        let mut mask = u.ge(zero) & v.ge(zero) & (u + v).le(one);
        if cull.back() {
            mask = mask & den.lt(zero);
        }
        if mask.none() {
            return None;
        }
        // 3. The distance, strictly inside the interval.
        let t = n.dot(c) * k;
        mask = mask & t.gt(ray.t_min) & t.lt(ray.t_max);
        Some(LaneHit::new(t, u, v, mask))
    }
}
