//! The focal triangle path is as accurate as Möller–Trumbore (issue 10, Required 1).
//!
//! Classes of rays from one eye against one triangle, each case aimed at a point whose exact
//! barycentrics are all ≥ 0.02 (so every method must hit): random; far (c/ℓ = 2^4…2^12);
//! needles (aspect 10…10^4); grazing (cos θ = 2^-10…1); large coordinates (offset 10^5, the
//! triangle of size 1 at 4–16 units); plane grids at 3–5 units (cells 0.06–0.085, seen at
//! cos θ 0.59–1, as Embree's watertightness test). Per method and class: the maximum relative
//! `t` error and absolute `u`, `v` error against the exact answers (`exact_ref`), and the
//! largest `t` error over the case's 2-ulp margin (what moving every input by 2 ulps changes).
//! Pinned: the focal path's maxima are at most 2× Möller's; focal's `t` error is within the
//! 2-ulp margin on every case; and where that margin is below 2^-18 relative, within 2^-16.
//! The cases are drawn from exact operations only, so every target checks the same ones.
//! `--nocapture` prints the table.

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::Cull;
use raylane::Ray;
use raylane::triangle::{FocalTriangle, Moller, Triangle, Watertight};
use raylane_lab::loops as internals;

use crate::kernels::exact_reference::{Exact, exact};

fn unit(rng: &mut SmallRng) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// One case: eye, direction, triangle.
type Case = (Vec3, Vec3, [Vec3; 3]);

/// A direction from `eye` towards a random point of the triangle (barycentrics ≥ 0.05 before
/// rounding).
fn aim(rng: &mut SmallRng, eye: Vec3, t: [Vec3; 3]) -> Case {
    let (mut u, mut v) = (
        rng.random_range(0.05..0.9f32),
        rng.random_range(0.05..0.9f32),
    );
    if u + v > 0.95 {
        (u, v) = (0.95 - v, 0.95 - u);
    }
    let p = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
    (eye, p - eye, t)
}

fn around(rng: &mut SmallRng, q: Vec3, size: f32) -> [Vec3; 3] {
    [
        q + unit(rng) * size,
        q + unit(rng) * size,
        q + unit(rng) * size,
    ]
}

fn random(rng: &mut SmallRng) -> Case {
    let eye = unit(rng) * rng.random_range(0.0..8.0f32);
    let q = unit(rng) * rng.random_range(0.0..4.0f32);
    let tri = around(rng, q, 2.0);
    aim(rng, eye, tri)
}

fn far(rng: &mut SmallRng) -> Case {
    let k = rng.random_range(4..=12);
    let q = unit(rng) * rng.random_range(0.0..2.0f32);
    let eye = q + unit(rng) * (1u32 << k) as f32;
    let tri = around(rng, q, 0.5);
    aim(rng, eye, tri)
}

fn needle(rng: &mut SmallRng) -> Case {
    let aspect = pow2(rng.random_range(3.32..13.29));
    let (a, l, s) = (unit(rng), unit(rng), unit(rng));
    let side = l.cross(s).normalize();
    let len = 2.0;
    let b = a + l * len;
    let c = a + l * (len * rng.random_range(0.1..0.9f32)) + side * (len / aspect);
    let eye = a + unit(rng) * rng.random_range(2.0..6.0f32);
    aim(rng, eye, [a, b, c])
}

/// `2^x` from exact operations only (`powi` of 2 and a linear mantissa), so that every
/// target draws the same cases.
fn pow2(x: f32) -> f32 {
    let k = x.floor();
    2f32.powi(k as i32) * (1.0 + (x - k))
}

fn grazing(rng: &mut SmallRng) -> Case {
    // A triangle of size ~1 in a random plane through a random point, the eye 2–4 units from
    // the target point at cos θ = 2^-10…1 to the plane's normal.
    let n = unit(rng);
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    let o = unit(rng) * 2.0;
    let at = |x: f32, y: f32| o + e1 * x + e2 * y;
    let tri = [at(-1.0, -0.8), at(1.1, -0.9), at(0.1, 1.2)];
    let (_, p, _) = aim(rng, Vec3::ZERO, tri); // the target point (aimed from the origin)
    let cos = 1.0 / pow2(rng.random_range(0.0..10.0));
    let h = (e1 * rng.random_range(-1.0..1.0f32) + e2 * rng.random_range(-1.0..1.0f32))
        .normalize_or(e1);
    let sin = (1.0 - cos * cos).sqrt();
    let up = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let eye = p + (h * sin + n * (cos * up)) * rng.random_range(2.0..4.0f32);
    (eye, p - eye, tri)
}

fn large(rng: &mut SmallRng) -> Case {
    let o = Vec3::new(1.0e5, -1.0e5, 1.0e5) + unit(rng) * 1000.0;
    let tri = around(rng, o, 1.0);
    let eye = o + unit(rng) * rng.random_range(4.0..16.0f32);
    aim(rng, eye, tri)
}

fn grid(rng: &mut SmallRng) -> Case {
    let n = unit(rng);
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    let cos = rng.random_range(0.59..1.0f32);
    let dist = rng.random_range(3.0..5.0f32);
    let s = rng.random_range(0.06..0.085f32);
    let (i, j) = (
        rng.random_range(-100..100) as f32,
        rng.random_range(-100..100) as f32,
    );
    let eye = Vec3::ZERO;
    // The plane at `dist` along a direction at angle θ to its normal.
    let axis = -(n * cos + e1 * (1.0 - cos * cos).sqrt());
    let p0 = eye + axis * dist;
    let at = |a: f32, b: f32| p0 + e1 * (a * s) + e2 * (b * s);
    let tri = if rng.random_bool(0.5) {
        [at(i, j), at(i + 1.0, j), at(i, j + 1.0)]
    } else {
        [at(i + 1.0, j + 1.0), at(i, j + 1.0), at(i + 1.0, j)]
    };
    aim(rng, eye, tri)
}

/// Per method: max relative t error, max |u| error, max |v| error, max `t` error over the
/// 2-ulp margin, misses.
#[derive(Clone, Copy, Debug, Default)]
struct Stat {
    t: f64,
    u: f64,
    v: f64,
    cond: f64,
    miss: usize,
}

impl Stat {
    fn add(&mut self, x: &Exact, h: Option<raylane_lab::loops::HitRecord>) {
        match h {
            Some(h) => {
                self.t = self.t.max(x.t_err(h.t));
                self.cond = self.cond.max((h.t as f64 - x.t).abs() / x.margin);
                self.u = self.u.max((h.u as f64 - x.u).abs());
                self.v = self.v.max((h.v as f64 - x.v).abs());
            }
            None => self.miss += 1,
        }
    }
}

#[test]
fn focal_is_as_accurate_as_moller() {
    type Gen = fn(&mut SmallRng) -> Case;
    let classes: [(&str, Gen); 6] = [
        ("random", random),
        ("far", far),
        ("needle", needle),
        ("grazing", grazing),
        ("large", large),
        ("grid", grid),
    ];
    // The same cases on every target (exact operations and a seeded generator): x86-64 and
    // AArch64 (under qemu-user, ~10× slower) check the same maxima.
    let n = 4000;
    let mut rng = SmallRng::seed_from_u64(10);
    println!("class: cases; max rel t / abs u / abs v error: focal | moller | watertight");
    for (name, gen_case) in classes {
        let mut s = [Stat::default(); 3];
        let (mut kept, mut conditioned, mut worst_conditioned) = (0, 0, 0.0f64);
        while kept < n {
            let (eye, dir, [a, b, c]) = gen_case(&mut rng);
            let x = exact(eye, dir, a, b, c);
            if !x.t.is_finite() || x.t <= 0.0 || !x.inside_by(0.02) {
                continue;
            }
            kept += 1;
            let ray = Ray::new(eye, dir);
            let tri = Triangle::new(a, b, c);
            let f = internals::triangle::focal::intersect(
                &ray,
                &FocalTriangle::new(eye, &tri),
                Cull::None,
            );
            s[0].add(&x, f);
            s[1].add(
                &x,
                internals::triangle::intersect::<Moller>(&ray, &tri, Cull::None),
            );
            s[2].add(
                &x,
                internals::triangle::intersect::<Watertight>(&ray, &tri, Cull::None),
            );
            if x.margin / x.t < 2f64.powi(-18)
                && let Some(h) = f
            {
                conditioned += 1;
                worst_conditioned = worst_conditioned.max(x.t_err(h.t));
            }
        }
        println!(
            "{name:8}: {kept}; {:.2e} / {:.2e} / {:.2e} | {:.2e} / {:.2e} / {:.2e} | \
             {:.2e} / {:.2e} / {:.2e}; t error / 2-ulp margin {:.2} | {:.2} | {:.2}; \
             well-conditioned {conditioned}, focal max {:.2e}",
            s[0].t,
            s[0].u,
            s[0].v,
            s[1].t,
            s[1].u,
            s[1].v,
            s[2].t,
            s[2].u,
            s[2].v,
            s[0].cond,
            s[1].cond,
            s[2].cond,
            worst_conditioned
        );
        assert_eq!(s[0].miss, 0, "{name}: focal missed an interior point");
        assert!(s[0].t <= 2.0 * s[1].t, "{name}: focal t {:e}", s[0].t);
        assert!(s[0].u <= 2.0 * s[1].u, "{name}: focal u {:e}", s[0].u);
        assert!(s[0].v <= 2.0 * s[1].v, "{name}: focal v {:e}", s[0].v);
        assert!(worst_conditioned <= 2f64.powi(-16), "{name}");
        // On every case, focal's t is within what a 2-ulp move of the inputs can change.
        assert!(
            s[0].cond <= 1.0,
            "{name}: focal t error {} margins",
            s[0].cond
        );
    }
}
