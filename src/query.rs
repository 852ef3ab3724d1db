//! Queries: one vocabulary for every set of primitives.
//!
//! [`Query`] asks a set of primitives three questions, for one [`Ray`] or for a
//! [`RayPacket`] of any width:
//!
//! * [`closest`](Query::closest): the closest hit ([`Hit`] for a ray, [`Hits`] per lane for a
//!   packet; a packet query returns the same record, lane by lane, as the one-ray query);
//! * [`any`](Query::any): whether anything is hit (occlusion; stops early);
//! * [`all`](Query::all): a callback per hit, in the order each set documents.
//!
//! It is implemented by `[Sphere]`, `[Triangle]` and `[Plane]`, and by tuples of up to four
//! sets (a scene whose hits carry the set's position in [`Hit::set`]). A set of primitives
//! uses its documented default kernel ([`Robust`] for spheres, [`Watertight`] for triangles,
//! the one plane test for planes); [`Query::using`] picks another kernel and
//! [`Using::culled`] drops back faces:
//!
//! ```
//! use raylane::glam::Vec3;
//! use raylane::sphere::{Geometric, Sphere};
//! use raylane::triangle::{Cull, Triangle};
//! use raylane::{Query, Ray, RayPacket};
//!
//! let spheres = [Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0)];
//! let ray = Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0));
//! let hit = spheres.closest(&ray).unwrap();
//! assert_eq!((hit.t, hit.point, hit.normal), (4.0, Vec3::new(0.0, 0.0, -4.0), Vec3::Z));
//! assert!(hit.front);
//! // Another kernel; a packet of eight rays gives the same record in every lane.
//! let hits = spheres.using::<Geometric>().closest(&RayPacket::<wide::f32x8>::splat(&ray));
//! assert_eq!(hits.lane(5), Some(hit));
//!
//! // Triangles: two-sided by default, front faces only when culled.
//! let tris = [Triangle::new(Vec3::new(-1.0, -1.0, -2.0), Vec3::new(1.0, -1.0, -2.0),
//!                           Vec3::new(0.0, 1.0, -2.0))];
//! assert!(tris.any(&ray));
//! let from_behind = Ray::new(Vec3::new(0.0, 0.0, -4.0), Vec3::Z);
//! assert!(!tris.closest(&from_behind).unwrap().front);
//! assert_eq!(tris.using::<raylane::triangle::Watertight>().culled(Cull::Back).closest(&from_behind), None);
//!
//! // A scene: a tuple of sets; `set` says which one was hit.
//! let hit = (&spheres[..], &tris[..]).closest(&ray).unwrap();
//! assert_eq!((hit.set, hit.t), (1, 2.0));
//! ```
//!
//! **Records.** The closest-hit loops keep only `t`, the barycentrics and the index of the
//! best candidate ([`hit`]); the point `o + t·d` (3 mul, 3 add), the unit
//! geometric normal and the face are computed once per ray, for the winner
//! ([`Hits::from_spheres`], [`Hits::from_triangles`], [`Hits::from_planes`]), with the same
//! operations in every lane: every lane of every width equals the scalar path bit for bit.
//! The normal faces the ray's origin (`d·normal ≤ 0`); [`Hit::front`] says whether that is
//! the primitive's outer side (spheres: hit from outside; triangles: `d·N < 0` with
//! `N = (B − A) × (C − A)`, i.e. A, B, C counter-clockwise as seen from the origin; planes:
//! `d·n < 0`). **Misses** are one word: `None` for a ray, a clear lane in [`Hits::mask`]
//! (with `t = +inf`, zero vectors and index `u32::MAX`) for a packet.
//!
//! **Unit directions.** [`QuadraticUnit`](crate::sphere::QuadraticUnit) and
//! [`Geometric`](crate::sphere::Geometric) assume `|d| = 1`. Through a query, a ray whose
//! `|d|²` differs from 1 by more than `2^-20` is a miss for them (a documented answer, never
//! wrong roots); normalise directions first (a correctly rounded `d/|d|` is well inside).

use core::marker::PhantomData;

use glam::Vec3;

use crate::hit::{self, Best, LaneHit};
use crate::lane::{Lane, Mask, Scalar};
use crate::plane::{self, Plane, PlanePacket};
use crate::ray::{Ray, RayPacket};
use crate::sphere::{Robust, Roots, Sphere, SphereKernel, SpherePacket};
use crate::triangle::{Cull, Triangle, TriangleKernel, TrianglePacket, Watertight};
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
    /// Which set of a scene (its position in the tuple); 0 for a plain set.
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

/// `2^e` for `-126 ≤ e ≤ 127`.
const fn pow2(e: i32) -> f32 {
    f32::from_bits(((127 + e) as u32) << 23)
}

/// Largest `| |d|² − 1 |` a unit-direction kernel accepts through a query (`2^-20`).
pub const UNIT_TOLERANCE: f32 = pow2(-20);

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

    /// The same records with `set` in every lane that hit.
    #[inline]
    #[must_use]
    pub fn with_set(mut self, set: u32) -> Self {
        let mut bits = self.mask.bits();
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if let Some(s) = self.set.as_mut().get_mut(i) {
                *s = set;
            }
        }
        self
    }

    /// Takes the lanes of `other` that hit strictly closer than `self` (ties keep `self`):
    /// how hits of several sets, meshes or parts are merged.
    #[inline]
    pub fn merge(&mut self, other: &Hits<L>) {
        let take = other.mask & other.t.lt(self.t);
        if take.none() {
            return;
        }
        self.t = L::select(take, other.t, self.t);
        self.point = V3::select(take, other.point, self.point);
        self.normal = V3::select(take, other.normal, self.normal);
        self.front = (take & other.front) | self.front.and_not(take);
        self.u = L::select(take, other.u, self.u);
        self.v = L::select(take, other.v, self.v);
        self.mask = self.mask | take;
        let mut bits = take.bits();
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if let (Some(d), Some(s)) =
                (self.index.as_mut().get_mut(i), other.index.as_ref().get(i))
            {
                *d = *s;
            }
            if let (Some(d), Some(s)) = (self.set.as_mut().get_mut(i), other.set.as_ref().get(i)) {
                *d = *s;
            }
        }
    }

    /// The records of the spheres that won: `best` from a closest-hit loop whose sphere hits
    /// were made by [`sphere_hit`] (its `u` marks exit roots), `sphere(i)` the sphere of index
    /// `i`. Normal: `(o + t·d − c)/|o + t·d − c|` (3 add, 3 mul, 2 add, 1 sqrt, 3 div), flipped
    /// for exit roots.
    #[inline]
    #[must_use]
    pub fn from_spheres(
        rays: &RayPacket<L>,
        best: &Best<L>,
        sphere: impl Fn(u32) -> Option<Sphere>,
    ) -> Self {
        if best.mask.none() {
            return Self::miss();
        }
        let get = |i: usize| {
            winner(best, i)
                .and_then(&sphere)
                .unwrap_or(Sphere::new(Vec3::ZERO, f32::NAN))
        };
        let c = V3::<L>::from_fn(|i| get(i).center());
        let point = rays.origin.along(rays.dir, best.t);
        let n = unit(point - c, best.mask, |i| {
            let (o, d, c) = (
                rays.origin.precise_lane(i),
                rays.dir.precise_lane(i),
                c.precise_lane(i),
            );
            o.along(d, best.t.precise_lane(i)) - c
        });
        // Entry roots carry u = 0, exit roots u = 1 (see `sphere_hit`).
        let front = best.mask & best.u.lt(L::from_f32(0.5));
        finish(best, point, V3::select(front, n, -n), front, false)
    }

    /// The records of the triangles that won: `best` from a closest-hit loop over triangles,
    /// `tri(i)` the triangle of index `i`, `cull` the query's culling. Normal: `N/|N|` with
    /// `N = (B − A) × (C − A)` (6 add, 6 mul, 3 add; then 3 mul, 2 add, 1 sqrt, 3 div), facing
    /// the origin; front: `d·N/|N| < 0` (3 mul, 2 add, 1 cmp), or every hit under
    /// [`Cull::Back`] (the kernel decided it).
    #[inline]
    #[must_use]
    pub fn from_triangles(
        rays: &RayPacket<L>,
        best: &Best<L>,
        cull: Cull,
        tri: impl Fn(u32) -> Option<Triangle>,
    ) -> Self {
        if best.mask.none() {
            return Self::miss();
        }
        let p = TrianglePacket::<L>::from_fn(|i| {
            winner(best, i).and_then(&tri).unwrap_or(Triangle::never())
        });
        let n = unit((p.b - p.a).cross(p.c - p.a), best.mask, |i| {
            let (a, b, c) = (
                p.a.precise_lane(i),
                p.b.precise_lane(i),
                p.c.precise_lane(i),
            );
            (b - a).cross(c - a)
        });
        let point = rays.origin.along(rays.dir, best.t);
        let front = if cull.back() {
            best.mask
        } else {
            best.mask & rays.dir.dot(n).lt(L::from_f32(0.0))
        };
        finish(best, point, V3::select(front, n, -n), front, true)
    }

    /// The records of the planes that won: normal `n/|n|` facing the origin, front `d·n < 0`.
    #[inline]
    #[must_use]
    pub fn from_planes(
        rays: &RayPacket<L>,
        best: &Best<L>,
        cull: Cull,
        plane: impl Fn(u32) -> Option<Plane>,
    ) -> Self {
        if best.mask.none() {
            return Self::miss();
        }
        let normal = V3::<L>::from_fn(|i| {
            winner(best, i)
                .and_then(&plane)
                .map_or(Vec3::ZERO, |p| p.normal)
        });
        let n = unit(normal, best.mask, |i| normal.precise_lane(i));
        let point = rays.origin.along(rays.dir, best.t);
        let front = if cull.back() {
            best.mask
        } else {
            best.mask & rays.dir.dot(n).lt(L::from_f32(0.0))
        };
        finish(best, point, V3::select(front, n, -n), front, false)
    }
}

/// The index of lane `i`'s winner, if it hit.
#[inline(always)]
fn winner<L: Lane>(best: &Best<L>, i: usize) -> Option<u32> {
    if best.mask.test(i) {
        best.index.as_ref().get(i).copied()
    } else {
        None
    }
}

/// The records from a finished loop state and the winners' point, normal and face.
#[inline(always)]
fn finish<L: Lane>(
    best: &Best<L>,
    point: V3<L>,
    normal: V3<L>,
    front: L::Mask,
    barycentrics: bool,
) -> Hits<L> {
    let zero = L::from_f32(0.0);
    let z = V3::new(zero, zero, zero);
    let m = best.mask;
    Hits {
        t: best.t,
        point: V3::select(m, point, z),
        normal: V3::select(m, normal, z),
        front: front & m,
        index: best.index,
        set: {
            let mut s = L::indices(u32::MAX);
            let mut bits = m.bits();
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if let Some(x) = s.as_mut().get_mut(i) {
                    *x = 0;
                }
            }
            s
        },
        u: if barycentrics { best.u } else { zero },
        v: if barycentrics { best.v } else { zero },
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
    let odd = mask.and_not(n2.ge(L::from_f32(pow2(-100))) & n2.le(L::from_f32(pow2(100))));
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

/// The first root of `roots` inside the interval as a loop candidate, with `u = 1` marking an
/// exit root (the origin is inside: a back face) and `u = 0` an entry root; under
/// [`Cull::Back`] only entry roots.
#[inline(always)]
#[must_use]
pub fn sphere_hit<L: Lane>(roots: &Roots<L>, cull: Cull) -> LaneHit<L> {
    let zero = L::from_f32(0.0);
    if cull.back() {
        LaneHit::new(roots.t0, zero, zero, roots.m0)
    } else {
        let t = L::select(roots.m0, roots.t0, roots.t1);
        let exit = L::select(roots.m0, zero, L::from_f32(1.0));
        LaneHit::new(t, exit, zero, roots.m0 | roots.m1)
    }
}

/// Reports the roots of sphere `index` to an `all` query: the entry roots, then (unless culled)
/// the exit roots, each as records when some lane has one.
pub(crate) fn each_root<L: Lane>(
    rays: &RayPacket<L>,
    roots: &Roots<L>,
    cull: Cull,
    index: u32,
    sphere: &dyn Fn(u32) -> Option<Sphere>,
    f: &mut dyn FnMut(&Hits<L>),
) {
    let zero = L::from_f32(0.0);
    let entry = LaneHit::new(roots.t0, zero, zero, roots.m0);
    let exit = LaneHit::new(roots.t1, L::from_f32(1.0), zero, roots.m1);
    let sides: &[LaneHit<L>] = if cull.back() {
        &[entry]
    } else {
        &[entry, exit]
    };
    for h in sides {
        if h.mask.any() {
            let best = Best::single(h, index);
            f(&Hits::from_spheres(rays, &best, sphere));
        }
    }
}

/// Rays a kernel can answer: for the unit-direction kernels, lanes whose `|d|²` is more than
/// [`UNIT_TOLERANCE`] from 1 get the empty interval (a miss); others unchanged.
#[inline(always)]
pub(crate) fn admit<L: Lane>(rays: &RayPacket<L>, unit_directions: bool) -> RayPacket<L> {
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

/// Caller storage too small for a result: `needed` entries are required (e.g.
/// [`Mesh::focus`](crate::mesh::Mesh::focus); nothing was written).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooSmall {
    /// The number of entries the storage must hold.
    pub needed: usize,
}

/// The rays of a focal cache's query: lanes whose origin is not exactly `eye` get the empty
/// interval (a documented miss; 3 cmp per query).
#[inline(always)]
pub(crate) fn at_eye<L: Lane>(rays: &RayPacket<L>, eye: Vec3) -> RayPacket<L> {
    let e = V3::<L>::splat(eye);
    let o = rays.origin;
    let same = o.x.ge(e.x) & o.x.le(e.x) & o.y.ge(e.y) & o.y.le(e.y) & o.z.ge(e.z) & o.z.le(e.z);
    RayPacket {
        t_min: L::select(same, rays.t_min, L::from_f32(f32::INFINITY)),
        t_max: L::select(same, rays.t_max, L::from_f32(f32::NEG_INFINITY)),
        ..*rays
    }
}

/// A set queried with kernel `K` (and optionally culled): made by [`Query::using`].
#[derive(Debug)]
pub struct Using<'a, S: ?Sized, K> {
    set: &'a S,
    cull: Cull,
    kernel: PhantomData<K>,
}

impl<S: ?Sized, K> Clone for Using<'_, S, K> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: ?Sized, K> Copy for Using<'_, S, K> {}

impl<'a, S: ?Sized, K> Using<'a, S, K> {
    /// `set` with kernel `K`, two-sided.
    #[inline]
    #[must_use]
    pub fn new(set: &'a S) -> Self {
        Using {
            set,
            cull: Cull::None,
            kernel: PhantomData,
        }
    }

    /// The same query culled: [`Cull::Back`] keeps front faces only (triangles: `d·N < 0`;
    /// spheres: entry roots, so a ray from inside misses; planes: `d·n < 0`).
    #[inline]
    #[must_use]
    pub fn culled(self, cull: Cull) -> Self {
        Using { cull, ..self }
    }

    /// The set.
    #[inline]
    #[must_use]
    pub fn set(&self) -> &'a S {
        self.set
    }

    /// The culling.
    #[inline]
    #[must_use]
    pub fn cull(&self) -> Cull {
        self.cull
    }
}

/// What a query is asked for: one [`Ray`] or a [`RayPacket`] of any width. Lets
/// [`Query::closest`], [`Query::any`] and [`Query::all`] take either.
pub trait Rays {
    /// The closest-hit answer: `Option<Hit>` for a ray, [`Hits`] for a packet.
    type Closest;
    /// The occlusion answer: `bool` for a ray, the lane mask for a packet.
    type Any;
    /// What [`Query::all`] passes per hit: [`Hit`] for a ray, [`Hits`] for a packet.
    type Record;
    /// `q`'s closest hit of these rays.
    fn closest_in<Q: Query + ?Sized>(&self, q: &Q) -> Self::Closest;
    /// Whether these rays hit anything in `q`.
    fn any_in<Q: Query + ?Sized>(&self, q: &Q) -> Self::Any;
    /// Every hit of these rays in `q`.
    fn all_in<Q: Query + ?Sized>(&self, q: &Q, f: &mut dyn FnMut(Self::Record));
}

impl Rays for Ray {
    type Closest = Option<Hit>;
    type Any = bool;
    type Record = Hit;
    #[inline]
    fn closest_in<Q: Query + ?Sized>(&self, q: &Q) -> Option<Hit> {
        q.closest_ray(self)
    }
    #[inline]
    fn any_in<Q: Query + ?Sized>(&self, q: &Q) -> bool {
        q.any_ray(self)
    }
    #[inline]
    fn all_in<Q: Query + ?Sized>(&self, q: &Q, f: &mut dyn FnMut(Hit)) {
        q.all_packet(&RayPacket::<f32>::splat(self), &mut |h: &Hits<f32>| {
            if let Some(h) = h.lane(0) {
                f(h)
            }
        });
    }
}

impl<L: Lane> Rays for RayPacket<L> {
    type Closest = Hits<L>;
    type Any = L::Mask;
    type Record = Hits<L>;
    #[inline]
    fn closest_in<Q: Query + ?Sized>(&self, q: &Q) -> Hits<L> {
        q.closest_packet(self)
    }
    #[inline]
    fn any_in<Q: Query + ?Sized>(&self, q: &Q) -> L::Mask {
        q.any_packet(self)
    }
    #[inline]
    fn all_in<Q: Query + ?Sized>(&self, q: &Q, f: &mut dyn FnMut(Hits<L>)) {
        q.all_packet(self, &mut |h: &Hits<L>| f(*h));
    }
}

/// The one query vocabulary (see the [module docs](self)): closest hit, occlusion and every
/// hit, for a ray or a packet, over any set of primitives or scene.
///
/// Implementations provide the three packet methods; the one-ray methods default to the
/// scalar packet (`RayPacket<f32>`), and [`closest`](Self::closest), [`any`](Self::any) and
/// [`all`](Self::all) take either a [`Ray`] or a packet. Every lane of a packet answer equals
/// the one-ray answer for that lane's ray, bit for bit.
pub trait Query {
    /// The closest hit per lane; lanes that miss have their `mask` bit clear.
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L>;
    /// Lanes that hit anything (occlusion); may stop as soon as every valid lane has hit.
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask;
    /// Every hit: `f` once per primitive (and root) that some lane hits, with the lanes that
    /// hit it in `mask`, in the order the implementation documents.
    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>));

    /// The closest hit of one ray, or `None`.
    #[inline]
    fn closest_ray(&self, ray: &Ray) -> Option<Hit> {
        self.closest_packet(&RayPacket::<f32>::splat(ray)).lane(0)
    }

    /// True when one ray hits anything.
    #[inline]
    fn any_ray(&self, ray: &Ray) -> bool {
        self.any_packet(&RayPacket::<f32>::splat(ray))
    }

    /// The closest hit of a [`Ray`] (`Option<Hit>`) or of a packet ([`Hits`]).
    #[inline]
    fn closest<R: Rays>(&self, rays: &R) -> R::Closest {
        rays.closest_in(self)
    }

    /// Whether a [`Ray`] (`bool`) or each lane of a packet (mask) hits anything.
    #[inline]
    fn any<R: Rays>(&self, rays: &R) -> R::Any {
        rays.any_in(self)
    }

    /// Every hit of a [`Ray`] (`f(Hit)`) or of a packet (`f(Hits)`).
    #[inline]
    fn all<R: Rays>(&self, rays: &R, mut f: impl FnMut(R::Record)) {
        rays.all_in(self, &mut f)
    }

    /// This set with kernel `K` instead of its default (see [`Using`]).
    #[inline]
    fn using<K>(&self) -> Using<'_, Self, K> {
        Using::new(self)
    }
}

impl<Q: Query + ?Sized> Query for &Q {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        (**self).closest_packet(rays)
    }
    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        (**self).any_packet(rays)
    }
    #[inline]
    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        (**self).all_packet(rays, f)
    }
    #[inline]
    fn closest_ray(&self, ray: &Ray) -> Option<Hit> {
        (**self).closest_ray(ray)
    }
    #[inline]
    fn any_ray(&self, ray: &Ray) -> bool {
        (**self).any_ray(ray)
    }
}

// ---- spheres ----

/// Spheres with kernel `K`: N rays × 1 sphere, in slice order. `all` reports, per sphere in
/// slice order, its entry roots, then its exit roots.
impl<K: SphereKernel> Query for Using<'_, [Sphere], K> {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        let r = admit(rays, K::UNIT_DIRECTIONS);
        let cull = self.cull;
        let best = hit::closest(&r, self.set, |r, s| {
            Some(sphere_hit(&K::roots(r, &SpherePacket::splat(s)), cull))
        });
        Hits::from_spheres(&r, &best, |i| self.set.get(i as usize).copied())
    }

    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        let r = admit(rays, K::UNIT_DIRECTIONS);
        let cull = self.cull;
        hit::any(&r, self.set, |r, s| {
            Some(sphere_hit(&K::roots(r, &SpherePacket::splat(s)), cull))
        })
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        let r = admit(rays, K::UNIT_DIRECTIONS);
        for (i, s) in self.set.iter().enumerate() {
            let roots = K::roots(&r, &SpherePacket::splat(s));
            each_root(&r, &roots, self.cull, i as u32, &|_| Some(*s), f);
        }
    }
}

/// Spheres with the default kernel, [`Robust`] (any direction, two-sided).
impl Query for [Sphere] {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        Using::<_, Robust>::new(self).closest_packet(rays)
    }
    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        Using::<_, Robust>::new(self).any_packet(rays)
    }
    #[inline]
    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        Using::<_, Robust>::new(self).all_packet(rays, f)
    }
}

// ---- triangles ----

/// Triangles with kernel `K`: N rays × 1 triangle, in slice order; `all` in slice order.
impl<K: TriangleKernel> Query for Using<'_, [Triangle], K> {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        let pre = K::prepare(rays);
        let cull = self.cull;
        let best = hit::closest(rays, self.set, |r, t| {
            Some(K::intersect(r, &pre, &TrianglePacket::splat(t), cull))
        });
        Hits::from_triangles(rays, &best, cull, |i| self.set.get(i as usize).copied())
    }

    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        let pre = K::prepare(rays);
        let cull = self.cull;
        hit::any(rays, self.set, |r, t| {
            Some(K::intersect(r, &pre, &TrianglePacket::splat(t), cull))
        })
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        let pre = K::prepare(rays);
        for (i, t) in self.set.iter().enumerate() {
            let h = K::intersect(rays, &pre, &TrianglePacket::splat(t), self.cull);
            if h.mask.any() {
                let best = Best::single(&h.normalized(), i as u32);
                f(&Hits::from_triangles(rays, &best, self.cull, |_| Some(*t)));
            }
        }
    }
}

/// Triangles with the default kernel, [`Watertight`] (two-sided).
impl Query for [Triangle] {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        Using::<_, Watertight>::new(self).closest_packet(rays)
    }
    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        Using::<_, Watertight>::new(self).any_packet(rays)
    }
    #[inline]
    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        Using::<_, Watertight>::new(self).all_packet(rays, f)
    }
}

// ---- planes ----

/// The one ray–plane kernel ([`plane`]); the only kernel of [`Using`] over planes.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlaneTest;

/// The plane test with culling: under [`Cull::Back`], only `d·n < 0` (3 mul, 2 add, 1 cmp).
#[inline(always)]
fn plane_hit<L: Lane>(r: &RayPacket<L>, p: &Plane, cull: Cull) -> LaneHit<L> {
    let p = PlanePacket::splat(p);
    let h = plane::intersect_lanes(r, &p);
    if cull.back() && h.mask.any() {
        let front = r.dir.dot(p.normal).lt(L::from_f32(0.0));
        LaneHit::new(h.t, h.u, h.v, h.mask & front)
    } else {
        h
    }
}

/// Planes: N rays × 1 plane in slice order (a plane is crossed at most once); `all` in
/// slice order.
impl Query for Using<'_, [Plane], PlaneTest> {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        let cull = self.cull;
        let best = hit::closest(rays, self.set, |r, p| Some(plane_hit(r, p, cull)));
        Hits::from_planes(rays, &best, cull, |i| self.set.get(i as usize).copied())
    }

    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        let cull = self.cull;
        hit::any(rays, self.set, |r, p| Some(plane_hit(r, p, cull)))
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        for (i, p) in self.set.iter().enumerate() {
            let h = plane_hit(rays, p, self.cull);
            if h.mask.any() {
                let best = Best::single(&h, i as u32);
                f(&Hits::from_planes(rays, &best, self.cull, |_| Some(*p)));
            }
        }
    }
}

/// Planes with the one plane test (two-sided).
impl Query for [Plane] {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        Using::<_, PlaneTest>::new(self).closest_packet(rays)
    }
    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        Using::<_, PlaneTest>::new(self).any_packet(rays)
    }
    #[inline]
    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        Using::<_, PlaneTest>::new(self).all_packet(rays, f)
    }
}

// ---- scenes ----

/// Scenes as tuples of sets: `set` is the position in the tuple. `closest` queries the sets
/// in order, each with the rays' `t_max` shrunk to (a relaxed bound of) the best hit so far,
/// and keeps a later set's hit only when strictly closer (ties to the earlier set); `any`
/// stops once every valid lane has hit; `all` reports set 0's hits, then set 1's, ...
macro_rules! scene {
    ($($q:ident $i:tt),+) => {
        impl<$($q: Query),+> Query for ($($q,)+) {
            #[inline]
            fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
                let mut best = Hits::<L>::miss();
                $(
                    let r = rays.shrink(best.mask, hit::relax(best.t));
                    best.merge(&self.$i.closest_packet(&r).with_set($i));
                )+
                best
            }

            #[inline]
            fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
                let valid = rays.valid();
                let mut hit = L::Mask::splat(false);
                $(
                    if valid.and_not(hit).any() {
                        hit = hit | self.$i.any_packet(rays);
                    }
                )+
                hit & valid
            }

            fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
                $(
                    self.$i.all_packet(rays, &mut |h: &Hits<L>| f(&h.with_set($i)));
                )+
            }
        }
    };
}

scene!(A 0, B 1);
scene!(A 0, B 1, C 2);
scene!(A 0, B 1, C 2, D 3);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_records() {
        let s = [Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0)];
        let out = Ray::new(Vec3::ZERO, -Vec3::Z);
        let h = s.closest(&out).unwrap();
        assert_eq!(h.t, 4.0);
        assert_eq!(h.point, Vec3::new(0.0, 0.0, -4.0));
        assert_eq!(h.normal, Vec3::Z);
        assert!(h.front);
        assert_eq!((h.index, h.set, h.u, h.v), (0, 0, 0.0, 0.0));
        // From inside: the exit, a back face, normal facing the origin (inward).
        let inside = Ray::new(Vec3::new(0.0, 0.0, -5.0), -Vec3::Z);
        let h = s.closest(&inside).unwrap();
        assert_eq!((h.t, h.front, h.normal), (1.0, false, Vec3::Z));
        assert_eq!(
            s.using::<Robust>().culled(Cull::Back).closest(&inside),
            None
        );
        let mut n = 0;
        s.all(&out, |h| {
            assert_eq!(h.front, n == 0);
            n += 1;
        });
        assert_eq!(n, 2);
        assert!(s.any(&out));
        assert!(!s.any(&Ray::new(Vec3::ZERO, Vec3::Z)));
    }

    #[test]
    fn triangle_records() {
        let t = [Triangle::new(
            Vec3::ZERO,
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 3.0, 0.0),
        )];
        let down = Ray::new(Vec3::new(1.0, 1.0, 5.0), -Vec3::Z);
        let h = t.closest(&down).unwrap();
        assert_eq!((h.t, h.u), (5.0, 0.25));
        assert_eq!(h.point, Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(h.normal, Vec3::Z);
        assert!(h.front);
        let up = Ray::new(Vec3::new(1.0, 1.0, -5.0), Vec3::Z);
        let h = t.closest(&up).unwrap();
        assert_eq!((h.front, h.normal), (false, -Vec3::Z));
        let culled = t.using::<Watertight>().culled(Cull::Back);
        assert_eq!(culled.closest(&up), None);
        assert!(culled.closest(&down).unwrap().front);
    }

    #[test]
    fn plane_records() {
        let p = [Plane::new(
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(0.0, 3.0, 0.0),
        )];
        let h = p.closest(&Ray::new(Vec3::ZERO, Vec3::Y)).unwrap();
        assert_eq!((h.t, h.front, h.normal), (2.0, false, -Vec3::Y));
        let h = p
            .closest(&Ray::new(Vec3::new(0.0, 4.0, 0.0), -Vec3::Y))
            .unwrap();
        assert_eq!((h.t, h.front, h.normal), (2.0, true, Vec3::Y));
        assert_eq!(
            p.using::<PlaneTest>()
                .culled(Cull::Back)
                .closest(&Ray::new(Vec3::ZERO, Vec3::Y)),
            None
        );
    }

    #[test]
    fn unit_kernels_miss_non_unit_directions() {
        use crate::sphere::Geometric;
        let s = [Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0)];
        let g = s.using::<Geometric>();
        assert_eq!(g.closest(&Ray::new(Vec3::ZERO, -Vec3::Z)).unwrap().t, 4.0);
        assert_eq!(g.closest(&Ray::new(Vec3::ZERO, -2.0 * Vec3::Z)), None);
        assert!(!g.any(&Ray::new(Vec3::ZERO, -2.0 * Vec3::Z)));
    }

    #[test]
    fn scenes_merge_sets() {
        let s = [Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0)];
        let p = [Plane::new(Vec3::new(0.0, 0.0, -3.0), Vec3::Z)];
        let ray = Ray::new(Vec3::ZERO, -Vec3::Z);
        let h = (&s[..], &p[..]).closest(&ray).unwrap();
        assert_eq!((h.set, h.t, h.index), (1, 3.0, 0));
        let h = (&p[..], &s[..]).closest(&ray).unwrap();
        assert_eq!((h.set, h.t), (0, 3.0));
        let mut sets = [0u32; 2];
        (&s[..], &p[..]).all(&ray, |h| sets[h.set as usize] += 1);
        assert_eq!(sets, [2, 1]);
        let far = Ray::with_interval(Vec3::ZERO, -Vec3::Z, 0.0, 3.5);
        assert_eq!((&s[..], &p[..]).closest(&far).unwrap().set, 1);
    }

    #[test]
    fn tiny_and_huge_normals_are_unit() {
        let e = 1e-11;
        let t = [Triangle::new(
            Vec3::ZERO,
            Vec3::new(e, 0.0, 0.0),
            Vec3::new(0.0, e, 0.0),
        )];
        let h = t
            .closest(&Ray::new(Vec3::new(e / 4.0, e / 4.0, 1.0), -Vec3::Z))
            .unwrap();
        assert_eq!(h.normal, Vec3::Z);
        let s = [Sphere::new(Vec3::ZERO, 1e30)];
        let h = s
            .closest(&Ray::new(Vec3::new(0.0, 0.0, 3e30), -Vec3::Z))
            .unwrap();
        assert_eq!(h.normal, Vec3::Z);
    }
}
