//! `Bvh::from_parts` checks what it reopens: over 3,000 mutations of a real tree (the bunny's),
//! the kinds the issue probed — a child pointed at another node (a DAG, a cycle, a padded
//! node), the same leaf in two slots, swapped nodes, NaN, random or shrunk boxes, an unused
//! lane with real geometry, a vertex moved out of its box, a dropped subtree, repeated indices
//! (issue 31) — nothing panics or loops, and every tree it accepts answers as brute force over
//! its leaves' primitives, one ray and packets of every width alike, bit for bit, `all`
//! reporting each primitive once.

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::bvh::{self, Bvh, Leaf, Node, Packed, PartsError, Tri4};
use raylane::mesh::Mesh;
use raylane::triangle::Triangle;
use raylane::{Query, Ray};

use crate::bvh::baked_trees::from_both_sides;
use crate::bvh::equals_brute_force::{brute_with_ids, every_width, owned};

/// The tree's answers, if it reopens: the closest hit (one ray, and packets of 1, 4, 8 and 16
/// lanes, bit for bit) and `all`'s hits are brute force's over the primitives in its leaves'
/// used lanes (ties to the lower index, then to the earlier lane: indices may repeat).
fn answers_if_accepted(nodes: &[Node], leaves: &[Tri4], rays: &[Ray]) -> Result<(), PartsError> {
    let tree = Bvh::from_parts(nodes, leaves)?;
    let (ids, flat): (Vec<u32>, Vec<Triangle>) = leaves
        .iter()
        .flat_map(|l| (0..bvh::LEAF_WIDTH).map(move |k| (l.index[k], l.prim(k))))
        .filter(|&(i, _)| i != bvh::EMPTY)
        .unzip();
    let want: Vec<_> = rays
        .iter()
        .map(|r| brute_with_ids(&flat, &ids, r))
        .collect();
    every_width(&tree, rays, &want);
    for r in rays {
        let mut every = Vec::new();
        flat[..].all(r, |h| every.push((h.t.to_bits(), ids[h.index as usize])));
        let mut all = Vec::new();
        tree.all(r, |h| all.push((h.t.to_bits(), h.index)));
        all.sort_unstable();
        every.sort_unstable();
        assert_eq!(all, every);
    }
    Ok(())
}

#[test]
fn from_parts_refuses_every_kind_of_broken_tree() {
    let m = crate::sets::bunny_visible_surface::load_bin(include_bytes!("../../data/bunny.bin"));
    let mesh = Mesh::new(&m.pos, &m.idx);
    let (nodes, leaves) = owned(&mesh);
    let c = m.pos.iter().fold(Vec3::ZERO, |a, &p| a + p) / m.pos.len() as f32;
    let rs: Vec<Ray> = (0..16)
        .map(|i| {
            let o = c + Vec3::new(0.3, 0.2, 0.25);
            Ray::new(o, m.pos[(i * 97) % m.pos.len()] - o)
        })
        .collect();
    answers_if_accepted(&nodes, &leaves, &rs).expect("the built tree");
    let mut rng = SmallRng::seed_from_u64(21);
    let mut outcomes = std::collections::BTreeMap::new();
    let (nn, nl) = (nodes.len(), leaves.len());
    for case in 0..3000 {
        let (mut n, mut l) = (nodes.clone(), leaves.clone());
        let i = rng.random_range(0..nn);
        let k = rng.random_range(0..bvh::WIDTH);
        let kind = case % 11;
        match kind {
            // An inner child pointed elsewhere: a DAG, a cycle, backwards, out of range.
            0 => n[i].child[k] = rng.random_range(0..nn as u32 + 2),
            // A leaf slot pointed at another leaf (the same leaf twice).
            1 => n[i].child[k] = bvh::LEAF | rng.random_range(0..nl as u32 + 1),
            // Two nodes swapped.
            2 => n.swap(i, rng.random_range(0..nn)),
            // A box bound made NaN, random, or shrunk.
            3 => {
                let row = rng.random_range(0..6);
                n[i].bounds[row][k] = match rng.random_range(0..3) {
                    0 => f32::NAN,
                    1 => rng.random_range(-1.0..1.0),
                    _ => n[i].bounds[row][k] + if row < 3 { 1e-3 } else { -1e-3 },
                };
            }
            // An unused lane given real geometry, or a used lane emptied.
            4 => {
                let j = rng.random_range(0..nl);
                let lane = rng.random_range(0..bvh::LEAF_WIDTH);
                if l[j].index[lane] == bvh::EMPTY {
                    let t = mesh.triangle(7).unwrap();
                    let leaf = &mut l[j];
                    for axis in 0..3 {
                        leaf.a[axis][lane] = t.a()[axis];
                        leaf.b[axis][lane] = t.b()[axis];
                        leaf.c[axis][lane] = t.c()[axis];
                    }
                }
                l[j].index[lane] = bvh::EMPTY;
            }
            // A vertex moved (out of its boxes, mostly).
            5 => {
                let j = rng.random_range(0..nl);
                let lane = rng.random_range(0..bvh::LEAF_WIDTH);
                l[j].a[rng.random_range(0..3)][lane] += rng.random_range(-0.05..0.05);
            }
            // A node padded in, reached through a second parent.
            6 => {
                n.push(n[i]);
                n[rng.random_range(0..nn)].child[k] = i as u32;
            }
            // A leaf copied over another.
            7 => {
                let j = rng.random_range(0..nl);
                l[j] = l[rng.random_range(0..nl)];
            }
            // A subtree dropped.
            8 => n[i].child[k] = bvh::EMPTY,
            // Indices repeated (issue 31): every index one value, a leaf's lanes its first
            // lane's, or lanes their neighbour leaf's. Nothing checks indices; the answers
            // must still be brute force's at every width.
            10 => {
                let j = rng.random_range(0..nl);
                let one = l[j].index[0];
                for (m, leaf) in l.iter_mut().enumerate() {
                    for lane in 0..bvh::LEAF_WIDTH {
                        if leaf.index[lane] == bvh::EMPTY {
                            continue;
                        }
                        leaf.index[lane] = match case / 11 % 3 {
                            0 => one,
                            1 if m == j => one,
                            2 if m + 1 < nl && rng.random_bool(0.5) => leaves[m + 1].index[0],
                            _ => leaf.index[lane],
                        };
                    }
                }
            }
            // Random bits in a child reference.
            _ => n[i].child[k] ^= 1 << rng.random_range(0..32),
        }
        let outcome = match answers_if_accepted(&n, &l, &rs) {
            Ok(()) => "accepted".to_string(),
            Err(e) => format!("{e:?}").split('(').next().unwrap().to_string(),
        };
        *outcomes.entry((kind, outcome)).or_insert(0) += 1;
    }
    eprintln!("3000 mutated trees: {outcomes:?}");
    let accepted: usize = outcomes
        .iter()
        .filter(|((_, o), _)| o == "accepted")
        .map(|(_, n)| n)
        .sum();
    // Some mutations leave a valid tree (a vertex moved inside its boxes, a lane emptied, a
    // bound that still contains the child): those are checked above, the rest refused.
    assert!(accepted > 100 && accepted < 2000, "{outcomes:?}");
}

/// Issue 31, gap 3 for `from_parts`: two triangles with one index, in two leaves, tied at the
/// same `t` on their shared edge (the baked test's `two_leaves`, as a [`Node`] tree). Rays from
/// either side visit them in opposite orders, a packet's lane in its first lane's; the tie
/// rule's last key (leaf and lane) picks the earlier for every ray at every width. Fails with
/// the rule `(t, set, index)`: the ray from the right alone returns the second.
#[test]
fn repeated_indices_give_one_answer_at_every_width() {
    let p = [
        Vec3::new(-1.0, 0.0, 0.5),
        Vec3::ZERO,
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.5),
    ];
    let a = Triangle::new(p[0], p[1], p[2]);
    let b = Triangle::new(p[1], p[3], p[2]);
    for index in [[0, 0], [5, 5], [0, 1], [1, 0]] {
        let mut leaves = [Tri4::EMPTY; 2];
        let mut root = Node::EMPTY;
        for (k, t) in [a, b].into_iter().enumerate() {
            let l = &mut leaves[k];
            for axis in 0..3 {
                (l.a[axis][0], l.b[axis][0], l.c[axis][0]) =
                    (t.a()[axis], t.b()[axis], t.c()[axis]);
            }
            l.index[0] = index[k];
            let (lo, hi) = l.bounds(0);
            for axis in 0..3 {
                root.bounds[axis][k] = lo[axis];
                root.bounds[3 + axis][k] = hi[axis];
            }
            root.child[k] = bvh::LEAF | k as u32;
        }
        let tree = Bvh::from_parts(std::slice::from_ref(&root), &leaves).unwrap();
        let rays = from_both_sides();
        let want: Vec<_> = rays
            .iter()
            .map(|r| brute_with_ids(&[a, b], &index, r))
            .collect();
        // The earlier triangle (a) when the indices tie, else the lower index's.
        let first = if index[0] <= index[1] { a } else { b };
        for (r, w) in rays.iter().zip(&want) {
            let mut h = [first][..].closest(r).unwrap();
            h.index = index[0].min(index[1]);
            assert_eq!(*w, crate::sets::query_records_every_width::bits(Some(h)));
            assert_eq!(h.t, 1.0);
        }
        every_width(&tree, &rays, &want);
    }
}
