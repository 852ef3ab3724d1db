//! The collectors' rules, the same for every set (flat slices, meshes, BVHs at every width,
//! tuples and instance scenes): a hit counts when its rounded `t` lies in `(t_min, t_max)`,
//! the closest is the smallest `(t, set, index)`, `any` stops at the first occluder. Each test
//! here failed before the one traversal (issue 19's defects 1–4).

use glam::Vec3;
use raylane::bvh::{self, BuildError, Bvh, Inst4, Instance, Node, Packed, Scene, Scratch};
use raylane::mesh::Mesh;
use raylane::opcount::{Counted, measure};
use raylane::triangle::Triangle;
use raylane::{Hit, Lane, Mask, Query, Ray, RayPacket};
use wide::{f32x4, f32x8, f32x16};

use crate::bvh::equals_brute_force::owned;
use crate::sets::query_records_every_width::bits;

/// The closest hit of `r` through `q` at every width (one ray, packets of 1, 4, 8, 16 with `r`
/// in every lane), all required equal; and `any`, `all` required to agree with it.
fn every_way<Q: Query + ?Sized>(q: &Q, r: &Ray) -> Option<Hit> {
    let one = q.closest(r);
    fn lanes<L: Lane<Scalar = f32>, Q: Query + ?Sized>(q: &Q, r: &Ray) -> Vec<Option<[u32; 12]>> {
        let h = q.closest(&RayPacket::<L>::splat(r));
        (0..L::LANES).map(|i| bits(h.lane(i))).collect()
    }
    for got in [
        lanes::<f32, Q>(q, r),
        lanes::<f32x4, Q>(q, r),
        lanes::<f32x8, Q>(q, r),
        lanes::<f32x16, Q>(q, r),
    ] {
        assert!(
            got.iter().all(|g| *g == bits(one)),
            "{r:?}: {got:?} vs {one:?}"
        );
    }
    assert_eq!(q.any(r), one.is_some(), "any vs closest: {r:?}");
    assert_eq!(
        q.any(&RayPacket::<f32x8>::splat(r)).bits(),
        if one.is_some() { 0xff } else { 0 },
        "any x8 vs closest: {r:?}"
    );
    let mut all = Vec::new();
    q.all(r, |h| all.push(h));
    assert_eq!(all.is_empty(), one.is_none(), "all vs closest: {r:?}");
    if let Some(h) = one {
        assert!(all.iter().any(|a| bits(Some(*a)) == bits(Some(h))), "{r:?}");
        assert!(all.iter().all(|a| a.t >= h.t && a.t < r.t_max()), "{r:?}");
    }
    one
}

/// Eight triangles around the origin, each with a vertex there: a ray from the origin with
/// `t_min < 0` hits every one of them at `t = 0`.
fn fan() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let ring = [
        (1.0, 0.0),
        (1.0, 1.0),
        (0.0, 1.0),
        (-1.0, 1.0),
        (-1.0, 0.0),
        (-1.0, -1.0),
        (0.0, -1.0),
        (1.0, -1.0),
    ];
    let mut pos = vec![Vec3::ZERO];
    let mut idx = Vec::new();
    for (i, &(x, y)) in ring.iter().enumerate() {
        let (nx, ny) = ring[(i + 1) % 8];
        pos.push(Vec3::new(x, y, 0.5));
        pos.push(Vec3::new(nx, ny, -0.5));
        idx.push([0, 2 * i as u32 + 1, 2 * i as u32 + 2]);
    }
    (pos, idx)
}

#[test]
fn ties_at_t_zero_go_to_the_lowest_index_in_every_set_and_width() {
    let (pos, idx) = fan();
    let mesh = Mesh::new(&pos, &idx);
    let tris: Vec<Triangle> = (0..idx.len()).map(|i| mesh.triangle(i).unwrap()).collect();
    let (nodes, leaves) = owned(&mesh);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let ray = Ray::with_interval(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), -1.0, f32::INFINITY);
    let want = every_way(&tris[..], &ray).expect("the fan is hit at t = 0");
    assert_eq!((want.t, want.index), (0.0, 0));
    assert_eq!(bits(every_way(&mesh, &ray)), bits(Some(want)));
    assert_eq!(bits(every_way(&tree, &ray)), bits(Some(want)));
    // Across sets: the lower set wins a tie, in a tuple and in a scene of instances.
    let pair = (&tree, &tris[..]);
    assert_eq!(
        every_way(&pair, &ray).map(|h| (h.set, h.index)),
        Some((0, 0))
    );
    let objects = [tree];
    let id = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    let instances = [Instance::new(0, id), Instance::new(0, id)];
    let need = Scene::<bvh::Tri4>::needed(2);
    let mut n = vec![Node::EMPTY; need.nodes];
    let mut l = vec![Inst4::EMPTY; need.leaves];
    let mut s = vec![Scratch::default(); need.scratch];
    let scene = Scene::build(&objects, &instances, &mut n, &mut l, &mut s).unwrap();
    assert_eq!(
        every_way(&scene, &ray).map(|h| (h.t, h.set, h.index)),
        Some((0.0, 0, 0))
    );
}

#[test]
fn rays_from_shared_vertices_of_a_real_mesh_agree_with_brute_force() {
    let m = crate::sets::bunny_visible_surface::load_bin(include_bytes!("../../data/bunny.bin"));
    let mesh = Mesh::new(&m.pos, &m.idx);
    let tris = crate::bvh::equals_brute_force::flat(&mesh);
    let (nodes, leaves) = owned(&mesh);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let mut hits = 0;
    for (k, &v) in m.pos.iter().enumerate().step_by(7).take(400) {
        let d = Vec3::new(
            ((k * 37) % 11) as f32 - 5.0,
            ((k * 13) % 7) as f32 - 3.0,
            ((k * 5) % 9) as f32 - 4.0,
        );
        let ray = Ray::with_interval(v, d, -1.0, f32::INFINITY);
        let want = every_way(&tris[..], &ray);
        hits += want.is_some() as usize;
        assert_eq!(bits(every_way(&tree, &ray)), bits(want), "vertex {k}");
    }
    assert!(hits > 200, "{hits}");
}

#[test]
fn any_all_and_closest_agree_at_every_t_max() {
    let m = crate::sets::bunny_visible_surface::load_bin(include_bytes!("../../data/bunny.bin"));
    let mesh = Mesh::new(&m.pos, &m.idx);
    let tris = crate::bvh::equals_brute_force::flat(&mesh);
    let (nodes, leaves) = owned(&mesh);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let c = m.pos.iter().fold(Vec3::ZERO, |a, &p| a + p) / m.pos.len() as f32;
    let mut near = 0;
    for k in 0..300 {
        let o = c + Vec3::new(0.3, 0.1 * (k % 5) as f32, 0.25);
        let d = m.pos[(k * 11) % m.pos.len()] - o;
        let Some(h) = tris.closest(&Ray::new(o, d)) else {
            continue;
        };
        // t_max at the hit, and one, two and three ulps above and below it.
        let mut t = h.t;
        for _ in 0..3 {
            t = t.next_down();
        }
        for _ in 0..7 {
            let ray = Ray::with_interval(o, d, 0.0, t);
            let want = every_way(&tris[..], &ray);
            assert_eq!(bits(every_way(&mesh, &ray)), bits(want), "{ray:?}");
            assert_eq!(bits(every_way(&tree, &ray)), bits(want), "{ray:?}");
            assert_eq!(want.is_some(), h.t < t, "{ray:?}");
            near += 1;
            t = t.next_up();
        }
    }
    assert!(near > 1000, "{near}");
}

/// The operations (counted lanes: node tests and kernels) of one `any` query of a packet of
/// one ray through a scene of `n` copies of a triangle stacked along the ray.
fn scene_any_ops(n: usize) -> u32 {
    let pos = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let idx = [[0u32, 1, 2]];
    let mesh = Mesh::new(&pos, &idx);
    let (nodes, leaves) = owned(&mesh);
    let objects = [Bvh::from_parts(&nodes, &leaves).unwrap()];
    let instances: Vec<Instance> = (0..n)
        .map(|i| {
            let z = -2.0 - i as f32;
            Instance::new(
                0,
                [
                    [1.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, z],
                ],
            )
        })
        .collect();
    let need = Scene::<bvh::Tri4>::needed(n);
    let mut nn = vec![Node::EMPTY; need.nodes];
    let mut l = vec![Inst4::EMPTY; need.leaves];
    let mut s = vec![Scratch::default(); need.scratch];
    let scene = Scene::build(&objects, &instances, &mut nn, &mut l, &mut s).unwrap();
    let ray = Ray::new(Vec3::ZERO, Vec3::NEG_Z);
    assert!(scene.any(&ray));
    let rp = RayPacket::<Counted<f32>>::splat(&ray);
    let (hit, ops) = measure(|| scene.any(&rp));
    assert!(hit);
    ops.flops() + ops.cmp
}

#[test]
fn scene_any_stops_at_the_first_occluder() {
    let one = scene_any_ops(1);
    let many = scene_any_ops(4096);
    eprintln!("scene any: {one} ops for 1 instance, {many} for 4096");
    // A deeper top level costs a few more node tests, never the instances behind the first.
    assert!(
        many < 4 * one,
        "1 instance: {one} ops, 4096 instances: {many} ops"
    );
}

#[test]
fn refit_refuses_a_different_number_of_primitives() {
    let (pos, idx) = fan();
    let mesh = Mesh::new(&pos, &idx);
    let need = bvh::TriangleBvh::needed(mesh.len());
    let mut nodes = vec![Node::EMPTY; need.nodes];
    let mut leaves = vec![bvh::Tri4::EMPTY; need.leaves];
    let mut scratch = vec![Scratch::default(); need.scratch];
    let (n, l) = {
        let t = Bvh::build(&mesh, &mut nodes, &mut leaves, &mut scratch).unwrap();
        (t.nodes().len(), t.leaves().len())
    };
    let more_idx = [idx.clone(), vec![[0, 1, 2]]].concat();
    let more = Mesh::new(&pos, &more_idx);
    assert_eq!(
        Bvh::refit(&more, &mut nodes[..n], &mut leaves[..l]).err(),
        Some(BuildError::Mismatch)
    );
    let fewer = Mesh::new(&pos, &idx[..7]);
    assert_eq!(
        Bvh::refit(&fewer, &mut nodes[..n], &mut leaves[..l]).err(),
        Some(BuildError::Mismatch)
    );
    assert!(Bvh::refit(&mesh, &mut nodes[..n], &mut leaves[..l]).is_ok());
}
