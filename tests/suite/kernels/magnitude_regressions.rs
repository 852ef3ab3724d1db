//! Robustness regressions (issue 10, "found by a structured fuzzer"): each test reproduces an
//! exact case of the issue, and the magnitude sweep measures the range the sphere kernels
//! document.

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::bounds::{self, Bound};
use raylane::mesh::Mesh;
use raylane::sphere::focal::{Focal, FocalKernel};
use raylane::sphere::{
    self, FocalSphere, Geometric, Quadratic, QuadraticUnit, Robust, Roots, Sphere, SphereKernel,
    SpherePacket,
};
use raylane::triangle::FocalTriangle;
use raylane::{Lane, Pinhole, Ray, RayPacket, V3};
use raylane_lab::loops as internals;
use raylane_lab::loops::LaneRecords;

/// `v` as an exact `f64` vector.
fn w(v: Vec3) -> V3<f64> {
    V3::splat(v)
}

fn len(v: V3<f64>) -> f64 {
    v.length_squared().sqrt()
}
use wide::{f32x4, f32x8, f32x16};

// ---------------------------------------------------------------------------------------------
// 1. The camera.

fn row_past_the_edge<L: Lane<Scalar = f32>>() {
    let cam = Pinhole::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 64, 48);
    for x in [u32::MAX - 1, u32::MAX, u32::MAX - 20, 64, 63, 62] {
        let p = cam.row_packet::<L>(x, 0);
        for i in 0..L::LANES {
            let inside = u64::from(x) + (i as u64) < 64;
            assert_eq!(p.ray(i).is_valid(), inside, "x = {x}, lane {i}");
            if !inside {
                assert_eq!(p.t_min().lane(i), f32::INFINITY);
                assert_eq!(p.t_max().lane(i), f32::NEG_INFINITY);
            }
        }
    }
    // Rows below the image, also at u32::MAX.
    let p = cam.row_packet::<L>(0, u32::MAX);
    assert!((0..L::LANES).all(|i| !p.ray(i).is_valid()));
}

#[test]
fn row_packet_past_u32_max_is_empty_not_wrapped() {
    row_past_the_edge::<f32>();
    row_past_the_edge::<f32x4>();
    row_past_the_edge::<f32x8>();
    row_past_the_edge::<f32x16>();
}

// ---------------------------------------------------------------------------------------------
// 2. Invalid bounds cull nothing, for `Mesh` and `FocalMesh` alike.

const MAX: f32 = f32::MAX;

#[test]
fn ritter_radius_past_f32_max_is_no_bound() {
    let far = [
        Vec3::new(MAX, 0.0, 0.0),
        Vec3::new(-MAX, 0.0, 0.0),
        Vec3::new(0.0, MAX, 0.0),
    ];
    assert_eq!(bounds::ritter(&far), None);
    // Huge but representable: a valid sphere containing every point.
    let big = [Vec3::new(MAX, 0.0, 0.0), Vec3::new(MAX / 4.0, 0.0, 0.0)];
    let s = bounds::ritter(&big).expect("a sphere");
    assert!(s.is_valid() && s.radius().is_finite());
    for p in big {
        let d = w(p) - w(s.center());
        assert!(len(d) <= s.radius() as f64);
    }
}

#[test]
fn invalid_bound_culls_nothing_in_mesh_and_focal_mesh() {
    let pos = [
        Vec3::new(5.0, -1.0, -1.0),
        Vec3::new(5.0, 1.0, -1.0),
        Vec3::new(5.0, 0.0, 1.0),
        Vec3::new(MAX, 0.0, 0.0),
        Vec3::new(-MAX, 0.0, 0.0),
        Vec3::new(0.0, MAX, 0.0),
    ];
    let idx = [[0, 1, 2], [3, 4, 5]];
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    let bounded = Mesh::bounded(&pos, &idx);
    let bad = Mesh::new(&pos, &idx).with_bound(&Sphere::new(Vec3::ZERO, -1.0));
    for mesh in [bounded, bad] {
        let h = raylane::Query::closest(&mesh, &ray);
        assert_eq!(h.map(|h| h.t), Some(5.0));
        let mut cache = [FocalTriangle::never(); 2];
        let fm = raylane::focal::FocalMesh::new(&mesh, Vec3::ZERO, &mut cache).unwrap();
        let fh = raylane::Query::closest(&fm, &RayPacket::<f32x8>::splat(&ray));
        for i in 0..8 {
            assert_eq!(fh.lane(i).map(|h| h.t), Some(5.0), "focal mesh, lane {i}");
        }
        assert_eq!(raylane::Query::closest(&fm, &ray).map(|h| h.t), Some(5.0));
        assert!(raylane::Query::any(&fm, &ray));
    }
    // The focal form of an invalid bound passes every ray, and is itself never hit.
    let e = Bound::new(&Sphere::new(Vec3::ZERO, -1.0)).focal(Vec3::ZERO);
    let rp = RayPacket::<f32>::splat(&ray);
    assert!(<Focal as FocalKernel>::candidate(
        &rp,
        &internals::sphere::focal::Splat(&e)
    ));
    assert!(!<Focal as FocalKernel>::roots(&rp, &FocalSphere::splat(&e)).any());
}

// ---------------------------------------------------------------------------------------------
// 3. Sphere kernels at extreme magnitudes: the cases of the issue.

/// The roots of `K` for one ray and sphere, in every width (asserting the widths agree).
fn roots<K: SphereKernel>(ray: &Ray, s: &Sphere) -> Vec<f32> {
    let one = K::roots(&RayPacket::<f32>::splat(ray), &SpherePacket::splat(s));
    let (r, n) = one.lane(0);
    let want = r[..n].to_vec();
    fn check<K: SphereKernel, L: Lane<Scalar = f32>>(ray: &Ray, s: &Sphere, want: &[f32]) {
        let p: Roots<L> = K::roots(&RayPacket::<L>::splat(ray), &SpherePacket::splat(s));
        for i in 0..L::LANES {
            let (r, n) = p.lane(i);
            assert_eq!(&r[..n], want, "{} lane {i} of {}", K::NAME, L::LANES);
        }
    }
    check::<K, f32x4>(ray, s, &want);
    check::<K, f32x8>(ray, s, &want);
    check::<K, f32x16>(ray, s, &want);
    want
}

fn focal_roots(ray: &Ray, s: &Sphere) -> Vec<f32> {
    let e = FocalSphere::new(ray.origin(), s);
    let r = <Focal as FocalKernel>::roots(&RayPacket::<f32>::splat(ray), &FocalSphere::splat(&e));
    let (r, n) = r.lane(0);
    r[..n].to_vec()
}

#[test]
fn huge_sphere_tiny_interval_has_no_root() {
    let s = Sphere::new(Vec3::ZERO, 1e12);
    let o = Vec3::new(1.0, 0.0, 0.0);
    let d = Vec3::new(1e12, 0.0, 0.0);
    // Exact roots ±1 − 1/r (r = d = 999999995904): nothing inside (−1e-3, 1e-3).
    let ray = Ray::with_interval(o, d, -1e-3, 1e-3);
    assert_eq!(roots::<Robust>(&ray, &s), Vec::<f32>::new());
    assert_eq!(roots::<Quadratic>(&ray, &s), Vec::<f32>::new());
    // Over (0, inf) the exit at t = 1 (1 − 1e-12, rounded) is found.
    let ray = Ray::new(o, d);
    assert_eq!(roots::<Robust>(&ray, &s), vec![1.0]);
    assert_eq!(roots::<Quadratic>(&ray, &s), vec![1.0]);
    assert_eq!(
        roots::<Robust>(&Ray::with_interval(o, d, -2.0, 2.0), &s),
        vec![-1.0, 1.0]
    );
}

#[test]
fn spheres_beyond_1e19_are_hit_with_unit_directions() {
    for r in [1.85e19f32, 1e20, 1e30, 1e38] {
        let s = Sphere::new(Vec3::ZERO, r);
        // From 2r away towards the centre: exact roots r and 3r.
        let ray = Ray::new(Vec3::new(-2.0 * r, 0.0, 0.0), Vec3::X);
        let want = vec![r, 3.0 * r];
        let want_entry = if (3.0 * r).is_finite() {
            want.clone()
        } else {
            vec![r]
        };
        for (name, got) in [
            ("robust", roots::<Robust>(&ray, &s)),
            ("quadratic", roots::<Quadratic>(&ray, &s)),
            ("quadratic-unit", roots::<QuadraticUnit>(&ray, &s)),
            ("geometric", roots::<Geometric>(&ray, &s)),
            ("focal", focal_roots(&ray, &s)),
        ] {
            assert_eq!(got, want_entry, "{name} r = {r}");
        }
        // From inside, the exit.
        let ray = Ray::new(Vec3::ZERO, Vec3::Y);
        for (name, got) in [
            ("robust", roots::<Robust>(&ray, &s)),
            ("quadratic", roots::<Quadratic>(&ray, &s)),
            ("geometric", roots::<Geometric>(&ray, &s)),
            ("focal", focal_roots(&ray, &s)),
        ] {
            assert_eq!(got, vec![r], "{name} r = {r} from inside");
        }
    }
}

#[test]
fn tiny_sphere_roots_and_normal() {
    let s = Sphere::new(Vec3::ZERO, 1e-17);
    let ray = Ray::new(Vec3::new(-2e-17, 0.0, 0.0), Vec3::new(1e-17, 0.0, 0.0));
    // Exact roots: 1 and 3 (to within an ulp of the f32 inputs' ratios).
    for (name, got) in [
        ("robust", roots::<Robust>(&ray, &s)),
        ("quadratic", roots::<Quadratic>(&ray, &s)),
    ] {
        assert_eq!(got.len(), 2, "{name}: {got:?}");
        assert!(
            (got[0] - 1.0).abs() < 1e-6 && (got[1] - 3.0).abs() < 1e-6,
            "{name}: {got:?}"
        );
    }
    let hit = internals::sphere::intersect::<Robust>(&ray, &s).unwrap();
    let sf = sphere::surface(
        &RayPacket::<f32>::splat(&ray),
        &SpherePacket::splat(&s),
        hit.t,
    );
    assert_eq!(sf.normal.lane(0), Vec3::NEG_X);
    // Smaller still: a normal from the f64 path, unit and finite.
    for r in [1e-25f32, 1e-38, 1e-44] {
        let s = Sphere::new(Vec3::ZERO, r);
        let ray = Ray::new(Vec3::new(0.0, -2.0 * r, 0.0), Vec3::Y);
        let t = internals::sphere::intersect::<Robust>(&ray, &s).map(|h| h.t);
        let Some(t) = t else {
            panic!("r = {r}: no hit")
        };
        let n = sphere::surface(&RayPacket::<f32>::splat(&ray), &SpherePacket::splat(&s), t)
            .normal
            .lane(0);
        assert!(
            n.is_finite() && (n.length() - 1.0).abs() < 1e-6,
            "r = {r}: {n}"
        );
        assert_eq!(n, Vec3::NEG_Y, "r = {r}");
    }
}

// ---------------------------------------------------------------------------------------------
// 4. Ascending roots and agreeing packet shapes near tangency of far spheres.

#[test]
fn near_tangent_far_roots_are_ascending_and_shapes_agree() {
    let mut rng = SmallRng::seed_from_u64(0x7a9e);
    let mut pairs = 0;
    let mut bad = 0;
    for _ in 0..20_000 {
        let k = rng.random_range(18..=24);
        let c = (1u64 << k) as f32 * rng.random_range(1.0f32..2.0);
        let r = rng.random_range(0.5f32..2.0);
        let axis = Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
        let o = Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
        let center = o + axis.normalize() * c;
        // Aim at the rim seen from the origin: rays within about c·2^-24 of tangency.
        let side = axis
            .cross(Vec3::new(rng.random(), rng.random(), rng.random()))
            .normalize();
        let rim = center + side * r;
        let d = (rim - o).normalize();
        let ray = Ray::new(o, d);
        let s = Sphere::new(center, r);
        for got in [
            roots::<Robust>(&ray, &s),
            roots::<Quadratic>(&ray, &s),
            roots::<Geometric>(&ray, &s),
            focal_roots(&ray, &s),
        ] {
            if got.len() == 2 {
                pairs += 1;
                bad += (got[0] > got[1]) as u32;
            }
        }
        // Both packet shapes, with decoys: the same closest hit.
        let spheres = [
            s,
            Sphere::new(center * 2.0, r),
            Sphere::new(center, r * 0.5),
        ];
        same_shapes::<Robust>(&ray, &spheres);
    }
    // Without the ordering select, 431 of these 44,479 pairs (all from robust) came back out
    // of order.
    println!("{pairs} pairs of roots, {bad} out of order");
    assert_eq!(bad, 0);
    assert!(pairs > 1000, "{pairs}");
}

fn same_shapes<K: SphereKernel>(ray: &Ray, spheres: &[Sphere]) {
    let n = internals::sphere::closest::<K, f32>(&RayPacket::splat(ray), spheres).get();
    let mut packed = [SpherePacket::<f32x8>::from_spheres(&[]); 2];
    let m = SpherePacket::pack(spheres, &mut packed);
    let soa = internals::sphere::closest_soa::<K, f32x8>(ray, &packed[..m]);
    assert_eq!(n, soa, "{}", K::NAME);
}

// ---------------------------------------------------------------------------------------------
// 5. The documented range, measured: scaling positions and radius by 2^k and directions by
//    2^j scales every exact root by 2^(k − j). Inside the range every kernel's f32 answer is
//    the unit-scale answer scaled exactly (bit for bit); outside it, a hit is within 2^-20 of
//    the exact root (the f64 fallback) or the lane misses.

/// The documented range: |o − c|, r and |d| within 2^-RANGE…2^RANGE.
const RANGE: i32 = 30;

fn pow2(e: i32) -> f32 {
    2f32.powi(e)
}

/// Exact roots of ray and sphere (double-double would be overkill: f64 on f32 inputs, with the
/// base cases far from tangency, is exact to ~2^-45 relative).
fn exact(ray: &Ray, s: &Sphere) -> [f64; 2] {
    let o = w(ray.origin()) - w(s.center());
    let d = w(ray.dir());
    let (a, b, r) = (d.dot(d), -o.dot(d), s.radius() as f64);
    let l = o + d.scale(b / a);
    let disc = a * (r * r - l.dot(l));
    let q = b + b.signum() * disc.sqrt();
    let (t0, t1) = ((o.dot(o) - r * r) / q, q / a);
    [t0.min(t1), t0.max(t1)]
}

/// What the sweep saw: the worst error outside the range (as a fraction of the tolerance),
/// lost roots, and the cases inside and outside the range.
#[derive(Default, Debug)]
struct Tally {
    worst: f64,
    lost: u32,
    outside: u32,
    inside: u32,
}

/// The roots of one kernel for one ray and sphere (scalar path).
type RootsOf = fn(&Ray, &Sphere) -> Roots<f32>;

fn kernel_roots<K: SphereKernel>(ray: &Ray, s: &Sphere) -> Roots<f32> {
    K::roots(&RayPacket::splat(ray), &SpherePacket::splat(s))
}

/// The guarded focal cache, built for the ray's origin.
fn focal_cache_roots(ray: &Ray, s: &Sphere) -> Roots<f32> {
    let e = FocalSphere::new(ray.origin(), s);
    <Focal as FocalKernel>::roots(&RayPacket::splat(ray), &FocalSphere::splat(&e))
}

/// Sweeps `roots` over scaled copies of `bases`; `unit` keeps |d| = 1, and `exact` asks for
/// bit-exact scale invariance inside the range (else only that no root is lost there).
fn sweep(
    name: &str,
    roots: RootsOf,
    unit: bool,
    exact_scale: bool,
    bases: &[(Ray, Sphere)],
    tally: &mut Tally,
) {
    let js: Vec<i32> = if unit {
        vec![0]
    } else {
        (-140..=140).step_by(5).collect()
    };
    for (ray, s) in bases {
        let base = roots(ray, s);
        let (b, bn) = base.lane(0);
        let ex = exact(ray, s);
        // The kernel's own accuracy on the base case (Quadratic loses bits to T·T − r²).
        let rel = |t: f32, x: f64| ((t as f64 - x) / x).abs();
        let base_err = (0..bn)
            .map(|i| {
                ex.iter()
                    .map(|&x| rel(b[i], x))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        let tol = (2.0 * base_err).max(1.0 / 1_048_576.0);
        for k in (-140..=140).step_by(5) {
            for &j in &js {
                let (pk, pj) = (pow2(k), pow2(j));
                let (o, c, r, d) = (
                    ray.origin() * pk,
                    s.center() * pk,
                    s.radius() * pk,
                    ray.dir() * pj,
                );
                // Only exact copies of the base case (no input under- or overflowed).
                if o / pk != ray.origin()
                    || c / pk != s.center()
                    || r / pk != s.radius()
                    || d / pj != ray.dir()
                    || !(o.is_finite() && c.is_finite() && r.is_finite() && d.is_finite())
                {
                    continue;
                }
                let scale = (k - j) as f64;
                let sray = Ray::with_interval(o, d, ray.t_min(), ray.t_max());
                let ss = Sphere::new(c, r);
                let got = roots(&sray, &ss);
                let (g, gn) = got.lane(0);
                let want_t = |t: f32| t as f64 * 2f64.powf(scale);
                // Inside the documented range, with one binade of margin for the rounding of the
                // squares the guard compares.
                let (lo, hi) = (2f64.powi(1 - RANGE), 2f64.powi(RANGE - 1));
                let inside = |m: f64| (lo..=hi).contains(&m);
                let f = len(w(o) - w(c));
                let in_range = inside(r as f64) && inside(len(w(d))) && f <= hi;
                if in_range {
                    tally.inside += 1;
                    assert_eq!(gn, bn, "{name} k={k} j={j} {ray:?} {s:?}");
                    for i in 0..gn {
                        if exact_scale {
                            assert_eq!(g[i] as f64, want_t(b[i]), "{name} k={k} j={j}");
                        } else {
                            assert!(rel(g[i], want_t(b[i])) <= tol, "{name} k={k} j={j}");
                        }
                    }
                } else {
                    tally.outside += 1;
                    // A hit is a root of the exact problem; it may be missing.
                    for &t in &g[..gn] {
                        let e = ex
                            .iter()
                            .map(|&x| {
                                // Relative, or within f32's subnormal spacing.
                                let x = x * 2f64.powf(scale);
                                let err = (t as f64 - x).abs();
                                if err <= 2f64.powi(-149) {
                                    0.0
                                } else {
                                    err / x.abs()
                                }
                            })
                            .fold(f64::INFINITY, f64::min);
                        assert!(
                            e <= tol,
                            "{} k={k} j={j}: t = {t}, exact {ex:?}·2^{scale}",
                            name
                        );
                        tally.worst = tally.worst.max(e / tol);
                    }
                    // A root lost although it is a normal f32 (the others round to 0 or inf).
                    let normal = |x: f64| (2f64.powi(-126)..=f32::MAX as f64).contains(&x.abs());
                    let lost = (0..bn).any(|i| {
                        let x = b[i] as f64 * 2f64.powf(scale);
                        normal(x) && !g[..gn].iter().any(|&t| rel(t, x) <= 2.0 * tol)
                    });
                    if lost {
                        tally.lost += 1;
                        // Measured: only where squares underflow before the guard can see them
                        // (|d| or both |o − c| and r below 2^-62).
                        let tiny = 2f64.powi(-62);
                        assert!(
                            len(w(d)) < tiny || (f < tiny && (r as f64) < tiny),
                            "{} k={k} j={j}: {:?} of {:?}",
                            name,
                            &g[..gn],
                            &b[..bn]
                        );
                    }
                }
            }
        }
    }
}

/// Base cases at unit scale: spheres at distance ≤ 8 r, rays whose line passes within 0.9 r of
/// the centre (far from tangency), from outside and inside, |d| from 1/2 to 2.
fn bases(unit: bool) -> Vec<(Ray, Sphere)> {
    let mut rng = SmallRng::seed_from_u64(0x5ca1e);
    let mut out = Vec::new();
    while out.len() < 24 {
        let s = Sphere::new(
            Vec3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                0.0,
            ),
            rng.random_range(0.5..2.0),
        );
        let o = Vec3::new(
            rng.random_range(-8.0..8.0),
            rng.random_range(-8.0..8.0),
            rng.random_range(-8.0..8.0),
        );
        let aim = s.center()
            + Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * (0.5 * s.radius());
        let mut d = aim - o;
        if unit {
            d = d.normalize();
        } else {
            d *= rng.random_range(0.5..2.0) / d.length();
        }
        let ray = Ray::new(o, d);
        let [t0, t1] = exact(&ray, &s);
        if t1 > 0.0 && (t0.abs() > 1e-3 || t0 < 0.0) {
            out.push((ray, s));
        }
    }
    out
}

#[test]
fn sphere_kernels_are_scale_exact_in_range_and_never_wrong_outside() {
    let mut all = Tally::default();
    let kernels: [(&str, RootsOf, bool, bool); 5] = [
        ("robust", kernel_roots::<Robust>, false, true),
        ("quadratic", kernel_roots::<Quadratic>, false, true),
        ("quadratic-unit", kernel_roots::<QuadraticUnit>, true, true),
        ("geometric", kernel_roots::<Geometric>, true, true),
        // The focal thresholds carry absolute floors: not bit-exact under scaling.
        ("focal", focal_cache_roots, true, false),
    ];
    for (name, f, unit, exact_scale) in kernels {
        let mut t = Tally::default();
        sweep(name, f, unit, exact_scale, &bases(unit), &mut t);
        println!("{name}: {t:?}");
        assert!(t.inside > 100 && t.outside > 100, "{name}: {t:?}");
        all.worst = all.worst.max(t.worst);
        all.lost += t.lost;
    }
    assert!(all.worst <= 1.0);
}
