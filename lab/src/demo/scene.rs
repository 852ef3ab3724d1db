//! The scene types and the cameras.

use glam::Vec3;

use raylane::Cull;
use raylane::camera::Pinhole;
use raylane::lane::{Lane, sqrt_f32};
use raylane::plane::Plane;
use raylane::ray::RayPacket;
use raylane::sphere::Sphere;
use raylane::vec3::V3;

/// How a surface is coloured (linear RGB in `[0, 1]`, lit by the scene's light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Paint {
    /// One colour.
    Flat([f32; 3]),
    /// Squares of side `size` in the x–z plane (by the hit point's x and z), alternating `a`
    /// and `b`.
    Checker {
        /// Colour of the squares whose x and z indices have an even sum.
        a: [f32; 3],
        /// Colour of the others.
        b: [f32; 3],
        /// Side of a square.
        size: f32,
    },
    /// The unit normal `n` as the colour `(n + 1)/2`, unlit and without gamma (shows every
    /// facet).
    Normal,
}

/// A mesh part: the triangles `first .. first + count` of a scene's index triples, with their
/// own bounding sphere, paint and face culling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part {
    /// First index triple.
    pub first: u32,
    /// Number of index triples.
    pub count: u32,
    /// Its paint.
    pub paint: Paint,
    /// [`Cull::Back`] for closed meshes wound outward (a ray through a crack then shows the
    /// background instead of the inside), [`Cull::None`] for two-sided surfaces.
    pub cull: Cull,
}

/// What a frame shows, over borrowed slices (see [`scenes`](super::scenes) for the lectures' scenes).
#[derive(Clone, Copy, Debug)]
pub struct Scene<'a> {
    /// Spheres.
    pub spheres: &'a [Sphere],
    /// Paint of each sphere (missing entries are grey).
    pub sphere_paints: &'a [Paint],
    /// Planes.
    pub planes: &'a [Plane],
    /// Paint of each plane.
    pub plane_paints: &'a [Paint],
    /// Vertex positions shared by every mesh part.
    pub positions: &'a [Vec3],
    /// Index triples of every mesh part.
    pub indices: &'a [[u32; 3]],
    /// Mesh parts (at most [`MAX_PARTS`](super::MAX_PARTS)).
    pub parts: &'a [Part],
    /// Unit direction towards the light.
    pub light: Vec3,
}

/// `v/|v|` with the crate's square root, or zero for a zero or non-finite vector.
pub(super) fn unit(v: Vec3) -> Vec3 {
    let w = V3::<f32>::from(v);
    let n = sqrt_f32(w.length_squared());
    if n > 0.0 && n.is_finite() {
        w.div_by(n).into()
    } else {
        Vec3::ZERO
    }
}

/// An orthographic camera: parallel rays along `dir` from the pixels of an image plane.
///
/// Pixel `(x, y)`'s ray starts at `corner + (x + ½)·du + (y + ½)·dv` (computed per lane, so
/// origins differ from ray to ray) and has the unit direction `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ortho {
    /// The outer corner of pixel (0, 0).
    pub corner: Vec3,
    /// One pixel to the right.
    pub du: Vec3,
    /// One pixel down.
    pub dv: Vec3,
    /// The unit direction of every ray.
    pub dir: Vec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Ortho {
    /// An image plane centred on `center`, looking along `forward`, with `up` roughly up,
    /// `view_height` world units tall and `width × height` square pixels.
    #[must_use]
    pub fn new(
        center: Vec3,
        forward: Vec3,
        up: Vec3,
        view_height: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let dir = unit(forward);
        let right = unit(dir.cross(up));
        let down = dir.cross(right);
        let pixel = view_height / height.max(1) as f32;
        let (du, dv) = (right * pixel, down * pixel);
        let corner = center - du * (width as f32 * 0.5) - dv * (height as f32 * 0.5);
        Ortho {
            corner,
            du,
            dv,
            dir,
            width,
            height,
        }
    }

    /// The rays of pixels `(x, y) … (x + L::LANES − 1, y)`, interval `(0, +inf)`; lanes past
    /// the right edge never hit.
    #[must_use]
    pub fn row_packet<L: Lane>(&self, x: u32, y: u32) -> RayPacket<L> {
        let px = L::from_f32_fn(|i| x.saturating_add(i as u32) as f32 + 0.5);
        let py = L::from_f32(y as f32 + 0.5);
        let origin =
            V3::splat(self.corner) + V3::splat(self.du).scale(px) + V3::splat(self.dv).scale(py);
        let inside = L::from_f32_fn(|i| {
            if x.saturating_add(i as u32) < self.width && y < self.height {
                f32::INFINITY
            } else {
                0.0
            }
        });
        RayPacket::new(origin, V3::splat(self.dir), L::from_f32(0.0), inside)
    }
}

/// Where primary rays come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Camera {
    /// Rays from one focal point: the focal caches apply.
    Pinhole(Pinhole),
    /// Parallel rays (see [`Ortho`]).
    Ortho(Ortho),
}

impl Camera {
    /// Image width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        match self {
            Camera::Pinhole(p) => p.width,
            Camera::Ortho(o) => o.width,
        }
    }

    /// Image height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        match self {
            Camera::Pinhole(p) => p.height,
            Camera::Ortho(o) => o.height,
        }
    }

    /// The rays of `L::LANES` pixels of row `y` from column `x`.
    #[must_use]
    pub fn row_packet<L: Lane>(&self, x: u32, y: u32) -> RayPacket<L> {
        match self {
            Camera::Pinhole(p) => p.row_packet(x, y),
            Camera::Ortho(o) => o.row_packet(x, y),
        }
    }
}
