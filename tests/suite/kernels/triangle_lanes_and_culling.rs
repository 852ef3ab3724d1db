//! Triangles: every lane of every width equals the scalar path bit for bit (every kernel and
//! entry point, two-sided and culled, over seeded random batches with NaN, infinite, zero and
//! degenerate lanes and padding), bad input is a miss, the focal operation counts are pinned,
//! and bounding spheres are measured (tightness against the exact minimal sphere, hits never
//! lost to culling, triangle tests saved).

use crate::sets::query_records_every_width::record;
use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::Cull;
use raylane::bounds::{self, Bound};
use raylane::kernel::LaneHit;
use raylane::lane::{Lane, Mask};
use raylane::mesh::Mesh;
use raylane::opcount::OpCounts;
use raylane::sphere::SphereKernel;
use raylane::sphere::focal::FocalKernel;
use raylane::triangle::focal::FocalRays;
use raylane::triangle::{
    self, Badouel, BaldwinWeber, Cramer, FocalTriangle, HavelHerout, Moller, Plucker,
    PrecomputedKernel, Triangle, TriangleKernel, TrianglePacket, Wald, Watertight,
};
use raylane::{Hits, Query, Ray, RayPacket};
use raylane_lab::demo::shapes;
use raylane_lab::loops as internals;
use raylane_lab::loops::HitRecord;
use raylane_lab::loops::{Best, LaneRecords};
use raylane_lab::opcount::table;
use raylane_lab::registry::{Kernel, Prim, Visitor};
use std::marker::PhantomData;
use wide::{f32x4, f32x8, f32x16};

const CULLS: [Cull; 2] = [Cull::None, Cull::Back];

/// A random f32 that is sometimes special.
fn coord(rng: &mut SmallRng, scale: f32) -> f32 {
    match rng.random_range(0..120) {
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

/// Triangles: mostly random, some degenerate (repeated or collinear vertices) or non-finite.
fn tri(rng: &mut SmallRng) -> Triangle {
    let a = vec(rng, 10.0);
    let b = vec(rng, 10.0);
    let c = match rng.random_range(0..12) {
        0 => a,
        1 => a + (b - a) * 2.0,
        _ => vec(rng, 10.0),
    };
    Triangle::new(a, b, c)
}

/// Rays: mostly aimed at a point of `t` (or at its vertex or edge, for the exact fallbacks),
/// some random, some with a zero or non-finite direction.
fn ray(rng: &mut SmallRng, t: &Triangle) -> Ray {
    let o = vec(rng, 20.0);
    let aim = match rng.random_range(0..4) {
        0 => t.a(),
        1 => (t.a() + t.b()) * 0.5,
        _ => t.point(rng.random_range(-0.2..1.0), rng.random_range(-0.2..1.0)),
    };
    let d = match rng.random_range(0..12) {
        0 => Vec3::ZERO,
        1 => vec(rng, 3.0),
        2 => (aim - o) * 1e-3,
        _ => aim - o,
    };
    Ray::new(o, d)
}

fn same<L: Lane<Scalar = f32>>(p: &LaneHit<L>, i: usize, s: &LaneHit<f32>, what: &str) {
    assert_eq!(p.mask.test(i), s.mask, "{what}: mask lane {i}");
    assert_eq!(p.t.lane(i).to_bits(), s.t.to_bits(), "{what}: t lane {i}");
    assert_eq!(p.u.lane(i).to_bits(), s.u.to_bits(), "{what}: u lane {i}");
    assert_eq!(p.v.lane(i).to_bits(), s.v.to_bits(), "{what}: v lane {i}");
    for x in [p.t.lane(i), p.u.lane(i), p.v.lane(i)] {
        assert!(!x.is_nan(), "{what}: NaN in a record");
    }
    if !s.mask {
        assert_eq!(
            (s.t, s.u, s.v),
            (f32::INFINITY, 0.0, 0.0),
            "{what}: canonical miss"
        );
    }
}

fn kernel<K: TriangleKernel, L: Lane<Scalar = f32>>(rays: &[Ray], tris: &[Triangle]) {
    let rp = RayPacket::<L>::from_rays(rays);
    let tp = TrianglePacket::<L>::from_triangles(tris);
    for cull in CULLS {
        let packed = K::intersect(&rp, &K::prepare(&rp), &tp, cull);
        for i in 0..L::LANES {
            let t = tris.get(i).copied().unwrap_or(Triangle::never());
            let r = RayPacket::<f32>::splat(&rp.ray(i));
            let s = K::intersect(&r, &K::prepare(&r), &TrianglePacket::splat(&t), cull);
            same(&packed, i, &s, K::NAME);
        }
    }
}

fn focal_kernel<L: Lane<Scalar = f32>>(rays: &[Ray], tris: &[Triangle]) {
    let rp = RayPacket::<L>::from_rays(rays);
    let entries: Vec<FocalTriangle<f32>> = (0..L::LANES)
        .map(|i| {
            let t = tris.get(i).copied().unwrap_or(Triangle::never());
            FocalTriangle::new(rp.ray(i).origin(), &t)
        })
        .collect();
    let cache = FocalTriangle::<L>::gather(&entries);
    for cull in CULLS {
        let packed =
            internals::triangle::focal::intersect_lanes(&FocalRays::new(&rp), &cache, cull);
        for (i, e) in entries.iter().enumerate() {
            let r = RayPacket::<f32>::splat(&rp.ray(i));
            let s = internals::triangle::focal::intersect_lanes(
                &FocalRays::new(&r),
                &FocalTriangle::splat(e),
                cull,
            );
            same(&packed, i, &s, "focal");
        }
    }
}

fn every_kernel<L: Lane<Scalar = f32>>(seed: u64) {
    let mut rng = SmallRng::seed_from_u64(seed);
    for _ in 0..400 {
        let tris: Vec<Triangle> = (0..L::LANES).map(|_| tri(&mut rng)).collect();
        let rays: Vec<Ray> = tris.iter().map(|t| ray(&mut rng, t)).collect();
        // Sometimes fewer rays than lanes: the padding lanes must miss.
        let n = if rng.random_range(0..8) == 0 {
            rng.random_range(0..L::LANES)
        } else {
            L::LANES
        };
        // Every triangle kernel of the registry.
        for k in Kernel::of(Prim::Triangle) {
            k.visit(Lanes::<L>(&rays[..n], &tris, PhantomData));
        }
    }
}

/// [`kernel`] or [`focal_kernel`] for a registry kernel.
struct Lanes<'a, L>(&'a [Ray], &'a [Triangle], PhantomData<L>);

impl<L: Lane<Scalar = f32>> Visitor for Lanes<'_, L> {
    type Output = ();
    fn triangle<K: TriangleKernel>(self, _: Kernel) {
        kernel::<K, L>(self.0, self.1);
    }
    fn focal_triangle(self, _: Kernel) {
        focal_kernel::<L>(self.0, self.1);
    }
    fn sphere<K: SphereKernel>(self, k: Kernel) {
        unreachable!("{} is not a triangle kernel", k.name())
    }
    fn focal_sphere<K: FocalKernel>(self, k: Kernel, _: bool) {
        unreachable!("{} is not a triangle kernel", k.name())
    }
    fn plane(self, k: Kernel) {
        unreachable!("{} is not a triangle kernel", k.name())
    }
    fn focal_plane(self, k: Kernel) {
        unreachable!("{} is not a triangle kernel", k.name())
    }
}

/// One ray against one triangle with a registry kernel (the focal cache with the eye at the
/// ray's origin).
fn intersect(k: Kernel, ray: &Ray, tri: &Triangle, cull: Cull) -> Option<HitRecord> {
    struct One<'a>(&'a Ray, &'a Triangle, Cull);
    impl Visitor for One<'_> {
        type Output = Option<HitRecord>;
        fn triangle<K: TriangleKernel>(self, _: Kernel) -> Self::Output {
            internals::triangle::intersect::<K>(self.0, self.1, self.2)
        }
        fn focal_triangle(self, _: Kernel) -> Self::Output {
            internals::triangle::focal::intersect(
                self.0,
                &FocalTriangle::new(self.0.origin(), self.1),
                self.2,
            )
        }
        fn sphere<K: SphereKernel>(self, k: Kernel) -> Self::Output {
            unreachable!("{} is not a triangle kernel", k.name())
        }
        fn focal_sphere<K: FocalKernel>(self, k: Kernel, _: bool) -> Self::Output {
            unreachable!("{} is not a triangle kernel", k.name())
        }
        fn plane(self, k: Kernel) -> Self::Output {
            unreachable!("{} is not a triangle kernel", k.name())
        }
        fn focal_plane(self, k: Kernel) -> Self::Output {
            unreachable!("{} is not a triangle kernel", k.name())
        }
    }
    k.visit(One(ray, tri, cull))
}

/// One ray against one triangle with every triangle kernel of the registry.
fn every_intersect(ray: &Ray, tri: &Triangle, cull: Cull) -> Vec<Option<HitRecord>> {
    Kernel::of(Prim::Triangle)
        .map(|k| intersect(k, ray, tri, cull))
        .collect()
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

/// A closed mesh (an octahedron with a split face fan) and rays from one eye aimed exactly at
/// its vertices and edges: the exact fallbacks of the watertight and focal kernels run in
/// packets, lane by lane.
fn fallback_lanes<L: Lane<Scalar = f32>>(seed: u64) {
    let mut rng = SmallRng::seed_from_u64(seed);
    let pos = [
        Vec3::new(1.5, 0.25, 0.0),
        Vec3::new(-1.5, 0.25, 0.0),
        Vec3::new(0.0, 1.75, 0.0),
        Vec3::new(0.0, -1.25, 0.0),
        Vec3::new(0.0, 0.25, 1.5),
        Vec3::new(0.0, 0.25, -1.5),
    ];
    let idx = [
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    let mesh = Mesh::new(&pos, &idx);
    for _ in 0..50 {
        let eye = Vec3::new(
            rng.random_range(-6.0..6.0),
            rng.random_range(-6.0..6.0),
            rng.random_range(4.0..8.0),
        );
        let rays: Vec<Ray> = (0..L::LANES)
            .map(|_| {
                let a = pos[rng.random_range(0..6)];
                let b = pos[rng.random_range(0..6)];
                let p = if rng.random_range(0..2) == 0 {
                    a
                } else {
                    (a + b) * 0.5
                };
                Ray::new(eye, p - eye)
            })
            .collect();
        let rp = RayPacket::<L>::from_rays(&rays);
        let mut cache = vec![FocalTriangle::never(); idx.len()];
        let fm = raylane::focal::FocalMesh::new(&mesh, eye, &mut cache).unwrap();
        let fr = FocalRays::new(&rp);
        for i in 0..idx.len() {
            let t = mesh.triangle(i).unwrap();
            let tp = TrianglePacket::<L>::splat(&t);
            for cull in CULLS {
                let packed = Watertight::intersect(&rp, &Watertight::prepare(&rp), &tp, cull);
                let fpacked = internals::triangle::focal::intersect_lanes(
                    &fr,
                    &FocalTriangle::splat(&fm.cache()[i]),
                    cull,
                );
                for (k, r) in rays.iter().enumerate() {
                    let s = RayPacket::<f32>::splat(r);
                    let single = Watertight::intersect(
                        &s,
                        &Watertight::prepare(&s),
                        &TrianglePacket::splat(&t),
                        cull,
                    );
                    same(&packed, k, &single, "watertight fallback");
                    let fs = internals::triangle::focal::intersect_lanes(
                        &FocalRays::new(&s),
                        &FocalTriangle::splat(&fm.cache()[i]),
                        cull,
                    );
                    same(&fpacked, k, &fs, "focal fallback");
                }
            }
        }
    }
}

#[test]
fn exact_fallback_lanes_equal_scalar() {
    fallback_lanes::<f32x4>(1);
    fallback_lanes::<f32x8>(2);
    fallback_lanes::<f32x16>(3);
}

fn same_hit<L: Lane<Scalar = f32>>(h: &Best<L>, i: usize, s: &Best<f32>, what: &str) {
    assert_eq!(h.lane(i), s.get(), "{what}: lane {i}");
    if let Some(r) = h.lane(i) {
        assert_eq!(r.t.to_bits(), s.t.to_bits(), "{what}: t bits lane {i}");
        assert!(r.u >= 0.0 && r.v >= 0.0 && !r.u.is_nan() && !r.v.is_nan());
    }
}

/// All hits as sorted `(lane, index, t bits)` triples.
type AllHits = Vec<(usize, u32, u32)>;

fn collect_hits<L: Lane<Scalar = f32>>(out: &mut AllHits, h: &Hits<L>) {
    for lane in 0..L::LANES {
        if let Some(x) = h.lane(lane) {
            out.push((lane, x.index, x.t.to_bits()));
        }
    }
}

fn collect<L: Lane<Scalar = f32>>(out: &mut AllHits, i: u32, h: &LaneHit<L>) {
    for lane in 0..L::LANES {
        if h.mask.test(lane) {
            out.push((lane, i, h.t.lane(lane).to_bits()));
        }
    }
}

fn entry_points_of<K: TriangleKernel, L: Lane<Scalar = f32>>(
    rays: &[Ray],
    tris: &[Triangle],
    mesh: &Mesh,
    cull: Cull,
) {
    let rp = RayPacket::<L>::from_rays(rays);
    let closest = internals::triangle::closest::<K, L>(&rp, tris, cull);
    let any = internals::triangle::any::<K, L>(&rp, tris, cull);
    let mut soa = vec![TrianglePacket::<L>::from_triangles(&[]); tris.len().div_ceil(L::LANES)];
    TrianglePacket::pack(tris, &mut soa);
    let mq = mesh.using::<K>().culled(cull);
    let m_closest = mq.closest(&rp);
    let m_any = mq.any(&rp);
    for (i, r) in rays.iter().enumerate() {
        let s = RayPacket::<f32>::splat(r);
        let single = internals::triangle::closest::<K, f32>(&s, tris, cull);
        same_hit(&closest, i, &single, K::NAME);
        assert_eq!(any.test(i), single.mask, "{} any", K::NAME);
        assert_eq!(
            internals::triangle::closest_soa::<K, L>(r, &soa, cull),
            single.get()
        );
        assert_eq!(
            internals::triangle::any_soa::<K, L>(r, &soa, cull),
            single.mask
        );
        if tris.len() == 1 {
            assert_eq!(
                internals::triangle::intersect::<K>(r, &tris[0], cull),
                single.get()
            );
        }
        let m_single = mq.closest(r);
        assert_eq!(m_closest.lane(i), m_single, "mesh closest, lane {i}");
        if tris.len() == mesh.len() {
            assert_eq!(record(m_single), single.get(), "mesh = its triangles");
        }
        assert_eq!(m_any.test(i), m_single.is_some(), "mesh any");
    }
    // All hits: the same per lane as the scalar path, for the slice and the mesh.
    for use_mesh in [false, true] {
        let mut seen = AllHits::new();
        let mut want = AllHits::new();
        if use_mesh {
            mq.all(&rp, |h: Hits<L>| collect_hits(&mut seen, &h));
        } else {
            internals::triangle::all::<K, L>(&rp, tris, cull, |i, h| collect(&mut seen, i, h));
        }
        for (lane, r) in rays.iter().enumerate() {
            let s = RayPacket::<f32>::splat(r);
            let mut add = |i: u32, h: &LaneHit<f32>| want.push((lane, i, h.t.to_bits()));
            if use_mesh {
                mq.all(r, |h: raylane::Hit| {
                    add(h.index, &LaneHit::new(h.t, h.u, h.v, true))
                });
            } else {
                internals::triangle::all::<K, f32>(&s, tris, cull, &mut add);
            }
        }
        seen.sort_unstable();
        want.sort_unstable();
        assert_eq!(seen, want, "{} all (mesh: {use_mesh})", K::NAME);
    }
}

/// Stored records give the hits of the kernel that precomputes per query, bit for bit.
fn stored_records<K, L>(rays: &[Ray], tris: &[Triangle], cull: Cull)
where
    K: PrecomputedKernel + TriangleKernel,
    L: Lane<Scalar = f32>,
{
    let rp = RayPacket::<L>::from_rays(rays);
    let mut records = vec![K::precompute(&TrianglePacket::<L>::splat(&tris[0])); tris.len()];
    assert_eq!(
        triangle::precompute_all::<K, L>(tris, &mut records),
        tris.len()
    );
    let stored = raylane_lab::loops::closest_with(&rp, &records, |r, rec| K::test(r, rec, cull));
    let fresh = internals::triangle::closest::<K, L>(&rp, tris, cull);
    for i in 0..rays.len() {
        assert_eq!(
            stored.lane(i),
            fresh.lane(i),
            "{} stored, lane {i}",
            <K as TriangleKernel>::NAME
        );
    }
}

fn focal_entry_points<L: Lane<Scalar = f32>>(
    eye: Vec3,
    rays: &[Ray],
    tris: &[Triangle],
    mesh: &Mesh,
    cull: Cull,
) {
    let rp = RayPacket::<L>::from_rays(rays);
    let mut cache = vec![FocalTriangle::never(); tris.len()];
    internals::triangle::focal::focus(eye, tris, &mut cache);
    let mut packed = vec![FocalTriangle::<L>::gather(&[]); tris.len().div_ceil(L::LANES)];
    FocalTriangle::pack(&cache, &mut packed);
    let closest = internals::triangle::focal::closest::<L>(&rp, &cache, cull);
    let any = internals::triangle::focal::any::<L>(&rp, &cache, cull);
    let mut mcache = vec![FocalTriangle::never(); mesh.len()];
    let fm = raylane::focal::FocalMesh::new(mesh, eye, &mut mcache)
        .unwrap()
        .culled(cull);
    let m_closest = fm.closest(&rp);
    let m_any = fm.any(&rp);
    for (i, r) in rays.iter().enumerate() {
        let s = RayPacket::<f32>::splat(r);
        let single = internals::triangle::focal::closest::<f32>(&s, &cache, cull);
        same_hit(&closest, i, &single, "focal closest");
        assert_eq!(any.test(i), single.mask, "focal any");
        assert_eq!(
            internals::triangle::focal::closest_soa::<L>(r, &packed, cull),
            single.get(),
            "focal soa"
        );
        assert_eq!(
            internals::triangle::focal::any_soa::<L>(r, &packed, cull),
            single.mask,
            "focal any soa"
        );
        let m_single = fm.closest(r);
        assert_eq!(m_closest.lane(i), m_single, "focal mesh closest, lane {i}");
        assert_eq!(record(m_single), single.get(), "focal mesh = its entries");
        assert_eq!(m_any.test(i), m_single.is_some(), "focal mesh any");
        // The focal kernel finds what the watertight kernel finds, up to edge ties.
        if let (Some(a), Some(b)) = (m_single, mesh.using::<Watertight>().culled(cull).closest(r)) {
            assert!(
                (a.t - b.t).abs() <= 1e-4 * a.t.abs().max(1.0),
                "focal {a:?} vs watertight {b:?}"
            );
        }
    }
    let mut seen = AllHits::new();
    fm.all(&rp, |h: Hits<L>| collect_hits(&mut seen, &h));
    let mut want = AllHits::new();
    for (lane, r) in rays.iter().enumerate() {
        fm.all(r, |h: raylane::Hit| {
            want.push((lane, h.index, h.t.to_bits()))
        });
    }
    seen.sort_unstable();
    want.sort_unstable();
    assert_eq!(seen, want, "focal mesh all");
}

fn entry_points<L: Lane<Scalar = f32>>(seed: u64) {
    let mut rng = SmallRng::seed_from_u64(seed);
    for round in 0..40 {
        // A random soup with shared vertices, NaN positions and out-of-range indices.
        let pos: Vec<Vec3> = (0..20).map(|_| vec(&mut rng, 6.0)).collect();
        let idx: Vec<[u32; 3]> = (0..23)
            .map(|_| [0; 3].map(|_| rng.random_range(0..21u32)))
            .collect();
        let mesh = if round % 2 == 0 {
            Mesh::bounded(&pos, &idx)
        } else {
            Mesh::new(&pos, &idx)
        };
        let tris: Vec<Triangle> = (0..mesh.len())
            .map(|i| mesh.triangle(i).unwrap_or(Triangle::never()))
            .collect();
        let rays: Vec<Ray> = (0..L::LANES)
            .map(|i| ray(&mut rng, &tris[i % tris.len()]))
            .collect();
        for cull in CULLS {
            entry_points_of::<Cramer, L>(&rays, &tris, &mesh, cull);
            entry_points_of::<Moller, L>(&rays, &tris, &mesh, cull);
            entry_points_of::<Watertight, L>(&rays, &tris, &mesh, cull);
            entry_points_of::<Plucker, L>(&rays, &tris, &mesh, cull);
            entry_points_of::<Wald, L>(&rays, &tris, &mesh, cull);
            stored_records::<Wald, L>(&rays, &tris, cull);
            stored_records::<Badouel, L>(&rays, &tris, cull);
            stored_records::<HavelHerout, L>(&rays, &tris, cull);
            stored_records::<BaldwinWeber, L>(&rays, &tris, cull);
            entry_points_of::<Moller, L>(&rays[..1], &tris[..1], &mesh, cull);
            // Rays from one eye for the focal caches.
            let eye = Vec3::new(
                rng.random_range(-9.0..9.0),
                rng.random_range(-9.0..9.0),
                9.0,
            );
            let frays: Vec<Ray> = rays.iter().map(|r| Ray::new(eye, r.dir())).collect();
            focal_entry_points::<L>(eye, &frays, &tris, &mesh, cull);
        }
    }
}

#[test]
fn entry_points_equal_scalar() {
    entry_points::<f32x4>(40);
    entry_points::<f32x8>(80);
    entry_points::<f32x16>(160);
}

#[test]
fn bad_input_is_a_miss() {
    let good = Triangle::new(
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
    );
    let down = Ray::new(Vec3::new(1.0, 1.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
    let one = |r: &Ray, t: &Triangle| every_intersect(r, t, Cull::None);
    for h in one(&down, &good) {
        let h = h.expect("the base case hits");
        assert_eq!((h.t, h.u), (5.0, 0.25));
        assert!((h.v - 1.0 / 3.0).abs() < 1e-7);
    }
    let nan = f32::NAN;
    let bad_tris = [
        Triangle::new(Vec3::new(nan, 0.0, 0.0), Vec3::X, Vec3::Y),
        Triangle::new(Vec3::ZERO, Vec3::new(0.0, f32::INFINITY, 0.0), Vec3::Y),
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0),
        Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO),
        Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::Y),
        Triangle::new(
            Vec3::ZERO,
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(0.2, 0.4, 0.6),
        ),
    ];
    for t in &bad_tris {
        assert!(!t.is_valid());
        for h in one(&down, t) {
            assert_eq!(h, None);
        }
    }
    let bad_rays = [
        Ray::new(Vec3::new(1.0, 1.0, 5.0), Vec3::ZERO),
        Ray::new(Vec3::new(nan, 1.0, 5.0), Vec3::new(0.0, 0.0, -1.0)),
        Ray::new(
            Vec3::new(1.0, 1.0, 5.0),
            Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
        ),
        Ray::new(Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 1.0)), // origin on the triangle
        Ray::new(Vec3::new(-5.0, 1.0, 0.0), Vec3::X),                 // in the plane
        Ray::new(Vec3::new(-5.0, 1.0, 1.0), Vec3::X),                 // parallel
        Ray::with_interval(
            Vec3::new(1.0, 1.0, 5.0),
            Vec3::new(0.0, 0.0, -1.0),
            0.0,
            5.0,
        ),
    ];
    for r in &bad_rays {
        for h in one(r, &good) {
            assert_eq!(h, None, "{r:?}");
        }
    }
    // Culling keeps front faces only: the base case is a front face (d·N < 0).
    let up = Ray::new(Vec3::new(1.0, 1.0, -5.0), Vec3::new(0.0, 0.0, 1.0));
    for h in every_intersect(&down, &good, Cull::Back) {
        assert!(h.is_some());
    }
    for h in every_intersect(&up, &good, Cull::Back) {
        assert_eq!(h, None);
    }
    // A mesh with out-of-range indices and NaN positions: skipped, never a panic.
    let pos = [Vec3::ZERO, Vec3::X, Vec3::new(nan, 0.0, 0.0)];
    let idx = [[0, 1, 7], [0, 1, 2], [u32::MAX, 0, 1]];
    let mesh = Mesh::bounded(&pos, &idx);
    assert!(mesh.triangle(0).is_none() && !mesh.triangle(1).unwrap().is_valid());
    let r = RayPacket::<f32x8>::splat(&down);
    assert!(mesh.closest(&r).mask.none());
    let mut cache = [FocalTriangle::never(); 3];
    assert!(
        raylane::focal::FocalMesh::new(&mesh, down.origin(), &mut cache)
            .unwrap()
            .closest(&r)
            .mask
            .none()
    );
}

/// The focal kernel's counts, pinned: a miss costs 9 mul and 6 add; edges passed but the
/// triangle behind the eye (`t > 0` is the sign of `V`, exact) 9 mul and 6 add; a hit with
/// `t`, `u`, `v` 13 mul, 10 add, 1 div: `det = D·N` from the cached plane normal (3 mul,
/// 2 add), `|e_ca| + |e_ab|` and `Σ|e|` (2 add) for the barycentrics' denominator and the
/// fallback, the upper end as `±V < t_max·det` (1 mul), then `t = ±V/det`, the division that
/// only the hits winning so far reach in a closest-hit loop. `u`, `v` are divided once per
/// ray, for the winner (not per test).
#[test]
fn focal_counts_are_pinned() {
    let get = |kernel: &str, path: &str| {
        table()
            .iter()
            .find(|r| r.kernel == kernel && r.path == path)
            .unwrap_or_else(|| panic!("no row {kernel}/{path}"))
            .counts
    };
    let c = OpCounts::new;
    let miss = get("triangle-focal", "miss");
    let behind = get("triangle-focal", "behind");
    let hit = get("triangle-focal", "hit");
    assert_eq!(miss, c(9, 6, 0, 0, 6));
    assert!(miss.mul <= 9 && miss.add <= 6 && miss.div == 0);
    // Edges passed, the triangle behind the eye: no flop more than a miss.
    assert_eq!(behind, c(9, 6, 0, 0, 8));
    // The hit with t, u, v: 13 mul, 10 add, 1 div.
    // cmp: the interval and the range guard (`src/triangle/mod.rs`, `within`).
    assert_eq!(hit, c(13, 10, 1, 0, 15));
    assert_eq!(hit.minus(&behind), c(4, 4, 1, 0, 7));
    // A doubtful lane costs the same f32 work (the exact predicate runs in f64, uncounted).
    assert_eq!(get("triangle-focal", "doubtful").flops(), hit.flops());
    // Per ray and query: the exact scaling and the unit direction.
    assert_eq!(get("triangle-focal", "per ray"), c(9, 2, 1, 1, 2));
    // The other kernels, for comparison.
    assert_eq!(get("moller", "miss"), c(21, 22, 0, 0, 5));
    assert_eq!(get("moller", "hit"), c(25, 24, 1, 0, 12));
    assert_eq!(get("watertight", "miss"), c(12, 18, 0, 0, 6));
    assert_eq!(get("watertight", "hit"), c(19, 22, 1, 0, 15));
    assert_eq!(get("cramer", "hit"), c(30, 27, 3, 0, 7));
}

/// The `doubtful` row of the report takes the exact path and still hits.
#[test]
fn focal_doubtful_rays_hit() {
    let tri = Triangle::new(
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
    );
    let eye = Vec3::new(1.0, 1.0, 5.0);
    let e = FocalTriangle::new(eye, &tri);
    // The edge value of AB is exactly zero; its normal (0, −20, 4) has first nonzero
    // component y < 0, and the other two edges are negative: a front face, claimed.
    let r = Ray::new(eye, Vec3::new(2.0, 0.0, 0.0) - eye);
    let h = internals::triangle::focal::intersect(&r, &e, Cull::None)
        .expect("claimed by simulation of simplicity");
    assert_eq!((h.t, h.u, h.v), (1.0, 0.5, 0.0));
}

// ---------------------------------------------------------------------------------------------
// Bounding spheres.

type P = [f64; 3];

fn d2(a: P, b: P) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// The smallest ball through the support points (1 to 4 of them).
fn ball(s: &[P]) -> (P, f64) {
    let sub = |a: P, b: P| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: P, b: P| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: P, b: P| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    match s.len() {
        0 => ([0.0; 3], -1.0),
        1 => (s[0], 0.0),
        2 => {
            let c = [0, 1, 2].map(|k| (s[0][k] + s[1][k]) / 2.0);
            (c, d2(c, s[0]))
        }
        3 => {
            let (a, b) = (sub(s[1], s[0]), sub(s[2], s[0]));
            let n = cross(a, b);
            let nn = dot(n, n);
            let x = cross(n, a);
            let y = cross(b, n);
            let o = [0, 1, 2].map(|k| (dot(b, b) * x[k] + dot(a, a) * y[k]) / (2.0 * nn));
            let c = [0, 1, 2].map(|k| s[0][k] + o[k]);
            (c, d2(c, s[0]))
        }
        _ => {
            let (a, b, c) = (sub(s[1], s[0]), sub(s[2], s[0]), sub(s[3], s[0]));
            let det = dot(a, cross(b, c));
            let (aa, bb, cc) = (dot(a, a), dot(b, b), dot(c, c));
            let (bc, ca, ab) = (cross(b, c), cross(c, a), cross(a, b));
            let o = [0, 1, 2].map(|k| (aa * bc[k] + bb * ca[k] + cc * ab[k]) / (2.0 * det));
            let ctr = [0, 1, 2].map(|k| s[0][k] + o[k]);
            (ctr, d2(ctr, s[0]))
        }
    }
}

/// Welzl's minimal enclosing ball (move-to-front form), exact up to f64 rounding.
fn welzl(pts: &mut Vec<P>, n: usize, support: &mut Vec<P>) -> (P, f64) {
    let mut b = ball(support);
    if support.len() == 4 {
        return b;
    }
    let mut i = 0;
    while i < n {
        let p = pts[i];
        if b.1 < 0.0 || d2(p, b.0) > b.1 * (1.0 + 1e-12) + 1e-300 {
            support.push(p);
            b = welzl(pts, i, support);
            support.pop();
            pts.remove(i);
            pts.insert(0, p);
        }
        i += 1;
    }
    b
}

fn minimal_radius(points: &[Vec3], rng: &mut SmallRng) -> f64 {
    let mut p: Vec<P> = points
        .iter()
        .map(|v| [v.x as f64, v.y as f64, v.z as f64])
        .collect();
    for i in (1..p.len()).rev() {
        p.swap(i, rng.random_range(0..=i));
    }
    let n = p.len();
    let (c, r2) = welzl(&mut p, n, &mut Vec::new());
    for q in &p {
        assert!(
            d2(*q, c) <= r2 * (1.0 + 1e-9) + 1e-12,
            "welzl does not enclose"
        );
    }
    r2.sqrt()
}

fn cloud(rng: &mut SmallRng, kind: usize, n: usize) -> Vec<Vec3> {
    let c = Vec3::new(
        rng.random_range(-5.0..5.0),
        rng.random_range(-5.0..5.0),
        3.0,
    );
    (0..n)
        .map(|_| {
            let u = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            // A cube, a sphere's surface, a flat box, a ball clustered near its centre.
            c + match kind {
                0 => u,
                1 => u.normalize_or_zero() * 2.0,
                2 => u * Vec3::new(4.0, 1.0, 0.25),
                _ => u.normalize_or_zero() * rng.random_range(0.0..1.0f32).powi(3),
            }
        })
        .collect()
}

#[test]
fn ritter_sphere_is_tight_and_encloses() {
    let mut rng = SmallRng::seed_from_u64(5);
    let names = ["cube cloud", "sphere surface", "flat box", "clustered ball"];
    println!("bounding sphere radius / minimal radius (Welzl), 40 sets of 300 points each:");
    let mut worst: f64 = 1.0;
    for (kind, name) in names.iter().enumerate() {
        let (mut sum, mut max) = (0.0, 0.0f64);
        for _ in 0..40 {
            let pts = cloud(&mut rng, kind, 300);
            let s = bounds::ritter(&pts).unwrap();
            for p in &pts {
                let (p, c) = ([p.x, p.y, p.z], s.center());
                let d = d2(p.map(|x| x as f64), [c.x as f64, c.y as f64, c.z as f64]).sqrt();
                assert!(
                    d <= s.radius() as f64,
                    "a point outside the bounding sphere"
                );
            }
            let ratio = s.radius() as f64 / minimal_radius(&pts, &mut rng);
            assert!(ratio >= 1.0 - 1e-6 && ratio <= 3f64.sqrt());
            sum += ratio;
            max = max.max(ratio);
        }
        println!("  {name}: mean {:.4}, worst {:.4}", sum / 40.0, max);
        worst = worst.max(max);
    }
    assert!(
        worst < 1.25,
        "Ritter's sphere much looser than expected: {worst}"
    );
    // Indexed: only referenced, in-range, finite vertices count.
    let pos = [
        Vec3::ZERO,
        Vec3::X,
        Vec3::splat(100.0),
        Vec3::splat(f32::NAN),
        Vec3::Y,
    ];
    let s = bounds::ritter_indexed(&pos, &[[0, 1, 4], [0, 3, 1], [0, 1, 9]]).unwrap();
    assert!(s.radius() < 1.0);
    assert!(bounds::ritter(&[]).is_none());
}

/// A scene of many small meshes (icosahedra) and rays from one eye, most missing most meshes.
struct Scene {
    pos: Vec<Vec<Vec3>>,
    idx: Vec<[u32; 3]>,
}

/// The unit icosahedron (the demo's icosphere of frequency 1): 12 vertices, 20 triangles.
fn icosahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (mut pos, mut idx) = (vec![Vec3::ZERO; 12], vec![[0; 3]; 20]);
    assert_eq!(shapes::icosphere(1, &mut pos, &mut idx), Some((12, 20)));
    (pos, idx)
}

fn scene(rng: &mut SmallRng, n: usize) -> Scene {
    let (unit, idx) = icosahedron();
    let pos = (0..n)
        .map(|_| {
            let c = Vec3::new(
                rng.random_range(-20.0..20.0),
                rng.random_range(-20.0..20.0),
                rng.random_range(10.0..60.0),
            );
            let r = rng.random_range(0.3..1.5f32);
            unit.iter().map(|p| c + *p * r).collect()
        })
        .collect();
    Scene { pos, idx }
}

/// Rays that test the culling hardest: aimed at the vertices farthest from each bound's centre
/// (on the bounding surface), at edge points there, and grazing the bounding sphere there.
fn rim_rays(rng: &mut SmallRng, eye: Vec3, meshes: &[Mesh]) -> Vec<Ray> {
    let mut out = Vec::new();
    for m in meshes {
        let s = m.bound().unwrap().sphere();
        let far = m
            .positions()
            .iter()
            .copied()
            .max_by(|a, b| a.distance(s.center()).total_cmp(&b.distance(s.center())))
            .unwrap();
        let next = m.positions()[rng.random_range(0..m.positions().len())];
        for p in [far, (far + next) * 0.5, far + (next - far) * 0.01] {
            out.push(Ray::new(eye, p - eye));
            // Tangent to the bounding sphere at p, from a nearby origin.
            let n = (p - s.center()).normalize();
            let t = n.any_orthonormal_vector();
            out.push(Ray::new(p - t * 3.0, t));
        }
    }
    out
}

#[test]
fn culling_never_loses_a_hit_and_saves_tests() {
    let mut rng = SmallRng::seed_from_u64(11);
    let sc = scene(&mut rng, 120);
    let bounded: Vec<Mesh> = sc.pos.iter().map(|p| Mesh::bounded(p, &sc.idx)).collect();
    let plain: Vec<Mesh> = sc.pos.iter().map(|p| Mesh::new(p, &sc.idx)).collect();
    let eye = Vec3::new(0.0, 0.0, -5.0);
    let mut rays: Vec<Ray> = (0..800)
        .map(|_| {
            let d = Vec3::new(
                rng.random_range(-0.5..0.5),
                rng.random_range(-0.5..0.5),
                1.0,
            );
            Ray::new(eye, d)
        })
        .collect();
    rays.extend(rim_rays(&mut rng, eye, &bounded));
    let tris_per_mesh = sc.idx.len();
    let (mut tested, mut focal_tested, mut hits) = (0usize, 0usize, 0usize);
    let mut caches: Vec<Vec<FocalTriangle<f32>>> =
        vec![vec![FocalTriangle::never(); tris_per_mesh]; bounded.len()];
    // General bound, every kernel: the same closest and all hits with and without culling.
    for r in &rays {
        let rp = RayPacket::<f32>::splat(r);
        for (b, p) in bounded.iter().zip(&plain) {
            if b.may_hit(&rp) {
                tested += tris_per_mesh;
            }
            fn check<K: TriangleKernel>(b: &Mesh, p: &Mesh, rp: &RayPacket<f32>) -> Option<f32> {
                let (x, y) = (b.using::<K>().closest(rp), p.using::<K>().closest(rp));
                assert_eq!(x.lane(0), y.lane(0), "{}: culling lost a hit", K::NAME);
                let (mut hx, mut hy) = (Vec::new(), Vec::new());
                b.using::<K>().all(rp, |h: Hits<f32>| hx.push(h.lane(0)));
                p.using::<K>().all(rp, |h: Hits<f32>| hy.push(h.lane(0)));
                assert_eq!(hx, hy, "{}: culling lost a hit", K::NAME);
                y.lane(0).map(|h| h.t)
            }
            check::<Cramer>(b, p, &rp);
            check::<Moller>(b, p, &rp);
            if check::<Watertight>(b, p, &rp).is_some() {
                hits += 1;
            }
        }
    }
    // The focal path: the bound as a FocalSphere, tested first.
    let mut focal_hits = 0;
    let focal_rays: Vec<Ray> = rays.iter().filter(|r| r.origin() == eye).copied().collect();
    let fms: Vec<_> = bounded
        .iter()
        .zip(caches.iter_mut())
        .map(|(b, c)| raylane::focal::FocalMesh::new(b, eye, c).unwrap())
        .collect();
    let mut pcaches: Vec<Vec<FocalTriangle<f32>>> =
        vec![vec![FocalTriangle::never(); tris_per_mesh]; plain.len()];
    let fps: Vec<_> = plain
        .iter()
        .zip(pcaches.iter_mut())
        .map(|(p, c)| raylane::focal::FocalMesh::new(p, eye, c).unwrap())
        .collect();
    for r in &focal_rays {
        let fr = FocalRays::new(&RayPacket::<f32>::splat(r));
        for (b, p) in fms.iter().zip(&fps) {
            if b.may_hit(&fr) {
                focal_tested += tris_per_mesh;
            }
            let (x, y) = (b.closest(r), p.closest(r));
            assert_eq!(x, y, "focal: culling lost a hit");
            focal_hits += y.is_some() as usize;
        }
    }
    let all = rays.len() * bounded.len() * tris_per_mesh;
    let focal_all = focal_rays.len() * bounded.len() * tris_per_mesh;
    println!(
        "culling: {} rays x {} meshes of {} triangles ({} ray-mesh hits): {} of {} triangle tests \
         run ({:.2} %, {:.1}x fewer)",
        rays.len(),
        bounded.len(),
        tris_per_mesh,
        hits,
        tested,
        all,
        100.0 * tested as f64 / all as f64,
        all as f64 / tested as f64
    );
    println!(
        "focal culling: {} rays from the eye ({} ray-mesh hits): {} of {} triangle tests run \
         ({:.2} %)",
        focal_rays.len(),
        focal_hits,
        focal_tested,
        focal_all,
        100.0 * focal_tested as f64 / focal_all as f64
    );
    assert!(
        hits > 100 && tested * 10 < all,
        "the scene should cull most tests"
    );
    assert!(focal_tested * 10 < focal_all);
    // The culling sphere is close to the mesh's own bounding sphere.
    let b = Bound::new(&bounded[0].bound().unwrap().sphere());
    assert_eq!(&b, bounded[0].bound().unwrap());
}

/// The four kernels agree, two-sided and culled, on well-conditioned random cases: the same
/// hit or miss, `t`, `u`, `v` within 1e-4.
#[test]
fn kernels_agree_with_each_other() {
    let mut rng = SmallRng::seed_from_u64(21);
    let mut front = 0;
    for _ in 0..3000 {
        let v = |rng: &mut SmallRng| {
            Vec3::new(
                rng.random_range(-5.0..5.0),
                rng.random_range(-5.0..5.0),
                rng.random_range(-5.0..5.0),
            )
        };
        let t = Triangle::new(v(&mut rng), v(&mut rng), v(&mut rng));
        let o = v(&mut rng) * 3.0;
        let (u, w) = (
            rng.random_range(-0.5..1.0f32),
            rng.random_range(-0.5..1.0f32),
        );
        let r = Ray::new(o, (t.point(u, w) - o) * rng.random_range(0.1..10.0f32));
        // Skip grazing rays and aims near an edge (ill-conditioned for the textbook forms).
        let n = (t.b() - t.a()).cross(t.c() - t.a());
        let cos = (r.dir().dot(n) / (r.dir().length() * n.length())).abs();
        if cos < 0.05 || [u, w, 1.0 - u - w].iter().any(|x| x.abs() < 0.02) {
            continue;
        }
        for cull in CULLS {
            let all = every_intersect(&r, &t, cull);
            let cramer = intersect(Kernel::Cramer, &r, &t, cull);
            let inside = u >= 0.0 && w >= 0.0 && u + w <= 1.0;
            let facing = r.dir().dot(n) < 0.0;
            let want = inside && (cull == Cull::None || facing);
            front += (want && cull == Cull::Back) as usize;
            for h in &all {
                assert_eq!(h.is_some(), want, "{r:?} {t:?} {cull:?}: {all:?}");
                if let (Some(h), Some(g)) = (h, cramer) {
                    assert!((h.t - g.t).abs() <= 1e-4 * g.t);
                    assert!((h.u - g.u).abs() <= 1e-4 && (h.v - g.v).abs() <= 1e-4);
                }
            }
        }
    }
    assert!(front > 100);
}
