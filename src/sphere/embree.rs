//! Embree's sphere test (`kernels/geometry/sphere_intersector.h`).

use super::{Roots, SphereKernel, SpherePacket};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// Embree's ray–sphere test (Intel, `kernels/geometry/sphere_intersector.h`, 2018–): the
/// perpendicular from the centre to the ray, then the half chord.
///
/// With `k = 1/(d·d)` (Embree computes it once per ray, in its per-ray precalculations),
/// `c0 = c − o`:
///
/// ```text
/// τ = (c0·d)·k                  the foot of the perpendicular
/// p = c0 − τ·d,  ℓ² = p·p       the perpendicular, squared
/// hit when ℓ² ≤ r²:  h = √((r² − ℓ²)·k),  t = τ ∓ h
/// ```
///
/// It differs from raylane's kernels: [`Geometric`](super::Geometric) forms `c² − τ²` (needs unit
/// directions, cancels for far spheres), [`Robust`](super::Robust) uses stable roots
/// `c/q`, `q/a`; Embree keeps the accurate perpendicular but forms both roots as `τ ∓ h`, so
/// the near root cancels when the origin is close to the surface.
///
/// **Claimed count.** None: `sphere_intersector.h` states none (read for this study).
/// **Operation count per lane** (measured by `examples/opcount.rs`, the study table, pinned
/// in `tests/suite/kernels/op_counts_pinned.rs`; the
/// per-ray reciprocal, 3 mul, 2 add, 1 div, counted in): miss 14 mul, 12 add, 1 div, 1 cmp;
/// hit 15 mul, 15 add, 1 div, 1 sqrt, 5 cmp.
///
/// **Edge cases.** NaN input is a miss (`ℓ² ≤ r²` fails).
#[derive(Clone, Copy, Debug, Default)]
pub struct EmbreeSphere;

impl SphereKernel for EmbreeSphere {
    const NAME: &'static str = "embree";
    const UNIT_DIRECTIONS: bool = false;
    #[inline(always)]
    fn maybe_roots<L: Lane>(ray: &RayPacket<L>, s: &SpherePacket<L>) -> Option<Roots<L>> {
        let d = ray.dir;
        // 1. Per ray: 1/(d·d).
        let k = L::from_f32(1.0) / d.length_squared();
        // 2. The foot of the perpendicular and the perpendicular itself.
        let c0 = s.center - ray.origin;
        let tau = c0.dot(d) * k;
        let p = c0 - d.scale(tau);
        let l2 = p.length_squared();
        let r2 = s.radius * s.radius;
        let real = l2.le(r2);
        if real.none() {
            return None;
        }
        // 3. The half chord and the two roots.
        let h = ((r2 - l2) * k).sqrt();
        Some(Roots::in_interval(ray, tau - h, tau + h, real))
    }
}
