//! Wald's projection test with a precomputed record (his thesis, 2004).

use super::precomputed::{PrecomputedKernel, cyclic, dominant, precomputed_triangle_kernel};
use super::{Cull, TrianglePacket};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// Ingo Wald, *Realtime Ray Tracing and Interactive Global Illumination*, PhD thesis,
/// Saarland University (2004), section 7.1 ("the optimized ray–triangle test", the
/// `TriAccel` record).
///
/// Per triangle: the axis `k` of the largest `|N|` (`u`, `v` the other two, cyclic), the
/// plane scaled so that its `k` coefficient is 1 (`n_u = N_u/N_k`, `n_v = N_v/N_k`,
/// `n_d = N·A/N_k`), and the two edge lines of the projected triangle scaled so that they give
/// the barycentrics directly (`N_k` is the projected determinant):
///
/// ```text
/// u = b_nu·h_u + b_nv·h_v + b_d     b_nu = e2_v/N_k,  b_nv = −e2_u/N_k   (weight of B)
/// v = c_nu·h_u + c_nv·h_v + c_d     c_nu = −e1_v/N_k, c_nv = e1_u/N_k    (weight of C)
/// ```
///
/// Per test: `f = (n_d − o_k − n_u·o_u − n_v·o_v) · 1/(d_k + n_u·d_u + n_v·d_v)`, then
/// `t_min < f < t_max`, the hit point `h = o + f·d` on `u`, `v`, then `u ≥ 0`, `v ≥ 0`,
/// `u + v ≤ 1`, each exit as early as the thesis takes it. The division is a reciprocal and a
/// multiply, as in the thesis.
///
/// **Claimed count.** None found. The study searched the stored public pages and code for the
/// thesis' figures for this test and reached implementations of the `TriAccel` record, not
/// the thesis' text; its tally, if any, is not checked here.
/// **Measured** per lane (pinned in `tests/suite/kernels/op_counts_pinned.rs`): a triangle behind the origin 5
/// mul, 5 add, 1 div, 2 cmp; a miss beyond edge BC and a hit 11 mul, 12 add, 1 div, 5 cmp;
/// precomputation 20 mul, 13 add, 1 div, 4 cmp. **Record:** 37 bytes (nine floats and the axis
/// with the sign of `N_k` in one byte; the thesis pads its `TriAccel` to 48).
///
/// **Limits.** Not watertight; the scaled plane and lines are rounded once per triangle, so
/// `t`, `u`, `v` carry their rounding. **Edge cases.** A ray parallel to the plane makes the
/// reciprocal infinite and `f` infinite or NaN: a miss. NaN fails every compare.
#[derive(Clone, Copy, Debug, Default)]
pub struct Wald;

/// [`Wald`]'s record per triangle lane (the thesis' `TriAccel`).
#[derive(Clone, Copy, Debug)]
pub struct WaldRecord<L: Lane> {
    n: [L; 3],
    b: [L; 3],
    c: [L; 3],
    k: (L::Mask, L::Mask),
    neg: L::Mask,
}

precomputed_triangle_kernel!(Wald, "wald");

impl PrecomputedKernel for Wald {
    const BYTES: usize = 37;
    type Prim<L: Lane> = WaldRecord<L>;

    #[inline(always)]
    fn precompute<L: Lane>(tri: &TrianglePacket<L>) -> WaldRecord<L> {
        let (e1, e2) = (tri.b - tri.a, tri.c - tri.a);
        let n = e1.cross(e2);
        let k = dominant(n);
        let (n, a, e1, e2) = (cyclic(k, n), cyclic(k, tri.a), cyclic(k, e1), cyclic(k, e2));
        // N_k is also the determinant of the projected edges (cyclic axes keep the sign).
        let inv = L::from_f32(1.0) / n.x;
        let (bu, bv) = (e2.z * inv, -(e2.y * inv));
        let (cu, cv) = (-(e1.z * inv), e1.y * inv);
        WaldRecord {
            n: [n.y * inv, n.z * inv, n.dot(a) * inv],
            b: [bu, bv, -(bu * a.y + bv * a.z)],
            c: [cu, cv, -(cu * a.y + cv * a.z)],
            k,
            neg: n.x.lt(L::from_f32(0.0)),
        }
    }

    #[inline(always)]
    fn test<L: Lane>(ray: &RayPacket<L>, r: &WaldRecord<L>, cull: Cull) -> Option<LaneHit<L>> {
        let (zero, one) = (L::from_f32(0.0), L::from_f32(1.0));
        let (o, d) = (cyclic(r.k, ray.origin), cyclic(r.k, ray.dir));
        // 1. The distance to the plane, f = (n_d − n·o)/(n·d), by a reciprocal (N·d has the
        //    sign of den·N_k: front faces have it negative).
        let den = d.x + r.n[0] * d.y + r.n[1] * d.z;
        let nd = one / den;
        let f = (r.n[2] - o.x - r.n[0] * o.y - r.n[1] * o.z) * nd;
        let mut mask = f.gt(ray.t_min) & f.lt(ray.t_max);
        if cull.back() {
            mask = mask & L::select(r.neg, -den, den).lt(zero);
        }
        if mask.none() {
            return None;
        }
        // 2. The hit point on the projection axes.
        let hu = o.y + f * d.y;
        let hv = o.z + f * d.z;
        // 3. u, the weight of B.
        let u = hu * r.b[0] + hv * r.b[1] + r.b[2];
        mask = mask & u.ge(zero);
        if mask.none() {
            return None;
        }
        // 4. v, the weight of C, and the third edge.
        let v = hu * r.c[0] + hv * r.c[1] + r.c[2];
        mask = mask & v.ge(zero) & (u + v).le(one);
        Some(LaneHit::new(f, u, v, mask))
    }
}
