//! Ray–sphere intersection: six formulations over one lane abstraction.
//!
//! | kernel | from | directions | strength |
//! | --- | --- | --- | --- |
//! | [`Quadratic`] | the general quadratic (lecture 004, `AppendAllIntersections`) | any | the textbook; fails for far small spheres and near roots of huge spheres |
//! | [`QuadraticUnit`] | the brute force of lecture 000 with `a = 1` | unit | the lecture's operation count |
//! | [`Geometric`] | the lecture's "faster method" (Glassner) | unit | fewest operations for a single ray |
//! | [`Robust`] | Ray Tracing Gems ch. 7 (precision lecture 001) | any | perpendicular-distance discriminant, stable roots |
//! | [`Pbrt`] | pbrt-v4's `Sphere::BasicIntersect` (intervals aside) | any | the same perpendicular as [`Robust`], discriminant as (r + ℓ)(r − ℓ) with ℓ = \|v\| |
//! | [`EmbreeSphere`] | Embree's `sphere_intersector.h` | any | perpendicular foot, roots τ ∓ h |
//! | [`focal`] | rays from one focal point, cached per sphere, with a precision guard | unit | 4 mul + 2 add per miss, exact hit/miss decisions to c/r = 2^20 |
//!
//! Every kernel returns all roots inside the ray's open interval, ascending ([`Roots`]): both
//! the entry and the exit point when the origin is outside, only the exit when it is inside.
//! [`surface`] gives the point, the unit outward normal and the squared distance for a root.
//!
//! Ask through [`Query`](crate::Query): `spheres.closest(&ray)` (default kernel [`Robust`]),
//! `spheres.using::<Geometric>().any(&packet)`; rays from one eye through the focal cache
//! [`FocalSpheres`](crate::focal::FocalSpheres).
//!
//! Bad input: a sphere with a non-finite centre or a radius that is not a finite positive
//! number is stored with a NaN radius by [`Sphere::new`] and never hit; bad rays are
//! sanitised by their constructors (see [`ray`](crate::ray)).
//!
//! ## Range
//!
//! f32 squares and products of four lengths leave f32's range (`2^±126…2^128`) well before the
//! inputs do: `r ≥ 1.85e19` overflows `r²`, `r = 1e-17` underflows `|d|²r²`. Each f32 kernel
//! therefore has a **range guard** on its hit path: a lane is answered in f32 when
//!
//! ```text
//! |d|² (not for the unit-direction kernels) and r² within 2^-60…2^60, and |o − c|² ≤ 2^60
//! ```
//!
//! (`|d|`, `r` within `2^-30…2^30`, `|o − c| ≤ 2^30`, checked on the squares the kernel computes
//! anyway: 5 compares, 3 for the unit-direction kernels, only on lanes that passed the miss
//! test; a NaN or infinite discriminant also reaches the guard, by a free bit test). Other
//! lanes are recomputed with [`Robust`] in `f64`, which holds every product of f32 inputs
//! without over- or underflow, then rounded. **Measured** (`tests/suite/kernels/magnitude_regressions.rs`, 24 cases
//! per kernel scaled by `2^k` in positions and radius and `2^j` in directions,
//! `k, j ∈ −140…140`): inside `2^-29…2^29` every f32 answer equals the unit-scale answer times
//! `2^(k−j)` bit for bit, so the accuracy measured at ordinary scale holds there; outside it
//! no kernel ever returned a wrong root (worst error 0.5 of the kernel's own tolerance), and
//! roots were lost (a clean miss) only where squares underflow before the guard sees them:
//! `|d| < 2^-62`, or both `|o − c|` and `r` below `2^-62` (65 of 58,500 out-of-range cases
//! for `robust`, 74 for `quadratic`, 2 of 960 for the unit-direction kernels). Roots that are
//! not normal f32 numbers round to 0, a subnormal or `±inf` (and then fail the interval).
//! The focal cache ([`focal`]) answers every finite input, in f32 or `f64`.

mod embree;
pub mod focal;
mod geometric;
mod pbrt;
mod quadratic;
mod robust;

pub use embree::EmbreeSphere;
pub use geometric::{Geometric, Prepared};
pub use pbrt::Pbrt;
pub use quadratic::{Quadratic, QuadraticUnit};
pub use robust::Robust;

pub use focal::FocalSphere;

use glam::Vec3;

use crate::kernel::{Cull, Kernel, LaneHit, Primitive};
use crate::lane::{Lane, Mask, Scalar, pow2};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// A sphere: centre and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    center: Vec3,
    radius: f32,
}

impl Sphere {
    /// A sphere; a non-finite centre or a radius that is not finite and positive gives a
    /// sphere that is never hit (its radius is stored as NaN).
    #[inline]
    #[must_use]
    pub fn new(center: Vec3, radius: f32) -> Self {
        let ok = center.is_finite() && radius.is_finite() && radius > 0.0;
        Sphere {
            center,
            radius: if ok { radius } else { f32::NAN },
        }
    }

    /// The centre.
    #[inline]
    #[must_use]
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// The radius (NaN for a sphere made from bad input).
    #[inline]
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// False for a sphere made from bad input.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        !self.radius.is_nan()
    }
}

/// Spheres in lanes (structure of arrays): lane `i` of each field is sphere `i`.
#[derive(Clone, Copy, Debug)]
pub struct SpherePacket<L: Lane> {
    pub(crate) center: V3<L>,
    pub(crate) radius: L,
}

impl<L: Lane> SpherePacket<L> {
    /// The same sphere in every lane.
    #[inline(always)]
    #[must_use]
    pub fn splat(s: &Sphere) -> Self {
        SpherePacket {
            center: V3::splat(s.center),
            radius: L::from_f32(s.radius),
        }
    }

    /// Up to `L::LANES` spheres, one per lane; lanes past `spheres.len()` are never hit.
    #[must_use]
    pub fn from_spheres(spheres: &[Sphere]) -> Self {
        let get = |i: usize| {
            spheres
                .get(i)
                .copied()
                .unwrap_or(Sphere::new(Vec3::ZERO, f32::NAN))
        };
        SpherePacket {
            center: V3::from_fn(
                #[cfg_attr(target_arch = "x86_64", inline(always))]
                |i| get(i).center,
            ),
            radius: L::from_f32_fn(|i| get(i).radius),
        }
    }

    /// Fills `out` with `spheres` in chunks of `L::LANES` (the last chunk padded with spheres
    /// that are never hit) and returns the number of chunks written (at most `out.len()`).
    pub fn pack(spheres: &[Sphere], out: &mut [SpherePacket<L>]) -> usize {
        let mut n = 0;
        for (chunk, slot) in spheres.chunks(L::LANES).zip(out.iter_mut()) {
            *slot = Self::from_spheres(chunk);
            n += 1;
        }
        n
    }

    /// Centres.
    #[inline]
    #[must_use]
    pub fn center(&self) -> V3<L> {
        self.center
    }

    /// Radii (NaN in lanes that are never hit).
    #[inline]
    #[must_use]
    pub fn radius(&self) -> L {
        self.radius
    }

    /// Lane `i` as a single higher-precision sphere (exact widening; for fallbacks).
    #[inline]
    #[must_use]
    pub(crate) fn precise_lane(&self, i: usize) -> SpherePacket<L::Precise> {
        SpherePacket {
            center: self.center.precise_lane(i),
            radius: self.radius.precise_lane(i),
        }
    }
}

/// The roots of one ray–sphere test per lane, ascending, each flagged when it lies inside the
/// ray's open interval. Roots outside the interval are stored as `+inf`.
#[derive(Clone, Copy, Debug)]
pub struct Roots<L: Lane> {
    /// The smaller root (entry point), `+inf` unless `m0`.
    pub t0: L,
    /// The larger root (exit point), `+inf` unless `m1`.
    pub t1: L,
    /// Lanes where `t0` is inside the interval.
    pub m0: L::Mask,
    /// Lanes where `t1` is inside the interval.
    pub m1: L::Mask,
}

impl<L: Lane> Roots<L> {
    /// No root in any lane.
    #[inline(always)]
    #[must_use]
    pub fn miss() -> Self {
        let inf = L::from_f32(f32::INFINITY);
        Roots {
            t0: inf,
            t1: inf,
            m0: Mask::splat(false),
            m1: Mask::splat(false),
        }
    }

    /// From the two roots `lo <= hi` of lanes in `real` (real roots): keeps those inside the
    /// ray's interval (4 compares).
    #[inline(always)]
    #[must_use]
    pub fn in_interval(ray: &RayPacket<L>, lo: L, hi: L, real: L::Mask) -> Self {
        let m0 = real & lo.gt(ray.t_min) & lo.lt(ray.t_max);
        let m1 = real & hi.gt(ray.t_min) & hi.lt(ray.t_max);
        let inf = L::from_f32(f32::INFINITY);
        Roots {
            t0: L::select(m0, lo, inf),
            t1: L::select(m1, hi, inf),
            m0,
            m1,
        }
    }

    /// The first root inside the interval per lane (the closest hit).
    #[inline(always)]
    #[must_use]
    pub fn first(&self) -> LaneHit<L> {
        let t = L::select(self.m0, self.t0, self.t1);
        let zero = L::from_f32(0.0);
        LaneHit {
            t,
            u: zero,
            v: zero,
            w: L::from_f32(1.0),
            mask: self.m0 | self.m1,
        }
    }

    /// Lanes with at least one root inside the interval.
    #[inline(always)]
    #[must_use]
    pub fn any(&self) -> L::Mask {
        self.m0 | self.m1
    }

    /// Lane `i` as up to two roots, ascending (`f32` lanes).
    #[must_use]
    pub fn lane(&self, i: usize) -> ([f32; 2], usize)
    where
        L: Lane<Scalar = f32>,
    {
        let mut out = [f32::INFINITY; 2];
        let mut n = 0;
        if self.m0.test(i) {
            out[n] = self.t0.lane(i);
            n += 1;
        }
        if self.m1.test(i) {
            out[n] = self.t1.lane(i);
            n += 1;
        }
        (out, n)
    }

    /// Replaces lane `i` with roots computed elsewhere (a higher-precision fallback), rounding
    /// them to the lane's precision and re-checking them against the lane's interval.
    #[inline(always)]
    #[must_use]
    pub(crate) fn with_precise_lane(
        self,
        i: usize,
        t_min: L::Scalar,
        t_max: L::Scalar,
        p: &Roots<L::Precise>,
    ) -> Self {
        let fit = |t: f64, m: bool| {
            let t = L::Scalar::from_f64(t);
            (m && t > t_min && t < t_max).then_some(t)
        };
        let inf = L::Scalar::from_f32(f32::INFINITY);
        let r0 = fit(p.t0.lane(0), p.m0.test(0));
        let r1 = fit(p.t1.lane(0), p.m1.test(0));
        Roots {
            t0: self.t0.with_lane(i, r0.unwrap_or(inf)),
            t1: self.t1.with_lane(i, r1.unwrap_or(inf)),
            m0: self.m0.with_lane(i, r0.is_some()),
            m1: self.m1.with_lane(i, r1.is_some()),
        }
    }
}

/// A ray–sphere formulation: all roots of ray lanes against sphere lanes.
///
/// Implemented by [`Quadratic`], [`QuadraticUnit`], [`Geometric`] and [`Robust`]; one generic
/// body each, shared by every lane width and by the op-counting lane.
pub trait SphereKernel {
    /// The method's name (as the checker spells it).
    const NAME: &'static str;
    /// True when the method needs unit-length directions.
    const UNIT_DIRECTIONS: bool;
    /// All roots of each ray lane against the sphere in the same lane, ascending, inside the
    /// ray's interval, or `None` when no lane has real roots: the miss path's early exit, so
    /// that a caller skips the merge of the answer entirely.
    fn maybe_roots<L: Lane>(ray: &RayPacket<L>, sphere: &SpherePacket<L>) -> Option<Roots<L>>;
    /// All roots of each ray lane against the sphere in the same lane, ascending, inside the
    /// ray's interval.
    #[inline(always)]
    fn roots<L: Lane>(ray: &RayPacket<L>, sphere: &SpherePacket<L>) -> Roots<L> {
        Self::maybe_roots(ray, sphere).unwrap_or_else(Roots::miss)
    }
}

/// Lower end of the squared magnitudes the f32 kernels accept on their fast path (`2^-60`).
pub(crate) const SQ_LO: f32 = pow2(-60);
/// Upper end of the squared magnitudes the f32 kernels accept on their fast path (`2^60`).
pub(crate) const SQ_HI: f32 = pow2(60);

/// True for f32 lanes: only they have a range guard (an `f64` lane holds every product of f32
/// inputs without over- or underflow, and is the guard's fallback).
#[inline(always)]
pub(crate) fn guarded<L: Lane>() -> bool {
    core::mem::size_of::<L::Scalar>() == 4
}

/// `SQ_LO ≤ x ≤ SQ_HI` per lane (2 cmp; false for NaN).
#[inline(always)]
pub(crate) fn in_range<L: Lane>(x: L) -> L::Mask {
    x.ge(L::from_f32(SQ_LO)) & x.le(L::from_f32(SQ_HI))
}

/// The range guard of the f32 kernels (see [the module docs](self#range)): lanes of `real`
/// whose scale left the safe range, `!(a, r² ∈ [2^-60, 2^60] and |o − c|² ≤ 2^60)`, to be
/// recomputed in `f64`. `a` is `None` for the unit-direction kernels (`a = 1` by contract).
/// 3 cmp, and 2 more with `a`; nothing for `f64` lanes.
#[inline(always)]
pub(crate) fn escaped<L: Lane>(real: L::Mask, a: Option<L>, r2: L, ff: L) -> L::Mask {
    if !guarded::<L>() {
        return Mask::splat(false);
    }
    let mut safe = in_range(r2) & ff.le(L::from_f32(SQ_HI));
    if let Some(a) = a {
        safe = safe & in_range(a);
    }
    real.and_not(safe)
}

/// `roots` with the lanes of `escaped` replaced by [`Robust`] evaluated in `L::Precise`
/// (`f64`), where no product of f32 inputs over- or underflows.
#[inline(always)]
pub(crate) fn with_fallback<L: Lane>(
    ray: &RayPacket<L>,
    s: &SpherePacket<L>,
    roots: Roots<L>,
    escaped: L::Mask,
) -> Roots<L> {
    // Lanes with a NaN radius (invalid or padding spheres) or bad rays stay misses (bit
    // tests, not counted).
    let valid = s.radius.is_finite() & ray.origin.is_finite() & ray.dir.is_finite();
    let escaped = escaped & valid;
    if escaped.none() {
        roots
    } else {
        precise(*ray, *s, roots, escaped)
    }
}

/// Recomputes the `lanes` with [`Robust`] in `L::Precise` (`f64`). Out of line and taking its
/// inputs by value, so the callers' packets never need an address.
#[inline(never)]
pub(crate) fn precise<L: Lane>(
    ray: RayPacket<L>,
    s: SpherePacket<L>,
    mut roots: Roots<L>,
    lanes: L::Mask,
) -> Roots<L> {
    let mut bits = lanes.bits();
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        let p = Robust::roots(&ray.precise_lane(i), &s.precise_lane(i));
        roots = roots.with_precise_lane(i, ray.t_min.lane(i), ray.t_max.lane(i), &p);
        bits &= bits - 1;
    }
    roots
}

/// Point, unit outward normal and squared distance from the ray origin of a root `t`
/// (lecture 004: `point = D + uE`, `normal = (point − C)/|point − C|`, `distanceSquared =
/// |uE|²`). The point costs 3 mul and 3 add; the normal 3 add, 3 mul, 2 add, 1 sqrt, 3 div
/// and 2 cmp (its range check, see [`surface`]); the distance² 3 mul, 2 add more.
#[derive(Clone, Copy, Debug)]
pub struct Surface<L: Lane> {
    /// `o + t·d`.
    pub point: V3<L>,
    /// Unit normal pointing away from the centre.
    pub normal: V3<L>,
    /// `|t·d|²`: squared distance from the ray origin.
    pub distance_squared: L,
}

/// Surface data of a root (see [`Surface`]).
///
/// **Range.** The normal is computed in f32 when `|point − centre|²` lies within
/// `2^-100…2^100` (2 cmp); other lanes (points within `2^-50` or beyond `2^50` of the centre,
/// e.g. spheres with `r < 2^-50`) get their normal from `o + t·d − c` evaluated in `f64` and
/// rounded, so a finite `t` on a sphere of any size gives a finite unit normal. Only a point
/// exactly at the centre (impossible for a root of a valid sphere unless `t` is wrong) gives
/// the zero vector. `distance_squared` is `+inf` when `|t·d|` exceeds about `2^64`.
#[inline]
#[must_use]
pub fn surface<L: Lane>(ray: &RayPacket<L>, sphere: &SpherePacket<L>, t: L) -> Surface<L> {
    let step = ray.dir.scale(t);
    let point = ray.origin + step;
    let out = point - sphere.center;
    let n2 = out.length_squared();
    let normal = out.div_by(n2.sqrt());
    const LO: f32 = pow2(-100);
    const HI: f32 = pow2(100);
    let odd = !(n2.ge(L::from_f32(LO)) & n2.le(L::from_f32(HI)));
    let normal = if guarded::<L>() && odd.any() {
        precise_normals(ray, sphere, t, normal, odd)
    } else {
        normal
    };
    Surface {
        point,
        normal,
        distance_squared: step.length_squared(),
    }
}

/// The normals of `lanes` from `o + t·d − c` in `f64`, rounded (see [`surface`]).
#[inline(never)]
fn precise_normals<L: Lane>(
    ray: &RayPacket<L>,
    sphere: &SpherePacket<L>,
    t: L,
    mut normal: V3<L>,
    lanes: L::Mask,
) -> V3<L> {
    let mut bits = lanes.bits();
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let (o, d, c) = (
            ray.origin.precise_lane(i),
            ray.dir.precise_lane(i),
            sphere.center.precise_lane(i),
        );
        let out = o.along(d, t.precise_lane(i)) - c;
        let len = out.length_squared().sqrt();
        let zero = <L::Precise as Lane>::from_f32(0.0);
        let n = if (len.gt(zero) & len.is_finite()).any() {
            out.div_by(len)
        } else {
            V3::new(zero, zero, zero)
        };
        let round = |x: L::Precise| L::Scalar::from_f64(x.lane(0));
        normal = V3::new(
            normal.x.with_lane(i, round(n.x)),
            normal.y.with_lane(i, round(n.y)),
            normal.z.with_lane(i, round(n.z)),
        );
    }
    normal
}

impl Primitive for Sphere {
    type Packet<L: Lane> = SpherePacket<L>;
    #[inline(always)]
    fn splat<L: Lane>(&self) -> SpherePacket<L> {
        SpherePacket::splat(self)
    }
}

/// Every sphere kernel is a [`Kernel`] of spheres: its first root inside the interval, with
/// `u = 1` marking an exit root (the origin is inside: a back face) and `u = 0` an entry root;
/// under [`Cull::Back`] only entry roots. [`each`](Kernel::each) gives the entry roots, then
/// (unless culled) the exit roots.
impl<K: SphereKernel> Kernel<Sphere> for K {
    type Rays<L: Lane> = ();
    const UNIT_DIRECTIONS: bool = K::UNIT_DIRECTIONS;

    #[inline(always)]
    fn prepare<L: Lane>(_: &RayPacket<L>) {}

    #[inline(always)]
    fn first<L: Lane>(
        rays: &RayPacket<L>,
        _: &(),
        s: &SpherePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        K::maybe_roots(rays, s).map(|r| first_root(&r, cull))
    }

    #[inline(always)]
    fn each<L: Lane>(
        rays: &RayPacket<L>,
        _: &(),
        s: &SpherePacket<L>,
        cull: Cull,
        f: impl FnMut(&LaneHit<L>) -> bool,
    ) -> bool {
        K::maybe_roots(rays, s).is_some_and(|r| each_root(&r, cull, f))
    }
}

/// The first root of `roots` inside the interval, with `u = 1` marking an exit root and
/// `u = 0` an entry root; under [`Cull::Back`] only entry roots.
#[inline(always)]
#[must_use]
pub fn first_root<L: Lane>(roots: &Roots<L>, cull: Cull) -> LaneHit<L> {
    let zero = L::from_f32(0.0);
    if cull.back() {
        LaneHit::new(roots.t0, zero, zero, roots.m0)
    } else {
        let t = L::select(roots.m0, roots.t0, roots.t1);
        let exit = L::select(roots.m0, zero, L::from_f32(1.0));
        LaneHit::new(t, exit, zero, roots.m0 | roots.m1)
    }
}

/// The entry roots, then (unless culled) the exit roots with `u = 1`, each passed to `f` when
/// some lane has one; stops when `f` returns true, and returns whether it stopped.
#[inline(always)]
pub fn each_root<L: Lane>(
    roots: &Roots<L>,
    cull: Cull,
    mut f: impl FnMut(&LaneHit<L>) -> bool,
) -> bool {
    let zero = L::from_f32(0.0);
    let entry = LaneHit::new(roots.t0, zero, zero, roots.m0);
    if entry.mask.any() && f(&entry) {
        return true;
    }
    if cull.back() {
        return false;
    }
    let exit = LaneHit::new(roots.t1, L::from_f32(1.0), zero, roots.m1);
    exit.mask.any() && f(&exit)
}
