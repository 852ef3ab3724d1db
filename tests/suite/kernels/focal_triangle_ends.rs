//! Focal triangles at the ends of `f32` (a hit is strictly inside its interval, finite, and
//! every entry point agrees), the fill rule on lone triangles and closed fans, and `+0` in
//! records (issue 10: the interval bug, Required 5 and 6).

use glam::Vec3;
use raylane::Cull;
use raylane::lane::{Lane, Mask};
use raylane::mesh::Mesh;
use raylane::triangle::{Cramer, FocalTriangle, Moller, Triangle, TriangleKernel, Watertight};
use raylane::{Query, Ray, RayPacket};
use raylane_lab::loops as internals;
use raylane_lab::loops::HitRecord;
use raylane_lab::loops::LaneRecords;
use wide::{f32x4, f32x8, f32x16};

/// Every focal entry point on one ray over `tris` from the ray's origin: the scalar record
/// (or `None`), after checking that all of them agree bit for bit.
fn focal_all_entry_points(ray: &Ray, tris: &[Triangle], cull: Cull) -> Option<HitRecord> {
    let eye = ray.origin();
    let cache: Vec<FocalTriangle<f32>> = tris.iter().map(|t| FocalTriangle::new(eye, t)).collect();
    let want =
        internals::triangle::focal::closest(&RayPacket::<f32>::splat(ray), &cache, cull).get();
    let same = |h: Option<HitRecord>, what: &str| {
        let bits = |h: Option<HitRecord>| {
            h.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.index))
        };
        assert_eq!(bits(h), bits(want), "{what} on {ray:?}");
    };
    fn packets<L: Lane<Scalar = f32>>(
        ray: &Ray,
        cache: &[FocalTriangle<f32>],
        cull: Cull,
    ) -> (Vec<Option<HitRecord>>, Option<HitRecord>, bool, bool) {
        let rp = RayPacket::<L>::splat(ray);
        let h = internals::triangle::focal::closest(&rp, cache, cull);
        let lanes = (0..L::LANES).map(|i| h.lane(i)).collect();
        let mut packed = vec![FocalTriangle::<L>::gather(&[]); cache.len().div_ceil(L::LANES)];
        FocalTriangle::pack(cache, &mut packed);
        let soa = internals::triangle::focal::closest_soa(ray, &packed, cull);
        let any = internals::triangle::focal::any(&rp, cache, cull).all();
        let any_soa = internals::triangle::focal::any_soa(ray, &packed, cull);
        (lanes, soa, any, any_soa)
    }
    let check = |(lanes, soa, any, any_soa): (Vec<Option<HitRecord>>, _, bool, bool), w: &str| {
        for h in lanes {
            same(h, w);
        }
        same(soa, w);
        assert_eq!(any, want.is_some(), "any x{w}");
        assert_eq!(any_soa, want.is_some(), "any_soa x{w}");
    };
    check(packets::<f32>(ray, &cache, cull), "1");
    check(packets::<f32x4>(ray, &cache, cull), "4");
    check(packets::<f32x8>(ray, &cache, cull), "8");
    check(packets::<f32x16>(ray, &cache, cull), "16");
    // One triangle at a time, and `all`.
    let mut first: Option<HitRecord> = None;
    for (i, e) in cache.iter().enumerate() {
        if let Some(h) = internals::triangle::focal::intersect(ray, e, cull)
            && first.is_none_or(|f| h.t < f.t)
        {
            first = Some(HitRecord {
                index: i as u32,
                ..h
            });
        }
    }
    // The same t; the same triangle unless distinct scaled t underflowed to one own-unit t
    // (the loops compare in the scaled units: every packet shape agrees, checked above).
    assert_eq!(
        first.map(|h| h.t.to_bits()),
        want.map(|h| h.t.to_bits()),
        "intersect"
    );
    if first.is_some_and(|h| h.t != 0.0 && h.t.is_normal()) {
        same(first, "intersect");
    }
    // The mesh over shared positions, with and without its bound.
    let positions: Vec<Vec3> = tris.iter().flat_map(|t| [t.a(), t.b(), t.c()]).collect();
    let indices: Vec<[u32; 3]> = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    for mesh in [
        Mesh::new(&positions, &indices),
        Mesh::bounded(&positions, &indices),
    ] {
        let mut out = vec![FocalTriangle::never(); tris.len()];
        let fm = raylane::focal::FocalMesh::new(&mesh, eye, &mut out)
            .unwrap()
            .culled(cull);
        let fr = RayPacket::<f32x8>::splat(ray);
        let h = fm.closest(&fr);
        for i in 0..8 {
            same(
                crate::sets::query_records_every_width::record(h.lane(i)),
                "FocalMesh::closest",
            );
        }
        assert_eq!(fm.any(&fr).all(), want.is_some(), "FocalMesh::any");
        let mut n = 0;
        fm.all(&fr, |h: raylane::Hits<f32x8>| n += h.mask.any() as usize);
        assert_eq!(n > 0, want.is_some(), "FocalMesh::all");
    }
    if let Some(h) = want {
        assert!(
            h.t > ray.t_min() && h.t < ray.t_max() && h.t.is_finite(),
            "{h:?}"
        );
        assert!(h.u.is_finite() && h.v.is_finite());
    }
    want
}

fn wall(x: f32) -> Triangle {
    Triangle::new(
        Vec3::new(x, -1.0, -1.0),
        Vec3::new(x, 1.0, -1.0),
        Vec3::new(x, 0.0, 1.0),
    )
}

/// Issue 10: a tiny direction put the hit at `t = 10^41`, reported as `inf`; a huge one put a
/// hit at `t = 3.3·10^-46`, reported as `0` with `t_min = 0`. Both are clean misses now, on
/// every entry point, as with Möller and Watertight.
#[test]
fn focal_hits_never_leave_their_interval() {
    let tiny = Ray::new(Vec3::ZERO, Vec3::new(1.0e-40, 0.0, 0.0));
    assert_eq!(
        focal_all_entry_points(&tiny, &[wall(10.0)], Cull::None),
        None
    );
    let huge = Ray::new(Vec3::ZERO, Vec3::new(3.0e38, 0.0, 0.0));
    assert_eq!(
        focal_all_entry_points(&huge, &[wall(1.0e-7)], Cull::None),
        None
    );
    for (ray, tri) in [(&tiny, wall(10.0)), (&huge, wall(1.0e-7))] {
        assert!(internals::triangle::intersect::<Moller>(ray, &tri, Cull::None).is_none());
        assert!(internals::triangle::intersect::<Watertight>(ray, &tri, Cull::None).is_none());
    }
    // Representable t at the ends: a subnormal t (1e-6/3e38 = 3.3e-45 → 2 or 3·2^-149) and a
    // t just below f32::MAX are hits.
    let h = focal_all_entry_points(&huge, &[wall(1.0e-6)], Cull::None).expect("subnormal t");
    assert!(h.t > 0.0 && h.t < 1.0e-44, "{h:?}");
    let big = Ray::new(Vec3::ZERO, Vec3::new(1.0e-30, 0.0, 0.0));
    let h = focal_all_entry_points(&big, &[wall(1.0e8)], Cull::None).expect("t = 1e38");
    assert!((h.t / 1.0e38 - 1.0).abs() < 1.0e-6, "{h:?}");
    // A sweep of magnitudes and intervals (walls in front and behind): every hit inside, every
    // entry point agreeing; with t_min = −inf a wall far behind must not come back at −inf.
    let mut hits = 0;
    for k in (-140..=127).step_by(3) {
        let d = Vec3::new(2f32.powi(k) * 1.5, 0.0, 2f32.powi(k) * 0.25);
        for x in [1.0e-30f32, 1.0e-6, 1.0, 1.0e6, 1.0e30] {
            for (lo, hi) in [
                (0.0, f32::INFINITY),
                (f32::NEG_INFINITY, f32::INFINITY),
                (-1.0, 1.0),
                (1.0e-44, 1.0e-38),
                (1.0e37, f32::MAX),
            ] {
                let ray = Ray::with_interval(Vec3::ZERO, d, lo, hi);
                let walls = [wall(x), wall(2.0 * x), wall(-x)];
                let h = focal_all_entry_points(&ray, &walls, Cull::None);
                hits += h.is_some() as usize;
            }
        }
    }
    assert!(hits > 100, "{hits}");
}

/// The fill rule: an exactly zero edge value takes the sign it has for the direction nudged by
/// `(ε, ε², ε³)`. Rays exactly through vertex C of a lone triangle in the plane z = 0 land,
/// nudged, at C + (ε, ε², …): the triangle (0,0,0), (4,0,0), (0,3,0) lies below-left of that
/// point and misses with focal from every eye, while (4,−1,0), (4,2,0), (0,0,0) contains the
/// +x side of its C and is hit; Cramer, Möller and Watertight count both vertices as inside.
/// In a closed fan around a vertex, exactly one triangle claims the ray.
#[test]
fn focal_fill_rule_on_lone_triangles_and_fans() {
    let (a, b, c) = (
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
    );
    let tri = Triangle::new(a, b, c);
    fn others(ray: &Ray, t: &Triangle) -> [bool; 3] {
        fn one<K: TriangleKernel>(ray: &Ray, t: &Triangle) -> bool {
            internals::triangle::intersect::<K>(ray, t, Cull::None).is_some()
        }
        [
            one::<Cramer>(ray, t),
            one::<Moller>(ray, t),
            one::<Watertight>(ray, t),
        ]
    }
    let right = Triangle::new(
        Vec3::new(4.0, -1.0, 0.0),
        Vec3::new(4.0, 2.0, 0.0),
        Vec3::ZERO,
    );
    for eye in [
        Vec3::new(1.0, 1.0, 5.0),
        Vec3::new(-1.0, 5.0, 5.0),
        Vec3::new(3.0, -2.0, -4.0),
    ] {
        for (t, claimed) in [(tri, false), (right, true)] {
            let ray = Ray::new(eye, t.c() - eye);
            let f = focal_all_entry_points(&ray, &[t], Cull::None);
            assert_eq!(f.is_some(), claimed, "eye {eye}, triangle {t:?}");
            assert_eq!(others(&ray, &t), [true; 3]);
        }
    }
    // A closed fan around C (a hexagon in the plane z = 0, and a cone): one triangle each.
    for lift in [0.0f32, 1.5, -2.0] {
        let ring: Vec<Vec3> = (0..6)
            .map(|i| {
                let a = i as f32 * core::f32::consts::TAU / 6.0 + 0.3;
                c + Vec3::new(2.0 * a.cos(), 2.0 * a.sin(), -lift)
            })
            .collect();
        let fan: Vec<Triangle> = (0..6)
            .map(|i| Triangle::new(c, ring[i], ring[(i + 1) % 6]))
            .collect();
        for eye in [
            Vec3::new(1.0, 1.0, 5.0),
            Vec3::new(-1.0, 5.0, 5.0),
            Vec3::new(0.0, 3.0, 7.0),
            Vec3::new(0.5, 1.0, 3.0),
        ] {
            // (Every direction within 35° of −z: inside both cones, whose half-angles are 45°
            // and 53°, so the true surface is crossed once.)
            let ray = Ray::new(eye, c - eye);
            let cache: Vec<_> = fan.iter().map(|t| FocalTriangle::new(eye, t)).collect();
            let n = cache
                .iter()
                .filter(|e| internals::triangle::focal::intersect(&ray, e, Cull::None).is_some())
                .count();
            assert_eq!(n, 1, "fan lift {lift}, eye {eye}");
            assert!(focal_all_entry_points(&ray, &fan, Cull::None).is_some());
        }
    }
}

/// Records carry `+0`: Watertight and Möller fold the sign of a back face into zero
/// barycentrics (`−0`); every entry point now returns `+0`, in every lane.
#[test]
fn records_carry_plus_zero() {
    let tri = Triangle::new(
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
    );
    // Through the point (1, 0, 0) of edge AB (v = 0) and the point (0, 1, 0) of edge CA
    // (u = 0), from behind and from the front.
    let rays = [
        Ray::new(Vec3::new(1.0, 0.0, -5.0), Vec3::Z),
        Ray::new(Vec3::new(1.0, 0.0, 5.0), Vec3::NEG_Z),
        Ray::new(Vec3::new(0.0, 1.0, -5.0), Vec3::Z),
        Ray::new(Vec3::new(0.0, 1.0, 5.0), Vec3::NEG_Z),
    ];
    fn check<K: TriangleKernel>(ray: &Ray, tri: &Triangle) -> usize {
        let plus = |h: HitRecord| {
            for x in [h.u, h.v] {
                assert!(x != 0.0 || x.to_bits() == 0, "{} gives -0: {h:?}", K::NAME);
            }
        };
        let mut n = 0;
        if let Some(h) = internals::triangle::intersect::<K>(ray, tri, Cull::None) {
            plus(h);
            n += 1;
        }
        let h =
            internals::triangle::closest::<K, f32x8>(&RayPacket::splat(ray), &[*tri], Cull::None);
        (0..8).filter_map(|i| h.lane(i)).for_each(plus);
        let h = internals::triangle::closest::<K, f32>(&RayPacket::splat(ray), &[*tri], Cull::None);
        h.get().into_iter().for_each(plus);
        n
    }
    let mut hits = 0;
    for ray in &rays {
        hits += check::<Watertight>(ray, &tri) + check::<Moller>(ray, &tri);
        hits += check::<Cramer>(ray, &tri);
        if let Some(h) = focal_all_entry_points(ray, &[tri], Cull::None) {
            assert!(h.u.to_bits() == 0 || h.u != 0.0);
            assert!(h.v.to_bits() == 0 || h.v != 0.0);
        }
    }
    assert!(hits >= 8, "{hits}");
}
