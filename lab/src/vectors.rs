//! Test vectors: parser, batched runner, per-method limits, comparison and digest.
//!
//! One implementation, no allocation, shared by the checker (`examples/check.rs`), the host
//! tests and the firmware under `targets/`. The files under `tests/vectors/` hold one case a
//! line (`#` starts a comment):
//!
//! ```text
//! sphere   ox oy oz  dx dy dz  cx cy cz  r                -> miss | t0 [t1]      [~ k0 [k1]]
//! plane    ox oy oz  dx dy dz  px py pz  nx ny nz         -> miss | t            [~ kt]
//! triangle ox oy oz  dx dy dz  ax ay az  bx by bz  cx cy cz -> miss | t u v      [~ kt ku kv]
//! ```
//!
//! The ray interval is `(0, +inf)`; sphere expectations list every root in it, ascending. A
//! hit may carry its *conditioning* after `~`, one number per expected value: for each `t` the
//! relative change that a 2-ulp move of the inputs can cause (first order), for `u` and `v`
//! the absolute change (see `tests/vectors/gen/README.md`). Lines without it are read as before.
//!
//! [`evaluate`] runs cases through one [`Method`] at one lane width, batching consecutive cases
//! of a kind into the lanes (so lane independence is tested too). [`compare`] checks an outcome
//! against the expectation: the same hit/miss, `t` within a relative
//! `max(T_TOLERANCE, COND_FACTOR·k)` and barycentrics within an absolute
//! `max(UV_TOLERANCE, COND_FACTOR·k)`, `k` the case's conditioning (0 when absent; see
//! [`tolerance`]). A case outside a method's documented limits ([`Method::limits`]) is reported
//! as such, not compared. [`accuracy`] measures each method's errors per class of input.

use core::fmt;
use core::hash::Hasher as _;

use glam::Vec3;

use crate::registry::{Kernel, Visitor};
use raylane::Cull;
use raylane::kernel::LaneHit;
use raylane::lane::{Lane, MAX_LANES, Mask};
use raylane::plane::{self, FocalPlane, Plane, PlanePacket};
use raylane::ray::RayPacket;
use raylane::sphere::focal::FocalKernel;
use raylane::sphere::{FocalSphere, Roots, Sphere, SphereKernel, SpherePacket};
use raylane::triangle::focal::FocalRays;
use raylane::triangle::{self, FocalTriangle, Triangle, TriangleKernel, TrianglePacket};
use raylane::vec3::V3;

/// Relative tolerance on `t`.
pub const T_TOLERANCE: f64 = 2e-5;
/// Absolute tolerance on the barycentrics `u`, `v`.
pub const UV_TOLERANCE: f64 = 2e-5;
/// How many times a case's recorded conditioning (the change a 2-ulp move of the inputs can
/// cause) a result may be off, where that exceeds [`T_TOLERANCE`] / [`UV_TOLERANCE`]: the
/// per-case tolerance of ill-conditioned cases (see [`tolerance`]). Measured ([`accuracy`]):
/// `robust`, sphere `focal`, `plane` and `watertight` stay below 1× on every class, `cramer`
/// and `moller` too except for `t` on needles (a documented limit).
pub const COND_FACTOR: f64 = 4.0;

/// The primitive a case tests: `sphere` lines have 10 inputs, `plane` lines 12, `triangle`
/// lines 15 ([`Kind::inputs`]).
pub use crate::registry::Prim as Kind;

impl Kind {
    /// Number of input numbers of a vector line.
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
    /// The conditioning of each expected value (`n = 0` when the line gives none): relative
    /// for `t`, absolute for `u`, `v` (see the [module docs](self)).
    pub cond: Values,
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
            cond: Values::MISS,
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
    /// A bad conditioning after `~` (not one nonnegative number per expected value).
    Conditioning,
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
    let rhs = rhs.split('#').next().unwrap_or("");
    let (rhs, cond_text) = match rhs.split_once('~') {
        Some((r, k)) => (r.trim(), Some(k)),
        None => (rhs.trim(), None),
    };
    let expect = if rhs == "miss" {
        Values::MISS
    } else {
        let v = numbers(rhs).ok_or(ParseError::Expectation)?;
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
    let cond = match cond_text {
        None => Values::MISS,
        Some(k) => {
            let c = numbers(k).ok_or(ParseError::Conditioning)?;
            if c.n != expect.n || c.n == 0 || c.as_slice().iter().any(|x| x.is_nan() || *x < 0.0) {
                return Err(ParseError::Conditioning);
            }
            c
        }
    };
    Ok(Case {
        kind,
        input,
        expect,
        cond,
        line,
    })
}

/// Up to three numbers separated by spaces; `None` for more, or for a bad number.
fn numbers(text: &str) -> Option<Values> {
    let mut v = Values::MISS;
    for w in text.split_ascii_whitespace() {
        if v.n == 3 {
            return None;
        }
        v.v[v.n as usize] = w.parse().ok()?;
        v.n += 1;
    }
    Some(v)
}

/// Iterates over the cases of a file's text: `(line number, result)`.
pub fn cases(text: &str) -> impl Iterator<Item = (u32, Result<Case, ParseError>)> + '_ {
    text.lines().enumerate().filter_map(|(i, l)| {
        let n = i as u32 + 1;
        parse_line(l, n).map(|r| (n, r))
    })
}

/// A formulation, as the checker names it: the [registry](crate::registry)'s methods, each
/// running its kernel for the primitive of a case.
pub use crate::registry::Method;

impl Method {
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

    /// True when the method takes this case's input at all: it tests the case's kind, and the
    /// direction is unit where the method needs one (the accuracy measurement's domain; the
    /// other limits only bound the error).
    #[must_use]
    pub fn admits(self, case: &Case) -> bool {
        self.applies(case.kind) && limits::unit_direction(self, case)
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
    use crate::registry::ErrorModel;
    use raylane::vec3::V3;

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

    /// The limit of the methods that take unit directions only.
    pub(super) const NEEDS_UNIT: &str = "needs a unit direction";

    /// False for a sphere case whose direction is not unit (`||d|² − 1| > 2^-20`) given to a
    /// method that needs one.
    pub(super) fn unit_direction(m: Method, case: &Case) -> bool {
        let needs_unit = m.kernel(case.kind).is_some_and(|k| k.needs_unit());
        let d = v(case, 3);
        case.kind != Kind::Sphere || !needs_unit || (d.dot(d) - 1.0).abs() <= 1.0 / 1_048_576.0
    }

    /// The triangle methods' limits on the values of a hit: measured error models
    /// (`tests/vectors/triangle_*.txt`) against the case's tolerance ([`super::tolerance`]).
    fn triangle(model: ErrorModel, case: &Case) -> Limit {
        let (o, d, a, b, c) = (v(case, 0), v(case, 3), v(case, 6), v(case, 9), v(case, 12));
        let n = (b - a).cross(c - a);
        let area2 = sqrt(n.dot(n));
        // Misses and degenerate triangles: every method's decisions are compared.
        if case.expect.n == 0 || area2 == 0.0 || !area2.is_finite() {
            return Limit::Inside;
        }
        let longest = [b - a, c - b, a - c]
            .iter()
            .fold(0.0f64, |x, e| x.max(e.dot(*e)));
        // Aspect ratio (longest edge over its height) = longest² / (2·area).
        let aspect = longest / area2;
        let tol_t = super::tolerance(case, 0);
        match model {
            ErrorModel::Needle => {
                // t is a triple product over the determinant, each rounded at the scale of
                // |e1|·|e2|·|s|: on needles the relative error of t grows with the aspect
                // ratio while t itself stays well conditioned. Measured (triangle_needle.txt):
                // at most 1.92·2^-24·aspect (Cramer, Möller; Plücker and Kensler–Shirley form
                // t the same way and pass every case inside this bound).
                if 2.0 * U * aspect > tol_t {
                    return Limit::Outside("needle: t error up to 2·2^-24·aspect ratio");
                }
                Limit::Inside
            }
            ErrorModel::Record => {
                // A record computed once per triangle (plane, lines, transform) carries
                // coordinates of size M (the largest |coordinate| of the origin and the
                // vertices) into every test: the plane offset cancels at the scale of M against
                // the distance `dist` from the origin to the plane, and the lines at the scale
                // of M against the smallest altitude h. Measured on every triangle file (the
                // largest ratio over the four methods): relative t error at most
                // 4.03·2^-24·(M/dist)·(1 + aspect/8), u, v error at most
                // 2.1·2^-24·M/(h·cos θ)·max(1, aspect/64).
                let m = [o, a, b, c].iter().fold(0.0f64, |x, p| {
                    x.max(p.x.abs()).max(p.y.abs()).max(p.z.abs())
                });
                let h = area2 / sqrt(longest);
                let cos = n.dot(d).abs() / (area2 * sqrt(d.dot(d)));
                let dist = n.dot(a - o).abs() / area2;
                if 5.0 * U * m / dist * (1.0 + aspect / 8.0) > tol_t {
                    return Limit::Outside(
                        "precomputed record: t error up to 4.03·2^-24·(M/dist)·(1 + aspect/8)",
                    );
                }
                let model = U * m / (h * cos);
                let tol_uv = super::tolerance(case, 1).min(super::tolerance(case, 2));
                if 3.0 * model * (aspect / 64.0).max(1.0) > tol_uv {
                    return Limit::Outside(
                        "precomputed record: u, v error up to 2·2^-24·M/(h·cos θ)·max(1, aspect/64)",
                    );
                }
                Limit::Inside
            }
            _ => Limit::Inside,
        }
    }

    pub(super) fn check(m: Method, case: &Case) -> Limit {
        let Some(kernel) = m.kernel(case.kind) else {
            return Limit::Outside("method does not apply to this kind");
        };
        let model = kernel.error_model();
        // Bad input must be a miss for every method.
        let all_finite = case.input[..case.kind.inputs()]
            .iter()
            .all(|x| x.is_finite());
        if !all_finite || case.kind == Kind::Plane {
            return Limit::Inside;
        }
        if case.kind == Kind::Triangle {
            return triangle(model, case);
        }
        let o = v(case, 0);
        let d = v(case, 3);
        let ctr = v(case, 6);
        let r = case.input[9] as f64;
        let a = d.dot(d);
        if r.is_nan() || r <= 0.0 || a == 0.0 {
            return Limit::Inside;
        }
        if !unit_direction(m, case) {
            return Limit::Outside(NEEDS_UNIT);
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
        match model {
            ErrorModel::Textbook => {
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
            ErrorModel::RobustSphere => {
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
            // Exact decisions and t within 2^-17 for unit directions and any c/r (focal); the
            // triangle models never reach here (only sphere cases are limited below).
            ErrorModel::Exact | ErrorModel::Needle | ErrorModel::Record => Limit::Inside,
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
    if ![1, 4, 8, 16].contains(&lanes) {
        return false;
    }
    // At the run-time SIMD level, in its lanes (raylane::simd::with_lanes): the digests of a
    // default x86-64 build then cover every level (RAYLANE_SIMD).
    struct Run<'a>(Method, &'a [Case], &'a mut [Outcome]);
    impl raylane::simd::Packets for Run<'_> {
        type Output = ();
        #[cfg_attr(target_arch = "x86_64", inline(always))]
        fn run<L: Lane<Scalar = f32>>(self) {
            run::<L>(self.0, self.1, self.2)
        }
    }
    raylane::simd::with_lanes(lanes, Run(method, cases, out));
    true
}

#[cfg_attr(target_arch = "x86_64", inline(always))]
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

/// Evaluates up to `L::LANES` cases of one kind in one packet: the method's kernel for the
/// kind, through the [registry](crate::registry).
#[cfg_attr(target_arch = "x86_64", inline(always))]
fn batch<L: Lane<Scalar = f32>>(method: Method, cases: &[Case], out: &mut [Outcome]) {
    raylane::lane::assert_fits::<L>();
    match method.kernel(cases[0].kind) {
        Some(k) => k.visit(Batch::<L>::new(cases, out)),
        None => out.iter_mut().for_each(|o| *o = Outcome::default()),
    }
}

/// One packet of cases (one ray per case, interval `(0, +inf)`) and where their outcomes go:
/// the [`Visitor`] that runs any kernel over it.
struct Batch<'a, L: Lane> {
    cases: &'a [Case],
    out: &'a mut [Outcome],
    ray: RayPacket<L>,
}

impl<'a, L: Lane<Scalar = f32>> Batch<'a, L> {
    fn new(cases: &'a [Case], out: &'a mut [Outcome]) -> Self {
        let ray = RayPacket::<L>::new(
            V3::from_fn(|i| case_lane(cases, i).origin()),
            V3::from_fn(|i| case_lane(cases, i).dir()),
            L::from_f32(0.0),
            L::from_f32(f32::INFINITY),
        );
        Batch { cases, out, ray }
    }

    /// The case of lane `i` (the last case in the lanes past the cases).
    fn get(&self, i: usize) -> Case {
        case_lane(self.cases, i)
    }

    /// Writes sphere roots.
    fn roots(self, roots: Roots<L>) {
        for (k, o) in self.out.iter_mut().enumerate() {
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

    /// Writes plane hits (`t`) or, with `uv`, triangle hits (`t u v`).
    fn hits(self, h: LaneHit<L>, uv: bool) {
        for (k, o) in self.out.iter_mut().enumerate() {
            let values = match (h.mask.test(k), uv) {
                (false, _) => Values::MISS,
                (true, false) => Values {
                    n: 1,
                    v: [h.t.lane(k), 0.0, 0.0],
                },
                (true, true) => Values {
                    n: 3,
                    v: [h.t.lane(k), h.u.lane(k), h.v.lane(k)],
                },
            };
            *o = Outcome {
                applicable: true,
                values,
            };
        }
    }
}

/// Lane `i`'s case: the last one in the lanes past `cases`.
fn case_lane(cases: &[Case], i: usize) -> Case {
    cases[i.min(cases.len() - 1)]
}

// Each family out of line on the boards: their caches (up to 16 lanes of focal entries) then
// never share one stack frame (the Cortex-M0 has 16 KB of RAM). Inline on x86-64, so that
// they run at the level `evaluate` entered (raylane::simd).
impl<L: Lane<Scalar = f32>> Visitor for Batch<'_, L> {
    type Output = ();

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline(never))]
    fn sphere<K: SphereKernel>(self, _: Kernel) {
        let spheres = SpherePacket::<L>::from_spheres(&sphere_list(self.cases));
        let roots = K::roots(&self.ray, &spheres);
        self.roots(roots);
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline(never))]
    fn focal_sphere<K: FocalKernel>(self, _: Kernel, guarded: bool) {
        // A per-case cache with the eye at the ray origin.
        let mut e =
            [FocalSphere::<f32>::new(Vec3::ZERO, &Sphere::new(Vec3::ZERO, f32::NAN)); MAX_LANES];
        for (slot, c) in e.iter_mut().zip(self.cases) {
            *slot = if guarded {
                FocalSphere::new(c.origin(), &c.sphere())
            } else {
                FocalSphere::unguarded(c.origin(), &c.sphere())
            };
        }
        let cache = FocalSphere::<L>::gather(&e[..self.cases.len().min(MAX_LANES)]);
        let roots = K::roots(&self.ray, &cache);
        self.roots(roots);
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline(never))]
    fn plane(self, _: Kernel) {
        let planes = PlanePacket::<L> {
            point: V3::from_fn(|i| self.get(i).vec(0)),
            normal: V3::from_fn(|i| self.get(i).vec(1)),
        };
        let h = plane::intersect_lanes(&self.ray, &planes);
        self.hits(h, false);
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline(never))]
    fn focal_plane(self, _: Kernel) {
        let num =
            L::from_f32_fn(|i| FocalPlane::new(self.get(i).origin(), &self.get(i).plane()).num());
        let h = plane::focal_lanes(&self.ray, num, V3::from_fn(|i| self.get(i).vec(1)));
        self.hits(h, false);
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline(never))]
    fn triangle<K: TriangleKernel>(self, _: Kernel) {
        let tris = TrianglePacket::<L>::from_fn(|i| self.get(i).triangle());
        let h = K::intersect(&self.ray, &K::prepare(&self.ray), &tris, Cull::None).normalized();
        self.hits(h, true);
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline(never))]
    fn focal_triangle(self, _: Kernel) {
        // A per-case cache with the eye at the ray origin.
        let mut e = [FocalTriangle::never(); MAX_LANES];
        for (slot, c) in e.iter_mut().zip(self.cases) {
            *slot = FocalTriangle::new(c.origin(), &c.triangle());
        }
        let cache = FocalTriangle::<L>::gather(&e[..self.cases.len().min(MAX_LANES)]);
        let h = triangle::focal::intersect_lanes(&FocalRays::new(&self.ray), &cache, Cull::None);
        self.hits(h, true);
    }
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

/// The tolerance on expected value `k` of a case: relative for a `t`,
/// `max(T_TOLERANCE, COND_FACTOR·cond)`, absolute for a barycentric,
/// `max(UV_TOLERANCE, COND_FACTOR·cond)`; `cond` is the case's recorded conditioning of that
/// value (0 when the line gives none).
#[must_use]
pub fn tolerance(case: &Case, k: usize) -> f64 {
    let cond = if (k as u8) < case.cond.n {
        case.cond.v[k] as f64
    } else {
        0.0
    };
    let floor = if is_barycentric(case.kind, k) {
        UV_TOLERANCE
    } else {
        T_TOLERANCE
    };
    floor.max(COND_FACTOR * cond)
}

/// True when value `k` of a result of this kind is a barycentric (`u` or `v`), not a `t`.
fn is_barycentric(kind: Kind, k: usize) -> bool {
    kind == Kind::Triangle && k > 0
}

/// The error of value `k` of `got` against the expectation: relative for a `t`, absolute for a
/// barycentric.
fn error(case: &Case, got: &Values, k: usize) -> f64 {
    let (x, y) = (case.expect.v[k] as f64, got.v[k] as f64);
    if is_barycentric(case.kind, k) {
        (x - y).abs()
    } else {
        (x - y).abs() / x.abs()
    }
}

/// True when `got` has the expected hit/miss and values within [`tolerance`] (ignoring
/// limits).
#[must_use]
pub fn matches(case: &Case, got: &Values) -> bool {
    case.expect.n == got.n && (0..got.n as usize).all(|k| error(case, got, k) <= tolerance(case, k))
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
        // The conditioning after `~`: one number per expected value, on hits only.
        let k = parse_line(
            "triangle 0 0 0 0 0 1 0 0 1 1 0 1 0 1 1 -> 1 0 0.5 ~ 1e-7 0 3e-6",
            1,
        )
        .unwrap()
        .unwrap();
        assert_eq!((k.cond.n, k.cond.v), (3, [1e-7, 0.0, 3e-6]));
        assert_eq!(tolerance(&k, 0), T_TOLERANCE);
        let k = parse_line("sphere 0 0 0 1 0 0 5 0 0 1 -> 4 6 ~ 1e-3 1e-6 # note", 1)
            .unwrap()
            .unwrap();
        assert_eq!(tolerance(&k, 0), COND_FACTOR * 1e-3f32 as f64);
        assert_eq!(tolerance(&k, 1), T_TOLERANCE);
        for bad in [
            "plane 0 0 0 1 0 0 2 0 0 1 0 0 -> 2 ~ 1e-7 1e-7",
            "plane 0 0 0 1 0 0 2 0 0 1 0 0 -> miss ~ 1e-7",
            "plane 0 0 0 1 0 0 2 0 0 1 0 0 -> 2 ~ -1",
            "plane 0 0 0 1 0 0 2 0 0 1 0 0 -> 2 ~",
        ] {
            assert_eq!(
                parse_line(bad, 1),
                Some(Err(ParseError::Conditioning)),
                "{bad}"
            );
        }
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

pub mod accuracy {
    //! Every method's accuracy against the exact answers, per class of input.
    //!
    //! Each class is one generated vector file (`tests/vectors/<file>.txt`, see [`CLASSES`]).
    //! [`measure`] runs a method over a class's cases and keeps, over the hits where the
    //! method agrees with the exact hit/miss (and number of sphere roots): the largest relative
    //! `t` error and the largest absolute `u`, `v` error against the exact answer (rounded to
    //! f32: a method that returns it has error 0), and the same errors divided by each case's
    //! recorded conditioning (what a 2-ulp move of the inputs can change; 1 means "as wrong as
    //! the inputs' last two bits allow"). Cases whose hit/miss differs are counted, not measured.
    //! [`write_report`] prints the Markdown tables of the README; `tests/suite/kernels/accuracy_pinned.rs`
    //! pins them and `cargo run --release --features vectors --example accuracy` prints them.

    use core::fmt;

    use super::{Case, Kind, Method, Outcome, error, evaluate, is_barycentric};

    /// One class of input: a generated vector file.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct Class {
        /// The primitive.
        pub kind: Kind,
        /// The name in the tables.
        pub name: &'static str,
        /// The file's stem under `tests/vectors/`.
        pub file: &'static str,
    }

    const fn class(kind: Kind, name: &'static str, file: &'static str) -> Class {
        Class { kind, name, file }
    }

    /// Every class, per kind in table order.
    pub const CLASSES: [Class; 15] = [
        class(Kind::Triangle, "random", "triangle_random"),
        class(Kind::Triangle, "far", "triangle_far"),
        class(Kind::Triangle, "needle", "triangle_needle"),
        class(Kind::Triangle, "grazing", "triangle_grazing"),
        class(Kind::Triangle, "offset", "triangle_offset"),
        class(Kind::Triangle, "grid", "triangle_grid"),
        class(Kind::Sphere, "random", "sphere_random"),
        class(Kind::Sphere, "far", "sphere_far"),
        class(Kind::Sphere, "grazing", "sphere_grazing"),
        class(Kind::Sphere, "offset", "sphere_offset"),
        class(Kind::Sphere, "tiny r", "sphere_tiny"),
        class(Kind::Sphere, "huge r", "sphere_huge"),
        class(Kind::Plane, "random", "plane_random"),
        class(Kind::Plane, "grazing", "plane_grazing"),
        class(Kind::Plane, "offset", "plane_offset"),
    ];

    /// The methods of a kind, in table order ([`Method::ALL`]'s).
    pub fn methods(kind: Kind) -> impl Iterator<Item = Method> {
        Method::ALL.into_iter().filter(move |m| m.applies(kind))
    }

    /// One method's errors over some cases.
    #[derive(Clone, Copy, Debug, Default, PartialEq)]
    pub struct Errors {
        /// Cases the method admits ([`Method::admits`]).
        pub cases: u32,
        /// Of those, hits where the method agrees with the exact hit/miss: the measured ones.
        pub hits: u32,
        /// Cases where the method's hit/miss (or number of sphere roots) differs from the
        /// exact one.
        pub wrong: u32,
        /// Largest relative error of a `t`.
        pub t: f64,
        /// Largest absolute error of a `u` or `v` (triangles).
        pub uv: f64,
        /// Largest `t` error over that value's conditioning.
        pub t_cond: f64,
        /// Largest `u`, `v` error over that value's conditioning.
        pub uv_cond: f64,
    }

    impl Errors {
        /// Adds one case and the method's outcome for it.
        pub fn add(&mut self, method: Method, case: &Case, got: &Outcome) {
            if !got.applicable || !method.admits(case) {
                return;
            }
            self.cases += 1;
            let (e, g) = (&case.expect, &got.values);
            if e.n != g.n {
                self.wrong += 1;
                return;
            }
            if e.n == 0 {
                return;
            }
            self.hits += 1;
            for k in 0..e.n as usize {
                let err = error(case, g, k);
                // NaN or infinite errors stay visible as infinite maxima.
                let err = if err.is_nan() { f64::INFINITY } else { err };
                let cond = if (k as u8) < case.cond.n {
                    case.cond.v[k] as f64
                } else {
                    f64::NAN
                };
                let ratio = match (err == 0.0, cond > 0.0) {
                    (true, _) => 0.0,
                    (false, true) => err / cond,
                    (false, false) if cond == 0.0 => f64::INFINITY,
                    _ => 0.0, // no conditioning recorded
                };
                let (max, max_cond) = if is_barycentric(case.kind, k) {
                    (&mut self.uv, &mut self.uv_cond)
                } else {
                    (&mut self.t, &mut self.t_cond)
                };
                *max = max.max(err);
                *max_cond = max_cond.max(ratio);
            }
        }
    }

    /// Runs `method` over `cases` at `lanes` lanes (`out`: scratch of at least `cases.len()`)
    /// and measures its errors; `None` for an unsupported width or too short a buffer.
    pub fn measure(
        method: Method,
        lanes: usize,
        cases: &[Case],
        out: &mut [Outcome],
    ) -> Option<Errors> {
        if !evaluate(method, lanes, cases, out) {
            return None;
        }
        let mut e = Errors::default();
        for (c, o) in cases.iter().zip(out.iter()) {
            e.add(method, c, o);
        }
        Some(e)
    }

    /// Parses a class file's `text` into `cases` and measures `method` over it at `lanes` lanes
    /// (`out`: scratch); `None` for a bad line, too small a buffer or an unsupported width.
    pub fn measure_text(
        method: Method,
        lanes: usize,
        text: &str,
        cases: &mut [Case],
        out: &mut [Outcome],
    ) -> Option<Errors> {
        let n = super::load(text, cases).ok()?;
        measure(method, lanes, &cases[..n], out)
    }

    /// Writes an error with two significant digits (`1.2e-7`), `0` or `inf`.
    fn write_error(f: &mut impl fmt::Write, x: f64) -> fmt::Result {
        if x == 0.0 {
            f.write_str("0")
        } else if x.is_finite() {
            write!(f, "{x:.1e}")
        } else {
            f.write_str("inf")
        }
    }

    /// Writes an error over conditioning: two decimals below 10, whole numbers above.
    fn write_ratio(f: &mut impl fmt::Write, x: f64) -> fmt::Result {
        if !x.is_finite() {
            f.write_str("inf")
        } else if x < 10.0 {
            write!(f, "{x:.2}")
        } else {
            write!(f, "{x:.0}")
        }
    }

    /// Writes one figure of a cell (after a space): `–` when nothing was measured.
    fn write_cell(f: &mut impl fmt::Write, e: &Errors, x: f64, ratio: bool) -> fmt::Result {
        f.write_str(" ")?;
        if e.hits == 0 {
            f.write_str("–")
        } else if ratio {
            write_ratio(f, x)
        } else {
            write_error(f, x)
        }
    }

    /// Writes the report: for each kind, a table of the largest errors (rows: classes;
    /// columns: methods, `t` and for triangles `u,v`) and one of the errors over conditioning.
    /// `errors(method, class)` gives the measured figures.
    pub fn write_report(
        f: &mut impl fmt::Write,
        mut errors: impl FnMut(Method, &Class) -> Errors,
    ) -> fmt::Result {
        for kind in [Kind::Triangle, Kind::Sphere, Kind::Plane] {
            let classes = || CLASSES.iter().filter(move |c| c.kind == kind);
            let mut table = [[Errors::default(); Method::ALL.len()]; CLASSES.len()];
            for (i, c) in classes().enumerate() {
                for (j, m) in methods(kind).enumerate() {
                    table[i][j] = errors(m, c);
                }
            }
            let n_methods = methods(kind).count();
            let uv = kind == Kind::Triangle;
            for ratio in [false, true] {
                let what = if ratio {
                    "error ÷ conditioning"
                } else {
                    "largest error"
                };
                write!(f, "\n| {}: {what} |", kind.name())?;
                for m in methods(kind) {
                    let m = m.name();
                    if uv {
                        write!(f, " {m} t | {m} u,v |")?;
                    } else {
                        write!(f, " {m} t |")?;
                    }
                }
                f.write_str("\n| --- |")?;
                for _ in methods(kind) {
                    f.write_str(if uv { " ---: | ---: |" } else { " ---: |" })?;
                }
                f.write_str("\n")?;
                for (i, c) in classes().enumerate() {
                    // Every case of the class (the unit-direction methods admit fewer).
                    let n = table[i][..n_methods].iter().map(|e| e.cases).max();
                    write!(f, "| {} ({}) |", c.name, n.unwrap_or(0))?;
                    for e in &table[i][..n_methods] {
                        let (t, u) = if ratio {
                            (e.t_cond, e.uv_cond)
                        } else {
                            (e.t, e.uv)
                        };
                        write_cell(f, e, t, ratio)?;
                        if e.wrong > 0 {
                            write!(f, " ({} wrong)", e.wrong)?;
                        }
                        f.write_str(" |")?;
                        if uv {
                            write_cell(f, e, u, ratio)?;
                            f.write_str(" |")?;
                        }
                    }
                    f.write_str("\n")?;
                }
            }
        }
        Ok(())
    }
}
