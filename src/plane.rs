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

use crate::hit::{self, Best, HitRecord, LaneHit};
use crate::lane::Lane;
use crate::query::{self, Hits, Query, TooSmall};
use crate::ray::{Ray, RayPacket};
use crate::triangle::Cull;
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
            point: V3::from_fn(|i| get(i).point),
            normal: V3::from_fn(|i| get(i).normal),
        }
    }
}

/// The ray–plane test: `t = ((a − o)·n)/(d·n)` inside the ray's interval.
#[inline(always)]
#[must_use]
#[doc(hidden)]
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
#[doc(hidden)]
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

/// Closest hit of one ray and one plane.
#[inline]
#[must_use]
#[doc(hidden)]
pub fn intersect(ray: &Ray, plane: &Plane) -> Option<HitRecord> {
    intersect_lanes(&RayPacket::<f32>::splat(ray), &PlanePacket::splat(plane)).record()
}

/// Closest hit of ray lanes over a slice of planes (N rays × 1 plane).
#[inline]
#[must_use]
#[doc(hidden)]
pub fn closest<L: Lane>(rays: &RayPacket<L>, planes: &[Plane]) -> hit::Best<L> {
    hit::closest(rays, planes, |r, p| {
        Some(intersect_lanes(r, &PlanePacket::splat(p)))
    })
}

/// Lanes whose ray hits some plane (occlusion).
#[inline]
#[must_use]
#[doc(hidden)]
pub fn any<L: Lane>(rays: &RayPacket<L>, planes: &[Plane]) -> L::Mask {
    hit::any(rays, planes, |r, p| {
        Some(intersect_lanes(r, &PlanePacket::splat(p)))
    })
}

/// Every plane some lane hits: `f(index, hit)` (a plane is crossed at most once).
#[inline]
#[doc(hidden)]
pub fn all<L: Lane>(rays: &RayPacket<L>, planes: &[Plane], mut f: impl FnMut(u32, &LaneHit<L>)) {
    for (i, p) in planes.iter().enumerate() {
        let h = intersect_lanes(rays, &PlanePacket::splat(p));
        if crate::lane::Mask::any(h.mask) {
            f(i as u32, &h);
        }
    }
}

/// Closest hit of ray lanes from the eye over cached planes.
#[inline]
#[must_use]
#[doc(hidden)]
pub fn closest_focal<L: Lane>(rays: &RayPacket<L>, cache: &[FocalPlane]) -> hit::Best<L> {
    hit::closest(rays, cache, |r, p| Some(p.intersect_lanes(r)))
}

/// Closest hit of one ray over planes packed in lanes (1 ray × N planes).
#[inline]
#[must_use]
#[doc(hidden)]
pub fn closest_soa<L: Lane>(ray: &Ray, planes: &[PlanePacket<L>]) -> Option<HitRecord> {
    hit::closest_soa(ray, planes, |r, p| Some(intersect_lanes(r, p)))
}

/// A plane cache that owns its eye: through [`Query`] it answers rays that start exactly at
/// the eye; rays from elsewhere are a miss (never an answer for the wrong origin).
#[derive(Clone, Copy, Debug)]
pub struct FocalPlanes<'c> {
    eye: Vec3,
    cache: &'c [FocalPlane],
    cull: Cull,
}

impl<'c> FocalPlanes<'c> {
    /// The number of entries [`focus`](Self::focus) needs for `planes`: one per plane.
    #[inline]
    #[must_use]
    pub fn needed(planes: &[Plane]) -> usize {
        planes.len()
    }

    /// Caches `planes` for rays from `eye` into `out` (entry `i` for plane `i`); `out` shorter
    /// than [`needed`](Self::needed) is an error (nothing built).
    pub fn focus(eye: Vec3, planes: &[Plane], out: &'c mut [FocalPlane]) -> Result<Self, TooSmall> {
        let needed = Self::needed(planes);
        let Some(out) = out.get_mut(..needed) else {
            return Err(TooSmall { needed });
        };
        for (slot, p) in out.iter_mut().zip(planes) {
            *slot = FocalPlane::new(eye, p);
        }
        Ok(FocalPlanes {
            eye,
            cache: out,
            cull: Cull::None,
        })
    }

    /// The eye.
    #[inline]
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The entries.
    #[inline]
    #[must_use]
    pub fn cache(&self) -> &'c [FocalPlane] {
        self.cache
    }

    /// The same cache with [`Query`] calls culled ([`Cull::Back`]: `d·n < 0` only).
    #[inline]
    #[must_use]
    pub fn culled(self, cull: Cull) -> Self {
        FocalPlanes { cull, ..self }
    }

    /// Plane `i`'s normal, for the records.
    fn plane(&self, i: u32) -> Option<Plane> {
        let e = self.cache.get(i as usize)?;
        Some(Plane::new(Vec3::ZERO, e.normal))
    }
}

/// The focal plane test with culling (under [`Cull::Back`], `d·n < 0` only: 3 mul, 2 add,
/// 1 cmp more).
#[inline(always)]
fn focal_hit<L: Lane>(r: &RayPacket<L>, p: &FocalPlane, cull: Cull) -> LaneHit<L> {
    let h = p.intersect_lanes(r);
    if cull.back() && crate::lane::Mask::any(h.mask) {
        let front = r.dir.dot(V3::splat(p.normal)).lt(L::from_f32(0.0));
        LaneHit::new(h.t, h.u, h.v, h.mask & front)
    } else {
        h
    }
}

/// Focal planes: N rays × 1 plane, in index order; `all` in index order.
impl Query for FocalPlanes<'_> {
    #[inline]
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        let r = query::at_eye(rays, self.eye);
        let cull = self.cull;
        let best = hit::closest(&r, self.cache, |r, p| Some(focal_hit(r, p, cull)));
        Hits::from_planes(&r, &best, cull, |i| self.plane(i))
    }

    #[inline]
    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        let r = query::at_eye(rays, self.eye);
        let cull = self.cull;
        hit::any(&r, self.cache, |r, p| Some(focal_hit(r, p, cull)))
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        let r = query::at_eye(rays, self.eye);
        for (i, p) in self.cache.iter().enumerate() {
            let h = focal_hit(&r, p, self.cull);
            if crate::lane::Mask::any(h.mask) {
                let best = Best::single(&h, i as u32);
                f(&Hits::from_planes(&r, &best, self.cull, |i| self.plane(i)));
            }
        }
    }
}
