//! Triangle meshes over caller-provided slices: shared vertex positions and index triples.
//!
//! A [`Mesh`] borrows `&[Vec3]` positions and `&[[u32; 3]]` triangles (A, B, C as indices into
//! the positions); nothing is copied or allocated. A triangle with an index out of range is
//! skipped (never a panic), and one with a non-finite vertex or zero area is never hit (see
//! [`Triangle::new`]). The index in a hit record is the triangle's position in `indices`;
//! `u` weighs its vertex B and `v` its vertex C. Each query builds the triangles from the
//! slices as it goes (with `Triangle::new`'s exact zero-area check: a few `f64` operations per
//! triangle and packet); the focal cache is built once per eye.
//!
//! Every triangle kernel runs over a mesh: [`Mesh::closest`], [`Mesh::any`], [`Mesh::all`]
//! (ray packets, N rays × 1 triangle) and [`Mesh::closest_soa`], [`Mesh::any_soa`] (one ray,
//! triangles gathered into lanes on the fly), two-sided or culled ([`Cull`]).
//!
//! **Culling.** [`Mesh::bounded`] adds a bounding sphere ([`bounds`]); each
//! query first asks [`Bound::may_hit`], and lanes it rejects are not tested (their interval
//! is emptied, so every lane width gives the scalar answer). For rays from one eye,
//! [`Mesh::focus`] builds the focal cache ([`FocalTriangle`]) into caller storage, with the
//! bound as a [`FocalSphere`] tested first.

use glam::Vec3;

use crate::bounds::{self, Bound};
use crate::hit::{self, Hit, HitRecord, LaneHit};
use crate::lane::{Lane, Mask};
use crate::ray::{Ray, RayPacket};
use crate::sphere::focal::{Focal, FocalKernel, Splat};
use crate::sphere::{FocalSphere, Sphere};
use crate::triangle::focal::{self as tf, FocalRays, FocalTriangle};
use crate::triangle::{Cull, Triangle, TriangleKernel, TrianglePacket};

/// A mesh over borrowed positions and index triples (see the [module docs](self)).
#[derive(Clone, Copy, Debug)]
pub struct Mesh<'a> {
    positions: &'a [Vec3],
    indices: &'a [[u32; 3]],
    bound: Option<Bound>,
}

/// Empties the interval of the lanes outside `keep`.
#[inline(always)]
fn only<L: Lane>(rays: &RayPacket<L>, keep: L::Mask) -> RayPacket<L> {
    RayPacket {
        t_min: L::select(keep, rays.t_min, L::from_f32(f32::INFINITY)),
        t_max: L::select(keep, rays.t_max, L::from_f32(f32::NEG_INFINITY)),
        ..*rays
    }
}

impl<'a> Mesh<'a> {
    /// A mesh without a bounding sphere.
    #[must_use]
    pub fn new(positions: &'a [Vec3], indices: &'a [[u32; 3]]) -> Self {
        Mesh {
            positions,
            indices,
            bound: None,
        }
    }

    /// A mesh with Ritter's bounding sphere of its referenced vertices (one pass over the
    /// triangles per Ritter step; no allocation).
    #[must_use]
    pub fn bounded(positions: &'a [Vec3], indices: &'a [[u32; 3]]) -> Self {
        Mesh {
            bound: bounds::ritter_indexed(positions, indices).map(|s| Bound::new(&s)),
            ..Self::new(positions, indices)
        }
    }

    /// The same mesh culled by `sphere`, which must contain every vertex.
    #[must_use]
    pub fn with_bound(self, sphere: &Sphere) -> Self {
        Mesh {
            bound: Some(Bound::new(sphere)),
            ..self
        }
    }

    /// The positions.
    #[inline]
    #[must_use]
    pub fn positions(&self) -> &'a [Vec3] {
        self.positions
    }

    /// The index triples.
    #[inline]
    #[must_use]
    pub fn indices(&self) -> &'a [[u32; 3]] {
        self.indices
    }

    /// The culling bound, if any.
    #[inline]
    #[must_use]
    pub fn bound(&self) -> Option<&Bound> {
        self.bound.as_ref()
    }

    /// Number of triangles (index triples, including skipped ones).
    #[inline]
    #[must_use]
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// True when there are no triangles.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Triangle `i`, or `None` when `i` or one of its indices is out of range.
    #[inline]
    #[must_use]
    pub fn triangle(&self, i: usize) -> Option<Triangle> {
        let [a, b, c] = *self.indices.get(i)?;
        let p = |k: u32| self.positions.get(k as usize).copied();
        Some(Triangle::new(p(a)?, p(b)?, p(c)?))
    }

    /// Lanes the bounding sphere cannot exclude (every lane without a bound).
    #[inline]
    #[must_use]
    pub fn may_hit<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        match &self.bound {
            Some(b) => b.may_hit(rays),
            None => Mask::splat(true),
        }
    }

    /// The rays with culled (and invalid) lanes emptied, or `None` when no lane is left.
    #[inline]
    fn culled<L: Lane>(&self, rays: &RayPacket<L>) -> Option<RayPacket<L>> {
        if self.bound.is_none() {
            return Some(*rays);
        }
        let keep = self.may_hit(rays) & rays.valid();
        keep.any().then(|| only(rays, keep))
    }

    /// Closest hit of ray lanes with kernel `K`.
    #[inline]
    #[must_use]
    pub fn closest<K: TriangleKernel, L: Lane>(&self, rays: &RayPacket<L>, cull: Cull) -> Hit<L> {
        self.try_closest::<K, L>(rays, cull)
            .unwrap_or_else(Hit::none)
    }

    /// [`closest`](Self::closest), or `None` when the bounding sphere excludes every valid lane
    /// (then no triangle was tested): for callers that count what culling saves.
    #[inline]
    #[must_use]
    pub fn try_closest<K: TriangleKernel, L: Lane>(
        &self,
        rays: &RayPacket<L>,
        cull: Cull,
    ) -> Option<Hit<L>> {
        let r = self.culled(rays)?;
        let pre = K::prepare(&r);
        Some(hit::closest(&r, 0..self.len(), |r, i| {
            let t = self.triangle(i)?;
            Some(K::intersect(r, &pre, &TrianglePacket::splat(&t), cull))
        }))
    }

    /// Lanes whose ray hits some triangle (occlusion), with kernel `K`.
    #[inline]
    #[must_use]
    pub fn any<K: TriangleKernel, L: Lane>(&self, rays: &RayPacket<L>, cull: Cull) -> L::Mask {
        let Some(r) = self.culled(rays) else {
            return Mask::splat(false);
        };
        let pre = K::prepare(&r);
        hit::any(&r, 0..self.len(), |r, i| {
            let t = self.triangle(i)?;
            Some(K::intersect(r, &pre, &TrianglePacket::splat(&t), cull))
        })
    }

    /// Every hit: `f(triangle index, hit)` for each triangle some lane hits, in index order.
    #[inline]
    pub fn all<K: TriangleKernel, L: Lane>(
        &self,
        rays: &RayPacket<L>,
        cull: Cull,
        mut f: impl FnMut(u32, &LaneHit<L>),
    ) {
        let Some(r) = self.culled(rays) else { return };
        let pre = K::prepare(&r);
        for i in 0..self.len() {
            let Some(t) = self.triangle(i) else { continue };
            let h = K::intersect(&r, &pre, &TrianglePacket::splat(&t), cull);
            if h.mask.any() {
                f(i as u32, &h.normalized());
            }
        }
    }

    /// Triangles `c·L::LANES ..` gathered into lanes (skipped ones never hit).
    #[inline]
    fn chunk<L: Lane>(&self, c: usize) -> TrianglePacket<L> {
        TrianglePacket::from_fn(|j| self.triangle(c * L::LANES + j).unwrap_or(Triangle::never()))
    }

    /// Closest hit of one ray, triangles gathered `L::LANES` at a time (1 ray × N).
    #[inline]
    #[must_use]
    pub fn closest_soa<K: TriangleKernel, L: Lane>(
        &self,
        ray: &Ray,
        cull: Cull,
    ) -> Option<HitRecord> {
        if !self.may_hit(&RayPacket::<f32>::splat(ray)) {
            return None;
        }
        let pre = K::prepare(&RayPacket::<L>::splat(ray));
        let chunks = (0..self.len().div_ceil(L::LANES)).map(|c| self.chunk::<L>(c));
        hit::closest_soa(ray, chunks, |r, t| Some(K::intersect(r, &pre, &t, cull)))
    }

    /// True when one ray hits some triangle (triangles gathered into lanes).
    #[inline]
    #[must_use]
    pub fn any_soa<K: TriangleKernel, L: Lane>(&self, ray: &Ray, cull: Cull) -> bool {
        if !self.may_hit(&RayPacket::<f32>::splat(ray)) {
            return false;
        }
        let pre = K::prepare(&RayPacket::<L>::splat(ray));
        let chunks = (0..self.len().div_ceil(L::LANES)).map(|c| self.chunk::<L>(c));
        hit::any_soa(ray, chunks, |r, t| Some(K::intersect(r, &pre, &t, cull)))
    }

    /// Builds the focal cache of every triangle for rays from `eye` into `out` (entry `i` for
    /// triangle `i`; skipped triangles get entries that are never hit) and returns the cached
    /// mesh over the entries written (`min(len, out.len())`). Entries are built from the shared
    /// positions, which makes shared edges watertight.
    pub fn focus<'c>(&self, eye: Vec3, out: &'c mut [FocalTriangle<f32>]) -> FocalMesh<'c> {
        let n = self.len().min(out.len());
        for (i, slot) in out[..n].iter_mut().enumerate() {
            *slot = match self.triangle(i) {
                Some(t) => FocalTriangle::new(eye, &t),
                None => FocalTriangle::never(),
            };
        }
        FocalMesh {
            cache: &out[..n],
            bound: self.bound.map(|b| b.focal(eye)),
        }
    }
}

/// A mesh's focal cache for one eye, with its bounding sphere as a [`FocalSphere`]. Queries
/// take [`FocalRays`] (prepared once per query for any number of meshes).
#[derive(Clone, Copy, Debug)]
pub struct FocalMesh<'c> {
    cache: &'c [FocalTriangle<f32>],
    bound: Option<FocalSphere<f32>>,
}

impl<'c> FocalMesh<'c> {
    /// A cached mesh from entries built elsewhere (e.g. [`focal::focus`](tf::focus)), without
    /// a bound.
    #[must_use]
    pub fn new(cache: &'c [FocalTriangle<f32>]) -> Self {
        FocalMesh { cache, bound: None }
    }

    /// The entries.
    #[inline]
    #[must_use]
    pub fn cache(&self) -> &'c [FocalTriangle<f32>] {
        self.cache
    }

    /// Lanes the bounding sphere cannot exclude (every lane without a bound): the first step
    /// of the guarded focal sphere test on the unit directions, `v² > k_lo` with `v = T·U`
    /// (4 mul, 2 add, 1 cmp). Over the whole line, the cached `k_lo` (`c² − r²` lowered by its
    /// rounding bound) makes a rejected lane a certain miss, and an eye inside the sphere
    /// (`k_lo < 0`) rejects none.
    #[inline]
    #[must_use]
    pub fn may_hit<L: Lane>(&self, rays: &FocalRays<L>) -> L::Mask {
        match &self.bound {
            Some(b) => Focal::candidate(&rays.unit_lines(), &Splat(b)),
            None => Mask::splat(true),
        }
    }

    /// The rays with culled (and invalid) lanes emptied, or `None` when no lane is left.
    #[inline]
    fn culled<L: Lane>(&self, rays: &FocalRays<L>) -> Option<FocalRays<L>> {
        if self.bound.is_none() {
            return Some(*rays);
        }
        let keep = self.may_hit(rays) & rays.scaled.valid();
        keep.any().then(|| FocalRays {
            scaled: only(&rays.scaled, keep),
            ..*rays
        })
    }

    /// Closest hit of rays from the eye.
    #[inline]
    #[must_use]
    pub fn closest<L: Lane>(&self, rays: &FocalRays<L>, cull: Cull) -> Hit<L> {
        self.try_closest(rays, cull).unwrap_or_else(Hit::none)
    }

    /// [`closest`](Self::closest), or `None` when the bounding sphere excludes every valid lane
    /// (then no triangle was tested): for callers that count what culling saves.
    #[inline]
    #[must_use]
    pub fn try_closest<L: Lane>(&self, rays: &FocalRays<L>, cull: Cull) -> Option<Hit<L>> {
        self.culled(rays)
            .map(|r| tf::closest_prepared(&r, self.cache, cull))
    }

    /// Lanes whose ray from the eye hits some triangle (occlusion).
    #[inline]
    #[must_use]
    pub fn any<L: Lane>(&self, rays: &FocalRays<L>, cull: Cull) -> L::Mask {
        match self.culled(rays) {
            Some(r) => hit::any(&r.scaled, self.cache, |r, e| {
                tf::maybe_hit(r, &tf::Splat(e), cull)
            }),
            None => Mask::splat(false),
        }
    }

    /// Every hit: `f(triangle index, hit)` for each triangle some lane hits.
    #[inline]
    pub fn all<L: Lane>(&self, rays: &FocalRays<L>, cull: Cull, f: impl FnMut(u32, &LaneHit<L>)) {
        if let Some(r) = self.culled(rays) {
            tf::all_prepared(&r, self.cache, cull, f);
        }
    }
}
