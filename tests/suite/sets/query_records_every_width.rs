//! Queries (issue 11): every lane of a packet query at widths 1, 4, 8 and 16 equals the one-ray
//! query, bit for bit, in every field of the record; the records keep the `t`, `u`, `v` and
//! index of the existing closest-hit loops; points and normals are what they claim.
//!
//! Over seeded random rays (some with NaN, infinite or zero directions, some not unit length)
//! against random spheres and planes and the vendored bunny, for the default kernels, other
//! kernels through `using`, culled queries and a scene of three sets.

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::Cull;
use raylane::lane::{Lane, Mask};
use raylane::plane::Plane;
use raylane::sphere::{Geometric, Quadratic, QuadraticUnit, Robust, Sphere};
use raylane::triangle::{Moller, Triangle, Watertight};
use raylane::{Hit, Hits, Query, Ray, RayPacket};
use raylane_lab::loops as internals;
use raylane_lab::loops::LaneRecords;
use wide::{f32x4, f32x8, f32x16};

use crate::sets::bunny_visible_surface::load_bin;

fn coord(rng: &mut SmallRng, scale: f32) -> f32 {
    match rng.random_range(0..200) {
        0 => f32::NAN,
        1 => f32::INFINITY,
        2 => 0.0,
        _ => rng.random_range(-scale..scale),
    }
}

fn vec(rng: &mut SmallRng, scale: f32) -> Vec3 {
    Vec3::new(coord(rng, scale), coord(rng, scale), coord(rng, scale))
}

/// Rays around a model of size `scale` centred at `c`: mostly aimed at it.
fn ray(rng: &mut SmallRng, c: Vec3, scale: f32) -> Ray {
    let o = c + vec(rng, 3.0 * scale);
    let d = match rng.random_range(0..10) {
        0 => Vec3::ZERO,
        1 => vec(rng, 3.0),
        2..=7 => (c + vec(rng, 0.5 * scale) - o).normalize_or_zero(),
        _ => vec(rng, 1.0).normalize_or_zero(),
    };
    if rng.random_range(0..8) == 0 {
        Ray::with_interval(o, d, -1.0, rng.random_range(0.0..4.0 * scale))
    } else {
        Ray::new(o, d)
    }
}

/// A query's record as the kernels' record (`t`, `u`, `v`, index), for the tests that compare
/// with the kernels' own entry points.
pub fn record(h: Option<Hit>) -> Option<raylane_lab::loops::HitRecord> {
    h.map(|h| raylane_lab::loops::HitRecord {
        t: h.t,
        u: h.u,
        v: h.v,
        index: h.index,
    })
}

/// The record's bits (so `-0`/`+0` would show); shared with the BVH tests.
pub(crate) fn bits(h: Option<Hit>) -> Option<[u32; 12]> {
    h.map(|h| {
        [
            h.t.to_bits(),
            h.point.x.to_bits(),
            h.point.y.to_bits(),
            h.point.z.to_bits(),
            h.normal.x.to_bits(),
            h.normal.y.to_bits(),
            h.normal.z.to_bits(),
            h.front as u32,
            h.index,
            h.set,
            h.u.to_bits(),
            h.v.to_bits(),
        ]
    })
}

/// Every lane of `q`'s packet answers for `rays` equals the one-ray answers; returns the
/// one-ray closest hits.
fn same<Q: Query + ?Sized, L: Lane<Scalar = f32>>(
    q: &Q,
    rays: &[Ray],
    what: &str,
) -> Vec<Option<Hit>> {
    let mut out = Vec::new();
    for chunk in rays.chunks(L::LANES) {
        let p = RayPacket::<L>::from_rays(chunk);
        let hits: Hits<L> = q.closest(&p);
        let any = q.any(&p);
        let mut all: Vec<Vec<[u32; 12]>> = vec![Vec::new(); L::LANES];
        q.all(&p, |h: Hits<L>| {
            for (i, v) in all.iter_mut().enumerate() {
                if let Some(b) = bits(h.lane(i)) {
                    v.push(b);
                }
            }
        });
        for (i, r) in chunk.iter().enumerate() {
            let one = q.closest(r);
            assert_eq!(
                bits(hits.lane(i)),
                bits(one),
                "{what}: closest, lane {i}, {r:?}"
            );
            assert_eq!(any.test(i), q.any(r), "{what}: any, lane {i}, {r:?}");
            assert_eq!(any.test(i), one.is_some(), "{what}: any vs closest, {r:?}");
            let mut each = Vec::new();
            q.all(r, |h: Hit| each.push(bits(Some(h)).unwrap()));
            assert_eq!(all[i], each, "{what}: all, lane {i}, {r:?}");
            if let Some(h) = one {
                check_record(&h, r, what);
                assert!(
                    each.contains(&bits(one).unwrap()),
                    "{what}: all lacks the closest"
                );
            }
            out.push(one);
        }
        for i in chunk.len()..L::LANES {
            assert!(
                !hits.mask.test(i) && !any.test(i),
                "{what}: padding lane {i} hit"
            );
        }
    }
    out
}

fn check_record(h: &Hit, r: &Ray, what: &str) {
    assert!(h.t > r.t_min() && h.t < r.t_max(), "{what}: t outside");
    assert_eq!(h.point, r.at(h.t), "{what}: point is o + t·d");
    let n = h.normal.length();
    assert!((n - 1.0).abs() < 1e-6, "{what}: |normal| = {n}");
    assert!(
        h.normal.dot(r.dir()) <= 0.0,
        "{what}: normal faces away from the origin"
    );
    for x in [h.u, h.v] {
        assert!((0.0..=1.0).contains(&x), "{what}: barycentric {x}");
    }
}

fn every_width<Q: Query + ?Sized>(q: &Q, rays: &[Ray], what: &str) -> Vec<Option<Hit>> {
    let one = same::<Q, f32>(q, rays, what);
    for w in [
        same::<Q, f32x4>(q, rays, what),
        same::<Q, f32x8>(q, rays, what),
        same::<Q, f32x16>(q, rays, what),
    ] {
        assert_eq!(
            w.iter().map(|h| bits(*h)).collect::<Vec<_>>(),
            one.iter().map(|h| bits(*h)).collect::<Vec<_>>()
        );
    }
    one
}

/// The centre of the points' bounding box and half its diagonal: what [`ray`] aims around.
fn around(pos: &[Vec3]) -> (Vec3, f32) {
    let (lo, hi) = pos
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    ((lo + hi) / 2.0, (hi - lo).length() / 2.0)
}

fn spheres(rng: &mut SmallRng, n: usize) -> Vec<Sphere> {
    (0..n)
        .map(|_| {
            let r = match rng.random_range(0..20) {
                0 => -1.0,
                1 => f32::NAN,
                _ => rng.random_range(0.05..3.0),
            };
            Sphere::new(vec(rng, 8.0), r)
        })
        .collect()
}

#[test]
fn sphere_queries_every_lane_equals_one_ray() {
    let mut rng = SmallRng::seed_from_u64(11);
    for _ in 0..6 {
        let s = spheres(&mut rng, 24);
        let rays: Vec<Ray> = (0..160).map(|_| ray(&mut rng, Vec3::ZERO, 8.0)).collect();
        let hits = every_width(&s[..], &rays, "spheres");
        // The same t and index as the existing loop.
        for (r, h) in rays.iter().zip(&hits) {
            let old = internals::sphere::closest::<Robust, f32>(&RayPacket::splat(r), &s).get();
            assert_eq!(
                old.map(|o| (o.t.to_bits(), o.index)),
                h.map(|h| (h.t.to_bits(), h.index))
            );
        }
        let n = hits.iter().filter(|h| h.is_some()).count();
        assert!(n > 20, "{n} sphere hits");
        every_width(&s.using::<Quadratic>(), &rays, "quadratic");
        every_width(&s.using::<QuadraticUnit>(), &rays, "quadratic unit");
        every_width(&s.using::<Geometric>(), &rays, "geometric");
        every_width(&s.using::<Robust>().culled(Cull::Back), &rays, "culled");
    }
}

#[test]
fn triangle_queries_every_lane_equals_one_ray() {
    let m = load_bin(include_bytes!("../../data/bunny.bin"));
    let tris: Vec<Triangle> = m
        .idx
        .iter()
        .map(|t| {
            Triangle::new(
                m.pos[t[0] as usize],
                m.pos[t[1] as usize],
                m.pos[t[2] as usize],
            )
        })
        .collect();
    let (c, size) = around(&m.pos);
    let mut rng = SmallRng::seed_from_u64(12);
    let mut rays: Vec<Ray> = (0..160).map(|_| ray(&mut rng, c, size)).collect();
    // Some from inside the body: back faces.
    rays.extend((0..40).map(|_| Ray::new(c, vec(&mut rng, 1.0))));
    let hits = every_width(&tris[..], &rays, "watertight");
    for (r, h) in rays.iter().zip(&hits) {
        let old = internals::triangle::closest::<Watertight, f32>(
            &RayPacket::splat(r),
            &tris,
            Cull::None,
        )
        .get();
        let key = |t: f32, u: f32, v: f32, i: u32| (t.to_bits(), u.to_bits(), v.to_bits(), i);
        assert_eq!(
            old.map(|o| key(o.t, o.u, o.v, o.index)),
            h.map(|h| key(h.t, h.u, h.v, h.index))
        );
    }
    let n = hits.iter().filter(|h| h.is_some()).count();
    assert!(n > 20, "{n} triangle hits");
    let fronts = hits.iter().flatten().filter(|h| h.front).count();
    assert!(fronts > 0 && fronts < n, "{fronts} of {n} front faces");
    every_width(&tris.using::<Moller>(), &rays, "moller");
    let culled = every_width(
        &tris.using::<Watertight>().culled(Cull::Back),
        &rays,
        "culled",
    );
    assert!(culled.iter().flatten().all(|h| h.front));
}

#[test]
fn plane_and_scene_queries_every_lane_equals_one_ray() {
    let mut rng = SmallRng::seed_from_u64(13);
    let planes: Vec<Plane> = (0..5)
        .map(|_| Plane::new(vec(&mut rng, 8.0), vec(&mut rng, 2.0)))
        .collect();
    let s = spheres(&mut rng, 12);
    let tris: Vec<Triangle> = (0..12)
        .map(|_| Triangle::new(vec(&mut rng, 8.0), vec(&mut rng, 8.0), vec(&mut rng, 8.0)))
        .collect();
    let rays: Vec<Ray> = (0..160).map(|_| ray(&mut rng, Vec3::ZERO, 8.0)).collect();
    every_width(&planes[..], &rays, "planes");
    let scene = (&s[..], &tris[..], &planes[..]);
    let hits = every_width(&scene, &rays, "scene");
    // The scene's answer is the closest of its sets' answers (ties to the earlier set).
    for (r, h) in rays.iter().zip(&hits) {
        let parts = [s.closest(r), tris.closest(r), planes.closest(r)];
        let mut want: Option<Hit> = None;
        for (k, p) in parts.into_iter().enumerate() {
            if let Some(p) = p
                && want.is_none_or(|w| p.t < w.t)
            {
                want = Some(Hit { set: k as u32, ..p });
            }
        }
        assert_eq!(bits(*h), bits(want), "scene vs sets: {r:?}");
    }
    let sets: Vec<u32> = hits.iter().flatten().map(|h| h.set).collect();
    for k in 0..3 {
        assert!(sets.contains(&k), "no hit of set {k}");
    }
}

#[test]
fn mesh_and_focal_mesh_queries_every_lane_equals_one_ray() {
    use raylane::mesh::Mesh;
    use raylane::set::TooSmall;
    use raylane::triangle::FocalTriangle;
    let m = load_bin(include_bytes!("../../data/bunny.bin"));
    // Two invalid triangles (an index out of range, a zero-area one): listed once, never hit.
    let mut idx = m.idx.clone();
    idx.push([0, 0, 1]);
    idx.push([0, 1, u32::MAX]);
    let tris: Vec<Triangle> = idx
        .iter()
        .map(|t| {
            let p = |k: u32| m.pos.get(k as usize).copied();
            match (p(t[0]), p(t[1]), p(t[2])) {
                (Some(a), Some(b), Some(c)) => Triangle::new(a, b, c),
                _ => Triangle::never(),
            }
        })
        .collect();
    let mesh = Mesh::new(&m.pos, &idx);
    assert_eq!(mesh.invalid(), 2);
    let bounded = Mesh::bounded(&m.pos, &idx);
    let (c, size) = around(&m.pos);
    let mut rng = SmallRng::seed_from_u64(14);
    let rays: Vec<Ray> = (0..120).map(|_| ray(&mut rng, c, size)).collect();
    let want = every_width(&tris[..], &rays, "triangles");
    for (q, what) in [(mesh, "mesh"), (bounded, "bounded mesh")] {
        let got = every_width(&q, &rays, what);
        assert_eq!(
            got.iter().map(|h| bits(*h)).collect::<Vec<_>>(),
            want.iter().map(|h| bits(*h)).collect::<Vec<_>>(),
            "{what} vs the same triangles"
        );
    }
    // Focal: rays from the eye; rays from elsewhere get the mesh's own answer, bit for bit.
    let eye = c + Vec3::new(0.2, 0.3, 2.0) * size;
    let mut cache = vec![FocalTriangle::never(); raylane::focal::FocalMesh::needed(&mesh)];
    assert_eq!(
        raylane::focal::FocalMesh::new(&mesh, eye, &mut cache[..10]).err(),
        Some(TooSmall { needed: idx.len() })
    );
    let fm = raylane::focal::FocalMesh::new(&bounded, eye, &mut cache).unwrap();
    let from_eye: Vec<Ray> = (0..160)
        .map(|_| Ray::new(eye, (c + vec(&mut rng, 0.6 * size) - eye).normalize()))
        .collect();
    let hits = every_width(&fm, &from_eye, "focal mesh");
    assert!(hits.iter().flatten().count() > 40);
    for (r, h) in from_eye.iter().zip(&hits) {
        // The same surface as Watertight, nearly the same t (different kernels).
        let w = tris.closest(r);
        assert_eq!(h.map(|h| h.index), w.map(|w| w.index), "{r:?}");
        let elsewhere = Ray::new(r.origin() + Vec3::X * 1e-3, r.dir());
        assert_eq!(
            bits(Query::closest(&fm, &elsewhere)),
            bits(bounded.closest(&elsewhere))
        );
        assert_eq!(Query::any(&fm, &elsewhere), bounded.any(&elsewhere));
    }
    let culled = every_width(&fm.culled(Cull::Back), &from_eye, "culled focal mesh");
    assert!(culled.iter().flatten().all(|h| h.front));
}

#[test]
fn sets_of_parts_equal_the_whole_mesh() {
    use raylane::mesh::Mesh;
    use raylane::set::Sets;
    let m = load_bin(include_bytes!("../../data/bunny.bin"));
    // Consecutive runs of the triangles, each a bounded mesh over the shared vertices; one
    // empty part (no bound, no triangle).
    let mut starts = vec![0usize];
    for len in [1, 0, 7, 100, 500, 33].into_iter().cycle() {
        let s = *starts.last().unwrap();
        if s + len >= m.idx.len() {
            break;
        }
        starts.push(s + len);
    }
    starts.push(m.idx.len());
    let parts: Vec<Mesh> = starts
        .windows(2)
        .map(|w| Mesh::bounded(&m.pos, &m.idx[w[0]..w[1]]))
        .collect();
    // The same parts as groups of three (a member owning several sets).
    let groups: Vec<Sets<Mesh>> = parts.chunks(3).map(Sets).collect();
    let whole = Mesh::bounded(&m.pos, &m.idx);
    let (c, size) = around(&m.pos);
    let mut rng = SmallRng::seed_from_u64(32);
    let rays: Vec<Ray> = (0..160).map(|_| ray(&mut rng, c, size)).collect();
    let want = every_width(&whole, &rays, "whole mesh");
    let got = every_width(&Sets(&parts), &rays, "parts");
    assert!(got.iter().flatten().map(|h| h.set).max() > Some(3));
    let as_whole = |h: Option<Hit>| {
        h.map(|h| Hit {
            index: starts[h.set as usize] as u32 + h.index,
            set: 0,
            ..h
        })
    };
    for (w, g) in want.iter().zip(&got) {
        assert_eq!(bits(as_whole(*g)), bits(*w));
    }
    let nested = every_width(&Sets(&groups), &rays, "groups of parts");
    assert_eq!(
        nested.iter().map(|h| bits(*h)).collect::<Vec<_>>(),
        got.iter().map(|h| bits(*h)).collect::<Vec<_>>()
    );
}

#[test]
fn focal_spheres_and_planes_answer_every_ray() {
    use raylane::Dir;
    use raylane::focal::FocalPlanes;
    use raylane::focal::FocalSpheres;
    use raylane::plane::FocalPlane;
    use raylane::set::TooSmall;
    use raylane::sphere::FocalSphere;
    let mut rng = SmallRng::seed_from_u64(15);
    let s = spheres(&mut rng, 20);
    let planes: Vec<Plane> = (0..4)
        .map(|_| Plane::new(vec(&mut rng, 8.0), vec(&mut rng, 2.0)))
        .collect();
    let eye = Vec3::new(1.0, 2.0, 12.0);
    let mut sc = vec![FocalSphere::pass_all(); FocalSpheres::needed(&s)];
    assert_eq!(
        FocalSpheres::new(&s, eye, &mut sc[..3]).err(),
        Some(TooSmall { needed: 20 })
    );
    let fs = FocalSpheres::new(&s, eye, &mut sc).unwrap();
    let mut pc = vec![FocalPlane::new(eye, &planes[0]); FocalPlanes::needed(&planes)];
    let fp = FocalPlanes::new(&planes, eye, &mut pc).unwrap();
    let rays: Vec<Ray> = (0..160)
        .map(|_| match Dir::new(vec(&mut rng, 8.0) - eye) {
            Some(d) => Ray::unit(eye, d),
            None => Ray::new(eye, Vec3::ZERO),
        })
        .collect();
    let hits = every_width(&fs, &rays, "focal spheres");
    assert!(hits.iter().flatten().count() > 20);
    for (r, h) in rays.iter().zip(&hits) {
        // The same sphere and face as Robust, t within the focal kernel's 2^-16.
        let w = s.closest(r);
        assert_eq!(
            h.map(|h| (h.index, h.front)),
            w.map(|w| (w.index, w.front)),
            "{r:?}"
        );
        if let (Some(h), Some(w)) = (h, w) {
            assert!((h.t - w.t).abs() <= w.t * 1.0 / 65536.0);
        }
        // Not from the eye, or not unit length: the spheres' own answer (Robust), bit for bit.
        let moved = Ray::new(r.origin() + Vec3::Y, r.dir());
        let long = Ray::new(r.origin(), r.dir() * 1.5);
        for other in [moved, long] {
            assert_eq!(
                bits(fs.closest(&other)),
                bits(s.closest(&other)),
                "{other:?}"
            );
            assert_eq!(fs.any(&other), s.any(&other));
        }
    }
    every_width(&fs.culled(Cull::Back), &rays, "culled focal spheres");
    let ph = every_width(&fp, &rays, "focal planes");
    for (r, h) in rays.iter().zip(&ph) {
        assert_eq!(
            bits(*h),
            bits(planes.closest(r)),
            "focal planes vs planes: {r:?}"
        );
        let moved = Ray::new(r.origin() + Vec3::X, r.dir());
        assert_eq!(bits(fp.closest(&moved)), bits(planes.closest(&moved)));
    }
    assert_eq!(Dir::new(Vec3::ZERO), None);
    assert_eq!(
        Dir::new(Vec3::new(0.0, 3e38, 3e38)).unwrap().get().y,
        core::f32::consts::FRAC_1_SQRT_2
    );
    assert!(Dir::new(Vec3::new(1e-40, 0.0, 0.0)).unwrap().get() == Vec3::X);
}
