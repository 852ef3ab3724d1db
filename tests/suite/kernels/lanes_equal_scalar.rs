//! Every lane of every width equals the scalar path, bit for bit: over seeded random batches
//! (including NaN, infinite, zero-direction and masked-off lanes) and for every entry point.

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::lane::{Lane, Mask};
use raylane::plane::{FocalPlane, Plane, PlanePacket};
use raylane::sphere::focal::{Focal, FocalKernel};
use raylane::sphere::{FocalSphere, Robust, Roots, Sphere, SphereKernel, SpherePacket};
use raylane::triangle::TriangleKernel;
use raylane::{Ray, RayPacket, V3};
use raylane_lab::loops as internals;
use raylane_lab::loops::{Best, LaneRecords};
use raylane_lab::registry::{Kernel, Prim, Visitor};
use std::marker::PhantomData;
use wide::{f32x4, f32x8, f32x16};

const BATCHES: usize = 400;

/// A random f32 that is sometimes special.
fn coord(rng: &mut SmallRng, scale: f32) -> f32 {
    match rng.random_range(0..100) {
        0 => f32::NAN,
        1 => f32::INFINITY,
        2 => f32::NEG_INFINITY,
        3 => 0.0,
        _ => rng.random_range(-scale..scale),
    }
}

fn vec(rng: &mut SmallRng, scale: f32) -> Vec3 {
    Vec3::new(coord(rng, scale), coord(rng, scale), coord(rng, scale))
}

/// Rays: mostly unit directions (some not), some zero, some aimed at a sphere near `aim`.
fn ray(rng: &mut SmallRng, aim: Vec3) -> Ray {
    let o = vec(rng, 20.0);
    let d = match rng.random_range(0..10) {
        0 => Vec3::ZERO,
        1 => vec(rng, 3.0),
        2..=5 => (aim + vec(rng, 1.0) - o).normalize_or_zero(),
        _ => vec(rng, 1.0).normalize_or_zero(),
    };
    Ray::new(o, d)
}

fn sphere(rng: &mut SmallRng) -> Sphere {
    let r = match rng.random_range(0..20) {
        0 => 0.0,
        1 => -1.0,
        2 => f32::NAN,
        _ => rng.random_range(0.01..6.0),
    };
    Sphere::new(vec(rng, 15.0), r)
}

fn same_roots<L: Lane<Scalar = f32>>(p: &Roots<L>, i: usize, s: &Roots<f32>, what: &str) {
    assert_eq!(
        p.t0.lane(i).to_bits(),
        s.t0.to_bits(),
        "{what}: t0 lane {i}"
    );
    assert_eq!(
        p.t1.lane(i).to_bits(),
        s.t1.to_bits(),
        "{what}: t1 lane {i}"
    );
    assert_eq!(p.m0.test(i), s.m0, "{what}: m0 lane {i}");
    assert_eq!(p.m1.test(i), s.m1, "{what}: m1 lane {i}");
    assert!(
        !p.t0.lane(i).is_nan() && !p.t1.lane(i).is_nan(),
        "{what}: NaN in a record"
    );
}

fn kernel<K: SphereKernel, L: Lane<Scalar = f32>>(rays: &[Ray], spheres: &[Sphere]) {
    let rp = RayPacket::<L>::from_rays(rays);
    let sp = SpherePacket::<L>::from_spheres(spheres);
    let packed = K::roots(&rp, &sp);
    for i in 0..L::LANES {
        let (r, s) = (
            rp.ray(i),
            spheres
                .get(i)
                .copied()
                .unwrap_or(Sphere::new(Vec3::ZERO, f32::NAN)),
        );
        let scalar = K::roots(&RayPacket::<f32>::splat(&r), &SpherePacket::splat(&s));
        same_roots(&packed, i, &scalar, K::NAME);
    }
}

fn focal_kernel<K: FocalKernel, L: Lane<Scalar = f32>>(
    rays: &[Ray],
    spheres: &[Sphere],
    guarded: bool,
) {
    let rp = RayPacket::<L>::from_rays(rays);
    let entries: Vec<FocalSphere<f32>> = (0..L::LANES)
        .map(|i| {
            let s = spheres
                .get(i)
                .copied()
                .unwrap_or(Sphere::new(Vec3::ZERO, f32::NAN));
            let eye = rp.ray(i).origin();
            if guarded {
                FocalSphere::new(eye, &s)
            } else {
                FocalSphere::unguarded(eye, &s)
            }
        })
        .collect();
    let packed = K::roots(&rp, &FocalSphere::<L>::gather(&entries));
    for (i, e) in entries.iter().enumerate() {
        let scalar = K::roots(&RayPacket::<f32>::splat(&rp.ray(i)), &FocalSphere::splat(e));
        same_roots(&packed, i, &scalar, K::NAME);
    }
}

fn planes<L: Lane<Scalar = f32>>(rays: &[Ray], ps: &[Plane]) {
    let rp = RayPacket::<L>::from_rays(rays);
    let pp = PlanePacket::<L>::from_planes(ps);
    let packed = internals::plane::intersect_lanes(&rp, &pp);
    let nums =
        L::from_f32_fn(|i| FocalPlane::new(rp.ray(i).origin(), &ps[i.min(ps.len() - 1)]).num());
    let focal =
        internals::plane::focal_lanes(&rp, nums, V3::from_fn(|i| ps[i.min(ps.len() - 1)].normal));
    for i in 0..L::LANES {
        let p = ps
            .get(i)
            .copied()
            .unwrap_or(Plane::new(Vec3::ZERO, Vec3::ZERO));
        let s = internals::plane::intersect_lanes(
            &RayPacket::<f32>::splat(&rp.ray(i)),
            &PlanePacket::splat(&p),
        );
        assert_eq!(packed.t.lane(i).to_bits(), s.t.to_bits(), "plane lane {i}");
        assert_eq!(packed.mask.test(i), s.mask);
        if i < ps.len() {
            assert_eq!(
                focal.t.lane(i).to_bits(),
                s.t.to_bits(),
                "plane-focal equals plane, lane {i}"
            );
        }
    }
}

fn every_kernel<L: Lane<Scalar = f32>>(seed: u64) {
    let mut rng = SmallRng::seed_from_u64(seed);
    for _ in 0..BATCHES {
        let spheres: Vec<Sphere> = (0..L::LANES).map(|_| sphere(&mut rng)).collect();
        let rays: Vec<Ray> = spheres.iter().map(|s| ray(&mut rng, s.center())).collect();
        // Sometimes fewer rays than lanes: the padding lanes must miss.
        let n = if rng.random_range(0..8) == 0 {
            rng.random_range(0..L::LANES)
        } else {
            L::LANES
        };
        // Every sphere kernel of the registry.
        for k in Kernel::of(Prim::Sphere) {
            k.visit(Lanes::<L>(&rays[..n], &spheres, PhantomData));
        }
        let ps: Vec<Plane> = spheres
            .iter()
            .map(|s| Plane::new(s.center(), vec(&mut rng, 1.0)))
            .collect();
        planes::<L>(&rays, &ps);
    }
}

/// [`kernel`] or [`focal_kernel`] for a registry kernel.
struct Lanes<'a, L>(&'a [Ray], &'a [Sphere], PhantomData<L>);

impl<L: Lane<Scalar = f32>> Visitor for Lanes<'_, L> {
    type Output = ();
    fn sphere<K: SphereKernel>(self, _: Kernel) {
        kernel::<K, L>(self.0, self.1);
    }
    fn focal_sphere<K: FocalKernel>(self, _: Kernel, guarded: bool) {
        focal_kernel::<K, L>(self.0, self.1, guarded);
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

#[test]
fn kernels_x4_equal_scalar() {
    every_kernel::<f32x4>(4);
}

#[test]
fn kernels_x8_equal_scalar() {
    every_kernel::<f32x8>(8);
}

#[test]
fn kernels_x16_equal_scalar() {
    every_kernel::<f32x16>(16);
}

/// Far small spheres near the rim exercise the focal guard's f64 fallback in packets.
fn far_rim<L: Lane<Scalar = f32>>(seed: u64) {
    let mut rng = SmallRng::seed_from_u64(seed);
    for k in 6..=20 {
        for _ in 0..40 {
            let eye = Vec3::new(
                rng.random_range(-5.0..5.0),
                rng.random_range(-5.0..5.0),
                0.0,
            );
            let r = rng.random_range(0.1..2.0f32);
            let dist = r * (1u32 << k) as f32;
            let dir = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                1.0,
            )
            .normalize();
            let side = dir.any_orthonormal_vector();
            let spheres: Vec<Sphere> = (0..L::LANES)
                .map(|_| {
                    Sphere::new(
                        eye + dir * dist + side * r * rng.random_range(0.9..1.1f32),
                        r,
                    )
                })
                .collect();
            let rays: Vec<Ray> = (0..L::LANES).map(|_| Ray::new(eye, dir)).collect();
            focal_kernel::<Focal, L>(&rays, &spheres, true);
            kernel::<Robust, L>(&rays, &spheres);
        }
    }
}

#[test]
fn focal_fallback_lanes_equal_scalar() {
    far_rim::<f32x4>(1);
    far_rim::<f32x8>(2);
    far_rim::<f32x16>(3);
}

fn same_hit<L: Lane<Scalar = f32>>(h: &Best<L>, i: usize, s: &Best<f32>) {
    assert_eq!(h.lane(i), s.get());
    if let Some(r) = h.lane(i) {
        assert_eq!(r.t.to_bits(), s.t.to_bits());
    }
}

fn entry_points<L: Lane<Scalar = f32>>(seed: u64) {
    let mut rng = SmallRng::seed_from_u64(seed);
    for _ in 0..60 {
        let spheres: Vec<Sphere> = (0..23).map(|_| sphere(&mut rng)).collect();
        let rays: Vec<Ray> = (0..L::LANES)
            .map(|i| ray(&mut rng, spheres[i].center()))
            .collect();
        let rp = RayPacket::<L>::from_rays(&rays);
        let closest = internals::sphere::closest::<Robust, L>(&rp, &spheres);
        let any = internals::sphere::any::<Robust, L>(&rp, &spheres);
        let mut soa = vec![SpherePacket::<L>::from_spheres(&[]); spheres.len().div_ceil(L::LANES)];
        SpherePacket::pack(&spheres, &mut soa);
        for (i, r) in rays.iter().enumerate() {
            let single = internals::sphere::closest::<Robust, f32>(&RayPacket::splat(r), &spheres);
            same_hit(&closest, i, &single);
            assert_eq!(any.test(i), single.mask);
            // 1 ray × N spheres in lanes gives the same hit.
            assert_eq!(
                internals::sphere::closest_soa::<Robust, L>(r, &soa),
                single.get()
            );
            assert_eq!(
                internals::sphere::any_soa::<Robust, L>(r, &soa),
                single.mask
            );
        }
        // All hits: every root of every sphere, the same per lane as the scalar path.
        let mut seen = Vec::new();
        internals::sphere::all::<Robust, L>(&rp, &spheres, |i, roots| {
            for lane in 0..L::LANES {
                let (t, n) = roots.lane(lane);
                for t in &t[..n] {
                    seen.push((lane, i, t.to_bits()));
                }
            }
        });
        let mut want = Vec::new();
        for (lane, r) in rays.iter().enumerate() {
            internals::sphere::all::<Robust, f32>(&RayPacket::splat(r), &spheres, |i, roots| {
                let (t, n) = roots.lane(0);
                for t in &t[..n] {
                    want.push((lane, i, t.to_bits()));
                }
            });
        }
        seen.sort_unstable();
        want.sort_unstable();
        assert_eq!(seen, want);
        // Focal caches: packets from one eye (a camera), N rays × 1 sphere and 1 ray × N.
        let eye = vec(&mut rng, 5.0);
        if !eye.is_finite() {
            continue;
        }
        let mut cache = vec![FocalSphere::new(eye, &spheres[0]); spheres.len()];
        internals::sphere::focal::focus(eye, &spheres, &mut cache);
        let mut packed = vec![FocalSphere::<L>::gather(&[]); spheres.len().div_ceil(L::LANES)];
        FocalSphere::pack(&cache, &mut packed);
        let frays: Vec<Ray> = rays
            .iter()
            .map(|r| Ray::new(eye, r.dir().normalize_or_zero()))
            .collect();
        let fp = RayPacket::<L>::from_rays(&frays);
        let fc = internals::sphere::focal::closest::<Focal, L>(&fp, &cache);
        let fa = internals::sphere::focal::any::<Focal, L>(&fp, &cache);
        for (i, r) in frays.iter().enumerate() {
            let single =
                internals::sphere::focal::closest::<Focal, f32>(&RayPacket::splat(r), &cache);
            same_hit(&fc, i, &single);
            assert_eq!(fa.test(i), single.mask);
            assert_eq!(
                internals::sphere::focal::closest_soa::<Focal, L>(r, &packed),
                single.get()
            );
            assert_eq!(
                internals::sphere::focal::any_soa::<Focal, L>(r, &packed),
                single.mask
            );
        }
    }
}

#[test]
fn entry_points_equal_scalar() {
    entry_points::<f32x4>(40);
    entry_points::<f32x8>(80);
    entry_points::<f32x16>(160);
}
