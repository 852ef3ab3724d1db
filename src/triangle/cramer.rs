//! The lecture's formulation: the 3×3 system solved by Cramer's rule (lecture 002).

use super::{Cull, TriangleKernel, TrianglePacket};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// Cramer's rule on the lecture's system (lecture 002, eqs. 19–25).
///
/// Substituting the ray into the plane of the triangle, `o + t·d = A + β(B − A) + γ(C − A)`,
/// gives the 3×3 system `β(A − B) + γ(A − C) + t·d = A − o`. With the columns `e1 = A − B`,
/// `e2 = A − C`, `s = A − o` and `det[x y z] = x·(y × z)`:
///
/// ```text
/// D = det[e1 e2 d]  = e1·(e2 × d)          (= d·N, N = (B − A) × (C − A))
/// β = det[s  e2 d]/D = (s·(e2 × d))/D       weight of B (u)
/// γ = det[e1 s  d]/D = (e1·(s × d))/D       weight of C (v)
/// t = det[e1 e2 s]/D = (s·(e1 × e2))/D
/// ```
///
/// `D` and `β` share the minor `e2 × d`. A hit needs `D ≠ 0`, `0 ≤ β ≤ 1`, `γ ≥ 0`, `β + γ ≤
/// 1` (the lecture lists `0 ≤ γ ≤ 1`, which would accept points beyond edge BC; the sum is
/// the third edge) and `t_min < t < t_max`. Each quotient is formed as soon as it is needed
/// and tested at once, so the masks narrow and the kernel returns when no lane is left.
///
/// **Operation count per lane** (measured by `examples/opcount.rs`): a miss beyond edge BC
/// (the latest exit) `ops cramer/miss: 21 mul, 22 add, 2 div, 5 cmp`; one outside
/// `0 ≤ β ≤ 1` exits after `ops cramer/miss (β): 12 mul, 16 add, 1 div, 3 cmp`; a hit
/// `ops cramer/hit: 30 mul, 27 add, 3 div, 7 cmp`.
///
/// **Limits.** Not watertight: `β`, `γ` and the sum are rounded independently, so a ray
/// through a shared edge can slip between two triangles or hit both (see
/// `tests/watertight.rs` for measured counts). **Edge cases.** `D = 0` (a ray parallel to the
/// plane, including one lying in it) is a miss; NaN anywhere fails every compare.
#[derive(Clone, Copy, Debug, Default)]
pub struct Cramer;

impl TriangleKernel for Cramer {
    const NAME: &'static str = "cramer";
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
        // 1. The columns of the system: A − B, A − C and the right-hand side A − o.
        let e1 = tri.a - tri.b;
        let e2 = tri.a - tri.c;
        let s = tri.a - ray.origin;
        // 2. D = det[e1 e2 d]; zero for rays parallel to the plane. Front faces have D < 0.
        let m = e2.cross(ray.dir);
        let den = e1.dot(m);
        let mut mask = if cull.back() {
            den.lt(zero)
        } else {
            den.abs().gt(zero)
        };
        if mask.none() {
            return None;
        }
        // 3. β = det[s e2 d]/D, the weight of B, in [0, 1].
        let beta = s.dot(m) / den;
        mask = mask & beta.ge(zero) & beta.le(one);
        if mask.none() {
            return None;
        }
        // 4. γ = det[e1 s d]/D, the weight of C: γ ≥ 0 and β + γ ≤ 1.
        let gamma = e1.dot(s.cross(ray.dir)) / den;
        mask = mask & gamma.ge(zero) & (beta + gamma).le(one);
        if mask.none() {
            return None;
        }
        // 5. t = det[e1 e2 s]/D inside the open interval.
        let t = s.dot(e1.cross(e2)) / den;
        mask = mask & t.gt(ray.t_min) & t.lt(ray.t_max);
        Some(LaneHit::new(t, beta, gamma, mask))
    }
}
