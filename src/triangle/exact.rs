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
//!
//! Public so that tests and tools can build exact references from the same arithmetic: a
//! polynomial in `f32` inputs that is a sum of triple products (a 3×3 determinant of
//! differences of `f32` vectors expands into such a sum) is [`triple`]s added into one
//! [`Expansion`] of enough capacity, and [`Expansion::approx`] rounds it.

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

/// An exact sum of `f64` terms, at most `N` nonzero components (16 by default; the crate's
/// own uses need at most 12). A sum that would need more than `N` loses its largest component
/// (never panics): size `N` for the polynomial at hand.
#[derive(Clone, Copy, Debug)]
pub struct Expansion<const N: usize = 16> {
    e: [f64; N],
    n: usize,
}

impl<const N: usize> Default for Expansion<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Expansion<N> {
    /// Zero.
    #[must_use]
    pub fn new() -> Self {
        Expansion { e: [0.0; N], n: 0 }
    }

    /// Adds every component of `other` exactly.
    pub fn add_all<const M: usize>(&mut self, other: &Expansion<M>) {
        for &x in other.e.iter().take(other.n) {
            self.add(x);
        }
    }

    /// Subtracts every component of `other` exactly.
    pub fn sub_all<const M: usize>(&mut self, other: &Expansion<M>) {
        for &x in other.e.iter().take(other.n) {
            self.add(-x);
        }
    }

    /// Adds one `f64` exactly (grow-expansion with zero elimination).
    pub fn add(&mut self, b: f64) {
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
    pub fn add_product(&mut self, x: f64, p: f64) {
        let (hi, lo) = split(p);
        self.add(x * hi);
        self.add(x * lo);
    }

    /// Sign of the exact sum: -1, 0 or 1.
    #[must_use]
    pub fn sign(&self) -> i32 {
        match self.n.checked_sub(1).and_then(|top| self.e.get(top)) {
            None => 0,
            Some(&x) if x > 0.0 => 1,
            Some(_) => -1,
        }
    }

    /// The sum rounded (to within a few `f64` ulps; the sign is exact).
    #[must_use]
    pub fn approx(&self) -> f64 {
        self.e.iter().take(self.n).sum()
    }

    /// The exact sum correctly rounded to `f32` (to nearest, ties to even): a function of the
    /// exact value alone, so the negated sum rounds to the exact negation. [`approx`] rounded to
    /// `f32` is within one step of it; the midpoints between adjacent `f32` values are exact
    /// in `f64`, and the sign of the sum minus a midpoint settles the step exactly. Beyond
    /// `f32`'s range: `±inf`.
    ///
    /// [`approx`]: Self::approx
    #[must_use]
    pub fn round_f32(&self) -> f32 {
        let y = self.approx() as f32;
        if !y.is_finite() {
            return y;
        }
        // (neighbour, midpoint to it): below and above.
        for z in [y.next_down(), y.next_up()] {
            if !z.is_finite() {
                continue;
            }
            let mid = (y as f64 + z as f64) / 2.0;
            let mut r = *self;
            r.add(-mid);
            let s = r.sign() * if z > y { 1 } else { -1 };
            // s > 0: the sum is beyond the midpoint towards z; 0: a tie, to the even one.
            if s > 0 || (s == 0 && z.to_bits() & 1 == 0) {
                return z;
            }
        }
        y
    }
}

/// The expansion of the triple product `d·(a × b)` (= det[d, a, b]) of `f32` vectors (widened
/// to `f64`): at most 12 components.
#[must_use]
pub fn triple(d: [f64; 3], a: [f64; 3], b: [f64; 3]) -> Expansion {
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
#[must_use]
pub fn sign_triple(d: [f64; 3], a: [f64; 3], b: [f64; 3]) -> i32 {
    triple(d, a, b).sign()
}

/// Component `(j, k)` of `(p − e) × (q − e)` for `f32` vectors, exactly: the six products
/// `p_j q_k − p_j e_k − e_j q_k − p_k q_j + p_k e_j + e_k q_j` (the `e_j e_k` terms cancel).
/// With `e = a`, `p = b`, `q = c` it is the plane normal `(b − a) × (c − a)`. The axes `j`,
/// `k` are taken modulo 3 (so no index can panic).
#[must_use]
pub fn cross_rel(e: [f64; 3], p: [f64; 3], q: [f64; 3], j: usize, k: usize) -> Expansion {
    let (j, k) = (j % 3, k % 3);
    // (Six components at most; `round_f32` adds one more.)
    let mut x = Expansion::new();
    for t in [
        p[j] * q[k],
        -(p[j] * e[k]),
        -(e[j] * q[k]),
        -(p[k] * q[j]),
        p[k] * e[j],
        e[k] * q[j],
    ] {
        x.add(t);
    }
    x
}

/// The simulation-of-simplicity sign of the edge normal `(p − e) × (q − e)` (`f32` vectors):
/// the sign of its first nonzero component, x then y then z (0 when it is zero). It is the
/// sign of `δ·((p − e) × (q − e))` for the infinitesimal direction `δ = (ε, ε², ε³)`.
#[must_use]
pub fn sos_sign_rel(e: [f64; 3], p: [f64; 3], q: [f64; 3]) -> i32 {
    for (j, k) in [(1, 2), (2, 0), (0, 1)] {
        let s = cross_rel(e, p, q, j, k).sign();
        if s != 0 {
            return s;
        }
    }
    0
}

/// `d·((p − e) × (q − e)) = det[d, p, q] − det[d, p, e] − det[d, e, q]` for `f32` vectors,
/// exactly (at most 36 components).
#[must_use]
pub fn edge_rel(d: [f64; 3], e: [f64; 3], p: [f64; 3], q: [f64; 3]) -> Expansion<40> {
    let mut x = Expansion::new();
    x.add_all(&triple(d, p, q));
    x.sub_all(&triple(d, p, e));
    x.sub_all(&triple(d, e, q));
    x
}

/// `det[a − e, b − e, c − e] = det[a, b, c] − det[e, b, c] − det[a, e, c] − det[a, b, e]` for
/// `f32` vectors, exactly (at most 48 components, and room for the one more that
/// [`Expansion::round_f32`] adds).
#[must_use]
pub fn det_rel(e: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Expansion<52> {
    let mut x = Expansion::new();
    x.add_all(&triple(a, b, c));
    x.sub_all(&triple(e, b, c));
    x.sub_all(&triple(a, e, c));
    x.sub_all(&triple(a, b, e));
    x
}

/// True when three points with finite `f32` coordinates are exactly collinear (zero area):
/// every component of `(b − a) × (c − a)` is exactly zero. A cheap `f64` evaluation with an
/// error bound settles almost every triangle; the rest get the exact expansion.
pub(crate) fn collinear(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> bool {
    // The three components, as (a_j, a_k, b_j, b_k, c_j, c_k) for (j, k) = (y, z), (z, x), (x, y).
    let [ax, ay, az] = a;
    let [bx, by, bz] = b;
    let [cx, cy, cz] = c;
    component_is_zero(ay, az, by, bz, cy, cz)
        && component_is_zero(az, ax, bz, bx, cz, cx)
        && component_is_zero(ax, ay, bx, by, cx, cy)
}

/// True when `(b_j − a_j)(c_k − a_k) − (b_k − a_k)(c_j − a_j)` is exactly zero.
#[inline(always)]
fn component_is_zero(aj: f64, ak: f64, bj: f64, bk: f64, cj: f64, ck: f64) -> bool {
    const TOL: f64 = 8.0 / 9_007_199_254_740_992.0; // 8·2^-53
    let (p, q) = (bj - aj, ck - ak);
    let (r, s) = (bk - ak, cj - aj);
    let approx = p * q - r * s;
    if approx.abs() > TOL * ((p * q).abs() + (r * s).abs()) {
        return false;
    }
    exactly_zero(aj, ak, bj, bk, cj, ck)
}

/// [`component_is_zero`] when the filter cannot decide (out of line: a build's triangles
/// almost never need it).
#[cold]
#[inline(never)]
fn exactly_zero(aj: f64, ak: f64, bj: f64, bk: f64, cj: f64, ck: f64) -> bool {
    // Exactly: b_j c_k − b_j a_k − a_j c_k − b_k c_j + b_k a_j + a_k c_j (the a_j a_k terms
    // cancel).
    let mut x = Expansion::<16>::new();
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
        let o = [0.0; 3];
        assert_eq!(sos_sign_rel(o, a, b), 1);
        assert_eq!(sos_sign_rel(o, b, a), -1);
        // Relative to an eye: d·((a − e) × (b − e)) = 0 for d = a − e exactly representable.
        let e = w([0.5, 0.25, -1.0]);
        let p = w([1.5, 1.25, 0.0]);
        assert_eq!(edge_rel(w([1.0, 1.0, 1.0]), e, p, b).sign(), 0);
        assert_eq!(det_rel(e, e, p, b).sign(), 0);
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
