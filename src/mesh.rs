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
//! Queries ([`Query`](crate::Query)): `mesh.closest(&ray)`, `mesh.any(&packet)`,
//! `mesh.all(..)` with the default kernel ([`Watertight`], two-sided), or `mesh.using::<K>()`
//! for any other triangle kernel and `.culled(Cull::Back)` for front faces only; N rays × 1
//! triangle, in index order.
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
//! **Culling.** [`Mesh::bounded`] adds a bounding sphere ([`bounds`]); each query first asks
//! [`Bound::may_hit`], and lanes it rejects are not tested (their interval is emptied, so every
//! lane width gives the scalar answer). For rays from one eye,
//! [`FocalMesh`](crate::focal::FocalMesh) caches the triangles, with the bound tested first.

use glam::Vec3;

use crate::bounds::{self, Bound};
use crate::hit::{Collector, Hits, Record, Winners};
use crate::kernel::{Cull, Kernel};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;
use crate::set::{Set, flat, mine};
use crate::sphere::Sphere;
use crate::triangle::{Triangle, Watertight};

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

    /// The lanes of `rays` to test: the valid ones the bounding sphere cannot exclude.
    #[inline(always)]
    pub(crate) fn kept<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        match &self.bound {
            Some(b) => b.may_hit(rays) & rays.valid(),
            None => rays.valid(),
        }
    }
}

/// Meshes: the bounding sphere first (lanes it excludes are not tested), then N rays × 1
/// triangle in index order; `all` in index order. Default kernel: [`Watertight`], two-sided.
impl Set for Mesh<'_> {
    type Prim = Triangle;
    type Kernel = Watertight;

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_with<K: Kernel<Triangle>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        let keep = self.kept(rays);
        keep.any()
            && flat::<Triangle, K, L, C>(
                rays,
                keep,
                cull,
                set,
                c,
                (0..self.len()).map(|i| self.prepared(i)),
            )
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records_with<L: Lane>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        w: &Winners<L>,
    ) -> Hits<L> {
        Triangle::records(
            rays,
            &mine(w, set),
            cull,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |loc| Some(self.prepared(loc as usize)),
        )
    }
}
