//! Loop subdivision (Loop 1987) of an indexed triangle mesh: each step splits every triangle
//! into four and smooths the vertices, so 4 steps turn the vendored 3,674-triangle bunny into
//! 940,544 triangles, the benchmarks' reproducible 10^6-triangle mesh.
//!
//! This file depends on `glam` and `std` only, so that the core crate's render example can
//! include it by path (`#[path = "../benches/src/subdivide.rs"]`) without the bench crate.
//!
//! Rules (Warren's weights):
//! * a new vertex on an interior edge `ab` with opposite vertices `c`, `d`:
//!   `3/8 (a + b) + 1/8 (c + d)`; on a boundary (or non-manifold) edge: `(a + b) / 2`;
//! * an old interior vertex with `n` neighbours: `(1 − nβ) v + β Σ neighbours`, with
//!   `β = 3/16` for `n = 3` and `3/(8n)` otherwise; an old boundary vertex:
//!   `3/4 v + 1/8 (b0 + b1)` over its two boundary neighbours (kept in place when it has
//!   more or fewer).
//!
//! Deterministic: new vertices are numbered in the order their edges are first met (triangle
//! by triangle, edges ab, bc, ca), sums are taken in that fixed order with plain f32 operations
//! (no fused multiply-add), so every target builds the same bits. Triangle `4i … 4i+3` of the
//! result are the corner triangles of `a`, `b`, `c` and the middle one of triangle `i`, with the
//! input's winding.

use std::collections::HashMap;

use glam::Vec3;

/// `(positions, triangles)` after one Loop step.
pub fn loop_step(pos: &[Vec3], tris: &[[u32; 3]]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
    // Edge → (new vertex index, opposite vertices in meeting order).
    let mut edges: HashMap<(u32, u32), (u32, Vec<u32>)> = HashMap::new();
    let mut order: Vec<(u32, u32)> = Vec::new();
    let n_old = pos.len() as u32;
    for t in tris {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let e = edges.entry(key(a, b)).or_insert_with(|| {
                order.push(key(a, b));
                (n_old + order.len() as u32 - 1, Vec::new())
            });
            e.1.push(c);
        }
    }
    let p = |i: u32| pos[i as usize];
    // Odd (edge) vertices.
    let mut out: Vec<Vec3> = Vec::with_capacity(pos.len() + order.len());
    out.extend_from_slice(pos);
    for &(a, b) in &order {
        let opp = &edges[&(a, b)].1;
        let v = if opp.len() == 2 {
            (p(a) + p(b)) * 0.375 + (p(opp[0]) + p(opp[1])) * 0.125
        } else {
            (p(a) + p(b)) * 0.5
        };
        out.push(v);
    }
    // Even (old) vertices: neighbours and boundary neighbours, in edge order.
    let mut ring: Vec<Vec<u32>> = vec![Vec::new(); pos.len()];
    let mut border: Vec<Vec<u32>> = vec![Vec::new(); pos.len()];
    for &(a, b) in &order {
        ring[a as usize].push(b);
        ring[b as usize].push(a);
        if edges[&(a, b)].1.len() != 2 {
            border[a as usize].push(b);
            border[b as usize].push(a);
        }
    }
    for (i, v) in pos.iter().enumerate() {
        let (r, bd) = (&ring[i], &border[i]);
        out[i] = if bd.is_empty() {
            let n = r.len();
            if n < 3 {
                *v
            } else {
                let beta = if n == 3 {
                    3.0 / 16.0
                } else {
                    3.0 / (8.0 * n as f32)
                };
                let sum = r.iter().fold(Vec3::ZERO, |s, &j| s + p(j));
                *v * (1.0 - n as f32 * beta) + sum * beta
            }
        } else if bd.len() == 2 {
            *v * 0.75 + (p(bd[0]) + p(bd[1])) * 0.125
        } else {
            *v
        };
    }
    let mid = |a: u32, b: u32| edges[&key(a, b)].0;
    let mut next = Vec::with_capacity(4 * tris.len());
    for &[a, b, c] in tris {
        let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
        next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    (out, next)
}

/// `steps` Loop steps.
pub fn loop_subdivide(pos: &[Vec3], tris: &[[u32; 3]], steps: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (mut p, mut t) = (pos.to_vec(), tris.to_vec());
    for _ in 0..steps {
        (p, t) = loop_step(&p, &t);
    }
    (p, t)
}

/// `tests/data/bunny.bin` (see `tests/data/README.md`): u32 vertex count, u32 triangle count,
/// f32 x, y, z per vertex, u16 a, b, c per triangle, little-endian. `None` if malformed.
pub fn load_bunny_bin(b: &[u8]) -> Option<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let u32_at = |o: usize| Some(u32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?));
    let (nv, nt) = (u32_at(0)? as usize, u32_at(4)? as usize);
    let f = |o: usize| Some(f32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?));
    let pos = (0..nv)
        .map(|i| Some(Vec3::new(f(8 + 12 * i)?, f(12 + 12 * i)?, f(16 + 12 * i)?)))
        .collect::<Option<Vec<_>>>()?;
    let base = 8 + 12 * nv;
    let h = |o: usize| Some(u16::from_le_bytes(b.get(o..o + 2)?.try_into().ok()?) as u32);
    let idx = (0..nt)
        .map(|i| {
            let o = base + 6 * i;
            Some([h(o)?, h(o + 2)?, h(o + 4)?])
        })
        .collect::<Option<Vec<_>>>()?;
    (b.len() == base + 6 * nt && idx.iter().flatten().all(|&i| (i as usize) < nv))
        .then_some((pos, idx))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every edge of a closed mesh is shared by exactly two triangles, in opposite directions.
    fn closed(tris: &[[u32; 3]]) -> bool {
        let mut edges = HashMap::new();
        for t in tris {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        edges
            .iter()
            .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
    }

    #[test]
    fn a_closed_mesh_stays_closed_and_shrinks_inside_its_hull() {
        let pos = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let tris = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        assert!(closed(&tris));
        let (p, t) = loop_subdivide(&pos, &tris, 3);
        assert_eq!((p.len(), t.len()), (4 + 6 + 24 + 96, 4 * 64));
        assert!(closed(&t));
        // Loop's vertices are convex combinations: inside the tetrahedron.
        assert!(
            p.iter()
                .all(|v| v.min_element() >= 0.0 && v.x + v.y + v.z <= 1.0 + 1e-6)
        );
        // Deterministic.
        assert_eq!(loop_subdivide(&pos, &tris, 3), (p, t));
    }

    #[test]
    fn the_vendored_bunny_subdivides_to_940544_triangles() {
        let (pos, tris) = load_bunny_bin(include_bytes!("../../tests/data/bunny.bin")).unwrap();
        assert_eq!((pos.len(), tris.len()), (1839, 3674));
        let (p, t) = loop_subdivide(&pos, &tris, 4);
        assert_eq!(t.len(), 940_544);
        assert!(p.iter().all(|v| v.is_finite()));
        assert!(t.iter().flatten().all(|&i| (i as usize) < p.len()));
    }
}
