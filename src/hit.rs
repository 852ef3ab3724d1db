//! Hits and collectors: what a query returns ([`Hit`], [`Hits`]), and the one place where
//! kernel answers become query answers ([`Collector`]: [`Closest`], [`Any`], [`All`]).
//!
//! Every set of the crate — flat slices, meshes, focal caches, BVHs and their instances —
//! runs its kernels and hands each answer to a collector, which alone decides what counts:
//!
//! * **The interval.** A hit counts when its rounded `t` lies in the ray's open interval
//!   `(t_min, t_max)`. Kernels are asked with `t_max` relaxed ([`relax`]), so that the
//!   test some of them make before dividing (`num < t_max·den`, rounded) can never drop such a
//!   hit, and the collector checks the rounded `t < t_max` itself. `closest`, `any` and `all`
//!   therefore agree for every `t_max`, finite or not.
//! * **The tie rule.** The closest hit is the smallest `(t, set, index, loc)`: the smallest
//!   rounded `t`, ties to the lower set (the position in a tuple, the instance of a scene),
//!   then the lower primitive index, then the lower `loc` (where the set keeps the primitive,
//!   [`At::loc`]: unique within a set). `loc` decides only between primitives that share an
//!   index, which a set can hold only where nothing checks its indices (a baked tree's ids, the
//!   leaves given to `Bvh::from_parts`); with unique indices the rule is `(t, set, index)`.
//!   It does not depend on the order the primitives are visited in, so brute force, a BVH
//!   and every packet width return the same hit, bit for bit.
//! * **Shrinking.** After a hit at `t`, kernels are asked with `t_max` relaxed from `t`
//!   (`t + (|t| + 2^-100)·2^-21`, strictly above `t` even at `t = 0`), so ties at `t` still
//!   reach the collector and everything farther is cut.
//! * **Stopping.** [`Any`] stops a traversal once every lane has hit; [`All`] reports every
//!   hit, in the order the set visits them.
//! * **Layers and filters.** A query may carry, per ray lane, a 32-bit layer mask and a set
//!   to ignore ([`Visibility`]), and a filter ([`Filter`]) that may reject any candidate
//!   ([`Candidate`]: its set, primitive, `t`, `u`, `v`, lane). They live here, in a collector
//!   wrapper ([`Screen`]) that every set traces into like any other collector: a set of
//!   instances asks it which lanes see an instance ([`Collector::sees`]), and every
//!   candidate passes the ignored set and the filter before the interval and tie rules see
//!   it. A rejected candidate is as if it did not exist, so the answers are brute force's
//!   with the same masks, ignored sets and filter, bit for bit. Queries without any of them
//!   never build a `Screen`: their code is the same as before.
//!
//! **Records.** The collectors keep only `t`, the barycentrics, the indices and where the
//! winner sits; the point `o + t·d` (3 mul, 3 add), the unit geometric normal and the face
//! are computed once per ray, for the winner ([`Record`]), with the same operations in every
//! lane: every lane of every width equals the scalar path bit for bit. The normal faces the
//! ray's origin (`d·normal ≤ 0`); [`Hit::front`] says whether that is the primitive's outer
//! side (spheres: hit from outside; triangles: `d·N < 0` with `N = (B − A) × (C − A)`, i.e.
//! A, B, C counter-clockwise as seen from the origin; planes: `d·n < 0`). **Misses** are one
//! word: `None` for a ray, a clear lane in [`Hits::mask`] (with `t = +inf`, zero vectors and
//! index `u32::MAX`) for a packet. No record holds a NaN or a `−0`.

use glam::Vec3;

use crate::kernel::{Cull, LaneHit, Primitive, plus_zero};
use crate::lane::{Lane, MAX_LANES, Mask, Scalar, pow2};
use crate::plane::Plane;
use crate::ray::RayPacket;
use crate::sphere::Sphere;
use crate::triangle::{Triangle, TrianglePacket};
use crate::vec3::V3;

/// One hit of one ray: what a game engine needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter: the point is `o + t·d`, `t` in units of `|d|`.
    pub t: f32,
    /// `o + t·d` (3 mul, 3 add, rounded as written).
    pub point: Vec3,
    /// Unit geometric normal, facing the ray's origin (`d·normal ≤ 0`).
    pub normal: Vec3,
    /// True when the ray hits the primitive's front (outer) side; see the
    /// [module docs](self).
    pub front: bool,
    /// Index of the primitive in its set.
    pub index: u32,
    /// Which set of a scene: the position in a tuple of sets or in [`Sets`](crate::set::Sets),
    /// the instance of a [`Scene`](crate::bvh::Scene); 0 for a plain set.
    pub set: u32,
    /// Barycentric weight of vertex B for triangles; 0 otherwise.
    pub u: f32,
    /// Barycentric weight of vertex C for triangles; 0 otherwise.
    pub v: f32,
}

/// The records of a packet query: [`Hit`]'s fields in lanes, and the lanes that hit.
#[derive(Clone, Copy, Debug)]
pub struct Hits<L: Lane> {
    /// Ray parameter; `+inf` where `mask` is clear.
    pub t: L,
    /// `o + t·d`; zero where `mask` is clear.
    pub point: V3<L>,
    /// Unit geometric normal facing the origin; zero where `mask` is clear.
    pub normal: V3<L>,
    /// Lanes that hit a front face.
    pub front: L::Mask,
    /// Primitive index in its set; `u32::MAX` where `mask` is clear.
    pub index: L::Indices,
    /// Set of a scene; `u32::MAX` where `mask` is clear.
    pub set: L::Indices,
    /// Barycentric weight of B (triangles), else 0.
    pub u: L,
    /// Barycentric weight of C (triangles), else 0.
    pub v: L,
    /// Lanes that hit.
    pub mask: L::Mask,
}

impl<L: Lane> Hits<L> {
    /// No lane hits.
    #[inline]
    #[must_use]
    pub fn miss() -> Self {
        let zero = L::from_f32(0.0);
        let z = V3::new(zero, zero, zero);
        Hits {
            t: L::from_f32(f32::INFINITY),
            point: z,
            normal: z,
            front: Mask::splat(false),
            index: L::indices(u32::MAX),
            set: L::indices(u32::MAX),
            u: zero,
            v: zero,
            mask: Mask::splat(false),
        }
    }

    /// Lane `i` as a record, or `None` when it missed.
    #[inline]
    #[must_use]
    pub fn lane(&self, i: usize) -> Option<Hit>
    where
        L: Lane<Scalar = f32>,
    {
        self.mask.test(i).then(|| Hit {
            t: self.t.lane(i),
            point: self.point.lane(i),
            normal: self.normal.lane(i),
            front: self.front.test(i),
            index: self.index.as_ref()[i],
            set: self.set.as_ref()[i],
            u: self.u.lane(i),
            v: self.v.lane(i),
        })
    }

    /// Writes one ray's record into lane `i` (a miss clears it).
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    pub(crate) fn set_lane(&mut self, i: usize, h: Option<&Hit>) {
        let s = |x: f32| L::Scalar::from_f32(x);
        let h = match h {
            Some(h) => *h,
            None => Hit {
                t: f32::INFINITY,
                point: Vec3::ZERO,
                normal: Vec3::ZERO,
                front: false,
                index: u32::MAX,
                set: u32::MAX,
                u: 0.0,
                v: 0.0,
            },
        };
        let put = |v: V3<L>, p: Vec3| {
            V3::new(
                v.x.with_lane(i, s(p.x)),
                v.y.with_lane(i, s(p.y)),
                v.z.with_lane(i, s(p.z)),
            )
        };
        let hit = h.t < f32::INFINITY;
        self.t = self.t.with_lane(i, s(h.t));
        self.point = put(self.point, h.point);
        self.normal = put(self.normal, h.normal);
        self.front = self.front.with_lane(i, h.front);
        self.u = self.u.with_lane(i, s(h.u));
        self.v = self.v.with_lane(i, s(h.v));
        self.mask = self.mask.with_lane(i, hit);
        if let Some(x) = self.index.as_mut().get_mut(i) {
            *x = h.index;
        }
        if let Some(x) = self.set.as_mut().get_mut(i) {
            *x = h.set;
        }
    }
}

/// Where a candidate comes from: the set (tuple position or instance), the primitive's index
/// in it, and where the set keeps the primitive (`loc`: the index for a flat set, the leaf
/// and lane in a BVH, the position in a baked tree), so that records can be made for the
/// winner alone. `loc` is unique within a set: the tie rule's last key (see the
/// [module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct At {
    /// The set.
    pub set: u32,
    /// The primitive's index in the set.
    pub index: u32,
    /// Where the set keeps it (unique within the set).
    pub loc: u32,
}

/// The closest hits of a packet once a traversal has finished: `t`, `u`, `v` (divided), where
/// each lane's winner comes from, and the lanes that hit.
#[derive(Clone, Copy, Debug)]
pub struct Winners<L: Lane> {
    /// Ray parameter; `+inf` where `mask` is clear.
    pub t: L,
    /// Barycentric weight of B for triangles; for spheres 1 on an exit root, else 0.
    pub u: L,
    /// Barycentric weight of C for triangles; 0 otherwise.
    pub v: L,
    /// The winners' indices (`u32::MAX` where `mask` is clear).
    pub index: L::Indices,
    /// Their sets.
    pub set: L::Indices,
    /// Where their sets keep them.
    pub loc: L::Indices,
    /// Lanes that hit.
    pub mask: L::Mask,
}

impl<L: Lane> Winners<L> {
    /// One candidate as a finished record (what [`All`] reports): `h` divided.
    #[inline(always)]
    #[must_use]
    pub fn single(h: &LaneHit<L>, at: At) -> Self {
        let h = h.normalized();
        let none = L::indices(u32::MAX);
        let (mut index, mut set, mut loc) = (none, none, none);
        L::select_indices(h.mask, at.index, &mut index);
        L::select_indices(h.mask, at.set, &mut set);
        L::select_indices(h.mask, at.loc, &mut loc);
        Winners {
            t: h.t,
            u: h.u,
            v: h.v,
            index,
            set,
            loc,
            mask: h.mask,
        }
    }

    /// Lane `i`'s `loc`, if it hit.
    #[inline(always)]
    #[must_use]
    pub fn loc(&self, i: usize) -> Option<u32> {
        if self.mask.test(i) {
            self.loc.as_ref().get(i).copied()
        } else {
            None
        }
    }
}

/// The relaxed upper end after a hit at `t`: `t + (|t| + 2^-100)·2^-21`, strictly above `t`
/// for every finite `t` (also `t = 0` and subnormal `t`, where `|t|·2^-21` alone would round
/// to nothing), and for `|t| ≥ 2^-76` exactly `t + |t|·2^-21`. A kernel's rounded
/// `num < t_max·den` then never rejects a hit whose rounded `t` is at most `t` (the product's
/// relative error, `2^-24`, is below the relaxation's `2^-21`; products that round below the
/// smallest normal skip that test, see [`crate::triangle`]).
#[inline(always)]
#[must_use]
pub fn relax<L: Lane>(t: L) -> L {
    const TINY: f32 = pow2(-100);
    const STEP: f32 = pow2(-21);
    t + (t.abs() + L::from_f32(TINY)) * L::from_f32(STEP)
}

/// Where a set's kernels send their answers (see the [module docs](self)): [`Closest`],
/// [`Any`] and [`All`]. A set asks each kernel with [`t_max`](Self::t_max) as the upper end
/// and passes every lane-wise answer to [`offer`](Self::offer).
pub trait Collector<L: Lane> {
    /// True when every hit is wanted (a sphere's exit roots too), not only the first per
    /// primitive; such a traversal cannot be restarted.
    const EVERY: bool = false;
    /// True when every hit of a primitive must be offered (a sphere's exit roots too), even by
    /// a traversal that may restart and prune ([`Screen`] with a filter: a rejected entry
    /// root must leave the exit root its chance). By default [`EVERY`](Self::EVERY).
    const EACH: bool = Self::EVERY;
    /// True when [`t_max`](Self::t_max) shrinks as hits are found (a traversal then prunes by
    /// it); false when it stays the relaxed upper end of the rays.
    const SHRINKS: bool = false;
    /// The lanes still looking for hits.
    fn active(&self) -> L::Mask;
    /// The upper end each lane's kernel test uses now (relaxed; see [`relax`]).
    fn t_max(&self) -> L;
    /// The lanes that see set `set` (an instance) on the layers `mask`: their query mask
    /// shares a bit with it and they do not ignore the set ([`Screen`], [`Visibility`]); a set
    /// of instances traces the other lanes past it. By default every lane: a query without
    /// masks sees everything, and the test folds away.
    #[inline(always)]
    fn sees(&self, set: u32, mask: u32) -> L::Mask {
        let _ = (set, mask);
        Mask::splat(true)
    }
    /// Takes the candidates of `h` (its `mask`'s lanes) of the primitive at `at`;
    /// `record` makes the records of one candidate (for collectors that report every hit).
    /// Returns true when the traversal may stop.
    fn offer(
        &mut self,
        h: &LaneHit<L>,
        at: At,
        record: impl FnOnce(&Winners<L>) -> Hits<L>,
    ) -> bool;
}

/// The closest hit per lane: the smallest `(t, set, index, loc)` with `t` inside the interval.
#[derive(Clone, Copy, Debug)]
pub struct Closest<L: Lane> {
    t: L,
    u: L,
    v: L,
    w: L,
    index: L::Indices,
    set: L::Indices,
    loc: L::Indices,
    mask: L::Mask,
    valid: L::Mask,
    /// The rays' own upper ends.
    t_end: L,
    /// The kernels' upper ends.
    t_max: L,
}

impl<L: Lane> Closest<L> {
    /// The collector for `rays` (nothing found yet).
    #[inline(always)]
    #[must_use]
    pub fn new(rays: &RayPacket<L>) -> Self {
        let m = LaneHit::<L>::miss();
        let valid = rays.valid();
        let none = L::indices(u32::MAX);
        Closest {
            t: m.t,
            u: m.u,
            v: m.v,
            w: m.w,
            index: none,
            set: none,
            loc: none,
            mask: m.mask,
            valid,
            t_end: rays.t_max,
            t_max: L::select(valid, relax(rays.t_max), rays.t_max),
        }
    }

    /// The winners, their barycentrics divided (once per ray), `−0` made `+0`.
    #[inline(always)]
    #[must_use]
    pub fn finish(&self) -> Winners<L> {
        Winners {
            t: plus_zero(self.t),
            u: plus_zero(self.u / self.w),
            v: plus_zero(self.v / self.w),
            index: self.index,
            set: self.set,
            loc: self.loc,
            mask: self.mask,
        }
    }
}

impl<L: Lane> Collector<L> for Closest<L> {
    const SHRINKS: bool = true;

    #[inline(always)]
    fn active(&self) -> L::Mask {
        self.valid
    }

    #[inline(always)]
    fn t_max(&self) -> L {
        self.t_max
    }

    #[inline(always)]
    fn offer(&mut self, h: &LaneHit<L>, at: At, _: impl FnOnce(&Winners<L>) -> Hits<L>) -> bool {
        if L::LANES == 1 {
            self.consider(h, at);
        } else {
            self.consider_lanes(*h, at);
        }
        false
    }
}

impl<L: Lane> Closest<L> {
    /// [`consider`](Self::consider) for packets: inline on x86-64 and AArch64, where a call
    /// per taken candidate costs more than the kernel (its vector registers saved and
    /// restored); out of line elsewhere (Cortex-M, RISC-V: their packets are arrays of
    /// scalars), one copy per lane type rather than one per kernel and set, for code size.
    #[cfg_attr(any(target_arch = "x86_64", target_arch = "aarch64"), inline(always))]
    #[cfg_attr(
        not(any(target_arch = "x86_64", target_arch = "aarch64")),
        inline(never)
    )]
    fn consider_lanes(&mut self, h: LaneHit<L>, at: At) {
        self.consider(&h, at);
    }

    /// The candidates of `h` from `at`: taken where they come first by `(t, set, index, loc)`.
    #[inline(always)]
    fn consider(&mut self, h: &LaneHit<L>, at: At) {
        // The interval (the kernel checked t_min), then the tie rule.
        let inside = h.mask & h.t.lt(self.t_end);
        let mut take = inside & h.t.lt(self.t);
        let tie = inside & h.t.le(self.t) & h.t.ge(self.t);
        if tie.any() {
            take = take | self.wins_tie(tie, at);
        }
        if take.any() {
            self.take(h, take, at);
        }
    }

    /// The lanes of `tie` (equal `t`) where `at` comes before the best so far.
    #[inline(never)]
    fn wins_tie(&self, tie: L::Mask, at: At) -> L::Mask {
        let mut take = L::Mask::splat(false);
        let mut bits = tie.bits();
        while bits != 0 {
            let j = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let get = |x: &L::Indices| x.as_ref().get(j).copied().unwrap_or(u32::MAX);
            // `loc` last: it decides only between primitives that share an index.
            if (at.set, at.index, at.loc) < (get(&self.set), get(&self.index), get(&self.loc)) {
                take = take.with_lane(j, true);
            }
        }
        take
    }

    /// Takes the hits of `h` (from `at`) in the lanes of `take`, and shrinks their `t_max`.
    #[inline(always)]
    fn take(&mut self, h: &LaneHit<L>, take: L::Mask, at: At) {
        self.t = L::select(take, h.t, self.t);
        self.u = L::select(take, h.u, self.u);
        self.v = L::select(take, h.v, self.v);
        self.w = L::select(take, h.w, self.w);
        self.mask = self.mask | take;
        self.t_max = L::select(take, relax(h.t), self.t_max);
        L::select_indices(take, at.index, &mut self.index);
        L::select_indices(take, at.set, &mut self.set);
        L::select_indices(take, at.loc, &mut self.loc);
    }
}

/// Whether each lane hits anything inside its interval (occlusion); stops once every lane has.
#[derive(Clone, Copy, Debug)]
pub struct Any<L: Lane> {
    hit: L::Mask,
    valid: L::Mask,
    t_end: L,
    t_max: L,
}

impl<L: Lane> Any<L> {
    /// The collector for `rays`.
    #[inline(always)]
    #[must_use]
    pub fn new(rays: &RayPacket<L>) -> Self {
        let valid = rays.valid();
        Any {
            hit: Mask::splat(false),
            valid,
            t_end: rays.t_max,
            t_max: L::select(valid, relax(rays.t_max), rays.t_max),
        }
    }

    /// The lanes that hit.
    #[inline(always)]
    #[must_use]
    pub fn finish(&self) -> L::Mask {
        self.hit & self.valid
    }
}

impl<L: Lane> Collector<L> for Any<L> {
    #[inline(always)]
    fn active(&self) -> L::Mask {
        self.valid.and_not(self.hit)
    }

    #[inline(always)]
    fn t_max(&self) -> L {
        self.t_max
    }

    #[inline(always)]
    fn offer(&mut self, h: &LaneHit<L>, _: At, _: impl FnOnce(&Winners<L>) -> Hits<L>) -> bool {
        self.hit = self.hit | (h.mask & h.t.lt(self.t_end) & self.valid);
        self.valid.and_not(self.hit).none()
    }
}

/// Lane `i` of the packet collector `c` traced alone by `trace` (a packet lane continued as
/// one ray); true when every lane of `c` is done.
#[inline(always)]
pub(crate) fn alone<L: Lane, C: Collector<L>>(
    c: &mut C,
    i: usize,
    trace: impl FnOnce(&mut LaneOf<'_, L, C>) -> bool,
) -> bool {
    trace(&mut LaneOf::new(c, i));
    c.active().none()
}

/// Lane `i` of a packet's collector as a one-ray collector: a packet lane continued as a
/// single ray (the BVH's hybrid traversal). Its activity and `t_max` are the lane's, its
/// candidates go to the lane (the same rule, so the same answer); it asks its traversal to
/// stop when the lane is done. Not for collectors that report every hit.
pub(crate) struct LaneOf<'c, L: Lane, C: Collector<L>> {
    c: &'c mut C,
    i: usize,
    /// The lane's `t_max` and activity, kept: only this collector's offers change them.
    t_max: f32,
    active: bool,
    _lane: core::marker::PhantomData<L>,
}

impl<'c, L: Lane, C: Collector<L>> LaneOf<'c, L, C> {
    /// Lane `i` of `c`.
    #[inline(always)]
    pub(crate) fn new(c: &'c mut C, i: usize) -> Self {
        LaneOf {
            t_max: c.t_max().lane(i).to_f64() as f32,
            active: c.active().test(i),
            c,
            i,
            _lane: core::marker::PhantomData,
        }
    }
}

impl<L: Lane, C: Collector<L>> Collector<f32> for LaneOf<'_, L, C> {
    const SHRINKS: bool = C::SHRINKS;
    const EACH: bool = C::EACH;

    #[inline(always)]
    fn active(&self) -> bool {
        self.active
    }

    #[inline(always)]
    fn t_max(&self) -> f32 {
        self.t_max
    }

    #[inline(always)]
    fn sees(&self, set: u32, mask: u32) -> bool {
        self.c.sees(set, mask).test(self.i)
    }

    #[inline(always)]
    fn offer(
        &mut self,
        h: &LaneHit<f32>,
        at: At,
        _: impl FnOnce(&Winners<f32>) -> Hits<f32>,
    ) -> bool {
        let one = LaneHit {
            t: L::from_f32(h.t),
            u: L::from_f32(h.u),
            v: L::from_f32(h.v),
            w: L::from_f32(h.w),
            mask: L::Mask::splat(false).with_lane(self.i, h.mask),
        };
        self.c.offer(&one, at, |_| Hits::miss());
        self.t_max = self.c.t_max().lane(self.i).to_f64() as f32;
        self.active = self.c.active().test(self.i);
        !self.active
    }
}

/// Every hit inside the interval, as records passed to a callback in the order the set
/// visits them.
pub struct All<L: Lane, F: FnMut(&Hits<L>)> {
    f: F,
    valid: L::Mask,
    t_end: L,
    t_max: L,
}

impl<L: Lane, F: FnMut(&Hits<L>)> All<L, F> {
    /// The collector for `rays`, calling `f` per hit.
    #[inline(always)]
    #[must_use]
    pub fn new(rays: &RayPacket<L>, f: F) -> Self {
        let valid = rays.valid();
        All {
            f,
            valid,
            t_end: rays.t_max,
            t_max: L::select(valid, relax(rays.t_max), rays.t_max),
        }
    }
}

impl<L: Lane, F: FnMut(&Hits<L>)> Collector<L> for All<L, F> {
    const EVERY: bool = true;

    #[inline(always)]
    fn active(&self) -> L::Mask {
        self.valid
    }

    #[inline(always)]
    fn t_max(&self) -> L {
        self.t_max
    }

    #[inline(always)]
    fn offer(
        &mut self,
        h: &LaneHit<L>,
        at: At,
        record: impl FnOnce(&Winners<L>) -> Hits<L>,
    ) -> bool {
        let inside = h.mask & h.t.lt(self.t_end);
        if inside.any() {
            let one = LaneHit::deferred(h.t, h.u, h.v, h.w, inside);
            (self.f)(&record(&Winners::single(&one, at)));
        }
        false
    }
}

/// A candidate hit as a query's [`Filter`] sees it: where it comes from and where it lies.
/// The values are those the hit's record would carry, bit for bit, at every width.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The set ([`Hit::set`]: the instance of a scene, the position in a tuple).
    pub set: u32,
    /// The primitive's index in its set ([`Hit::index`]).
    pub index: u32,
    /// The ray parameter ([`Hit::t`]).
    pub t: f32,
    /// Triangles: the barycentric weight of vertex B ([`Hit::u`]). Spheres: 1 on an exit root
    /// (the ray leaving the sphere: its back face), 0 on an entry root. Planes: 0.
    pub u: f32,
    /// Triangles: the barycentric weight of vertex C ([`Hit::v`]). Otherwise 0.
    pub v: f32,
    /// The ray's lane in its packet (0 for one ray; within a tile, the lane in its block):
    /// for filters that differ per ray (each bullet ignores its own shooter).
    pub lane: u32,
}

/// What a query asks of each candidate hit ([`Screen`]): keep it (`true`) or reject it. Any
/// `Fn(&Candidate) -> bool` is one; [`Unfiltered`] keeps everything at no cost.
///
/// A filter must answer the same for the same candidate: it may be asked more than once about
/// one (a traversal that restarts), and it is not asked about candidates that can no longer
/// count (beyond the ray's interval or, for `closest`, beyond the closest hit kept so far).
pub trait Filter {
    /// True for [`Unfiltered`]: a query then skips the filter entirely, at compile time.
    const NONE: bool = false;
    /// Whether the candidate `c` counts.
    fn keep(&self, c: &Candidate) -> bool;
}

impl<F: Fn(&Candidate) -> bool> Filter for F {
    #[inline(always)]
    fn keep(&self, c: &Candidate) -> bool {
        self(c)
    }
}

/// No filter: every candidate counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unfiltered;

impl Filter for Unfiltered {
    const NONE: bool = true;
    #[inline(always)]
    fn keep(&self, _: &Candidate) -> bool {
        true
    }
}

/// What each ray lane of a query may see (a ray is lane 0): its 32-bit layer mask (an instance
/// whose mask shares no bit with it is not seen; a mask of 0 sees nothing; sets that carry no
/// masks count as carrying every bit), and one set it ignores (an instance, or a member of a
/// tuple: "ignore self"), whose candidates do not count and which a scene does not even
/// traverse for that lane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Visibility {
    masks: [u32; MAX_LANES],
    /// The ignored set per lane ([`u32::MAX`]: none).
    ignored: [u32; MAX_LANES],
    /// Every lane holds `masks[0]`.
    same_mask: bool,
    /// Every lane holds `ignored[0]`.
    same_ignored: bool,
}

impl Visibility {
    /// Every layer, nothing ignored: the default, which sees everything.
    pub const ALL: Visibility = Visibility {
        masks: [u32::MAX; MAX_LANES],
        ignored: [u32::MAX; MAX_LANES],
        same_mask: true,
        same_ignored: true,
    };

    /// The layer mask `mask` in every lane.
    #[must_use]
    pub const fn mask(self, mask: u32) -> Self {
        Visibility {
            masks: [mask; MAX_LANES],
            same_mask: true,
            ..self
        }
    }

    /// Lane `i` with the layer mask `masks[i]`; lanes past the slice get 0 (they see nothing).
    #[must_use]
    pub fn masks(self, masks: &[u32]) -> Self {
        let (lanes, same) = per_lane(masks, 0);
        Visibility {
            masks: lanes,
            same_mask: same,
            ..self
        }
    }

    /// Every lane ignores the set `set` ([`Hit::set`]).
    #[must_use]
    pub const fn ignore(self, set: u32) -> Self {
        Visibility {
            ignored: [set; MAX_LANES],
            same_ignored: true,
            ..self
        }
    }

    /// Lane `i` ignores the set `sets[i]`; lanes past the slice ignore nothing.
    #[must_use]
    pub fn ignores(self, sets: &[u32]) -> Self {
        let (lanes, same) = per_lane(sets, u32::MAX);
        Visibility {
            ignored: lanes,
            same_ignored: same,
            ..self
        }
    }

    /// Lane `i`'s mask (0 past [`MAX_LANES`]).
    #[must_use]
    pub fn lane_mask(&self, i: usize) -> u32 {
        self.masks.get(i).copied().unwrap_or(0)
    }

    /// The set lane `i` ignores ([`u32::MAX`]: none).
    #[must_use]
    pub fn lane_ignores(&self, i: usize) -> u32 {
        self.ignored.get(i).copied().unwrap_or(u32::MAX)
    }

    /// True when some lane ignores a set.
    fn ignoring(&self) -> bool {
        !(self.same_ignored && self.ignored[0] == u32::MAX)
    }

    /// The lanes of `L` whose mask shares a bit with `mask`.
    #[inline(always)]
    fn share<L: Lane>(&self, mask: u32) -> L::Mask {
        if self.same_mask {
            return Mask::splat(self.masks[0] & mask != 0);
        }
        lanes::<L>(&self.masks, |m| m & mask != 0)
    }

    /// The lanes of `L` that ignore `set`.
    #[inline(always)]
    fn ignore_lanes<L: Lane>(&self, set: u32) -> L::Mask {
        if self.same_ignored {
            return Mask::splat(self.ignored[0] == set);
        }
        lanes::<L>(&self.ignored, |i| i == set)
    }
}

impl Default for Visibility {
    fn default() -> Self {
        Visibility::ALL
    }
}

/// `values` in lanes (`fill` past the slice), and whether every lane holds the first.
fn per_lane(values: &[u32], fill: u32) -> ([u32; MAX_LANES], bool) {
    let mut lanes = [fill; MAX_LANES];
    for (l, v) in lanes.iter_mut().zip(values) {
        *l = *v;
    }
    let same = lanes.iter().all(|&v| v == lanes[0]);
    (lanes, same)
}

/// The lanes of `L` whose value passes `test`.
#[inline(always)]
fn lanes<L: Lane>(values: &[u32; MAX_LANES], test: impl Fn(u32) -> bool) -> L::Mask {
    let mut m = L::Mask::splat(false);
    for (i, &v) in values.iter().enumerate().take(L::LANES) {
        if test(v) {
            m = m.with_lane(i, true);
        }
    }
    m
}

/// A collector seen through a query's [`Visibility`] (layer masks, an ignored set per lane)
/// and [`Filter`]: the lanes whose mask is 0 are done before they start, a set of instances
/// asks [`sees`](Collector::sees) which lanes see an instance (and traces it for those only),
/// and every other candidate is put to the ignored sets and to the filter before the collector
/// sees it. A rejected candidate never reaches the collector: it neither counts nor shrinks
/// `t_max` (so the kernels' relaxed pruning never drops a winner behind it), `closest`
/// continues past it, `any` does not stop on it and `all` does not report it. Answers
/// therefore equal brute force over every candidate with the same masks, ignored sets and
/// filter, at every width. With a filter, every root of a sphere is offered (the exit root
/// counts when the filter rejects the entry root).
///
/// Without a filter ([`Unfiltered`]), with every mask bit set and nothing ignored, it is the
/// collector itself (a lane mask `AND` per offer); queries that ask for none of them never
/// build one, and their code is unchanged.
pub struct Screen<'c, L: Lane, C, F> {
    inner: &'c mut C,
    sight: &'c Visibility,
    /// The lanes whose mask is not 0.
    seeing: L::Mask,
    /// Some lane ignores a set.
    ignoring: bool,
    filter: &'c F,
}

impl<'c, L: Lane, C: Collector<L>, F: Filter> Screen<'c, L, C, F> {
    /// `inner` seen through `sight` and `filter`.
    #[inline(always)]
    pub fn new(inner: &'c mut C, sight: &'c Visibility, filter: &'c F) -> Self {
        Screen {
            seeing: sight.share::<L>(u32::MAX),
            ignoring: sight.ignoring(),
            inner,
            sight,
            filter,
        }
    }

    /// [`keep_lanes`](Self::keep_lanes) out of line: one copy per packet type.
    #[inline(never)]
    fn keep(&self, h: &LaneHit<L>, at: At, m: L::Mask) -> L::Mask {
        self.keep_lanes(h, at, m)
    }

    /// The lanes of `m` whose candidates in `h` (from `at`) the filter keeps.
    #[inline(always)]
    fn keep_lanes(&self, h: &LaneHit<L>, at: At, mut m: L::Mask) -> L::Mask {
        let u = plus_zero(h.u / h.w);
        let v = plus_zero(h.v / h.w);
        let mut bits = m.bits();
        while bits != 0 {
            let j = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let c = Candidate {
                set: at.set,
                index: at.index,
                t: h.t.lane(j).to_f64() as f32,
                u: u.lane(j).to_f64() as f32,
                v: v.lane(j).to_f64() as f32,
                lane: j as u32,
            };
            if !self.filter.keep(&c) {
                m = m.with_lane(j, false);
            }
        }
        m
    }
}

impl<L: Lane, C: Collector<L>, F: Filter> Collector<L> for Screen<'_, L, C, F> {
    const EVERY: bool = C::EVERY;
    const SHRINKS: bool = C::SHRINKS;
    const EACH: bool = C::EACH || !F::NONE;

    #[inline(always)]
    fn active(&self) -> L::Mask {
        self.inner.active() & self.seeing
    }

    #[inline(always)]
    fn t_max(&self) -> L {
        self.inner.t_max()
    }

    #[inline(always)]
    fn sees(&self, set: u32, mask: u32) -> L::Mask {
        let m = self.inner.sees(set, mask) & self.sight.share::<L>(mask);
        if self.ignoring {
            m.and_not(self.sight.ignore_lanes::<L>(set))
        } else {
            m
        }
    }

    #[inline(always)]
    fn offer(
        &mut self,
        h: &LaneHit<L>,
        at: At,
        record: impl FnOnce(&Winners<L>) -> Hits<L>,
    ) -> bool {
        let mut m = h.mask & self.seeing;
        if self.ignoring {
            m = m.and_not(self.sight.ignore_lanes::<L>(at.set));
        }
        if !F::NONE {
            // Beyond the relaxed upper end nothing can count: the filter is not asked.
            m = m & h.t.lt(self.inner.t_max());
            // One ray's candidate is asked in line (in the query's SIMD level, crate::simd);
            // a packet's lanes in one copy out of line.
            if m.any() {
                m = if L::LANES == 1 {
                    self.keep_lanes(h, at, m)
                } else {
                    self.keep(h, at, m)
                };
            }
        }
        if m.none() {
            return false;
        }
        let h = LaneHit { mask: m, ..*h };
        self.inner.offer(&h, at, record) || self.active().none()
    }
}

/// How a primitive's records are made from the winners (see the [module docs](self)).
pub trait Record: Primitive {
    /// The records of `w`'s lanes; `prim(loc)` is the winning primitive kept at `loc` (a
    /// lane's `w.loc`; asked only for the lanes of `w.mask`); `cull` is the query's.
    fn records<L: Lane>(
        rays: &RayPacket<L>,
        w: &Winners<L>,
        cull: Cull,
        prim: impl Fn(u32) -> Option<Self>,
    ) -> Hits<L>;
}

/// Spheres: normal `(o + t·d − c)/|o + t·d − c|` (3 add, 3 mul, 2 add, 1 sqrt, 3 div), flipped
/// for exit roots (marked by `u = 1`).
impl Record for Sphere {
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(
        rays: &RayPacket<L>,
        w: &Winners<L>,
        _cull: Cull,
        sphere: impl Fn(u32) -> Option<Sphere>,
    ) -> Hits<L> {
        if w.mask.none() {
            return Hits::miss();
        }
        let c = if L::LANES == 1 {
            V3::splat(w.loc(0).and_then(sphere).map_or(Vec3::ZERO, |s| s.center()))
        } else {
            let rows = gather(w, [0.0; 3], |loc| {
                sphere(loc).map(|s| s.center().to_array())
            });
            V3::new(row(&rows, 0), row(&rows, 1), row(&rows, 2))
        };
        let point = rays.origin.along(rays.dir, w.t);
        let n = unit(point - c, w.mask, |i| {
            let (o, d, c) = (
                rays.origin.precise_lane(i),
                rays.dir.precise_lane(i),
                c.precise_lane(i),
            );
            o.along(d, w.t.precise_lane(i)) - c
        });
        let front = w.mask & w.u.lt(L::from_f32(0.5));
        finish(w, point, V3::select(front, n, -n), front, false)
    }
}

/// Triangles: normal `N/|N|` with `N = (B − A) × (C − A)` (6 add, 6 mul, 3 add; then 3 mul,
/// 2 add, 1 sqrt, 3 div), facing the origin; front: `d·N/|N| < 0` (3 mul, 2 add, 1 cmp), or
/// every hit under [`Cull::Back`] (the kernel decided it).
impl Record for Triangle {
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(
        rays: &RayPacket<L>,
        w: &Winners<L>,
        cull: Cull,
        tri: impl Fn(u32) -> Option<Triangle>,
    ) -> Hits<L> {
        if w.mask.none() {
            return Hits::miss();
        }
        let p = if L::LANES == 1 {
            TrianglePacket::splat(&w.loc(0).and_then(tri).unwrap_or(Triangle::never()))
        } else {
            let rows = gather(w, [f32::NAN; 9], |loc| {
                tri(loc).map(|t| {
                    let (a, b, c) = (t.a(), t.b(), t.c());
                    [a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z]
                })
            });
            let v = |k: usize| V3::new(row(&rows, k), row(&rows, k + 1), row(&rows, k + 2));
            TrianglePacket {
                a: v(0),
                b: v(3),
                c: v(6),
            }
        };
        let n = unit((p.b - p.a).cross(p.c - p.a), w.mask, |i| {
            let (a, b, c) = (
                p.a.precise_lane(i),
                p.b.precise_lane(i),
                p.c.precise_lane(i),
            );
            (b - a).cross(c - a)
        });
        let point = rays.origin.along(rays.dir, w.t);
        let front = if cull.back() {
            w.mask
        } else {
            w.mask & rays.dir.dot(n).lt(L::from_f32(0.0))
        };
        finish(w, point, V3::select(front, n, -n), front, true)
    }
}

/// Planes: normal `n/|n|` facing the origin, front `d·n < 0`.
impl Record for Plane {
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(
        rays: &RayPacket<L>,
        w: &Winners<L>,
        cull: Cull,
        plane: impl Fn(u32) -> Option<Plane>,
    ) -> Hits<L> {
        if w.mask.none() {
            return Hits::miss();
        }
        let normal = if L::LANES == 1 {
            V3::splat(w.loc(0).and_then(plane).map_or(Vec3::ZERO, |p| p.normal))
        } else {
            let rows = gather(w, [0.0; 3], |loc| plane(loc).map(|p| p.normal.to_array()));
            V3::new(row(&rows, 0), row(&rows, 1), row(&rows, 2))
        };
        let n = unit(normal, w.mask, |i| normal.precise_lane(i));
        let point = rays.origin.along(rays.dir, w.t);
        let front = if cull.back() {
            w.mask
        } else {
            w.mask & rays.dir.dot(n).lt(L::from_f32(0.0))
        };
        finish(w, point, V3::select(front, n, -n), front, false)
    }
}

/// `N` values per lane of `w`, as rows of lanes ([`row`]): `f(loc)` for each lane of
/// `w.mask` (one pass over its set lanes, the others never asked; `loc` is the lane's `w.loc`),
/// `default` where `f` gives `None` or the lane is outside the mask. A packet's records gather
/// their winners' primitives with it (callgrind, x86-64-v3, the vendored bunny's primary rays
/// in packets of 16: asking every lane cost about 10 more instructions per ray); one lane
/// takes its own ([`Winners::loc`]: no rows to fill).
#[inline(always)]
fn gather<L: Lane, const N: usize>(
    w: &Winners<L>,
    default: [f32; N],
    mut f: impl FnMut(u32) -> Option<[f32; N]>,
) -> [[f32; MAX_LANES]; N] {
    let mut rows = [[0f32; MAX_LANES]; N];
    for (row, d) in rows.iter_mut().zip(default) {
        *row = [d; MAX_LANES];
    }
    let mut bits = w.mask.bits();
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        if let Some(v) = w.loc.as_ref().get(i).and_then(|&loc| f(loc)) {
            for (row, x) in rows.iter_mut().zip(v) {
                if let Some(r) = row.get_mut(i) {
                    *r = x;
                }
            }
        }
    }
    rows
}

/// Row `k` of [`gather`]'s rows as lanes.
#[inline(always)]
fn row<L: Lane, const N: usize>(rows: &[[f32; MAX_LANES]; N], k: usize) -> L {
    L::from_f32_fn(|i| rows[k][i])
}

/// The records from the winners and their point, normal and face.
#[inline(always)]
fn finish<L: Lane>(
    w: &Winners<L>,
    point: V3<L>,
    normal: V3<L>,
    front: L::Mask,
    barycentrics: bool,
) -> Hits<L> {
    let zero = L::from_f32(0.0);
    let z = V3::new(zero, zero, zero);
    let m = w.mask;
    Hits {
        t: w.t,
        point: V3::select(m, point, z),
        normal: V3::select(m, normal, z),
        front: front & m,
        index: w.index,
        set: w.set,
        u: if barycentrics { w.u } else { zero },
        v: if barycentrics { w.v } else { zero },
        mask: m,
    }
}

/// `v/|v|` in the lanes of `mask` (3 mul, 2 add, 1 sqrt, 3 div, 2 cmp); lanes whose `|v|²`
/// lies outside `2^-100…2^100` (under- or overflow) are recomputed from `exact(i)` in `f64`
/// and rounded; a zero or non-finite vector gives zero.
#[inline(always)]
fn unit<L: Lane>(
    v: V3<L>,
    mask: L::Mask,
    exact: impl Fn(usize) -> V3<<L as Lane>::Precise>,
) -> V3<L> {
    let n2 = v.length_squared();
    let n = v.div_by(n2.sqrt());
    const LO: f32 = pow2(-100);
    const HI: f32 = pow2(100);
    let odd = mask.and_not(n2.ge(L::from_f32(LO)) & n2.le(L::from_f32(HI)));
    if odd.any() {
        precise_unit(n, odd, exact)
    } else {
        n
    }
}

/// The `lanes` of [`unit`] recomputed in `f64`.
#[inline(never)]
fn precise_unit<L: Lane>(
    mut n: V3<L>,
    lanes: L::Mask,
    exact: impl Fn(usize) -> V3<<L as Lane>::Precise>,
) -> V3<L> {
    let mut bits = lanes.bits();
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let w = exact(i);
        let len = w.length_squared().sqrt();
        let zero = <L::Precise as Lane>::from_f32(0.0);
        let u = if (len.gt(zero) & len.is_finite()).any() {
            w.div_by(len)
        } else {
            V3::new(zero, zero, zero)
        };
        let round = |x: L::Precise| L::Scalar::from_f64(x.lane(0));
        n = V3::new(
            n.x.with_lane(i, round(u.x)),
            n.y.with_lane(i, round(u.y)),
            n.z.with_lane(i, round(u.z)),
        );
    }
    n
}
