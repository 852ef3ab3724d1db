//! Closed triangle meshes generated in code, into caller storage (no allocation).
//!
//! * [`icosphere`]: the geodesic sphere of frequency `n` — each face of the icosahedron cut
//!   into `n²` triangles, every vertex pushed out to the unit sphere — with
//!   [`icosphere_vertices(n)`](icosphere_vertices) `= 10n² + 2` shared vertices and
//!   [`icosphere_triangles(n)`](icosphere_triangles) `= 20n²` triangles, stored face by face
//!   (triangles `f·n² .. (f + 1)·n²` cover face `f` of the icosahedron), each face's patch by
//!   patch ([`icosphere_patches`]: the four triangles that halve its edges), so that each
//!   patch can be a mesh part with its own small bounding sphere.
//! * [`cube`]: 8 vertices, 12 triangles.
//!
//! Every vertex shared by several triangles is stored once and referenced by index, and every
//! triangle is wound counter-clockwise seen from outside (`(B − A) × (C − A)` points out), so
//! back-face culling ([`Cull::Back`](raylane::Cull)) keeps the outside. Positions are
//! computed in `f64` with correctly rounded operations only (`libm::sqrt` included), then
//! rounded once to `f32`: the same bits on every target.

use glam::Vec3;

use raylane::vec3::V3;

/// Exact-input `f64` vectors (the crate's `V3` over the `f64` lane).
type D3 = V3<f64>;

/// The icosahedron's corners (unnormalised): `(±1, ±φ, 0)` and its cyclic permutations.
fn corners() -> [D3; 12] {
    let t = (1.0 + libm::sqrt(5.0)) / 2.0;
    [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|[x, y, z]| V3::new(x, y, z))
}

/// The icosahedron's faces, as corner indices.
const FACES: [[u8; 3]; 20] = [
    [0, 11, 5],
    [0, 5, 1],
    [0, 1, 7],
    [0, 7, 10],
    [0, 10, 11],
    [1, 5, 9],
    [5, 11, 4],
    [11, 10, 2],
    [10, 7, 6],
    [7, 1, 8],
    [3, 9, 4],
    [3, 4, 2],
    [3, 2, 6],
    [3, 6, 8],
    [3, 8, 9],
    [4, 9, 5],
    [2, 4, 11],
    [6, 2, 10],
    [8, 6, 7],
    [9, 8, 1],
];

/// `p/|p|` rounded to f32.
fn unit(p: D3) -> Vec3 {
    let q = p.div_by(libm::sqrt(p.dot(p)));
    Vec3::new(q.x as f32, q.y as f32, q.z as f32)
}

/// Number of vertices of the frequency-`n` icosphere: `10n² + 2`.
#[must_use]
pub const fn icosphere_vertices(n: u32) -> usize {
    10 * (n as usize) * (n as usize) + 2
}

/// Number of triangles of the frequency-`n` icosphere: `20n²`.
#[must_use]
pub const fn icosphere_triangles(n: u32) -> usize {
    20 * (n as usize) * (n as usize)
}

/// The 30 edges of the icosahedron as corner pairs `(p, q)`, `p < q`, in order of first use.
fn edges() -> [(u8, u8); 30] {
    let mut out = [(0u8, 0u8); 30];
    let mut n = 0;
    for f in FACES {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let e = (a.min(b), a.max(b));
            if !out[..n].contains(&e) && n < out.len() {
                out[n] = e;
                n += 1;
            }
        }
    }
    out
}

/// Writes the unit icosphere of frequency `n ≥ 1` (see the [module docs](self)) into
/// `positions` and `indices` and returns `(vertices, triangles)`, or `None` when `n` is 0 or
/// the slices are too short.
pub fn icosphere(
    n: u32,
    positions: &mut [Vec3],
    indices: &mut [[u32; 3]],
) -> Option<(usize, usize)> {
    let (nv, nt) = (icosphere_vertices(n), icosphere_triangles(n));
    if n == 0 || n > 1024 || positions.len() < nv || indices.len() < nt {
        return None;
    }
    let c = corners();
    let edges = edges();
    let nn = n as usize;
    let m = nn - 1; // points inside each edge
    let interior = m * m.saturating_sub(1) / 2; // points inside each face
    let edge_base = 12;
    let face_base = 12 + 30 * m;
    // 1. Corners and edge points, each computed once from its edge's canonical order.
    for (i, p) in c.iter().enumerate() {
        positions[i] = unit(*p);
    }
    for (e, &(p, q)) in edges.iter().enumerate() {
        let (a, b) = (c[p as usize], c[q as usize]);
        for k in 1..nn {
            let (wa, wb) = ((nn - k) as f64, k as f64);
            positions[edge_base + e * m + k - 1] = unit(a.scale(wa) + b.scale(wb));
        }
    }
    // 2. Per face (wound outward): interior points, then the n² triangles.
    let mut t = 0;
    for (f, face) in FACES.iter().enumerate() {
        let [ia, mut ib, mut ic] = face.map(usize::from);
        if (c[ib] - c[ia]).cross(c[ic] - c[ia]).dot(c[ia]) < 0.0 {
            core::mem::swap(&mut ib, &mut ic);
        }
        let (a, b, cc) = (c[ia], c[ib], c[ic]);
        // Grid point (i, j) is A·(n − i − j) + B·i + C·j.
        let on_edge = |from: usize, to: usize, k: usize| -> usize {
            let e = (from.min(to) as u8, from.max(to) as u8);
            let idx = edges.iter().position(|&x| x == e).unwrap_or(0);
            let kk = if from < to { k } else { nn - k };
            edge_base + idx * m + kk - 1
        };
        let interior_base = |i: usize| (i - 1) * m - (i - 1) * i / 2;
        let vertex = |i: usize, j: usize| -> u32 {
            let v = if i == 0 && j == 0 {
                ia
            } else if i == nn {
                ib
            } else if j == nn {
                ic
            } else if j == 0 {
                on_edge(ia, ib, i)
            } else if i == 0 {
                on_edge(ia, ic, j)
            } else if i + j == nn {
                on_edge(ib, ic, j)
            } else {
                face_base + f * interior + interior_base(i) + j - 1
            };
            v as u32
        };
        for i in 1..nn {
            for j in 1..nn - i {
                let (wa, wb, wc) = ((nn - i - j) as f64, i as f64, j as f64);
                positions[vertex(i, j) as usize] = unit(a.scale(wa) + b.scale(wb) + cc.scale(wc));
            }
        }
        for patch in 0..4 {
            for i in 0..nn {
                for j in 0..nn - i {
                    if patch_of(n, i, j, false) == patch {
                        indices[t] = [vertex(i, j), vertex(i + 1, j), vertex(i, j + 1)];
                        t += 1;
                    }
                    if i + j + 1 < nn && patch_of(n, i, j, true) == patch {
                        indices[t] = [vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1)];
                        t += 1;
                    }
                }
            }
        }
    }
    orient_outward(positions, &mut indices[..t], D3::default());
    Some((nv, t))
}

/// The patch of the face's triangle at grid point `(i, j)` (the upward one, or the downward
/// one when `down`): which of the four triangles that halve the face's edges holds its
/// centroid — 0 at corner A, 1 at B, 2 at C, 3 in the middle.
fn patch_of(n: u32, i: usize, j: usize, down: bool) -> usize {
    let h = n as usize / 2;
    let d = if down { 2 } else { 1 };
    if i >= h {
        1
    } else if j >= h {
        2
    } else if i + j + d <= h {
        0
    } else {
        3
    }
}

/// Number of triangles in each of the four patches of every face of the frequency-`n`
/// icosphere (`(n/2)²` each for even `n`). [`icosphere`] stores each face's triangles patch
/// by patch, so a patch is a contiguous range: face `f`'s patch `p` starts at
/// `f·n² + Σ_{q<p} sizes[q]`.
#[must_use]
pub fn icosphere_patches(n: u32) -> [usize; 4] {
    let mut sizes = [0; 4];
    let nn = n as usize;
    for i in 0..nn {
        for j in 0..nn - i {
            sizes[patch_of(n, i, j, false)] += 1;
            if i + j + 1 < nn {
                sizes[patch_of(n, i, j, true)] += 1;
            }
        }
    }
    sizes
}

/// Writes an axis-aligned cube of half-size 1 about the origin: 8 vertices, 12 triangles
/// (two per face), wound outward. Returns `None` when the slices are too short.
pub fn cube(positions: &mut [Vec3], indices: &mut [[u32; 3]]) -> Option<(usize, usize)> {
    if positions.len() < 8 || indices.len() < 12 {
        return None;
    }
    // Corner i has x = ±1 by bit 0, y by bit 1, z by bit 2.
    for (i, p) in positions.iter_mut().take(8).enumerate() {
        let s = |b: usize| if (i >> b) & 1 == 1 { 1.0 } else { -1.0 };
        *p = Vec3::new(s(0), s(1), s(2));
    }
    // Each face's corners in cyclic order, split along its first diagonal.
    let quads: [[u32; 4]; 6] = [
        [0, 2, 6, 4],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 5, 7, 6],
    ];
    for (k, q) in quads.iter().enumerate() {
        indices[2 * k] = [q[0], q[1], q[2]];
        indices[2 * k + 1] = [q[0], q[2], q[3]];
    }
    orient_outward(positions, &mut indices[..12], D3::default());
    Some((8, 12))
}

/// Swaps B and C of every triangle whose normal points towards `center` (convex shapes).
fn orient_outward(positions: &[Vec3], indices: &mut [[u32; 3]], center: D3) {
    for t in indices {
        let p = |i: u32| {
            positions
                .get(i as usize)
                .map_or(D3::default(), |v| V3::splat(*v))
        };
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        if (b - a).cross(c - a).dot(a - center) < 0.0 {
            t.swap(1, 2);
        }
    }
}
