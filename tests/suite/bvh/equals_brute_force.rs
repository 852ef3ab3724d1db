//! The BVH (issue 14, items 1–3): built over caller storage, its closest hit equals brute
//! force's with the same kernel bit for bit (`t`, `u`, `v`, index; ties to the lower index) at
//! every width, `any` agrees, and bad input builds a valid tree.
//!
//! Scenes: random triangle soups and sphere sets, the vendored bunny, the watertightness
//! edge/vertex sets (every hit of every ray equals brute force's, so the BVH leaks exactly as
//! often as Watertight does: never), rays that graze box faces exactly and run along them,
//! and bad input (NaN/inf and coincident vertices, empty and one-triangle meshes, a thousand
//! copies of one triangle, all primitives at one point, coordinates near `1e30`).

use crate::sets::query_records_every_width::bits;
use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::Cull;
use raylane::bvh::{self, BuildError, Bvh, Node, Packed, Primitives, Scratch, Sphere4, Tri4};
use raylane::mesh::Mesh;
use raylane::set::TooSmall;
use raylane::sphere::{Robust, Sphere};
use raylane::triangle::{Moller, Triangle, Watertight};
use raylane::{Hit, Lane, Mask, Query, Ray, RayPacket};
use wide::{f32x4, f32x8, f32x16};

/// A tree over `p` in owned vectors trimmed to what the build used.
pub(crate) fn owned<P: Primitives + ?Sized>(p: &P) -> (Vec<Node>, Vec<P::Leaf>) {
    let need = bvh::TriangleBvh::needed(p.count());
    let mut nodes = vec![Node::EMPTY; need.nodes];
    let mut leaves = vec![P::Leaf::EMPTY; need.leaves];
    let mut scratch = vec![Scratch::default(); need.scratch];
    let (n, l) = {
        let b =
            bvh::Bvh::build(p, &mut nodes, &mut leaves, &mut scratch).expect("storage from needed");
        (b.nodes().len(), b.leaves().len())
    };
    nodes.truncate(n);
    leaves.truncate(l);
    (nodes, leaves)
}

pub(crate) fn v3(rng: &mut SmallRng, s: f32) -> Vec3 {
    Vec3::new(
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    )
}

/// Random rays at a scene in `[-1, 1]^3`: half aimed at `aim` points (so they hit), some with
/// finite or negative interval ends.
pub(crate) fn rays(rng: &mut SmallRng, n: usize, aim: &[Vec3]) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let o = v3(rng, 3.0);
            let d = if i % 2 == 0 && !aim.is_empty() {
                aim[rng.random_range(0..aim.len())] - o
            } else {
                v3(rng, 1.0)
            };
            match i % 5 {
                0 => Ray::with_interval(o, d, 0.0, rng.random_range(0.2..2.0)),
                1 => Ray::with_interval(o, d, -rng.random_range(0.0..2.0), f32::INFINITY),
                _ => Ray::new(o, d),
            }
        })
        .collect()
}

/// Packets of `L` rays: the tree's records equal the flat set's, lane by lane; `any` agrees.
fn packets_of<L: Lane<Scalar = f32>>(rays: &[Ray], tree: &impl Query, flat: &impl Query) {
    for (c, chunk) in rays.chunks(L::LANES).enumerate() {
        let p = RayPacket::<L>::from_rays(chunk);
        let want = flat.closest(&p);
        let got = tree.closest(&p);
        for i in 0..L::LANES {
            assert_eq!(
                bits(got.lane(i)),
                bits(want.lane(i)),
                "{} lanes, packet {c}, lane {i}: {:?}",
                L::LANES,
                chunk.get(i)
            );
        }
        assert_eq!(tree.any(&p).bits(), flat.any(&p).bits());
    }
}

/// The closest hit over `flat` by brute force under the tie rule `(t, id, position)`, with
/// `ids[i]` the id of `flat[i]` (ids need not be unique): the smallest `t`, ties to the lower
/// id, then to the earlier triangle; that triangle's record, with its id.
pub(crate) fn brute_with_ids(flat: &[Triangle], ids: &[u32], r: &Ray) -> Option<[u32; 12]> {
    let mut best: Option<(f32, u32, u32)> = None;
    flat.all(r, |h| {
        let key = (h.t, ids[h.index as usize], h.index);
        if best.is_none_or(|b| key < b) {
            best = Some(key);
        }
    });
    best.map(|(_, id, at)| {
        let at = at as usize;
        let mut h = flat[at..=at].closest(r).expect("the winner hits alone");
        h.index = id;
        bits(Some(h)).unwrap()
    })
}

/// `tree`'s closest hits of `rays`, one ray at a time and in packets of 1, 4, 8 and 16 of them
/// (so that a lane may follow another lane's visiting order), are `want`'s, bit for bit; `any`
/// agrees.
pub(crate) fn every_width(tree: &impl Query, rays: &[Ray], want: &[Option<[u32; 12]>]) {
    for (i, r) in rays.iter().enumerate() {
        assert_eq!(bits(tree.closest(r)), want[i], "one ray, ray {i}: {r:?}");
        assert_eq!(tree.any(r), want[i].is_some(), "any, ray {i}: {r:?}");
    }
    packets_want::<f32>(tree, rays, want);
    packets_want::<f32x4>(tree, rays, want);
    packets_want::<f32x8>(tree, rays, want);
    packets_want::<f32x16>(tree, rays, want);
}

fn packets_want<L: Lane<Scalar = f32>>(
    tree: &impl Query,
    rays: &[Ray],
    want: &[Option<[u32; 12]>],
) {
    for (c, chunk) in rays.chunks(L::LANES).enumerate() {
        let got = tree.closest(&RayPacket::<L>::from_rays(chunk));
        for (i, r) in chunk.iter().enumerate() {
            let k = c * L::LANES + i;
            assert_eq!(
                bits(got.lane(i)),
                want[k],
                "{} lanes, ray {k}: {r:?}",
                L::LANES
            );
        }
    }
}

/// The tree against the flat set on every ray: one-ray `closest`/`any` and packets of 1, 4,
/// 8, 16 rays, bit for bit. Returns the number of hits.
pub(crate) fn check(tree: &impl Query, flat: &impl Query, rays: &[Ray]) -> usize {
    let mut hits = 0;
    for (i, r) in rays.iter().enumerate() {
        let want = flat.closest(r);
        hits += want.is_some() as usize;
        assert_eq!(bits(tree.closest(r)), bits(want), "ray {i}: {r:?}");
        assert_eq!(tree.any(r), flat.any(r), "any, ray {i}: {r:?}");
    }
    packets_of::<f32>(rays, tree, flat);
    packets_of::<f32x4>(rays, tree, flat);
    packets_of::<f32x8>(rays, tree, flat);
    packets_of::<f32x16>(rays, tree, flat);
    hits
}

/// Checks a triangle set against brute force on `rays`; returns the hit count. Also with
/// another kernel ([`Moller`]), which the tree takes as the flat set does.
fn check_tris(tris: &[Triangle], rays: &[Ray]) -> usize {
    let (nodes, leaves) = owned(tris);
    let tree = Bvh::from_parts(&nodes, &leaves).expect("a valid tree");
    check(
        &tree.using::<Moller>(),
        &tris.using::<Moller>(),
        &rays[..rays.len().min(300)],
    );
    check(&tree, &tris, rays)
}

fn check_spheres(spheres: &[Sphere], rays: &[Ray]) -> usize {
    let (nodes, leaves) = owned(spheres);
    let tree = Bvh::from_parts(&nodes, &leaves).expect("a valid tree");
    check(&tree, &spheres, rays)
}

/// A mesh's triangles as a flat set (the reference).
pub(crate) fn flat(mesh: &Mesh) -> Vec<Triangle> {
    (0..mesh.len()).map(|i| mesh.triangle(i).unwrap()).collect()
}

pub(crate) fn soup(rng: &mut SmallRng, n: usize) -> Vec<Triangle> {
    (0..n)
        .map(|_| {
            let a = v3(rng, 1.0);
            let s = rng.random_range(0.02..0.4);
            Triangle::new(a, a + v3(rng, s), a + v3(rng, s))
        })
        .collect()
}

pub(crate) fn centroids(tris: &[Triangle]) -> Vec<Vec3> {
    tris.iter()
        .filter(|t| t.is_valid())
        .map(|t| (t.a() + t.b() + t.c()) / 3.0)
        .collect()
}

#[test]
fn random_triangle_soups_equal_brute_force() {
    let mut rng = SmallRng::seed_from_u64(14);
    for n in [1usize, 2, 5, 9, 33, 200, 1500] {
        let tris = soup(&mut rng, n);
        let rs = rays(&mut rng, 800, &centroids(&tris));
        let hits = check_tris(&tris, &rs);
        assert!(hits > 100, "{n} triangles: only {hits} hits");
        // Front faces only.
        let (nodes, leaves) = owned(&tris[..]);
        let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
        let culled = tris[..].using::<Watertight>().culled(Cull::Back);
        assert!(check(&tree.culled(Cull::Back), &culled, &rs[..200]) > 20);
    }
}

#[test]
fn random_sphere_sets_equal_brute_force() {
    let mut rng = SmallRng::seed_from_u64(15);
    for n in [1usize, 3, 8, 100, 1000] {
        let spheres: Vec<Sphere> = (0..n)
            .map(|_| Sphere::new(v3(&mut rng, 1.0), rng.random_range(0.01..0.2)))
            .collect();
        let aim: Vec<Vec3> = spheres.iter().map(|s| s.center()).collect();
        let rs = rays(&mut rng, 800, &aim);
        let hits = check_spheres(&spheres, &rs);
        assert!(hits > 100, "{n} spheres: only {hits} hits");
        let (nodes, leaves) = owned(&spheres[..]);
        let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
        let culled = spheres[..].using::<Robust>().culled(Cull::Back);
        assert!(check(&tree.culled(Cull::Back), &culled, &rs[..200]) > 20);
    }
}

/// Packets of 16 rays from one eye in the plane of a face of a sphere's box, aimed within
/// `2^-16` of the point where the sphere touches that face: tangent rays that graze the box
/// (hits and misses decided by rounding). The frustum's prune of the leaf's sphere boxes must
/// let every such sphere through; the answers equal brute force at every width.
#[test]
fn sphere_packets_at_their_boxes_faces() {
    let mut rng = SmallRng::seed_from_u64(23);
    let mut spheres = Vec::new();
    for i in 0..27 {
        let c = Vec3::new((i % 3) as f32, (i / 3 % 3) as f32, (i / 9) as f32);
        spheres.push(Sphere::new(c, 0.4));
    }
    let mut rs = Vec::new();
    for _ in 0..60 {
        let s = spheres[rng.random_range(0..spheres.len())];
        let mut axis = Vec3::ZERO;
        axis[rng.random_range(0..3)] = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let p = s.center() + axis * s.radius();
        // A direction in the face's plane (perpendicular to the axis).
        let u = v3(&mut rng, 1.0).reject_from_normalized(axis);
        let eye = p + u.normalize_or(Vec3::ONE.reject_from_normalized(axis)) * 3.0;
        for _ in 0..16 {
            let jitter = v3(&mut rng, 1.0) * (1.0 / 65536.0);
            rs.push(Ray::new(eye, p + jitter - eye));
        }
    }
    let hits = check_spheres(&spheres, &rs);
    assert!(hits > 100, "{hits}");
}

#[test]
fn vendored_bunny_equals_brute_force() {
    let m = crate::sets::bunny_visible_surface::load_bin(include_bytes!("../../data/bunny.bin"));
    let mesh = Mesh::new(&m.pos, &m.idx);
    let (nodes, leaves) = owned(&mesh);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let (lo, hi) = m.pos.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(l, h), &p| (l.min(p), h.max(p)),
    );
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    let mut rng = SmallRng::seed_from_u64(16);
    let mut rs = Vec::new();
    for _ in 0..12 {
        let eye = c + v3(&mut rng, 1.0).normalize_or(Vec3::X) * r * rng.random_range(1.2..4.0);
        for _ in 0..200 {
            let target = c + v3(&mut rng, r * 0.8);
            rs.push(Ray::new(eye, target - eye));
        }
    }
    let tris = flat(&mesh);
    let hits = check(&tree, &&tris[..], &rs);
    assert!(hits > 500, "{hits} hits");
    let s = tree.stats();
    assert_eq!(s.primitives, m.idx.len());
    assert!(s.depth <= bvh::MAX_DEPTH);
}

/// Every hit of every watertightness ray (aimed at shared vertices and edges) equals brute
/// force's, so the tree leaks exactly when Watertight does: never (0 leaks, asserted).
#[test]
fn watertight_sets_no_leaks_through_the_tree() {
    for (si, s) in crate::kernels::watertight_no_leaks::shapes()
        .iter()
        .enumerate()
    {
        let mesh = Mesh::new(&s.pos, &s.idx);
        let (nodes, leaves) = owned(&mesh);
        let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
        let cases = crate::kernels::watertight_no_leaks::cases(s, 7 + si as u64);
        let tris = flat(&mesh);
        let mut leaks = 0;
        for c in &cases {
            let mut want = Vec::new();
            tris[..].all(&c.ray, |h| want.push(bits(Some(h)).unwrap()));
            let mut got = Vec::new();
            tree.all(&c.ray, |h| got.push(bits(Some(h)).unwrap()));
            want.sort();
            got.sort();
            assert_eq!(got, want, "{:?}", c.ray);
            // Crossings: distinct t (relative gap 1e-5) must reach the expected count.
            let mut ts: Vec<f32> = got.iter().map(|g| f32::from_bits(g[0])).collect();
            ts.sort_by(f32::total_cmp);
            ts.dedup_by(|b, a| (*b - *a) <= 1e-5 * a.abs().max(1e-3));
            leaks += (ts.len() < c.crossings) as usize;
            assert_eq!(bits(tree.closest(&c.ray)), bits(tris[..].closest(&c.ray)));
        }
        assert_eq!(leaks, 0, "shape {si}");
    }
}

/// Axis-aligned triangles whose boxes share faces, rays lying exactly in those faces, running
/// along box edges and hitting box corners: nothing is lost to the box test.
#[test]
fn rays_grazing_box_faces() {
    let tris = grazing_grid();
    let mut rs = Vec::new();
    let mut rng = SmallRng::seed_from_u64(17);
    for _ in 0..600 {
        let k = |rng: &mut SmallRng| rng.random_range(0..7) as f32;
        let half = |rng: &mut SmallRng| rng.random_range(0..14) as f32 * 0.5;
        // In a box face (z = 0 or 1, d.z = 0), through grid lines and corners.
        let z = if rng.random_bool(0.5) { 0.0 } else { 1.0 };
        let o = Vec3::new(half(&mut rng) - 1.0, half(&mut rng) - 1.0, z);
        let d = Vec3::new(k(&mut rng) - 3.0, k(&mut rng) - 3.0, 0.0);
        rs.push(Ray::new(o, d));
        // Straight down a grid line or corner, and along the walls' planes.
        let o = Vec3::new(k(&mut rng), half(&mut rng), 3.0);
        rs.push(Ray::new(o, Vec3::new(0.0, 0.0, -1.0)));
        rs.push(Ray::new(o, Vec3::new(0.0, -0.0, -2.0)));
        rs.push(Ray::new(
            Vec3::new(k(&mut rng), -1.0, 0.5),
            Vec3::new(0.0, 1.0, 0.0),
        ));
        // Oblique through a corner point of the grid.
        let p = Vec3::new(k(&mut rng), k(&mut rng), z);
        let o = p + v3(&mut rng, 3.0);
        rs.push(Ray::new(o, p - o));
    }
    let hits = check_tris(&tris, &rs);
    assert!(hits > 500, "{hits}");
    let rs = grazing_packets(&mut rng);
    let hits = check_tris(&tris, &rs);
    assert!(hits > 500, "{hits}");
}

/// A 6×6 grid of unit squares in the planes z = 0 and z = 1, and walls at x = k: triangles
/// whose boxes are flat, meeting along grid lines.
pub(crate) fn grazing_grid() -> Vec<Triangle> {
    let mut tris = Vec::new();
    for i in 0..6 {
        for j in 0..6 {
            let (x, y) = (i as f32, j as f32);
            for z in [0.0, 1.0] {
                tris.push(Triangle::new(
                    Vec3::new(x, y, z),
                    Vec3::new(x + 1.0, y, z),
                    Vec3::new(x + 1.0, y + 1.0, z),
                ));
                tris.push(Triangle::new(
                    Vec3::new(x, y, z),
                    Vec3::new(x + 1.0, y + 1.0, z),
                    Vec3::new(x, y + 1.0, z),
                ));
            }
            tris.push(Triangle::new(
                Vec3::new(x, y, 0.0),
                Vec3::new(x, y + 1.0, 0.0),
                Vec3::new(x, y, 1.0),
            ));
        }
    }
    tris
}

/// Packets of 16 rays from one eye (so every packet of 4, 8 or 16 shares it: the frustum
/// tests the leaves' flat triangle boxes), eyes on grid points, in the planes and off them,
/// aimed at grid points and edge midpoints of [`grazing_grid`]; then packets whose origins
/// differ but whose directions share their signs (a frustum, not one eye).
pub(crate) fn grazing_packets(rng: &mut SmallRng) -> Vec<Ray> {
    let mut rs = Vec::new();
    for e in 0..40 {
        let eye = match e % 4 {
            0 => Vec3::new(half_step(rng), half_step(rng), 0.0),
            1 => Vec3::new(half_step(rng) - 1.0, half_step(rng), 1.0),
            2 => Vec3::new(half_step(rng), half_step(rng), 2.5),
            _ => v3(rng, 4.0) + Vec3::splat(3.0),
        };
        for _ in 0..16 {
            let z = [0.0, 1.0, 0.5][rng.random_range(0..3)];
            let p = Vec3::new(half_step(rng), half_step(rng), z);
            let d = p - eye;
            rs.push(Ray::new(eye, if d == Vec3::ZERO { Vec3::Z } else { d }));
        }
    }
    for _ in 0..40 {
        let d = Vec3::new(
            rng.random_range(0.1..1.0),
            rng.random_range(0.1..1.0),
            -rng.random_range(0.1..1.0),
        );
        for _ in 0..16 {
            let o = Vec3::new(half_step(rng), half_step(rng), 2.0) - d * 3.0;
            rs.push(Ray::with_interval(o, d, 0.0, 10.0));
        }
    }
    rs
}

/// A grid coordinate in steps of ½ from 0 to 6.5.
fn half_step(rng: &mut SmallRng) -> f32 {
    rng.random_range(0..14) as f32 * 0.5
}

/// Bad input builds a valid tree (accepted by `from_parts`), never panics, and the answers
/// still equal brute force.
#[test]
fn bad_input_builds_valid_trees() {
    let mut rng = SmallRng::seed_from_u64(18);
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let a = Vec3::new(0.1, 0.2, 0.3);
    let tri = Triangle::new(a, Vec3::new(1.0, 0.0, 0.2), Vec3::new(0.0, 1.0, -0.1));
    let big = 1e30f32;
    let scenes: Vec<(&str, Vec<Triangle>)> = vec![
        ("empty", vec![]),
        ("one", vec![tri]),
        ("nan/inf", {
            let mut v = soup(&mut rng, 50);
            v.push(Triangle::new(Vec3::splat(nan), a, a));
            v.push(Triangle::new(Vec3::new(inf, 0.0, 0.0), a, -a));
            v.push(Triangle::new(a, a, Vec3::ONE)); // coincident vertices
            v.push(Triangle::new(a, a * 2.0, a * 3.0)); // collinear
            v.rotate_left(7);
            v
        }),
        ("1000 copies", vec![tri; 1000]),
        ("one point", vec![Triangle::new(a, a, a); 300]),
        ("near 1e30", {
            (0..100)
                .map(|_| {
                    let p = v3(&mut rng, 1.0) * big;
                    Triangle::new(p, p + v3(&mut rng, 0.3) * big, p + v3(&mut rng, 0.3) * big)
                })
                .collect()
        }),
        ("huge and tiny", {
            let mut v = soup(&mut rng, 40);
            v.push(Triangle::new(
                Vec3::new(-big, -big, 0.5),
                Vec3::new(big, -big, 0.5),
                Vec3::new(0.0, big, 0.5),
            ));
            v
        }),
    ];
    for (name, tris) in &scenes {
        let aim: Vec<Vec3> = centroids(tris);
        let mut rs = rays(&mut rng, 300, &aim);
        if name.contains("1e30") {
            rs.extend(aim.iter().map(|&p| {
                let o = v3(&mut rng, 3.0) * big;
                Ray::new(o, p - o)
            }));
        }
        check_tris(tris, &rs);
    }
    // Spheres: invalid radii and centres, one point, huge.
    let mut spheres: Vec<Sphere> = (0..30)
        .map(|_| Sphere::new(v3(&mut rng, 1.0), 0.1))
        .collect();
    spheres.push(Sphere::new(a, -1.0));
    spheres.push(Sphere::new(Vec3::splat(nan), 1.0));
    spheres.push(Sphere::new(a, inf));
    spheres.extend([Sphere::new(a, 0.05); 50]);
    spheres.push(Sphere::new(Vec3::splat(3e38), 3e38));
    let aim: Vec<Vec3> = spheres.iter().map(|s| s.center()).collect();
    let rs = rays(&mut rng, 300, &aim);
    check_spheres(&spheres, &rs);
    // Rays with extreme directions and zero components.
    let tris = soup(&mut rng, 100);
    let mut rs = Vec::new();
    for &s in &[1e-30f32, 1e-10, 1e10, 1e30] {
        for p in centroids(&tris).iter().take(20) {
            let o = v3(&mut rng, 3.0);
            rs.push(Ray::new(o, (*p - o) * s));
            rs.push(Ray::new(Vec3::new(p.x, p.y, 4.0), Vec3::new(0.0, 0.0, -s)));
        }
    }
    check_tris(&tris, &rs);
}

/// Scenes far from the origin (`R + |o|∞` up to about `1e12`) with rays along an axis, with
/// tiny direction components (whose inverses the slab test clamps: at `±2^64` where the node
/// test is fused) and whole directions just above and below the fused test's `|d|∞` limit
/// (`2^-45`): the tree answers as brute force, with Möller (hits inside its range at both
/// scales) and Watertight (hits inside its range, `2^30`).
#[test]
fn far_scenes_with_flat_directions() {
    let mut rng = SmallRng::seed_from_u64(23);
    for &s in &[1e8f32, 1e11] {
        let at = Vec3::new(1.0, -0.5, 0.25) * (3.0 * s);
        let tris: Vec<Triangle> = soup(&mut rng, 60)
            .iter()
            .map(|t| Triangle::new(t.a() * s + at, t.b() * s + at, t.c() * s + at))
            .collect();
        let mut rs = Vec::new();
        for p in centroids(&tris).iter().take(25) {
            for &tiny in &[0.0f32, 1e-30, 1e-20, 1e-12, 1e-6] {
                for &k in &[1.0f32, 1e-13, 1e-15] {
                    let down = Vec3::new(tiny, -tiny, -1.0) * k;
                    rs.push(Ray::new(*p + Vec3::new(0.0, 0.0, 4.0 * s), down));
                    let side = Vec3::new(1.0, tiny, 0.0) * k;
                    rs.push(Ray::new(*p - Vec3::new(2.0 * s, 0.0, 0.0), side));
                }
            }
        }
        let (nodes, leaves) = owned(&tris[..]);
        let tree = Bvh::from_parts(&nodes, &leaves).expect("a valid tree");
        let flat: &[Triangle] = &tris;
        let hits = check(&tree.using::<Moller>(), &flat.using::<Moller>(), &rs);
        assert!(hits > rs.len() / 4, "scale {s}: {hits} Möller hits");
        let hits = check(&tree, &flat, &rs);
        assert!(s > 1e9 || hits > rs.len() / 4, "scale {s}: {hits} hits");
    }
}

#[test]
fn short_storage_is_an_error() {
    let mut rng = SmallRng::seed_from_u64(19);
    let tris = soup(&mut rng, 100);
    let need = bvh::TriangleBvh::needed(tris.len());
    let mut nodes = vec![Node::EMPTY; need.nodes];
    let mut leaves = vec![Tri4::EMPTY; need.leaves];
    let mut scratch = vec![Scratch::default(); need.scratch];
    assert_eq!(
        bvh::Bvh::build(
            &tris[..],
            &mut nodes[..need.nodes - 1],
            &mut leaves,
            &mut scratch
        )
        .err(),
        Some(BuildError::Nodes(TooSmall { needed: need.nodes }))
    );
    assert_eq!(
        bvh::Bvh::build(&tris[..], &mut nodes, &mut leaves, &mut scratch[..0]).err(),
        Some(BuildError::Scratch(TooSmall {
            needed: need.scratch
        }))
    );
    let (used, reference) = {
        let t = bvh::Bvh::build(&tris[..], &mut nodes, &mut leaves, &mut scratch).unwrap();
        (t.leaves().len(), leaf_bits(t.leaves()))
    };
    // Short leaves are reported with the exact count the tree uses, and that count builds
    // the same tree.
    assert!(used < need.leaves / 2, "{used} leaves of {}", need.leaves);
    assert_eq!(
        bvh::Bvh::build(&tris[..], &mut nodes, &mut leaves[..3], &mut scratch).err(),
        Some(BuildError::Leaves(TooSmall { needed: used }))
    );
    let mut exact = vec![Tri4::EMPTY; used];
    let t = bvh::Bvh::build(&tris[..], &mut nodes, &mut exact, &mut scratch).unwrap();
    assert_eq!(leaf_bits(t.leaves()), reference);
    assert_eq!(bvh::TriangleBvh::needed(0).nodes, 1);
}

/// Leaves as bits (unused lanes hold NaN).
fn leaf_bits(l: &[Tri4]) -> Vec<u32> {
    l.iter()
        .flat_map(|t| {
            [t.a, t.b, t.c]
                .into_iter()
                .flatten()
                .flatten()
                .map(f32::to_bits)
                .chain(t.index)
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Same input, same bytes (the builder uses no hashing, no addresses, no fused operations).
#[test]
fn builds_are_deterministic() {
    let mut rng = SmallRng::seed_from_u64(20);
    let tris = soup(&mut rng, 3000);
    let (n1, l1) = owned(&tris[..]);
    let (n2, l2) = owned(&tris[..]);
    assert_eq!(n1, n2);
    assert_eq!(leaf_bits(&l1), leaf_bits(&l2));
    // Leaves hold every triangle exactly once.
    let mut seen = vec![false; tris.len()];
    for l in &l1 {
        for &i in &l.index {
            if i != bvh::EMPTY {
                assert!(!seen[i as usize]);
                seen[i as usize] = true;
            }
        }
    }
    assert!(seen.iter().all(|&s| s));
}

#[test]
fn refit_after_moving_vertices() {
    let m = crate::sets::bunny_visible_surface::load_bin(include_bytes!("../../data/bunny.bin"));
    let mut pos = m.pos.clone();
    let need = bvh::TriangleBvh::needed(m.idx.len());
    let mut nodes = vec![Node::EMPTY; need.nodes];
    let mut leaves = vec![Tri4::EMPTY; need.leaves];
    let mut scratch = vec![Scratch::default(); need.scratch];
    let (n, l) = {
        let b = bvh::Bvh::build(
            &Mesh::new(&pos, &m.idx),
            &mut nodes,
            &mut leaves,
            &mut scratch,
        )
        .unwrap();
        (b.nodes().len(), b.leaves().len())
    };
    // A wave through the mesh.
    for p in &mut pos {
        *p += Vec3::new((p.y * 40.0).sin() * 0.01, 0.0, (p.x * 30.0).cos() * 0.02);
    }
    let mesh = Mesh::new(&pos, &m.idx);
    let tree = bvh::Bvh::refit(&mesh, &mut nodes[..n], &mut leaves[..l]).unwrap();
    let mut rng = SmallRng::seed_from_u64(21);
    let aim: Vec<Vec3> = (0..200).map(|i| pos[i * 7]).collect();
    let rs: Vec<Ray> = (0..1500)
        .map(|i| {
            let o = aim[i % aim.len()] + v3(&mut rng, 0.5);
            Ray::new(o, aim[(i * 13) % aim.len()] - o)
        })
        .collect();
    let tris = flat(&mesh);
    let hits = check(&tree, &&tris[..], &rs);
    assert!(hits > 500);
}

#[test]
fn from_parts_rejects_broken_trees() {
    let mut rng = SmallRng::seed_from_u64(22);
    let tris = soup(&mut rng, 100);
    let (mut nodes, leaves) = owned(&tris[..]);
    assert!(Bvh::from_parts(&nodes, &leaves).is_ok());
    assert!(Bvh::<Tri4>::from_parts(&[], &leaves).is_err());
    nodes[0].child[0] = 0; // a cycle
    assert!(Bvh::from_parts(&nodes, &leaves).is_err());
    nodes[0].child[0] = bvh::LEAF | 10_000;
    assert!(Bvh::from_parts(&nodes, &leaves).is_err());
    let _ = Sphere4::EMPTY;
}

/// Depth stays bounded: copies of one triangle (no SAH plane: middle-index splits, 8 ways per
/// level) and an exponentially spaced row (SAH peels one triangle per level until
/// `SAH_DEPTH`). Ties go to the lowest index among the copies.
#[test]
fn depth_is_bounded_and_ties_go_to_the_lowest_index() {
    let tri = Triangle::new(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    );
    let copies = vec![tri; 20_000];
    let (nodes, leaves) = owned(&copies[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    // 20,000 → 2,500 → 313 → 40 → 5 → 1: six levels.
    assert!(tree.stats().depth <= 6, "{:?}", tree.stats());
    let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.0, 0.0, -1.0));
    assert_eq!(tree.closest(&ray).unwrap().index, 0);
    let p = RayPacket::<f32x8>::splat(&ray);
    assert_eq!(tree.closest(&p).lane(5).unwrap().index, 0);
    // 300,000 copies: six levels whose every box a ray enters, so the one-ray queries
    // short stack overflows and they run again with the full one.
    let copies = vec![tri; 300_000];
    let (nodes, leaves) = owned(&copies[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    assert!(tree.stats().depth >= 6, "{:?}", tree.stats());
    assert_eq!(tree.closest(&ray).unwrap().index, 0);
    assert!(tree.any(&ray));

    let row: Vec<Triangle> = (0..400)
        .map(|i| {
            let x = 2f32.powf(i as f32 / 4.0);
            Triangle::new(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x * 1.1, 0.0, 0.0),
                Vec3::new(x, x * 0.1, 0.0),
            )
        })
        .collect();
    let (nodes, leaves) = owned(&row[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let s = tree.stats();
    assert!(s.depth <= bvh::MAX_DEPTH, "{s:?}");
    println!("exponential row: {s:?}");
    let mut rng = SmallRng::seed_from_u64(23);
    let rs: Vec<Ray> = (0..400)
        .map(|i| {
            let x = 2f32.powf(i as f32 / 4.0) * 1.02;
            let o = Vec3::new(x, x * 0.01, 1.0) + v3(&mut rng, 0.001);
            Ray::new(o, Vec3::new(0.0, 0.0, -1.0))
        })
        .collect();
    // Beyond the kernels' range (2^30) rays may miss, in the tree as in brute force.
    assert!(check_tris(&row, &rs) > 100);
}

/// A 3×4 object→world transform: rotation about an axis, scale, translation.
fn transform(rng: &mut SmallRng, scale: f32, mirror: bool) -> [[f32; 4]; 3] {
    let axis = v3(rng, 1.0).normalize_or(Vec3::Z);
    let q = glam::Quat::from_axis_angle(axis, rng.random_range(0.0..core::f32::consts::TAU));
    let m = glam::Mat3::from_quat(q) * scale;
    let m = if mirror {
        m * glam::Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0))
    } else {
        m
    };
    let t = v3(rng, 3.0);
    [0, 1, 2].map(|r| [m.col(0)[r], m.col(1)[r], m.col(2)[r], t[r]])
}

/// Instances (item 4): rotated, scaled, mirrored and singular placements of a mesh and a
/// sphere set under a top-level BVH; each answer is the instances' own answers merged by
/// `t`, ties to the lower instance, with the instance id in `set`; packets equal one-ray
/// queries lane by lane.
#[test]
fn instanced_scenes_equal_instance_by_instance() {
    use raylane::bvh::{Inst4, Instance, Scene};
    let mut rng = SmallRng::seed_from_u64(24);
    let m = crate::sets::bunny_visible_surface::load_bin(include_bytes!("../../data/bunny.bin"));
    let bunny = flat(&Mesh::new(&m.pos, &m.idx));
    let soup = soup(&mut rng, 300);
    let (n0, l0) = owned(&bunny[..]);
    let (n1, l1) = owned(&soup[..]);
    let objects = [
        Bvh::from_parts(&n0, &l0).unwrap(),
        Bvh::from_parts(&n1, &l1).unwrap(),
    ];
    let flats: [&[Triangle]; 2] = [&bunny, &soup];
    let mut instances: Vec<Instance> = (0..24)
        .map(|i| {
            let scale = [0.5, 1.0, 3.0, 20.0][i % 4];
            Instance::new((i % 2) as u32, transform(&mut rng, scale, i % 5 == 0))
        })
        .collect();
    // Singular (flattened) and missing-object instances: never wrong, only slow or absent.
    let mut flat_t = transform(&mut rng, 1.0, false);
    flat_t[2] = [0.0, 0.0, 0.0, 0.5];
    instances.push(Instance::new(1, flat_t));
    instances.push(Instance::new(7, transform(&mut rng, 1.0, false)));
    assert!(!instances[24].invertible && instances[0].invertible && instances[5].mirror);
    let need = bvh::TriangleBvh::needed(instances.len());
    let mut nodes = vec![Node::EMPTY; need.nodes];
    let mut leaves = vec![Inst4::EMPTY; need.leaves];
    let mut scratch = vec![Scratch::default(); need.scratch];
    let scene = Scene::build(&objects, &instances, &mut nodes, &mut leaves, &mut scratch).unwrap();

    let aim: Vec<Vec3> = instances
        .iter()
        .map(|i| Vec3::new(i.to_world[0][3], i.to_world[1][3], i.to_world[2][3]))
        .collect();
    let rs: Vec<Ray> = (0..1500)
        .map(|i| {
            let o = v3(&mut rng, 12.0);
            let target = aim[i % aim.len()] + v3(&mut rng, 0.3);
            if i % 7 == 0 {
                Ray::with_interval(o, target - o, 0.0, rng.random_range(0.3..1.5))
            } else {
                Ray::new(o, target - o)
            }
        })
        .collect();
    let mut hits = 0;
    for (k, r) in rs.iter().enumerate() {
        // Reference: every instance in order, strictly closer wins.
        let mut want: Option<(f32, u32, Hit)> = None;
        let mut any = false;
        for (i, inst) in instances.iter().enumerate() {
            let Some(f) = flats.get(inst.object as usize) else {
                continue;
            };
            let local = inst.ray_to_object(r);
            any |= f.any(&local);
            if let Some(h) = f.closest(&local)
                && want.is_none_or(|w| h.t < w.0)
            {
                want = Some((h.t, i as u32, h));
            }
        }
        let got = scene.closest(r);
        assert_eq!(scene.any(r), any, "ray {k}");
        match (got, want) {
            (None, None) => {}
            (Some(g), Some((t, i, h))) => {
                hits += 1;
                assert_eq!(
                    (g.t.to_bits(), g.set, g.index, g.u.to_bits(), g.v.to_bits()),
                    (t.to_bits(), i, h.index, h.u.to_bits(), h.v.to_bits()),
                    "ray {k}"
                );
                assert_eq!(g.front, h.front != instances[i as usize].mirror);
                assert_eq!(g.point, r.at(g.t));
                assert!((g.normal.length() - 1.0).abs() < 1e-5 && g.normal.dot(r.dir()) <= 0.0);
            }
            (g, w) => panic!("ray {k}: {g:?} vs {:?}", w.map(|w| w.2)),
        }
    }
    assert!(hits > 300, "{hits}");
    for chunk in rs.chunks(8).take(60) {
        let p = RayPacket::<f32x8>::from_rays(chunk);
        let h = scene.closest(&p);
        for (j, r) in chunk.iter().enumerate() {
            assert_eq!(bits(h.lane(j)), bits(scene.closest(r)));
        }
    }
}

/// Nodes as bits.
fn node_bits(n: &[Node]) -> Vec<u32> {
    n.iter()
        .flat_map(|n| {
            n.bounds
                .iter()
                .flatten()
                .map(|x| x.to_bits())
                .chain(n.child)
                .collect::<Vec<_>>()
        })
        .collect()
}

/// `OwnedBvh::new` builds on every core (feature `std`, which the tests turn on): the same
/// nodes and leaves as the one-thread build over caller storage, bit for bit, and the same
/// for the baked image (built the same way).
#[test]
fn the_threaded_build_is_the_one_thread_tree() {
    let mut rng = SmallRng::seed_from_u64(21);
    let m = crate::sets::bunny_visible_surface::load_bin(include_bytes!("../../data/bunny.bin"));
    let bunny = Mesh::new(&m.pos, &m.idx);
    let mut big = soup(&mut rng, 70_000);
    // Coincident and degenerate triangles: ranges no plane splits, never-hit triangles.
    big.extend(std::iter::repeat_n(big[7], 300));
    big.push(Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::X));
    let check = |(nodes, leaves): (Vec<Node>, Vec<Tri4>), tree: bvh::OwnedBvh<Tri4>| {
        let t = tree.view();
        assert_eq!(node_bits(t.nodes()), node_bits(&nodes));
        assert_eq!(leaf_bits(t.leaves()), leaf_bits(&leaves));
        assert!(t.nodes().len() > 9, "{} nodes", t.nodes().len());
    };
    check(owned(&bunny), bvh::OwnedBvh::new(&bunny).unwrap());
    check(owned(&big[..]), bvh::OwnedBvh::new(&big[..]).unwrap());
}
