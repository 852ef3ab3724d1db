//! Instances: objects (a BVH over a mesh or a sphere set) placed by affine transforms under a
//! top-level BVH; one query returns the closest hit over the scene with the instance id in
//! [`Hit::set`].
//!
//! **Ray transform.** Each instance stores the world→object map `M`, `c` (the inverse of the
//! object→world transform it was given, computed in `f64` and rounded once). A world ray
//! `o + t·d` becomes `M·o + c`, `M·d` with each coordinate evaluated as
//! `((m0·x + m1·y) + m2·z) + c` (9 mul, 9 add for the origin, 9 mul, 6 add for the direction,
//! no fused operation): the same bits on every target. `t` is unchanged by an affine map, so
//! hits of different instances compare directly.
//!
//! **Answer.** The smallest `t` over every instance's object query (the object's own answer:
//! the brute-force closest hit with its kernel, ties to the lower primitive index), ties to the
//! lower instance; the same whatever order the top level visits instances in. The record's
//! point is `o + t·d` on the world ray, the normal `Mᵀ·n/|Mᵀ·n|` (facing the world ray's
//! origin, as `n` faces the object ray's), `front` as the object decided it, inverted when the
//! transform mirrors (`det < 0`), `u`, `v` and `index` the object's.
//!
//! **Top level.** An instance's world box is the object's root box through the object→world
//! transform, widened by `2^-10` of its largest coordinate. An instance whose transform is not
//! invertible to within `|A·M − I| ≤ 2^-16` (or not finite) gets an infinite box: it is
//! tested by every ray (still exact, only slower).

use glam::Vec3;

use super::leaf::points_box;
use super::traverse::{Slab, Stack};
use super::{
    BuildError, Bvh, EMPTY, LEAF, LEAF_WIDTH, Leaf, Node, Packed, Primitives, STACK, Scratch,
    WIDTH, build, max, min,
};
use crate::hit::relax;
use crate::lane::{Lane, Mask};
use crate::query::{Hit, Hits, Query};
use crate::ray::{Ray, RayPacket};
use crate::vec3::V3;

/// An object placed in the world: the object's index and its object→world affine transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index of the object (in the scene's object slice).
    pub object: u32,
    /// Object→world: rows `[a0, a1, a2, b]`, `world = A·p + b`.
    pub to_world: [[f32; 4]; 3],
    /// World→object (the rounded inverse): rows `[m0, m1, m2, c]`.
    pub to_object: [[f32; 4]; 3],
    /// The transform mirrors (`det A < 0`): front faces swap.
    pub mirror: bool,
    /// `M` inverts `A` to within `2^-16` and everything is finite.
    pub invertible: bool,
}

impl Instance {
    /// Object `object` placed by `to_world` (rows: `world_k = a_k·p + b_k`).
    #[must_use]
    pub fn new(object: u32, to_world: [[f32; 4]; 3]) -> Self {
        let a = |r: usize, c: usize| to_world[r][c] as f64;
        // Cofactors and determinant in f64 (fixed order), rounded once.
        let cof = |r: usize, c: usize| {
            let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
            let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
            a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1)
        };
        let det = a(0, 0) * cof(0, 0) + a(0, 1) * cof(0, 1) + a(0, 2) * cof(0, 2);
        let mut m = [[0.0f64; 4]; 3];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().take(3).enumerate() {
                *x = cof(c, r) / det;
            }
        }
        for row in &mut m {
            row[3] = -((row[0] * a(0, 3) + row[1] * a(1, 3)) + row[2] * a(2, 3));
        }
        let to_object = m.map(|row| row.map(|x| x as f32));
        // Residual of the rounded inverse: A·M − I.
        let mut ok = det.is_finite() && det != 0.0;
        let mo = |r: usize, c: usize| f64::from(to_object[r][c]);
        for r in 0..3 {
            for c in 0..3 {
                let s = (a(r, 0) * mo(0, c) + a(r, 1) * mo(1, c)) + a(r, 2) * mo(2, c);
                let e = s - if r == c { 1.0 } else { 0.0 };
                ok &= e.abs() <= 1.0 / 65536.0;
            }
        }
        ok &= to_object.iter().flatten().all(|x| x.is_finite());
        ok &= to_world.iter().flatten().all(|x| x.is_finite());
        Instance {
            object,
            to_world,
            to_object,
            mirror: det < 0.0,
            invertible: ok,
        }
    }

    /// The world ray in object space (see the [module docs](self)).
    #[must_use]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        let m = &self.to_object;
        let (o, d) = (ray.origin(), ray.dir());
        let p = |r: usize| ((m[r][0] * o.x + m[r][1] * o.y) + m[r][2] * o.z) + m[r][3];
        let v = |r: usize| (m[r][0] * d.x + m[r][1] * d.y) + m[r][2] * d.z;
        Ray::with_interval(
            Vec3::new(p(0), p(1), p(2)),
            Vec3::new(v(0), v(1), v(2)),
            ray.t_min(),
            ray.t_max(),
        )
    }

    /// The world box of an object box (empty in, empty out; infinite when not invertible).
    fn world_box(&self, lo: [f32; 3], hi: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        if !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]) {
            return ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        }
        if !self.invertible {
            return ([f32::NEG_INFINITY; 3], [f32::INFINITY; 3]);
        }
        let a = &self.to_world;
        let mut corners = [Vec3::ZERO; 8];
        for (i, c) in corners.iter_mut().enumerate() {
            let p = [0, 1, 2].map(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] });
            let w = |r: usize| ((a[r][0] * p[0] + a[r][1] * p[1]) + a[r][2] * p[2]) + a[r][3];
            *c = Vec3::new(w(0), w(1), w(2));
        }
        let (mut lo, mut hi) = points_box(&corners);
        let mut big = 0.0f32;
        for k in 0..3 {
            big = max(big, max(lo[k].abs(), hi[k].abs()));
        }
        let m = big * (1.0 / 1024.0);
        for k in 0..3 {
            lo[k] -= m;
            hi[k] += m;
        }
        (lo, hi)
    }
}

/// Four instances of a top-level leaf: their indices and world boxes.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inst4 {
    /// World boxes: min x, y, z, then max x, y, z; lane `k` is instance `k`.
    pub bounds: [[f32; LEAF_WIDTH]; 6],
    /// Instance indices ([`EMPTY`] for unused lanes).
    pub index: [u32; LEAF_WIDTH],
}

impl Packed for Inst4 {
    const EMPTY: Self = Inst4 {
        bounds: [
            [f32::INFINITY; LEAF_WIDTH],
            [f32::INFINITY; LEAF_WIDTH],
            [f32::INFINITY; LEAF_WIDTH],
            [f32::NEG_INFINITY; LEAF_WIDTH],
            [f32::NEG_INFINITY; LEAF_WIDTH],
            [f32::NEG_INFINITY; LEAF_WIDTH],
        ],
        index: [EMPTY; LEAF_WIDTH],
    };

    fn indices(&self) -> &[u32; LEAF_WIDTH] {
        &self.index
    }

    fn bounds(&self, k: usize) -> ([f32; 3], [f32; 3]) {
        let b = &self.bounds;
        ([b[0][k], b[1][k], b[2][k]], [b[3][k], b[4][k], b[5][k]])
    }
}

/// The box of a tree's root (the union of its children's boxes).
fn root_box<P: Packed>(t: &Bvh<P>) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    if let Some(n) = t.nodes.first() {
        for k in 0..WIDTH {
            if n.child[k] == EMPTY {
                continue;
            }
            for a in 0..3 {
                lo[a] = min(lo[a], n.bounds[a][k]);
                hi[a] = max(hi[a], n.bounds[3 + a][k]);
            }
        }
    }
    (lo, hi)
}

/// Instances over objects, as primitives for the top-level build.
struct Placed<'a, 's, P: Packed> {
    objects: &'a [Bvh<'s, P>],
    instances: &'a [Instance],
}

impl<P: Packed> Primitives for Placed<'_, '_, P> {
    type Leaf = Inst4;
    fn count(&self) -> usize {
        self.instances.len()
    }
    fn bounds(&self, i: u32) -> ([f32; 3], [f32; 3]) {
        let Some(inst) = self.instances.get(i as usize) else {
            return ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        };
        match self.objects.get(inst.object as usize) {
            Some(o) => {
                let (lo, hi) = root_box(o);
                inst.world_box(lo, hi)
            }
            None => ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        }
    }
    fn put(&self, i: u32, leaf: &mut Inst4, k: usize) {
        let (lo, hi) = self.bounds(i);
        for a in 0..3 {
            leaf.bounds[a][k] = lo[a];
            leaf.bounds[3 + a][k] = hi[a];
        }
        leaf.index[k] = i;
    }
}

/// A scene: instances of objects under a top-level BVH (see the [module docs](self)).
#[derive(Clone, Copy, Debug)]
pub struct Scene<'s, P: Leaf> {
    top: Bvh<'s, Inst4>,
    objects: &'s [Bvh<'s, P>],
    instances: &'s [Instance],
}

impl<'s, P: Leaf> Scene<'s, P> {
    /// Builds the top level over `instances` of `objects` into caller storage (sizes from
    /// [`needed`](super::needed)`(instances.len())`, leaves of [`Inst4`]). An instance of a
    /// missing object is never hit.
    ///
    /// # Errors
    ///
    /// As [`build`].
    pub fn build(
        objects: &'s [Bvh<'s, P>],
        instances: &'s [Instance],
        nodes: &'s mut [Node],
        leaves: &'s mut [Inst4],
        scratch: &mut [Scratch],
    ) -> Result<Self, BuildError> {
        let top = build(&Placed { objects, instances }, nodes, leaves, scratch)?;
        Ok(Scene {
            top,
            objects,
            instances,
        })
    }

    /// The top-level tree.
    #[must_use]
    pub fn top(&self) -> &Bvh<'s, Inst4> {
        &self.top
    }

    /// The closest hit of one world ray (see the [module docs](self)).
    fn closest_one(&self, ray: &Ray) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        let slab = Slab::new(ray.origin(), ray.dir(), self.top.reach);
        let t_end = ray.t_max();
        let mut t_max = relax(t_end);
        let mut best: Option<Hit> = None;
        let mut stack = Stack::<STACK>::new();
        while let Some((c, tn)) = stack.pop() {
            if tn > t_max {
                continue;
            }
            if c & LEAF == 0 {
                if let Some(n) = self.top.nodes.get(c as usize) {
                    let (bits, tn) = slab.test(n, ray.t_min(), t_max);
                    stack.push_sorted(n, bits, &tn.to_array());
                }
                continue;
            }
            let Some(leaf) = self.top.leaves.get((c & !LEAF) as usize) else {
                continue;
            };
            for &i in leaf.indices() {
                let Some(h) = self.instance_hit(i, &ray.with_t_max(t_max)) else {
                    continue;
                };
                let closer = match &best {
                    None => true,
                    Some(b) => h.t < b.t || (h.t == b.t && h.set < b.set),
                };
                if h.t < t_end && closer {
                    t_max = relax(h.t);
                    best = Some(h);
                }
            }
        }
        best
    }

    /// Instance `i`'s closest hit of the world ray, as a world record.
    fn instance_hit(&self, i: u32, ray: &Ray) -> Option<Hit> {
        let inst = self.instances.get(i as usize)?;
        let object = self.objects.get(inst.object as usize)?;
        let local = inst.ray_to_object(ray);
        let h = object.closest(&local)?;
        Some(self.world_record(inst, i, ray, h))
    }

    /// An object record in world space: point on the world ray, normal `Mᵀ·n` normalised.
    fn world_record(&self, inst: &Instance, i: u32, ray: &Ray, h: Hit) -> Hit {
        let m = &inst.to_object;
        let n = h.normal;
        let w = |c: usize| (m[0][c] * n.x + m[1][c] * n.y) + m[2][c] * n.z;
        let v = V3::<f32>::from(Vec3::new(w(0), w(1), w(2)));
        let len = v.length_squared().sqrt();
        let normal = if len > 0.0 && len.is_finite() {
            v.div_by(len).into()
        } else {
            Vec3::ZERO
        };
        Hit {
            point: ray.at(h.t),
            normal,
            front: h.front != inst.mirror,
            set: i,
            ..h
        }
    }
}

/// A scene answers like its instances queried one by one (see the [module docs](self)).
/// Packets are answered lane by lane through the one-ray path (every lane equals it); `any`
/// stops at the first hit; `all` reports, per lane, every instance's hits in top-level
/// traversal order.
impl<P: Leaf> Query for Scene<'_, P> {
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        let mut out = Hits::<L>::miss();
        for j in 0..L::LANES {
            if let Some(h) = lane_ray(rays, j).and_then(|r| self.closest_one(&r)) {
                put_lane_generic(&mut out, j, &h);
            }
        }
        out
    }

    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        let mut m = L::Mask::splat(false);
        for j in 0..L::LANES {
            if lane_ray(rays, j).is_some_and(|r| self.any_ray(&r)) {
                m = m.with_lane(j, true);
            }
        }
        m
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        for j in 0..L::LANES {
            let Some(r) = lane_ray(rays, j) else { continue };
            self.each_instance(&r, &mut |inst, i, local| {
                object_all(self, inst, i, &r, local, &mut |h: &Hit| {
                    let mut out = Hits::<L>::miss();
                    put_lane_generic(&mut out, j, h);
                    f(&out);
                });
            });
        }
    }

    fn closest_ray(&self, ray: &Ray) -> Option<Hit> {
        self.closest_one(ray)
    }

    fn any_ray(&self, ray: &Ray) -> bool {
        let mut hit = false;
        self.each_instance(ray, &mut |inst, _, local| {
            if !hit {
                hit = self
                    .objects
                    .get(inst.object as usize)
                    .is_some_and(|o| o.any(local));
            }
        });
        hit
    }
}

impl<P: Leaf> Scene<'_, P> {
    /// Calls `f(instance, index, object ray)` for every instance whose top-level box the ray
    /// enters (interval not shrunk).
    fn each_instance(&self, ray: &Ray, f: &mut dyn FnMut(&Instance, u32, &Ray)) {
        if !ray.is_valid() {
            return;
        }
        let slab = Slab::new(ray.origin(), ray.dir(), self.top.reach);
        let mut stack = Stack::<STACK>::new();
        while let Some((c, _)) = stack.pop() {
            if c & LEAF == 0 {
                if let Some(n) = self.top.nodes.get(c as usize) {
                    let (bits, tn) = slab.test(n, ray.t_min(), ray.t_max());
                    stack.push_sorted(n, bits, &tn.to_array());
                }
                continue;
            }
            let Some(leaf) = self.top.leaves.get((c & !LEAF) as usize) else {
                continue;
            };
            for &i in leaf.indices() {
                if let Some(inst) = self.instances.get(i as usize) {
                    f(inst, i, &inst.ray_to_object(ray));
                }
            }
        }
    }
}

/// Every hit of one instance's object, as world records.
fn object_all<P: Leaf>(
    scene: &Scene<P>,
    inst: &Instance,
    i: u32,
    ray: &Ray,
    local: &Ray,
    f: &mut dyn FnMut(&Hit),
) {
    if let Some(o) = scene.objects.get(inst.object as usize) {
        o.all(local, |h| f(&scene.world_record(inst, i, ray, h)));
    }
}

/// Lane `j` of a packet as a scalar ray (`None` for an empty interval).
fn lane_ray<L: Lane>(rays: &RayPacket<L>, j: usize) -> Option<Ray> {
    use crate::lane::Scalar;
    let f = |x: L| x.lane(j).to_f64() as f32;
    let v = |v: V3<L>| Vec3::new(f(v.x), f(v.y), f(v.z));
    let r = Ray::with_interval(v(rays.origin), v(rays.dir), f(rays.t_min), f(rays.t_max));
    r.is_valid().then_some(r)
}

/// Writes one ray's record into lane `j` of a packet record.
fn put_lane_generic<L: Lane>(out: &mut Hits<L>, j: usize, h: &Hit) {
    use crate::lane::Scalar;
    let s = |x: f32| L::Scalar::from_f32(x);
    out.t = out.t.with_lane(j, s(h.t));
    out.point = V3::new(
        out.point.x.with_lane(j, s(h.point.x)),
        out.point.y.with_lane(j, s(h.point.y)),
        out.point.z.with_lane(j, s(h.point.z)),
    );
    out.normal = V3::new(
        out.normal.x.with_lane(j, s(h.normal.x)),
        out.normal.y.with_lane(j, s(h.normal.y)),
        out.normal.z.with_lane(j, s(h.normal.z)),
    );
    out.front = out.front.with_lane(j, h.front);
    out.u = out.u.with_lane(j, s(h.u));
    out.v = out.v.with_lane(j, s(h.v));
    out.mask = out.mask.with_lane(j, true);
    if let Some(x) = out.index.as_mut().get_mut(j) {
        *x = h.index;
    }
    if let Some(x) = out.set.as_mut().get_mut(j) {
        *x = h.set;
    }
}
