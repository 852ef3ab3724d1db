//! The lectures' scenes, built into caller storage.
//!
//! 1. [`Precision`]: the precision lecture's unit sphere 100 and 4100 units in front of an
//!    orthographic camera. At 4100 units `T·T − r²` keeps no bit of `r²`: `quadratic` and
//!    `geometric` lose the sphere in rounding noise (speckle over a disc about twice its size;
//!    the unguarded focal test loses half of it instead), while `robust` and the focal guard
//!    draw the same disc as at 100 units, every pixel as the exact answer has it.
//! 2. [`Ground`]: small spheres on a ground sphere of radius 2^20 seen from 1 unit above its
//!    surface (the lecture's "ground is a huge sphere"): the near root `μ − √δ` cancels, so
//!    `quadratic` draws the checkerboard in steps and `geometric` in speckle; `robust`
//!    (`t0 = c/q`) and the focal guard (whose `t` check sends these rays to its `f64` path)
//!    draw it clean.
//! 3. [`icosphere`]: a closed mesh of `20n²` triangles over shared vertices (the geodesic
//!    sphere, one part with its own bounding sphere per face of the icosahedron), shaded by
//!    normal: a crack would show the background.
//! 4. [`Mix`]: spheres, two closed meshes (an icosahedron and a cube) and a checkered ground
//!    plane, in fixed-size arrays — the scene the firmware renders.

use glam::Vec3;

use super::scene::unit;
use super::shapes;
use super::{Camera, Ortho, Paint, Part, Scene};
use crate::registry::Kernel;
use raylane::Cull;
use raylane::camera::Pinhole;
use raylane::plane::Plane;
use raylane::sphere::Sphere;

/// Direction towards the light of the lit scenes (unit length up to rounding).
pub const LIGHT: Vec3 = Vec3::new(-0.48, 0.8, 0.36);

const RED: [f32; 3] = [0.8, 0.15, 0.1];
const BLUE: [f32; 3] = [0.15, 0.3, 0.85];
const YELLOW: [f32; 3] = [0.9, 0.75, 0.15];
const GREEN: [f32; 3] = [0.2, 0.7, 0.3];
const PURPLE: [f32; 3] = [0.55, 0.3, 0.75];
const ORANGE: [f32; 3] = [0.95, 0.55, 0.2];
const CHECKER: Paint = Paint::Checker {
    a: [0.85, 0.85, 0.82],
    b: [0.3, 0.33, 0.38],
    size: 1.0,
};

/// Scene 1: a unit sphere `distance` units in front of an orthographic camera (precision
/// lecture). The camera looks along a direction that is not an axis, so the rays' origins and
/// the centre have full-precision coordinates.
#[derive(Clone, Copy, Debug)]
pub struct Precision {
    spheres: [Sphere; 1],
    paints: [Paint; 1],
}

impl Precision {
    /// The lecture's distances.
    pub const DISTANCES: [f32; 2] = [100.0, 4100.0];
    /// The methods shown side by side.
    pub const METHODS: [Kernel; 4] = [
        Kernel::Quadratic,
        Kernel::Geometric,
        Kernel::Robust,
        Kernel::Focal,
    ];
    /// Centre of the image plane.
    const CENTER: Vec3 = Vec3::new(0.3, 0.2, 0.1);
    /// Viewing direction (unit up to rounding).
    const FORWARD: Vec3 = Vec3::new(-0.48, -0.6, -0.64);
    /// Height of the view in world units (the sphere's diameter is 2).
    const VIEW: f32 = 4.0;

    /// The unit sphere `distance` units along the viewing direction.
    #[must_use]
    pub fn new(distance: f32) -> Self {
        let c = Self::CENTER + unit(Self::FORWARD) * distance;
        Precision {
            spheres: [Sphere::new(c, 1.0)],
            paints: [Paint::Flat(ORANGE)],
        }
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> Scene<'_> {
        Scene {
            spheres: &self.spheres,
            sphere_paints: &self.paints,
            planes: &[],
            plane_paints: &[],
            positions: &[],
            indices: &[],
            parts: &[],
            light: unit(Vec3::new(0.3, 0.9, 0.3)),
        }
    }

    /// The orthographic camera, `width × height` pixels.
    #[must_use]
    pub fn camera(width: u32, height: u32) -> Camera {
        Camera::Ortho(Ortho::new(
            Self::CENTER,
            Self::FORWARD,
            Vec3::Y,
            Self::VIEW,
            width,
            height,
        ))
    }
}

/// Scene 2: small spheres on a huge ground sphere, seen from [`Ground::EYE_HEIGHT`] above it.
#[derive(Clone, Copy, Debug)]
pub struct Ground {
    spheres: [Sphere; 5],
    paints: [Paint; 5],
}

impl Ground {
    /// Radius of the ground sphere (its top is at y = 0).
    pub const RADIUS: f32 = 1_048_576.0;
    /// Height of the eye above the ground.
    pub const EYE_HEIGHT: f32 = 1.0;
    /// The methods shown side by side.
    pub const METHODS: [Kernel; 4] = [
        Kernel::Quadratic,
        Kernel::Geometric,
        Kernel::Robust,
        Kernel::Focal,
    ];

    /// The scene's spheres: the ground first.
    #[must_use]
    pub fn new() -> Self {
        let r = Self::RADIUS;
        Ground {
            spheres: [
                Sphere::new(Vec3::new(0.0, -r, 0.0), r),
                Sphere::new(Vec3::new(-1.3, 0.6, -0.5), 0.6),
                Sphere::new(Vec3::new(0.4, 0.4, 0.6), 0.4),
                Sphere::new(Vec3::new(1.5, 0.5, -1.2), 0.5),
                Sphere::new(Vec3::new(-0.2, 0.25, 2.2), 0.25),
            ],
            paints: [
                CHECKER,
                Paint::Flat(RED),
                Paint::Flat(BLUE),
                Paint::Flat(GREEN),
                Paint::Flat(YELLOW),
            ],
        }
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> Scene<'_> {
        Scene {
            spheres: &self.spheres,
            sphere_paints: &self.paints,
            planes: &[],
            plane_paints: &[],
            positions: &[],
            indices: &[],
            parts: &[],
            light: LIGHT,
        }
    }

    /// The pinhole camera, `width × height` pixels.
    #[must_use]
    pub fn camera(width: u32, height: u32) -> Camera {
        Camera::Pinhole(Pinhole::look_at(
            Vec3::new(0.0, Self::EYE_HEIGHT, 6.0),
            Vec3::new(0.0, 0.3, 0.0),
            Vec3::Y,
            50.0,
            width,
            height,
        ))
    }
}

impl Default for Ground {
    fn default() -> Self {
        Self::new()
    }
}

/// Scene 3's default frequency: `20·16² = 5120` triangles.
pub const FREQUENCY: u32 = 16;

/// Number of parts of scene 3 (four patches per face of the icosahedron).
pub const ICOSPHERE_PARTS: usize = 80;

/// Scene 3: the unit icosphere of frequency `n` (see [`shapes::icosphere`]) written into
/// `positions` (at least `10n² + 2`), `indices` (at least `20n²`) and `parts` (at least
/// [`ICOSPHERE_PARTS`]): one part per patch of a face of the icosahedron (`n²/4` triangles
/// each for even `n`), each with its own bounding sphere, shaded by normal, back faces culled.
/// `None` when a slice is too short.
pub fn icosphere<'a>(
    n: u32,
    positions: &'a mut [Vec3],
    indices: &'a mut [[u32; 3]],
    parts: &'a mut [Part],
) -> Option<Scene<'a>> {
    let (nv, nt) = shapes::icosphere(n, positions, indices)?;
    let sizes = shapes::icosphere_patches(n);
    let mut k = 0;
    let mut first = 0;
    for _face in 0..20 {
        for &count in &sizes {
            if count > 0 {
                *parts.get_mut(k)? = Part {
                    first,
                    count: count as u32,
                    paint: Paint::Normal,
                    cull: Cull::Back,
                };
                k += 1;
            }
            first += count as u32;
        }
    }
    let parts = &parts[..k];
    Some(Scene {
        spheres: &[],
        sphere_paints: &[],
        planes: &[],
        plane_paints: &[],
        positions: &positions[..nv],
        indices: &indices[..nt],
        parts,
        light: LIGHT,
    })
}

/// Scene 3's pinhole camera, `width × height` pixels.
#[must_use]
pub fn icosphere_camera(width: u32, height: u32) -> Camera {
    Camera::Pinhole(Pinhole::look_at(
        Vec3::new(0.9, 0.65, 2.0),
        Vec3::ZERO,
        Vec3::Y,
        60.0,
        width,
        height,
    ))
}

/// Scene 4: three spheres, an icosahedron, a cube and a checkered ground plane.
#[derive(Clone, Copy, Debug)]
pub struct Mix {
    spheres: [Sphere; Mix::SPHERES],
    sphere_paints: [Paint; Mix::SPHERES],
    planes: [Plane; Mix::PLANES],
    plane_paints: [Paint; Mix::PLANES],
    positions: [Vec3; 20],
    indices: [[u32; 3]; Mix::TRIANGLES],
    parts: [Part; 2],
}

impl Mix {
    /// Number of spheres (for cache storage).
    pub const SPHERES: usize = 3;
    /// Number of planes.
    pub const PLANES: usize = 1;
    /// Number of triangles.
    pub const TRIANGLES: usize = 32;
    /// The image size the firmware renders (and the test command compares).
    pub const FIRMWARE_SIZE: (u32, u32) = (64, 48);

    /// The scene's data.
    #[must_use]
    pub fn new() -> Self {
        let mut positions = [Vec3::ZERO; 20];
        let mut indices = [[0u32; 3]; Mix::TRIANGLES];
        // An icosahedron of radius 0.75 (vertices 0..12, triangles 0..20) …
        let (ico_center, ico_r) = (Vec3::new(1.7, 0.8, -0.6), 0.75);
        if let Some((nv, nt)) = shapes::icosphere(1, &mut positions[..12], &mut indices[..20]) {
            for p in &mut positions[..nv] {
                *p = ico_center + *p * ico_r;
            }
            debug_assert_eq!((nv, nt), (12, 20));
        }
        // … and a cube of half-size 0.6, turned about y by atan(3/4) (vertices 12..20).
        let (cube_center, h) = (Vec3::new(-0.4, 0.6, -2.2), 0.6);
        if let Some((nv, nt)) = shapes::cube(&mut positions[12..], &mut indices[20..]) {
            for p in &mut positions[12..12 + nv] {
                let (x, z) = (p.x * h, p.z * h);
                *p = cube_center + Vec3::new(0.8 * x + 0.6 * z, p.y * h, -0.6 * x + 0.8 * z);
            }
            for t in &mut indices[20..20 + nt] {
                *t = t.map(|i| i + 12);
            }
        }
        Mix {
            spheres: [
                Sphere::new(Vec3::new(-1.6, 1.0, 0.2), 1.0),
                Sphere::new(Vec3::new(0.7, 0.45, 1.3), 0.45),
                Sphere::new(Vec3::new(2.1, 0.3, 1.6), 0.3),
            ],
            sphere_paints: [Paint::Flat(RED), Paint::Flat(BLUE), Paint::Flat(YELLOW)],
            planes: [Plane::new(Vec3::ZERO, Vec3::Y)],
            plane_paints: [CHECKER],
            positions,
            indices,
            parts: [
                Part {
                    first: 0,
                    count: 20,
                    paint: Paint::Flat(GREEN),
                    cull: Cull::Back,
                },
                Part {
                    first: 20,
                    count: 12,
                    paint: Paint::Flat(PURPLE),
                    cull: Cull::Back,
                },
            ],
        }
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> Scene<'_> {
        Scene {
            spheres: &self.spheres,
            sphere_paints: &self.sphere_paints,
            planes: &self.planes,
            plane_paints: &self.plane_paints,
            positions: &self.positions,
            indices: &self.indices,
            parts: &self.parts,
            light: LIGHT,
        }
    }

    /// The pinhole camera, `width × height` pixels.
    #[must_use]
    pub fn camera(width: u32, height: u32) -> Camera {
        Camera::Pinhole(Pinhole::look_at(
            Vec3::new(0.4, 2.2, 6.5),
            Vec3::new(0.1, 0.6, -0.3),
            Vec3::Y,
            42.0,
            width,
            height,
        ))
    }
}

impl Default for Mix {
    fn default() -> Self {
        Self::new()
    }
}
