//! Test vectors: parser, batched runner, per-method limits, comparison and digest.
//!
//! One implementation, no allocation, shared by the checker (`examples/check.rs`), the host
//! tests and the firmware under `targets/`. The files under `tests/vectors/` hold one case a
//! line (`#` starts a comment):
//!
//! ```text
//! sphere   ox oy oz  dx dy dz  cx cy cz  r                -> miss | t0 [t1]
//! plane    ox oy oz  dx dy dz  px py pz  nx ny nz         -> miss | t
//! triangle ox oy oz  dx dy dz  ax ay az  bx by bz  cx cy cz -> miss | t u v
//! ```
//!
//! The ray interval is `(0, +inf)`; sphere expectations list every root in it, ascending.
//!
//! [`evaluate`] runs cases through one [`Method`] at one lane width, batching consecutive cases
//! of a kind into the lanes (so lane independence is tested too). [`compare`] checks an outcome
//! against the expectation: `t` within a relative [`T_TOLERANCE`], barycentrics within an
//! absolute [`UV_TOLERANCE`], and the same hit/miss. A case outside a method's documented
//! limits ([`Method::limits`]) is reported as such, not compared.

use core::fmt;
use core::hash::Hasher as _;

use glam::Vec3;

use crate::lane::{Lane, MAX_LANES, Mask};
use crate::plane::{self, FocalPlane, Plane, PlanePacket};
use crate::ray::RayPacket;
use crate::sphere::focal::{Focal, FocalKernel, FocalUnguarded};
use crate::sphere::{
    FocalSphere, Geometric, Quadratic, QuadraticUnit, Robust, Roots, Sphere, SphereKernel,
    SpherePacket,
};
use crate::triangle::{
    self, Cramer, Cull, FocalRays, FocalTriangle, Moller, Triangle, TriangleKernel, TrianglePacket,
    Watertight,
};
use crate::vec3::V3;

/// Relative tolerance on `t`.
pub const T_TOLERANCE: f64 = 2e-5;
/// Absolute tolerance on the barycentrics `u`, `v`.
pub const UV_TOLERANCE: f64 = 2e-5;

/// The primitive a case tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `sphere` lines: 10 inputs.
    Sphere,
    /// `plane` lines: 12 inputs.
    Plane,
    /// `triangle` lines: 15 inputs.
    Triangle,
}

impl Kind {
    /// The keyword that starts the line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Kind::Sphere => "sphere",
            Kind::Plane => "plane",
            Kind::Triangle => "triangle",
        }
    }

    /// Number of input numbers.
    #[must_use]
    pub fn inputs(self) -> usize {
        match self {
            Kind::Sphere => 10,
            Kind::Plane => 12,
            Kind::Triangle => 15,
        }
    }
}

/// A result: `miss`, or up to three values (`t0 [t1]` for spheres, `t` for planes, `t u v`
/// for triangles).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Values {
    /// How many of `v` are used; 0 is a miss.
    pub n: u8,
    /// The values.
    pub v: [f32; 3],
}

impl Values {
    /// A miss.
    pub const MISS: Values = Values { n: 0, v: [0.0; 3] };

    /// The used values.
    #[must_use]
    pub fn as_slice(&self) -> &[f32] {
        &self.v[..self.n as usize]
    }
}

impl fmt::Display for Values {
    /// `miss`, or the values separated by spaces, each the shortest decimal that reads back
    /// to the same f32.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.n == 0 {
            return f.write_str("miss");
        }
        for (i, x) in self.as_slice().iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write_shortest(f, *x)?;
        }
        Ok(())
    }
}

/// Writes `x` as its shortest round-trip decimal (plain notation for moderate magnitudes,
/// scientific otherwise).
pub fn write_shortest(f: &mut impl fmt::Write, x: f32) -> fmt::Result {
    let a = x.abs();
    if x == 0.0 || (1e-4..1e16).contains(&a) || !x.is_finite() {
        write!(f, "{x}")
    } else {
        write!(f, "{x:e}")
    }
}

/// One parsed line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Case {
    /// The primitive.
    pub kind: Kind,
    /// The inputs (the first [`Kind::inputs`] are used).
    pub input: [f32; 15],
    /// The expected result.
    pub expect: Values,
    /// Line number in its file (1-based).
    pub line: u32,
}

impl Default for Case {
    /// A placeholder (a plane case expecting a miss), for filling buffers.
    fn default() -> Self {
        Case {
            kind: Kind::Plane,
            input: [0.0; 15],
            expect: Values::MISS,
            line: 0,
        }
    }
}

impl Case {
    /// Ray origin.
    #[must_use]
    pub fn origin(&self) -> Vec3 {
        Vec3::new(self.input[0], self.input[1], self.input[2])
    }
    /// Ray direction.
    #[must_use]
    pub fn dir(&self) -> Vec3 {
        Vec3::new(self.input[3], self.input[4], self.input[5])
    }
    /// Input vector `k` after the ray (0: centre / point / A, 1: normal / B, 2: C).
    #[must_use]
    pub fn vec(&self, k: usize) -> Vec3 {
        let i = 6 + 3 * k;
        Vec3::new(self.input[i], self.input[i + 1], self.input[i + 2])
    }
    /// The sphere of a sphere case.
    #[must_use]
    pub fn sphere(&self) -> Sphere {
        Sphere::new(self.vec(0), self.input[9])
    }
    /// The plane of a plane case.
    #[must_use]
    pub fn plane(&self) -> Plane {
        Plane::new(self.vec(0), self.vec(1))
    }
    /// The triangle of a triangle case.
    #[must_use]
    pub fn triangle(&self) -> Triangle {
        Triangle::new(self.vec(0), self.vec(1), self.vec(2))
    }
}

/// Why a line could not be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParseError {
    /// The first word is not `sphere`, `plane` or `triangle`.
    UnknownKind,
    /// Wrong number of inputs before `->`.
    InputCount,
    /// A number did not parse.
    Number,
    /// No `->`, or a bad expectation.
    Expectation,
}

/// Parses one line: `None` for blank and comment lines.
#[must_use]
pub fn parse_line(line: &str, number: u32) -> Option<Result<Case, ParseError>> {
    let s = line.trim();
    if s.is_empty() || s.starts_with('#') {
        return None;
    }
    Some(parse_case(s, number))
}

fn parse_case(s: &str, line: u32) -> Result<Case, ParseError> {
    let (lhs, rhs) = s.split_once("->").ok_or(ParseError::Expectation)?;
    let mut words = lhs.split_ascii_whitespace();
    let kind = match words.next() {
        Some("sphere") => Kind::Sphere,
        Some("plane") => Kind::Plane,
        Some("triangle") => Kind::Triangle,
        _ => return Err(ParseError::UnknownKind),
    };
    let mut input = [0f32; 15];
    let mut n = 0;
    for w in words {
        if n == kind.inputs() {
            return Err(ParseError::InputCount);
        }
        input[n] = w.parse().map_err(|_| ParseError::Number)?;
        n += 1;
    }
    if n != kind.inputs() {
        return Err(ParseError::InputCount);
    }
    let rhs = rhs.split('#').next().unwrap_or("").trim();
    let expect = if rhs == "miss" {
        Values::MISS
    } else {
        let mut v = Values::MISS;
        for w in rhs.split_ascii_whitespace() {
            if v.n == 3 {
                return Err(ParseError::Expectation);
            }
            v.v[v.n as usize] = w.parse().map_err(|_| ParseError::Expectation)?;
            v.n += 1;
        }
        let want = match kind {
            Kind::Sphere => v.n == 1 || v.n == 2,
            Kind::Plane => v.n == 1,
            Kind::Triangle => v.n == 3,
        };
        if !want {
            return Err(ParseError::Expectation);
        }
        v
    };
    Ok(Case {
        kind,
        input,
        expect,
        line,
    })
}

/// Iterates over the cases of a file's text: `(line number, result)`.
pub fn cases(text: &str) -> impl Iterator<Item = (u32, Result<Case, ParseError>)> + '_ {
    text.lines().enumerate().filter_map(|(i, l)| {
        let n = i as u32 + 1;
        parse_line(l, n).map(|r| (n, r))
    })
}

/// A formulation, as the checker names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// [`Quadratic`]: spheres.
    Quadratic,
    /// [`QuadraticUnit`]: spheres, unit directions.
    QuadraticUnit,
    /// [`Geometric`]: spheres, unit directions.
    Geometric,
    /// [`Robust`]: spheres.
    Robust,
    /// The focal caches: spheres ([`Focal`], guarded, unit directions), planes
    /// ([`FocalPlane`]) and triangles ([`FocalTriangle`], any direction); per case the eye is
    /// the ray origin.
    Focal,
    /// [`FocalUnguarded`]: spheres, unit directions.
    FocalUnguarded,
    /// The ray–plane test.
    Plane,
    /// [`Cramer`]: triangles (lecture 002).
    Cramer,
    /// [`Moller`]: triangles (Möller–Trumbore, division deferred).
    Moller,
    /// [`Watertight`]: triangles (Woop, Benthin, Wald 2013).
    Watertight,
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Method; 10] = [
        Method::Quadratic,
        Method::QuadraticUnit,
        Method::Geometric,
        Method::Robust,
        Method::Focal,
        Method::FocalUnguarded,
        Method::Plane,
        Method::Cramer,
        Method::Moller,
        Method::Watertight,
    ];

    /// The checker's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::Quadratic => Quadratic::NAME,
            Method::QuadraticUnit => QuadraticUnit::NAME,
            Method::Geometric => Geometric::NAME,
            Method::Robust => Robust::NAME,
            Method::Focal => Focal::NAME,
            Method::FocalUnguarded => FocalUnguarded::NAME,
            Method::Plane => "plane",
            Method::Cramer => Cramer::NAME,
            Method::Moller => Moller::NAME,
            Method::Watertight => Watertight::NAME,
        }
    }

    /// Looks a name up.
    #[must_use]
    pub fn parse(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// True when the method tests this kind of primitive.
    #[must_use]
    pub fn applies(self, kind: Kind) -> bool {
        match kind {
            Kind::Sphere => !matches!(
                self,
                Method::Plane | Method::Cramer | Method::Moller | Method::Watertight
            ),
            Kind::Plane => matches!(self, Method::Plane | Method::Focal),
            Kind::Triangle => matches!(
                self,
                Method::Cramer | Method::Moller | Method::Watertight | Method::Focal
            ),
        }
    }

    /// The crate's recommended general method for a kind (any direction, any origin).
    #[must_use]
    pub fn recommended(kind: Kind) -> Option<Method> {
        match kind {
            Kind::Sphere => Some(Method::Robust),
            Kind::Plane => Some(Method::Plane),
            Kind::Triangle => Some(Method::Watertight),
        }
    }

    /// Whether a case lies inside the method's documented limits (see [`Limit`]).
    #[must_use]
    pub fn limits(self, case: &Case) -> Limit {
        limits::check(self, case)
    }
}

/// Whether a case is inside a method's documented limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// Inside: the result must match.
    Inside,
    /// Outside, with the documented reason.
    Outside(&'static str),
}

mod limits {
    //! The documented limits of each method, as predicates on a case's inputs (computed in
    //! f64). They follow the error bounds in each kernel's documentation.

    use super::{Case, Kind, Limit, Method, T_TOLERANCE};
    use crate::vec3::V3;

    const U: f64 = 1.0 / 16_777_216.0;

    fn sqrt(x: f64) -> f64 {
        libm::sqrt(x)
    }

    /// Inputs `k..k + 3` of a case as an exact `f64` vector.
    fn v(c: &Case, k: usize) -> V3<f64> {
        V3::new(
            c.input[k] as f64,
            c.input[k + 1] as f64,
            c.input[k + 2] as f64,
        )
    }

    pub(super) fn check(m: Method, case: &Case) -> Limit {
        if !m.applies(case.kind) {
            return Limit::Outside("method does not apply to this kind");
        }
        // Bad input must be a miss for every method.
        let all_finite = case.input[..case.kind.inputs()]
            .iter()
            .all(|x| x.is_finite());
        if !all_finite || case.kind != Kind::Sphere {
            return Limit::Inside;
        }
        let o = v(case, 0);
        let d = v(case, 3);
        let ctr = v(case, 6);
        let r = case.input[9] as f64;
        let a = d.dot(d);
        if r.is_nan() || r <= 0.0 || a == 0.0 {
            return Limit::Inside;
        }
        let unit = (a - 1.0).abs() <= 1.0 / 1_048_576.0;
        let needs_unit = matches!(
            m,
            Method::QuadraticUnit | Method::Geometric | Method::Focal | Method::FocalUnguarded
        );
        if needs_unit && !unit {
            return Limit::Outside("needs a unit direction");
        }
        // Geometry in f64: T = C − O, μ = d·T, c² = |T|², l² = perpendicular distance², the
        // rim margin m = |r² − l²| and the roots.
        let t = ctr - o;
        let mu = d.dot(t);
        let c2 = t.dot(t);
        let l2 = (c2 - mu * mu / a).max(0.0);
        let margin = (r * r - l2).abs();
        let disc_signed = mu * mu - a * (c2 - r * r);
        let disc = disc_signed.max(0.0);
        let roots = [(mu - sqrt(disc)) / a, (mu + sqrt(disc)) / a];
        // Smallest root inside (0, inf); infinite for a miss (then only decisions matter).
        let t_small = if disc_signed > 0.0 {
            roots
                .iter()
                .filter(|t| **t > 0.0)
                .fold(f64::INFINITY, |m, t| m.min(*t))
        } else {
            f64::INFINITY
        };
        let c = sqrt(c2);
        let tol = 0.5 * T_TOLERANCE;
        match m {
            Method::Quadratic
            | Method::QuadraticUnit
            | Method::Geometric
            | Method::FocalUnguarded => {
                // The constant term c² − r² (or c² − v²) carries an error of about 16·2^-24·c²:
                // decisions need the rim margin above twice that, and t's error
                // E/(2√(margin)) + 4·2^-24·(|μ| + √disc) must stay within half the tolerance.
                let e = 16.0 * U * c2 * a;
                if margin * a < 2.0 * e {
                    return Limit::Outside("within 32·2^-24·c² of the rim");
                }
                let err_t = (e / (2.0 * sqrt(margin * a)) + 4.0 * U * (mu.abs() + sqrt(disc))) / a;
                if t_small.is_finite() && err_t > tol * t_small {
                    return Limit::Outside("root error of the textbook form above tolerance");
                }
                Limit::Inside
            }
            Method::Robust => {
                // |l| carries an error of about 8·2^-24·|f|; c = f·f − r² about 4·2^-24·|f|².
                let el = 8.0 * U * c;
                let l = sqrt(l2);
                if (l - r).abs() < 2.0 * el {
                    return Limit::Outside("within 16·2^-24·|f| of the rim");
                }
                if !t_small.is_finite() {
                    return Limit::Inside;
                }
                let cc = (c2 - r * r).abs();
                let sq = sqrt(a * disc);
                let q = mu.abs() + sqrt(disc);
                let e_root = a * (l + r) * el / sq.max(f64::MIN_POSITIVE);
                let err0 = 4.0 * U * c2 / cc + e_root / q + 6.0 * U;
                let err1 = e_root / q + 6.0 * U;
                if err0.max(err1) > tol {
                    return Limit::Outside("root error of the robust form above tolerance");
                }
                Limit::Inside
            }
            // Exact decisions and t within 2^-17 for unit directions and any c/r.
            Method::Focal | Method::Plane => Limit::Inside,
            // Triangle methods never reach here (only sphere cases are limited).
            Method::Cramer | Method::Moller | Method::Watertight => Limit::Inside,
        }
    }
}

/// A method's result for one case; `applicable` is false when the method does not test the
/// case's kind.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outcome {
    /// False when the method does not test this kind.
    pub applicable: bool,
    /// The computed values (`n = 0`: a miss).
    pub values: Values,
}

/// Evaluates `cases` with `method` at `lanes` lanes (1, 4, 8 or 16), writing `out[i]` for
/// `cases[i]`. Consecutive cases of the same kind share a packet. Returns false (and writes
/// nothing) for an unsupported lane count or when `out` is shorter than `cases`.
pub fn evaluate(method: Method, lanes: usize, cases: &[Case], out: &mut [Outcome]) -> bool {
    if out.len() < cases.len() {
        return false;
    }
    match lanes {
        1 => run::<f32>(method, cases, out),
        4 => run::<wide::f32x4>(method, cases, out),
        8 => run::<wide::f32x8>(method, cases, out),
        16 => run::<wide::f32x16>(method, cases, out),
        _ => return false,
    }
    true
}

fn run<L: Lane<Scalar = f32>>(method: Method, cases: &[Case], out: &mut [Outcome]) {
    let mut i = 0;
    while i < cases.len() {
        let kind = cases[i].kind;
        let mut j = i;
        while j < cases.len() && j - i < L::LANES && cases[j].kind == kind {
            j += 1;
        }
        batch::<L>(method, &cases[i..j], &mut out[i..j]);
        i = j;
    }
}

/// Evaluates up to `L::LANES` cases of one kind in one packet.
fn batch<L: Lane<Scalar = f32>>(method: Method, cases: &[Case], out: &mut [Outcome]) {
    crate::lane::assert_fits::<L>();
    let kind = cases[0].kind;
    if !method.applies(kind) {
        out.iter_mut().for_each(|o| *o = Outcome::default());
        return;
    }
    let n = cases.len();
    let get = |i: usize| cases[i.min(n - 1)];
    let ray = RayPacket::<L>::new(
        V3::from_fn(|i| get(i).origin()),
        V3::from_fn(|i| get(i).dir()),
        L::from_f32(0.0),
        L::from_f32(f32::INFINITY),
    );
    match kind {
        Kind::Sphere => {
            let spheres = || SpherePacket::<L>::from_spheres(&sphere_list(cases));
            let roots: Roots<L> = match method {
                Method::Quadratic => Quadratic::roots(&ray, &spheres()),
                Method::QuadraticUnit => QuadraticUnit::roots(&ray, &spheres()),
                Method::Geometric => Geometric::roots(&ray, &spheres()),
                Method::Robust => Robust::roots(&ray, &spheres()),
                Method::Focal | Method::FocalUnguarded => {
                    let mut e =
                        [FocalSphere::<f32>::new(Vec3::ZERO, &Sphere::new(Vec3::ZERO, f32::NAN));
                            MAX_LANES];
                    for (k, c) in cases.iter().enumerate() {
                        e[k] = if method == Method::Focal {
                            FocalSphere::new(c.origin(), &c.sphere())
                        } else {
                            FocalSphere::unguarded(c.origin(), &c.sphere())
                        };
                    }
                    let cache = FocalSphere::<L>::gather(&e[..n]);
                    if method == Method::Focal {
                        Focal::roots(&ray, &cache)
                    } else {
                        FocalUnguarded::roots(&ray, &cache)
                    }
                }
                _ => Roots::miss(),
            };
            for (k, o) in out.iter_mut().enumerate() {
                let (t, m) = roots.lane(k);
                *o = Outcome {
                    applicable: true,
                    values: Values {
                        n: m as u8,
                        v: [t[0], t[1], 0.0],
                    },
                };
            }
        }
        Kind::Plane => {
            let h = if method == Method::Focal {
                let num =
                    L::from_f32_fn(|i| FocalPlane::new(get(i).origin(), &get(i).plane()).num());
                plane::focal_lanes(&ray, num, V3::from_fn(|i| get(i).vec(1)))
            } else {
                let planes = PlanePacket::<L> {
                    point: V3::from_fn(|i| get(i).vec(0)),
                    normal: V3::from_fn(|i| get(i).vec(1)),
                };
                plane::intersect_lanes(&ray, &planes)
            };
            for (k, o) in out.iter_mut().enumerate() {
                let values = if h.mask.test(k) {
                    Values {
                        n: 1,
                        v: [h.t.lane(k), 0.0, 0.0],
                    }
                } else {
                    Values::MISS
                };
                *o = Outcome {
                    applicable: true,
                    values,
                };
            }
        }
        Kind::Triangle => {
            let tris = TrianglePacket::<L>::from_fn(|i| get(i).triangle());
            let two_sided = Cull::None;
            let h = match method {
                Method::Cramer => tri_lanes::<Cramer, L>(&ray, &tris),
                Method::Moller => tri_lanes::<Moller, L>(&ray, &tris),
                Method::Watertight => tri_lanes::<Watertight, L>(&ray, &tris),
                _ => {
                    // A per-case cache with the eye at the ray origin.
                    let mut e = [FocalTriangle::never(); MAX_LANES];
                    for (k, c) in cases.iter().enumerate() {
                        e[k] = FocalTriangle::new(c.origin(), &c.triangle());
                    }
                    let cache = FocalTriangle::<L>::gather(&e[..n]);
                    triangle::focal::intersect_lanes(&FocalRays::new(&ray), &cache, two_sided)
                }
            };
            for (k, o) in out.iter_mut().enumerate() {
                let values = if h.mask.test(k) {
                    Values {
                        n: 3,
                        v: [h.t.lane(k), h.u.lane(k), h.v.lane(k)],
                    }
                } else {
                    Values::MISS
                };
                *o = Outcome {
                    applicable: true,
                    values,
                };
            }
        }
    }
}

fn tri_lanes<K: TriangleKernel, L: Lane>(
    ray: &RayPacket<L>,
    tris: &TrianglePacket<L>,
) -> crate::hit::LaneHit<L> {
    K::intersect(ray, &K::prepare(ray), tris, Cull::None).normalized()
}

fn sphere_list(cases: &[Case]) -> [Sphere; MAX_LANES] {
    let mut s = [Sphere::new(Vec3::ZERO, f32::NAN); MAX_LANES];
    for (k, c) in cases.iter().enumerate().take(MAX_LANES) {
        s[k] = c.sphere();
    }
    s
}

/// The verdict on one case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Same hit/miss, values within tolerance.
    Pass,
    /// Different.
    Fail,
    /// Outside the method's limits (or the method does not apply): not compared.
    Skip(&'static str),
}

/// Compares a method's outcome with the case's expectation (see the [module docs](self)).
#[must_use]
pub fn compare(method: Method, case: &Case, got: &Outcome) -> Verdict {
    if let Limit::Outside(why) = method.limits(case) {
        return Verdict::Skip(why);
    }
    if !got.applicable {
        return Verdict::Skip("method does not apply to this kind");
    }
    if matches(case, &got.values) {
        Verdict::Pass
    } else {
        Verdict::Fail
    }
}

/// True when `got` has the expected hit/miss and values within tolerance (ignoring limits).
#[must_use]
pub fn matches(case: &Case, got: &Values) -> bool {
    let (e, g) = (case.expect, *got);
    if e.n != g.n {
        return false;
    }
    for k in 0..e.n as usize {
        let (x, y) = (e.v[k] as f64, g.v[k] as f64);
        let barycentric = case.kind == Kind::Triangle && k > 0;
        let ok = if barycentric {
            (x - y).abs() <= UV_TOLERANCE
        } else {
            (x - y).abs() <= T_TOLERANCE * x.abs()
        };
        if !ok {
            return false;
        }
    }
    true
}

/// FNV-1a (64-bit) over results in order: for each case its applicability, the number of
/// values and the bit pattern of every value. Equal digests mean bit-identical results.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Digest(u64);

impl Default for Digest {
    fn default() -> Self {
        Digest(fnv::FnvHasher::default().finish())
    }
}

impl Digest {
    /// An empty digest.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one outcome.
    pub fn update(&mut self, o: &Outcome) {
        let mut h = fnv::FnvHasher::with_key(self.0);
        h.write(&[o.applicable as u8, o.values.n]);
        for x in o.values.as_slice() {
            h.write(&x.to_bits().to_le_bytes());
        }
        self.0 = h.finish();
    }

    /// The digest value.
    #[must_use]
    pub fn value(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_each_kind() {
        let c = parse_line(
            "sphere 1 0 1  0.40824829 0.81649658 0.40824829  5 5 5 3 -> 4.8989797 9.797959",
            3,
        )
        .unwrap()
        .unwrap();
        assert_eq!((c.kind, c.expect.n, c.line), (Kind::Sphere, 2, 3));
        assert_eq!(parse_line("  # comment", 1), None);
        assert_eq!(
            parse_line("plane 0 0 0 1 0 0 2 0 0 1 0 0 -> 2", 1)
                .unwrap()
                .unwrap()
                .expect
                .v[0],
            2.0
        );
        assert_eq!(
            parse_line("triangle 0 0 0 0 0 1 0 0 1 1 0 1 0 1 1 -> miss", 1)
                .unwrap()
                .unwrap()
                .expect,
            Values::MISS
        );
        assert_eq!(
            parse_line("plane 0 0 -> 1", 1),
            Some(Err(ParseError::InputCount))
        );
        assert_eq!(
            parse_line("cone 0 -> 1", 1),
            Some(Err(ParseError::UnknownKind))
        );
        assert_eq!(
            parse_line("plane 0 0 0 1 0 0 2 0 0 1 0 0 -> 1 2", 1),
            Some(Err(ParseError::Expectation))
        );
        let nan = parse_line("sphere NaN 0 0 1 0 0 inf 0 0 -1 -> miss", 1)
            .unwrap()
            .unwrap();
        assert!(nan.input[0].is_nan() && nan.input[6].is_infinite());
    }
}

/// The lane widths every method is run at.
pub const LANE_WIDTHS: [usize; 4] = [1, 4, 8, 16];

/// Counts of one method over some cases.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Inside the method's limits and matching.
    pub passed: usize,
    /// Inside the method's limits and not matching.
    pub failed: usize,
    /// Outside the method's limits, or of a kind it does not test.
    pub skipped: usize,
}

/// Evaluates `cases` with `method` at `lanes` lanes, compares every outcome with its
/// expectation, and folds the outcomes into `digest` in order. `out` is scratch space of at
/// least `cases.len()` outcomes. The checker's core, shared by the host digests and the
/// firmware; returns `None` for an unsupported width or too small a buffer.
pub fn check(
    method: Method,
    lanes: usize,
    cases: &[Case],
    out: &mut [Outcome],
    digest: &mut Digest,
) -> Option<Tally> {
    if !evaluate(method, lanes, cases, out) {
        return None;
    }
    let mut t = Tally::default();
    for (c, o) in cases.iter().zip(out.iter()) {
        digest.update(o);
        match compare(method, c, o) {
            Verdict::Pass => t.passed += 1,
            Verdict::Fail => t.failed += 1,
            Verdict::Skip(_) => t.skipped += 1,
        }
    }
    Some(t)
}

/// Parses a file's text into `buf`; returns the number of cases, or the first bad line.
pub fn load(text: &str, buf: &mut [Case]) -> Result<usize, (u32, ParseError)> {
    let mut n = 0;
    for (line, r) in cases(text) {
        let c = r.map_err(|e| (line, e))?;
        let slot = buf.get_mut(n).ok_or((line, ParseError::InputCount))?;
        *slot = c;
        n += 1;
    }
    Ok(n)
}
