//! `Bvh::from_parts` checks what it reopens: over 3,000 mutations of a real tree (the bunny's),
//! the kinds the issue probed — a child pointed at another node (a DAG, a cycle, a padded
//! node), the same leaf in two slots, swapped nodes, NaN, random or shrunk boxes, an unused
//! lane with real geometry, a vertex moved out of its box, a dropped subtree — nothing panics
//! or loops, and every tree it accepts answers as brute force over its leaves' primitives,
//! one ray and a packet alike, `all` reporting each primitive once.

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::bvh::{self, Bvh, Leaf, Node, PartsError, Tri4};
use raylane::mesh::Mesh;
use raylane::triangle::Triangle;
use raylane::{Query, Ray, RayPacket};
use wide::f32x8;

use crate::bvh::equals_brute_force::owned;
use crate::sets::query_records_every_width::bits;

/// The tree's answers, if it reopens: the closest hit and `all`'s hits are brute force's over
/// the primitives in its leaves' used lanes (ties to the lower index), at 1 and 8 lanes.
fn answers_if_accepted(nodes: &[Node], leaves: &[Tri4], rays: &[Ray]) -> Result<(), PartsError> {
    let tree = Bvh::from_parts(nodes, leaves)?;
    let (ids, flat): (Vec<u32>, Vec<Triangle>) = leaves
        .iter()
        .flat_map(|l| (0..bvh::LEAF_WIDTH).map(move |k| (l.index[k], l.prim(k))))
        .filter(|&(i, _)| i != bvh::EMPTY)
        .unzip();
    for r in rays {
        let got = tree.closest(r);
        let mut best: Option<(f32, u32)> = None;
        let mut every = Vec::new();
        flat[..].all(r, |h| {
            let key = (h.t, ids[h.index as usize]);
            every.push((h.t.to_bits(), key.1));
            if best.is_none_or(|b| key < b) {
                best = Some(key);
            }
        });
        assert_eq!(got.map(|h| (h.t, h.index)), best);
        assert_eq!(
            bits(tree.closest(&RayPacket::<f32x8>::splat(r)).lane(5)),
            bits(got)
        );
        assert_eq!(tree.any(r), got.is_some());
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
        let kind = case % 10;
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
