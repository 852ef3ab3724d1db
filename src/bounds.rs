//! Bounding spheres: computed without allocation, and a culling test that never loses a hit.
//!
//! Lecture 002 ("Bounding sphere"): a ray that misses a sphere containing an object cannot hit
//! the object, so one sphere test can skip all of a mesh's triangles.
//!
//! **The sphere** ([`ritter`], [`ritter_indexed`]): Ritter's method (*Graphics Gems*, 1990) —
//! from any point find the farthest point `y`, from `y` the farthest `z`, start with the sphere
//! on the diameter `yz`, and grow it over one more pass to include each point left outside —
//! computed in `f64`, and compared with the sphere about the bounding box's centre; the smaller
//! is kept. The centre is rounded to f32 and the radius is the largest distance from that
//! centre, rounded up: every point is inside, exactly. **Tightness:** never more than `√3`
//! times the minimal radius (the box-centred candidate guarantees it); measured against the
//! exact minimal sphere (Welzl) in `tests/triangles.rs`, Ritter's sphere is typically within
//! a few per cent on meshes and point clouds (the test prints the figures).
//!
//! **The culling test** ([`Bound::may_hit`] for any ray, [`Bound::focal`] for rays from one
//! eye) must never reject a ray that a triangle kernel reports as a hit:
//!
//! * a reported hit lies on the ray's line within `η·(|C − o| + r)` of the mesh (`η = 2^-16`):
//!   the watertight and focal kernels decide exactly for vertices perturbed by at most a few
//!   `2^-24·|A − o|`; Möller and Cramer round more, but far less than `2^-16` for every ray
//!   that is not nearly parallel to a sliver triangle. So the test uses the padded radius
//!   `ρ = r + η·(|C − o| + r)`;
//! * the test is on the *line*, not the interval: a hit anywhere along the ray implies the
//!   line passes within `ρ` of the centre, so no interval bookkeeping can lose it;
//! * the line's distance is computed in f32 with a rigorous error bound. With `f = C − o`,
//!   `l = f − (f·d/d·d)·d` is within `11·2^-24·|f|` of the exact perpendicular, so the test
//!   `|l|² ≤ R2 + κ·|f|²` with `R2 ≥ (1 + μ)(1 + η)²r²` and `κ ≥ (1 + 1/μ)(η + 11·2^-24)²`
//!   (inflated for the rounding of the compare itself) accepts every line that passes within
//!   `ρ`, for any `μ > 0`; both `μ = 2^-10` and `μ = 2^-4` are tested and a lane is rejected
//!   when either rejects it. A NaN anywhere accepts (the compares are `!(|l|² > …)`).
//!
//! Cost per ray and mesh ([`Bound::may_hit`]):
//! `ops bound/per mesh: 17 mul, 16 add, 1 div, 4 cmp`; with a focal cache ([`Bound::focal`])
//! the [`FocalSphere`] test: 4 mul, 2 add, 1 cmp on a miss.
//!
//! **Limits.** The bound is a test only for directions with `d·d` within `2^-100…2^100`
//! (`|d|` within `2^-50…2^50`), where `d·d` neither underflows nor overflows; rays outside
//! that range are never culled (two compares). An invalid bound culls nothing, both here and
//! as a focal entry ([`Bound::focal`]). The pad grows with the distance to the mesh: the effective
//! radius is about 0.1 % larger than `r` up to `|C − o| ≈ 60 r`, 3 % at `1000 r`, 22 % at
//! `10⁴ r`.

use glam::Vec3;

use crate::lane::Lane;
use crate::ray::RayPacket;
use crate::sphere::{FocalSphere, Sphere};
use crate::vec3::V3;

/// Unit roundoff of f32.
const U: f64 = 1.0 / 16_777_216.0;
/// How far from a mesh a reported hit may lie, relative to `|C − o| + r`.
pub const ETA: f64 = 1.0 / 65_536.0;
/// The splits between the radius and the distance terms of the padded square (one suits
/// meshes near the origin, the other far ones; the smaller bound is used).
const MU: [f64; 2] = [1.0 / 1024.0, 1.0 / 16.0];

/// The range of `d·d` where [`Bound::may_hit`] culls (`2^-100…2^100`).
const DD_LO: f32 = f32::from_bits((127 - 100) << 23);
const DD_HI: f32 = f32::from_bits((127 + 100) << 23);

/// Rounds toward +inf.
fn up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x { y.next_up() } else { y }
}

fn wide(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// Ritter's sphere (see the [module docs](self)) of the finite points of `points`, or `None`
/// when there is none or when the enclosing radius exceeds `f32::MAX` (points spread over
/// more than f32's range, e.g. `±f32::MAX`): the result is always a valid sphere.
#[must_use]
pub fn ritter(points: &[Vec3]) -> Option<Sphere> {
    bounding(|| points.iter().copied())
}

/// Ritter's sphere of the vertices referenced by `indices` (out-of-range indices and
/// non-finite positions are skipped), or `None` when there is none or its radius would exceed
/// `f32::MAX` (as [`ritter`]).
#[must_use]
pub fn ritter_indexed(positions: &[Vec3], indices: &[[u32; 3]]) -> Option<Sphere> {
    bounding(|| {
        indices
            .iter()
            .filter(|t| t.iter().all(|&i| (i as usize) < positions.len()))
            .flat_map(|t| t.iter().filter_map(|&i| positions.get(i as usize).copied()))
    })
}

fn bounding<I: Iterator<Item = Vec3>>(points: impl Fn() -> I) -> Option<Sphere> {
    let pts = || points().filter(|p| p.is_finite()).map(wide);
    let first = pts().next()?;
    let farthest = |from: [f64; 3]| {
        pts().fold((from, 0.0), |(q, d), p| {
            let e = dist2(p, from);
            if e > d { (p, e) } else { (q, d) }
        })
    };
    // 1. Ritter: the diameter between two far points, then grow over the rest.
    let (y, _) = farthest(first);
    let (z, d) = farthest(y);
    let mut c = [
        (y[0] + z[0]) / 2.0,
        (y[1] + z[1]) / 2.0,
        (y[2] + z[2]) / 2.0,
    ];
    let mut r = libm::sqrt(d) / 2.0;
    for p in pts() {
        let e = libm::sqrt(dist2(p, c));
        if e > r {
            let grow = (e - r) / 2.0;
            for k in 0..3 {
                c[k] += grow * (p[k] - c[k]) / e;
            }
            r += grow;
        }
    }
    // 2. The centre of the bounding box, which keeps the radius within √3 of the minimum.
    let (lo, hi) = pts().fold(
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            )
        },
    );
    let boxed = [
        (lo[0] + hi[0]) / 2.0,
        (lo[1] + hi[1]) / 2.0,
        (lo[2] + hi[2]) / 2.0,
    ];
    // 3. Round each centre to f32, take the exact enclosing radius about it, keep the smaller.
    let enclose = |c: [f64; 3]| {
        let c = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
        let r2 = pts().fold(0.0f64, |m, p| m.max(dist2(p, wide(c))));
        (c, up(libm::sqrt(r2) * (1.0 + 1.0e-12) + 1.0e-38))
    };
    let (c1, r1) = enclose(c);
    let (c2, r2) = enclose(boxed);
    let (c, r) = if r2 < r1 { (c2, r2) } else { (c1, r1) };
    // A radius past f32::MAX (points spread over more than f32's range) has no sphere: `None`,
    // never a sphere with a NaN radius. A single point still gets a positive radius.
    r.is_finite()
        .then(|| Sphere::new(c, r.max(f32::MIN_POSITIVE)))
}

/// A bounding sphere prepared for culling (see the [module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    sphere: Sphere,
    /// `R2` per split: the padded radius squared, inflated for rounding.
    r2: [f32; 2],
    /// `κ` per split: the coefficient of `|C − o|²`.
    kappa: [f32; 2],
}

impl Bound {
    /// The culling form of `sphere` (an invalid sphere culls nothing).
    #[must_use]
    pub fn new(sphere: &Sphere) -> Self {
        let r = sphere.radius() as f64;
        let g3 = 3.0 * U / (1.0 - 3.0 * U);
        let alpha = 1.0 + ETA;
        let beta = ETA + 11.0 * U;
        let low = (1.0 - U) * (1.0 - U);
        let pad = 1.0 + 1.0e-12;
        let r2 = MU.map(|mu| {
            let r2 = (1.0 + g3) * (1.0 + mu) * alpha * alpha * r * r / low * pad;
            if sphere.is_valid() {
                up(r2)
            } else {
                f32::INFINITY
            }
        });
        let kappa = MU.map(|mu| {
            up((1.0 + g3) * (1.0 + 1.0 / mu) * beta * beta / ((1.0 - g3) * low * low) * pad)
        });
        Bound {
            sphere: *sphere,
            r2,
            kappa,
        }
    }

    /// The sphere.
    #[inline]
    #[must_use]
    pub fn sphere(&self) -> Sphere {
        self.sphere
    }

    /// False only in lanes whose ray line passes farther than `ρ = r + η(|C − o| + r)` from
    /// the centre, so that no triangle inside the sphere can report a hit: 17 mul, 16 add,
    /// 1 div, 4 cmp. Lanes whose `d·d` lies outside `2^-100…2^100` are never culled.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    #[must_use]
    pub fn may_hit<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        let d = rays.dir;
        // 1. Origin to centre, and the foot of the perpendicular along the ray.
        let f = V3::splat(self.sphere.center()) - rays.origin;
        let dd = d.length_squared();
        let s = f.dot(d) / dd;
        // 2. The perpendicular and its square against the padded, inflated radius.
        let l2 = (f - d.scale(s)).length_squared();
        let f2 = f.length_squared();
        let limit0 = L::from_f32(self.r2[0]) + L::from_f32(self.kappa[0]) * f2;
        let limit1 = L::from_f32(self.r2[1]) + L::from_f32(self.kappa[1]) * f2;
        // 3. Directions outside the range where d·d is accurate are never culled.
        let scaled = dd.ge(L::from_f32(DD_LO)) & dd.le(L::from_f32(DD_HI));
        !(l2.gt(limit0) | l2.gt(limit1)) | !scaled
    }

    /// The sphere as a guarded focal cache entry for rays from `eye`, with the radius padded
    /// by `(η + 4·2^-24)(|C − E| + r)`: the focal triangle kernel decides exactly for vertices
    /// within `2^-24|A − E|` of the true ones, and the unit direction that the sphere test
    /// uses is within `3·2^-24` of the ray's. [`FocalSphere`]'s guard then decides the line
    /// exactly, so no hit is lost.
    ///
    /// **An invalid bound culls nothing**, as in [`may_hit`](Self::may_hit): when the sphere is
    /// invalid (e.g. `Sphere::new(c, -1.0)`), the eye is not finite, or the padded radius is
    /// not representable in f32, the entry is [`FocalSphere::pass_all`], whose cheap test
    /// accepts every ray (and which, used as a sphere, is never hit).
    #[must_use]
    pub fn focal(&self, eye: Vec3) -> FocalSphere<f32> {
        let s = &self.sphere;
        let c = libm::sqrt(dist2(wide(s.center()), wide(eye)));
        let r = s.radius() as f64;
        let rho = up((r + (ETA + 4.0 * U) * (c + r)) * (1.0 + 1.0e-9));
        let padded = Sphere::new(s.center(), rho);
        if padded.is_valid() && eye.is_finite() {
            FocalSphere::new(eye, &padded)
        } else {
            FocalSphere::pass_all()
        }
    }
}
