//! Rays and ray packets.
//!
//! A ray is an origin `o`, a direction `d` and an open interval `(t_min, t_max)`: a hit at
//! parameter `t` (the point `o + t·d`) counts only when `t_min < t < t_max`. Directions need not
//! be unit length unless a method says so ([`Geometric`](crate::sphere::Geometric),
//! [`QuadraticUnit`](crate::sphere::QuadraticUnit) and the focal caches do); `t` is measured in
//! units of `|d|`.
//!
//! Constructors sanitise bad input once, so kernels need no per-test checks: a ray with a
//! non-finite origin or direction, a zero direction, or an interval that is empty or NaN gets
//! the empty interval `(+inf, -inf)` and every kernel reports a miss for it.

use glam::Vec3;

use crate::lane::{Lane, Scalar};
use crate::vec3::V3;

/// Largest `| |d|² − 1 |` a unit direction may have (`2^-20`): what [`Dir::new`] guarantees
/// and what the unit-direction kernels accept (others answer such rays in their own way, see
/// [`admit`](crate::kernel::admit)).
pub const UNIT_TOLERANCE: f32 = 1.0 / 1_048_576.0;

/// One ray (the scalar API type, with glam vectors).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    origin: Vec3,
    dir: Vec3,
    t_min: f32,
    t_max: f32,
}

impl Ray {
    /// A ray over the interval `(0, +inf)`.
    #[inline]
    #[must_use]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::with_interval(origin, dir, 0.0, f32::INFINITY)
    }

    /// A ray over `(0, +inf)` with a unit direction (`t` is then a distance): the rays the
    /// unit-direction kernels answer.
    #[inline]
    #[must_use]
    pub fn unit(origin: Vec3, dir: Dir) -> Self {
        Self::new(origin, dir.0)
    }

    /// A ray over `(t_min, t_max)`. Bad input (see the [module docs](self)) gives a ray that
    /// never hits.
    #[inline]
    #[must_use]
    pub fn with_interval(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        let p = RayPacket::<f32>::new(origin.into(), dir.into(), t_min, t_max);
        Ray {
            origin,
            dir,
            t_min: p.t_min,
            t_max: p.t_max,
        }
    }

    /// The origin.
    #[inline]
    #[must_use]
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// The direction (as given; not normalised).
    #[inline]
    #[must_use]
    pub fn dir(&self) -> Vec3 {
        self.dir
    }

    /// Lower end of the open interval.
    #[inline]
    #[must_use]
    pub fn t_min(&self) -> f32 {
        self.t_min
    }

    /// Upper end of the open interval.
    #[inline]
    #[must_use]
    pub fn t_max(&self) -> f32 {
        self.t_max
    }

    /// False for rays that were sanitised to the empty interval.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.t_min < self.t_max
    }

    /// The point `o + t·d`.
    #[inline]
    #[must_use]
    pub fn at(&self, t: f32) -> Vec3 {
        V3::<f32>::from(self.origin)
            .along(self.dir.into(), t)
            .into()
    }

    /// The same ray over `(t_min, t_max)` (sanitised again).
    #[inline]
    #[must_use]
    pub fn with_t_max(self, t_max: f32) -> Self {
        Self::with_interval(self.origin, self.dir, self.t_min, t_max)
    }
}

/// A unit direction: what the unit-direction kernels ([`Geometric`](crate::sphere::Geometric),
/// [`QuadraticUnit`](crate::sphere::QuadraticUnit), the sphere focal caches) need. Made by
/// [`Dir::new`], whose `v/|v|` (correctly rounded `sqrt` and divisions) is checked to satisfy
/// `||d|² − 1| ≤ 2^-20`; use it with [`Ray::unit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dir(Vec3);

impl Dir {
    /// +x.
    pub const X: Dir = Dir(Vec3::X);
    /// +y.
    pub const Y: Dir = Dir(Vec3::Y);
    /// +z.
    pub const Z: Dir = Dir(Vec3::Z);
    /// −x.
    pub const NEG_X: Dir = Dir(Vec3::NEG_X);
    /// −y.
    pub const NEG_Y: Dir = Dir(Vec3::NEG_Y);
    /// −z.
    pub const NEG_Z: Dir = Dir(Vec3::NEG_Z);

    /// `v/|v|`, or `None` for a zero or non-finite `v`. `v` is first divided by its largest
    /// `|component|` so that no square over- or underflows (at most 3 div, 3 mul, 2 add,
    /// 1 sqrt, 3 div).
    #[must_use]
    pub fn new(v: Vec3) -> Option<Dir> {
        let m = v.abs().max_element();
        if !(v.is_finite() && m > 0.0) {
            return None;
        }
        let w = V3::<f32>::from(v / m);
        let d = w.div_by(crate::lane::sqrt_f32(w.length_squared()));
        let ok = (d.length_squared() - 1.0).abs() <= UNIT_TOLERANCE;
        ok.then_some(Dir(d.into()))
    }

    /// The vector.
    #[inline]
    #[must_use]
    pub fn get(self) -> Vec3 {
        self.0
    }
}

impl From<Dir> for Vec3 {
    #[inline]
    fn from(d: Dir) -> Vec3 {
        d.0
    }
}

/// Rays in lanes (structure of arrays): lane `i` of every field is ray `i`.
///
/// `RayPacket<f32>` is one ray, `RayPacket<f32x8>` eight. Build packets with [`new`](Self::new),
/// [`splat`](Self::splat), [`from_rays`](Self::from_rays) or a
/// [`Pinhole`](crate::camera::Pinhole) camera.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket<L: Lane> {
    pub(crate) origin: V3<L>,
    pub(crate) dir: V3<L>,
    pub(crate) t_min: L,
    pub(crate) t_max: L,
}

/// Four rays in `f32x4` lanes.
pub type Ray4 = RayPacket<wide::f32x4>;
/// Eight rays in `f32x8` lanes.
pub type Ray8 = RayPacket<wide::f32x8>;
/// Sixteen rays in `f32x16` lanes.
pub type Ray16 = RayPacket<wide::f32x16>;

impl<L: Lane> RayPacket<L> {
    /// Rays from lane values; lanes with bad input get the empty interval (never hit).
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    #[must_use]
    pub fn new(origin: V3<L>, dir: V3<L>, t_min: L, t_max: L) -> Self {
        let zero = L::from_f32(0.0);
        let nonzero = dir.x.abs().gt(zero) | dir.y.abs().gt(zero) | dir.z.abs().gt(zero);
        let valid = origin.is_finite() & dir.is_finite() & nonzero & t_min.lt(t_max);
        RayPacket {
            origin,
            dir,
            t_min: L::select(valid, t_min, L::from_f32(f32::INFINITY)),
            t_max: L::select(valid, t_max, L::from_f32(f32::NEG_INFINITY)),
        }
    }

    /// The same ray in every lane.
    #[inline]
    #[must_use]
    pub fn splat(ray: &Ray) -> Self {
        RayPacket {
            origin: V3::splat(ray.origin),
            dir: V3::splat(ray.dir),
            t_min: L::from_f32(ray.t_min),
            t_max: L::from_f32(ray.t_max),
        }
    }

    /// Up to `L::LANES` rays, one per lane; lanes beyond `rays.len()` never hit.
    #[must_use]
    pub fn from_rays(rays: &[Ray]) -> Self {
        let n = rays.len().min(L::LANES);
        let get = |i: usize| if i < n { Some(rays[i]) } else { None };
        RayPacket {
            origin: V3::from_fn(|i| get(i).map_or(Vec3::ZERO, |r| r.origin)),
            dir: V3::from_fn(|i| get(i).map_or(Vec3::ZERO, |r| r.dir)),
            t_min: L::from_f32_fn(|i| get(i).map_or(f32::INFINITY, |r| r.t_min)),
            t_max: L::from_f32_fn(|i| get(i).map_or(f32::NEG_INFINITY, |r| r.t_max)),
        }
    }

    /// The origins.
    #[inline]
    #[must_use]
    pub fn origin(&self) -> V3<L> {
        self.origin
    }

    /// The directions.
    #[inline]
    #[must_use]
    pub fn dir(&self) -> V3<L> {
        self.dir
    }

    /// Lower ends of the intervals.
    #[inline]
    #[must_use]
    pub fn t_min(&self) -> L {
        self.t_min
    }

    /// Upper ends of the intervals.
    #[inline]
    #[must_use]
    pub fn t_max(&self) -> L {
        self.t_max
    }

    /// The same rays with upper ends replaced where `mask` is set (used by closest-hit loops
    /// to shrink the interval as hits are found).
    #[inline(always)]
    #[must_use]
    pub fn shrink(&self, mask: L::Mask, t: L) -> Self {
        RayPacket {
            t_max: L::select(mask, t, self.t_max),
            ..*self
        }
    }

    /// True in lanes whose interval is not empty.
    #[inline]
    #[must_use]
    pub fn valid(&self) -> L::Mask {
        self.t_min.lt(self.t_max)
    }

    /// Lane `i` as a scalar ray (for `f32` lanes).
    #[inline]
    #[must_use]
    pub fn ray(&self, i: usize) -> Ray
    where
        L: Lane<Scalar = f32>,
    {
        Ray {
            origin: self.origin.lane(i),
            dir: self.dir.lane(i),
            t_min: self.t_min.lane(i),
            t_max: self.t_max.lane(i),
        }
    }

    /// Lane `i` as a scalar ray, its values rounded to `f32` (exact for [`Lane::PLAIN_F32`]
    /// lanes, whose values are `f32`).
    #[inline(always)]
    pub(crate) fn lane_ray(&self, i: usize) -> Ray {
        let f = |x: L| x.lane(i).to_f64() as f32;
        let v = |p: &V3<L>| Vec3::new(f(p.x), f(p.y), f(p.z));
        Ray {
            origin: v(&self.origin),
            dir: v(&self.dir),
            t_min: f(self.t_min),
            t_max: f(self.t_max),
        }
    }

    /// Lane `i` as a single higher-precision ray (exact widening; for fallbacks).
    #[inline]
    #[must_use]
    pub fn precise_lane(&self, i: usize) -> RayPacket<L::Precise> {
        RayPacket {
            origin: self.origin.precise_lane(i),
            dir: self.dir.precise_lane(i),
            t_min: self.t_min.precise_lane(i),
            t_max: self.t_max.precise_lane(i),
        }
    }
}

impl From<Ray> for RayPacket<f32> {
    #[inline]
    fn from(r: Ray) -> Self {
        RayPacket::splat(&r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_rays_get_the_empty_interval() {
        let o = Vec3::ZERO;
        let d = Vec3::X;
        assert!(Ray::new(o, d).is_valid());
        assert!(!Ray::new(o, Vec3::ZERO).is_valid());
        assert!(!Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), d).is_valid());
        assert!(!Ray::new(o, Vec3::new(0.0, f32::INFINITY, 0.0)).is_valid());
        assert!(!Ray::with_interval(o, d, 1.0, 1.0).is_valid());
        assert!(!Ray::with_interval(o, d, f32::NAN, 1.0).is_valid());
        assert!(!Ray::with_interval(o, d, 0.0, f32::NAN).is_valid());
        assert!(Ray::with_interval(o, d, f32::NEG_INFINITY, 1.0).is_valid());
    }
}
