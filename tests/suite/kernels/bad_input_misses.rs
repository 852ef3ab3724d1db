//! Bad input is a documented miss: no panic, no NaN in any record, for every kernel and entry
//! point. (Triangles have their own bad-input tests in tests/triangles.rs.)

use glam::Vec3;
use raylane::plane::{FocalPlane, Plane};
use raylane::sphere::focal::Focal;
use raylane::sphere::focal::FocalKernel;
use raylane::sphere::{
    FocalSphere, Geometric, Quadratic, QuadraticUnit, Robust, Sphere, SphereKernel, SpherePacket,
};
use raylane::triangle::TriangleKernel;
use raylane::{Lane, Ray, RayPacket};
use raylane_lab::loops as internals;
use raylane_lab::registry::{Kernel, Prim, Visitor};
use wide::f32x8;

const NAN: f32 = f32::NAN;
const INF: f32 = f32::INFINITY;

/// A sphere around the origin, radius 2: every good ray from inside hits it.
fn ball() -> Sphere {
    Sphere::new(Vec3::ZERO, 2.0)
}

fn bad_rays() -> Vec<(&'static str, Ray)> {
    let o = Vec3::ZERO;
    vec![
        ("zero direction", Ray::new(o, Vec3::ZERO)),
        ("NaN origin", Ray::new(Vec3::new(NAN, 0.0, 0.0), Vec3::X)),
        ("NaN direction", Ray::new(o, Vec3::new(0.0, NAN, 0.0))),
        (
            "infinite origin",
            Ray::new(Vec3::new(0.0, 0.0, -INF), Vec3::Z),
        ),
        ("infinite direction", Ray::new(o, Vec3::new(INF, 0.0, 0.0))),
        ("empty interval", Ray::with_interval(o, Vec3::X, 1.0, 1.0)),
        (
            "reversed interval",
            Ray::with_interval(o, Vec3::X, 2.0, 1.0),
        ),
        ("NaN interval", Ray::with_interval(o, Vec3::X, NAN, 1.0)),
    ]
}

fn bad_spheres() -> Vec<(&'static str, Sphere)> {
    vec![
        ("zero radius", Sphere::new(Vec3::ZERO, 0.0)),
        ("negative radius", Sphere::new(Vec3::ZERO, -2.0)),
        ("NaN radius", Sphere::new(Vec3::ZERO, NAN)),
        ("infinite radius", Sphere::new(Vec3::ZERO, INF)),
        ("NaN centre", Sphere::new(Vec3::new(NAN, 0.0, 0.0), 2.0)),
        (
            "infinite centre",
            Sphere::new(Vec3::new(0.0, -INF, 0.0), 2.0),
        ),
    ]
}

fn misses<K: SphereKernel>(ray: &Ray, s: &Sphere, what: &str) {
    let r = K::roots(&RayPacket::<f32>::splat(ray), &SpherePacket::splat(s));
    assert!(!r.m0 && !r.m1, "{} {what}: a hit", K::NAME);
    assert!(
        r.t0 == INF && r.t1 == INF,
        "{} {what}: record not canonical",
        K::NAME
    );
    let p = K::roots(&RayPacket::<f32x8>::splat(ray), &SpherePacket::splat(s));
    assert!(p.any().none(), "{} {what}: a packet hit", K::NAME);
    assert_eq!(internals::sphere::intersect::<K>(ray, s), None);
}

fn focal_misses<K: FocalKernel>(ray: &Ray, s: &Sphere, guarded: bool, what: &str) {
    let e = if guarded {
        FocalSphere::new(ray.origin(), s)
    } else {
        FocalSphere::unguarded(ray.origin(), s)
    };
    let r = K::roots(&RayPacket::<f32>::splat(ray), &FocalSphere::splat(&e));
    assert!(
        !r.m0 && !r.m1 && r.t0 == INF && r.t1 == INF,
        "{} {what}",
        K::NAME
    );
}

/// [`misses`] or [`focal_misses`] for a registry kernel.
struct Misses<'a>(&'a Ray, &'a Sphere, &'a str);

impl Visitor for Misses<'_> {
    type Output = ();
    fn sphere<K: SphereKernel>(self, _: Kernel) {
        misses::<K>(self.0, self.1, self.2);
    }
    fn focal_sphere<K: FocalKernel>(self, _: Kernel, guarded: bool) {
        focal_misses::<K>(self.0, self.1, guarded, self.2);
    }
    fn plane(self, k: Kernel) {
        unreachable!("{} is not a sphere kernel", k.name())
    }
    fn focal_plane(self, k: Kernel) {
        unreachable!("{} is not a sphere kernel", k.name())
    }
    fn triangle<K: TriangleKernel>(self, k: Kernel) {
        unreachable!("{} is not a sphere kernel", k.name())
    }
    fn focal_triangle(self, k: Kernel) {
        unreachable!("{} is not a sphere kernel", k.name())
    }
}

/// Every sphere kernel of the registry misses.
fn every_kernel_misses(ray: &Ray, s: &Sphere, what: &str) {
    for k in Kernel::of(Prim::Sphere) {
        k.visit(Misses(ray, s, what));
    }
}

#[test]
fn bad_rays_miss_every_sphere_kernel() {
    for (what, ray) in bad_rays() {
        every_kernel_misses(&ray, &ball(), what);
        let p = internals::plane::intersect(&ray, &Plane::new(Vec3::X, Vec3::X));
        assert_eq!(p, None, "plane {what}");
    }
}

#[test]
fn bad_spheres_are_never_hit() {
    // From the centre of where the sphere would be: a kernel ignoring validity would hit.
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    for (what, s) in bad_spheres() {
        assert!(!s.is_valid(), "{what}");
        every_kernel_misses(&ray, &s, what);
    }
    // The same ray hits the good sphere with every kernel.
    for t in [
        internals::sphere::intersect::<Quadratic>(&ray, &ball()),
        internals::sphere::intersect::<QuadraticUnit>(&ray, &ball()),
        internals::sphere::intersect::<Geometric>(&ray, &ball()),
        internals::sphere::intersect::<Robust>(&ray, &ball()),
    ] {
        assert_eq!(t.map(|h| h.t), Some(2.0));
    }
}

#[test]
fn bad_planes_miss() {
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    let cases = [
        ("zero normal", Plane::new(Vec3::X, Vec3::ZERO)),
        ("NaN normal", Plane::new(Vec3::X, Vec3::new(NAN, 1.0, 0.0))),
        (
            "infinite point",
            Plane::new(Vec3::new(INF, 0.0, 0.0), Vec3::X),
        ),
        ("parallel", Plane::new(Vec3::Y, Vec3::Y)),
        ("ray in the plane", Plane::new(Vec3::ZERO, Vec3::Y)),
        ("behind", Plane::new(-Vec3::X, Vec3::X)),
    ];
    for (what, p) in cases {
        assert_eq!(internals::plane::intersect(&ray, &p), None, "{what}");
        let f = FocalPlane::new(ray.origin(), &p).intersect_lanes(&RayPacket::<f32>::splat(&ray));
        assert!(!f.mask && f.t == INF, "focal {what}");
    }
}

#[test]
fn slices_of_bad_input_give_canonical_misses() {
    let mut spheres: Vec<Sphere> = bad_spheres().into_iter().map(|(_, s)| s).collect();
    spheres.push(Sphere::new(Vec3::new(10.0, 0.0, 0.0), 1.0));
    let rays: Vec<Ray> = bad_rays().into_iter().map(|(_, r)| r).collect();
    let rp = RayPacket::<f32x8>::from_rays(&rays);
    let h = internals::sphere::closest::<Robust, f32x8>(&rp, &spheres);
    assert!(h.mask.none());
    for i in 0..8 {
        assert_eq!(h.t.lane(i), INF);
        assert_eq!(h.index[i], u32::MAX);
    }
    assert!(internals::sphere::any::<Robust, f32x8>(&rp, &spheres).none());
    let mut cache = vec![FocalSphere::new(Vec3::ZERO, &ball()); spheres.len()];
    internals::sphere::focal::focus(Vec3::new(NAN, 0.0, 0.0), &spheres, &mut cache);
    let good = RayPacket::<f32x8>::splat(&Ray::new(Vec3::ZERO, Vec3::X));
    assert!(
        internals::sphere::focal::closest::<Focal, f32x8>(&good, &cache)
            .mask
            .none(),
        "a NaN eye hits nothing"
    );
}
