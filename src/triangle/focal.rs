//! Rays from one focal point: per-triangle caches of edge-plane normals, watertight by
//! construction.
//!
//! Primary rays of a pinhole camera all start at the eye `E` (lecture 000, "Rays from Focal
//! Point"). With `A′ = A − E`, `B′ = B − E`, `C′ = C − E` (rounded to f32 once, from the shared
//! vertex positions), the planes through `E` and each edge have the normals
//!
//! ```text
//! n_ab = A′ × B′     n_bc = B′ × C′     n_ca = C′ × A′          (cached, f32)
//! V = A′·(B′ × C′) = N·A′,  N = (B − A) × (C − A) = n_ab + n_bc + n_ca   (cached, exact sign)
//! ```
//!
//! and per ray with direction `D` (any length):
//!
//! ```text
//! e_ab = D·n_ab,  e_bc = D·n_bc,  e_ca = D·n_ca        9 mul, 6 add   → a miss ends here
//! det = e_ab + e_bc + e_ca (= D·N)                      2 add
//! u = e_ca/det (weight of B),  v = e_ab/det (weight of C),  t = V/det
//! ```
//!
//! The ray crosses the triangle when the three edge values have one sign (negative: a front
//! face, `D·N < 0`). With that sign folded in, `|det| = |e_ab| + |e_bc| + |e_ca|`, `t > 0` is
//! the sign of `±V`, and `t < t_max` is `±V < t_max·|det|`; only lanes that pass divide
//! (`t = ±V/|det|`: in a closest-hit loop, only the hits that win so far), and `u`, `v` are
//! divided once per ray for the winner (see [`triangle`](super) on deferred division).
//!
//! **Watertight, each crossing reported once.** Two triangles sharing the edge AB compute its
//! normal as `A′ × B′` and `B′ × A′` from the same f32 vectors: in IEEE arithmetic these are
//! exact negations, and so are their dot products with `D`. Each edge sign is moreover made
//! *exact*: the cache holds a bound `K` on the rounding error of `e` (for directions scaled so
//! that `max|D_i| < 4`), and the rare lanes with `|e| ≤ K` recompute the sign of
//! `det[D, A′, B′]` exactly (expansion arithmetic in `f64`, Shewchuk 1997). An exactly zero
//! edge value takes the sign of the first nonzero component of its exact normal (x, then y,
//! then z): simulation of simplicity, the same as perturbing `D` by `(ε, ε², ε³)`. Every
//! decision is then the exact decision for one perturbed ray against the mesh of vertices
//! `A′`, so a ray through a shared edge or a shared vertex of a closed fan is claimed by
//! exactly one triangle, and no ray slips through a closed mesh. (The signs of twin edges
//! alone do not suffice at vertices: the rounded spoke normals of a fan need not meet in one
//! line, and `tests/watertight.rs` measured 20 leaks and 299 double hits on vertex-aimed rays
//! without the exact signs.)
//!
//! **Scaled directions.** For the bound `K` to hold without a per-ray multiply, [`FocalRays`]
//! scales each direction by the power of two `s` that brings `max|D_i|` into `[1, 2)` (exact,
//! unless a component is below `2^-126` of the largest) and the interval by `1/s`; `t` is
//! scaled back by `s` once per query (1 mul per ray), `u`, `v` need nothing.
//!
//! **Operation count per lane** (measured by `examples/opcount.rs`): miss 9 mul, 6 add,
//! 6 cmp; edges passed but the triangle behind the eye 9 mul, 8 add; a hit with `t`, `u`, `v`
//! 10 mul, 8 add, 1 div, 11 cmp (`u`, `v`: 2 div once per ray, for the winner). Per ray and
//! query ([`FocalRays::new`]): 5 mul and 2 cmp for the scaling, 6 mul, 2 add, 1 div,
//! 1 sqrt for the unit direction that bounding spheres use, and 1 mul to scale `t` back. A
//! doubtful lane (`|e| ≤ K`) adds an exact predicate in `f64` per doubtful edge (about 60
//! flops, not counted).
//!
//! **Requirements and limits.** Rays start exactly at the cache's eye (their origin is not
//! read). Coordinates relative to the eye up to about `2^42` (`V` must fit in f32); beyond,
//! the entry is never hit. Decisions are exact for the rounded vertices `A′` (within
//! `2^-24|A − E|` of the true ones). `t` and the barycentrics come from the sum of the three
//! edge values, each of size up to `c·ℓ` for a triangle of size `ℓ` at distance `c`, while the
//! sum is about `ℓ²·cos θ` (θ between the ray and the normal): their relative error is about
//! `3·2^-24·c/(ℓ·cos θ)`, a few ulps for a triangle seen face-on from nearby, up to 8e-5 on
//! the benchmark scenes (triangles of size 0.4–2 at 4–40 units, some seen nearly edge-on). The
//! general kernels (`watertight`, `moller`) are more accurate there. **Edge cases.** Invalid triangles (see
//! [`Triangle::new`]), a non-finite eye, and `E` on the line through an edge give entries
//! that are never hit or edges whose zero values count as positive; bad rays miss.
//!
//! [`Triangle::new`]: super::Triangle::new

use glam::Vec3;

use super::exact;
use super::{Cull, Triangle, resolve};
use crate::hit::{self, Hit, HitRecord, LaneHit};
use crate::lane::{Lane, Mask, Scalar};
use crate::ray::{Ray, RayPacket};
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
    /// `A′ × B′`, `B′ × C′`, `C′ × A′` in f32.
    n_ab: V3<L>,
    n_bc: V3<L>,
    n_ca: V3<L>,
    /// Rounding bounds of the edge values for scaled directions.
    k_ab: L,
    k_bc: L,
    k_ca: L,
    /// `A′·(B′ × C′)`, rounded from its exact value.
    v: L,
    /// `A′`, `B′`, `C′`, for the exact fallback.
    a: V3<L>,
    b: V3<L>,
    c: V3<L>,
}

/// Rounds toward +inf.
fn up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}

fn wide(v: V3<f32>) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

/// The rounding bound of `fl(D·fl(p × q))` against `D·(p × q)` for `max|D_i| < D_MAX`:
/// `D_MAX·(γ2·Σ(|p_j q_k| + |p_k q_j|) + γ3·Σ|n_i|)`, padded, plus an underflow term.
fn bound(p: [f64; 3], q: [f64; 3], n: V3<f32>) -> f64 {
    let g2 = 2.0 * U / (1.0 - 2.0 * U);
    let g3 = 3.0 * U / (1.0 - 3.0 * U);
    let m = (p[1] * q[2]).abs()
        + (p[2] * q[1]).abs()
        + (p[2] * q[0]).abs()
        + (p[0] * q[2]).abs()
        + (p[0] * q[1]).abs()
        + (p[1] * q[0]).abs();
    let s = (n.x as f64).abs() + (n.y as f64).abs() + (n.z as f64).abs();
    D_MAX * (g2 * m + g3 * s) * (1.0 + 1.0e-12) + 1.0e-42
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
            v: f32::NAN,
            a: nan,
            b: nan,
            c: nan,
        }
    }

    /// The cache entry of `tri` for rays from `eye` (see the [module docs](self)).
    #[must_use]
    pub fn new(eye: Vec3, tri: &Triangle) -> Self {
        Self::from_vertices(eye, tri.a(), tri.b(), tri.c())
    }

    /// The entry of the triangle `a`, `b`, `c` for rays from `eye`. Triangles that share a
    /// vertex position get bit-identical `A′` (one rounded subtraction), which is what makes
    /// shared edges watertight: build every entry from the shared positions.
    #[must_use]
    pub fn from_vertices(eye: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Self {
        if !eye.is_finite() || !Triangle::new(a, b, c).is_valid() {
            return Self::never();
        }
        // 1. Vertices relative to the eye, rounded once.
        let e = V3::<f32>::from(eye);
        let (a, b, c) = (V3::from(a) - e, V3::from(b) - e, V3::from(c) - e);
        let (wa, wb, wc) = (wide(a), wide(b), wide(c));
        if exact::collinear(wa, wb, wc) {
            return Self::never();
        }
        // 2. Edge-plane normals in f32 (twins are exact negations) and their rounding bounds.
        let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
        let (k_ab, k_bc, k_ca) = (
            bound(wa, wb, n_ab),
            bound(wb, wc, n_bc),
            bound(wc, wa, n_ca),
        );
        // 3. V = A′·(B′ × C′), exact then rounded (its sign is exact).
        let v = exact::triple(wa, wb, wc).approx();
        let fits = |n: V3<f32>| [n.x, n.y, n.z].iter().all(|x| (*x as f64).abs() <= LIMIT);
        let ok = fits(n_ab) && fits(n_bc) && fits(n_ca) && v.abs() <= LIMIT;
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
            v: v as f32,
            a,
            b,
            c,
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
            v: L::from_f32(e.v),
            a: v(e.a),
            b: v(e.b),
            c: v(e.c),
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
            v: s(|e| e.v),
            a: v(|e| e.a),
            b: v(|e| e.b),
            c: v(|e| e.c),
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
pub(crate) trait FocalTriangleLanes<L: Lane> {
    /// `n_ab`, `n_bc`, `n_ca` in lanes.
    fn normals(&self) -> (V3<L>, V3<L>, V3<L>);
    /// `k_ab`, `k_bc`, `k_ca` in lanes.
    fn bounds(&self) -> (L, L, L);
    /// `V` in lanes.
    fn v(&self) -> L;
    /// `A′`, `B′`, `C′` of lane `i` in `f64` (exact), for the exact fallback.
    fn vertices(&self, i: usize) -> [[f64; 3]; 3];
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
    fn v(&self) -> L {
        self.v
    }
    #[inline(always)]
    fn vertices(&self, i: usize) -> [[f64; 3]; 3] {
        let w = |v: V3<L>| {
            [
                v.x.lane(i).to_f64(),
                v.y.lane(i).to_f64(),
                v.z.lane(i).to_f64(),
            ]
        };
        [w(self.a), w(self.b), w(self.c)]
    }
}

/// One cache entry seen in every lane, broadcast lazily (see [`FocalTriangleLanes`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Splat<'a>(pub(crate) &'a FocalTriangle<f32>);

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
    fn v(&self) -> L {
        L::from_f32(self.0.v)
    }
    #[inline(always)]
    fn vertices(&self, _i: usize) -> [[f64; 3]; 3] {
        let e = self.0;
        [wide(e.a), wide(e.b), wide(e.c)]
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
/// `s` with `max|D_i|` in `[1, 2)`, the interval by `1/s`, and a unit direction for bounding
/// spheres ([`FocalSphere`](crate::sphere::FocalSphere)).
#[derive(Clone, Copy, Debug)]
pub struct FocalRays<L: Lane> {
    pub(crate) scaled: RayPacket<L>,
    pub(crate) scale: L,
    pub(crate) unit: V3<L>,
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
    /// 5 mul and 2 cmp for the scaling, 6 mul, 2 add, 1 div, 1 sqrt for the unit direction.
    #[inline]
    #[must_use]
    pub fn new(rays: &RayPacket<L>) -> Self {
        let d = rays.dir;
        // 1. The largest |component| and the power of two that brings it into [1, 2).
        let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
        let m = L::select(ax.ge(ay), ax, ay);
        let m = L::select(m.ge(az), m, az);
        crate::lane::assert_fits::<L>();
        let mut s = [0f64; crate::lane::MAX_LANES];
        let mut inv = [0f64; crate::lane::MAX_LANES];
        for i in 0..L::LANES {
            (s[i], inv[i]) = pow2_scale(m.lane(i).to_f64());
        }
        let scale = L::from_fn(|i| L::Scalar::from_f64(s[i]));
        let inv = L::from_fn(|i| L::Scalar::from_f64(inv[i]));
        // 2. Exact scaling of the direction and the interval.
        let dir = d.scale(scale);
        let scaled = RayPacket {
            origin: rays.origin,
            dir,
            t_min: rays.t_min * inv,
            t_max: rays.t_max * inv,
        };
        // 3. The unit direction.
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
    pub fn unit_lines(&self) -> RayPacket<L> {
        RayPacket {
            origin: self.scaled.origin,
            dir: self.unit,
            t_min: L::from_f32(f32::NEG_INFINITY),
            t_max: L::from_f32(f32::INFINITY),
        }
    }

    /// Converts a hit from the scaled units to the rays' own (1 mul).
    #[inline(always)]
    #[must_use]
    pub fn unscale(&self, h: LaneHit<L>) -> LaneHit<L> {
        LaneHit {
            t: h.t * self.scale,
            ..h
        }
    }
}

/// The focal test of scaled ray lanes (from [`FocalRays`]: the rounding bounds `K` hold only
/// for `max|D_i| < 4`) against cached triangle lanes; `t` in the scaled units. See the
/// [module docs](self).
#[inline(always)]
#[must_use]
pub(crate) fn kernel<L: Lane, F: FocalTriangleLanes<L>>(
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
pub(crate) fn maybe_hit<L: Lane, F: FocalTriangleLanes<L>>(
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
    // 4. |det| = Σ|e| and ±V with the sign of det; the interval, then the one division.
    let (x_ab, x_ca) = (e_ab.abs(), e_ca.abs());
    let ad = x_ab + e_bc.abs() + x_ca;
    let v = f.v();
    Some(resolve(ray, mask, L::select(front, -v, v), x_ca, x_ab, ad))
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
        let [a, b, c] = f.vertices(i);
        let mut signs = [0i32; 3];
        for (k, (p, q)) in [(a, b), (b, c), (c, a)].into_iter().enumerate() {
            let (pos, neg) = certain[k];
            signs[k] = if pos.test(i) {
                1
            } else if neg.test(i) {
                -1
            } else {
                match exact::sign_triple(d, p, q) {
                    0 if exact::sos_sign(p, q) < 0 => -1,
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

/// The hit of one ray from the eye on one cached triangle, or `None`.
#[inline]
#[must_use]
pub fn intersect(ray: &Ray, tri: &FocalTriangle<f32>, cull: Cull) -> Option<HitRecord> {
    intersect_lanes(&FocalRays::new(&RayPacket::splat(ray)), tri, cull).record()
}

/// Closest hit of prepared rays over cached triangles (N rays × 1 triangle).
#[inline]
#[must_use]
pub fn closest_prepared<L: Lane>(
    rays: &FocalRays<L>,
    cache: &[FocalTriangle<f32>],
    cull: Cull,
) -> Hit<L> {
    // Two passes, the cheap edge test over a block of triangles first.
    let mut best = hit::closest_filtered(
        &rays.scaled,
        cache,
        |r, e| candidate(r, &Splat(e), cull),
        |r, e| maybe_hit(r, &Splat(e), cull),
    );
    best.t = best.t * rays.scale;
    best
}

/// Closest hit of ray packets from the cache's eye over cached triangles (N rays × 1).
#[inline]
#[must_use]
pub fn closest<L: Lane>(rays: &RayPacket<L>, cache: &[FocalTriangle<f32>], cull: Cull) -> Hit<L> {
    closest_prepared(&FocalRays::new(rays), cache, cull)
}

/// Lanes whose ray hits some cached triangle (occlusion).
#[inline]
#[must_use]
pub fn any<L: Lane>(rays: &RayPacket<L>, cache: &[FocalTriangle<f32>], cull: Cull) -> L::Mask {
    let fr = FocalRays::new(rays);
    hit::any(&fr.scaled, cache, |r, e| maybe_hit(r, &Splat(e), cull))
}

/// Every hit of prepared rays: `f(index, hit)` for each cached triangle some lane hits (`t` in
/// the rays' own units).
#[inline]
pub fn all_prepared<L: Lane>(
    rays: &FocalRays<L>,
    cache: &[FocalTriangle<f32>],
    cull: Cull,
    mut f: impl FnMut(u32, &LaneHit<L>),
) {
    for (i, e) in cache.iter().enumerate() {
        let h = kernel(&rays.scaled, &Splat(e), cull);
        if h.mask.any() {
            f(i as u32, &rays.unscale(h).normalized());
        }
    }
}

/// Every hit: `f(index, hit)` for each cached triangle some lane hits.
#[inline]
pub fn all<L: Lane>(
    rays: &RayPacket<L>,
    cache: &[FocalTriangle<f32>],
    cull: Cull,
    f: impl FnMut(u32, &LaneHit<L>),
) {
    all_prepared(&FocalRays::new(rays), cache, cull, f);
}

/// The scaled ray and its scale, for the one-ray entry points.
fn scaled_ray(ray: &Ray) -> (Ray, f32) {
    let fr = FocalRays::<f32>::new(&RayPacket::splat(ray));
    (fr.scaled.ray(0), fr.scale)
}

/// Closest hit of one ray from the eye over cached triangles packed in lanes (1 ray × N).
#[inline]
#[must_use]
pub fn closest_soa<L: Lane>(
    ray: &Ray,
    cache: &[FocalTriangle<L>],
    cull: Cull,
) -> Option<HitRecord> {
    let (r, s) = scaled_ray(ray);
    hit::closest_soa(&r, cache, |r, e| maybe_hit(r, e, cull)).map(|h| HitRecord { t: h.t * s, ..h })
}

/// True when one ray from the eye hits some cached triangle packed in lanes.
#[inline]
#[must_use]
pub fn any_soa<L: Lane>(ray: &Ray, cache: &[FocalTriangle<L>], cull: Cull) -> bool {
    let (r, _) = scaled_ray(ray);
    hit::any_soa(&r, cache, |r, e| maybe_hit(r, e, cull))
}
