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
        for i in 0..self.n {
            let (s, h) = two_sum(q, self.e[i]);
            if h != 0.0 {
                self.e[m] = h;
                m += 1;
            }
            q = s;
        }
        if q != 0.0 && m < self.e.len() {
            self.e[m] = q;
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
        match self.n {
            0 => 0,
            n if self.e[n - 1] > 0.0 => 1,
            _ => -1,
        }
    }

    /// The sum rounded (to within a few `f64` ulps; the sign is exact).
    pub(crate) fn approx(&self) -> f64 {
        self.e[..self.n].iter().sum()
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
    const TOL: f64 = 8.0 / 9_007_199_254_740_992.0; // 8·2^-53
    for (j, k) in [(1, 2), (2, 0), (0, 1)] {
        // (b_j − a_j)(c_k − a_k) − (b_k − a_k)(c_j − a_j)
        let (p, q) = (b[j] - a[j], c[k] - a[k]);
        let (r, s) = (b[k] - a[k], c[j] - a[j]);
        let approx = p * q - r * s;
        if approx.abs() > TOL * ((p * q).abs() + (r * s).abs()) {
            return false;
        }
        // Exactly: b_j c_k − b_j a_k − a_j c_k − b_k c_j + b_k a_j + a_k c_j (the a_j a_k
        // terms cancel).
        let mut x = Expansion::new();
        for t in [
            b[j] * c[k],
            -(b[j] * a[k]),
            -(a[j] * c[k]),
            -(b[k] * c[j]),
            b[k] * a[j],
            a[k] * c[j],
        ] {
            x.add(t);
        }
        if x.sign() != 0 {
            return false;
        }
    }
    true
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
