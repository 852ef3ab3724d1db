//! Ray–plane intersection (lecture 002).
//!
//! A plane through the point `a` with normal `n` holds the points `p` with `(p − a)·n = 0`.
//! Substituting the ray `o + t·d`:
//!
//! ```text
//! t = ((a − o)·n) / (d·n)
//! ```
//!
//! **Operation count per lane**, hit or miss: `ops plane/miss: 6 mul, 7 add, 1 div, 2 cmp`,
//! `ops plane/hit: 6 mul, 7 add, 1 div, 2 cmp`. The focal variant ([`FocalPlane`]) caches
//! the numerator `(a − E)·n` per plane for rays from the eye `E`:
//! `ops plane-focal/miss: 3 mul, 2 add, 1 div, 2 cmp` per ray, the same on a hit.
//!
//! **Edge cases.** A ray parallel to the plane (`d·n = 0`) gives `t = ±inf` or NaN, which fails
//! the interval test: a miss, including the ray that lies in the plane. A zero or non-finite
//! normal or point gives a miss the same way (NaN or infinite `t`). Planes are two-sided.
//! Directions need not be unit (`t` is in units of `|d|`).

use glam::Vec3;

use crate::kernel::{Cull, Kernel, LaneHit, Primitive};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// A plane through `point` with normal `normal` (any length; zero means never hit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// A point of the plane.
    pub point: Vec3,
    /// The normal (need not be unit length).
    pub normal: Vec3,
}

impl Plane {
    /// The plane through `point` with normal `normal`.
    #[inline]
    #[must_use]
    pub fn new(point: Vec3, normal: Vec3) -> Self {
        Plane { point, normal }
    }
}

/// Planes in lanes (structure of arrays).
#[derive(Clone, Copy, Debug)]
pub struct PlanePacket<L: Lane> {
    /// A point of each plane.
    pub point: V3<L>,
    /// Each normal.
    pub normal: V3<L>,
}

impl<L: Lane> PlanePacket<L> {
    /// The same plane in every lane.
    #[inline(always)]
    #[must_use]
    pub fn splat(p: &Plane) -> Self {
        PlanePacket {
            point: V3::splat(p.point),
            normal: V3::splat(p.normal),
        }
    }

    /// Up to `L::LANES` planes, one per lane; missing lanes never hit (zero normal).
    #[must_use]
    pub fn from_planes(planes: &[Plane]) -> Self {
        let get = |i: usize| {
            planes
                .get(i)
                .copied()
                .unwrap_or(Plane::new(Vec3::ZERO, Vec3::ZERO))
        };
        PlanePacket {
            point: V3::from_fn(
                #[cfg_attr(target_arch = "x86_64", inline(always))]
                |i| get(i).point,
            ),
            normal: V3::from_fn(
                #[cfg_attr(target_arch = "x86_64", inline(always))]
                |i| get(i).normal,
            ),
        }
    }
}

/// The ray–plane test: `t = ((a − o)·n)/(d·n)` inside the ray's interval.
#[inline(always)]
#[must_use]
pub fn intersect_lanes<L: Lane>(ray: &RayPacket<L>, p: &PlanePacket<L>) -> LaneHit<L> {
    // 1. Numerator: signed distance of the origin, scaled by |n|.
    let num = (p.point - ray.origin).dot(p.normal);
    // 2. The focal part: the same per-ray test with the numerator given.
    focal_lanes(ray, num, p.normal)
}

/// The per-ray part shared with the focal variant: `t = num/(d·n)` and the interval test
/// (3 mul, 2 add, 1 div, 2 cmp), with the numerator `num = (a − E)·n` given per lane.
#[inline(always)]
#[must_use]
pub fn focal_lanes<L: Lane>(ray: &RayPacket<L>, num: L, normal: V3<L>) -> LaneHit<L> {
    // Denominator; parallel rays give t = ±inf or NaN, which fails the interval test.
    let den = ray.dir.dot(normal);
    let t = num / den;
    let hit = t.gt(ray.t_min) & t.lt(ray.t_max);
    let zero = L::from_f32(0.0);
    LaneHit::new(t, zero, zero, hit)
}

/// A plane as seen from one focal point: the cached numerator `(a − E)·n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FocalPlane {
    num: f32,
    normal: Vec3,
}

impl FocalPlane {
    /// Caches `(a − E)·n` for rays from `eye` (computed exactly as [`intersect_lanes`] does, so
    /// both give the same bits).
    #[inline]
    #[must_use]
    pub fn new(eye: Vec3, plane: &Plane) -> Self {
        let num = (V3::<f32>::from(plane.point) - V3::from(eye)).dot(plane.normal.into());
        FocalPlane {
            num,
            normal: plane.normal,
        }
    }

    /// The plane's normal.
    #[inline]
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// The cached numerator `(a − E)·n`.
    #[inline]
    #[must_use]
    pub fn num(&self) -> f32 {
        self.num
    }

    /// The per-ray test for ray lanes starting at the cache's eye: 3 mul, 2 add, 1 div, 2 cmp.
    #[inline(always)]
    #[must_use]
    pub fn intersect_lanes<L: Lane>(&self, ray: &RayPacket<L>) -> LaneHit<L> {
        focal_lanes(ray, L::from_f32(self.num), V3::splat(self.normal))
    }
}

impl Primitive for Plane {
    type Packet<L: Lane> = PlanePacket<L>;
    #[inline(always)]
    fn splat<L: Lane>(&self) -> PlanePacket<L> {
        PlanePacket::splat(self)
    }
}

/// The one ray–plane kernel ([`intersect_lanes`]), as the [`Kernel`] of planes; under
/// [`Cull::Back`] only `d·n < 0` (3 mul, 2 add, 1 cmp more).
#[derive(Clone, Copy, Debug, Default)]
pub struct PlaneTest;

impl Kernel<Plane> for PlaneTest {
    type Rays<L: Lane> = ();

    #[inline(always)]
    fn prepare<L: Lane>(_: &RayPacket<L>) {}

    #[inline(always)]
    fn first<L: Lane>(
        rays: &RayPacket<L>,
        _: &(),
        p: &PlanePacket<L>,
        cull: Cull,
    ) -> Option<LaneHit<L>> {
        let h = intersect_lanes(rays, p);
        Some(if cull.back() && h.mask.any() {
            let front = rays.dir.dot(p.normal).lt(L::from_f32(0.0));
            LaneHit::new(h.t, h.u, h.v, h.mask & front)
        } else {
            h
        })
    }
}
