//! Queries: one vocabulary for every set of primitives.
//!
//! [`Query`] asks any set three questions, for one [`Ray`] or for a [`RayPacket`] of any
//! width:
//!
//! * [`closest`](Query::closest): the closest hit ([`Hit`] for a ray, [`Hits`] per lane for a
//!   packet; a packet query returns the same record, lane by lane, as the one-ray query);
//! * [`any`](Query::any): whether anything is hit (occlusion; stops at the first hit);
//! * [`all`](Query::all): a callback per hit, in the order the set visits them.
//!
//! It is implemented by every set ([`Trace`]): `[Sphere]`, `[Triangle]`, `[Plane]`,
//! [`Mesh`](crate::mesh::Mesh), [`Bvh`](crate::bvh::Bvh), [`Scene`](crate::bvh::Scene), the
//! focal caches ([`crate::focal`]), tuples of up to four of them and
//! [`Sets`](crate::set::Sets), a slice of them (a scene whose hits carry the member's position
//! in [`Hit::set`]). A set of primitives uses its default kernel
//! ([`Robust`](crate::sphere::Robust) for spheres, [`Watertight`](crate::triangle::Watertight)
//! for triangles, the plane test for planes); [`using`](Query::using) names another kernel of
//! the same primitive and [`culled`](Query::culled) drops back faces, on a slice, a mesh, a
//! BVH or a scene alike:
//!
//! ```
//! use raylane::glam::Vec3;
//! use raylane::sphere::{Geometric, Sphere};
//! use raylane::triangle::{Moller, Triangle};
//! use raylane::{Cull, Query, Ray, RayPacket};
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
//! assert_eq!(tris.culled(Cull::Back).closest(&from_behind), None);
//! assert_eq!(tris.using::<Moller>().culled(Cull::Back).closest(&from_behind), None);
//!
//! // A scene: a tuple of sets; `set` says which one was hit.
//! let hit = (&spheres[..], &tris[..]).closest(&ray).unwrap();
//! assert_eq!((hit.set, hit.t), (1, 2.0));
//! ```
//!
//! A kernel of another primitive is refused when the query is written, not when it runs:
//!
//! ```compile_fail,E0277
//! use raylane::sphere::Sphere;
//! use raylane::triangle::Watertight;
//! use raylane::Query;
//!
//! let spheres = [Sphere::new(raylane::glam::Vec3::ZERO, 1.0)];
//! let _ = spheres.using::<Watertight>(); // Watertight is not a kernel of spheres
//! ```
//!
//! **Unit directions.** [`QuadraticUnit`](crate::sphere::QuadraticUnit) and
//! [`Geometric`](crate::sphere::Geometric) assume `|d| = 1`. Through a query, a ray whose
//! `|d|²` differs from 1 by more than `2^-20` is a miss for them (a documented answer, never
//! wrong roots); normalise directions first ([`Dir`](crate::Dir)).

use crate::camera::{Tile, block_lane};
use crate::hit::{All, Any, Closest, Hit, Hits};
use crate::kernel::{Cull, Kernel};
use crate::lane::{Lane, Mask, Scalar};
use crate::ray::{Ray, RayPacket};
use crate::set::{Set, Trace, Using};
use crate::simd;
use crate::vec3::V3;

/// The one query vocabulary (see the [module docs](self)): closest hit, occlusion and every
/// hit, for a ray or a packet, over any set. Every lane of a packet answer equals the one-ray
/// answer for that lane's ray, bit for bit.
pub trait Query {
    /// The closest hit of a [`Ray`] (`Option<Hit>`) or of a packet ([`Hits`]).
    fn closest<R: Rays>(&self, rays: &R) -> R::Closest;

    /// Whether a [`Ray`] (`bool`) or each lane of a packet (mask) hits anything.
    fn any<R: Rays>(&self, rays: &R) -> R::Any;

    /// Every hit of a [`Ray`] (`f(Hit)`) or of a packet (`f(Hits)`, with the lanes that hit
    /// one primitive in its `mask`).
    fn all<R: Rays>(&self, rays: &R, f: impl FnMut(R::Record));

    /// This set with kernel `K` of its primitive instead of its default (see [`Using`]).
    #[inline]
    fn using<K: Kernel<Self::Prim>>(&self) -> Using<'_, Self, K>
    where
        Self: Set,
    {
        Using::new(self)
    }

    /// This set with its default kernel, culled ([`Cull::Back`]: front faces only).
    #[inline]
    fn culled(&self, cull: Cull) -> Using<'_, Self, Self::Kernel>
    where
        Self: Set,
    {
        Using::new(self).culled(cull)
    }
}

impl<T: Trace + ?Sized> Query for T {
    #[inline]
    fn closest<R: Rays>(&self, rays: &R) -> R::Closest {
        R::closest(self, rays)
    }

    #[inline]
    fn any<R: Rays>(&self, rays: &R) -> R::Any {
        R::any(self, rays)
    }

    #[inline]
    fn all<R: Rays>(&self, rays: &R, mut f: impl FnMut(R::Record)) {
        R::all(self, rays, &mut f)
    }
}

/// What a query is asked for: one [`Ray`] or a [`RayPacket`] of any width.
pub trait Rays {
    /// The closest-hit answer: `Option<Hit>` for a ray, [`Hits`] for a packet.
    type Closest;
    /// The occlusion answer: `bool` for a ray, the lane mask for a packet.
    type Any;
    /// What [`Query::all`] passes per hit: [`Hit`] for a ray, [`Hits`] for a packet.
    type Record;
    /// `t`'s closest hit of these rays.
    fn closest<T: Trace + ?Sized>(t: &T, rays: &Self) -> Self::Closest;
    /// Whether these rays hit anything in `t`.
    fn any<T: Trace + ?Sized>(t: &T, rays: &Self) -> Self::Any;
    /// Every hit of these rays in `t`.
    fn all<T: Trace + ?Sized>(t: &T, rays: &Self, f: &mut dyn FnMut(Self::Record));
}

impl Rays for Ray {
    type Closest = Option<Hit>;
    type Any = bool;
    type Record = Hit;

    #[inline]
    fn closest<T: Trace + ?Sized>(t: &T, ray: &Ray) -> Option<Hit> {
        simd::run(
            #[inline(always)]
            || closest_ray(t, ray),
        )
    }

    #[inline]
    fn any<T: Trace + ?Sized>(t: &T, ray: &Ray) -> bool {
        simd::run(
            #[inline(always)]
            || {
                let mut c = Any::new(&RayPacket::<f32>::splat(ray));
                t.trace_ray(ray, 0, &mut c);
                c.finish()
            },
        )
    }

    #[inline]
    fn all<T: Trace + ?Sized>(t: &T, ray: &Ray, f: &mut dyn FnMut(Hit)) {
        simd::run(
            #[inline(always)]
            || {
                let packet = RayPacket::<f32>::splat(ray);
                let mut c = All::new(&packet, |h: &Hits<f32>| {
                    if let Some(h) = h.lane(0) {
                        f(h)
                    }
                });
                t.trace(&packet, 0, &mut c);
            },
        )
    }
}

/// One ray's closest hit and its record (the body [`Rays::closest`] runs at the
/// [level](crate::simd)).
#[cfg_attr(target_arch = "x86_64", inline(always))]
fn closest_ray<T: Trace + ?Sized>(t: &T, ray: &Ray) -> Option<Hit> {
    let packet = RayPacket::<f32>::splat(ray);
    let mut c = Closest::new(&packet);
    t.trace_ray(ray, 0, &mut c);
    let w = c.finish();
    if !w.mask {
        return None;
    }
    t.records(&packet, 0, &w).lane(0)
}

/// A packet's closest hits and their records, in the lanes queries run in.
#[cfg_attr(target_arch = "x86_64", inline(always))]
fn closest_packet<T: Trace + ?Sized, L: Lane>(t: &T, rays: &RayPacket<L>) -> Hits<L> {
    let mut c = Closest::new(rays);
    t.trace(rays, 0, &mut c);
    t.records(rays, 0, &c.finish())
}

/// A packet's occlusion, in the lanes queries run in.
#[cfg_attr(target_arch = "x86_64", inline(always))]
fn any_packet<T: Trace + ?Sized, L: Lane>(t: &T, rays: &RayPacket<L>) -> L::Mask {
    let mut c = Any::new(rays);
    t.trace(rays, 0, &mut c);
    c.finish()
}

/// The rays of a packet in `M`'s lanes (the same values).
#[cfg_attr(target_arch = "x86_64", inline(always))]
fn packet_in<L: Lane, M: Lane<Scalar = f32>>(r: &RayPacket<L>) -> RayPacket<M> {
    let c = |x: L| M::from_fn(|i| x.lane(i).to_f64() as f32);
    let v = |v: V3<L>| V3::new(c(v.x), c(v.y), c(v.z));
    RayPacket {
        origin: v(r.origin),
        dir: v(r.dir),
        t_min: c(r.t_min),
        t_max: c(r.t_max),
    }
}

/// A packet's records from `M`'s lanes in `L`'s (the same values).
#[cfg_attr(target_arch = "x86_64", inline(always))]
fn hits_out<L: Lane, M: Lane<Scalar = f32>>(h: &Hits<M>) -> Hits<L> {
    let c = |x: M| L::from_fn(|i| L::Scalar::from_f32(x.lane(i)));
    let v = |v: V3<M>| V3::new(c(v.x), c(v.y), c(v.z));
    let ids = |x: &M::Indices| {
        let mut out = L::indices(u32::MAX);
        for (o, i) in out.as_mut().iter_mut().zip(x.as_ref()) {
            *o = *i;
        }
        out
    };
    Hits {
        t: c(h.t),
        point: v(h.point),
        normal: v(h.normal),
        front: L::Mask::from_bits(h.front.bits()),
        index: ids(&h.index),
        set: ids(&h.set),
        u: c(h.u),
        v: c(h.v),
        mask: L::Mask::from_bits(h.mask.bits()),
    }
}

/// Packets of plain `f32` lanes run at the [level](crate::simd) chosen when the program runs,
/// in its vectors ([`simd::with_lanes`]: raylane's own AVX and AVX-512 types for 8 and 16
/// lanes on x86-64), converted in and out bit for bit; other lane types (counting, `f64`), and
/// scenes ([`Trace::LEVEL_LANES`]), run as they are.
impl<L: Lane> Rays for RayPacket<L> {
    type Closest = Hits<L>;
    type Any = L::Mask;
    type Record = Hits<L>;

    #[inline]
    fn closest<T: Trace + ?Sized>(t: &T, rays: &Self) -> Hits<L> {
        struct Q<'a, T: ?Sized, L: Lane>(&'a T, &'a RayPacket<L>);
        impl<T: Trace + ?Sized, L: Lane> simd::Packets for Q<'_, T, L> {
            type Output = Hits<L>;
            #[inline(always)]
            fn run<M: Lane<Scalar = f32>>(self) -> Hits<L> {
                hits_out(&closest_packet(self.0, &packet_in::<L, M>(self.1)))
            }
        }
        if const { L::PLAIN_F32 && T::LEVEL_LANES } {
            simd::with_lanes_of::<L, _>(Q(t, rays))
        } else {
            closest_packet(t, rays)
        }
    }

    #[inline]
    fn any<T: Trace + ?Sized>(t: &T, rays: &Self) -> L::Mask {
        struct Q<'a, T: ?Sized, L: Lane>(&'a T, &'a RayPacket<L>);
        impl<T: Trace + ?Sized, L: Lane> simd::Packets for Q<'_, T, L> {
            type Output = L::Mask;
            #[inline(always)]
            fn run<M: Lane<Scalar = f32>>(self) -> L::Mask {
                L::Mask::from_bits(any_packet(self.0, &packet_in::<L, M>(self.1)).bits())
            }
        }
        if const { L::PLAIN_F32 && T::LEVEL_LANES } {
            simd::with_lanes_of::<L, _>(Q(t, rays))
        } else {
            any_packet(t, rays)
        }
    }

    #[inline]
    fn all<T: Trace + ?Sized>(t: &T, rays: &Self, f: &mut dyn FnMut(Hits<L>)) {
        struct Q<'a, 'f, T: ?Sized, L: Lane>(
            &'a T,
            &'a RayPacket<L>,
            &'a mut dyn FnMut(Hits<L>),
            core::marker::PhantomData<&'f ()>,
        );
        impl<T: Trace + ?Sized, L: Lane> simd::Packets for Q<'_, '_, T, L> {
            type Output = ();
            #[inline(always)]
            fn run<M: Lane<Scalar = f32>>(self) {
                let f = self.2;
                let r = packet_in::<L, M>(self.1);
                let mut c = All::new(&r, |h: &Hits<M>| f(hits_out(h)));
                self.0.trace(&r, 0, &mut c);
            }
        }
        if const { L::PLAIN_F32 && T::LEVEL_LANES } {
            simd::with_lanes_of::<L, _>(Q(t, rays, f, core::marker::PhantomData))
        } else {
            let mut c = All::new(rays, |h: &Hits<L>| f(*h));
            t.trace(rays, 0, &mut c);
        }
    }
}

/// A tile's query: in the [level](crate::simd)'s lanes, entered once for the whole tile, or
/// (scenes, [`Trace::LEVEL_LANES`]) in the tile's own.
#[inline(always)]
fn tile_entry<T: Trace + ?Sized, L: Lane<Scalar = f32>, F: simd::Packets>(f: F) -> F::Output {
    if const { T::LEVEL_LANES } {
        simd::with_lanes_of::<L, F>(f)
    } else {
        f.run::<L>()
    }
}

/// A tile enters the [level](crate::simd) once, its packets in the level's vectors.
impl<L: Lane<Scalar = f32>, const W: usize, const H: usize> Rays for Tile<'_, L, W, H> {
    type Closest = [[Option<Hit>; W]; H];
    type Any = [[bool; W]; H];
    /// The pixel `(x, y)` of the image and its hit.
    type Record = (u32, u32, Hit);

    #[inline]
    fn closest<T: Trace + ?Sized>(t: &T, tile: &Self) -> [[Option<Hit>; W]; H] {
        struct Q<'a, 't, T: ?Sized, L: Lane, const W: usize, const H: usize>(
            &'a T,
            &'a Tile<'t, L, W, H>,
        );
        impl<T: Trace + ?Sized, L: Lane<Scalar = f32>, const W: usize, const H: usize> simd::Packets
            for Q<'_, '_, T, L, W, H>
        {
            type Output = [[Option<Hit>; W]; H];
            #[inline(always)]
            fn run<M: Lane<Scalar = f32>>(self) -> Self::Output {
                let mut out = [[None; W]; H];
                for k in 0..Tile::<L, W, H>::BLOCKS {
                    let (dx, dy, rays) = self.1.block_in::<M>(k);
                    let hits = closest_packet(self.0, &rays);
                    for i in 0..L::LANES {
                        let (px, py) = block_lane::<L>(i);
                        out[dy + py][dx + px] = hits.lane(i);
                    }
                }
                out
            }
        }
        tile_entry::<T, L, _>(Q(t, tile))
    }

    #[inline]
    fn any<T: Trace + ?Sized>(t: &T, tile: &Self) -> [[bool; W]; H] {
        struct Q<'a, 't, T: ?Sized, L: Lane, const W: usize, const H: usize>(
            &'a T,
            &'a Tile<'t, L, W, H>,
        );
        impl<T: Trace + ?Sized, L: Lane<Scalar = f32>, const W: usize, const H: usize> simd::Packets
            for Q<'_, '_, T, L, W, H>
        {
            type Output = [[bool; W]; H];
            #[inline(always)]
            fn run<M: Lane<Scalar = f32>>(self) -> Self::Output {
                let mut out = [[false; W]; H];
                for k in 0..Tile::<L, W, H>::BLOCKS {
                    let (dx, dy, rays) = self.1.block_in::<M>(k);
                    let hit = any_packet(self.0, &rays);
                    for i in 0..L::LANES {
                        let (px, py) = block_lane::<L>(i);
                        out[dy + py][dx + px] = hit.test(i);
                    }
                }
                out
            }
        }
        tile_entry::<T, L, _>(Q(t, tile))
    }

    #[inline]
    fn all<T: Trace + ?Sized>(t: &T, tile: &Self, f: &mut dyn FnMut((u32, u32, Hit))) {
        struct Q<'a, 't, T: ?Sized, L: Lane, const W: usize, const H: usize>(
            &'a T,
            &'a Tile<'t, L, W, H>,
            &'a mut dyn FnMut((u32, u32, Hit)),
        );
        impl<T: Trace + ?Sized, L: Lane<Scalar = f32>, const W: usize, const H: usize> simd::Packets
            for Q<'_, '_, T, L, W, H>
        {
            type Output = ();
            #[inline(always)]
            fn run<M: Lane<Scalar = f32>>(self) {
                let (x, y) = self.1.origin();
                let f = self.2;
                for k in 0..Tile::<L, W, H>::BLOCKS {
                    let (dx, dy, r) = self.1.block_in::<M>(k);
                    let mut c = All::new(&r, |h: &Hits<M>| {
                        for i in 0..L::LANES {
                            if let Some(hit) = h.lane(i) {
                                let (px, py) = block_lane::<L>(i);
                                f((x + (dx + px) as u32, y + (dy + py) as u32, hit));
                            }
                        }
                    });
                    self.0.trace(&r, 0, &mut c);
                }
            }
        }
        tile_entry::<T, L, _>(Q(t, tile, f))
    }
}
