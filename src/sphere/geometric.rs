//! The lecture's faster method (Glassner, *An Introduction to Ray Tracing*, 1989).

use super::{Roots, SphereKernel, SpherePacket};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// The geometric test for unit directions (lecture 000, "Faster Method").
///
/// With `T = C − E` (eye to centre), `c² = T·T` and the unit direction `U`, the distance along
/// the ray to the foot of the perpendicular from the centre is `v = T·U`, and the squared
/// distance from the centre to the ray is `b² = c² − v²`. The ray hits when `r² ≥ c² − v²`,
/// at `Q = E + (v ∓ d)U` with `d = √(r² − (c² − v²))`.
///
/// `T`, `c²` and `r²` depend only on the ray origin and the sphere: for rays from one focal
/// point they are computed once ([`Prepared`], [`Geometric::prepare`]) and the per-ray test is
/// the lecture's count:
///
/// ```text
/// v = T·U                     3 mul, 2 add
/// r² ≥ c² − v²                1 mul, 1 sub, 1 cmp     → miss: 4 mul, 3 add, 1 cmp
/// d = √(r² − (c² − v²))       1 sub, 1 sqrt
/// t = v ∓ d                   2 add                    (Q = E + tU: 3 mul, 3 add more)
/// ```
///
/// As a [`SphereKernel`] (one ray, one sphere, nothing cached) it first prepares `T`, `c²`,
/// `r²` (3 mul + 1 mul, 5 add): `ops geometric/miss: 8 mul, 8 add, 1 cmp`. A hit adds the
/// half chord, the two roots, the 4 interval compares and the 3 of the
/// [range guard](super#range): `ops geometric/hit: 8 mul, 11 add, 1 sqrt, 8 cmp`.
///
/// **Range.** `r` within `2^-30…2^30` and `c ≤ 2^30` in f32 (checked on `r²` and `c²`);
/// outside, [`SphereKernel::roots`] answers in `f64` with [`Robust`](super::Robust), while
/// [`Geometric::roots_prepared`] (whose prepared values no longer hold the sphere) misses.
///
/// **Requires unit directions.** **Limits:** `c² − v²` cancels for spheres far away relative to
/// their radius, as in [`Quadratic`](super::Quadratic): decisions near the rim degrade from
/// `c/r ≈ 2^8` and the sphere vanishes around 2^12; `t` is accurate to about `2^-24 c²/d`.
/// **Edge cases:** as for [`Quadratic`](super::Quadratic); a zero direction cannot reach the
/// kernel (rays are sanitised).
#[derive(Clone, Copy, Debug, Default)]
pub struct Geometric;

/// What the geometric test needs per (origin, sphere): `T = C − E`, `c² = T·T`, `r²`.
#[derive(Clone, Copy, Debug)]
pub struct Prepared<L: Lane> {
    /// Eye to centre.
    pub t: V3<L>,
    /// `T·T`.
    pub c2: L,
    /// Radius squared.
    pub r2: L,
}

impl Geometric {
    /// Computes `T`, `c²`, `r²` for rays from `eye` (3 add, 4 mul, 2 add).
    #[inline(always)]
    #[must_use]
    pub fn prepare<L: Lane>(eye: V3<L>, s: &SpherePacket<L>) -> Prepared<L> {
        let t = s.center - eye;
        Prepared {
            t,
            c2: t.dot(t),
            r2: s.radius * s.radius,
        }
    }

    /// The per-ray test with prepared values: the lecture's 4 mul, 3 add on a miss. Lanes
    /// outside the range (see [`Geometric`]) are a miss here: prepared values no longer hold
    /// the sphere for the `f64` fallback that [`SphereKernel::roots`] runs.
    #[inline(always)]
    #[must_use]
    pub fn roots_prepared<L: Lane>(ray: &RayPacket<L>, p: &Prepared<L>) -> Roots<L> {
        Self::body(ray, p).map_or_else(Roots::miss, |(roots, _)| roots)
    }

    /// The body: the roots of lanes in range, and the lanes the range guard sent away; `None`
    /// when no lane has real roots.
    #[inline(always)]
    fn body<L: Lane>(ray: &RayPacket<L>, p: &Prepared<L>) -> Option<(Roots<L>, L::Mask)> {
        // 1. Foot of the perpendicular along the ray.
        let v = p.t.dot(ray.dir);
        // 2. Squared distance from the centre to the ray, against r².
        let b2 = p.c2 - v * v;
        // `!(r² < b²)`: a NaN or infinite b² (squares that overflowed) goes on to the range
        // guard (`finite_or_nan` is not counted).
        let real = !p.r2.lt(b2.finite_or_nan());
        if real.none() {
            return None;
        }
        // 3. Half chord and both roots, for lanes inside the range.
        let escaped = super::escaped(real, None, p.r2, p.c2);
        let d = (p.r2 - b2).sqrt();
        Some((
            Roots::in_interval(ray, v - d, v + d, real.and_not(escaped)),
            escaped,
        ))
    }
}

impl SphereKernel for Geometric {
    const NAME: &'static str = "geometric";
    const UNIT_DIRECTIONS: bool = true;
    #[inline(always)]
    fn maybe_roots<L: Lane>(ray: &RayPacket<L>, sphere: &SpherePacket<L>) -> Option<Roots<L>> {
        let (roots, escaped) = Geometric::body(ray, &Geometric::prepare(ray.origin, sphere))?;
        Some(super::with_fallback(ray, sphere, roots, escaped))
    }
}
