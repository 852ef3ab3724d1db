//! Rays from one focal point: per-sphere caches with a precision guard.
//!
//! Primary rays of a pinhole camera all start at the focal point `E` (lecture 000, "Rays from
//! Focal Point": *intermediate values remain constant across all pixels*). Per sphere the cache
//! holds `T = C − E` and thresholds computed once, in `f64`, by [`FocalSphere::new`]; per ray
//! with unit direction `U` the test is
//!
//! ```text
//! v  = T·U                          3 mul, 2 add
//! v² > k_lo ?                       1 mul, 1 cmp      → miss: 4 mul, 2 add, 1 cmp
//! ```
//!
//! where `k_lo = K − E₁`, `K = c² − r²` (the lecture's `r² > c² − v²` with `c² − r²` folded into
//! one cached value, one addition fewer than the lecture's 4 mul + 3 add), and `E₁` bounds the
//! f32 rounding error of `v²` (`≈ 9.2·2^-24·c²`) plus the error allowed in `|U|² = 1`
//! (`2^-20`). Below `k_lo` the miss is certain.
//!
//! **The guard.** Rays that pass the cheap test are decided by the perpendicular form of the
//! precision lecture, reusing `v`: `p = T − vU`, `l² = p·p` (6 mul, 5 add). Subtracting before
//! squaring keeps the error of `l²` near `4·2^-24·c·r` instead of `9·2^-24·c²`. Two more cached
//! thresholds, derived from a rounding-error bound, make `l² ≤ l2_hit` a certain hit whose
//! `t = v ∓ √(r² − l²)` is within `2^-16` (1.5e-5) relative of the exact root, and `l² ≥ l2_miss` a
//! certain miss. Only lanes in between — rays grazing the rim within that bound, or spheres so
//! close to the eye that `t` itself is ill-conditioned — are recomputed with the [`Robust`]
//! body in `f64` (one lane at a time, then rounded to f32). The result: zero misclassified
//! rays for `c/r` up to 2^20 and beyond, on every ray whose exact answer survives a 2-ulp move
//! of the inputs, at the unguarded miss cost.
//!
//! Why not `d = √(v² − K)` for hits, as in the lecture? Its error `≈ 9·2^-24·c²/(2d)` exceeds
//! 1e-5 of `t` once `c/r` passes about 5; the sphere of the precision lecture vanishes at 4096.
//! [`FocalUnguarded`] keeps that textbook form (for comparison and benchmarks).
//!
//! **Operation count per lane** (measured): `ops focal/miss: 4 mul, 2 add, 1 cmp`;
//! `ops focal/hit: 10 mul, 10 add, 1 sqrt, 9 cmp`; a doubtful lane adds one `f64` evaluation
//! of [`Robust`] (`ops focal/doubtful: 27 mul, 27 add, 3 div, 2 sqrt, 16 cmp` in all).
//!
//! **Requirements.** Rays start exactly at the eye the cache was built for and have unit
//! directions (`||U|² − 1| ≤ 2^-20`, which any f32 `normalize` meets; [`Pinhole`] makes such
//! rays). **Edge cases.** Invalid spheres (see [`Sphere::new`]) and a non-finite eye give
//! `k_lo = +inf`: never hit.
//!
//! **Range.** The f32 path serves `c ≤ 10^18` and `r` within `10^-12…10^18`; every other
//! sphere sends all its rays to the `f64` path (no ray is a certain miss there, even when `l²`
//! overflows f32), so every finite input gets a correct answer: measured over positions
//! scaled by `2^-140…2^140` (`tests/suite/kernels/magnitude_regressions.rs`), no root lost and none wrong.
//! [`FocalUnguarded`] answers only `c ≤ 2^30`, `r` within `2^-30…2^30` and never hits
//! other spheres (a documented clean miss).
//!
//! [`Robust`]: super::Robust
//! [`Pinhole`]: crate::camera::Pinhole
//! [`Sphere::new`]: super::Sphere::new

use glam::Vec3;

use super::{Roots, Sphere, SpherePacket};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// Unit roundoff of f32.
const U: f64 = 1.0 / 16_777_216.0;
/// Allowed deviation of `|U|²` from 1.
const ETA: f64 = 1.0 / 1_048_576.0;
/// Relative accuracy promised for `t` on the f32 hit path.
const EPS_T: f64 = 1.0 / 65_536.0;
/// Relative error of the f64 cache arithmetic (generous).
const F64_REL: f64 = 1.0 / 1_125_899_906_842_624.0; // 2^-50
/// Absolute floor for f32 underflow in products.
const ABS: f64 = 1e-36;

/// One sphere as seen from one focal point (or `L::LANES` spheres in lanes).
///
/// Build with [`FocalSphere::new`] (guarded) or [`FocalSphere::unguarded`], then [`splat`] it
/// for packets of rays or [`gather`]/[`pack`] several into lanes for one ray against many.
///
/// [`splat`]: FocalSphere::splat
/// [`gather`]: FocalSphere::gather
/// [`pack`]: FocalSphere::pack
#[derive(Clone, Copy, Debug)]
pub struct FocalSphere<L: Lane> {
    /// `T = C − E`, rounded to f32.
    t: V3<L>,
    /// Certain miss when `v² ≤ k_lo` (guarded); `K = c² − r²` itself when unguarded.
    k_lo: L,
    /// `r²` rounded to f32.
    r2: L,
    /// Certain, accurate hit when `l² ≤ l2_hit`.
    l2_hit: L,
    /// Certain miss when `l² ≥ l2_miss`.
    l2_miss: L,
    /// A certain hit's roots are accurate when both have magnitude at least `t_acc`.
    t_acc: L,
    /// The sphere, for the `f64` fallback.
    center: V3<L>,
    radius: L,
}

fn sq(x: f64) -> f64 {
    x * x
}

/// Rounds toward −inf.
fn down(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) > x { y.next_down() } else { y }
}

/// Rounds toward +inf.
fn up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}

impl FocalSphere<f32> {
    /// The guarded cache entry of `sphere` for rays from `eye` (see the [module docs](self)).
    #[must_use]
    pub fn new(eye: Vec3, sphere: &Sphere) -> Self {
        Self::build(eye, sphere, true)
    }

    /// The lecture's unguarded entry: `k_lo = K` and hits from `√(v² − K)` (fails for far
    /// small spheres; for comparison).
    #[must_use]
    pub fn unguarded(eye: Vec3, sphere: &Sphere) -> Self {
        Self::build(eye, sphere, false)
    }

    fn build(eye: Vec3, sphere: &Sphere, guarded: bool) -> Self {
        let (center, radius) = (sphere.center(), sphere.radius());
        let te = [
            center.x as f64 - eye.x as f64,
            center.y as f64 - eye.y as f64,
            center.z as f64 - eye.z as f64,
        ];
        let c2 = te[0] * te[0] + te[1] * te[1] + te[2] * te[2];
        let r = radius as f64;
        let th = if !(sphere.is_valid() && eye.is_finite()) {
            Thresholds::NEVER
        } else if guarded {
            Thresholds::guarded(c2, r)
        } else {
            Thresholds::unguarded(c2, r)
        };
        FocalSphere {
            t: V3::new(te[0] as f32, te[1] as f32, te[2] as f32),
            k_lo: th.k_lo,
            r2: ((r * r) as f32).max(0.0),
            l2_hit: th.l2_hit,
            l2_miss: th.l2_miss,
            t_acc: th.t_acc,
            center: center.into(),
            radius,
        }
    }
}

/// The per-entry thresholds of the focal test (see the [module docs](self)).
struct Thresholds {
    k_lo: f32,
    l2_hit: f32,
    l2_miss: f32,
    t_acc: f32,
}

impl Thresholds {
    /// Bad input: the cheap test rejects every ray.
    const NEVER: Thresholds = Thresholds {
        k_lo: f32::INFINITY,
        l2_hit: f32::NEG_INFINITY,
        l2_miss: f32::INFINITY,
        t_acc: f32::INFINITY,
    };

    /// The lecture's unguarded test: `k_lo = K = c² − r²`.
    fn unguarded(c2: f64, r: f64) -> Self {
        // Outside c ≤ 2^30, 2^-30 ≤ r ≤ 2^30 the f32 squares lose their range: never hit.
        let range = (1.0 / 1_073_741_824.0)..=1_073_741_824.0;
        let fits = c2 <= sq(*range.end()) && range.contains(&r);
        let k_lo = if fits {
            (c2 - r * r) as f32
        } else {
            f32::INFINITY
        };
        Thresholds {
            k_lo,
            l2_hit: f32::NEG_INFINITY,
            l2_miss: f32::INFINITY,
            t_acc: f32::INFINITY,
        }
    }

    /// The guarded test's three steps, from the exact `c²` and `r`.
    fn guarded(c2: f64, r: f64) -> Self {
        let r2e = r * r;
        let c = libm::sqrt(c2);
        if !(c <= 1.0e18 && (1.0e-12..=1.0e18).contains(&r)) {
            // Squares would leave f32's range: every ray takes the f64 path (`l2_miss = NaN`
            // so that no lane is a certain miss, not even one whose `l²` overflowed).
            return Thresholds {
                k_lo: f32::NEG_INFINITY,
                l2_hit: f32::NEG_INFINITY,
                l2_miss: f32::NAN,
                t_acc: f32::INFINITY,
            };
        }
        let n1 = 1.0 + ETA;
        // Step 1. |v_c − v| ≤ dv (T rounded once, three products, two sums), and the bound E₁ on
        // |fl(v_c²) − |U|²K − disc| that makes v² ≤ K − E₁ a certain miss.
        let dv = 4.02 * U * c * libm::sqrt(n1);
        let e1 = 9.2 * U * c2 * n1 + (ETA + F64_REL) * (c2 + r2e) + ABS;
        let k_lo = down((c2 - r2e) - e1);
        // Step 2. p_c = p + αU + w with p ⊥ U, |α| ≤ α_max (dv and the non-unit |U|), |w| ≤ W0 +
        // 2^-24|p_c| (roundings of T, vU and the subtraction). Then |l_c| lies within W of
        // √(l² + α²|U|²), which bounds l from both sides.
        let alpha = dv + c * libm::sqrt(n1) * ETA / (1.0 - ETA);
        let a2 = alpha * alpha * n1;
        let w0 = 2.01 * U * c * n1 + 1e-18;
        let g3 = 3.01 * U;
        let l2_miss =
            up(sq((libm::sqrt(r2e + a2) + w0) / (1.0 - U)) * (1.0 + g3) * (1.0 + F64_REL));
        let l2_sure = if r > w0 {
            sq((r - w0) / (1.0 + U)) * (1.0 - g3) * (1.0 - F64_REL)
        } else {
            -1.0
        };
        let (l2_acc, t_acc) = Self::accuracy(c, r, alpha, a2, w0);
        let l2_hit = l2_sure.min(l2_acc);
        Thresholds {
            k_lo,
            l2_hit: if l2_hit >= 0.0 {
                down(l2_hit)
            } else {
                f32::NEG_INFINITY
            },
            l2_miss,
            t_acc,
        }
    }

    /// Step 3. Accuracy of t = v ∓ √(r² − l²) on a certain hit: |t_c − t| ≤ err = rest + E_X/√X,
    /// with rest = α + (2u+η)(c+r) and E_X the error of X = r² − l². Every root of a ray from
    /// outside has |t| ≥ c − r, so aim for err = 0.98·2^-16·|c − r| (at least 2·rest) and accept
    /// only X ≥ X_min = (E_X/(err − rest))² (l² ≤ l2_acc). A root is then within 2^-16 of the
    /// exact one when |t_c| ≥ t_acc = err/2^-16 + err — true for every root of a ray from
    /// outside; one compare per root, per lane, catches the rest. Returns `(l2_acc, t_acc)`.
    fn accuracy(c: f64, r: f64, alpha: f64, a2: f64, w0: f64) -> (f64, f32) {
        let (n1, g3, r2e) = (1.0 + ETA, 3.01 * U, r * r);
        let a = libm::sqrt(a2);
        let wp = w0 + 1.01 * U * (r + a + w0);
        let e_l2 = a2 + 2.0 * wp * (r + a) + wp * wp + g3 * sq(r + a + wp);
        let e_x = 1.01 * e_l2 + 2.01 * U * r2e;
        let rest = alpha + 1.01 * (2.0 * U + ETA) * (c + r) * n1;
        let err = (0.98 * EPS_T * (c - r).abs()).max(2.0 * rest);
        let x_min = sq(e_x / (err - rest));
        let l2_acc = r2e * (1.0 - U) - x_min - e_x;
        let err = err * (1.0 + F64_REL);
        (l2_acc, up(err / EPS_T + err))
    }
}

impl FocalSphere<f32> {
    /// An entry whose cheap test passes every ray (`k_lo = −inf`) and which is never hit
    /// (its sphere is invalid, so the `f64` path misses): what [`Bound::focal`] returns for
    /// an invalid bound, which must cull nothing.
    ///
    /// [`Bound::focal`]: crate::bounds::Bound::focal
    #[must_use]
    pub fn pass_all() -> Self {
        FocalSphere {
            k_lo: f32::NEG_INFINITY,
            ..Self::new(Vec3::ZERO, &Sphere::new(Vec3::ZERO, f32::NAN))
        }
    }
}

impl<L: Lane> FocalSphere<L> {
    /// The same entry in every lane (N rays × 1 sphere).
    #[inline(always)]
    #[must_use]
    pub fn splat(e: &FocalSphere<f32>) -> Self {
        FocalSphere {
            t: V3::splat(e.t.into()),
            k_lo: L::from_f32(e.k_lo),
            r2: L::from_f32(e.r2),
            l2_hit: L::from_f32(e.l2_hit),
            l2_miss: L::from_f32(e.l2_miss),
            t_acc: L::from_f32(e.t_acc),
            center: V3::splat(e.center.into()),
            radius: L::from_f32(e.radius),
        }
    }

    /// Up to `L::LANES` entries, one per lane (1 ray × N spheres); missing lanes never hit.
    #[must_use]
    pub fn gather(entries: &[FocalSphere<f32>]) -> Self {
        let never = FocalSphere::<f32>::new(Vec3::ZERO, &Sphere::new(Vec3::ZERO, f32::NAN));
        let get = |i: usize| entries.get(i).copied().unwrap_or(never);
        FocalSphere {
            t: V3::from_fn(
                #[cfg_attr(target_arch = "x86_64", inline(always))]
                |i| get(i).t.into(),
            ),
            k_lo: L::from_f32_fn(|i| get(i).k_lo),
            r2: L::from_f32_fn(|i| get(i).r2),
            l2_hit: L::from_f32_fn(|i| get(i).l2_hit),
            l2_miss: L::from_f32_fn(|i| get(i).l2_miss),
            t_acc: L::from_f32_fn(|i| get(i).t_acc),
            center: V3::from_fn(
                #[cfg_attr(target_arch = "x86_64", inline(always))]
                |i| get(i).center.into(),
            ),
            radius: L::from_f32_fn(|i| get(i).radius),
        }
    }

    /// Packs entries into `out` in chunks of `L::LANES`; returns the number of chunks written.
    pub fn pack(entries: &[FocalSphere<f32>], out: &mut [FocalSphere<L>]) -> usize {
        let mut n = 0;
        for (chunk, slot) in entries.chunks(L::LANES).zip(out.iter_mut()) {
            *slot = Self::gather(chunk);
            n += 1;
        }
        n
    }

    /// The sphere in each lane.
    #[inline]
    #[must_use]
    pub fn sphere(&self) -> SpherePacket<L> {
        SpherePacket {
            center: self.center,
            radius: self.radius,
        }
    }
}

/// Where a focal kernel reads its cached sphere lanes from: a [`FocalSphere<L>`] already in
/// lanes (1 ray × N spheres), or a [`Splat`] of one entry (N rays × 1 sphere) that broadcasts
/// only what each step needs, so a miss touches `T` and `k_lo` alone.
pub trait FocalLanes<L: Lane> {
    /// `T = C − E` in lanes.
    fn t(&self) -> V3<L>;
    /// The cheap test's threshold in lanes.
    fn k_lo(&self) -> L;
    /// The hit path's thresholds: `(r², l2_hit, l2_miss, t_acc)`.
    fn guard(&self) -> (L, L, L, L);
    /// The spheres, for the `f64` fallback.
    fn sphere(&self) -> SpherePacket<L>;
}

impl<L: Lane> FocalLanes<L> for FocalSphere<L> {
    #[inline(always)]
    fn t(&self) -> V3<L> {
        self.t
    }
    #[inline(always)]
    fn k_lo(&self) -> L {
        self.k_lo
    }
    #[inline(always)]
    fn guard(&self) -> (L, L, L, L) {
        (self.r2, self.l2_hit, self.l2_miss, self.t_acc)
    }
    #[inline(always)]
    fn sphere(&self) -> SpherePacket<L> {
        SpherePacket {
            center: self.center,
            radius: self.radius,
        }
    }
}

/// One cache entry seen in every lane, broadcast lazily (see [`FocalLanes`]).
#[derive(Clone, Copy, Debug)]
pub struct Splat<'a>(pub &'a FocalSphere<f32>);

impl<L: Lane> FocalLanes<L> for Splat<'_> {
    #[inline(always)]
    fn t(&self) -> V3<L> {
        V3::splat(self.0.t.into())
    }
    #[inline(always)]
    fn k_lo(&self) -> L {
        L::from_f32(self.0.k_lo)
    }
    #[inline(always)]
    fn guard(&self) -> (L, L, L, L) {
        let e = self.0;
        (
            L::from_f32(e.r2),
            L::from_f32(e.l2_hit),
            L::from_f32(e.l2_miss),
            L::from_f32(e.t_acc),
        )
    }
    #[inline(always)]
    fn sphere(&self) -> SpherePacket<L> {
        SpherePacket {
            center: V3::splat(self.0.center.into()),
            radius: L::from_f32(self.0.radius),
        }
    }
}

/// Builds the guarded cache of `spheres` for rays from `eye` into `out` (no allocation);
/// returns the number of entries written (`min(spheres.len(), out.len())`).
pub fn focus(eye: Vec3, spheres: &[Sphere], out: &mut [FocalSphere<f32>]) -> usize {
    let mut n = 0;
    for (s, slot) in spheres.iter().zip(out.iter_mut()) {
        *slot = FocalSphere::new(eye, s);
        n += 1;
    }
    n
}

/// A focal-point sphere test over [`FocalSphere`] caches.
pub trait FocalKernel {
    /// The method's name.
    const NAME: &'static str;
    /// All roots of ray lanes (starting at the cache's eye, unit directions) against the cached
    /// sphere in each lane, ascending, inside the ray's interval.
    fn roots<L: Lane, S: FocalLanes<L>>(ray: &RayPacket<L>, s: &S) -> Roots<L> {
        Self::maybe_roots(ray, s).unwrap_or_else(Roots::miss)
    }
    /// The same, or `None` when no lane passes the cheap test (every lane misses).
    fn maybe_roots<L: Lane, S: FocalLanes<L>>(ray: &RayPacket<L>, s: &S) -> Option<Roots<L>>;
    /// The lanes that pass the cheap test (step 1 alone): the first pass of the closest/any
    /// loops, which then run the whole test only for spheres where some lane passes.
    #[inline(always)]
    fn candidate<L: Lane, S: FocalLanes<L>>(ray: &RayPacket<L>, s: &S) -> L::Mask {
        cheap(ray, s).2
    }
}

/// The guarded focal test (the default; see the [module docs](self)).
#[derive(Clone, Copy, Debug, Default)]
pub struct Focal;

/// The lecture's unguarded focal test: `v² > K`, `t = v ∓ √(v² − K)`.
/// `ops focal-unguarded/miss: 4 mul, 2 add, 1 cmp`; a hit adds 1 sqrt, 3 add and the 4
/// interval compares: `ops focal-unguarded/hit: 4 mul, 5 add, 1 sqrt, 5 cmp`. Misclassifies
/// far small spheres (`c/r` beyond about 2^11) and loses accuracy in `t` from `c/r ≈ 5`. Build
/// its cache with [`FocalSphere::unguarded`].
#[derive(Clone, Copy, Debug, Default)]
pub struct FocalUnguarded;

impl FocalKernel for Focal {
    const NAME: &'static str = "focal";
    #[inline(always)]
    fn maybe_roots<L: Lane, S: FocalLanes<L>>(ray: &RayPacket<L>, s: &S) -> Option<Roots<L>> {
        focal::<L, S, true>(ray, s)
    }
}

impl FocalKernel for FocalUnguarded {
    const NAME: &'static str = "focal-unguarded";
    #[inline(always)]
    fn maybe_roots<L: Lane, S: FocalLanes<L>>(ray: &RayPacket<L>, s: &S) -> Option<Roots<L>> {
        focal::<L, S, false>(ray, s)
    }
}

/// Step 1 of both tests: `v = T·U`, `v²`, and the lanes with `v² > k_lo` (4 mul, 2 add, 1 cmp).
#[inline(always)]
fn cheap<L: Lane, S: FocalLanes<L>>(ray: &RayPacket<L>, s: &S) -> (L, L, L::Mask) {
    let v = s.t().dot(ray.dir);
    let v2 = v * v;
    (v, v2, v2.gt(s.k_lo()))
}

/// One body for both; `GUARDED` selects the perpendicular hit path and the fallback.
#[inline(always)]
fn focal<L: Lane, S: FocalLanes<L>, const GUARDED: bool>(
    ray: &RayPacket<L>,
    s: &S,
) -> Option<Roots<L>> {
    // 1. Foot of the perpendicular, and the cheap test against the cached threshold.
    let (v, v2, maybe) = cheap(ray, s);
    let k_lo = s.k_lo();
    if maybe.none() {
        return None;
    }
    if !GUARDED {
        let d = (v2 - k_lo).sqrt();
        return Some(Roots::in_interval(ray, v - d, v + d, maybe));
    }
    // 2.–4. Reading the rest of the entry only now.
    Some(hit_path(ray, s, v, maybe))
}

/// Steps 2–4 of the guarded test, for lanes that passed the cheap test (`maybe`).
#[inline(always)]
fn hit_path<L: Lane, S: FocalLanes<L>>(
    ray: &RayPacket<L>,
    s: &S,
    v: L,
    maybe: L::Mask,
) -> Roots<L> {
    let (r2, l2_hit, l2_miss, t_acc) = s.guard();
    // 2. Perpendicular from the centre to the ray: p = T − vU, l² = p·p.
    let l2 = (s.t() - ray.dir.scale(v)).length_squared();
    let sure_miss = l2.ge(l2_miss);
    // 3. Half chord and both roots; a certain hit needs l² ≤ l2_hit and both roots far enough
    //    from zero for their error bound to be within 2^-16 of them.
    let d = (r2 - l2).sqrt();
    let (t0, t1) = (v - d, v + d);
    let sure_hit = maybe & l2.le(l2_hit) & t0.abs().ge(t_acc) & t1.abs().ge(t_acc);
    let roots = Roots::in_interval(ray, t0, t1, sure_hit);
    // 4. Lanes the guard cannot decide: the robust body in f64, one lane at a time.
    let doubtful = maybe.and_not(sure_hit | sure_miss);
    if doubtful.none() {
        roots
    } else {
        super::precise(*ray, s.sphere(), roots, doubtful)
    }
}
