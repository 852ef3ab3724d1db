//! The brute-force quadratic (lectures 000 and 004).

use super::{Roots, SphereKernel, SpherePacket};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// The general quadratic, any nonzero direction (lecture 004, `Sphere::AppendAllIntersections`).
///
/// Substituting the ray `o + t·d` into `|p − c|² = r²` gives `a t² + b t + c = 0` with
/// `a = d·d`, `b = 2 d·(o − c)`, `c = |o − c|² − r²`. With `T = c − o` and `μ = d·T = −b/2`
/// (the half coefficient saves two multiplies and changes no rounding that matters):
///
/// ```text
/// δ = μ² − a (T·T − r²)        (= (b² − 4ac)/4)
/// t = (μ ∓ √δ) / a             when δ ≥ 0
/// ```
///
/// **Operation count per lane** (measured by `examples/opcount.rs`):
/// `ops quadratic/miss: 12 mul, 11 add, 1 cmp`; a hit adds 1 sqrt, 2 add, 2 div, the 4
/// interval compares and the 5 compares of the [range guard](super#range):
/// `ops quadratic/hit: 12 mul, 13 add, 2 div, 1 sqrt, 10 cmp` (`QuadraticUnit`, with 3:
/// `ops quadratic-unit/hit: 8 mul, 11 add, 1 sqrt, 8 cmp`).
///
/// **Range.** `|d|`, `r` within `2^-30…2^30` and `|o − c| ≤ 2^30` in f32; lanes outside are
/// answered by [`Robust`] in `f64` or (below `2^-62`) miss — see [the module](super#range).
///
/// **Limits.** In f32 the constant term `T·T − r²` loses `2·log2(|T|/r)` bits, so spheres far
/// away relative to their size are misclassified near their rim from about `|T|/r ≈ 2^8` on
/// and vanish altogether at about 2^12 (the precision lecture's disappearing sphere); and the
/// near root `μ − √δ` cancels when the origin is close to a huge sphere. Use [`Robust`] or the
/// focal cache there.
///
/// **Edge cases.** A tangent ray (`δ = 0`) hits twice at the same `t`. NaN anywhere yields a
/// miss (every compare is false); bad rays and spheres are sanitised by their constructors.
///
/// [`Robust`]: super::Robust
#[derive(Clone, Copy, Debug, Default)]
pub struct Quadratic;

/// The lecture-000 brute force for unit directions: `a = 1`, so `t = μ ∓ √(μ² − T·T + r²)`.
///
/// ```text
/// T = C − L          3 add
/// μ = U·T            3 mul, 2 add
/// T·T                3 mul, 2 add
/// r²                 1 mul
/// δ = μ² − (T·T − r²) 1 mul, 2 add    → miss: 8 mul, 9 add, 1 cmp (δ ≥ 0)
/// √δ                 1 sqrt           → the lecture's "8 multiplies, 9 additions, 1 square root"
/// t = μ ∓ √δ         2 add            (the two roots; the lecture's tally leaves these out)
/// ```
///
/// The point `P = L + tU` adds 3 mul and 3 add ([`surface`](super::surface)); the hit path
/// also runs the [range guard](super#range) (3 cmp).
///
/// **Requires unit directions**: with `|d| ≠ 1` the roots are wrong (nothing is normalised).
/// Limits and edge cases as for [`Quadratic`].
#[derive(Clone, Copy, Debug, Default)]
pub struct QuadraticUnit;

/// One body for both: `UNIT` skips `a = d·d` and the divisions.
#[inline(always)]
fn quadratic<L: Lane, const UNIT: bool>(
    ray: &RayPacket<L>,
    s: &SpherePacket<L>,
) -> Option<Roots<L>> {
    // 1. Base to centre and the half linear coefficient.
    let t = s.center - ray.origin;
    let mu = ray.dir.dot(t);
    // 2. The discriminant (over 4): δ = μ² − a(T·T − r²).
    let tt = t.dot(t);
    let r2 = s.radius * s.radius;
    let c = tt - r2;
    let a = if UNIT {
        L::from_f32(1.0)
    } else {
        ray.dir.length_squared()
    };
    let delta = if UNIT { mu * mu - c } else { mu * mu - a * c };
    // `!(δ < 0)`: a NaN or infinite δ (squares that overflowed) goes on to the range guard,
    // unless the sphere is invalid or padding (NaN radius): such lanes are dropped after the
    // early exit, which the common miss thus takes on one compare (`finite_or_nan` and
    // `is_finite` are not counted).
    let real = !delta.finite_or_nan().lt(L::from_f32(0.0));
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
    // 3. Both roots, ascending.
    let root = delta.sqrt();
    let (lo, hi) = if UNIT {
        (mu - root, mu + root)
    } else {
        ((mu - root) / a, (mu + root) / a)
    };
    let roots = Roots::in_interval(ray, lo, hi, real);
    // 4. The range guard: lanes whose scale left f32's safe range, recomputed in f64.
    let escaped = super::escaped(real, (!UNIT).then_some(a), r2, tt);
    Some(super::with_fallback(ray, s, roots, escaped))
}

impl SphereKernel for Quadratic {
    const NAME: &'static str = "quadratic";
    const UNIT_DIRECTIONS: bool = false;
    #[inline(always)]
    fn maybe_roots<L: Lane>(ray: &RayPacket<L>, sphere: &SpherePacket<L>) -> Option<Roots<L>> {
        quadratic::<L, false>(ray, sphere)
    }
}

impl SphereKernel for QuadraticUnit {
    const NAME: &'static str = "quadratic-unit";
    const UNIT_DIRECTIONS: bool = true;
    #[inline(always)]
    fn maybe_roots<L: Lane>(ray: &RayPacket<L>, sphere: &SpherePacket<L>) -> Option<Roots<L>> {
        quadratic::<L, true>(ray, sphere)
    }
}
