//! Leaves (4 primitives in structure-of-arrays lanes) and the primitive sets a tree is built
//! over.

use glam::Vec3;
use wide::f32x4;

use super::{EMPTY, LEAF_WIDTH, max, min};
use crate::hit::Record;
use crate::kernel::{Kernel, Primitive, XYZ};
use crate::lane::Lane;
use crate::mesh::Mesh;
use crate::sphere::{Robust, Sphere, SpherePacket};
use crate::triangle::{Triangle, TrianglePacket, Watertight};
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

/// A leaf of primitives a kernel tests: up to [`LEAF_WIDTH`] of one kind in lanes (unused
/// lanes hold geometry that is never hit).
pub trait Leaf: Packed {
    /// The primitive type.
    type Prim: Record;
    /// The kernel of a plain query ([`Watertight`] for triangles, [`Robust`] for spheres).
    type Kernel: Kernel<Self::Prim>;
    /// The primitive in lane `k` (one that is never hit for an unused lane).
    fn prim(&self, k: usize) -> Self::Prim;
    /// Lane `k`'s primitive in every lane (N rays × 1 primitive).
    fn splat<L: Lane>(&self, k: usize) -> <Self::Prim as Primitive>::Packet<L>;
    /// The leaf's primitives in `f32x4` lanes (1 ray × 4 primitives), their coordinates in
    /// the axis order `order` (`XYZ`: x, y, z; what [`Kernel::order`] asks for).
    fn four(&self, order: [usize; 3]) -> <Self::Prim as Primitive>::Packet<f32x4>;
    /// The boxes of the lanes' primitives that can be hit, as [`Packed::bounds`] gives them
    /// (rows minimum x, y, z, maximum x, y, z; a primitive per lane), for a packet's cull.
    fn boxes(&self) -> [f32x4; 6];
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

/// The rows of `v` in lanes, in the axis order `order` (an axis beyond z reads as NaN).
#[inline(always)]
fn lanes4(v: &[[f32; LEAF_WIDTH]; 3], order: [usize; 3]) -> V3<f32x4> {
    // A function, not a closure: a closure may be left out of line (see crate::simd).
    #[inline(always)]
    fn row(v: &[[f32; LEAF_WIDTH]; 3], k: usize) -> f32x4 {
        f32x4::new(v.get(k).copied().unwrap_or([f32::NAN; LEAF_WIDTH]))
    }
    V3::new(row(v, order[0]), row(v, order[1]), row(v, order[2]))
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
    type Kernel = Watertight;

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn prim(&self, k: usize) -> Triangle {
        self.triangle(k)
    }

    #[inline(always)]
    fn splat<L: Lane>(&self, k: usize) -> TrianglePacket<L> {
        TrianglePacket {
            a: V3::splat(get(&self.a, k)),
            b: V3::splat(get(&self.b, k)),
            c: V3::splat(get(&self.c, k)),
        }
    }

    #[inline(always)]
    fn four(&self, order: [usize; 3]) -> TrianglePacket<f32x4> {
        TrianglePacket {
            a: lanes4(&self.a, order),
            b: lanes4(&self.b, order),
            c: lanes4(&self.c, order),
        }
    }

    #[inline(always)]
    fn boxes(&self) -> [f32x4; 6] {
        triangle_boxes(&self.four(XYZ))
    }
}

/// The boxes of four triangles in lanes, as [`Packed::bounds`] gives them for every triangle
/// that can be hit (no NaN vertex): rows minimum x, y, z, maximum x, y, z.
#[inline(always)]
pub(crate) fn triangle_boxes(p: &TrianglePacket<f32x4>) -> [f32x4; 6] {
    let lo = |a: f32x4, b: f32x4, c: f32x4| a.fast_min(b).fast_min(c);
    let hi = |a: f32x4, b: f32x4, c: f32x4| a.fast_max(b).fast_max(c);
    let (a, b, c) = (p.a, p.b, p.c);
    [
        lo(a.x, b.x, c.x),
        lo(a.y, b.y, c.y),
        lo(a.z, b.z, c.z),
        hi(a.x, b.x, c.x),
        hi(a.y, b.y, c.y),
        hi(a.z, b.z, c.z),
    ]
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
    type Kernel = Robust;

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn prim(&self, k: usize) -> Sphere {
        Sphere::new(get(&self.center, k), self.radius[k])
    }

    #[inline(always)]
    fn splat<L: Lane>(&self, k: usize) -> SpherePacket<L> {
        SpherePacket {
            center: V3::splat(get(&self.center, k)),
            radius: L::from_f32(self.radius[k]),
        }
    }

    #[inline(always)]
    fn four(&self, order: [usize; 3]) -> SpherePacket<f32x4> {
        SpherePacket {
            center: lanes4(&self.center, order),
            radius: f32x4::new(self.radius),
        }
    }

    #[inline(always)]
    fn boxes(&self) -> [f32x4; 6] {
        // As `bounds` for every valid sphere (finite radius).
        let (c, r) = (lanes4(&self.center, XYZ), f32x4::new(self.radius));
        [c.x - r, c.y - r, c.z - r, c.x + r, c.y + r, c.z + r]
    }
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
        // As the mesh checked it when made (`Triangle::new`'s bits, without its exact test
        // again: about 3 % of a build).
        let t = self.prepared(i as usize);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Lane `k` of [`Leaf::boxes`] is [`Packed::bounds`]`(k)`, bit for bit, for triangles and
    /// spheres that can be hit (tiny, huge, negative and axis-flat ones), so the packets'
    /// prune tests the boxes the builder used.
    #[test]
    fn lane_boxes_are_the_bounds() {
        let coords = [
            0.0, -0.0, 1.5, -3.25, 1e-30, -7e-20, 3e15, -2.5e20, 0.1, 0.7,
        ];
        let v = |i: usize| {
            let c = |j: usize| coords[(i * 7 + j * 3) % coords.len()];
            Vec3::new(c(0), c(1), c(2))
        };
        let mut checked = 0;
        for round in 0..12 {
            let mut tris = Tri4::EMPTY;
            let mut spheres = Sphere4::EMPTY;
            for k in 0..LEAF_WIDTH {
                let i = round * LEAF_WIDTH + k;
                let t = Triangle::new(v(i), v(i + 1), v(i + 5));
                tris.set_triangle(k, &t, i as u32);
                set(&mut spheres.center, k, v(i));
                spheres.radius[k] = [0.0, 0.25, 1e-20, 4e10][i % 4];
                spheres.index[k] = i as u32;
            }
            let bounds = |k: usize| (Packed::bounds(&tris, k), Packed::bounds(&spheres, k));
            for (which, boxes) in [tris.boxes(), spheres.boxes()].into_iter().enumerate() {
                for k in 0..LEAF_WIDTH {
                    let (t, s) = bounds(k);
                    let (lo, hi) = if which == 0 { t } else { s };
                    if !lo.iter().zip(&hi).all(|(a, b)| a <= b) {
                        continue; // never hit (a zero-area triangle): nothing to prune
                    }
                    checked += 1;
                    let lane = |r: usize| boxes[r].to_array()[k].to_bits();
                    for a in 0..3 {
                        assert_eq!(lane(a), lo[a].to_bits(), "round {round}, lane {k}");
                        assert_eq!(lane(3 + a), hi[a].to_bits(), "round {round}, lane {k}");
                    }
                }
            }
        }
        assert!(checked > 80, "{checked}");
    }
}
