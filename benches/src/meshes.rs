//! The scenes of the BVH benchmark (`examples/scenes.rs`): meshes, a sphere field, and the
//! three kinds of rays every contender traces.
//!
//! * Meshes: the vendored bunny (`tests/data/bunny.bin`, 3,674 triangles), its Loop
//!   subdivisions ([`crate::subdivide`]; 4 steps give 940,544 triangles), and the OBJ files of
//!   `../shared/meshes` (spot, fandisk, the Stanford bunny), loaded with `tobj` and skipped
//!   when absent.
//! * Spheres: `n` spheres of seed [`SPHERE_FIELD_SEED`] in a cube, radii so that they cover
//!   about a third of the cube's cross-section seen from the front.
//! * Rays ([`Workload`]): a 640×480 pinhole camera framing the scene's bounding sphere
//!   (primary rays from one eye); from every primary hit, one cosine-weighted diffuse bounce
//!   (incoherent, seeded) and one shadow ray to a point light (any-hit). The secondary rays
//!   start at the hit point moved off the surface by 10^-4 of the scene's radius along the
//!   normal (on the side the primary ray came from), with `t_min = 0`, so contenders without
//!   a `t_min` (parry3d) trace exactly the same rays.

use std::path::{Path, PathBuf};

use glam::Vec3;
use raylane::sphere::Sphere;
use raylane::triangle::Triangle;
use raylane::{Pinhole, Ray};

use crate::scene::Rng;
use crate::subdivide;

/// Image size of the primary rays.
pub const WIDTH: u32 = 640;
/// Image height.
pub const HEIGHT: u32 = 480;
/// Vertical field of view, degrees.
pub const FOV: f32 = 40.0;
/// Seed of the diffuse bounces.
pub const BOUNCE_SEED: u64 = 29;
/// Seed of the sphere field.
pub const SPHERE_FIELD_SEED: u64 = 31;

/// One answer per ray: `(t, primitive)` of the closest hit (or `(0, 0)` for an occluded
/// shadow ray), `None` for a miss.
pub type Answers = Vec<Option<(f32, u32)>>;

/// An indexed triangle mesh.
#[derive(Clone, Debug)]
pub struct MeshData {
    /// Name shown in the tables.
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles (indices into `positions`).
    pub indices: Vec<[u32; 3]>,
}

impl MeshData {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// True when there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The triangles, unshared.
    pub fn triangles(&self) -> Vec<Triangle> {
        let p = |i: u32| self.positions[i as usize];
        self.indices
            .iter()
            .map(|&[a, b, c]| Triangle::new(p(a), p(b), p(c)))
            .collect()
    }

    /// Centre and radius of the bounding box's sphere.
    pub fn bounds(&self) -> (Vec3, f32) {
        let (lo, hi) = self.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
    }
}

/// The vendored low-resolution Stanford bunny.
pub fn vendored_bunny() -> MeshData {
    let (positions, indices) =
        subdivide::load_bunny_bin(include_bytes!("../../tests/data/bunny.bin"))
            .expect("tests/data/bunny.bin is well formed");
    MeshData {
        name: "bunny (vendored)".into(),
        positions,
        indices,
    }
}

/// The vendored bunny after `steps` Loop subdivision steps (3,674 × 4^steps triangles).
pub fn subdivided_bunny(steps: u32) -> MeshData {
    let b = vendored_bunny();
    let (positions, indices) = subdivide::loop_subdivide(&b.positions, &b.indices, steps);
    MeshData {
        name: format!("bunny Loop×{steps}"),
        positions,
        indices,
    }
}

/// The directory of the optional real meshes: `$RAYLANE_MESHES`, else `../shared/meshes`
/// next to the repository.
pub fn shared_dir() -> PathBuf {
    std::env::var_os("RAYLANE_MESHES").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/meshes"),
        PathBuf::from,
    )
}

/// Every triangle of an OBJ file (all its models, shared vertices kept), or `None` when it
/// cannot be read.
pub fn load_obj(path: &Path, name: &str) -> Option<MeshData> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(path, &opts).ok()?;
    let mut m = MeshData {
        name: name.into(),
        positions: Vec::new(),
        indices: Vec::new(),
    };
    for model in models {
        let base = m.positions.len() as u32;
        let p = &model.mesh.positions;
        m.positions
            .extend(p.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        m.indices.extend(
            model
                .mesh
                .indices
                .chunks_exact(3)
                .map(|c| [base + c[0], base + c[1], base + c[2]]),
        );
    }
    (!m.is_empty()).then_some(m)
}

/// The real meshes of [`shared_dir`] that are present: spot, fandisk, the Stanford bunny.
pub fn shared_meshes() -> Vec<MeshData> {
    let dir = shared_dir();
    [
        ("spot.obj", "spot"),
        ("fandisk.obj", "fandisk"),
        ("stanford-bunny.obj", "Stanford bunny"),
    ]
    .into_iter()
    .filter_map(|(f, name)| load_obj(&dir.join(f), name))
    .collect()
}

/// `n` spheres in the cube [-1, 1]³ (seed [`SPHERE_FIELD_SEED`]), radii uniform in
/// [0.5, 1.5]·r with `r` chosen so that their cross-sections sum to about 3 times the cube's
/// face: a dense field, as a particle system or a point cloud of balls.
pub fn sphere_field(n: usize) -> Vec<Sphere> {
    let mut rng = Rng::new(SPHERE_FIELD_SEED);
    // n · π r² ≈ 3 · 4  ⇒  r = sqrt(12 / (π n)).
    let r = (12.0 / (std::f32::consts::PI * n.max(1) as f32)).sqrt();
    (0..n)
        .map(|_| {
            let c = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            Sphere::new(c, rng.range(0.5 * r, 1.5 * r))
        })
        .collect()
}

/// The camera framing a bounding sphere (`centre`, `radius`) from the front (+z), slightly
/// above, at the distance where the sphere just fits the image's height.
pub fn framing(centre: Vec3, radius: f32) -> Pinhole {
    let half = (FOV.to_radians() * 0.5).sin();
    let dist = radius / half * 0.6;
    let dir = Vec3::new(0.25, 0.3, 1.0).normalize();
    Pinhole::look_at(centre + dir * dist, centre, Vec3::Y, FOV, WIDTH, HEIGHT)
}

/// The side of a camera tile in the primary workload ([`Workload::tiled`]).
pub const TILE: u32 = 16;

/// The pixels of `cam` in the order of [`Workload::tiled`] (the image's sides are multiples
/// of [`TILE`]).
pub fn tile_pixels(cam: &Pinhole) -> Vec<(u32, u32)> {
    let mut v = Vec::with_capacity((cam.width * cam.height) as usize);
    for ty in (0..cam.height).step_by(TILE as usize) {
        for tx in (0..cam.width).step_by(TILE as usize) {
            for by in (0..TILE).step_by(4) {
                for bx in (0..TILE).step_by(4) {
                    for j in 0..4 {
                        for i in 0..4 {
                            v.push((tx + bx + i, ty + by + j));
                        }
                    }
                }
            }
        }
    }
    v
}

/// The point light: up, right and in front of the scene, 3 radii from its centre.
pub fn light(centre: Vec3, radius: f32) -> Vec3 {
    centre + Vec3::new(-1.0, 2.0, 1.5).normalize() * (3.0 * radius)
}

/// A closest hit as the workloads need it: `t`, the geometric normal (any length, either
/// side).
pub type SurfaceHit = Option<(f32, Vec3)>;

/// The three ray sets of one scene.
pub struct Workload {
    /// The camera of the primary rays.
    pub cam: Pinhole,
    /// The primary rays, row by row (640 × 480).
    pub primary: Vec<Ray>,
    /// Diffuse bounces, one per primary hit, in pixel order.
    pub diffuse: Vec<Ray>,
    /// Shadow rays to the light, one per primary hit, in pixel order (`t_max` = the light's
    /// distance).
    pub shadow: Vec<Ray>,
}

impl Workload {
    /// The camera's primary rays.
    pub fn primary(cam: &Pinhole) -> Vec<Ray> {
        (0..cam.height)
            .flat_map(|y| (0..cam.width).map(move |x| crate::scene::pixel_ray(cam, x, y)))
            .collect()
    }

    /// The camera's primary rays in tile order: tiles of [`TILE`]² pixels row by row, each in
    /// blocks of 4 × 4 pixels row by row, each block row by row. Packets of 16 consecutive rays
    /// are then 4 × 4 blocks and packets of 8 are 4 × 2 blocks, for every contender alike.
    pub fn tiled(cam: &Pinhole) -> Vec<Ray> {
        tile_pixels(cam)
            .into_iter()
            .map(|(x, y)| crate::scene::pixel_ray(cam, x, y))
            .collect()
    }

    /// The secondary rays from the primary rays' hits (`hits[i]` for `primary[i]`, from a
    /// reference tracer).
    pub fn new(cam: Pinhole, hits: &[SurfaceHit], centre: Vec3, radius: f32) -> Self {
        let primary = Self::primary(&cam);
        let mut rng = Rng::new(BOUNCE_SEED);
        let lamp = light(centre, radius);
        let eps = 1e-4 * radius;
        let (mut diffuse, mut shadow) = (Vec::new(), Vec::new());
        for (r, h) in primary.iter().zip(hits) {
            let Some((t, n)) = *h else { continue };
            let n = n.normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            // The normal on the side the ray came from.
            let n = if n.dot(r.dir()) > 0.0 { -n } else { n };
            let p = r.at(t) + n * eps;
            // Cosine-weighted: a uniform point on the unit sphere added to the normal.
            let d = (n + rng.unit()).normalize_or_zero();
            let d = if d == Vec3::ZERO { n } else { d };
            diffuse.push(Ray::new(p, d));
            let to = lamp - p;
            let dist = to.length();
            shadow.push(Ray::with_interval(p, to / dist, 0.0, dist));
        }
        Workload {
            cam,
            primary,
            diffuse,
            shadow,
        }
    }
}
