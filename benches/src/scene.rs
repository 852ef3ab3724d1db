//! Seeded scenes: the one source of every benchmark's primitives and rays.
//!
//! `no_std` and allocation-free, so that the firmware's instruction counts
//! (`targets/src/bin/bench.rs`, which includes this file with `#[path]`) run the very scenes the
//! host benchmarks and the peers see. Every generator is an iterator over a seeded xorshift
//! stream: the same seed gives the same bits on every target (only correctly rounded
//! operations: `+ − × ÷ √` on f32).
//!
//! * The camera: eye at the origin looking down −z, 60° vertical field of view.
//! * Spheres of radius 0.2–1.5, triangles of circumradius 0.4–2 (random orientation), planes
//!   (random normal), centred in the view frustum 4–40 units in front of the eye.
//! * Coherent rays: one per pixel from the eye ([`pixel_ray`]). Incoherent rays: origins
//!   uniform in the box around the frustum, aimed at random points of it ([`random_rays`]).

use glam::Vec3;
use raylane::plane::Plane;
use raylane::sphere::Sphere;
use raylane::triangle::Triangle;
use raylane::{Pinhole, Ray, RayPacket, V3};

use core::hash::Hasher as _;

/// Seed of the sphere scenes.
pub const SPHERE_SEED: u64 = 7;
/// Seed of the triangle scenes.
pub const TRIANGLE_SEED: u64 = 11;
/// Seed of the plane scenes.
pub const PLANE_SEED: u64 = 13;
/// Seed of the incoherent rays.
pub const RAY_SEED: u64 = 17;

/// A small deterministic generator (xorshift64*), so every contender sees the same scene.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * x
    }

    /// Uniform on the unit sphere (rejection from the cube; `normalize` is one correctly
    /// rounded square root and three divisions, the same bits everywhere).
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l2 = v.length_squared();
            if l2 > 1.0e-4 && l2 <= 1.0 {
                return v / raylane::lane::sqrt_f32(l2);
            }
        }
    }

    /// A point of the view frustum, 4–40 units in front of the eye; `aspect` is height/width.
    pub fn in_view(&mut self, aspect: f32) -> Vec3 {
        let z = -self.range(4.0, 40.0);
        let half = -z * 0.55;
        Vec3::new(self.range(-half, half), self.range(-half, half) * aspect, z)
    }
}

/// The benchmark camera: eye at the origin looking down −z, 60° vertical field of view.
pub fn camera(width: u32, height: u32) -> Pinhole {
    Pinhole::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, width, height)
}

/// The primary ray of pixel `(x, y)` (bit-identical to lane `x % L` of the camera's
/// `row_packet`: every lane width computes the scalar path's bits).
pub fn pixel_ray(cam: &Pinhole, x: u32, y: u32) -> Ray {
    cam.row_packet::<f32>(x, y).ray(0)
}

/// Spheres of radius 0.2–1.5 centred in the view frustum (`aspect` = height/width).
pub fn spheres(seed: u64, aspect: f32) -> impl Iterator<Item = Sphere> {
    let mut rng = Rng::new(seed);
    core::iter::repeat_with(move || {
        let c = rng.in_view(aspect);
        Sphere::new(c, rng.range(0.2, 1.5))
    })
}

/// Triangles in random orientations, vertices on a sphere of radius 0.4–2 around a centre in
/// the view frustum.
pub fn triangles(seed: u64, aspect: f32) -> impl Iterator<Item = Triangle> {
    let mut rng = Rng::new(seed);
    core::iter::repeat_with(move || {
        let c = rng.in_view(aspect);
        let s = rng.range(0.4, 2.0);
        let (a, b, d) = (rng.unit(), rng.unit(), rng.unit());
        Triangle::new(c + a * s, c + b * s, c + d * s)
    })
}

/// Planes through a point of the view frustum with a random unit normal.
pub fn planes(seed: u64, aspect: f32) -> impl Iterator<Item = Plane> {
    let mut rng = Rng::new(seed);
    core::iter::repeat_with(move || {
        let p = rng.in_view(aspect);
        Plane::new(p, rng.unit())
    })
}

/// Incoherent rays: origins uniform in the box around the view frustum
/// (`|x| ≤ 24`, `|y| ≤ 24·aspect`, `−44 ≤ z ≤ 0`), aimed at a random point of the frustum
/// (unit directions; like secondary rays bouncing inside the scene).
pub fn random_rays(seed: u64, aspect: f32) -> impl Iterator<Item = Ray> {
    let mut rng = Rng::new(seed);
    core::iter::repeat_with(move || {
        let o = Vec3::new(
            rng.range(-24.0, 24.0),
            rng.range(-24.0, 24.0) * aspect,
            rng.range(-44.0, 0.0),
        );
        let d = rng.in_view(aspect) - o;
        let l2 = d.length_squared();
        let d = if l2 > 1.0e-6 {
            d / raylane::lane::sqrt_f32(l2)
        } else {
            Vec3::Z
        };
        Ray::new(o, d)
    })
}

/// `v` as an exact `f64` vector.
fn wide(v: Vec3) -> V3<f64> {
    V3::splat(v)
}

/// True when the whole line of `ray` passes clearly outside `s` (distance from the centre
/// above 1.01 r, in f64): every sphere kernel takes its miss path.
pub fn line_misses_sphere(ray: &Ray, s: &Sphere) -> bool {
    let (o, d, c) = (wide(ray.origin()), wide(ray.dir()), wide(s.center()));
    let r = s.radius() as f64;
    let t = c - o;
    let v = t.dot(d) / d.dot(d);
    let p = t - d.scale(v);
    p.dot(p) > 1.0201 * r * r
}

/// True when the line of `ray` clearly crosses the plane of `t` outside the triangle (the
/// three edge functions of the line do not share a sign, each beyond a small margin, in f64).
pub fn line_misses_triangle(ray: &Ray, t: &Triangle) -> bool {
    let (o, d) = (wide(ray.origin()), wide(ray.dir()));
    let (a, b, c) = (wide(t.a()) - o, wide(t.b()) - o, wide(t.c()) - o);
    let e = [d.dot(a.cross(b)), d.dot(b.cross(c)), d.dot(c.cross(a))];
    let scale = e[0].abs() + e[1].abs() + e[2].abs();
    let pos = e.iter().any(|&x| x > 1e-3 * scale);
    let neg = e.iter().any(|&x| x < -1e-3 * scale);
    pos && neg && e.iter().all(|&x| x.abs() > 1e-3 * scale)
}

/// Packs `rays` into lanes, `L::LANES` at a time (the last packet padded with rays that never
/// hit), calling `f` on each packet.
pub fn for_each_packet<L: raylane::Lane>(rays: &[Ray], mut f: impl FnMut(RayPacket<L>)) {
    for chunk in rays.chunks(L::LANES) {
        f(RayPacket::from_rays(chunk));
    }
}

/// FNV-1a over the bits of a scene, to show that the host and the firmware count the same
/// scene.
#[derive(Clone, Copy, Debug)]
pub struct Digest(pub u64);

impl Default for Digest {
    fn default() -> Self {
        Digest(fnv::FnvHasher::default().finish())
    }
}

impl Digest {
    /// Adds the bits of `x` (FNV-1a).
    pub fn f32(&mut self, x: f32) {
        let mut h = fnv::FnvHasher::with_key(self.0);
        h.write(&x.to_bits().to_le_bytes());
        self.0 = h.finish();
    }

    /// Adds a vector.
    pub fn vec3(&mut self, v: Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }

    /// Adds a ray (origin, direction, interval).
    pub fn ray(&mut self, r: &Ray) {
        self.vec3(r.origin());
        self.vec3(r.dir());
        self.f32(r.t_min());
        self.f32(r.t_max());
    }

    /// Adds a sphere.
    pub fn sphere(&mut self, s: &Sphere) {
        self.vec3(s.center());
        self.f32(s.radius());
    }

    /// Adds a triangle.
    pub fn triangle(&mut self, t: &Triangle) {
        self.vec3(t.a());
        self.vec3(t.b());
        self.vec3(t.c());
    }

    /// Adds a plane.
    pub fn plane(&mut self, p: &Plane) {
        self.vec3(p.point);
        self.vec3(p.normal);
    }
}
