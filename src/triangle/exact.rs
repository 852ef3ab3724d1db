//! Exact signs of small polynomials in `f32` inputs, by floating-point expansions in `f64`.
//!
//! Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
//! Predicates" (Discrete & Computational Geometry 18, 1997): `two_sum` (Knuth), the Veltkamp
//! split and Dekker's product, no fused multiply-add. A product of two `f32` values is exact in
//! `f64` (48 bits); a product of an `f32` and such a 48-bit product is split into two exact
//! `f64` terms; an expansion holds their exact sum as nonoverlapping components of increasing
//! magnitude, whose sign is the sign of the last one.
//!
//! Used off the fast paths only: the focal cache's edge-sign fallback and its per-triangle
//! constants, and the exact zero-area test of [`Triangle::new`](super::Triangle::new). The
//! inputs must be finite `f32` values (widened to `f64`); every intermediate then stays far
//! inside `f64`'s normal range (|products| between 2^-450 and 2^385).

/// `a + b = x + y` exactly (Knuth's two-sum; no overflow assumed).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    (x, (a - av) + (b - bv))
}

/// Veltkamp's split: `a = hi + lo` with at most 26 significant bits in each.
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// An exact sum of `f64` terms (at most 16 components).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Expansion {
    e: [f64; 16],
    n: usize,
}

impl Expansion {
    pub(crate) fn new() -> Self {
        Expansion { e: [0.0; 16], n: 0 }
    }

    /// Adds one `f64` exactly (grow-expansion with zero elimination).
    pub(crate) fn add(&mut self, b: f64) {
        let mut q = b;
        let mut m = 0;
        // In place: component i is read before slot m <= i is written. `get` keeps every
        // access in bounds without a panic path (at most 12 components are ever used).
        for i in 0..self.n {
            let Some(&e) = self.e.get(i) else { break };
            let (s, h) = two_sum(q, e);
            if h != 0.0 {
                if let Some(slot) = self.e.get_mut(m) {
                    *slot = h;
                }
                m += 1;
            }
            q = s;
        }
        if q != 0.0
            && let Some(slot) = self.e.get_mut(m)
        {
            *slot = q;
            m += 1;
        }
        self.n = m;
    }

    /// Adds `x·p` exactly, for `x` an `f32` value and `p` a product of two `f32` values.
    pub(crate) fn add_product(&mut self, x: f64, p: f64) {
        let (hi, lo) = split(p);
        self.add(x * hi);
        self.add(x * lo);
    }

    /// Sign of the exact sum: -1, 0 or 1.
    pub(crate) fn sign(&self) -> i32 {
        match self.n.checked_sub(1).and_then(|top| self.e.get(top)) {
            None => 0,
            Some(&x) if x > 0.0 => 1,
            Some(_) => -1,
        }
    }

    /// The sum rounded (to within a few `f64` ulps; the sign is exact).
    pub(crate) fn approx(&self) -> f64 {
        self.e.iter().take(self.n).sum()
    }
}

/// The expansion of the triple product `d·(a × b)` (= det[d, a, b]) of `f32` vectors.
pub(crate) fn triple(d: [f64; 3], a: [f64; 3], b: [f64; 3]) -> Expansion {
    let mut x = Expansion::new();
    x.add_product(d[0], a[1] * b[2]);
    x.add_product(-d[0], a[2] * b[1]);
    x.add_product(d[1], a[2] * b[0]);
    x.add_product(-d[1], a[0] * b[2]);
    x.add_product(d[2], a[0] * b[1]);
    x.add_product(-d[2], a[1] * b[0]);
    x
}

/// Exact sign of `d·(a × b)` for `f32` vectors.
pub(crate) fn sign_triple(d: [f64; 3], a: [f64; 3], b: [f64; 3]) -> i32 {
    triple(d, a, b).sign()
}

/// Exact sign of `p·q − r·s` for `f32` values (both products are exact in `f64`, and a rounded
/// subtraction keeps the sign of the exact difference).
#[inline]
pub(crate) fn sign_2x2(p: f64, q: f64, r: f64, s: f64) -> i32 {
    let x = p * q - r * s;
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// The simulation-of-simplicity sign of an edge normal `a × b` (`f32` vectors): the sign of its
/// first nonzero component, x then y then z (0 when `a × b = 0`). It is the sign of `p·(a × b)`
/// for the infinitesimal perturbation `p = (ε, ε², ε³)` of a ray direction.
pub(crate) fn sos_sign(a: [f64; 3], b: [f64; 3]) -> i32 {
    let x = sign_2x2(a[1], b[2], a[2], b[1]);
    if x != 0 {
        return x;
    }
    let y = sign_2x2(a[2], b[0], a[0], b[2]);
    if y != 0 {
        return y;
    }
    sign_2x2(a[0], b[1], a[1], b[0])
}

/// True when three points with finite `f32` coordinates are exactly collinear (zero area):
/// every component of `(b − a) × (c − a)` is exactly zero. A cheap `f64` evaluation with an
/// error bound settles almost every triangle; the rest get the exact expansion.
pub(crate) fn collinear(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> bool {
    // The three components, as (a_j, a_k, b_j, b_k, c_j, c_k) for (j, k) = (y, z), (z, x), (x, y).
    let [ax, ay, az] = a;
    let [bx, by, bz] = b;
    let [cx, cy, cz] = c;
    [
        (ay, az, by, bz, cy, cz),
        (az, ax, bz, bx, cz, cx),
        (ax, ay, bx, by, cx, cy),
    ]
    .into_iter()
    .all(|(aj, ak, bj, bk, cj, ck)| component_is_zero(aj, ak, bj, bk, cj, ck))
}

/// True when `(b_j − a_j)(c_k − a_k) − (b_k − a_k)(c_j − a_j)` is exactly zero.
fn component_is_zero(aj: f64, ak: f64, bj: f64, bk: f64, cj: f64, ck: f64) -> bool {
    const TOL: f64 = 8.0 / 9_007_199_254_740_992.0; // 8·2^-53
    let (p, q) = (bj - aj, ck - ak);
    let (r, s) = (bk - ak, cj - aj);
    let approx = p * q - r * s;
    if approx.abs() > TOL * ((p * q).abs() + (r * s).abs()) {
        return false;
    }
    // Exactly: b_j c_k − b_j a_k − a_j c_k − b_k c_j + b_k a_j + a_k c_j (the a_j a_k terms
    // cancel).
    let mut x = Expansion::new();
    for t in [
        bj * ck,
        -(bj * ak),
        -(aj * ck),
        -(bk * cj),
        bk * aj,
        ak * cj,
    ] {
        x.add(t);
    }
    x.sign() == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(v: [f32; 3]) -> [f64; 3] {
        [v[0] as f64, v[1] as f64, v[2] as f64]
    }

    #[test]
    fn triple_sign_is_exact() {
        // d = a exactly: d·(a × b) = 0 although f32 arithmetic leaves rounding noise.
        let a = w([0.1, 0.7, -1.3]);
        let b = w([2.9, -0.3, 0.37]);
        assert_eq!(sign_triple(a, a, b), 0);
        assert_eq!(sign_triple(b, a, b), 0);
        // A tiny nonzero value far below f64's rounding of the naive sum.
        let d = w([1.0, 1.0, 1.0]);
        let a = w([1.0e20, 1.0, 0.0]);
        let b = w([1.0e20, 0.0, 1.0]);
        // d·(a × b) = (1, −1e20, −1e20)·(1,1,1) summed with ... exact value computed in i128.
        let exact: i128 = {
            let (ax, ay, az) = (100_000_002_004_087_734_272i128, 1i128, 0i128);
            let (bx, by, bz) = (ax, 0i128, 1i128);
            let cx = ay * bz - az * by;
            let cy = az * bx - ax * bz;
            let cz = ax * by - ay * bx;
            cx + cy + cz
        };
        assert_eq!(a[0], 100_000_002_004_087_734_272.0);
        assert_eq!(sign_triple(d, a, b), exact.signum() as i32);
        assert_eq!(sos_sign(a, b), 1);
        assert_eq!(sos_sign(b, a), -1);
    }

    #[test]
    fn collinear_points() {
        assert!(collinear(
            w([0.0, 0.0, 0.0]),
            w([0.1, 0.2, 0.3]),
            w([0.2, 0.4, 0.6])
        ));
        assert!(!collinear(
            w([0.0, 0.0, 0.0]),
            w([0.1, 0.2, 0.3]),
            w([0.2, 0.4, 0.6000001])
        ));
        assert!(collinear(
            w([1.0, 1.0, 1.0]),
            w([1.0, 1.0, 1.0]),
            w([5.0, -3.0, 2.0])
        ));
    }
}
