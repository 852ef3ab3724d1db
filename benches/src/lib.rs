//! Seeded scenes shared by the benchmarks.

use glam::Vec3;
use raylane::Pinhole;
use raylane::sphere::Sphere;

/// A small deterministic generator (xorshift64*), so every contender sees the same scene.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * x
    }
}

/// A general scene: `n` spheres of radius 0.2–1.5 scattered 4–40 units in front of a camera at
/// the origin looking down −z with a 60° field of view; `width × height` primary rays.
pub fn sphere_scene(n: usize, seed: u64, width: u32, height: u32) -> (Pinhole, Vec<Sphere>) {
    let mut rng = Rng::new(seed);
    let cam = Pinhole::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, width, height);
    let spheres = (0..n)
        .map(|_| {
            let z = -rng.range(4.0, 40.0);
            let half = -z * 0.55;
            let c = Vec3::new(
                rng.range(-half, half),
                rng.range(-half, half) * height as f32 / width as f32,
                z,
            );
            Sphere::new(c, rng.range(0.2, 1.5))
        })
        .collect();
    (cam, spheres)
}
