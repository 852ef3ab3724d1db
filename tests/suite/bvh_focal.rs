//! The BVH's focal mode (issue 14, item 2): a tree with a per-eye cache answers every query as
//! brute force does, bit for bit, for rays from the eye (one ray and packets of 1, 4, 8, 16),
//! and for rays from elsewhere (world mode); leaves are filled lazily; short storage is an
//! error; a non-finite eye runs in world mode.

use crate::bvh::{centroids, check, flat, owned, rays, soup, v3};
use crate::query::bits;
use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::bvh::{
    self, BuildError, Bvh, FocalLeaf, FocalNode, Leaf, Node, NodeCache, SphereNode, Tri4,
};
use raylane::mesh::Mesh;
use raylane::sphere::{Robust, Sphere};
use raylane::triangle::{Cull, Triangle};
use raylane::{Query, Ray};

/// Per-eye storage for `tree`.
fn storage<P: Leaf>(tree: &Bvh<'_, P>) -> (Vec<FocalNode>, Vec<FocalLeaf<P>>) {
    let (n, l) = bvh::focal_needed(tree);
    (vec![FocalNode::EMPTY; n], vec![FocalLeaf::EMPTY; l])
}

/// Rays from `eye`: most aimed at `aim` points, some random, with finite, negative and
/// infinite interval ends.
fn from_eye(rng: &mut SmallRng, eye: Vec3, n: usize, aim: &[Vec3]) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let d = if i % 3 != 0 && !aim.is_empty() {
                aim[rng.random_range(0..aim.len())] - eye
            } else {
                v3(rng, 1.0)
            };
            match i % 5 {
                0 => Ray::with_interval(eye, d, 0.0, rng.random_range(0.5..4.0)),
                1 => Ray::with_interval(eye, d, -rng.random_range(0.0..2.0), f32::INFINITY),
                _ => Ray::new(eye, d),
            }
        })
        .collect()
}

#[test]
fn focal_soups_equal_brute_force() {
    let mut rng = SmallRng::seed_from_u64(141);
    for n in [1usize, 5, 40, 600] {
        let tris = soup(&mut rng, n);
        let aim = centroids(&tris);
        let (nodes, leaves) = owned(&tris[..]);
        for cull in [Cull::None, Cull::Back] {
            let tree = Bvh::from_parts(&nodes, &leaves).unwrap().with_cull(cull);
            let flat = tris[..]
                .using::<raylane::triangle::Watertight>()
                .culled(cull);
            let (mut fnodes, mut fleaves) = storage(&tree);
            for _ in 0..3 {
                let eye = v3(&mut rng, 3.0);
                let focal = tree.focus(eye, &mut fnodes, &mut fleaves).unwrap();
                let mut rs = from_eye(&mut rng, eye, 240, &aim);
                let hits = check(&focal, &flat, &rs);
                assert!(n < 40 || hits > 40, "{n} triangles: {hits} hits");
                // The lecture's focal sphere node test: the same answers.
                let mut snodes = vec![SphereNode::EMPTY; fnodes.len()];
                let spheres = tree.focus_with(eye, &mut snodes, &mut fleaves).unwrap();
                check(&spheres, &flat, &rs);
                // Packets mixing rays from the eye and from elsewhere (world mode).
                rs.extend(rays(&mut rng, 40, &aim));
                rs.rotate_left(7);
                let focal = tree.focus(eye, &mut fnodes, &mut fleaves).unwrap();
                check(&focal, &flat, &rs);
            }
        }
    }
}

#[test]
fn focal_spheres_equal_brute_force() {
    let mut rng = SmallRng::seed_from_u64(142);
    let spheres: Vec<Sphere> = (0..300)
        .map(|_| Sphere::new(v3(&mut rng, 1.0), rng.random_range(0.01..0.2)))
        .collect();
    let aim: Vec<Vec3> = spheres.iter().map(|s| s.center()).collect();
    let (nodes, leaves) = owned(&spheres[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let (mut fnodes, mut fleaves) = storage(&tree);
    for _ in 0..4 {
        let eye = v3(&mut rng, 3.0);
        let focal = tree.focus(eye, &mut fnodes, &mut fleaves).unwrap();
        let rs = from_eye(&mut rng, eye, 300, &aim);
        assert!(check(&focal, &spheres[..].using::<Robust>(), &rs) > 100);
    }
}

/// The vendored bunny's tree (nodes, leaves), its triangles as a flat set, and the centre and
/// half-diagonal of its box.
fn bunny() -> (Vec<Node>, Vec<Tri4>, Vec<Triangle>, Vec3, f32) {
    let m = crate::bunny::load_bin(include_bytes!("../data/bunny.bin"));
    let mesh = Mesh::new(&m.pos, &m.idx);
    let (nodes, leaves) = owned(&mesh);
    let (lo, hi) = m.pos.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(l, h), &p| (l.min(p), h.max(p)),
    );
    (
        nodes,
        leaves,
        flat(&mesh),
        (lo + hi) * 0.5,
        (hi - lo).length() * 0.5,
    )
}

/// The vendored bunny from eyes near and far (and one inside its box), with every width.
#[test]
fn focal_bunny_equals_brute_force_and_fills_lazily() {
    let (nodes, leaves, tris, c, r) = bunny();
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let mut rng = SmallRng::seed_from_u64(143);
    let (mut fnodes, mut fleaves) = storage(&tree);
    for k in 0..8 {
        let eye = if k == 0 {
            c
        } else {
            c + v3(&mut rng, 1.0).normalize_or(Vec3::X) * r * rng.random_range(1.1..30.0)
        };
        let focal = tree.focus(eye, &mut fnodes, &mut fleaves).unwrap();
        assert_eq!(focal.filled(), 0);
        let aim: Vec<Vec3> = (0..64).map(|_| c + v3(&mut rng, r * 0.8)).collect();
        let rs = from_eye(&mut rng, eye, 300, &aim);
        let hits = check(&focal, &&tris[..], &rs);
        assert!(hits > 50, "eye {k}: {hits} hits");
        let filled = focal.filled();
        assert!(
            filled > 0 && filled < tree.leaves().len(),
            "{filled} leaves filled"
        );
        let mut snodes = vec![SphereNode::EMPTY; fnodes.len()];
        let spheres = tree.focus_with(eye, &mut snodes, &mut fleaves).unwrap();
        check(&spheres, &&tris[..], &rs);
    }
}

/// The watertightness edge/vertex sets with the tree focused on each ray's origin: every hit
/// equals brute force's (0 leaks).
#[test]
fn focal_watertight_sets() {
    for (si, s) in crate::watertight::shapes().iter().enumerate() {
        let mesh = Mesh::new(&s.pos, &s.idx);
        let (nodes, leaves) = owned(&mesh);
        let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
        let tris = flat(&mesh);
        let (mut fnodes, mut fleaves) = storage(&tree);
        for c in crate::watertight::cases(s, 70 + si as u64).iter().take(400) {
            let focal = tree
                .focus(c.ray.origin(), &mut fnodes, &mut fleaves)
                .unwrap();
            let mut want = Vec::new();
            tris[..].all(&c.ray, |h| want.push(bits(Some(h)).unwrap()));
            let mut got = Vec::new();
            focal.all(&c.ray, |h| got.push(bits(Some(h)).unwrap()));
            want.sort();
            got.sort();
            assert_eq!(got, want, "{:?}", c.ray);
            assert!(got.len() >= c.crossings.min(1), "a leak: {:?}", c.ray);
            assert_eq!(bits(focal.closest(&c.ray)), bits(tris[..].closest(&c.ray)));
        }
    }
}

#[test]
fn focal_storage_and_bad_eyes() {
    let mut rng = SmallRng::seed_from_u64(144);
    let tris = soup(&mut rng, 200);
    let (nodes, leaves) = owned(&tris[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let (n, l) = bvh::focal_needed(&tree);
    assert_eq!((n, l), (nodes.len(), leaves.len()));
    let mut fnodes = vec![FocalNode::EMPTY; n];
    let mut fleaves = vec![FocalLeaf::EMPTY; l];
    let eye = Vec3::new(0.1, 2.5, -3.0);
    assert_eq!(
        tree.focus(eye, &mut fnodes[..n - 1], &mut fleaves)
            .unwrap_err(),
        BuildError::Nodes(n)
    );
    assert_eq!(
        tree.focus(eye, &mut fnodes, &mut fleaves[..l - 1])
            .unwrap_err(),
        BuildError::Leaves(l)
    );
    // Non-finite eyes: world mode, still brute force's answers (for finite rays).
    let aim = centroids(&tris);
    for bad in [Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 0.0)] {
        let focal = tree.focus(bad, &mut fnodes, &mut fleaves).unwrap();
        check(&focal, &&tris[..], &rays(&mut rng, 64, &aim));
        assert_eq!(focal.filled(), 0);
    }
    // −0 and +0: an eye at the origin with rays from −0 runs in world mode, same answers.
    let focal = tree.focus(Vec3::ZERO, &mut fnodes, &mut fleaves).unwrap();
    let rs: Vec<Ray> = aim
        .iter()
        .map(|&a| Ray::new(Vec3::new(-0.0, 0.0, -0.0), a))
        .collect();
    check(&focal, &&tris[..], &rs);
    // Triangles: one that is never hit.
    let one = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X)];
    let (nodes, leaves) = owned(&one[..]);
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let (mut fnodes, mut fleaves) = storage(&tree);
    let focal = tree.focus(Vec3::Z, &mut fnodes, &mut fleaves).unwrap();
    assert_eq!(focal.closest(&Ray::new(Vec3::Z, -Vec3::Z)), None);
}

/// Coherent packets (camera rows, and parallel rays from a grid of origins), where packets
/// take the interval ("frustum") node test: every lane equals brute force, in world and focal
/// mode, at every width.
#[test]
fn coherent_packets_equal_brute_force() {
    let (nodes, leaves, tris, c, r) = bunny();
    let tree = Bvh::from_parts(&nodes, &leaves).unwrap();
    let (mut fnodes, mut fleaves) = storage(&tree);
    let mut rng = SmallRng::seed_from_u64(145);
    for k in 0..4 {
        let eye = c + v3(&mut rng, 1.0).normalize_or(Vec3::X) * r * (1.3 + k as f32);
        let cam = raylane::Pinhole::look_at(eye, c, Vec3::Y, 40.0, 64, 48);
        let rs: Vec<Ray> = (0..cam.height)
            .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
            .map(|(x, y)| cam.row_packet::<f32>(x, y).ray(0))
            .collect();
        let hits = check(&tree, &&tris[..], &rs);
        assert!(hits > 100, "eye {k}: {hits} hits");
        let focal = tree.focus(eye, &mut fnodes, &mut fleaves).unwrap();
        check(&focal, &&tris[..], &rs);
        // Parallel rays from a grid of origins (origin intervals), some with finite ends.
        let d = (c - eye).normalize();
        let (u, v) = (
            d.any_orthonormal_pair().0 * r / 20.0,
            d.any_orthonormal_pair().1 * r / 20.0,
        );
        let rs: Vec<Ray> = (0..48 * 48)
            .map(|i| {
                let o = eye + u * ((i % 48) as f32 - 24.0) + v * ((i / 48) as f32 - 24.0);
                if i % 7 == 0 {
                    Ray::with_interval(o, d, 0.5 * r, 2.0 * r + k as f32 * r)
                } else {
                    Ray::new(o, d)
                }
            })
            .collect();
        assert!(check(&tree, &&tris[..], &rs) > 200);
    }
}
