//! What every kernel shares: its answer per lane ([`LaneHit`]), the face culling it is asked
//! for ([`Cull`]), and the one trait that names a kernel of a primitive ([`Kernel`]), through
//! which every set of the crate calls its kernels.
//!
//! A kernel tests ray lanes against primitive lanes: lane `i` of the answer is ray `i` against
//! primitive `i`. Splatting one side gives the two shapes the sets use: N rays × 1 primitive
//! (the primitive in every lane: flat sets, packet traversals) and 1 ray × N primitives (the
//! ray in every lane: a BVH leaf's primitives against one ray).

use crate::lane::{Lane, Mask};
use crate::ray::{Ray, RayPacket, UNIT_TOLERANCE};

/// One lane-wise test result: the parameter `t`, two surface parameters `u`, `v`
/// (barycentrics for triangles, scaled by `w` while a query runs; for spheres `u = 1` marks
/// an exit root, see [`Kernel::first`]) and the lanes that hit inside the ray's interval.
///
/// Misses are canonical: `t = +inf`, `u = v = 0`, `w = 1`.
#[derive(Clone, Copy, Debug)]
pub struct LaneHit<L: Lane> {
    /// Ray parameter of the hit; `+inf` where `mask` is clear.
    pub t: L,
    /// First surface parameter (barycentric weight of vertex B for triangles), times `w`.
    pub u: L,
    /// Second surface parameter (barycentric weight of vertex C for triangles), times `w`.
    pub v: L,
    /// The denominator of `u` and `v` (a kernel that defers its division leaves it to the
    /// query, which divides once per ray, for the winner); 1 once [`normalized`](Self::normalized).
    pub w: L,
    /// Lanes that hit inside the ray interval.
    pub mask: L::Mask,
}

impl<L: Lane> LaneHit<L> {
    /// No lane hits.
    #[inline(always)]
    #[must_use]
    pub fn miss() -> Self {
        let zero = L::from_f32(0.0);
        LaneHit {
            t: L::from_f32(f32::INFINITY),
            u: zero,
            v: zero,
            w: L::from_f32(1.0),
            mask: Mask::splat(false),
        }
    }

    /// Canonicalises: lanes outside `mask` get `t = +inf`, `u = v = 0`.
    #[inline(always)]
    #[must_use]
    pub fn new(t: L, u: L, v: L, mask: L::Mask) -> Self {
        Self::deferred(t, u, v, L::from_f32(1.0), mask)
    }

    /// A hit whose barycentrics are `u/w`, `v/w`: the division is left to the query, which does
    /// it once per ray for the winner ([`normalized`](Self::normalized)).
    #[inline(always)]
    #[must_use]
    pub fn deferred(t: L, u: L, v: L, w: L, mask: L::Mask) -> Self {
        let zero = L::from_f32(0.0);
        LaneHit {
            t: L::select(mask, t, L::from_f32(f32::INFINITY)),
            u: L::select(mask, u, zero),
            v: L::select(mask, v, zero),
            w: L::select(mask, w, L::from_f32(1.0)),
            mask,
        }
    }

    /// `u/w`, `v/w` (2 div): the record as callers see it, with `−0` made `+0` in `t`, `u`,
    /// `v` (`x + 0`).
    #[inline(always)]
    #[must_use]
    pub fn normalized(self) -> Self {
        LaneHit {
            t: plus_zero(self.t),
            u: plus_zero(self.u / self.w),
            v: plus_zero(self.v / self.w),
            w: L::from_f32(1.0),
            ..self
        }
    }
}

/// `x + 0`: `−0` becomes `+0` (IEEE round-to-nearest), every other value (NaN aside) is
/// unchanged. Kernels that fold a sign into their numerators (`select(back, −x, x)`) return
/// `−0` for a zero barycentric on a back face, or for `t = 0`; records carry `+0`, so that
/// `u == 0.0` and the bits agree whichever side a ray comes from. One add per field, at the
/// one place records are made (never in a kernel's counted path).
#[inline(always)]
pub(crate) fn plus_zero<L: Lane>(x: L) -> L {
    x + L::from_f32(0.0)
}

/// Which faces a test reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Cull {
    /// Two-sided (the default): hits from either side.
    #[default]
    None,
    /// Back faces culled, front faces only: triangles `d·N < 0` with
    /// `N = (B − A) × (C − A)`; spheres their entry roots (a ray from inside misses); planes
    /// `d·n < 0`.
    Back,
}

impl Cull {
    /// True for [`Cull::Back`].
    #[inline(always)]
    #[must_use]
    pub fn back(self) -> bool {
        matches!(self, Cull::Back)
    }
}

/// A primitive the kernels test: its lanes form [`Packet`](Self::Packet)s.
pub trait Primitive: Copy {
    /// Primitives in lanes (lane `i` is primitive `i`): what a kernel reads.
    type Packet<L: Lane>: Copy;
    /// The same primitive in every lane (N rays × 1 primitive).
    fn splat<L: Lane>(&self) -> Self::Packet<L>;
}

/// A kernel of primitive `P`: the one trait through which every set calls its kernels, and
/// the type parameter of a query's [`using`](crate::Query::using) (which accepts only
/// kernels of the set's primitive).
///
/// Implemented by every sphere kernel ([`SphereKernel`](crate::sphere::SphereKernel)), every
/// triangle kernel ([`TriangleKernel`](crate::triangle::TriangleKernel)) and the plane test
/// ([`PlaneTest`](crate::plane::PlaneTest)).
pub trait Kernel<P: Primitive> {
    /// Per-ray constants (`()` for the kernels that need none).
    type Rays<L: Lane>: Copy;
    /// True when the kernel needs unit directions: a set asks it only for lanes whose `|d|²`
    /// is within [`UNIT_TOLERANCE`] of 1 ([`admit`]).
    const UNIT_DIRECTIONS: bool = false;
    /// The per-ray constants of `rays` (once per query and packet).
    fn prepare<L: Lane>(rays: &RayPacket<L>) -> Self::Rays<L>;
    /// The first hit of each ray lane on the primitive in the same lane, inside the lane's
    /// interval (spheres: the entry root, or the exit root from inside with `u = 1`; under
    /// [`Cull::Back`] entry roots only). `u`, `v` may be deferred ([`LaneHit::deferred`]).
    /// `None` when every lane missed the kernel's first test (its early exit), so that a set
    /// skips the merge of the answer entirely.
    fn first<L: Lane>(
        rays: &RayPacket<L>,
        pre: &Self::Rays<L>,
        prim: &P::Packet<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>>;
    /// The axis order in which [`first_one`](Self::first_one) takes the primitives'
    /// coordinates, for rays that all share lane 0's: a kernel whose per-ray constants permute
    /// the axes ([`Watertight`](crate::triangle::Watertight)) asks for its permutation, so that
    /// a leaf loads its primitives permuted once for all lanes rather than the kernel
    /// selecting lane by lane. By default [`XYZ`].
    #[inline(always)]
    fn order<L: Lane>(_pre: &Self::Rays<L>) -> [usize; 3] {
        XYZ
    }
    /// [`first`](Self::first) for one ray, the same in every lane of `rays`, against `prim`
    /// with its coordinates in the order [`order(pre)`](Self::order): the same values as
    /// [`first`](Self::first) on the primitives as they are, so the same bits. By default
    /// [`first`](Self::first).
    #[inline(always)]
    fn first_one<L: Lane>(
        rays: &RayPacket<L>,
        pre: &Self::Rays<L>,
        prim: &P::Packet<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        Self::first(rays, pre, prim, cull)
    }
    /// [`each`](Self::each) for one ray, as [`first_one`](Self::first_one) is
    /// [`first`](Self::first).
    #[inline(always)]
    fn each_one<L: Lane>(
        rays: &RayPacket<L>,
        pre: &Self::Rays<L>,
        prim: &P::Packet<L>,
        cull: Cull,
        f: impl FnMut(&LaneHit<L>) -> bool,
    ) -> bool {
        Self::each(rays, pre, prim, cull, f)
    }
    /// Every hit, in order along the rays (spheres: the entry roots, then, unless culled, the
    /// exit roots with `u = 1`), each passed to `f`; stops when `f` returns true, and returns
    /// whether it stopped. By default the [`first`](Self::first) hit alone.
    #[inline(always)]
    fn each<L: Lane>(
        rays: &RayPacket<L>,
        pre: &Self::Rays<L>,
        prim: &P::Packet<L>,
        cull: Cull,
        mut f: impl FnMut(&LaneHit<L>) -> bool,
    ) -> bool {
        Self::first(rays, pre, prim, cull).is_some_and(|h| h.mask.any() && f(&h))
    }
}

/// The axis order x, y, z (see [`Kernel::order`]).
pub const XYZ: [usize; 3] = [0, 1, 2];

/// Whether a kernel can answer `ray`: for kernels that need unit directions, false when
/// `|d|²` is more than [`UNIT_TOLERANCE`] from 1 ([`admit`] for one ray: such a ray misses).
#[inline(always)]
#[must_use]
pub(crate) fn admits(ray: &Ray, unit_directions: bool) -> bool {
    !(unit_directions && (ray.dir().length_squared() - 1.0).abs() > UNIT_TOLERANCE)
}

/// The rays a kernel can answer: for kernels that need unit directions, lanes whose `|d|²`
/// is more than [`UNIT_TOLERANCE`] from 1 get `t_min = +inf` (no `t` lies above it: a miss);
/// others unchanged (3 mul, 2 add, 2 cmp for such kernels, nothing for the others).
#[inline(always)]
#[must_use]
pub fn admit<L: Lane>(rays: &RayPacket<L>, unit_directions: bool) -> RayPacket<L> {
    if !unit_directions {
        return *rays;
    }
    let e = rays.dir.length_squared() - L::from_f32(1.0);
    let ok = e.abs().le(L::from_f32(UNIT_TOLERANCE));
    RayPacket {
        t_min: L::select(ok, rays.t_min, L::from_f32(f32::INFINITY)),
        t_max: L::select(ok, rays.t_max, L::from_f32(f32::NEG_INFINITY)),
        ..*rays
    }
}
