//! A deterministic, seeded, structured fuzzer over every public entry point and lane width
//! (issue 10, "Robustness"). It runs as an ordinary test, so overflow checks are on (the test
//! profile has them).
//!
//! **Inputs.** Each case draws a magnitude `2^e` (`e` anywhere in f32's range, weighted
//! towards ordinary scales) and builds spheres, planes, triangles and a mesh around rays that
//! are *aimed* at them (vertices, edge points, rims, centres), so hits are frequent; then
//! replaces a few coordinates by special values: zeros of either sign, subnormals, huge and
//! tiny values, NaN and ±inf. Near-degenerate geometry (collinear and repeated vertices,
//! slivers one ulp thick, zero and non-finite radii, out-of-range mesh indices) is drawn on
//! purpose.
//!
//! **Invariants.** No panic; every reported hit lies strictly inside its ray's interval and
//! has finite `t`, `u`, `v`; sphere roots are ascending; both packet shapes (N rays × 1
//! primitive and 1 ray × N primitives) return the same closest hit; every lane of every width
//! (4, 8, 16) equals the scalar path bit for bit; `any` agrees with `closest`; a mesh with its
//! Ritter bound returns what the unbounded mesh returns; pixels outside the image never give a
//! valid ray.
//!
//! **Iterations.** `RAYLANE_FUZZ_CASES` overrides the number of cases (default 3,000 on the
//! host, 300 on AArch64, whose CI run is under qemu-user); the seed is fixed (`RAYLANE_FUZZ_SEED`
//! changes it), so a failure names its case and replays.

use crate::sets::query_records_every_width::record;
use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::Cull;
use raylane::bounds::{self, Bound};
use raylane::mesh::Mesh;
use raylane::plane::{FocalPlane, Plane, PlanePacket};
use raylane::sphere::focal::{Focal, FocalKernel, FocalUnguarded};
use raylane::sphere::{
    self, FocalSphere, Geometric, Quadratic, QuadraticUnit, Robust, Roots, Sphere, SphereKernel,
    SpherePacket,
};
use raylane::triangle::{
    Cramer, FocalTriangle, Moller, Triangle, TriangleKernel, TrianglePacket, Watertight,
};
use raylane::{Hits, Lane, Mask, Pinhole, Query, Ray, RayPacket};
use raylane_lab::loops as internals;
use raylane_lab::loops::{Best, HitRecord, LaneRecords};
use wide::{f32x4, f32x8, f32x16};

/// Focal triangle hits are checked to be finite and strictly inside their interval (issue 10,
/// "Focal triangle hits outside the interval": `t = inf` for `d = 1e-40`, `t = 0` for
/// `d = 3e38`, fixed by mapping the interval into the scaled units exactly).
const CHECK_FOCAL_TRIANGLE_INTERVAL: bool = true;

/// Rays per case: one packet of the widest width.
const RAYS: usize = 16;

fn cases() -> u64 {
    let default = if cfg!(target_arch = "aarch64") {
        300
    } else {
        3_000
    };
    std::env::var("RAYLANE_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn seed() -> u64 {
    std::env::var("RAYLANE_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x00f0_22ed)
}

// ---------------------------------------------------------------------------------------------
// Inputs.

/// A special value: a signed zero, a subnormal, NaN, ±inf, ±MAX, ±MIN_POSITIVE, a huge or tiny
/// power of two, or random bits.
fn special(rng: &mut SmallRng) -> f32 {
    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    match rng.random_range(0..9) {
        0 => 0.0 * sign,
        1 => f32::from_bits(rng.random_range(1..0x0080_0000)) * sign,
        2 => f32::NAN,
        3 => f32::INFINITY * sign,
        4 => f32::MAX * sign,
        5 => f32::MIN_POSITIVE * sign,
        6 => 2f32.powi(rng.random_range(60..128)) * sign,
        7 => 2f32.powi(rng.random_range(-149..-60)) * sign,
        _ => f32::from_bits(rng.random::<u32>()),
    }
}

/// The magnitude of one case: mostly ordinary, sometimes anywhere in f32's range.
fn magnitude(rng: &mut SmallRng) -> f32 {
    match rng.random_range(0..10) {
        0..=5 => 2f32.powi(rng.random_range(-4..5)),
        6 | 7 => 2f32.powi(rng.random_range(-40..41)),
        _ => 2f32.powi(rng.random_range(-140..128)),
    }
}

struct Gen {
    rng: SmallRng,
    /// Probability that a coordinate is replaced by a special value.
    spoil: f64,
    scale: f32,
}

impl Gen {
    fn f(&mut self) -> f32 {
        if self.rng.random_bool(self.spoil) {
            special(&mut self.rng)
        } else {
            self.rng.random_range(-4.0f32..4.0) * self.scale
        }
    }
    fn v(&mut self) -> Vec3 {
        Vec3::new(self.f(), self.f(), self.f())
    }
    /// `v` with a coordinate or two spoiled now and then.
    fn spoilt(&mut self, v: Vec3) -> Vec3 {
        let mut v = v;
        for k in 0..3 {
            if self.rng.random_bool(self.spoil) {
                v[k] = special(&mut self.rng);
            }
        }
        v
    }
    /// A point on the segment `a`–`b` (exact dyadic fractions or random ones).
    fn between(&mut self, a: Vec3, b: Vec3) -> Vec3 {
        let f = match self.rng.random_range(0..4) {
            0 => 0.0,
            1 => 0.5,
            2 => 1.0,
            _ => self.rng.random_range(0.0..1.0),
        };
        a + (b - a) * f
    }
    /// A triangle, near-degenerate now and then.
    fn triangle(&mut self) -> [Vec3; 3] {
        let a = self.v();
        let b = self.v();
        let mut c = self.v();
        match self.rng.random_range(0..8) {
            0 => c = self.between(a, b),                                 // collinear
            1 => c = b,                                                  // repeated vertex
            2 => c = Vec3::new(b.x.next_up(), b.y, b.z),                 // one ulp off
            3 => c = a + (b - a) * 0.5 + Vec3::splat(f32::MIN_POSITIVE), // sliver
            _ => {}
        }
        [a, b, c]
    }
    fn sphere(&mut self) -> Sphere {
        let c = self.v();
        let r = match self.rng.random_range(0..10) {
            0 => special(&mut self.rng),
            1 => 0.0,
            _ => self.rng.random_range(0.01f32..3.0) * self.scale,
        };
        Sphere::new(c, r)
    }
    /// A ray from `o` aimed at `target`, unit or not, with an interval that is usually
    /// `(0, inf)` and sometimes narrow, negative, empty or NaN.
    fn ray(&mut self, o: Vec3, target: Vec3, unit: bool) -> Ray {
        let mut d = self.spoilt(target - o);
        if unit {
            d = d.normalize_or_zero();
        } else if self.spoil > 0.0 && self.rng.random_bool(0.2) {
            // Directions far from the positions' scale (in cases with special values).
            d *= 2f32.powi(self.rng.random_range(-100..100));
        }
        let (lo, hi) = match self.rng.random_range(0..10) {
            0 => (self.f(), self.f()),
            1 => (-1.0, 1.0),
            2 => (f32::NEG_INFINITY, f32::INFINITY),
            3 => (0.0, self.rng.random_range(0.0..3.0)),
            _ => (0.0, f32::INFINITY),
        };
        Ray::with_interval(o, d, lo, hi)
    }
}

/// One case: rays from anywhere (`rays`), rays from one eye (`eye_rays`, and `eye_units`
/// with unit directions for the focal sphere cache), and primitives they are aimed at.
#[derive(Debug)]
struct Case {
    rays: Vec<Ray>,
    eye: Vec3,
    eye_rays: Vec<Ray>,
    eye_units: Vec<Ray>,
    spheres: Vec<Sphere>,
    planes: Vec<Plane>,
    tris: Vec<Triangle>,
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
}

fn case(rng: &mut SmallRng) -> Case {
    let scale = magnitude(rng);
    let spoil = [0.0, 0.01, 0.05, 0.2][rng.random_range(0..4)];
    let mut g = Gen {
        rng: SmallRng::seed_from_u64(rng.random()),
        spoil,
        scale,
    };
    let spheres: Vec<Sphere> = (0..g.rng.random_range(1..6)).map(|_| g.sphere()).collect();
    let tris: Vec<Triangle> = (0..g.rng.random_range(1..6))
        .map(|_| {
            let [a, b, c] = g.triangle();
            Triangle::new(a, b, c)
        })
        .collect();
    let planes: Vec<Plane> = (0..g.rng.random_range(1..4))
        .map(|_| Plane::new(g.v(), g.v()))
        .collect();
    // A small mesh over shared positions, some indices out of range.
    let positions: Vec<Vec3> = (0..g.rng.random_range(3..9)).map(|_| g.v()).collect();
    let n = positions.len() as u32;
    let indices: Vec<[u32; 3]> = (0..g.rng.random_range(1..8))
        .map(|_| {
            let mut i = || {
                if g.rng.random_bool(0.05) {
                    n + g.rng.random_range(0..3)
                } else {
                    g.rng.random_range(0..n)
                }
            };
            [i(), i(), i()]
        })
        .collect();
    // Targets: vertices, edge points, sphere rims and centres, plane points.
    let mut targets: Vec<Vec3> = Vec::new();
    for t in &tris {
        let [a, b, c] = [t.a(), t.b(), t.c()];
        targets.extend([a, b, c, g.between(a, b), (a + b + c) / 3.0]);
    }
    for s in &spheres {
        let dir = Vec3::new(g.rng.random(), g.rng.random(), g.rng.random()) - 0.5;
        targets.extend([
            s.center(),
            s.center() + dir.normalize_or_zero() * s.radius(),
        ]);
    }
    targets.extend(planes.iter().map(|p| p.point));
    targets.extend(positions.iter().copied());
    let pick = |g: &mut Gen| {
        if targets.is_empty() || g.rng.random_bool(0.1) {
            g.v()
        } else {
            targets[g.rng.random_range(0..targets.len())]
        }
    };
    let rays = (0..RAYS)
        .map(|_| {
            let (o, t) = (g.v(), pick(&mut g));
            let unit = g.rng.random_bool(0.5);
            g.ray(o, t, unit)
        })
        .collect();
    let eye = if g.rng.random_bool(0.95) {
        g.v()
    } else {
        g.spoilt(Vec3::ZERO)
    };
    // Rays from the eye: any direction for triangles and planes (unit, or scaled by up to
    // 2^±140 in cases that are not ordinary), their unit versions for the focal spheres.
    let eye_rays: Vec<Ray> = (0..RAYS)
        .map(|_| {
            let t = pick(&mut g);
            let mut r = g.ray(eye, t, true);
            if g.spoil > 0.0 && g.rng.random_bool(0.3) {
                let d = r.dir() * 2f32.powi(g.rng.random_range(-140..128));
                r = Ray::with_interval(eye, d, r.t_min(), r.t_max());
            }
            r
        })
        .collect();
    let eye_units = eye_rays
        .iter()
        .map(|r| Ray::with_interval(eye, r.dir().normalize_or_zero(), r.t_min(), r.t_max()))
        .collect();
    Case {
        rays,
        eye,
        eye_rays,
        eye_units,
        spheres,
        planes,
        tris,
        positions,
        indices,
    }
}

// ---------------------------------------------------------------------------------------------
// Invariants.

/// Bits of a record, so that `-0 ≠ +0` and NaN equals itself.
fn bits(h: Option<HitRecord>) -> Option<[u32; 4]> {
    h.map(|h| [h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.index])
}

/// A hit record: finite, strictly inside the ray's interval (`interval`: check `t` too).
#[track_caller]
fn record_ok(what: &str, ray: &Ray, h: &HitRecord, interval: bool) {
    assert!(
        h.u.is_finite() && h.v.is_finite(),
        "{what}: record not finite {h:?} for {ray:?}"
    );
    if interval {
        assert!(h.t.is_finite(), "{what}: t not finite {h:?} for {ray:?}");
        assert!(
            ray.t_min() < h.t && h.t < ray.t_max(),
            "{what}: t outside the interval {h:?} for {ray:?}"
        );
    }
}

/// The sphere roots of lane `i`: ascending, finite, inside the interval.
#[track_caller]
fn roots_ok<L: Lane<Scalar = f32>>(what: &str, ray: &Ray, r: &Roots<L>, i: usize) -> Vec<u32> {
    let (t, n) = r.lane(i);
    for &t in &t[..n] {
        assert!(
            t.is_finite() && ray.t_min() < t && t < ray.t_max(),
            "{what}: root {t} for {ray:?}"
        );
    }
    if n == 2 {
        assert!(
            t[0] <= t[1],
            "{what}: roots {t:?} not ascending for {ray:?}"
        );
    }
    t[..n].iter().map(|t| t.to_bits()).collect()
}

/// The bits of `x`, with every NaN as the one canonical NaN: the sign and payload of a NaN
/// that an operation produces are not fixed by IEEE 754 (they differ between compilers, e.g.
/// rustc 1.89 and 1.95, for the camera's NaN directions), and a NaN direction is a bad ray
/// whatever its bits.
fn nan_bits(x: f32) -> u32 {
    if x.is_nan() {
        f32::NAN.to_bits()
    } else {
        x.to_bits()
    }
}

#[track_caller]
fn same<T: PartialEq + std::fmt::Debug>(what: &str, a: T, b: T) {
    assert_eq!(a, b, "{what}");
}

// ---------------------------------------------------------------------------------------------
// Spheres.

fn sphere_kernel<K: SphereKernel, L: Lane<Scalar = f32>>(c: &Case) {
    let rays = &c.rays[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    let name = K::NAME;
    // Roots, every sphere: lanes equal scalar, ascending, inside.
    for s in &c.spheres {
        let p = K::roots(&packet, &SpherePacket::splat(s));
        for (i, ray) in rays.iter().enumerate() {
            let one = K::roots(&RayPacket::<f32>::splat(ray), &SpherePacket::splat(s));
            let want = roots_ok(name, ray, &one, 0);
            same(name, roots_ok(name, ray, &p, i), want);
            let rec = internals::sphere::intersect::<K>(ray, s);
            if let Some(h) = rec {
                record_ok(name, ray, &h, true);
                // The surface of a hit: finite, unit normal.
                let sf =
                    sphere::surface(&RayPacket::<f32>::splat(ray), &SpherePacket::splat(s), h.t);
                let n = sf.normal.lane(0);
                assert!(n.is_finite(), "{name}: normal {n} for {ray:?} {s:?}");
                assert!(
                    n == Vec3::ZERO || (n.length() - 1.0).abs() < 1e-5,
                    "{name}: normal {n} for {ray:?} {s:?}"
                );
            }
        }
    }
    // Slices: closest, any, all; both packet shapes.
    let h = internals::sphere::closest::<K, L>(&packet, &c.spheres);
    let any = internals::sphere::any::<K, L>(&packet, &c.spheres);
    let mut packed = vec![SpherePacket::<L>::from_spheres(&[]); c.spheres.len()];
    let n = SpherePacket::pack(&c.spheres, &mut packed);
    for (i, ray) in rays.iter().enumerate() {
        let one = internals::sphere::closest::<K, f32>(&RayPacket::splat(ray), &c.spheres).get();
        same(name, bits(h.lane(i)), bits(one));
        if let Some(r) = one {
            record_ok(name, ray, &r, true);
        }
        same(name, any.test(i), one.is_some());
        same(
            name,
            bits(internals::sphere::closest_soa::<K, L>(ray, &packed[..n])),
            bits(one),
        );
        same(
            name,
            internals::sphere::any_soa::<K, L>(ray, &packed[..n]),
            one.is_some(),
        );
    }
    internals::sphere::all::<K, L>(&packet, &c.spheres, |_, r| {
        for (i, ray) in rays.iter().enumerate() {
            roots_ok(name, ray, r, i);
        }
    });
}

fn focal_sphere<K: FocalKernel, L: Lane<Scalar = f32>>(c: &Case, guarded: bool) {
    let rays = &c.eye_units[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    let name = K::NAME;
    let mut cache = vec![FocalSphere::pass_all(); c.spheres.len()];
    if guarded {
        internals::sphere::focal::focus(c.eye, &c.spheres, &mut cache);
    } else {
        for (s, e) in c.spheres.iter().zip(&mut cache) {
            *e = FocalSphere::unguarded(c.eye, s);
        }
    }
    for e in &cache {
        let p = K::roots(&packet, &FocalSphere::<L>::splat(e));
        let g = K::roots(&packet, &internals::sphere::focal::Splat(e));
        for (i, ray) in rays.iter().enumerate() {
            let one = K::roots(&RayPacket::<f32>::splat(ray), &FocalSphere::<f32>::splat(e));
            let want = roots_ok(name, ray, &one, 0);
            same(name, roots_ok(name, ray, &p, i), want.clone());
            same(name, roots_ok(name, ray, &g, i), want);
        }
    }
    let h = internals::sphere::focal::closest::<K, L>(&packet, &cache);
    let any = internals::sphere::focal::any::<K, L>(&packet, &cache);
    let mut packed = vec![FocalSphere::<L>::gather(&[]); cache.len()];
    let n = FocalSphere::pack(&cache, &mut packed);
    for (i, ray) in rays.iter().enumerate() {
        let one = internals::sphere::focal::closest::<K, f32>(&RayPacket::splat(ray), &cache).get();
        same(name, bits(h.lane(i)), bits(one));
        if let Some(r) = one {
            record_ok(name, ray, &r, true);
        }
        same(name, any.test(i), one.is_some());
        same(
            name,
            bits(internals::sphere::focal::closest_soa::<K, L>(
                ray,
                &packed[..n],
            )),
            bits(one),
        );
        same(
            name,
            internals::sphere::focal::any_soa::<K, L>(ray, &packed[..n]),
            one.is_some(),
        );
    }
    internals::sphere::focal::all::<K, L>(&packet, &cache, |_, r| {
        for (i, ray) in rays.iter().enumerate() {
            roots_ok(name, ray, r, i);
        }
    });
}

// ---------------------------------------------------------------------------------------------
// Planes.

fn planes<L: Lane<Scalar = f32>>(c: &Case) {
    let rays = &c.rays[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    for p in &c.planes {
        let h = internals::plane::intersect_lanes(&packet, &PlanePacket::splat(p));
        for (i, ray) in rays.iter().enumerate() {
            let one = internals::plane::intersect(ray, p);
            if let Some(r) = one {
                record_ok("plane", ray, &r, true);
            }
            same("plane lanes", h.mask.test(i), one.is_some());
            if let Some(r) = one {
                same("plane t", h.t.lane(i).to_bits(), r.t.to_bits());
            }
        }
    }
    let h = internals::plane::closest::<L>(&packet, &c.planes);
    let any = internals::plane::any::<L>(&packet, &c.planes);
    let soa = PlanePacket::<L>::from_planes(&c.planes[..c.planes.len().min(L::LANES)]);
    for (i, ray) in rays.iter().enumerate() {
        let one = internals::plane::closest::<f32>(&RayPacket::splat(ray), &c.planes).get();
        same("plane closest", bits(h.lane(i)), bits(one));
        same("plane any", any.test(i), one.is_some());
        if c.planes.len() <= L::LANES {
            same(
                "plane closest_soa",
                bits(internals::plane::closest_soa::<L>(ray, &[soa])),
                bits(one),
            );
        }
    }
    internals::plane::all::<L>(&packet, &c.planes, |_, h| {
        for (i, ray) in rays.iter().enumerate() {
            if h.mask.test(i) {
                assert!(h.t.lane(i) > ray.t_min() && h.t.lane(i) < ray.t_max());
            }
        }
    });
    // The focal planes, from the eye.
    let rays = &c.eye_rays[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    let cache: Vec<FocalPlane> = c.planes.iter().map(|p| FocalPlane::new(c.eye, p)).collect();
    let h = internals::plane::closest_focal::<L>(&packet, &cache);
    for (i, ray) in rays.iter().enumerate() {
        let one = internals::plane::closest_focal::<f32>(&RayPacket::splat(ray), &cache).get();
        same("plane focal lanes", bits(h.lane(i)), bits(one));
        if let Some(r) = one {
            record_ok("plane focal", ray, &r, true);
        }
        // The cache gives the bits of the uncached test.
        same(
            "plane focal = plane",
            bits(one),
            bits(internals::plane::closest::<f32>(&RayPacket::splat(ray), &c.planes).get()),
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Triangles and meshes.

#[track_caller]
fn hits_agree<L: Lane<Scalar = f32>>(
    what: &str,
    rays: &[Ray],
    h: &Best<L>,
    one: impl Fn(&Ray) -> Option<HitRecord>,
) {
    for (i, ray) in rays.iter().enumerate() {
        same(what, bits(h.lane(i)), bits(one(ray)));
    }
}

fn triangle_kernel<K: TriangleKernel, L: Lane<Scalar = f32>>(c: &Case, cull: Cull) {
    let rays = &c.rays[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    let name = K::NAME;
    let h = internals::triangle::closest::<K, L>(&packet, &c.tris, cull);
    let any = internals::triangle::any::<K, L>(&packet, &c.tris, cull);
    let mut packed = vec![TrianglePacket::<L>::from_triangles(&[]); c.tris.len()];
    let n = TrianglePacket::pack(&c.tris, &mut packed);
    let one = |ray: &Ray| {
        internals::triangle::closest::<K, f32>(&RayPacket::splat(ray), &c.tris, cull).get()
    };
    hits_agree(name, rays, &h, one);
    for (i, ray) in rays.iter().enumerate() {
        let o = one(ray);
        if let Some(r) = o {
            record_ok(name, ray, &r, true);
        }
        same(name, any.test(i), o.is_some());
        same(
            name,
            bits(internals::triangle::closest_soa::<K, L>(
                ray,
                &packed[..n],
                cull,
            )),
            bits(o),
        );
        same(
            name,
            internals::triangle::any_soa::<K, L>(ray, &packed[..n], cull),
            o.is_some(),
        );
        for t in &c.tris {
            if let Some(r) = internals::triangle::intersect::<K>(ray, t, cull) {
                record_ok(name, ray, &r, true);
            }
        }
    }
    internals::triangle::all::<K, L>(&packet, &c.tris, cull, |_, h| {
        for (i, ray) in rays.iter().enumerate() {
            if h.mask.test(i) {
                let r = HitRecord {
                    t: h.t.lane(i),
                    u: h.u.lane(i),
                    v: h.v.lane(i),
                    index: 0,
                };
                record_ok(name, ray, &r, true);
            }
        }
    });
}

fn focal_triangles<L: Lane<Scalar = f32>>(c: &Case, cull: Cull) {
    let check = CHECK_FOCAL_TRIANGLE_INTERVAL;
    let rays = &c.eye_rays[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    let cache: Vec<FocalTriangle<f32>> = c
        .tris
        .iter()
        .map(|t| FocalTriangle::new(c.eye, t))
        .collect();
    let h = internals::triangle::focal::closest::<L>(&packet, &cache, cull);
    let any = internals::triangle::focal::any::<L>(&packet, &cache, cull);
    let mut packed = vec![FocalTriangle::<L>::gather(&[]); cache.len()];
    let n = FocalTriangle::pack(&cache, &mut packed);
    let one = |ray: &Ray| {
        internals::triangle::focal::closest::<f32>(&RayPacket::splat(ray), &cache, cull).get()
    };
    hits_agree("triangle-focal", rays, &h, one);
    for (i, ray) in rays.iter().enumerate() {
        let o = one(ray);
        if let Some(r) = o {
            record_ok("triangle-focal", ray, &r, check);
        }
        same("triangle-focal any", any.test(i), o.is_some());
        same(
            "triangle-focal closest_soa",
            bits(internals::triangle::focal::closest_soa::<L>(
                ray,
                &packed[..n],
                cull,
            )),
            bits(o),
        );
        same(
            "triangle-focal any_soa",
            internals::triangle::focal::any_soa::<L>(ray, &packed[..n], cull),
            o.is_some(),
        );
        for e in &cache {
            if let Some(r) = internals::triangle::focal::intersect(ray, e, cull) {
                record_ok("triangle-focal intersect", ray, &r, check);
            }
        }
    }
    internals::triangle::focal::all::<L>(&packet, &cache, cull, |_, h| {
        for (i, ray) in rays.iter().enumerate() {
            if h.mask.test(i) {
                let r = HitRecord {
                    t: h.t.lane(i),
                    u: h.u.lane(i),
                    v: h.v.lane(i),
                    index: 0,
                };
                record_ok("triangle-focal all", ray, &r, check);
            }
        }
    });
}

fn meshes<K: TriangleKernel, L: Lane<Scalar = f32>>(c: &Case, cull: Cull) {
    let rays = &c.rays[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    let name = K::NAME;
    let plain = Mesh::new(&c.positions, &c.indices);
    let ritter = Mesh::bounded(&c.positions, &c.indices);
    let odd = plain.with_bound(&c.spheres[0]);
    if let Some(b) = ritter.bound() {
        let s = b.sphere();
        assert!(s.is_valid(), "ritter: invalid sphere {s:?}");
    }
    let plain_q = plain.using::<K>().culled(cull);
    for (m, exact) in [(plain, true), (ritter, true), (odd, false)] {
        let q = m.using::<K>().culled(cull);
        let h = q.closest(&packet);
        let any = q.any(&packet);
        let one = |ray: &Ray| record(q.closest(ray));
        query_hits_agree(name, rays, &h, one);
        for (i, ray) in rays.iter().enumerate() {
            let o = one(ray);
            if let Some(r) = o {
                record_ok(name, ray, &r, true);
            }
            same(name, any.test(i), o.is_some());
            same(name, q.any(ray), o.is_some());
            if exact {
                // The Ritter bound contains every vertex: culling never loses a hit.
                let p = record(plain_q.closest(ray));
                assert_eq!(bits(o), bits(p), "ritter culling: {ray:?}, {:?}", m.bound());
            }
        }
        q.all(&packet, |h: Hits<L>| {
            for (i, ray) in rays.iter().enumerate() {
                if let Some(r) = record(h.lane(i)) {
                    record_ok(name, ray, &r, true);
                }
            }
        });
    }
}

fn query_hits_agree<L: Lane<Scalar = f32>>(
    what: &str,
    rays: &[Ray],
    h: &Hits<L>,
    one: impl Fn(&Ray) -> Option<HitRecord>,
) {
    for (i, ray) in rays.iter().enumerate() {
        same(what, bits(record(h.lane(i))), bits(one(ray)));
    }
}

fn focal_meshes<L: Lane<Scalar = f32>>(c: &Case, cull: Cull) {
    let check = CHECK_FOCAL_TRIANGLE_INTERVAL;
    let rays = &c.eye_rays[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    let plain = Mesh::new(&c.positions, &c.indices);
    let invalid = plain.with_bound(&Sphere::new(Vec3::ZERO, -1.0));
    let mut base = vec![FocalTriangle::never(); raylane::focal::FocalMesh::needed(&plain)];
    let unbounded = raylane::focal::FocalMesh::new(&plain, c.eye, &mut base)
        .unwrap()
        .culled(cull);
    for m in [plain, Mesh::bounded(&c.positions, &c.indices), invalid] {
        let mut cache = vec![FocalTriangle::never(); raylane::focal::FocalMesh::needed(&m)];
        let fm = raylane::focal::FocalMesh::new(&m, c.eye, &mut cache)
            .unwrap()
            .culled(cull);
        let h = Query::closest(&fm, &packet);
        let any = Query::any(&fm, &packet);
        let one = |ray: &Ray| record(Query::closest(&fm, ray));
        query_hits_agree("focal mesh", rays, &h, one);
        for (i, ray) in rays.iter().enumerate() {
            let o = one(ray);
            if let Some(r) = o {
                record_ok("focal mesh", ray, &r, check);
            }
            same("focal mesh any", any.test(i), o.is_some());
            // A bound (valid or not) never loses a hit of the unbounded cache.
            let u = record(Query::closest(&unbounded, ray));
            same("focal mesh culling", bits(o), bits(u));
        }
        Query::all(&fm, &packet, |h: Hits<L>| {
            for (i, ray) in rays.iter().enumerate() {
                if let Some(r) = record(h.lane(i)) {
                    record_ok("focal mesh all", ray, &r, check);
                }
            }
        });
    }
}

// ---------------------------------------------------------------------------------------------
// Bounds and the camera.

fn bounds_and_camera<L: Lane<Scalar = f32>>(c: &Case, rng: &mut SmallRng) {
    // Ritter: a valid sphere containing every finite point, or None.
    for s in [
        bounds::ritter(&c.positions),
        bounds::ritter_indexed(&c.positions, &c.indices),
    ]
    .into_iter()
    .flatten()
    {
        assert!(s.is_valid() && s.radius().is_finite(), "ritter {s:?}");
        for p in c.positions.iter().filter(|p| p.is_finite()) {
            let d = [
                p.x as f64 - s.center().x as f64,
                p.y as f64 - s.center().y as f64,
                p.z as f64 - s.center().z as f64,
            ];
            let e = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if bounds::ritter(&c.positions) == Some(s) {
                assert!(e <= s.radius() as f64, "ritter: {p} outside {s:?}");
            }
        }
    }
    // may_hit: lanes equal scalar; the focal form is a valid entry.
    let rays = &c.rays[..L::LANES];
    let packet = RayPacket::<L>::from_rays(rays);
    for s in &c.spheres {
        let b = Bound::new(s);
        let m = b.may_hit(&packet);
        for (i, ray) in rays.iter().enumerate() {
            same(
                "may_hit",
                m.test(i),
                b.may_hit(&RayPacket::<f32>::splat(ray)),
            );
        }
        let e = b.focal(c.eye);
        let fr = RayPacket::<L>::from_rays(&c.eye_units[..L::LANES]);
        let _ = Focal::candidate(&fr, &internals::sphere::focal::Splat(&e));
    }
    // The camera: pixels outside the image never give a valid ray; lanes equal scalar.
    let g = |rng: &mut SmallRng| {
        if rng.random_bool(0.2) {
            special(rng)
        } else {
            rng.random_range(-10.0f32..10.0)
        }
    };
    let v = |rng: &mut SmallRng| Vec3::new(g(rng), g(rng), g(rng));
    let dims = [0u32, 1, 2, 7, 64, u32::MAX];
    let (w, h) = (
        dims[rng.random_range(0..dims.len())],
        dims[rng.random_range(0..dims.len())],
    );
    let fov = if rng.random_bool(0.2) {
        special(rng)
    } else {
        rng.random_range(1.0f32..170.0)
    };
    let cam = Pinhole::look_at(v(rng), v(rng), v(rng), fov, w, h);
    let xs = [
        0,
        1,
        w.saturating_sub(1),
        w,
        u32::MAX - 1,
        u32::MAX,
        rng.random(),
    ];
    let ys = [0, h.saturating_sub(1), h, u32::MAX, rng.random()];
    let (x, y) = (
        xs[rng.random_range(0..xs.len())],
        ys[rng.random_range(0..ys.len())],
    );
    let p = cam.row_packet::<L>(x, y);
    for i in 0..L::LANES {
        let col = u64::from(x) + i as u64;
        let inside = col < u64::from(w) && y < h;
        if !inside {
            assert!(
                !p.ray(i).is_valid(),
                "pixel ({col}, {y}) outside {w}×{h} is valid"
            );
        }
        if let Ok(xi) = u32::try_from(col) {
            let one = cam.row_packet::<f32>(xi, y).ray(0);
            let lane = p.ray(i);
            same(
                "camera lanes",
                (
                    lane.origin().to_array().map(nan_bits),
                    lane.dir().to_array().map(nan_bits),
                    lane.t_min().to_bits(),
                    lane.t_max().to_bits(),
                ),
                (
                    one.origin().to_array().map(nan_bits),
                    one.dir().to_array().map(nan_bits),
                    one.t_min().to_bits(),
                    one.t_max().to_bits(),
                ),
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------

fn width<L: Lane<Scalar = f32>>(c: &Case, rng: &mut SmallRng) {
    sphere_kernel::<Quadratic, L>(c);
    sphere_kernel::<QuadraticUnit, L>(c);
    sphere_kernel::<Geometric, L>(c);
    sphere_kernel::<Robust, L>(c);
    focal_sphere::<Focal, L>(c, true);
    focal_sphere::<FocalUnguarded, L>(c, false);
    planes::<L>(c);
    for cull in [Cull::None, Cull::Back] {
        triangle_kernel::<Cramer, L>(c, cull);
        triangle_kernel::<Moller, L>(c, cull);
        triangle_kernel::<Watertight, L>(c, cull);
        focal_triangles::<L>(c, cull);
        meshes::<Watertight, L>(c, cull);
        meshes::<Moller, L>(c, cull);
        focal_meshes::<L>(c, cull);
    }
    bounds_and_camera::<L>(c, rng);
}

/// Case `case_seed` at every width (f32x4, f32x8, f32x16): the case and whether it passed.
fn run_case(case_seed: u64) -> (Case, std::thread::Result<()>) {
    let mut r = SmallRng::seed_from_u64(case_seed);
    let c = case(&mut r);
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        width::<f32x4>(&c, &mut r);
        width::<f32x8>(&c, &mut r);
        width::<f32x16>(&c, &mut r);
    }));
    (c, run)
}

/// The cases the fuzzer found before the test ahead of the deferred division skipped subnormal
/// products (`src/triangle/mod.rs`, `within`): a hit at `t ≈ 2^-45…2^-49`, or at `t = 0` with
/// `t_min < 0`, where `t_max·det` is subnormal, so N rays × 1 triangle (`t_max` shrunk by an
/// earlier hit) dropped a closer triangle that 1 ray × N triangles found: three Watertight
/// meshes, one Watertight slice, one focal slice. And three found with other seeds before
/// `|det| < 2^-100` became a clean miss: meshes of size `2^-53` (and `2^-75`) whose products
/// under-flowed, hit at `t = 1, u = 1` or `t = 0` outside their Ritter bound.
#[test]
fn fuzz_triangle_range_regressions() {
    for seed in [
        0x9809_d5ed_9b3f_2b21,
        0xbd40_debc_ef7a_1fa7,
        0x9e4b_417e_b533_a204,
        0x985e_a72e_e987_448d,
        0xab0c_61af_de6e_b89f,
        0x983b_d7b5_6b8a_c1e8,
        0xfcbb_30fe_57de_15f6,
        0xb9b6_c8d9_f91b_99d5,
    ] {
        let (_, run) = run_case(seed);
        if let Err(e) = run {
            eprintln!("fuzz regression {seed:#x} failed");
            std::panic::resume_unwind(e);
        }
    }
}

#[test]
fn fuzz_every_entry_point_and_width() {
    let n = cases();
    let mut rng = SmallRng::seed_from_u64(seed());
    // `RAYLANE_FUZZ_REPLAY=<case seed>` runs that one case.
    let replay: Option<u64> = std::env::var("RAYLANE_FUZZ_REPLAY")
        .ok()
        .and_then(|s| u64::from_str_radix(s.trim_start_matches("0x"), 16).ok());
    for k in 0..n {
        let case_seed: u64 = replay.unwrap_or_else(|| rng.random());
        if replay.is_some() && k > 0 {
            break;
        }
        let (c, run) = run_case(case_seed);
        if let Err(e) = run {
            if replay.is_some() {
                eprintln!("{c:#?}");
            }
            eprintln!("fuzz case {k} failed: replay with RAYLANE_FUZZ_REPLAY={case_seed:#x}");
            std::panic::resume_unwind(e);
        }
    }
    println!("fuzz: {n} cases × 3 widths, every entry point");
}

/// The two focal triangle cases of issue 10 ("Focal triangle hits outside the interval"): run
/// through every focal triangle entry point, with their interval checked
/// ([`CHECK_FOCAL_TRIANGLE_INTERVAL`]).
#[test]
fn focal_triangle_interval_cases_from_the_issue() {
    let far = Triangle::new(
        Vec3::new(10.0, -1.0, -1.0),
        Vec3::new(10.0, 1.0, -1.0),
        Vec3::new(10.0, 0.0, 1.0),
    );
    let near = Triangle::new(
        Vec3::new(1e-7, -1.0, -1.0),
        Vec3::new(1e-7, 1.0, -1.0),
        Vec3::new(1e-7, 0.0, 1.0),
    );
    for (tri, d) in [(far, 1e-40f32), (near, 3e38)] {
        let ray = Ray::new(Vec3::ZERO, Vec3::new(d, 0.0, 0.0));
        let e = FocalTriangle::new(Vec3::ZERO, &tri);
        let cache = [e];
        let mut packed = [FocalTriangle::<f32x8>::gather(&[])];
        FocalTriangle::pack(&cache, &mut packed);
        let results = [
            internals::triangle::focal::intersect(&ray, &e, Cull::None),
            internals::triangle::focal::closest::<f32>(&RayPacket::splat(&ray), &cache, Cull::None)
                .get(),
            internals::triangle::focal::closest::<f32x8>(
                &RayPacket::splat(&ray),
                &cache,
                Cull::None,
            )
            .lane(7),
            internals::triangle::focal::closest_soa::<f32x8>(&ray, &packed, Cull::None),
        ];
        for h in results.into_iter().flatten() {
            record_ok(
                "issue focal triangle",
                &ray,
                &h,
                CHECK_FOCAL_TRIANGLE_INTERVAL,
            );
        }
        // Möller and Watertight: no hit for either.
        assert_eq!(
            internals::triangle::intersect::<Moller>(&ray, &tri, Cull::None),
            None
        );
        assert_eq!(
            internals::triangle::intersect::<Watertight>(&ray, &tri, Cull::None),
            None
        );
    }
}
