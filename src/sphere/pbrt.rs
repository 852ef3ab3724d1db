//! pbrt-v4's sphere test (`Sphere::BasicIntersect`), its interval arithmetic left out.

use super::{Roots, SphereKernel, SpherePacket};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// Pharr, Jakob and Humphreys, *Physically Based Rendering*, 4th edition (2023), section 6.2.2
/// (`Sphere::BasicIntersect` in pbrt-v4's `shapes.h`), with plain `f32` in place of its
/// `Interval` type and the sphere's object space a translation by the centre.
///
/// With `f = o − c`, `a = d·d`, `b = 2·(d·f)`, `c = f·f − r²`:
///
/// ```text
/// v = f − (b/(2a))·d,  ℓ = |v|              (the perpendicular, as Ray Tracing Gems ch. 7)
/// Δ = 4a·(r + ℓ)·(r − ℓ)                    (x² − y² as (x + y)(x − y))
/// q = −(b − √Δ)/2 if b < 0, else −(b + √Δ)/2
/// t0 = q/a, t1 = c/q, swapped when t0 > t1
/// ```
///
/// It differs from [`Robust`](super::Robust) (the same book's source): the perpendicular's
/// length is a square root, so the discriminant factors as `(r + ℓ)(r − ℓ)` instead of
/// `r² − ℓ·ℓ`, and the factors 2, 4 and ½ of the textbook quadratic stay (exact multiplies).
///
/// **Claimed count.** None quoted: the study did not search the book's text for one.
/// **Operation count per lane** (measured by `examples/opcount.rs`, the study table; pinned in
/// `tests/suite/kernels/op_counts_pinned.rs`): miss 21 mul, 17 add, 1 div, 1 sqrt, 1 cmp; hit 22 mul, 18 add,
/// 3 div, 2 sqrt, 7 cmp.
///
/// **Limits.** The decisions carry the rounding of `ℓ` (a few `2^-24·|f|`), like
/// [`Robust`](super::Robust)'s. **Edge cases.** `b = 0` with `Δ = 0` makes `q = 0`: roots NaN or
/// infinite, a miss. NaN input is a miss.
#[derive(Clone, Copy, Debug, Default)]
pub struct Pbrt;

impl SphereKernel for Pbrt {
    const NAME: &'static str = "pbrt";
    const UNIT_DIRECTIONS: bool = false;
    #[inline(always)]
    fn maybe_roots<L: Lane>(ray: &RayPacket<L>, s: &SpherePacket<L>) -> Option<Roots<L>> {
        let d = ray.dir;
        let (zero, half, two) = (L::from_f32(0.0), L::from_f32(0.5), L::from_f32(2.0));
        // 1. Object space (a translation), and the quadratic's coefficients.
        let f = ray.origin - s.center;
        let a = d.length_squared();
        let b = two * d.dot(f);
        let c = f.length_squared() - s.radius * s.radius;
        // 2. The perpendicular's length and the factored discriminant.
        let v = f - d.scale(b / (two * a));
        let l = v.length_squared().sqrt();
        let disc = L::from_f32(4.0) * a * (s.radius + l) * (s.radius - l);
        let real = disc.ge(zero);
        if real.none() {
            return None;
        }
        // 3. Stable roots, ordered by a compare.
        let root = disc.sqrt();
        let q = -(half * (b + L::select(b.lt(zero), -root, root)));
        let (t0, t1) = (q / a, c / q);
        let swap = t0.gt(t1);
        Some(Roots::in_interval(
            ray,
            L::select(swap, t1, t0),
            L::select(swap, t0, t1),
            real,
        ))
    }
}
