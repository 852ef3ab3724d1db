//! Ray–triangle intersection: ten formulations over one lane abstraction.
//!
//! | kernel | from | per-ray setup | watertight | strength |
//! | --- | --- | --- | --- | --- |
//! | [`Cramer`] | lecture 002: the 3×3 system by Cramer's rule | none | no | the textbook; three divisions, early exits |
//! | [`Moller`] | Möller & Trumbore 1997, division deferred (as in Embree) | none | no | fewest operations without per-ray setup |
//! | [`Watertight`] | Woop, Benthin & Wald 2013 | shear, 3 div | yes (no leaks; edges may be hit twice) | any ray, any triangle |
//! | [`Badouel`] | Badouel 1990: plane, then a 2-D test | plane and projection per triangle ([`PrecomputedKernel`]) | no | the plane rejects first |
//! | [`Plucker`] | Segura & Feito 1998, as in Embree's Plücker test | none | no leaks (edges may be hit twice) | edge tests exact in sign across shared edges |
//! | [`Wald`] | Wald 2004 (thesis): precomputed projection | 37-byte record per triangle | no | fewest operations per hit of the published tests |
//! | [`HavelHerout`] | Havel & Herout 2010: three precomputed planes | 48-byte record | no | no branch before the sign test |
//! | [`KenslerShirley`] | Kensler & Shirley 2006 | none | no | one reciprocal for t, u, v |
//! | [`BaldwinWeber`] | Baldwin & Weber 2016: precomputed affine transform | 48-byte record | no | no per-triangle axis in the test |
//! | [`focal`] | rays from one focal point, edge normals cached per triangle (exactly rounded) | exact power-of-two scale | yes, and each crossing is reported once (exact decisions, a stated fill rule) | 9 mul + 6 add per miss; `t`, `u`, `v` measured at most 2× Möller's error |
//!
//! **Conventions.** A hit satisfies `o + t·d = A + u(B − A) + v(C − A)` with `t_min < t <
//! t_max`, `u ≥ 0`, `v ≥ 0`, `u + v ≤ 1`: `u` weighs vertex B and `v` vertex C. Triangles
//! are two-sided unless [`Cull::Back`] is asked for, which keeps only front faces: `d·N < 0`
//! with `N = (B − A) × (C − A)`, i.e. A, B, C counter-clockwise as seen from the ray origin.
//! Directions need not be unit length; `t` is in units of `|d|`.
//!
//! **Deferred division.** [`Moller`], [`Watertight`], [`Plucker`], [`HavelHerout`] and
//! [`focal`] test the edges against the unscaled determinant, `t > 0` as the sign of its
//! numerator and `t < t_max` as `num_t < t_max·|det|` (skipped where that product is
//! subnormal, so it cannot drop a hit at any magnitude); only lanes that pass divide,
//! `t = num_t/|det|`, and a hit needs the rounded `t` strictly inside `(t_min, t_max)`. In a
//! closest-hit loop that is only the hits that win so far: the loops relax `t_max` after each
//! hit so that the rounded product never drops a winner, and take a candidate only when its
//! rounded `t` is below the best, so every traversal order and both packet shapes find the
//! same closest hit, bit for bit (see [`crate::hit`]). `u`, `v` are divided once per ray, for
//! the winner.
//!
//! **Range.** The edge functions, `det` and `num_t` are products of two and three
//! coordinates: for meshes of size `2^-40…2^30` they neither under- nor overflow, and
//! [`Watertight`] is measured watertight there (both ends tested by
//! `tests/suite/kernels/watertight_range_ends.rs`; the accuracy tables are measured at ordinary scale).
//! Outside that range the products round to zero, subnormals or infinity and rays may leak
//! through edges or miss (a clean miss: `t = +inf`; the deferred-division kernels miss
//! wherever `|det| < 2^-100`), but the answers stay consistent: each
//! ray–triangle answer depends on that ray and triangle only, the test before the division is
//! conservative at every magnitude (above), so N rays × 1 triangle and 1 ray × N triangles
//! return the same closest hit bit for bit, every lane equals the scalar path, and every
//! record is finite and strictly inside its interval. The seeded fuzzer
//! (`tests/suite/kernels/fuzz_every_width.rs`: magnitudes `2^-140…2^127`, special values) checks this on every
//! case, its former failures kept as regression cases.
//!
//! **Asking.** Through [`Query`](crate::Query): `tris.closest(&ray)` (default kernel
//! [`Watertight`]), `tris.using::<Moller>().any(&packet)`; meshes over shared vertex slices are
//! in [`mesh`](crate::mesh), with their focal cache [`FocalMesh`](crate::focal::FocalMesh).
//!
//! **Bad input.** [`Triangle::new`] stores a triangle with a non-finite coordinate or exactly
//! zero area (collinear vertices, decided exactly) with NaN vertices, and every kernel misses
//! it; bad rays are sanitised by their constructors. No record ever holds a NaN.
//!
//! ```
//! use glam::Vec3;
//! use raylane::triangle::{Triangle, Watertight};
//! use raylane::{Query, Ray, RayPacket};
//!
//! let tri = [Triangle::new(Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0))];
//! let ray = Ray::new(Vec3::new(1.0, 1.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
//! let hit = tri[..].using::<Watertight>().closest(&ray).unwrap();
//! assert_eq!((hit.t, hit.u), (5.0, 0.25)); // u weighs B, v weighs C
//!
//! // A packet gets the same record per lane.
//! let hits = tri[..].closest(&RayPacket::<wide::f32x8>::splat(&ray));
//! assert_eq!(hits.lane(7), Some(hit));
//! ```

mod badouel;
mod baldwin;
mod cramer;
pub mod exact;
pub mod focal;
mod havel;
mod kensler;
mod moller;
mod plucker;
mod precomputed;
mod wald;
mod watertight;

pub use badouel::{Badouel, BadouelRecord};
pub use baldwin::{AffineRecord, BaldwinWeber};
pub use cramer::Cramer;
pub use focal::FocalTriangle;
pub use havel::{HavelHerout, PlanesRecord};
pub use kensler::KenslerShirley;
pub use moller::Moller;
pub use plucker::Plucker;
pub use precomputed::{PrecomputedKernel, precompute_all};
pub use wald::{Wald, WaldRecord};
pub use watertight::{Shear, Watertight};

use glam::Vec3;

use crate::kernel::Cull;
use crate::kernel::{Kernel, LaneHit, Primitive, XYZ};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// A triangle: three vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    a: Vec3,
    b: Vec3,
    c: Vec3,
}

impl Triangle {
    /// A triangle; a non-finite coordinate or exactly zero area (decided exactly) gives a
    /// triangle that is never hit (its vertices are stored as NaN).
    #[must_use]
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        let w = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        let ok =
            a.is_finite() && b.is_finite() && c.is_finite() && !exact::collinear(w(a), w(b), w(c));
        if ok {
            Triangle { a, b, c }
        } else {
            Self::never()
        }
    }

    /// Vertices exactly as [`Triangle::new`] stored them (NaN for a triangle that is never
    /// hit), without its checks: for copies of valid triangles (a `Mesh` checked once when built,
    /// the BVH's leaves).
    #[inline(always)]
    #[must_use]
    pub(crate) const fn stored(a: Vec3, b: Vec3, c: Vec3) -> Self {
        Triangle { a, b, c }
    }

    /// A triangle that is never hit (NaN vertices).
    #[must_use]
    pub const fn never() -> Self {
        let nan = Vec3::splat(f32::NAN);
        Triangle {
            a: nan,
            b: nan,
            c: nan,
        }
    }

    /// Vertex A.
    #[inline]
    #[must_use]
    pub fn a(&self) -> Vec3 {
        self.a
    }

    /// Vertex B (weighted by `u`).
    #[inline]
    #[must_use]
    pub fn b(&self) -> Vec3 {
        self.b
    }

    /// Vertex C (weighted by `v`).
    #[inline]
    #[must_use]
    pub fn c(&self) -> Vec3 {
        self.c
    }

    /// False for a triangle made from bad input.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        !self.a.x.is_nan()
    }

    /// The point with barycentrics `u` (of B) and `v` (of C): `A + u(B − A) + v(C − A)`.
    #[inline]
    #[must_use]
    pub fn point(&self, u: f32, v: f32) -> Vec3 {
        self.a + (self.b - self.a) * u + (self.c - self.a) * v
    }
}

/// Triangles in lanes (structure of arrays): lane `i` of each field is triangle `i`.
#[derive(Clone, Copy, Debug)]
pub struct TrianglePacket<L: Lane> {
    pub(crate) a: V3<L>,
    pub(crate) b: V3<L>,
    pub(crate) c: V3<L>,
}

impl<L: Lane> TrianglePacket<L> {
    /// The same triangle in every lane.
    #[inline(always)]
    #[must_use]
    pub fn splat(t: &Triangle) -> Self {
        TrianglePacket {
            a: V3::splat(t.a),
            b: V3::splat(t.b),
            c: V3::splat(t.c),
        }
    }

    /// Lane `i` holds `f(i)`.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    #[must_use]
    pub fn from_fn(mut f: impl FnMut(usize) -> Triangle) -> Self {
        crate::lane::assert_fits::<L>();
        if L::LANES == 1 {
            // One lane: the triangle itself (no rows to fill).
            let t = f(0);
            return TrianglePacket {
                a: V3::splat(t.a),
                b: V3::splat(t.b),
                c: V3::splat(t.c),
            };
        }
        // The nine coordinates' lanes, written once per triangle, then read as vectors (rows
        // of lanes: each vector one contiguous load).
        let mut c = [[0f32; crate::lane::MAX_LANES]; 9];
        #[allow(clippy::needless_range_loop)] // `i` is the column of nine rows
        for i in 0..L::LANES {
            let t = f(i);
            for (k, v) in [t.a, t.b, t.c].into_iter().enumerate() {
                c[3 * k][i] = v.x;
                c[3 * k + 1][i] = v.y;
                c[3 * k + 2][i] = v.z;
            }
        }
        let v = |k: usize| V3 {
            x: L::from_f32_fn(|i| c[k][i]),
            y: L::from_f32_fn(|i| c[k + 1][i]),
            z: L::from_f32_fn(|i| c[k + 2][i]),
        };
        TrianglePacket {
            a: v(0),
            b: v(3),
            c: v(6),
        }
    }

    /// Up to `L::LANES` triangles, one per lane; lanes past `tris.len()` are never hit.
    #[must_use]
    pub fn from_triangles(tris: &[Triangle]) -> Self {
        Self::from_fn(|i| tris.get(i).copied().unwrap_or(Triangle::never()))
    }

    /// Fills `out` with `tris` in chunks of `L::LANES` (the last chunk padded with triangles
    /// that are never hit); returns the number of chunks written (at most `out.len()`).
    pub fn pack(tris: &[Triangle], out: &mut [TrianglePacket<L>]) -> usize {
        let mut n = 0;
        for (chunk, slot) in tris.chunks(L::LANES).zip(out.iter_mut()) {
            *slot = Self::from_triangles(chunk);
            n += 1;
        }
        n
    }

    /// Vertices A.
    #[inline]
    #[must_use]
    pub fn a(&self) -> V3<L> {
        self.a
    }

    /// Vertices B.
    #[inline]
    #[must_use]
    pub fn b(&self) -> V3<L> {
        self.b
    }

    /// Vertices C.
    #[inline]
    #[must_use]
    pub fn c(&self) -> V3<L> {
        self.c
    }
}

/// A ray–triangle formulation: ray lanes against triangle lanes.
///
/// Implemented by [`Cramer`], [`Moller`] and [`Watertight`]; one generic body each, shared by
/// every lane width and by the op-counting lane. [`prepare`](Self::prepare) computes what
/// depends on the rays only (once per packet and query); [`intersect`](Self::intersect) runs
/// per triangle.
pub trait TriangleKernel {
    /// The method's name (as the checker spells it).
    const NAME: &'static str;
    /// Per-ray constants (`()` for the methods that need none).
    type Rays<L: Lane>: Copy;
    /// The per-ray constants of `rays`.
    fn prepare<L: Lane>(rays: &RayPacket<L>) -> Self::Rays<L>;
    /// The hit of each ray lane on the triangle in the same lane (`pre` from
    /// [`prepare`](Self::prepare) of the same rays; `ray` may have a shrunk `t_max`).
    ///
    /// The kernels that defer their division return `u`, `v` still scaled by the determinant:
    /// call [`LaneHit::normalized`] before reading them (the entry points of this module do).
    #[inline(always)]
    fn intersect<L: Lane>(
        ray: &RayPacket<L>,
        pre: &Self::Rays<L>,
        tri: &TrianglePacket<L>,
        cull: Cull,
    ) -> LaneHit<L> {
        Self::maybe_intersect(ray, pre, tri, cull).unwrap_or_else(LaneHit::miss)
    }
    /// The same, or `None` when every lane failed one of the kernel's tests (its early exits:
    /// a caller then skips the merge of the answer entirely).
    fn maybe_intersect<L: Lane>(
        ray: &RayPacket<L>,
        pre: &Self::Rays<L>,
        tri: &TrianglePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>>;
    /// The axis order of [`Kernel::order`]: by default [`XYZ`].
    #[inline(always)]
    fn order<L: Lane>(_pre: &Self::Rays<L>) -> [usize; 3] {
        XYZ
    }
    /// [`maybe_intersect`](Self::maybe_intersect) for one ray, the same in every lane, against
    /// `tri` with its coordinates in the order [`order(pre)`](Self::order) (see
    /// [`Kernel::first_one`]).
    #[inline(always)]
    fn maybe_intersect_one<L: Lane>(
        ray: &RayPacket<L>,
        pre: &Self::Rays<L>,
        tri: &TrianglePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        Self::maybe_intersect(ray, pre, tri, cull)
    }
}

/// The steps shared by the deferred-division kernels, for lanes in `mask` whose edge tests
/// passed: `num_t = t·|det|`, `num_u = u·|det|`, `num_v = v·|det|` (already carrying the sign
/// of `det`) and `den = |det| > 0`.
///
/// 1. The lower end on the unscaled value: `num_t > 0` (exact in sign) unless `t_min < 0` —
///    2 cmp; a triangle behind the origin costs no division.
/// 2. The upper end before dividing: `num_t < t_max·den`, or `t_max·den` below the smallest
///    normal `2^-126` — 1 mul, 2 cmp. The product rounds, but the closest-hit loops relax
///    `t_max` to `t + |t|·2^-21` after each hit and take a candidate only when its rounded `t`
///    is below the best (see [`crate::hit`]), so this never drops a hit that would win: only
///    the hits that win so far reach step 3. That holds while the product is normal (relative
///    error `2^-24` < the relaxation's `2^-21`); a subnormal product has an absolute error that
///    no relative margin covers (tiny `t`, tiny `det`: N rays × 1 triangle then missed a
///    closer triangle that 1 ray × N triangles found), so such lanes skip the pre-test and are
///    decided on their rounded `t` alone. Exact either way: `fl(t_max·den) < 2^-126` implies
///    `t_max·den < 2^-126`, and the pre-test only ever rejects lanes whose `t` fails step 3.
/// 3. `t = num_t/den` (1 div), strictly inside `(t_min, t_max)`, and `den ≥ 2^-100` — 3 cmp.
///    Below `2^-100` the products that make `det` and the numerators have under-flowed
///    (`det` is a product of three coordinates: a mesh of size `2^-53` seen with directions of
///    length `2^-53` gave `t = 1`, `u = 1` or `t = 0` far outside the mesh's bound), so such a
///    lane is a clean miss, the same in every packet shape. `u`, `v` stay
///    unscaled with `den`: the loops divide them once per ray, for the winner.
#[inline(always)]
pub(crate) fn resolve<L: Lane>(
    ray: &RayPacket<L>,
    mask: L::Mask,
    num_t: L,
    num_u: L,
    num_v: L,
    den: L,
) -> Option<LaneHit<L>> {
    let mask = in_front(ray, mask, num_t);
    if mask.none() {
        return None;
    }
    within(ray, mask, num_t, den, num_u, num_v, den)
}

/// Step 1 of [`resolve`]: the lanes of `mask` with `num_t > 0` (or `t_min < 0`).
#[inline(always)]
pub(crate) fn in_front<L: Lane>(ray: &RayPacket<L>, mask: L::Mask, num_t: L) -> L::Mask {
    let zero = L::from_f32(0.0);
    mask & (num_t.gt(zero) | ray.t_min.lt(zero))
}

/// The smallest `|det|` a deferred-division kernel reports a hit for, `2^-100` (see [`resolve`]).
const MIN_DET: f32 = 1.0 / (1u128 << 100) as f32;

/// Steps 2 and 3 of [`resolve`], with `t = num_t/den` and the barycentrics deferred as
/// `num_u/w`, `num_v/w` (the focal kernel divides `t` and `u`, `v` by different
/// denominators; the others pass `w = den`).
#[inline(always)]
pub(crate) fn within<L: Lane>(
    ray: &RayPacket<L>,
    mask: L::Mask,
    num_t: L,
    den: L,
    num_u: L,
    num_v: L,
    w: L,
) -> Option<LaneHit<L>> {
    let bound = ray.t_max * den;
    // A subnormal product carries an absolute rounding error: decide those lanes on `t`.
    let mask = mask & (num_t.lt(bound) | bound.lt(L::from_f32(f32::MIN_POSITIVE)));
    if mask.none() {
        return None;
    }
    let t = num_t / den;
    // Below `2^-100` the products that make `det` and the numerators have under-flowed: a
    // clean miss rather than a `t`, `u`, `v` made of rounding errors.
    let mask = mask
        & t.gt(ray.t_min)
        & t.lt(ray.t_max)
        & den.ge(L::from_f32(MIN_DET))
        & num_u.is_finite()
        & num_v.is_finite();
    Some(LaneHit::deferred(t, num_u, num_v, w, mask))
}

impl Primitive for Triangle {
    type Packet<L: Lane> = TrianglePacket<L>;
    #[inline(always)]
    fn splat<L: Lane>(&self) -> TrianglePacket<L> {
        TrianglePacket::splat(self)
    }
}

/// Every triangle kernel is a [`Kernel`] of triangles (its one hit per triangle; `u`, `v` may
/// be deferred).
impl<K: TriangleKernel> Kernel<Triangle> for K {
    type Rays<L: Lane> = K::Rays<L>;

    #[inline(always)]
    fn prepare<L: Lane>(rays: &RayPacket<L>) -> K::Rays<L> {
        K::prepare(rays)
    }

    #[inline(always)]
    fn first<L: Lane>(
        rays: &RayPacket<L>,
        pre: &K::Rays<L>,
        tri: &TrianglePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        K::maybe_intersect(rays, pre, tri, cull)
    }

    #[inline(always)]
    fn order<L: Lane>(pre: &K::Rays<L>) -> [usize; 3] {
        K::order(pre)
    }

    #[inline(always)]
    fn first_one<L: Lane>(
        rays: &RayPacket<L>,
        pre: &K::Rays<L>,
        tri: &TrianglePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        K::maybe_intersect_one(rays, pre, tri, cull)
    }

    #[inline(always)]
    fn each_one<L: Lane>(
        rays: &RayPacket<L>,
        pre: &K::Rays<L>,
        tri: &TrianglePacket<L>,
        cull: Cull,
        mut f: impl FnMut(&LaneHit<L>) -> bool,
    ) -> bool {
        // As `each`'s default: a triangle has one hit.
        Self::first_one(rays, pre, tri, cull).is_some_and(|h| h.mask.any() && f(&h))
    }
}
