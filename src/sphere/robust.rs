//! The robust f32 formulation (Haines, Günther, Akenine-Möller: "Precision Improvements for
//! Ray/Sphere Intersection", Ray Tracing Gems, 2019, ch. 7; precision lecture 001).

use super::{Roots, SphereKernel, SpherePacket};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// Perpendicular-distance discriminant and stable roots; any nonzero direction.
///
/// With `f = o − c`, `a = d·d` and `β = −f·d`, the vector from the centre to the foot of the
/// perpendicular is `l = f + (β/a)·d` (= `f − (f·d̂)d̂`). Subtracting *before* squaring keeps
/// the bits that `f·f − r²` loses:
///
/// ```text
/// Δ = a (r² − l·l)                       (= b'² − a c, the discriminant over 4)
/// q = β + sign(β) √Δ                      (no cancellation)
/// t0 = c / q,  t1 = q / a,  c = f·f − r²  (t0·t1 = c/a)
/// ```
///
/// **Operation count per lane**: `ops robust/miss: 14 mul, 13 add, 1 div, 1 cmp`; a hit
/// (`ops robust/hit: 17 mul, 17 add, 3 div, 1 sqrt, 12 cmp`) adds 3 mul, 4 add,
/// 2 div, 1 sqrt, 1 cmp (the sign), 1 cmp (the order: near tangency `c/q` and `q/a` are
/// rounded separately and used to come back up to 6 ulps out of order at `|f|/r ≥ 2^18`; a
/// select makes them ascending), the 4 interval compares and the 5 of the
/// [range guard](super#range).
///
/// **Range.** `|d|`, `r` within `2^-30…2^30` and `|f| ≤ 2^30` in f32; lanes outside are
/// recomputed by this same body in `f64` (or, below `2^-62`, may miss) — see
/// [the module](super#range).
///
/// **Limits.** Decisions are exact up to an error of a few `2^-24·|f|` in the distance `|l|`:
/// rays passing within about `8·2^-24·|f|` of the rim of a far sphere may be misclassified
/// (beyond `|f|/r ≈ 2^16` that band covers a visible part of the sphere; the focal cache
/// sends those lanes to an `f64` evaluation of this same body). `t0 = c/q` inherits the
/// rounding of `c = f·f − r²`, which is large relative to `c` only when the origin lies within
/// about `2^-10·|f|` of the surface.
///
/// **Edge cases.** `β = 0` with `Δ = 0` makes `q = 0` and the roots NaN or infinite: a miss.
/// NaN input is a miss.
#[derive(Clone, Copy, Debug, Default)]
pub struct Robust;

impl SphereKernel for Robust {
    const NAME: &'static str = "robust";
    const UNIT_DIRECTIONS: bool = false;
    #[inline(always)]
    fn maybe_roots<L: Lane>(ray: &RayPacket<L>, s: &SpherePacket<L>) -> Option<Roots<L>> {
        let d = ray.dir;
        // 1. Centre to origin, a = d·d, β = −f·d.
        let f = ray.origin - s.center;
        let a = d.length_squared();
        let beta = -f.dot(d);
        // 2. Perpendicular from the centre to the ray, and the discriminant.
        let l = f.along(d, beta / a);
        let r2 = s.radius * s.radius;
        let disc = a * (r2 - l.length_squared());
        // `!(Δ < 0)`: a NaN or infinite Δ (squares that overflowed) goes on to the range
        // guard, unless the sphere is invalid or padding (NaN radius): such lanes are dropped
        // after the early exit, which the common miss thus takes on one compare
        // (`finite_or_nan` and `is_finite` are not counted).
        let real = !disc.finite_or_nan().lt(L::from_f32(0.0));
        if real.none() {
            return None;
        }
        // Packets drop them here, so that a leaf's padding lanes keep a packet on the miss
        // path; one ray's NaN roots fail the interval and the guard drops them.
        let real = if L::LANES > 1 {
            real & s.radius.is_finite()
        } else {
            real
        };
        if real.none() {
            return None;
        }
        // 3. Stable roots: q never cancels; the smaller root is c/q when β ≥ 0.
        let ff = f.length_squared();
        let c = ff - r2;
        let root = disc.sqrt();
        let up = beta.ge(L::from_f32(0.0));
        let q = beta + L::select(up, root, -root);
        let (ta, tb) = (c / q, q / a);
        let (lo, hi) = (L::select(up, ta, tb), L::select(up, tb, ta));
        // 4. Ascending: near tangency c/q and q/a are rounded separately and may cross.
        let swap = hi.lt(lo);
        let (lo, hi) = (L::select(swap, hi, lo), L::select(swap, lo, hi));
        let roots = Roots::in_interval(ray, lo, hi, real);
        // 5. The range guard: lanes whose scale left f32's safe range, recomputed in f64.
        let escaped = super::escaped(real, Some(a), r2, ff);
        Some(super::with_fallback(ray, s, roots, escaped))
    }
}
