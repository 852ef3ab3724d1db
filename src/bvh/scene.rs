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
use wide::f32x4;

use super::node::Slab;
use super::{
    BuildError, Bvh, EMPTY, LEAF_WIDTH, Layout, Leaf, Node, Packed, Primitives, Scratch, Sizes,
    max, min, sizes, traverse,
};
use crate::hit::{Collector, Hit, Hits, Winners};
use crate::kernel::{Cull, Kernel};
use crate::lane::{Lane, Mask, Scalar};
use crate::ray::{Ray, RayPacket};
use crate::set::{Set, owned};
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
        // (Loops, not `map`: a closure may be left out of line.)
        let mut to_object = [[0.0f32; 4]; 3];
        for (out, row) in to_object.iter_mut().zip(&m) {
            for (y, &x) in out.iter_mut().zip(row) {
                *y = x as f32;
            }
        }
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
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        object_ray(&self.to_object, ray)
    }

    /// The world rays of a packet in object space, lane by lane as
    /// [`ray_to_object`](Self::ray_to_object) (the same operations, so the same bits), over
    /// the same intervals.
    #[must_use]
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    pub fn packet_to_object<L: Lane>(&self, rays: &RayPacket<L>) -> RayPacket<L> {
        object_packet(&self.to_object, rays)
    }

    /// An object record in world space: point on the world ray, normal `Mᵀ·n` normalised.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    pub(crate) fn world_record(&self, i: u32, ray: &Ray, h: Hit) -> Hit {
        world_record(&self.to_object, self.mirror, i, ray, h)
    }

    /// The world box of an object box (empty in, empty out; infinite when not invertible).
    pub(crate) fn world_box(&self, lo: [f32; 3], hi: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        if !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]) {
            return ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        }
        if !self.invertible {
            return ([f32::NEG_INFINITY; 3], [f32::INFINITY; 3]);
        }
        // The 8 corners `p` (coordinate k from `hi` where bit k of the corner's number is set),
        // each world coordinate `((a0·p0 + a1·p1) + a2·p2) + b` (a product per row and end
        // made once), taken into the box in the corners' order (which decides between ±0).
        let a = &self.to_world;
        let (mut out_lo, mut out_hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for r in 0..3 {
            let ends = |k: usize| [a[r][k] * lo[k], a[r][k] * hi[k]];
            let (x, y, z) = (ends(0), ends(1), ends(2));
            for i in 0..8 {
                let w = ((x[i & 1] + y[i >> 1 & 1]) + z[i >> 2 & 1]) + a[r][3];
                out_lo[r] = min(out_lo[r], w);
                out_hi[r] = max(out_hi[r], w);
            }
        }
        let (mut lo, mut hi) = (out_lo, out_hi);
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

/// [`Instance::ray_to_object`] with the world→object map `m`.
#[inline]
pub(crate) fn object_ray(m: &[[f32; 4]; 3], ray: &Ray) -> Ray {
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

/// [`Instance::packet_to_object`] with the world→object map `m`.
#[inline]
pub(crate) fn object_packet<L: Lane>(m: &[[f32; 4]; 3], rays: &RayPacket<L>) -> RayPacket<L> {
    let (o, d) = (rays.origin, rays.dir);
    let c = |x: f32| L::from_f32(x);
    let p = |r: usize| ((c(m[r][0]) * o.x + c(m[r][1]) * o.y) + c(m[r][2]) * o.z) + c(m[r][3]);
    let v = |r: usize| (c(m[r][0]) * d.x + c(m[r][1]) * d.y) + c(m[r][2]) * d.z;
    RayPacket::new(
        V3::new(p(0), p(1), p(2)),
        V3::new(v(0), v(1), v(2)),
        rays.t_min,
        rays.t_max,
    )
}

/// An object record `h` of instance `i` (world→object map `m`, mirroring when `mirror`) in
/// world space: point on the world ray, normal `Mᵀ·n` normalised, the face flipped when the
/// transform mirrors.
#[cfg_attr(target_arch = "x86_64", inline(always))]
pub(crate) fn world_record(m: &[[f32; 4]; 3], mirror: bool, i: u32, ray: &Ray, h: Hit) -> Hit {
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
        front: h.front != mirror,
        set: i,
        ..h
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

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    fn indices(&self) -> &[u32; LEAF_WIDTH] {
        &self.index
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    fn bounds(&self, k: usize) -> ([f32; 3], [f32; 3]) {
        let b = &self.bounds;
        ([b[0][k], b[1][k], b[2][k]], [b[3][k], b[4][k], b[5][k]])
    }
}

/// Instances over objects, as primitives for the top-level build.
struct Placed<'a, 's, P: Packed, N: Layout> {
    objects: &'a [Bvh<'s, P, N>],
    instances: &'a [Instance],
}

impl<P: Packed, N: Layout> Primitives for Placed<'_, '_, P, N> {
    type Leaf = Inst4;
    fn count(&self) -> usize {
        self.instances.len()
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    fn bounds(&self, i: u32) -> ([f32; 3], [f32; 3]) {
        let Some(inst) = self.instances.get(i as usize) else {
            return ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        };
        match self.objects.get(inst.object as usize) {
            Some(o) => {
                let (lo, hi) = o.root_box();
                inst.world_box(lo, hi)
            }
            None => ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        }
    }
    fn put(&self, i: u32, leaf: &mut Inst4, k: usize) {
        leaf.put(k, i, self.bounds(i));
    }
}

impl Inst4 {
    /// Lane `k` set to instance `i` with the world box `(lo, hi)`.
    pub(crate) fn put(&mut self, k: usize, i: u32, (lo, hi): ([f32; 3], [f32; 3])) {
        for a in 0..3 {
            self.bounds[a][k] = lo[a];
            self.bounds[3 + a][k] = hi[a];
        }
        self.index[k] = i;
    }
}

/// A scene: instances of objects under a top-level BVH (see the [module docs](self)).
#[derive(Clone, Copy, Debug)]
pub struct Scene<'s, P: Leaf, N: Layout = Node> {
    top: Bvh<'s, Inst4>,
    objects: &'s [Bvh<'s, P, N>],
    instances: &'s [Instance],
}

impl<'s, P: Leaf, N: Layout> Scene<'s, P, N> {
    /// The storage the top level over `n` instances needs (leaves of [`Inst4`]).
    #[must_use]
    pub const fn needed(n: usize) -> Sizes {
        sizes(n)
    }

    /// Builds the top level over `instances` of `objects` into caller storage (sizes from
    /// [`needed`](Self::needed)). An instance of a missing object is never hit.
    ///
    /// # Errors
    ///
    /// As [`Bvh::build`].
    pub fn build(
        objects: &'s [Bvh<'s, P, N>],
        instances: &'s [Instance],
        nodes: &'s mut [Node],
        leaves: &'s mut [Inst4],
        scratch: &mut [Scratch],
    ) -> Result<Self, BuildError> {
        let top = Bvh::build(&Placed { objects, instances }, nodes, leaves, scratch)?;
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

    /// Instance `i` and its object.
    #[inline(always)]
    fn placed(&self, i: u32) -> Option<(&Instance, &Bvh<'s, P, N>)> {
        let inst = self.instances.get(i as usize)?;
        Some((inst, self.objects.get(inst.object as usize)?))
    }
}

/// A scene answers like its instances queried one by one with the same kernel and culling:
/// the smallest `t`, ties to the lower instance, then the lower primitive. The top level is a
/// BVH whose leaves are instances, traversed by the one traversal: a leaf moves the rays into
/// the object's space and traverses the object, offering its hits to the same collector (so
/// `any` stops at the first occluder). `set` in the records is the instance.
impl<P: Leaf, N: Layout> Set for Scene<'_, P, N> {
    type Prim = P::Prim;
    type Kernel = P::Kernel;
    const LEVEL_LANES: bool = false;

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn sets(&self) -> u32 {
        self.instances.len() as u32
    }

    fn trace_with<K: Kernel<P::Prim>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        instances(
            &self.top,
            rays,
            c,
            |i, r, c| {
                let Some((inst, object)) = self.placed(i) else {
                    return false;
                };
                let local = inst.packet_to_object(r);
                object.trace_with::<K, L, C>(cull, &local, set + i, c)
            },
            0,
            |_, _, _| false,
        )
    }

    // The top level inlined into the query's SIMD level (crate::simd), as in `OwnedScene`.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    fn trace_ray_with<K: Kernel<P::Prim>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        if C::EVERY {
            return self.trace_with::<K, f32, C>(cull, &RayPacket::splat(ray), set, c);
        }
        instances_one(&self.top, ray, 0, c, |i, c| {
            let Some((inst, object)) = self.placed(i) else {
                return false;
            };
            let local = inst.ray_to_object(ray);
            object.trace_ray_with::<K, C>(cull, &local, set + i, c)
        })
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    fn records_with<L: Lane>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        w: &Winners<L>,
    ) -> Hits<L> {
        instance_records(rays, set, self.sets(), w, |i, ray, one| {
            let (inst, object) = self.placed(i)?;
            let local = inst.ray_to_object(ray);
            let h = object
                .records_with(cull, &RayPacket::splat(&local), 0, one)
                .lane(0)?;
            Some(inst.world_record(set + i, ray, h))
        })
    }
}

/// The top level's traversal for a packet (the one packet traversal, leaves of instances):
/// `visit(i, rays, c)` for the instances `i` of every leaf the rays reach (unused lanes give
/// [`EMPTY`]), with the rays' intervals shrunk to the collector's, until it returns true. With
/// the packet's frustum ([`Cone`](traverse::Cone)), only the instances whose own world boxes
/// it may enter (a pure prune, as for a leaf's primitives). Subtrees that `split` or fewer
/// lanes reach go to `single(node, lane, c)` (as [`traverse::many`]; `split = 0`: never).
#[inline(always)]
pub(crate) fn instances<L: Lane, C: Collector<L>>(
    top: &Bvh<'_, Inst4>,
    rays: &RayPacket<L>,
    c: &mut C,
    mut visit: impl FnMut(u32, &RayPacket<L>, &mut C) -> bool,
    split: u32,
    single: impl FnMut(u32, usize, &mut C) -> bool,
) -> bool {
    traverse::many(
        top.nodes,
        top.reach,
        rays,
        c,
        |li, r, cone, c| {
            let Some(leaf) = top.leaves.get(li as usize) else {
                return false;
            };
            let keep = cone.map_or(u32::MAX, |f| f.enters(leaf.bounds.map(f32x4::new)));
            for (k, &i) in leaf.indices().iter().enumerate() {
                if keep & (1 << k) != 0 && visit(i, r, c) {
                    return true;
                }
            }
            false
        },
        split,
        single,
    )
}

/// [`instances`] for one ray from the node reference `start` (0: the root; the one-ray
/// traversal): `visit(i, c)` per instance reached whose own world box the ray's interval
/// meets (the nodes' slab test on the leaf's four boxes, made at the first leaf: a pure
/// prune), nearest entry first.
#[inline(always)]
pub(crate) fn instances_one<C: Collector<f32>>(
    top: &Bvh<'_, Inst4>,
    ray: &Ray,
    start: u32,
    c: &mut C,
    mut visit: impl FnMut(u32, &mut C) -> bool,
) -> bool {
    let mut slab = None;
    traverse::one(
        top.nodes,
        top.reach,
        ray,
        start,
        c,
        #[cfg_attr(target_arch = "x86_64", inline(always))]
        |li, c| {
            let Some(leaf) = top.leaves.get(li as usize) else {
                return false;
            };
            // Not `get_or_insert_with` nor `array::map`: calls the compiler may leave out of
            // line, which then run at the baseline inside a query entered at a wider level.
            if slab.is_none() {
                slab = Some(Slab::new(ray.origin(), ray.dir(), top.reach));
            }
            let Some(slab) = &slab else {
                return false;
            };
            let b = &leaf.bounds;
            let boxes = [
                f32x4::new(b[0]),
                f32x4::new(b[1]),
                f32x4::new(b[2]),
                f32x4::new(b[3]),
                f32x4::new(b[4]),
                f32x4::new(b[5]),
            ];
            let (mut bits, tn) = slab.test4(&boxes, &leaf.index, ray.t_min(), c.t_max());
            while bits != 0 {
                // The nearest entry first; an instance entered beyond a closest hit found since
                // the test is skipped.
                let mut k = bits.trailing_zeros() as usize;
                let mut rest = bits & (bits - 1);
                while rest != 0 {
                    let j = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    if tn[j] < tn[k] {
                        k = j;
                    }
                }
                bits &= !(1 << k);
                if C::SHRINKS && tn[k] > c.t_max() {
                    continue;
                }
                if visit(leaf.index[k], c) {
                    return true;
                }
            }
            false
        },
    )
}

/// The records of a scene's winners `w` (sets `set..set + n`: instance `set[j] − set`), lane
/// by lane: `record(i, ray, one)` makes lane `j`'s world record from instance `i`, the lane's
/// world ray and its winner alone (`set` 0).
#[cfg_attr(target_arch = "x86_64", inline(always))]
pub(crate) fn instance_records<L: Lane>(
    rays: &RayPacket<L>,
    set: u32,
    n: u32,
    w: &Winners<L>,
    record: impl Fn(u32, &Ray, &Winners<f32>) -> Option<Hit>,
) -> Hits<L> {
    let w = owned(w, set, n);
    let mut out = Hits::<L>::miss();
    let mut bits = w.mask.bits();
    while bits != 0 {
        let j = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let Some(ray) = lane_ray(rays, j) else {
            continue;
        };
        let get = |x: &L::Indices| x.as_ref().get(j).copied().unwrap_or(u32::MAX);
        let i = get(&w.set).wrapping_sub(set);
        let one = Winners::<f32> {
            t: lane(w.t, j),
            u: lane(w.u, j),
            v: lane(w.v, j),
            index: [get(&w.index)],
            set: [0],
            loc: [get(&w.loc)],
            mask: true,
        };
        if let Some(h) = record(i, &ray, &one) {
            out.set_lane(j, Some(&h));
        }
    }
    out
}

/// Lane `j` as an `f32`.
#[inline(always)]
fn lane<L: Lane>(x: L, j: usize) -> f32 {
    x.lane(j).to_f64() as f32
}

/// Lane `j` of a packet as a scalar ray (`None` for an empty interval).
#[cfg_attr(target_arch = "x86_64", inline(always))]
fn lane_ray<L: Lane>(rays: &RayPacket<L>, j: usize) -> Option<Ray> {
    let v = |v: V3<L>| Vec3::new(lane(v.x, j), lane(v.y, j), lane(v.z, j));
    let r = Ray::with_interval(
        v(rays.origin),
        v(rays.dir),
        lane(rays.t_min, j),
        lane(rays.t_max, j),
    );
    r.is_valid().then_some(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::leaf::points_box;

    /// The world box as first written: the 8 corners through the transform, then their box.
    fn corners_box(inst: &Instance, lo: [f32; 3], hi: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let a = &inst.to_world;
        let mut corners = [Vec3::ZERO; 8];
        for (i, c) in corners.iter_mut().enumerate() {
            let p = [0, 1, 2].map(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] });
            let w = |r: usize| ((a[r][0] * p[0] + a[r][1] * p[1]) + a[r][2] * p[2]) + a[r][3];
            *c = Vec3::new(w(0), w(1), w(2));
        }
        points_box(&corners)
    }

    /// `world_box` takes the corners' coordinates into the box in the corners' order, with
    /// the same operations: the same bits as the corners' box (signed zeros, NaN, infinities).
    #[test]
    fn world_box_is_the_corners_box() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            -2.5,
            3.0e-39,
            1.0e30,
            -1.0e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut seed = 1u64;
        let mut pick = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            values[(seed >> 33) as usize % values.len()]
        };
        for _ in 0..20_000 {
            let m = [0, 1, 2].map(|_| [pick(), pick(), pick(), pick()]);
            let lo = [pick(), pick(), pick()];
            let hi = [pick(), pick(), pick()];
            let mut inst = Instance::new(0, m);
            inst.invertible = true;
            let (wlo, whi) = inst.world_box(lo, hi);
            if !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]) {
                continue;
            }
            let (mut clo, mut chi) = corners_box(&inst, lo, hi);
            let mut big = 0.0f32;
            for k in 0..3 {
                big = max(big, max(clo[k].abs(), chi[k].abs()));
            }
            let e = big * (1.0 / 1024.0);
            for k in 0..3 {
                clo[k] -= e;
                chi[k] += e;
            }
            let bits = |b: [f32; 3]| b.map(f32::to_bits);
            assert_eq!(
                (bits(wlo), bits(whi)),
                (bits(clo), bits(chi)),
                "{m:?} {lo:?} {hi:?}"
            );
        }
    }
}
