//! A pinhole camera: primary rays that all start at one focal point.
//!
//! The image plane is given by the centre of pixel (0, 0) minus half a pixel (`corner`) and
//! the vectors `du`, `dv` that step one pixel right and down. Pixel `(x, y)`'s ray starts at
//! the focal point `eye` and has the unit direction of `corner + (x + ½)·du + (y + ½)·dv − eye`.
//! Every ray of the camera shares its origin, which is what the focal-point caches
//! ([`FocalSpheres`](crate::sphere::FocalSphere), [`FocalPlane`](crate::plane::FocalPlane))
//! exploit.

use glam::Vec3;

use crate::lane::Lane;
use crate::ray::RayPacket;
use crate::vec3::V3;

/// A pinhole camera with a focal point and an image plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pinhole {
    /// The focal point: origin of every primary ray.
    pub eye: Vec3,
    /// Corner of the image plane (the outer corner of pixel (0, 0)).
    pub corner: Vec3,
    /// One pixel to the right.
    pub du: Vec3,
    /// One pixel down.
    pub dv: Vec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// `v / |v|` with the crate's square root (`vsqrt.f32` on Cortex-M, not glam's software
/// `libm` root), or zero for a zero or non-finite vector.
fn unit(v: Vec3) -> Vec3 {
    let w = V3::<f32>::from(v);
    let n = w.length_squared().sqrt();
    if n > 0.0 && n.is_finite() {
        w.div_by(n).into()
    } else {
        Vec3::ZERO
    }
}

impl Pinhole {
    /// A camera at `eye` looking at `target`, with `up` roughly up, a vertical field of view
    /// of `vfov_degrees`, and an image of `width × height` pixels (square pixels).
    #[must_use]
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        vfov_degrees: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let forward = unit(target - eye);
        let right = unit(forward.cross(up));
        let down = forward.cross(right);
        let half_h = libm::tanf(vfov_degrees.to_radians() * 0.5);
        let pixel = 2.0 * half_h / height.max(1) as f32;
        let du = right * pixel;
        let dv = down * pixel;
        let corner = eye + forward - du * (width as f32 * 0.5) - dv * (height as f32 * 0.5);
        Pinhole {
            eye,
            corner,
            du,
            dv,
            width,
            height,
        }
    }

    /// The rays of pixels `(x, y) … (x + L::LANES − 1, y)` of one image row, unit directions,
    /// interval `(0, +inf)`.
    ///
    /// **Pixels outside the image** (`x + i ≥ width` or `y ≥ height`, including columns past
    /// `u32::MAX`, which are counted without wrapping) get the empty interval `(+inf, −inf)`:
    /// they never hit, whatever their direction, and never alias another pixel. No input
    /// panics.
    #[must_use]
    pub fn row_packet<L: Lane>(&self, x: u32, y: u32) -> RayPacket<L> {
        // Column of lane i, in u64 so that x + i cannot wrap (x ≤ u32::MAX, i < 2^32).
        let col = |i: usize| u64::from(x) + i as u64;
        let px = L::from_f32_fn(|i| col(i) as f32 + 0.5);
        let py = L::from_f32((y as f32) + 0.5);
        let corner = V3::<L>::splat(self.corner);
        let target = corner + V3::splat(self.du).scale(px) + V3::splat(self.dv).scale(py);
        let d = target - V3::splat(self.eye);
        let dir = d.div_by(d.length_squared().sqrt());
        let inside = L::from_f32_fn(|i| {
            if col(i) < u64::from(self.width) && y < self.height {
                f32::INFINITY
            } else {
                0.0
            }
        });
        RayPacket::new(V3::splat(self.eye), dir, L::from_f32(0.0), inside)
    }
}
