//! The focal guard's promise: zero misclassified rays for c/r up to 2^20 on every case whose
//! exact answer survives a 2-ulp move of any input.
//!
//! Random eyes, unit directions and spheres at c/r = 2^k, k = 0..=20, with rays passing at a
//! distance uniform in [0, 2r] from the centre (half of them within 5% of the rim). The exact
//! answer is the sign of D = r² − l² (l: distance from the centre to the ray), computed in f64
//! from the f32 inputs (its error, ~2^-50·c·r, is far below the band below). A case is kept
//! when |D| > 1.5 × the first-order change of D when every input moves by 2 f32 ulps:
//! ∂D/∂C = −2p, ∂D/∂E = 2p, ∂D/∂U = 2 s p/|U|, ∂D/∂r = 2r (p: centre-to-ray perpendicular,
//! s = T·Û). Run with `--nocapture` to see every method's misclassification counts.

use glam::Vec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use raylane::lane::Mask;
use raylane::sphere::focal::{Focal, FocalKernel, FocalUnguarded};
use raylane::sphere::{
    FocalSphere, Geometric, Quadratic, Robust, Sphere, SphereKernel, SpherePacket,
};
use raylane::{Ray, RayPacket};
use wide::f32x8;

fn ulp(x: f32) -> f64 {
    let a = x.abs();
    if a == 0.0 {
        f64::from(f32::from_bits(1))
    } else {
        (f64::from(a.next_up()) - f64::from(a)).abs()
    }
}

/// The exact answer (true = hit), or None when 2-ulp moves of the inputs could change it.
fn exact(eye: Vec3, dir: Vec3, c: Vec3, r: f32) -> Option<bool> {
    let e = [eye.x as f64, eye.y as f64, eye.z as f64];
    let u = [dir.x as f64, dir.y as f64, dir.z as f64];
    let cc = [c.x as f64, c.y as f64, c.z as f64];
    let t = [cc[0] - e[0], cc[1] - e[1], cc[2] - e[2]];
    let n = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
    let uh = [u[0] / n, u[1] / n, u[2] / n];
    let s = t[0] * uh[0] + t[1] * uh[1] + t[2] * uh[2];
    if s <= 4.0 * r as f64 {
        return None; // keep the sphere well in front: only the rim decision is studied here
    }
    let p = [t[0] - s * uh[0], t[1] - s * uh[1], t[2] - s * uh[2]];
    let d = (r as f64) * (r as f64) - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    let ins = [eye.x, eye.y, eye.z];
    let dirs = [dir.x, dir.y, dir.z];
    let cs = [c.x, c.y, c.z];
    let mut band = 2.0 * r as f64 * 2.0 * ulp(r);
    for i in 0..3 {
        band += 2.0 * p[i].abs() * 2.0 * (ulp(cs[i]) + ulp(ins[i]));
        band += 2.0 * (s * p[i] / n).abs() * 2.0 * ulp(dirs[i]);
    }
    (d.abs() > 1.5 * band).then_some(d > 0.0)
}

fn case(rng: &mut SmallRng, k: u32) -> (Vec3, Vec3, Sphere) {
    let eye = if rng.random_range(0..4) == 0 {
        Vec3::ZERO
    } else {
        Vec3::new(
            rng.random_range(-10.0..10.0),
            rng.random_range(-10.0..10.0),
            rng.random_range(-10.0..10.0),
        )
    };
    let dir = Vec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
    .normalize();
    let r = rng.random_range(0.01..10.0f32);
    let side = dir.any_orthonormal_vector();
    let side = (side * rng.random_range(-1.0..1.0f32)
        + dir.cross(side) * rng.random_range(-1.0..1.0f32))
    .normalize();
    let l = if rng.random_bool(0.5) {
        rng.random_range(0.0..2.0f32)
    } else {
        rng.random_range(0.95..1.05f32)
    };
    let dist = r * (1u64 << k) as f32;
    (eye, dir, Sphere::new(eye + dir * dist + side * (l * r), r))
}

#[test]
fn focal_classifies_every_decidable_ray_up_to_2_pow_20() {
    let mut rng = SmallRng::seed_from_u64(2020);
    println!("k: decidable, misclassified by quadratic / geometric / robust / unguarded / focal");
    let mut total = 0;
    for k in 0..=20u32 {
        let mut wrong = [0usize; 5];
        let mut kept = 0;
        for _ in 0..3000 {
            let (eye, dir, s) = case(&mut rng, k);
            let Some(want) = exact(eye, dir, s.center(), s.radius()) else {
                continue;
            };
            kept += 1;
            let ray = Ray::new(eye, dir);
            let rp = RayPacket::<f32>::splat(&ray);
            let sp = SpherePacket::splat(&s);
            let got = [
                Quadratic::roots(&rp, &sp).any(),
                Geometric::roots(&rp, &sp).any(),
                Robust::roots(&rp, &sp).any(),
                FocalUnguarded::roots(&rp, &FocalSphere::splat(&FocalSphere::unguarded(eye, &s)))
                    .any(),
                Focal::roots(&rp, &FocalSphere::splat(&FocalSphere::new(eye, &s))).any(),
            ];
            for (w, g) in wrong.iter_mut().zip(got) {
                *w += (g != want) as usize;
            }
            // The packet path agrees with the scalar one (and so with the exact answer).
            let p = Focal::roots(
                &RayPacket::<f32x8>::splat(&ray),
                &FocalSphere::splat(&FocalSphere::new(eye, &s)),
            );
            assert_eq!(p.any().bits(), if got[4] { 0xff } else { 0 });
        }
        println!("2^{k:<2}: {kept:5}, {:?}", wrong);
        assert_eq!(
            wrong[4], 0,
            "focal misclassified a decidable ray at c/r = 2^{k}"
        );
        total += kept;
    }
    assert!(total > 40_000, "the sweep must keep most cases ({total})");
}
