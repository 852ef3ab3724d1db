//! Triangle meshes over caller-provided slices: shared vertex positions and index triples.
//!
//! A [`Mesh`] borrows `&[Vec3]` positions and `&[[u32; 3]]` triangles (A, B, C as indices into
//! the positions); nothing is copied or allocated. A triangle with an index out of range is
//! skipped (never a panic), and one with a non-finite vertex or zero area is never hit (see
//! [`Triangle::new`]). The index in a hit record is the triangle's position in `indices`;
//! `u` weighs its vertex B and `v` its vertex C.
//!
//! **Validated once.** [`Mesh::new`] and [`Mesh::bounded`] check every triangle once (index
//! range, finite vertices, and [`Triangle::new`]'s exact zero-area test in `f64`) and remember
//! the invalid ones (up to [`Mesh::LISTED`] of them); queries then only gather the vertices.
//! A mesh with more invalid triangles than that re-checks each triangle per query (correct,
//! slower; [`Mesh::invalid`] says how many there are). The focal cache is built once per eye.
//!
//! Queries ([`Query`]): `mesh.closest(&ray)`, `mesh.any(&packet)`, `mesh.all(..)` with the
//! default kernel ([`Watertight`](crate::triangle::Watertight), two-sided), or
//! `mesh.using::<K>()` for any other triangle kernel, culled with
//! [`Using::culled`] ([`Cull`]); N rays × 1 triangle, in index order.
//!
//! ```
//! use raylane::glam::Vec3;
//! use raylane::mesh::Mesh;
//! use raylane::{Query, Ray};
//!
//! let positions = [Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)];
//! let indices = [[0u32, 1, 2]];
//! let mesh = Mesh::new(&positions, &indices);
//! let hit = mesh.closest(&Ray::new(Vec3::new(1.0, 1.0, 5.0), Vec3::NEG_Z)).unwrap();
//! assert_eq!((hit.t, hit.u, hit.normal, hit.front), (5.0, 0.25, Vec3::Z, true));
//! ```
//!
//! **Culling.** [`Mesh::bounded`] adds a bounding sphere ([`bounds`]); each
//! query first asks [`Bound::may_hit`], and lanes it rejects are not tested (their interval
//! is emptied, so every lane width gives the scalar answer). For rays from one eye,
//! [`Mesh::focus`] builds the focal cache ([`FocalTriangle`]) into caller storage (too little
//! is an error, [`Mesh::needed`] says how much), with the bound as a [`FocalSphere`] tested
//! first; the [`FocalMesh`] owns its eye.

use glam::Vec3;

use crate::bounds::{self, Bound};
use crate::hit::{self, Best, LaneHit};
use crate::lane::{Lane, Mask};
use crate::query::{self, Hits, Query, TooSmall, Using};
use crate::ray::RayPacket;
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
    /// How many triangles are invalid (never hit).
    invalid: usize,
    /// The first [`Mesh::LISTED`] of them, ascending.
    listed: [u32; Mesh::LISTED],
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
        let mut m = Mesh {
            positions,
            indices,
            bound: None,
            invalid: 0,
            listed: [u32::MAX; Mesh::LISTED],
        };
        for i in 0..indices.len() {
            if !m.triangle(i).is_some_and(|t| t.is_valid()) {
                if let Some(slot) = m.listed.get_mut(m.invalid) {
                    *slot = i as u32;
                }
                m.invalid += 1;
            }
        }
        m
    }

    /// How many invalid triangles a mesh lists (and so skips without re-checking).
    pub const LISTED: usize = 16;

    /// The number of invalid triangles (out-of-range index, non-finite vertex or zero area):
    /// they are never hit.
    #[inline]
    #[must_use]
    pub fn invalid(&self) -> usize {
        self.invalid
    }

    /// Triangle `i` for a query: checked once when the mesh was built (a triangle that is
    /// never hit when invalid or out of range).
    #[inline(always)]
    pub(crate) fn prepared(&self, i: usize) -> Triangle {
        if self.invalid > Self::LISTED {
            return self.triangle(i).unwrap_or(Triangle::never());
        }
        let Some(&[a, b, c]) = self.indices.get(i) else {
            return Triangle::never();
        };
        let p = |k: u32| self.positions.get(k as usize).copied();
        let listed = || {
            self.listed
                .iter()
                .take(self.invalid)
                .any(|&j| j as usize == i)
        };
        match (p(a), p(b), p(c)) {
            (Some(a), Some(b), Some(c)) if self.invalid == 0 || !listed() => {
                Triangle::stored(a, b, c)
            }
            _ => Triangle::never(),
        }
    }

    /// The number of focal cache entries [`focus`](Self::focus) needs: one per
    /// triangle.
    #[inline]
    #[must_use]
    pub fn needed(&self) -> usize {
        self.len()
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
    pub(crate) fn kept<L: Lane>(&self, rays: &RayPacket<L>) -> Option<RayPacket<L>> {
        if self.bound.is_none() {
            return Some(*rays);
        }
        let keep = self.may_hit(rays) & rays.valid();
        keep.any().then(|| only(rays, keep))
    }

    /// The closest hit's loop state with kernel `K`, or `None` when the bounding sphere
    /// excludes every valid lane (then no triangle was tested): for the demo, which counts
    /// what culling saves.
    #[doc(hidden)]
    #[inline]
    #[must_use]
    pub fn try_closest<K: TriangleKernel, L: Lane>(
        &self,
        rays: &RayPacket<L>,
        cull: Cull,
    ) -> Option<Best<L>> {
        let r = self.kept(rays)?;
        let pre = K::prepare(&r);
        Some(hit::closest(&r, 0..self.len(), |r, i| {
            let t = self.prepared(i);
            Some(K::intersect(r, &pre, &TrianglePacket::splat(&t), cull))
        }))
    }

    /// Lanes whose ray hits some triangle (occlusion), with kernel `K`.
    #[inline]
    #[must_use]
    pub(crate) fn any_lanes<K: TriangleKernel, L: Lane>(
        &self,
        rays: &RayPacket<L>,
        cull: Cull,
    ) -> L::Mask {
        let Some(r) = self.kept(rays) else {
            return Mask::splat(false);
        };
        let pre = K::prepare(&r);
        hit::any(&r, 0..self.len(), |r, i| {
            let t = self.prepared(i);
            Some(K::intersect(r, &pre, &TrianglePacket::splat(&t), cull))
        })
    }

    /// Every hit: `f(triangle index, hit)` for each triangle some lane hits, in index order.
    #[inline]
    pub(crate) fn all_lanes<K: TriangleKernel, L: Lane>(
        &self,
        rays: &RayPacket<L>,
        cull: Cull,
        mut f: impl FnMut(u32, &LaneHit<L>),
    ) {
        let Some(r) = self.kept(rays) else { return };
        let pre = K::prepare(&r);
        for i in 0..self.len() {
            let t = self.prepared(i);
            let h = K::intersect(&r, &pre, &TrianglePacket::splat(&t), cull);
            if h.mask.any() {
                f(i as u32, &h.normalized());
            }
        }
    }

    /// Builds the focal cache of every triangle for rays from `eye` into `out` (entry `i` for
    /// triangle `i`, from the shared positions, which makes shared edges watertight; invalid
    /// triangles get entries that are never hit) and returns the cached mesh, which owns `eye`:
    /// its queries answer rays from `eye` only. `out` shorter than [`needed`](Self::needed) is
    /// an error (nothing is built); a longer one is used up to `needed`.
    pub fn focus<'c>(
        &self,
        eye: Vec3,
        out: &'c mut [FocalTriangle<f32>],
    ) -> Result<FocalMesh<'c>, TooSmall> {
        let needed = self.needed();
        let Some(out) = out.get_mut(..needed) else {
            return Err(TooSmall { needed });
        };
        for (i, slot) in out.iter_mut().enumerate() {
            *slot = match self.triangle(i) {
                Some(t) => FocalTriangle::new(eye, &t),
                None => FocalTriangle::never(),
            };
        }
        Ok(FocalMesh {
            cache: out,
            bound: self.bound.map(|b| b.focal(eye)),
            eye,
            cull: Cull::None,
        })
    }
}

/// A mesh's focal cache for one eye, which it owns, with its bounding sphere as a
/// [`FocalSphere`]: built by [`Mesh::focus`], queried through [`Query`] (rays from the eye
/// only).
#[derive(Clone, Copy, Debug)]
pub struct FocalMesh<'c> {
    cache: &'c [FocalTriangle<f32>],
    bound: Option<FocalSphere<f32>>,
    /// The eye the entries were built for: queries answer rays from it only.
    eye: Vec3,
    /// The culling of [`Query`] calls.
    cull: Cull,
}

impl<'c> FocalMesh<'c> {
    /// A cached mesh from entries built elsewhere (e.g. [`focal::focus`](tf::focus)), without
    /// a bound.
    #[must_use]
    pub fn new(cache: &'c [FocalTriangle<f32>]) -> Self {
        let eye = cache
            .iter()
            .find_map(|e| e.eye())
            .unwrap_or(Vec3::splat(f32::NAN));
        FocalMesh {
            cache,
            bound: None,
            eye,
            cull: Cull::None,
        }
    }

    /// The eye: through [`Query`], rays from elsewhere (an origin not exactly equal to it)
    /// are a miss, never an answer for the wrong rays. NaN for a cache without a valid entry.
    #[inline]
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The same cache with [`Query`] calls culled ([`Cull::Back`]: front faces only).
    #[inline]
    #[must_use]
    pub fn culled(self, cull: Cull) -> Self {
        FocalMesh { cull, ..self }
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
    fn kept<L: Lane>(&self, rays: &FocalRays<L>) -> Option<FocalRays<L>> {
        if self.bound.is_none() {
            return Some(*rays);
        }
        let keep = self.may_hit(rays) & rays.scaled.valid();
        keep.any().then(|| FocalRays {
            scaled: only(&rays.scaled, keep),
            ..*rays
        })
    }

    /// The closest hit's loop state for prepared rays from the eye, or `None` when the bounding
    /// sphere excludes every valid lane (then no triangle was tested): for the demo, which
    /// counts what culling saves.
    #[doc(hidden)]
    #[inline]
    #[must_use]
    pub fn try_closest<L: Lane>(&self, rays: &FocalRays<L>, cull: Cull) -> Option<Best<L>> {
        self.kept(rays)
            .map(|r| tf::closest_prepared(&r, self.cache, cull))
    }

    /// Lanes whose ray from the eye hits some triangle (occlusion).
    #[inline]
    #[must_use]
    fn any_lanes<L: Lane>(&self, rays: &FocalRays<L>, cull: Cull) -> L::Mask {
        match self.kept(rays) {
            Some(r) => hit::any(&r.scaled, self.cache, |r, e| {
                tf::maybe_hit(r, &tf::Splat(e), cull)
            }),
            None => Mask::splat(false),
        }
    }

    /// Every hit: `f(triangle index, hit)` for each triangle some lane hits.
    #[inline]
    fn all_lanes<L: Lane>(&self, rays: &FocalRays<L>, cull: Cull, f: impl FnMut(u32, &LaneHit<L>)) {
        if let Some(r) = self.kept(rays) {
            tf::all_prepared(&r, self.cache, cull, f);
        }
    }
}

/// Meshes with kernel `K`: the bounding sphere first (lanes it excludes miss), then N rays × 1
/// triangle in index order; `all` in index order.
impl<K: TriangleKernel> Query for Using<'_, Mesh<'_>, K> {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        let (m, cull) = (self.set(), self.cull());
        let Some(r) = m.kept(rays) else {
            return Hits::miss();
        };
        let pre = K::prepare(&r);
        let best = hit::closest(&r, 0..m.len(), |r, i| {
            Some(K::intersect(
                r,
                &pre,
                &TrianglePacket::splat(&m.prepared(i)),
                cull,
            ))
        });
        Hits::from_triangles(&r, &best, cull, |i| Some(m.prepared(i as usize)))
    }

    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        self.set().any_lanes::<K, L>(rays, self.cull())
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        let (m, cull) = (self.set(), self.cull());
        m.all_lanes::<K, L>(rays, cull, |i, h| {
            let best = Best::single(h, i);
            f(&Hits::from_triangles(rays, &best, cull, |i| {
                Some(m.prepared(i as usize))
            }));
        });
    }
}

/// Meshes with the default kernel, [`Watertight`](crate::triangle::Watertight) (two-sided).
impl Query for Mesh<'_> {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        Using::<_, crate::triangle::Watertight>::new(self).closest_packet(rays)
    }
    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        Using::<_, crate::triangle::Watertight>::new(self).any_packet(rays)
    }
    #[inline]
    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        Using::<_, crate::triangle::Watertight>::new(self).all_packet(rays, f)
    }
}

/// Focal meshes: rays whose origin is not exactly the cache's eye miss (see
/// [`FocalMesh::eye`]); the others are prepared once ([`FocalRays`]), culled by the bound, and
/// tested against the entries in index order (two passes per block, as
/// `hit::closest_filtered`). Culling: [`FocalMesh::culled`].
impl Query for FocalMesh<'_> {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        let r = query::at_eye(rays, self.eye);
        let best = self
            .try_closest(&FocalRays::new(&r), self.cull)
            .unwrap_or_else(Best::miss);
        Hits::from_triangles(&r, &best, self.cull, |i| {
            self.cache.get(i as usize).map(|e| e.triangle())
        })
    }

    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        let r = query::at_eye(rays, self.eye);
        self.any_lanes(&FocalRays::new(&r), self.cull)
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        let r = query::at_eye(rays, self.eye);
        self.all_lanes(&FocalRays::new(&r), self.cull, |i, h| {
            let best = Best::single(h, i);
            f(&Hits::from_triangles(&r, &best, self.cull, |i| {
                self.cache.get(i as usize).map(|e| e.triangle())
            }));
        });
    }
}
