//! Rays from one focal point: per-triangle caches of edge-plane normals, watertight by
//! construction, with exact decisions and accurate `t`, `u`, `v`.
//!
//! Primary rays of a pinhole camera all start at the eye `E` (lecture 000, "Rays from Focal
//! Point"). With `A′ = A − E`, `B′ = B − E`, `C′ = C − E` (exact, never rounded), the cache
//! holds, each component computed exactly from the `f32` inputs ([`exact`] module
//! expansions) and correctly rounded to `f32` once:
//!
//! ```text
//! n_ab = A′ × B′     n_bc = B′ × C′     n_ca = C′ × A′       edge-plane normals through E
//! N = (B − A) × (C − A)     V = N·A′ = A′·(B′ × C′)          the plane, in the same units
//! ```
//!
//! and per ray with direction `D` (any length):
//!
//! ```text
//! e_ab = D·n_ab,  e_bc = D·n_bc,  e_ca = D·n_ca        9 mul, 6 add   → a miss ends here
//! t > 0:  the sign of ±V (exact; ± the sign of the decision)   → behind the eye ends here
//! det = ±D·N                                            3 mul, 2 add
//! t = ±V/det,  u = |e_ca|/w (weight of B),  v = |e_ab|/w (weight of C),  w = max(det, |e_ca| + |e_ab|)
//! ```
//!
//! The ray crosses the triangle when the three edge values have one sign (negative: a front
//! face, `D·N < 0`); `t < t_max` is `±V < t_max·det`, and only lanes that pass divide
//! (`t = ±V/det`: in a closest-hit loop, only the hits that win so far); `u`, `v` are divided
//! once per ray for the winner (see [`triangle`](super) on deferred division). `w ≥ |e_ca| +
//! |e_ab|` keeps `u + v ≤ 1`. Where the rounded `D·N` lacks the decided sign (only for
//! `|cos θ|` below about `2^-22`, θ between the ray and the normal) `det` falls back to
//! `|e_ab| + |e_bc| + |e_ca|`.
//!
//! **Accuracy.** Every cached value is the correctly rounded exact value, so each edge value
//! and `D·N` carries only the rounding of one 3-term dot product (`γ3·Σ|D_i n_i|`): the same
//! size as what a 1-ulp move of `D` changes. `t` then has a relative error of a few ulps over
//! `|cos θ|`, independent of the distance (summing the three edge values instead, as this
//! kernel did before, cancels from `c·ℓ` down to `ℓ²·cos θ` and rounded normals `A′ × B′`
//! carry `2^-24·c²`: errors of `2^-24·(c/ℓ)²/cos θ` for a triangle of size `ℓ` at distance
//! `c`, 0.7 % at `c/ℓ = 250`). Measured against exact answers (`tests/focal_accuracy.rs`, 4,000
//! rays per class; maxima, focal \| Möller–Trumbore \| Watertight):
//!
//! | class | relative `t` error | `t` error over its 2-ulp margin | `u`, `v` (absolute) |
//! | --- | --- | --- | --- |
//! | random (eye and triangle within 8 units) | 2.6e-5 \| 1.4e-4 \| 5.4e-5 | 0.56 \| 4.0 \| 0.73 | 1.2e-4 \| 4.2e-4 \| 1.4e-4 |
//! | far (c/ℓ = 2^4…2^12) | 2.6e-5 \| 7.6e-5 \| 5.5e-5 | 0.77 \| 31 \| 0.97 | 1.1e-1 \| 1.6e-1 \| 1.9e-1 |
//! | needles (aspect 10…10^4) | 1.6e-4 \| 1.4e-2 \| 6.3e-4 | 0.50 \| 2427 \| 83 | 8.8e-2 \| 5.7e-2 \| 5.5e-2 |
//! | grazing (cos θ down to 2^-10) | 5.1e-5 \| 1.1e-4 \| 4.0e-5 | 0.37 \| 0.67 \| 0.52 | 8.6e-5 \| 1.3e-4 \| 4.9e-5 |
//! | large coordinates (offset 10^5) | 4.7e-6 \| 6.9e-6 \| 8.7e-6 | < 0.01 (all) | 9.8e-5 \| 9.8e-5 \| 3.0e-5 |
//! | plane grids (Embree's watertightness plane) | 2.6e-7 \| 3.8e-7 \| 2.5e-7 | 0.56 \| 0.81 \| 0.82 | 3.3e-5 \| 4.6e-5 \| 2.1e-5 |
//!
//! (The 2-ulp margin is the first-order change of the exact `t` when every input coordinate
//! moves by 2 ulps.) The large maxima belong to ill-conditioned cases (far or needle triangles
//! seen nearly edge-on, where a 2-ulp move of the inputs changes the answer as much): focal's
//! `t` stays within that margin on every case (pinned), and where such a move changes `t` by
//! less than 2^-18, focal's `t` is within 6.5e-7 (pinned: 2^-16); every class's maxima are
//! pinned at most 2× Möller's. Closest hit over the vendored
//! bunny from 1.5× to 100× its size: no hidden surface returned in 10^5 rays
//! (`tests/bunny.rs`).
//!
//! **Watertight, each crossing reported once; the fill rule.** Two triangles sharing the edge
//! AB cache `A′ × B′` and `B′ × A′`: exact negations (rounding to nearest is symmetric), and so
//! are their dot products with `D`. Each edge sign is moreover made *exact*: the cache holds a
//! bound `K` on the error of `e` (for directions scaled so that `max|D_i| < 4`,
//! `K = 4·(γ3 + 2^-24)·Σ|n_i|`), and the rare lanes with `|e| ≤ K` recompute the sign of
//! `D·((A − E) × (B − E))` exactly (expansions, Shewchuk 1997). An exactly zero edge value
//! takes the sign of the first nonzero component of the exact normal (x, then y, then z):
//! simulation of simplicity, the sign it has for the direction nudged to `D + (ε, ε², ε³)`.
//! That is this kernel's **fill rule**, as a rasterizer's top-left rule: a ray exactly
//! through an edge or a vertex belongs to the triangle that the nudged ray crosses. Every
//! decision is thus the exact decision for the nudged ray against the true vertices, so a ray
//! through a shared edge or a vertex of a closed fan is claimed by exactly one triangle, and
//! no ray slips through a closed mesh. A lone triangle, or a mesh's boundary, claims only the
//! points whose nudged ray passes inside: a ray ending exactly on a vertex may miss it (in the
//! plane z = 0 the nudged ray lands at the vertex plus `(ε, ε²)`, so the triangle (0,0,0),
//! (4,0,0), (0,3,0) is missed through its vertex (0,3,0) from every eye, while Cramer, Möller
//! and Watertight count it as inside; `tests/focal_rules.rs`).
//!
//! **Scaled directions and the interval.** For the bound `K` to hold without a per-ray
//! multiply, [`FocalRays`] scales each direction by the power of two `s` that brings
//! `max|D_i|` into `[1, 2)` (exact, unless a component is below `2^-126` of the largest) and
//! maps the interval to the scaled units exactly: the scaled `(t_min, t_max)` holds the `f32`
//! values whose `t·s`, rounded once, lies strictly inside the ray's interval, so a hit whose
//! own-unit `t` would overflow to `inf` or round to an end (to `0` for `t_min = 0`) is a miss.
//! `t` is scaled back by `s` once per query (per ray), `u`, `v` need nothing.
//!
//! **Operation count per lane** (measured by `examples/opcount.rs`):
//! `ops triangle-focal/miss: 9 mul, 6 add, 6 cmp`; edges passed but the triangle behind the eye
//! `ops triangle-focal/behind: 9 mul, 6 add, 8 cmp`; a hit with `t`, `u`, `v`
//! `ops triangle-focal/hit: 13 mul, 10 add, 1 div, 15 cmp` (`u`, `v`: 2 div once per ray, for
//! the winner). Per
//! ray and query ([`FocalRays::new`]): 3 mul and 2 cmp for the scaling, 6 mul, 2 add, 1 div,
//! 1 sqrt for the unit direction that bounding spheres use, and 1 mul, 1 add to scale `t`
//! back (the add turns `−0` into `+0`); the power of two and the interval are found per lane
//! in `f64` (not counted). A doubtful lane (`|e| ≤ K`) adds an exact predicate per doubtful
//! edge (`f64` expansions of three triple products, not counted).
//!
//! **The cache** is 112 bytes per triangle (28 `f32`: the four normals, three bounds, `V`, and
//! `A`, `B`, `C`, `E` for the exact fallback). Each value is rounded from `f64` with an error
//! bound, and from the exact expansion where the bound cannot settle the rounding (rarely).
//!
//! **Requirements and limits.** Rays start exactly at the cache's eye (their origin is not
//! read). An entry whose normals or `V` exceed `10^36` in magnitude is never hit (a triangle
//! of size `ℓ` at distance `c` needs `ℓ²·c` and `c·ℓ` below that, e.g. coordinates relative
//! to the eye up to about `2^40`). Where `V` or `N` fall below `f32`'s normal range
//! (`ℓ²·c` below about `10^-38`) `t`, `u`, `v` lose relative accuracy gradually, and a `V` that
//! rounds to zero gives no hit in `(0, t_max)`. Decisions stay exact throughout.
//! **Edge cases.** Invalid triangles (see [`Triangle::new`]), a non-finite eye, and `E` on
//! the line through an edge give entries that are never hit or edges whose zero values count
//! as positive; bad rays miss; records carry `+0`, never `−0`.
//!
//! [`Triangle::new`]: super::Triangle::new

use glam::Vec3;

use super::exact;
use super::{Cull, Triangle, in_front, within};
use crate::kernel::LaneHit;
use crate::lane::{Lane, Mask, Scalar};
use crate::ray::RayPacket;
use crate::vec3::V3;

/// Unit roundoff of f32.
const U: f64 = 1.0 / 16_777_216.0;
/// Bound on `max|D_i|` for scaled directions (`[1, 2)`, or `[2, 4)` beyond `2^127`).
const D_MAX: f64 = 4.0;
/// Largest normal component or `|V|` accepted in a cache entry.
const LIMIT: f64 = 1.0e36;

/// One triangle as seen from one focal point (or `L::LANES` triangles in lanes).
///
/// Build with [`FocalTriangle::new`] or [`focus`]; [`splat`](Self::splat) it for packets of
/// rays or [`gather`](Self::gather)/[`pack`](Self::pack) several into lanes for one ray
/// against many.
#[derive(Clone, Copy, Debug)]
pub struct FocalTriangle<L: Lane> {
    /// `A′ × B′`, `B′ × C′`, `C′ × A′`, each component rounded once from its exact value.
    n_ab: V3<L>,
    n_bc: V3<L>,
    n_ca: V3<L>,
    /// Rounding bounds of the edge values for scaled directions.
    k_ab: L,
    k_bc: L,
    k_ca: L,
    /// The plane normal `N = (B − A) × (C − A)`, each component rounded once from its
    /// exact value.
    n: V3<L>,
    /// `A′·(B′ × C′)` (`= N·A′`), rounded from its exact value.
    v: L,
    /// `A`, `B`, `C` and the eye `E`, for the exact fallback.
    a: V3<L>,
    b: V3<L>,
    c: V3<L>,
    e: V3<L>,
}

/// Rounds toward +inf.
fn up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}

fn wide(v: V3<f32>) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

/// The exact value of `x ± err` rounded to `f32`, when the whole interval rounds to one value
/// (rounding is monotone, so the exact value in it rounds there too); `None` when in doubt.
/// `err` is padded for the rounding of `x ± err` itself.
fn settled(x: f64, err: f64) -> Option<f32> {
    let err = err * 1.01 + x.abs() * (4.0 / 9_007_199_254_740_992.0);
    let (lo, hi) = ((x - err) as f32, (x + err) as f32);
    (lo == hi).then_some(lo)
}

/// `(p − e) × (q − e)` of `f32` vectors, each component correctly rounded to `f32` from its
/// exact value: in `f64` when its error bound settles the rounding (almost always), else from
/// the exact expansion. Twins are exact negations: swapping `p` and `q` negates the exact
/// value, and rounding to nearest is symmetric.
fn cross_rel(e: [f64; 3], p: [f64; 3], q: [f64; 3]) -> V3<f32> {
    let (a, b) = (sub(p, e), sub(q, e));
    let c = |j: usize, k: usize| {
        let (x, y) = (a[j] * b[k], a[k] * b[j]);
        // Two differences, two products and a subtraction, each within 2^-53 relative.
        settled(x - y, (x.abs() + y.abs()) * (6.0 / 9_007_199_254_740_992.0))
            .unwrap_or_else(|| exact::cross_rel(e, p, q, j, k).round_f32())
    };
    V3::new(c(1, 2), c(2, 0), c(0, 1))
}

/// `det[a − e, b − e, c − e]` correctly rounded to `f32` (fast path in `f64` as [`cross_rel`]).
fn det_rel(e: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f32 {
    let (p, q, r) = (sub(a, e), sub(b, e), sub(c, e));
    let terms = [
        p[0] * (q[1] * r[2]),
        -(p[0] * (q[2] * r[1])),
        p[1] * (q[2] * r[0]),
        -(p[1] * (q[0] * r[2])),
        p[2] * (q[0] * r[1]),
        -(p[2] * (q[1] * r[0])),
    ];
    let x: f64 = terms.iter().sum();
    let m: f64 = terms.iter().map(|t| t.abs()).sum();
    // Three differences, two products per term, five additions: within 10·2^-53 of m.
    settled(x, m * (16.0 / 9_007_199_254_740_992.0))
        .unwrap_or_else(|| exact::det_rel(e, a, b, c).round_f32())
}

fn sub(p: [f64; 3], q: [f64; 3]) -> [f64; 3] {
    [p[0] - q[0], p[1] - q[1], p[2] - q[2]]
}

/// The bound on `|fl(D·n) − D·n*|` for `n` rounded from the exact `n*` ([`cross_rel`]) and
/// `max|D_i| < D_MAX`: `γ3·Σ|D_i n_i|` for the dot product plus `Σ|D_i|·|n_i − n*_i|`,
/// at most `D_MAX·(γ3 + 1.0001·2^-24)·Σ|n_i|`; padded, plus an underflow term.
fn bound(n: V3<f32>) -> f64 {
    let g3 = 3.0 * U / (1.0 - 3.0 * U);
    let s = (n.x as f64).abs() + (n.y as f64).abs() + (n.z as f64).abs();
    D_MAX * (g3 + 1.0001 * U) * s * (1.0 + 1.0e-12) + 1.0e-42
}

impl FocalTriangle<f32> {
    /// An entry that is never hit.
    #[must_use]
    pub fn never() -> Self {
        let nan = V3::splat(Vec3::splat(f32::NAN));
        FocalTriangle {
            n_ab: nan,
            n_bc: nan,
            n_ca: nan,
            k_ab: f32::INFINITY,
            k_bc: f32::INFINITY,
            k_ca: f32::INFINITY,
            n: nan,
            v: f32::NAN,
            a: nan,
            b: nan,
            c: nan,
            e: nan,
        }
    }

    /// The entry of the triangle `a`, `b`, `c` for rays from `eye`. Triangles that share an
    /// edge (the same two vertex positions) get edge normals that are exact negations, which
    /// is what makes shared edges watertight: build every entry from the shared positions.
    #[must_use]
    pub fn from_vertices(eye: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Self {
        Self::new(eye, &Triangle::new(a, b, c))
    }

    /// The cache entry of `tri` for rays from `eye` (see the [module docs](self)).
    #[must_use]
    pub fn new(eye: Vec3, tri: &Triangle) -> Self {
        // A valid `Triangle` has finite vertices and nonzero area (checked when it was made).
        if !eye.is_finite() || !tri.is_valid() {
            return Self::never();
        }
        let (a, b, c) = (tri.a(), tri.b(), tri.c());
        let (we, wa, wb, wc) = (
            wide(eye.into()),
            wide(a.into()),
            wide(b.into()),
            wide(c.into()),
        );
        // 1. Edge-plane normals (A − E) × (B − E)…, exact then rounded (twins are exact
        //    negations), and the rounding bounds of the edge values.
        let (n_ab, n_bc, n_ca) = (
            cross_rel(we, wa, wb),
            cross_rel(we, wb, wc),
            cross_rel(we, wc, wa),
        );
        let (k_ab, k_bc, k_ca) = (bound(n_ab), bound(n_bc), bound(n_ca));
        // 2. The plane normal N = (B − A) × (C − A) and V = N·(A − E), exact then rounded
        //    (the sign of V is exact).
        let n = cross_rel(wa, wb, wc);
        let v = det_rel(we, wa, wb, wc);
        let fits = |n: V3<f32>| [n.x, n.y, n.z].iter().all(|x| (*x as f64).abs() <= LIMIT);
        let ok = fits(n_ab) && fits(n_bc) && fits(n_ca) && fits(n) && (v as f64).abs() <= LIMIT;
        if !ok || k_ab.max(k_bc).max(k_ca) > LIMIT {
            return Self::never();
        }
        FocalTriangle {
            n_ab,
            n_bc,
            n_ca,
            k_ab: up(k_ab),
            k_bc: up(k_bc),
            k_ca: up(k_ca),
            n,
            v,
            a: a.into(),
            b: b.into(),
            c: c.into(),
            e: eye.into(),
        }
    }
}

impl FocalTriangle<f32> {
    /// The eye the entry was built for (`None` for an entry that is never hit).
    #[inline]
    #[must_use]
    pub fn eye(&self) -> Option<Vec3> {
        let e: Vec3 = self.e.into();
        e.is_finite().then_some(e)
    }

    /// The triangle (one that is never hit for such an entry).
    #[inline]
    #[must_use]
    pub fn triangle(&self) -> Triangle {
        Triangle {
            a: self.a.into(),
            b: self.b.into(),
            c: self.c.into(),
        }
    }
}

impl<L: Lane> FocalTriangle<L> {
    /// The same entry in every lane (N rays × 1 triangle).
    #[inline(always)]
    #[must_use]
    pub fn splat(e: &FocalTriangle<f32>) -> Self {
        let v = |x: V3<f32>| V3::splat(x.into());
        FocalTriangle {
            n_ab: v(e.n_ab),
            n_bc: v(e.n_bc),
            n_ca: v(e.n_ca),
            k_ab: L::from_f32(e.k_ab),
            k_bc: L::from_f32(e.k_bc),
            k_ca: L::from_f32(e.k_ca),
            n: v(e.n),
            v: L::from_f32(e.v),
            a: v(e.a),
            b: v(e.b),
            c: v(e.c),
            e: v(e.e),
        }
    }

    /// Up to `L::LANES` entries, one per lane (1 ray × N triangles); missing lanes never hit.
    #[must_use]
    pub fn gather(entries: &[FocalTriangle<f32>]) -> Self {
        let never = FocalTriangle::never();
        let get = |i: usize| entries.get(i).copied().unwrap_or(never);
        let v = |f: fn(&FocalTriangle<f32>) -> V3<f32>| V3::from_fn(|i| f(&get(i)).into());
        let s = |f: fn(&FocalTriangle<f32>) -> f32| L::from_f32_fn(|i| f(&get(i)));
        FocalTriangle {
            n_ab: v(|e| e.n_ab),
            n_bc: v(|e| e.n_bc),
            n_ca: v(|e| e.n_ca),
            k_ab: s(|e| e.k_ab),
            k_bc: s(|e| e.k_bc),
            k_ca: s(|e| e.k_ca),
            n: v(|e| e.n),
            v: s(|e| e.v),
            a: v(|e| e.a),
            b: v(|e| e.b),
            c: v(|e| e.c),
            e: v(|e| e.e),
        }
    }

    /// Packs entries into `out` in chunks of `L::LANES`; returns the number of chunks written.
    pub fn pack(entries: &[FocalTriangle<f32>], out: &mut [FocalTriangle<L>]) -> usize {
        let mut n = 0;
        for (chunk, slot) in entries.chunks(L::LANES).zip(out.iter_mut()) {
            *slot = Self::gather(chunk);
            n += 1;
        }
        n
    }
}

/// Where the kernel reads its cached triangle lanes from: a [`FocalTriangle<L>`] already in
/// lanes (1 ray × N triangles), or a [`Splat`] of one entry (N rays × 1 triangle) that
/// broadcasts only what each step needs, so a miss reads the edge normals and bounds alone and
/// the exact fallback reads the scalar entry (no splatted copy of the whole entry is built).
pub trait FocalTriangleLanes<L: Lane> {
    /// `n_ab`, `n_bc`, `n_ca` in lanes.
    fn normals(&self) -> (V3<L>, V3<L>, V3<L>);
    /// `k_ab`, `k_bc`, `k_ca` in lanes.
    fn bounds(&self) -> (L, L, L);
    /// `N` in lanes.
    fn normal(&self) -> V3<L>;
    /// `V` in lanes.
    fn v(&self) -> L;
    /// `A`, `B`, `C` and the eye `E` of lane `i` in `f64` (exact), for the exact fallback.
    fn vertices(&self, i: usize) -> [[f64; 3]; 4];
}

impl<L: Lane> FocalTriangleLanes<L> for FocalTriangle<L> {
    #[inline(always)]
    fn normals(&self) -> (V3<L>, V3<L>, V3<L>) {
        (self.n_ab, self.n_bc, self.n_ca)
    }
    #[inline(always)]
    fn bounds(&self) -> (L, L, L) {
        (self.k_ab, self.k_bc, self.k_ca)
    }
    #[inline(always)]
    fn normal(&self) -> V3<L> {
        self.n
    }
    #[inline(always)]
    fn v(&self) -> L {
        self.v
    }
    #[inline(always)]
    fn vertices(&self, i: usize) -> [[f64; 3]; 4] {
        let w = |v: V3<L>| {
            [
                v.x.lane(i).to_f64(),
                v.y.lane(i).to_f64(),
                v.z.lane(i).to_f64(),
            ]
        };
        [w(self.a), w(self.b), w(self.c), w(self.e)]
    }
}

/// One cache entry seen in every lane, broadcast lazily (see [`FocalTriangleLanes`]).
#[derive(Clone, Copy, Debug)]
pub struct Splat<'a>(pub &'a FocalTriangle<f32>);

impl<L: Lane> FocalTriangleLanes<L> for Splat<'_> {
    #[inline(always)]
    fn normals(&self) -> (V3<L>, V3<L>, V3<L>) {
        let e = self.0;
        let v = |x: V3<f32>| V3::splat(x.into());
        (v(e.n_ab), v(e.n_bc), v(e.n_ca))
    }
    #[inline(always)]
    fn bounds(&self) -> (L, L, L) {
        let e = self.0;
        (
            L::from_f32(e.k_ab),
            L::from_f32(e.k_bc),
            L::from_f32(e.k_ca),
        )
    }
    #[inline(always)]
    fn normal(&self) -> V3<L> {
        V3::splat(self.0.n.into())
    }
    #[inline(always)]
    fn v(&self) -> L {
        L::from_f32(self.0.v)
    }
    #[inline(always)]
    fn vertices(&self, _i: usize) -> [[f64; 3]; 4] {
        let e = self.0;
        [wide(e.a), wide(e.b), wide(e.c), wide(e.e)]
    }
}

/// Builds the cache of `tris` for rays from `eye` into `out` (no allocation); returns the
/// number of entries written (`min(tris.len(), out.len())`).
pub fn focus(eye: Vec3, tris: &[Triangle], out: &mut [FocalTriangle<f32>]) -> usize {
    let mut n = 0;
    for (t, slot) in tris.iter().zip(out.iter_mut()) {
        *slot = FocalTriangle::new(eye, t);
        n += 1;
    }
    n
}

/// Rays from the eye, prepared once per query: each direction scaled exactly by a power of two
/// `s` with `max|D_i|` in `[1, 2)`, the interval mapped to the scaled units (a scaled `t`
/// strictly inside it comes back as a finite `t·s` strictly inside the ray's own interval),
/// and a unit direction for bounding spheres ([`FocalSphere`](crate::sphere::FocalSphere)).
#[derive(Clone, Copy, Debug)]
pub struct FocalRays<L: Lane> {
    pub(crate) scaled: RayPacket<L>,
    pub(crate) scale: L,
    pub(crate) unit: V3<L>,
}

/// The largest `f32` value `x` whose own-unit parameter `fl(x·s)` (`s = 1/inv`, a power of
/// two; one rounding to `f32`) is at most `t`, for `t` from `−inf` to `f32::MAX`: then
/// `x > above(t)` exactly when `fl(x·s) > t`. The rounding boundary above `t` (the midpoint to
/// the next `f32`, or `±(f32::MAX + 2^103)` where rounding reaches `±inf`) is exact in `f64`,
/// and so is its scaling by `inv`; a tie rounds to the even neighbour (to `inf` at the top).
fn above(t: f32, inv: f64) -> f32 {
    if t.is_nan() || t == f32::INFINITY {
        return t;
    }
    let q = t.next_up();
    let edge = f32::MAX as f64 + f64::from_bits((1023 + 103) << 52);
    let b = if t == f32::NEG_INFINITY {
        -edge
    } else if q == f32::INFINITY {
        edge
    } else {
        (t as f64 + q as f64) / 2.0
    };
    let tie_up = q == f32::INFINITY || q.to_bits() & 1 == 0;
    let c = b * inv;
    let x = -up(-c); // the largest f32 at most c
    if tie_up && x as f64 == c {
        x.next_down()
    } else {
        x
    }
}

/// The interval `(t_min, t_max)` of a ray in the units of its direction scaled by a power of
/// two `s = 1/inv`: the open interval of the `f32` values `x` whose own-unit parameter
/// `fl(x·s)` lies strictly inside `(t_min, t_max)`, so never `±inf`. `x·s` is exact unless it
/// over- or underflows, so this is `(t_min·inv, t_max·inv)` in the normal range; at the ends
/// it leaves out the scaled `t` that would come back infinite or round onto an end. By
/// symmetry of rounding, `fl(x·s) < t_max` exactly when `x < −above(−t_max)`.
fn scaled_interval(t_min: f32, t_max: f32, inv: f64) -> (f32, f32) {
    (above(t_min, inv), -above(-t_max, inv))
}

/// Powers of two `(s, 1/s)` with `m·s` in `[1, 2)` for `m` in f32's normal range.
fn pow2_scale(m: f64) -> (f64, f64) {
    let e = ((m.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    let k = e.clamp(-126, 126);
    let pow2 = |k: i32| f64::from_bits(((k + 1023) as u64) << 52);
    (pow2(-k), pow2(k))
}

impl<L: Lane> FocalRays<L> {
    /// Prepares `rays` (which must start at the eye of the caches they are tested against):
    /// 3 mul and 2 cmp for the scaling, 6 mul, 2 add, 1 div, 1 sqrt for the unit direction;
    /// the power of two and the scaled interval are found per lane in `f64` (not counted).
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    #[must_use]
    pub fn new(rays: &RayPacket<L>) -> Self {
        let d = rays.dir;
        // 1. The largest |component| and the power of two that brings it into [1, 2).
        let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
        let m = L::select(ax.ge(ay), ax, ay);
        let m = L::select(m.ge(az), m, az);
        crate::lane::assert_fits::<L>();
        let mut s = [0f64; crate::lane::MAX_LANES];
        let mut lo = [0f32; crate::lane::MAX_LANES];
        let mut hi = [0f32; crate::lane::MAX_LANES];
        for i in 0..L::LANES {
            let inv;
            (s[i], inv) = pow2_scale(m.lane(i).to_f64());
            // 2. The interval in the scaled units, such that a scaled t strictly inside comes
            //    back strictly inside (t_min, t_max) and finite.
            let (t0, t1) = (rays.t_min.lane(i).to_f64(), rays.t_max.lane(i).to_f64());
            (lo[i], hi[i]) = scaled_interval(t0 as f32, t1 as f32, inv);
        }
        let scale = L::from_fn(|i| L::Scalar::from_f64(s[i]));
        // 3. Exact scaling of the direction.
        let dir = d.scale(scale);
        let scaled = RayPacket {
            origin: rays.origin,
            dir,
            t_min: L::from_f32_fn(|i| lo[i]),
            t_max: L::from_f32_fn(|i| hi[i]),
        };
        // 4. The unit direction.
        let unit = dir.scale(L::from_f32(1.0) / dir.length_squared().sqrt());
        FocalRays {
            scaled,
            scale,
            unit,
        }
    }

    /// The scaled rays (the kernel's units).
    #[inline]
    #[must_use]
    pub fn scaled(&self) -> &RayPacket<L> {
        &self.scaled
    }

    /// `s`: a `t` in the scaled units times `s` is the ray's own `t`.
    #[inline]
    #[must_use]
    pub fn scale(&self) -> L {
        self.scale
    }

    /// The unit directions (for bounding-sphere tests).
    #[inline]
    #[must_use]
    pub fn unit(&self) -> V3<L> {
        self.unit
    }

    /// Rays for bounding spheres: from the eye along the unit directions, over `(−inf, +inf)`.
    #[inline]
    #[must_use]
    pub(crate) fn unit_lines(&self) -> RayPacket<L> {
        RayPacket {
            origin: self.scaled.origin,
            dir: self.unit,
            t_min: L::from_f32(f32::NEG_INFINITY),
            t_max: L::from_f32(f32::INFINITY),
        }
    }

    /// A `t` in the scaled units in the rays' own (1 mul, and 1 add for `+0`).
    #[inline(always)]
    #[must_use]
    pub fn own_units(&self, t: L) -> L {
        own_units(t, self.scale)
    }

    /// Converts a hit from the scaled units to the rays' own (1 mul, and 1 add for `+0`).
    #[inline(always)]
    #[must_use]
    pub fn unscale(&self, h: LaneHit<L>) -> LaneHit<L> {
        LaneHit {
            t: own_units(h.t, self.scale),
            ..h
        }
    }
}

/// `t·s + 0`: a scaled `t` in the rays' own units (exact unless it underflows), with `−0`
/// (a tiny negative `t` rounded to zero) made `+0` as in every record.
#[inline(always)]
fn own_units<L: Lane>(t: L, s: L) -> L {
    t * s + L::from_f32(0.0)
}

/// The focal test of scaled ray lanes (from [`FocalRays`]: the rounding bounds `K` hold only
/// for `max|D_i| < 4`) against cached triangle lanes; `t` in the scaled units. See the
/// [module docs](self).
#[inline(always)]
#[must_use]
pub fn kernel<L: Lane, F: FocalTriangleLanes<L>>(
    ray: &RayPacket<L>,
    f: &F,
    cull: Cull,
) -> LaneHit<L> {
    maybe_hit(ray, f, cull).unwrap_or_else(LaneHit::miss)
}

/// Steps 1 and 2 of the test: the edge values and their signs where they are certain.
struct Edges<L: Lane> {
    e: [L; 3],
    /// Certainly positive (`e > K`).
    pos: [L::Mask; 3],
    /// Certainly negative (`e < −K`).
    neg: [L::Mask; 3],
}

impl<L: Lane> Edges<L> {
    #[inline(always)]
    fn new<F: FocalTriangleLanes<L>>(ray: &RayPacket<L>, f: &F) -> Self {
        let d = ray.dir;
        // 1. Edge values: the direction against the three cached edge-plane normals.
        let (na, nb, nc) = f.normals();
        let e = [d.dot(na), d.dot(nb), d.dot(nc)];
        // 2. Signs beyond the rounding bound are exact.
        let (k_ab, k_bc, k_ca) = f.bounds();
        let k = [k_ab, k_bc, k_ca];
        Edges {
            e,
            pos: [e[0].gt(k[0]), e[1].gt(k[1]), e[2].gt(k[2])],
            neg: [e[0].lt(-k[0]), e[1].lt(-k[1]), e[2].lt(-k[2])],
        }
    }

    /// Some edge is certainly positive / certainly negative.
    #[inline(always)]
    fn any(&self) -> (L::Mask, L::Mask) {
        let [p0, p1, p2] = self.pos;
        let [n0, n1, n2] = self.neg;
        (p0 | p1 | p2, n0 | n1 | n2)
    }

    /// The lanes that certainly miss: a certainly positive and a certainly negative edge (with
    /// back faces culled, a certainly positive edge suffices).
    #[inline(always)]
    fn out(&self, cull: Cull) -> L::Mask {
        let (any_p, any_n) = self.any();
        if cull.back() { any_p } else { any_p & any_n }
    }

    /// True when every lane certainly misses.
    #[inline(always)]
    fn all_out(&self, cull: Cull) -> bool {
        self.out(cull).all()
    }
}

/// The lanes that may hit (none when [`maybe_hit`] returns `None`): the first pass of the
/// closest-hit loop, with no calls, so the rays stay in registers.
#[inline(always)]
#[must_use]
pub(crate) fn candidate<L: Lane, F: FocalTriangleLanes<L>>(
    ray: &RayPacket<L>,
    f: &F,
    cull: Cull,
) -> L::Mask {
    !Edges::new(ray, f).out(cull)
}

/// [`kernel`], or `None` when no lane hits: the miss paths end before any record is built, and
/// the closest/any loops skip their merge.
#[inline(always)]
#[must_use]
pub fn maybe_hit<L: Lane, F: FocalTriangleLanes<L>>(
    ray: &RayPacket<L>,
    f: &F,
    cull: Cull,
) -> Option<LaneHit<L>> {
    // 1.–2. Edge values and their certain signs; stop when every lane certainly misses.
    let edges = Edges::new(ray, f);
    if edges.all_out(cull) {
        return None;
    }
    let Edges {
        e: [e_ab, e_bc, e_ca],
        pos: [p_ab, p_bc, p_ca],
        neg: [n_ab, n_bc, n_ca],
    } = edges;
    let (any_p, any_n) = edges.any();
    // All negative is a front face, all positive a back face.
    let mut front = n_ab & n_bc & n_ca;
    let mut back = p_ab & p_bc & p_ca;
    // 3. Lanes where a sign in doubt could complete a pattern: decide those signs exactly.
    let finite = e_ab.is_finite() & e_bc.is_finite() & e_ca.is_finite();
    let maybe_front = !any_p;
    let maybe_back = !any_n;
    let mut doubtful = maybe_front.and_not(front);
    if !cull.back() {
        doubtful = doubtful | maybe_back.and_not(back);
    }
    doubtful = doubtful & finite;
    if doubtful.any() {
        let certain = [(p_ab, n_ab), (p_bc, n_bc), (p_ca, n_ca)];
        (front, back) = exact_signs(ray, f, doubtful, certain, front, back);
    }
    let mask = if cull.back() { front } else { front | back };
    if mask.none() {
        return None;
    }
    // 4. t > 0: ±V with the sign of det (exact).
    let v = f.v();
    let num_t = L::select(front, -v, v);
    let mask = in_front(ray, mask, num_t);
    if mask.none() {
        return None;
    }
    // 5. |det| = ±D·N from the cached plane normal (Σ|e| where the rounded D·N has not the
    //    sign of the exact decision); the barycentrics over max(|det|, |e_ca| + |e_ab|), so
    //    that u + v ≤ 1. The interval, then the one division.
    let (x_ab, x_ca) = (e_ab.abs(), e_ca.abs());
    let x_uv = x_ab + x_ca;
    let dn = ray.dir.dot(f.normal());
    let det = L::select(front, -dn, dn);
    let den = L::select(det.gt(L::from_f32(0.0)), det, x_uv + e_bc.abs());
    let w = L::select(x_uv.gt(den), x_uv, den);
    within(ray, mask, num_t, den, x_ca, x_ab, w)
}

/// Decides the `doubtful` lanes with exact edge signs (simulation of simplicity for zeros).
#[inline(never)]
fn exact_signs<L: Lane, F: FocalTriangleLanes<L>>(
    ray: &RayPacket<L>,
    f: &F,
    doubtful: L::Mask,
    certain: [(L::Mask, L::Mask); 3],
    mut front: L::Mask,
    mut back: L::Mask,
) -> (L::Mask, L::Mask) {
    let mut bits = doubtful.bits();
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let (lo, hi) = (ray.t_min.lane(i), ray.t_max.lane(i));
        if lo.partial_cmp(&hi) != Some(core::cmp::Ordering::Less) {
            continue; // an invalid ray misses anyway
        }
        let d = [
            ray.dir.x.lane(i).to_f64(),
            ray.dir.y.lane(i).to_f64(),
            ray.dir.z.lane(i).to_f64(),
        ];
        let [a, b, c, e] = f.vertices(i);
        let mut signs = [0i32; 3];
        for (k, (p, q)) in [(a, b), (b, c), (c, a)].into_iter().enumerate() {
            let (pos, neg) = certain[k];
            signs[k] = if pos.test(i) {
                1
            } else if neg.test(i) {
                -1
            } else {
                match exact::edge_rel(d, e, p, q).sign() {
                    0 if exact::sos_sign_rel(e, p, q) < 0 => -1,
                    0 => 1,
                    s => s,
                }
            };
        }
        front = front.with_lane(i, signs == [-1; 3]);
        back = back.with_lane(i, signs == [1; 3]);
    }
    (front, back)
}

/// The hit of prepared ray lanes on cached triangle lanes, `t` in the rays' own units.
#[inline(always)]
#[must_use]
pub fn intersect_lanes<L: Lane>(
    rays: &FocalRays<L>,
    tri: &FocalTriangle<L>,
    cull: Cull,
) -> LaneHit<L> {
    rays.unscale(kernel(&rays.scaled, tri, cull)).normalized()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::SmallRng;
    use rand::{Rng, SeedableRng};

    /// The `f64` fast paths give the correctly rounded exact values, bit for bit, also where
    /// components nearly cancel (collinear-ish points, large offsets, tiny and huge scales).
    #[test]
    fn fast_paths_round_like_the_expansions() {
        let mut rng = SmallRng::seed_from_u64(7);
        let mut f = |s: f32| rng.random_range(-1.0..1.0f32) * s;
        for i in 0..200_000 {
            let s = [1.0e-20, 1.0e-3, 1.0, 3.0e3, 1.0e5, 1.0e15][i % 6];
            let e = [f(s), f(s), f(s)].map(|x| x as f64);
            let p = [f(s), f(s), f(s)].map(|x| x as f64);
            let q: [f64; 3] = if i % 3 == 0 {
                // Nearly collinear with e and p: cancelling components.
                let k = f(1.0);
                [0, 1, 2].map(|j| ((e[j] + k as f64 * (p[j] - e[j])) as f32) as f64)
            } else {
                [f(s), f(s), f(s)].map(|x| x as f64)
            };
            let r = [f(s), f(s), f(s)].map(|x| x as f64);
            let fast = cross_rel(e, p, q);
            let want = |j, k| exact::cross_rel(e, p, q, j, k).round_f32().to_bits();
            assert_eq!(
                [fast.x.to_bits(), fast.y.to_bits(), fast.z.to_bits()],
                [want(1, 2), want(2, 0), want(0, 1)]
            );
            let twin = cross_rel(e, q, p);
            assert_eq!([twin.x, twin.y, twin.z], [-fast.x, -fast.y, -fast.z]);
            assert_eq!(
                det_rel(e, p, q, r).to_bits(),
                exact::det_rel(e, p, q, r).round_f32().to_bits()
            );
        }
    }
}
