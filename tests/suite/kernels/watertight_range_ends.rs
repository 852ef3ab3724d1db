//! The watertight range, tested at its ends: a closed icosphere with vertices on a dyadic grid
//! (so that scaling by `2^k` is exact), scaled to sizes `2^-40` and `2^30`, and rays with unit
//! directions aimed at its shared vertices and exact edge midpoints from outside and inside. The
//! `watertight` kernel must not leak at either end. Beyond them it does (`t·det` under- or
//! overflows): those sizes are measured and printed, not pinned.

use glam::Vec3;
use raylane::Ray;
use raylane::mesh::Mesh;
use raylane::triangle::{Cramer, Moller, TriangleKernel, Watertight};
use raylane_lab::demo::shapes;

/// The demo's icosphere of frequency 3 about an off-axis centre, radius 2, vertices snapped to
/// multiples of 2^-12 (shared vertices stay shared: the mesh is still closed).
fn mesh() -> (Vec<Vec3>, Vec<[u32; 3]>, Vec3) {
    let n = 3;
    let mut pos = vec![Vec3::ZERO; shapes::icosphere_vertices(n)];
    let mut idx = vec![[0; 3]; shapes::icosphere_triangles(n)];
    assert!(shapes::icosphere(n, &mut pos, &mut idx).is_some());
    let center = Vec3::new(0.25, -0.125, 0.0625);
    let snap = |x: f32| (x * 4096.0).round() / 4096.0;
    let pos = pos
        .into_iter()
        .map(|p| {
            let q = center + p * 2.0;
            Vec3::new(snap(q.x), snap(q.y), snap(q.z))
        })
        .collect();
    (pos, idx, center)
}

/// Rays at unit scale with their expected crossings: from outside through each vertex and each
/// edge midpoint (exact on the dyadic grid) towards the centre, and from the centre out.
fn rays(pos: &[Vec3], idx: &[[u32; 3]], center: Vec3) -> Vec<(Ray, usize)> {
    let mut targets: Vec<Vec3> = pos.to_vec();
    for t in idx {
        for k in 0..3 {
            let (a, b) = (pos[t[k] as usize], pos[t[(k + 1) % 3] as usize]);
            targets.push((a + b) * 0.5);
        }
    }
    let mut out = Vec::new();
    for p in targets {
        let o = p + (p - center) * 2.0;
        out.push((Ray::new(o, (p - o).normalize()), 2));
        out.push((Ray::new(center, (p - center).normalize()), 1));
    }
    out
}

/// Leaks of kernel `K` over the mesh scaled by `2^k` (origins scaled alike, unit directions:
/// `t` scales by `2^k` too, exactly).
fn leaks<K: TriangleKernel>(k: i32) -> (usize, usize) {
    let (pos, idx, center) = mesh();
    let s = 2f32.powi(k);
    let scaled: Vec<Vec3> = pos.iter().map(|&p| p * s).collect();
    let m = Mesh::new(&scaled, &idx);
    let cases = rays(&pos, &idx, center);
    let mut leaks = 0;
    for (ray, crossings) in &cases {
        let r = Ray::new(ray.origin() * s, ray.dir());
        let mut ts = Vec::new();
        raylane::Query::all(
            &raylane::set::Using::<_, K>::new(&m),
            &r,
            |h: raylane::Hit| {
                assert!(h.t.is_finite() && h.u.is_finite() && h.v.is_finite());
                ts.push(h.t)
            },
        );
        ts.sort_by(f32::total_cmp);
        // Distinct crossings: hits further apart than 1e-4 of the size (t is 1 to 6 sizes).
        let gap = 1e-4 * s;
        let groups = ts.windows(2).filter(|w| w[1] - w[0] > gap).count() + !ts.is_empty() as usize;
        leaks += (groups < *crossings) as usize;
    }
    (leaks, cases.len())
}

#[test]
fn watertight_holds_from_2_pow_minus_40_to_2_pow_30() {
    for k in [-40, 0, 30] {
        let (l, n) = leaks::<Watertight>(k);
        assert_eq!(l, 0, "watertight leaks at size 2^{k}: {l} of {n} rays");
    }
    // Outside the range (and the other methods), measured for the record.
    for k in [-52, -50, -48, 40, 42, 44] {
        println!(
            "size 2^{k}: leaks watertight {:?}, moller {:?}, cramer {:?}",
            leaks::<Watertight>(k),
            leaks::<Moller>(k),
            leaks::<Cramer>(k)
        );
    }
}
