//! Exact references for ray–triangle tests: `t`, `u`, `v` of the ray `E + t·D` against the
//! plane of `A`, `B`, `C` (all `f32` inputs), from exact expansions of the polynomials
//! (`raylane::triangle::exact`), each rounded once to `f64` at the end; and the first-order
//! change of `t` when every input moves by 2 ulps (the conditioning margin).

use glam::Vec3;
use raylane::triangle::exact::{Expansion, det_rel, edge_rel, triple};

type X = Expansion<40>;

fn w(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

/// The exact answer for one ray and one triangle (`f32` inputs), each value within a few
/// `f64` ulps of the exact rational.
#[derive(Clone, Copy, Debug)]
pub struct Exact {
    /// Ray parameter of the plane crossing (`inf`/NaN for a ray parallel to the plane).
    pub t: f64,
    /// Barycentric weight of B.
    pub u: f64,
    /// Barycentric weight of C.
    pub v: f64,
    /// First-order change of `t` when each input coordinate moves by 2 ulps.
    pub margin: f64,
}

impl Exact {
    /// True when the exact crossing is inside the triangle with every barycentric ≥ `m`.
    pub fn inside_by(&self, m: f64) -> bool {
        self.u >= m && self.v >= m && 1.0 - self.u - self.v >= m
    }
    /// Relative error of `t`.
    pub fn t_err(&self, t: f32) -> f64 {
        ((t as f64 - self.t) / self.t).abs()
    }
}

fn ulp(x: f32) -> f64 {
    let a = x.abs();
    if a == 0.0 {
        f32::from_bits(1) as f64
    } else {
        a.next_up() as f64 - a as f64
    }
}

/// The exact `t`, `u`, `v` and the 2-ulp margin of `t` for the ray `eye + t·dir`.
pub fn exact(eye: Vec3, dir: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Exact {
    let (e, d, wa, wb, wc) = (w(eye), w(dir), w(a), w(b), w(c));
    let num = det_rel(e, wa, wb, wc).approx();
    let mut den = X::new();
    den.add_all(&triple(d, wa, wb));
    den.add_all(&triple(d, wb, wc));
    den.add_all(&triple(d, wc, wa));
    let den = den.approx();
    let t = num / den;
    let u = edge_rel(d, e, wc, wa).approx() / den;
    let v = edge_rel(d, e, wa, wb).approx() / den;
    // N in f64 (for the margin only).
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let (e1, e2) = (sub(wb, wa), sub(wc, wa));
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let wts = [(1.0 - u - v).abs(), u.abs(), v.abs()];
    let mut m = 0.0;
    for i in 0..3 {
        let move_i = ulp(eye[i])
            + t.abs() * ulp(dir[i])
            + wts[0] * ulp(a[i])
            + wts[1] * ulp(b[i])
            + wts[2] * ulp(c[i]);
        m += n[i].abs() * 2.0 * move_i;
    }
    Exact {
        t,
        u,
        v,
        margin: m / den.abs(),
    }
}
