//! Trees baked on a host (`bvh::bake`): the baked tree answers as the mesh it was baked from,
//! bit for bit, at every width, with every collector; opening checks every byte (bad headers,
//! every error of its list), and no mutation of a real baked tree panics, loops, reads out of
//! bounds or gives a hit outside the baked triangles.

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::bvh::bake::{Baked, HEADER, OpenError, bake};
use raylane::mesh::Mesh;
use raylane::triangle::{Moller, Triangle};
use raylane::{Cull, Query, Ray, RayPacket};
use wide::f32x8;

use crate::bvh::equals_brute_force::{check, grazing_grid, grazing_packets, rays, soup};
use crate::sets::query_records_every_width::bits;

/// The bytes at a 16-byte boundary (as `include_baked!` links them).
#[repr(C, align(16))]
struct Aligned([u8; 1 << 20]);

fn aligned(bytes: &[u8]) -> Box<Aligned> {
    let mut a = Box::new(Aligned([0; 1 << 20]));
    a.0[..bytes.len()].copy_from_slice(bytes);
    a
}

fn bunny() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let m = crate::sets::bunny_visible_surface::load_bin(include_bytes!("../../data/bunny.bin"));
    (m.pos, m.idx)
}

#[test]
fn the_baked_bunny_answers_as_its_mesh() {
    let (pos, idx) = bunny();
    let mesh = Mesh::new(&pos, &idx);
    let bytes = bake(&mesh).unwrap();
    let a = aligned(&bytes);
    let tree = Baked::open(&a.0[..bytes.len()]).unwrap();
    assert_eq!(tree.len(), idx.len());
    let (nodes, tris, verts) = tree.bytes();
    assert_eq!(
        nodes + tris + verts + HEADER,
        bytes.len().next_multiple_of(4)
    );
    eprintln!(
        "baked bunny: {} triangles, {} nodes (depth {}), {} B: {:.1} B per triangle (nodes {:.1}, \
         triangles {:.1}, vertices {:.1})",
        idx.len(),
        tree.nodes().len(),
        tree.depth(),
        bytes.len(),
        bytes.len() as f64 / idx.len() as f64,
        nodes as f64 / idx.len() as f64,
        tris as f64 / idx.len() as f64,
        verts as f64 / idx.len() as f64
    );
    let mut rng = SmallRng::seed_from_u64(21);
    let c = pos.iter().fold(Vec3::ZERO, |a, &p| a + p) / pos.len() as f32;
    let aim: Vec<Vec3> = pos.iter().step_by(3).copied().collect();
    let rs: Vec<Ray> = rays(&mut rng, 1500, &aim)
        .into_iter()
        .map(|r| Ray::with_interval(c + 0.1 * r.origin(), r.dir(), r.t_min(), r.t_max()))
        .collect();
    assert!(check(&tree, &mesh, &rs) > 500);
    check(&tree.using::<Moller>(), &mesh.using::<Moller>(), &rs[..300]);
    check(
        &tree.culled(Cull::Back),
        &mesh.culled(Cull::Back),
        &rs[..300],
    );
    // `all`: the same hits as the mesh's, in any order.
    for r in &rs[..200] {
        let mut got = Vec::new();
        tree.all(r, |h| got.push(bits(Some(h))));
        let mut want = Vec::new();
        mesh.all(r, |h| want.push(bits(Some(h))));
        got.sort();
        want.sort();
        assert_eq!(got, want, "{r:?}");
    }
    // Same bytes from the same mesh.
    assert_eq!(bake(&mesh).unwrap(), bytes);
}

#[test]
fn baked_soups_and_bad_triangles_answer_as_their_meshes() {
    let mut rng = SmallRng::seed_from_u64(22);
    for n in [0usize, 1, 3, 17, 700] {
        let tris = soup(&mut rng, n);
        let mut pos = Vec::new();
        let mut idx = Vec::new();
        for t in &tris {
            let k = pos.len() as u32;
            pos.extend([t.a(), t.b(), t.c()]);
            idx.push([k, k + 1, k + 2]);
        }
        // Bad triangles: out of range, NaN, zero area.
        pos.push(Vec3::NAN);
        let z = pos.len() as u32 - 1;
        idx.push([0, 1, 999_999]);
        idx.push([0, z, 1]);
        idx.push([0, 0, 0]);
        let mesh = Mesh::new(&pos, &idx);
        let bytes = bake(&mesh).unwrap();
        let a = aligned(&bytes);
        let tree = Baked::open(&a.0[..bytes.len()]).unwrap();
        assert_eq!(tree.len(), n);
        let centroids: Vec<Vec3> = tris.iter().map(|t| (t.a() + t.b() + t.c()) / 3.0).collect();
        check(&tree, &mesh, &rays(&mut rng, 400, &centroids));
    }
}

/// The grazing grid (flat triangle boxes meeting along grid lines) baked: packets from one eye
/// and frustum packets (the leaves' triangle boxes pruned by the frustum) answer as the mesh.
#[test]
fn baked_grids_answer_packets_as_their_meshes() {
    let mut pos = Vec::new();
    let mut idx = Vec::new();
    for t in grazing_grid() {
        let k = pos.len() as u32;
        pos.extend([t.a(), t.b(), t.c()]);
        idx.push([k, k + 1, k + 2]);
    }
    let mesh = Mesh::new(&pos, &idx);
    let bytes = bake(&mesh).unwrap();
    let a = aligned(&bytes);
    let tree = Baked::open(&a.0[..bytes.len()]).unwrap();
    let rs = grazing_packets(&mut SmallRng::seed_from_u64(24));
    assert!(check(&tree, &mesh, &rs) > 500);
}

#[test]
fn opening_refuses_bad_headers() {
    let (pos, idx) = bunny();
    let bytes = bake(&Mesh::new(&pos, &idx)).unwrap();
    let len = bytes.len();
    let mut a = aligned(&bytes);
    let open = |a: &Aligned, n: usize| Baked::open(&a.0[..n]).err();
    assert_eq!(open(&a, len), None);
    assert_eq!(open(&a, 10), Some(OpenError::Truncated));
    assert_eq!(open(&a, len - 4), Some(OpenError::Truncated));
    assert_eq!(
        Baked::open(&a.0[1..len + 1]).err(),
        Some(OpenError::Misaligned)
    );
    a.0[0] = b'X';
    assert_eq!(open(&a, len), Some(OpenError::Magic));
    a.0[0] = b'R';
    a.0[4] = 2;
    assert_eq!(open(&a, len), Some(OpenError::Version(2)));
    a.0[4] = 1;
    a.0[6] = 2;
    assert_eq!(open(&a, len), Some(OpenError::Header));
    a.0[6] = 0;
    a.0[20] = 99;
    assert_eq!(open(&a, len), Some(OpenError::TooDeep));
    a.0[20] = bytes[20];
    assert_eq!(open(&a, len), None);
}

/// A baked tree's answers, if it opens: every hit is the brute-force hit over its own
/// (validated) triangles, and nothing panics.
fn answers_if_open(bytes: &[u8], rays: &[Ray]) -> Result<usize, OpenError> {
    let tree = Baked::open(bytes)?;
    // Brute force over the baked triangles themselves, ties to the lower id.
    let (ids, flat): (Vec<u32>, Vec<Triangle>) =
        (0..tree.len()).filter_map(|i| tree.get(i)).unzip();
    let mut hits = 0;
    for r in rays {
        let got = tree.closest(r);
        let mut best: Option<(f32, u32)> = None;
        flat[..].all(r, |h| {
            let key = (h.t, ids[h.index as usize]);
            if best.is_none_or(|b| key < b) {
                best = Some(key);
            }
        });
        assert_eq!(got.map(|h| (h.t, h.index)), best);
        let p = tree.closest(&RayPacket::<f32x8>::splat(r));
        assert_eq!(bits(p.lane(3)), bits(got));
        assert_eq!(tree.any(r), got.is_some());
        hits += got.is_some() as usize;
    }
    Ok(hits)
}

#[test]
fn no_mutation_of_a_baked_tree_panics_or_answers_wrongly() {
    let (pos, idx) = bunny();
    let mesh = Mesh::new(&pos, &idx);
    let bytes = bake(&mesh).unwrap();
    let flat: Vec<Triangle> = (0..idx.len()).map(|i| mesh.triangle(i).unwrap()).collect();
    let mut rng = SmallRng::seed_from_u64(23);
    let c = pos.iter().fold(Vec3::ZERO, |a, &p| a + p) / pos.len() as f32;
    let rs: Vec<Ray> = (0..24)
        .map(|i| {
            let o = c + Vec3::new(0.3, 0.2, 0.25);
            Ray::new(o, pos[(i * 97) % pos.len()] - o)
        })
        .collect();
    let (mut opened, mut refused) = (0, 0);
    let mut reasons = std::collections::BTreeMap::new();
    for case in 0..3000 {
        let mut b = bytes.clone();
        let flips = 1 + case % 4;
        for _ in 0..flips {
            let at = if case % 3 == 0 {
                rng.random_range(0..HEADER)
            } else {
                rng.random_range(0..b.len())
            };
            b[at] = match case % 5 {
                0 => rng.random(),
                1 => b[at] ^ (1 << rng.random_range(0..8)),
                2 => 0xff,
                3 => 0,
                _ => b[at].wrapping_add(1),
            };
        }
        let a = aligned(&b);
        match answers_if_open(&a.0[..b.len()], &rs) {
            Ok(_) => opened += 1,
            Err(e) => {
                refused += 1;
                *reasons
                    .entry(format!("{e:?}").split('(').next().unwrap().to_string())
                    .or_insert(0) += 1;
            }
        }
    }
    eprintln!(
        "3000 mutated trees: {opened} opened (answers checked), {refused} refused: {reasons:?}"
    );
    assert!(refused > 1000 && opened > 100, "{opened} {refused}");
    // The unmutated tree answers as the mesh.
    let a = aligned(&bytes);
    let tree = Baked::open(&a.0[..bytes.len()]).unwrap();
    for r in &rs {
        assert_eq!(bits(tree.closest(r)), bits(flat[..].closest(r)));
    }
}
