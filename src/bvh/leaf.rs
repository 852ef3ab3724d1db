//! Leaves (4 primitives in structure-of-arrays lanes) and the primitive sets a tree is built
//! over.

use glam::Vec3;
use wide::f32x4;

use super::{EMPTY, LEAF_WIDTH, max, min};
use crate::hit::{Best, LaneHit};
use crate::lane::{Lane, Mask};
use crate::mesh::Mesh;
use crate::query::{Hits, Query, Using, sphere_hit};
use crate::ray::RayPacket;
use crate::sphere::{Robust, Sphere, SphereKernel, SpherePacket};
use crate::triangle::{Cull, Shear, Triangle, TriangleKernel, TrianglePacket, Watertight};
use crate::vec3::V3;

/// What the builder and the refit need of a leaf: up to [`LEAF_WIDTH`] primitives (or
/// instances) in lanes, their indices in the set the tree was built over ([`EMPTY`] in unused
/// lanes), and their boxes.
pub trait Packed: Copy + core::fmt::Debug {
    /// A leaf with no primitive.
    const EMPTY: Self;
    /// Original indices of the primitives in the lanes.
    fn indices(&self) -> &[u32; LEAF_WIDTH];
    /// The box of lane `k` (empty — `min > max` — for a primitive that is never hit).
    fn bounds(&self, k: usize) -> ([f32; 3], [f32; 3]);
}

/// A leaf of primitives with their kernels (unused lanes hold NaN geometry, never hit).
pub trait Leaf: Packed {
    /// The primitive type.
    type Prim: Copy;
    /// The primitive in lane `k` (one that is never hit for an unused lane).
    fn prim(&self, k: usize) -> Self::Prim;
    /// The query records of the winners in `best` (`prim(i)`: the primitive of index `i`),
    /// as the flat sets make them ([`Hits::from_triangles`], [`Hits::from_spheres`]).
    fn records<L: Lane>(
        rays: &RayPacket<L>,
        best: &Best<L>,
        cull: Cull,
        prim: impl Fn(u32) -> Option<Self::Prim>,
    ) -> Hits<L>;
    /// Every hit of `rays` on `prim` (index `index`), as the flat set's `all` reports it.
    fn all<L: Lane>(
        prim: &Self::Prim,
        index: u32,
        rays: &RayPacket<L>,
        cull: Cull,
        f: &mut dyn FnMut(&Hits<L>),
    );
    /// Per-ray constants of the leaf kernel.
    type Rays<L: Lane>: Copy;
    /// The per-ray constants of `rays`.
    fn prepare<L: Lane>(rays: &RayPacket<L>) -> Self::Rays<L>;
    /// N rays × 1 primitive: lane `k`'s primitive splatted against the rays.
    fn test_one<L: Lane>(
        &self,
        k: usize,
        rays: &RayPacket<L>,
        pre: &Self::Rays<L>,
        cull: Cull,
    ) -> LaneHit<L>;
    /// 1 ray × 4 primitives: the ray splatted against the leaf's lanes (the same candidate
    /// per lane as [`test_one`](Self::test_one)).
    fn test_four(
        &self,
        ray: &RayPacket<f32x4>,
        pre: &Self::Rays<f32x4>,
        cull: Cull,
    ) -> LaneHit<f32x4>;
    /// What the per-eye cache of a [`FocalBvh`](super::FocalBvh) keeps of a leaf
    /// ([`RelTri4`]: the vertices minus the eye; `()` for spheres, whose kernel's fallback
    /// needs the centre itself).
    type Rel: Copy + core::fmt::Debug;
    /// The cache entry of a leaf not yet reached.
    const REL_EMPTY: Self::Rel;
    /// The cache entry for rays from `eye`.
    fn relative(&self, eye: Vec3) -> Self::Rel;
    /// [`test_four`](Self::test_four) for rays from the eye `rel` was made for: the same bits
    /// (by default `test_four` itself, for leaves that cache nothing).
    #[inline(always)]
    fn test_four_rel(
        &self,
        _rel: &Self::Rel,
        ray: &RayPacket<f32x4>,
        pre: &Self::Rays<f32x4>,
        cull: Cull,
    ) -> LaneHit<f32x4> {
        self.test_four(ray, pre, cull)
    }
    /// [`test_one`](Self::test_one) for rays from the eye `rel` was made for: the same bits
    /// (by default `test_one` itself).
    #[inline(always)]
    fn test_one_rel<L: Lane>(
        &self,
        _rel: &Self::Rel,
        k: usize,
        rays: &RayPacket<L>,
        pre: &Self::Rays<L>,
        cull: Cull,
    ) -> LaneHit<L> {
        self.test_one(k, rays, pre, cull)
    }
}

/// Four triangles' vertices minus an eye (`A − E`, `B − E`, `C − E`, each coordinate rounded
/// once, as the [`Watertight`] kernel's first step computes them for rays from `E`): what a
/// [`FocalBvh`](super::FocalBvh) caches per leaf. 144 bytes.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelTri4 {
    /// `A − E`: x, y, z lanes.
    pub a: [[f32; LEAF_WIDTH]; 3],
    /// `B − E`.
    pub b: [[f32; LEAF_WIDTH]; 3],
    /// `C − E`.
    pub c: [[f32; LEAF_WIDTH]; 3],
}

impl RelTri4 {
    /// No triangles (NaN: never hit).
    pub const EMPTY: Self = RelTri4 {
        a: [[f32::NAN; LEAF_WIDTH]; 3],
        b: [[f32::NAN; LEAF_WIDTH]; 3],
        c: [[f32::NAN; LEAF_WIDTH]; 3],
    };
}

/// `v − eye`, lane by lane.
#[inline(always)]
fn minus(v: &[[f32; LEAF_WIDTH]; 3], eye: Vec3) -> [[f32; LEAF_WIDTH]; 3] {
    let e = eye.to_array();
    core::array::from_fn(|a| v[a].map(|x| x - e[a]))
}

/// A set of primitives a tree can be built over.
pub trait Primitives {
    /// The leaf type the primitives are packed into.
    type Leaf: Packed;
    /// Number of primitives.
    fn count(&self) -> usize;
    /// The box of primitive `i` (empty for a primitive that is never hit).
    fn bounds(&self, i: u32) -> ([f32; 3], [f32; 3]);
    /// Writes primitive `i` into lane `k` of `leaf`.
    fn put(&self, i: u32, leaf: &mut Self::Leaf, k: usize);
}

/// Four triangles (160 bytes): vertices A, B, C as `[axis][lane]`, and their indices.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tri4 {
    /// Vertices A: x, y, z lanes.
    pub a: [[f32; LEAF_WIDTH]; 3],
    /// Vertices B.
    pub b: [[f32; LEAF_WIDTH]; 3],
    /// Vertices C.
    pub c: [[f32; LEAF_WIDTH]; 3],
    /// Triangle indices ([`EMPTY`] for unused lanes).
    pub index: [u32; LEAF_WIDTH],
}

/// Four spheres (80 bytes): centres as `[axis][lane]`, radii, indices.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere4 {
    /// Centres: x, y, z lanes.
    pub center: [[f32; LEAF_WIDTH]; 3],
    /// Radii (NaN for unused lanes and invalid spheres).
    pub radius: [f32; LEAF_WIDTH],
    /// Sphere indices ([`EMPTY`] for unused lanes).
    pub index: [u32; LEAF_WIDTH],
}

#[inline(always)]
fn get(v: &[[f32; LEAF_WIDTH]; 3], k: usize) -> Vec3 {
    Vec3::new(v[0][k], v[1][k], v[2][k])
}

#[inline(always)]
fn set(v: &mut [[f32; LEAF_WIDTH]; 3], k: usize, p: Vec3) {
    v[0][k] = p.x;
    v[1][k] = p.y;
    v[2][k] = p.z;
}

#[inline(always)]
fn lanes4(v: &[[f32; LEAF_WIDTH]; 3]) -> V3<f32x4> {
    V3::new(f32x4::new(v[0]), f32x4::new(v[1]), f32x4::new(v[2]))
}

/// The box of points, NaN coordinates ignored (all NaN: the empty box).
pub(crate) fn points_box(p: &[Vec3]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for v in p {
        for (a, x) in v.to_array().into_iter().enumerate() {
            lo[a] = min(lo[a], x);
            hi[a] = max(hi[a], x);
        }
    }
    (lo, hi)
}

impl Tri4 {
    /// Triangle in lane `k` (never-hit NaN for an unused lane).
    #[must_use]
    pub fn triangle(&self, k: usize) -> Triangle {
        if self.index[k] == EMPTY {
            return Triangle::never();
        }
        // Stored as `Triangle::new` made it (NaN for one that is never hit).
        Triangle::stored(get(&self.a, k), get(&self.b, k), get(&self.c, k))
    }

    fn set_triangle(&mut self, k: usize, t: &Triangle, index: u32) {
        set(&mut self.a, k, t.a());
        set(&mut self.b, k, t.b());
        set(&mut self.c, k, t.c());
        self.index[k] = index;
    }
}

impl Packed for Tri4 {
    const EMPTY: Self = Tri4 {
        a: [[f32::NAN; LEAF_WIDTH]; 3],
        b: [[f32::NAN; LEAF_WIDTH]; 3],
        c: [[f32::NAN; LEAF_WIDTH]; 3],
        index: [EMPTY; LEAF_WIDTH],
    };

    #[inline(always)]
    fn indices(&self) -> &[u32; LEAF_WIDTH] {
        &self.index
    }

    fn bounds(&self, k: usize) -> ([f32; 3], [f32; 3]) {
        points_box(&[get(&self.a, k), get(&self.b, k), get(&self.c, k)])
    }
}

impl Leaf for Tri4 {
    type Prim = Triangle;

    fn prim(&self, k: usize) -> Triangle {
        self.triangle(k)
    }

    #[inline]
    fn records<L: Lane>(
        rays: &RayPacket<L>,
        best: &Best<L>,
        cull: Cull,
        prim: impl Fn(u32) -> Option<Triangle>,
    ) -> Hits<L> {
        Hits::from_triangles(rays, best, cull, prim)
    }

    fn all<L: Lane>(
        prim: &Triangle,
        index: u32,
        rays: &RayPacket<L>,
        cull: Cull,
        f: &mut dyn FnMut(&Hits<L>),
    ) {
        Using::<[Triangle], Watertight>::new(core::slice::from_ref(prim))
            .culled(cull)
            .all_packet(rays, &mut |h: &Hits<L>| f(&reindex(h, index)));
    }

    type Rays<L: Lane> = Shear<L>;

    #[inline(always)]
    fn prepare<L: Lane>(rays: &RayPacket<L>) -> Shear<L> {
        Watertight::prepare(rays)
    }

    #[inline(always)]
    fn test_one<L: Lane>(
        &self,
        k: usize,
        rays: &RayPacket<L>,
        pre: &Shear<L>,
        cull: Cull,
    ) -> LaneHit<L> {
        let tri = TrianglePacket {
            a: V3::splat(get(&self.a, k)),
            b: V3::splat(get(&self.b, k)),
            c: V3::splat(get(&self.c, k)),
        };
        Watertight::intersect(rays, pre, &tri, cull)
    }

    #[inline(always)]
    fn test_four(&self, ray: &RayPacket<f32x4>, pre: &Shear<f32x4>, cull: Cull) -> LaneHit<f32x4> {
        let tri = TrianglePacket {
            a: lanes4(&self.a),
            b: lanes4(&self.b),
            c: lanes4(&self.c),
        };
        Watertight::intersect(ray, pre, &tri, cull)
    }

    type Rel = RelTri4;
    const REL_EMPTY: RelTri4 = RelTri4::EMPTY;

    #[inline]
    fn relative(&self, eye: Vec3) -> RelTri4 {
        RelTri4 {
            a: minus(&self.a, eye),
            b: minus(&self.b, eye),
            c: minus(&self.c, eye),
        }
    }

    #[inline(always)]
    fn test_four_rel(
        &self,
        rel: &RelTri4,
        ray: &RayPacket<f32x4>,
        pre: &Shear<f32x4>,
        cull: Cull,
    ) -> LaneHit<f32x4> {
        let tri = TrianglePacket {
            a: lanes4(&rel.a),
            b: lanes4(&rel.b),
            c: lanes4(&rel.c),
        };
        Watertight::intersect_relative(ray, pre, &tri, cull)
    }

    #[inline(always)]
    fn test_one_rel<L: Lane>(
        &self,
        rel: &RelTri4,
        k: usize,
        rays: &RayPacket<L>,
        pre: &Shear<L>,
        cull: Cull,
    ) -> LaneHit<L> {
        let tri = TrianglePacket {
            a: V3::splat(get(&rel.a, k)),
            b: V3::splat(get(&rel.b, k)),
            c: V3::splat(get(&rel.c, k)),
        };
        Watertight::intersect_relative(rays, pre, &tri, cull)
    }
}

impl Packed for Sphere4 {
    const EMPTY: Self = Sphere4 {
        center: [[f32::NAN; LEAF_WIDTH]; 3],
        radius: [f32::NAN; LEAF_WIDTH],
        index: [EMPTY; LEAF_WIDTH],
    };

    #[inline(always)]
    fn indices(&self) -> &[u32; LEAF_WIDTH] {
        &self.index
    }

    fn bounds(&self, k: usize) -> ([f32; 3], [f32; 3]) {
        sphere_box(&Sphere::new(get(&self.center, k), self.radius[k]))
    }
}

impl Leaf for Sphere4 {
    type Prim = Sphere;

    fn prim(&self, k: usize) -> Sphere {
        Sphere::new(get(&self.center, k), self.radius[k])
    }

    #[inline]
    fn records<L: Lane>(
        rays: &RayPacket<L>,
        best: &Best<L>,
        _cull: Cull,
        prim: impl Fn(u32) -> Option<Sphere>,
    ) -> Hits<L> {
        Hits::from_spheres(rays, best, prim)
    }

    fn all<L: Lane>(
        prim: &Sphere,
        index: u32,
        rays: &RayPacket<L>,
        cull: Cull,
        f: &mut dyn FnMut(&Hits<L>),
    ) {
        Using::<[Sphere], Robust>::new(core::slice::from_ref(prim))
            .culled(cull)
            .all_packet(rays, &mut |h: &Hits<L>| f(&reindex(h, index)));
    }

    type Rays<L: Lane> = ();

    #[inline(always)]
    fn prepare<L: Lane>(_rays: &RayPacket<L>) {}

    #[inline(always)]
    fn test_one<L: Lane>(&self, k: usize, rays: &RayPacket<L>, _: &(), cull: Cull) -> LaneHit<L> {
        let s = SpherePacket {
            center: V3::splat(get(&self.center, k)),
            radius: L::from_f32(self.radius[k]),
        };
        sphere_hit(&Robust::roots(rays, &s), cull)
    }

    #[inline(always)]
    fn test_four(&self, ray: &RayPacket<f32x4>, _: &(), cull: Cull) -> LaneHit<f32x4> {
        let s = SpherePacket {
            center: lanes4(&self.center),
            radius: f32x4::new(self.radius),
        };
        sphere_hit(&Robust::roots(ray, &s), cull)
    }

    type Rel = ();
    const REL_EMPTY: () = ();

    #[inline(always)]
    fn relative(&self, _eye: Vec3) {}
}

/// `h` with primitive index `index` in every lane that hit (the one-element set's records
/// carry 0).
fn reindex<L: Lane>(h: &Hits<L>, index: u32) -> Hits<L> {
    let mut h = *h;
    let mut bits = h.mask.bits();
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        if let Some(x) = h.index.as_mut().get_mut(i) {
            *x = index;
        }
    }
    h
}

/// `c ± r` (the empty box for an invalid sphere: NaN radius).
fn sphere_box(s: &Sphere) -> ([f32; 3], [f32; 3]) {
    let (c, r) = (s.center(), s.radius());
    points_box(&[c - Vec3::splat(r), c + Vec3::splat(r)])
}

impl Primitives for [Triangle] {
    type Leaf = Tri4;
    fn count(&self) -> usize {
        self.len()
    }
    fn bounds(&self, i: u32) -> ([f32; 3], [f32; 3]) {
        let t = self.get(i as usize).copied().unwrap_or(Triangle::never());
        points_box(&[t.a(), t.b(), t.c()])
    }
    fn put(&self, i: u32, leaf: &mut Tri4, k: usize) {
        let t = self.get(i as usize).copied().unwrap_or(Triangle::never());
        leaf.set_triangle(k, &t, i);
    }
}

impl Primitives for Mesh<'_> {
    type Leaf = Tri4;
    fn count(&self) -> usize {
        self.len()
    }
    /// The box of the vertices' finite coordinates (cheaper than validating the triangle:
    /// one that is never hit may get a box, and is still never hit).
    fn bounds(&self, i: u32) -> ([f32; 3], [f32; 3]) {
        let Some(idx) = self.indices().get(i as usize) else {
            return points_box(&[]);
        };
        let p = idx.map(|k| {
            let v = self
                .positions()
                .get(k as usize)
                .copied()
                .unwrap_or(Vec3::NAN);
            Vec3::select(v.is_finite_mask(), v, Vec3::NAN)
        });
        points_box(&p)
    }
    fn put(&self, i: u32, leaf: &mut Tri4, k: usize) {
        let t = self.triangle(i as usize).unwrap_or(Triangle::never());
        leaf.set_triangle(k, &t, i);
    }
}

impl Primitives for [Sphere] {
    type Leaf = Sphere4;
    fn count(&self) -> usize {
        self.len()
    }
    fn bounds(&self, i: u32) -> ([f32; 3], [f32; 3]) {
        match self.get(i as usize) {
            Some(s) => sphere_box(s),
            None => points_box(&[]),
        }
    }
    fn put(&self, i: u32, leaf: &mut Sphere4, k: usize) {
        let s = self
            .get(i as usize)
            .copied()
            .unwrap_or(Sphere::new(Vec3::ZERO, f32::NAN));
        set(&mut leaf.center, k, s.center());
        leaf.radius[k] = s.radius();
        leaf.index[k] = i;
    }
}
