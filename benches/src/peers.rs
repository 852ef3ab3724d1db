//! The peer libraries on a [`Frame`]: each holds the frame's primitives and rays converted once
//! to its own types (parry3d and bevy use glam 0.33, obvhs glam 0.34's `Vec3A`), and runs the
//! same closest-hit query raylane's loops run: every ray against every primitive, keeping the
//! nearest hit (ties to the lower index), the search interval shrinking to the best `t`.
//!
//! * parry3d 0.31: `Ball::cast_local_ray` on the ray moved into the ball's frame (3
//!   subtractions; `cast_ray` with a `Pose` would also rotate it) and
//!   `Triangle::cast_local_ray` (two-sided).
//! * bevy 0.20 (`bevy_shape`, where the bounding volumes moved from `bevy_math`):
//!   `RayCast3d::sphere_intersection_at(&BoundingSphere)`.
//! * obvhs 0.4: `Triangle::intersect` (Möller–Trumbore, two-sided). Not `intersect_embree`,
//!   which returns `t` scaled by `|N·d|`.
//!
//! Each `frame` is out of line, as raylane's are.

use std::hint::black_box;

use crate::Frame;

/// A peer library holding a frame's primitives and rays in its own types.
pub trait Peer {
    /// The peer's ray type.
    type Ray;

    /// The frame's rays, converted.
    fn rays(&self) -> &[Self::Ray];

    /// The closest hit of one ray over every primitive: `(t, index)`.
    fn closest(&self, ray: &Self::Ray) -> Option<(f32, u32)>;

    /// One frame; returns the number of rays hit. Out of line, one copy per peer.
    #[inline(never)]
    fn frame(&self) -> u32 {
        let mut n = 0;
        for r in self.rays() {
            let h = self.closest(black_box(r));
            n += h.is_some() as u32;
            black_box(&h);
        }
        n
    }

    /// The closest hit of every ray.
    fn answers(&self) -> Vec<Option<(f32, u32)>> {
        self.rays().iter().map(|r| self.closest(r)).collect()
    }
}

/// parry3d's glam (0.33) vector from ours (0.34).
fn pv(v: glam::Vec3) -> parry3d::math::Vector {
    parry3d::math::Vector::new(v.x, v.y, v.z)
}

/// bevy's glam (0.33) vector from ours.
fn bv(v: glam::Vec3) -> bevy_math::Vec3A {
    bevy_math::Vec3A::new(v.x, v.y, v.z)
}

/// parry3d: balls and rays.
pub struct ParryBalls {
    balls: Vec<(parry3d::math::Vector, parry3d::shape::Ball)>,
    rays: Vec<parry3d::query::Ray>,
}

impl ParryBalls {
    /// From a frame's spheres and rays.
    pub fn new(f: &Frame) -> Self {
        use parry3d::shape::Ball;
        ParryBalls {
            balls: f
                .spheres
                .iter()
                .map(|s| (pv(s.center()), Ball::new(s.radius())))
                .collect(),
            rays: f
                .rays
                .iter()
                .map(|r| parry3d::query::Ray::new(pv(r.origin()), pv(r.dir())))
                .collect(),
        }
    }
}

impl Peer for ParryBalls {
    type Ray = parry3d::query::Ray;

    fn rays(&self) -> &[parry3d::query::Ray] {
        &self.rays
    }

    #[inline(always)]
    fn closest(&self, ray: &parry3d::query::Ray) -> Option<(f32, u32)> {
        use parry3d::query::{Ray, RayCast};
        let mut best = f32::MAX;
        let mut hit = None;
        for (i, (c, ball)) in self.balls.iter().enumerate() {
            let local = Ray::new(ray.origin - *c, ray.dir);
            if let Some(t) = ball.cast_local_ray(&local, best, true)
                && t < best
            {
                best = t;
                hit = Some((t, i as u32));
            }
        }
        hit
    }
}

/// parry3d: triangles and rays.
pub struct ParryTriangles {
    tris: Vec<parry3d::shape::Triangle>,
    rays: Vec<parry3d::query::Ray>,
}

impl ParryTriangles {
    /// From a frame's triangles and rays.
    pub fn new(f: &Frame) -> Self {
        ParryTriangles {
            tris: f
                .tris
                .iter()
                .map(|t| parry3d::shape::Triangle::new(pv(t.a()), pv(t.b()), pv(t.c())))
                .collect(),
            rays: f
                .rays
                .iter()
                .map(|r| parry3d::query::Ray::new(pv(r.origin()), pv(r.dir())))
                .collect(),
        }
    }
}

impl Peer for ParryTriangles {
    type Ray = parry3d::query::Ray;

    fn rays(&self) -> &[parry3d::query::Ray] {
        &self.rays
    }

    #[inline(always)]
    fn closest(&self, ray: &parry3d::query::Ray) -> Option<(f32, u32)> {
        use parry3d::query::RayCast;
        let mut best = f32::MAX;
        let mut hit = None;
        for (i, t) in self.tris.iter().enumerate() {
            if let Some(t) = t.cast_local_ray(ray, best, true)
                && t < best
            {
                best = t;
                hit = Some((t, i as u32));
            }
        }
        hit
    }
}

/// bevy: bounding spheres and ray casts.
pub struct BevySpheres {
    spheres: Vec<bevy_shape::BoundingSphere>,
    rays: Vec<bevy_shape::RayCast3d>,
}

impl BevySpheres {
    /// From a frame's spheres and rays (unit directions, as `Dir3A` requires).
    pub fn new(f: &Frame) -> Self {
        use bevy_math::Dir3A;
        use bevy_shape::{BoundingSphere, RayCast3d};
        BevySpheres {
            spheres: f
                .spheres
                .iter()
                .map(|s| BoundingSphere::new(bv(s.center()), s.radius()))
                .collect(),
            rays: f
                .rays
                .iter()
                .map(|r| {
                    RayCast3d::new(bv(r.origin()), Dir3A::new_unchecked(bv(r.dir())), f32::MAX)
                })
                .collect(),
        }
    }
}

impl Peer for BevySpheres {
    type Ray = bevy_shape::RayCast3d;

    fn rays(&self) -> &[bevy_shape::RayCast3d] {
        &self.rays
    }

    #[inline(always)]
    fn closest(&self, ray: &bevy_shape::RayCast3d) -> Option<(f32, u32)> {
        let mut ray = ray.clone();
        let mut hit = None;
        for (i, s) in self.spheres.iter().enumerate() {
            if let Some(t) = ray.sphere_intersection_at(s)
                && hit.is_none_or(|(best, _)| t < best)
            {
                ray.max = t;
                hit = Some((t, i as u32));
            }
        }
        hit
    }
}

/// obvhs: triangles and rays.
pub struct ObvhsTriangles {
    tris: Vec<obvhs::triangle::Triangle>,
    rays: Vec<obvhs::ray::Ray>,
}

impl ObvhsTriangles {
    /// From a frame's triangles and rays.
    pub fn new(f: &Frame) -> Self {
        use glam::Vec3A;
        ObvhsTriangles {
            tris: f
                .tris
                .iter()
                .map(|t| obvhs::triangle::Triangle {
                    v0: Vec3A::from(t.a()),
                    v1: Vec3A::from(t.b()),
                    v2: Vec3A::from(t.c()),
                })
                .collect(),
            rays: f
                .rays
                .iter()
                .map(|r| obvhs::ray::Ray::new_inf(Vec3A::from(r.origin()), Vec3A::from(r.dir())))
                .collect(),
        }
    }
}

impl Peer for ObvhsTriangles {
    type Ray = obvhs::ray::Ray;

    fn rays(&self) -> &[obvhs::ray::Ray] {
        &self.rays
    }

    #[inline(always)]
    fn closest(&self, ray: &obvhs::ray::Ray) -> Option<(f32, u32)> {
        let mut ray = *ray;
        let mut hit = None;
        for (i, t) in self.tris.iter().enumerate() {
            let t = t.intersect(&ray);
            if t < ray.tmax && hit.is_none_or(|(best, _)| t < best) {
                ray.tmax = t;
                hit = Some((t, i as u32));
            }
        }
        hit
    }
}
