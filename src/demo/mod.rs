//! Demo scenes and their renderer (feature `demo`): what the kernels do, as pictures.
//!
//! The lectures' scenes ([`scenes`]) are rendered by the crate's packet kernels into
//! caller-provided buffers: `no_std`, no allocation, one [`Tile`] at a time, so the host's
//! `render` example can spread tiles over threads, the tests can render small images and check
//! them, and the firmware under `targets/` can render scene 4 on a Cortex-M4F. Every pixel is
//! computed lane by lane with the same operations at every lane width, so an image does not
//! depend on the packet width or the target: the firmware's `f32` image equals the host's
//! `f32x8` one byte for byte.
//!
//! **Rays.** A [`Camera::Pinhole`] makes packets of primary rays from one focal point
//! ([`Pinhole::row_packet`]); a [`Frame`] then builds the focal caches once, in caller
//! [`Storage`]: [`FocalSphere`] per sphere (guarded, or unguarded for
//! [`Method::FocalUnguarded`]), [`FocalPlane`] per plane and, per mesh part, a
//! [`FocalMesh`] whose bounding sphere ([`Mesh::bounded`]) is tested before its triangles.
//! The sphere method is chosen per frame ([`Method`]): the focal cache, or `quadratic`,
//! `geometric`, `robust` over the same packets. A [`Camera::Ortho`] makes parallel rays with
//! different origins (the precision lecture's orthographic camera): there the non-focal
//! kernels run per packet ([`Watertight`] for triangles), and [`Method::Focal`] builds a focal
//! cache *per ray*, with the ray's own origin as the eye, gathered into lanes — which shows
//! what the guard decides, not how fast the cache is.
//!
//! **Closest hit.** Spheres, then planes, then each mesh part; a kind's hit replaces the best
//! so far only where its `t` is strictly smaller (ties keep the earlier kind and index), and
//! each kind sees the rays' `t_max` relaxed to the best so far (`t + |t|·2^-21`, as in
//! [`hit`](crate::hit)).
//!
//! **Shading** uses `+ − × ÷ √` and compares only (no transcendental functions, whose library
//! implementations may differ between targets): Lambert's law under one directional light with
//! an ambient term, a checkerboard for [`Paint::Checker`], a sky gradient for rays that hit
//! nothing, and a gamma of 2 (a square root); [`Paint::Normal`] stores the normal map's
//! colours as they are. Triangle normals are the face normals `(B − A) × (C − A)`; every normal is turned
//! towards the viewer.
//!
//! **Output.** RGB8, row-major, for the tile's pixels, and optionally one [`ID_NONE`],
//! [`ID_SPHERE`], [`ID_PLANE`] or [`ID_TRIANGLE`] byte per pixel (what the tests count).
//! [`Stats`] counts rays and ray–primitive tests per lane (a packet of `k` rays against one
//! triangle counts `k`) and the triangle tests that bounding spheres saved.

pub mod scenes;
pub mod shapes;

use glam::Vec3;

use crate::camera::Pinhole;
use crate::hit::Hit;
use crate::lane::{Lane, MAX_LANES, Mask, sqrt_f32};
use crate::mesh::{FocalMesh, Mesh};
use crate::plane::{self, FocalPlane, Plane};
use crate::ray::RayPacket;
use crate::sphere::focal::{self as sf, Focal, FocalKernel, FocalUnguarded};
use crate::sphere::{
    self, FocalSphere, Geometric, Quadratic, QuadraticUnit, Robust, Sphere, SphereKernel,
};
use crate::triangle::{Cull, FocalRays, FocalTriangle, Watertight};
use crate::vec3::V3;

/// Largest number of mesh parts in a [`Scene`].
pub const MAX_PARTS: usize = 80;

/// Pixel id: the ray hit nothing.
pub const ID_NONE: u8 = 0;
/// Pixel id: the closest hit is a sphere.
pub const ID_SPHERE: u8 = 1;
/// Pixel id: the closest hit is a plane.
pub const ID_PLANE: u8 = 2;
/// Pixel id: the closest hit is a triangle.
pub const ID_TRIANGLE: u8 = 3;

/// The ray–sphere method of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// [`Quadratic`]: the general quadratic.
    Quadratic,
    /// [`QuadraticUnit`]: the brute force with `a = 1`.
    QuadraticUnit,
    /// [`Geometric`]: the lecture's faster method.
    Geometric,
    /// [`Robust`]: Ray Tracing Gems ch. 7.
    Robust,
    /// The guarded focal cache ([`Focal`]).
    Focal,
    /// The lecture's unguarded focal test ([`FocalUnguarded`]).
    FocalUnguarded,
}

impl Method {
    /// Every method.
    pub const ALL: [Method; 6] = [
        Method::Quadratic,
        Method::QuadraticUnit,
        Method::Geometric,
        Method::Robust,
        Method::Focal,
        Method::FocalUnguarded,
    ];

    /// The name, as the checker spells it.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Method::Quadratic => Quadratic::NAME,
            Method::QuadraticUnit => QuadraticUnit::NAME,
            Method::Geometric => Geometric::NAME,
            Method::Robust => Robust::NAME,
            Method::Focal => Focal::NAME,
            Method::FocalUnguarded => FocalUnguarded::NAME,
        }
    }

    /// The method called `name`.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

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

/// What a frame shows, over borrowed slices (see [`scenes`] for the lectures' scenes).
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
    /// Mesh parts (at most [`MAX_PARTS`]).
    pub parts: &'a [Part],
    /// Unit direction towards the light.
    pub light: Vec3,
}

/// `v/|v|` with the crate's square root, or zero for a zero or non-finite vector.
fn unit(v: Vec3) -> Vec3 {
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

/// Caller storage for a frame's focal caches. Pinhole frames need one sphere entry per sphere
/// (focal methods only), one plane entry per plane and one triangle entry per triangle of every
/// part; orthographic frames need none ([`Storage::none`]).
#[derive(Debug)]
pub struct Storage<'c> {
    /// Sphere entries.
    pub spheres: &'c mut [FocalSphere<f32>],
    /// Plane entries.
    pub planes: &'c mut [FocalPlane],
    /// Triangle entries.
    pub triangles: &'c mut [FocalTriangle<f32>],
}

impl Storage<'static> {
    /// No storage (orthographic frames).
    #[must_use]
    pub fn none() -> Self {
        Storage {
            spheres: &mut [],
            planes: &mut [],
            triangles: &mut [],
        }
    }
}

/// An unused sphere cache entry (never hit), to fill storage arrays with.
#[must_use]
pub fn empty_sphere() -> FocalSphere<f32> {
    FocalSphere::new(Vec3::ZERO, &Sphere::new(Vec3::ZERO, f32::NAN))
}

/// An unused plane cache entry (never hit), to fill storage arrays with.
#[must_use]
pub fn empty_plane() -> FocalPlane {
    FocalPlane::new(Vec3::ZERO, &Plane::new(Vec3::ZERO, Vec3::ZERO))
}

/// Why a frame cannot be set up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetupError {
    /// More than [`MAX_PARTS`] mesh parts.
    TooManyParts,
    /// A part's triangles lie outside the scene's index triples.
    BadPart,
    /// Too few sphere entries in the storage.
    SphereStorage,
    /// Too few plane entries in the storage.
    PlaneStorage,
    /// Too few triangle entries in the storage.
    TriangleStorage,
}

/// A rectangle of pixels: the unit of work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Tile {
    /// The whole image of a camera.
    #[must_use]
    pub fn all(camera: &Camera) -> Self {
        Tile {
            x: 0,
            y: 0,
            width: camera.width(),
            height: camera.height(),
        }
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// The tiles of size `tile_width × tile_height` (smaller at the right and bottom edges) that
/// cover a `width × height` image, row by row. Widths that are multiples of the lane count
/// waste no lanes.
pub fn tiles(
    width: u32,
    height: u32,
    tile_width: u32,
    tile_height: u32,
) -> impl Iterator<Item = Tile> {
    let (tw, th) = (tile_width.max(1), tile_height.max(1));
    (0..height.div_ceil(th)).flat_map(move |j| {
        (0..width.div_ceil(tw)).map(move |i| {
            let (x, y) = (i * tw, j * th);
            Tile {
                x,
                y,
                width: tw.min(width - x),
                height: th.min(height - y),
            }
        })
    })
}

/// Work counted while rendering, per ray lane (see the [module docs](self)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Primary rays (pixels).
    pub rays: u64,
    /// Ray–sphere tests.
    pub sphere_tests: u64,
    /// Ray–plane tests.
    pub plane_tests: u64,
    /// Ray–bounding-sphere tests of mesh parts.
    pub bound_tests: u64,
    /// Ray–triangle tests run.
    pub triangle_tests: u64,
    /// Ray–triangle tests skipped because a packet missed a part's bounding sphere.
    pub triangle_tests_saved: u64,
}

impl Stats {
    /// Every ray–primitive test run (spheres, planes, bounding spheres, triangles).
    #[must_use]
    pub fn tests(&self) -> u64 {
        self.sphere_tests + self.plane_tests + self.bound_tests + self.triangle_tests
    }

    /// Adds `o` to `self`.
    pub fn add(&mut self, o: &Stats) {
        self.rays += o.rays;
        self.sphere_tests += o.sphere_tests;
        self.plane_tests += o.plane_tests;
        self.bound_tests += o.bound_tests;
        self.triangle_tests += o.triangle_tests;
        self.triangle_tests_saved += o.triangle_tests_saved;
    }
}

/// One mesh part, ready to render.
#[derive(Clone, Copy, Debug)]
struct Piece<'a> {
    mesh: Mesh<'a>,
    focal: Option<FocalMesh<'a>>,
    paint: Paint,
    cull: Cull,
}

/// A scene seen by one camera with one sphere method, its caches built (see the
/// [module docs](self)). Shared by reference between the threads that render its tiles.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    scene: Scene<'a>,
    camera: Camera,
    method: Method,
    spheres: &'a [FocalSphere<f32>],
    planes: &'a [FocalPlane],
    pieces: [Option<Piece<'a>>; MAX_PARTS],
}

/// What is hit in each lane of a packet, merged over the kinds of primitive.
#[derive(Clone, Copy, Debug)]
struct Best {
    t: [f32; MAX_LANES],
    id: [u8; MAX_LANES],
    /// Sphere, plane or triangle index (within its part).
    index: [u32; MAX_LANES],
    part: [u8; MAX_LANES],
}

impl Best {
    fn new() -> Self {
        Best {
            t: [f32::INFINITY; MAX_LANES],
            id: [ID_NONE; MAX_LANES],
            index: [0; MAX_LANES],
            part: [0; MAX_LANES],
        }
    }

    /// Takes the lanes of `h` that are strictly closer.
    fn merge<L: Lane<Scalar = f32>>(&mut self, h: &Hit<L>, id: u8, part: u8) {
        let mut bits = h.mask.bits();
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let t = h.t.lane(i);
            if i < MAX_LANES && t < self.t[i] {
                self.t[i] = t;
                self.id[i] = id;
                self.index[i] = h.index.as_ref().get(i).copied().unwrap_or(0);
                self.part[i] = part;
            }
        }
    }

    /// The rays with `t_max` relaxed to the closest hit so far (as the closest-hit loops do).
    fn shrink<L: Lane<Scalar = f32>>(&self, rays: &RayPacket<L>) -> RayPacket<L> {
        let mut hit = L::Mask::splat(false);
        for i in 0..L::LANES.min(MAX_LANES) {
            if self.id[i] != ID_NONE {
                hit = hit.with_lane(i, true);
            }
        }
        let t = L::from_f32_fn(|i| {
            let t = self.t[i.min(MAX_LANES - 1)];
            t + f32::from_bits(t.to_bits() & 0x7fff_ffff) * (1.0 / 2_097_152.0)
        });
        rays.shrink(hit, t)
    }
}

/// Valid lanes of a packet.
fn count<L: Lane>(rays: &RayPacket<L>) -> u64 {
    u64::from(rays.valid().bits().count_ones())
}

impl<'a> Frame<'a> {
    /// Sets up `scene` for `camera` and `method`: builds the focal caches in `storage`
    /// (pinhole cameras) and each part's bounding sphere.
    pub fn new(
        scene: Scene<'a>,
        camera: Camera,
        method: Method,
        storage: Storage<'a>,
    ) -> Result<Self, SetupError> {
        if scene.parts.len() > MAX_PARTS {
            return Err(SetupError::TooManyParts);
        }
        let eye = match camera {
            Camera::Pinhole(p) => Some(p.eye),
            Camera::Ortho(_) => None,
        };
        let Storage {
            spheres: sphere_store,
            planes: plane_store,
            triangles: mut tri_store,
        } = storage;
        let spheres: &'a [FocalSphere<f32>] = match (eye, method) {
            (Some(e), Method::Focal | Method::FocalUnguarded) => {
                let out = sphere_store
                    .get_mut(..scene.spheres.len())
                    .ok_or(SetupError::SphereStorage)?;
                for (o, s) in out.iter_mut().zip(scene.spheres) {
                    *o = if method == Method::Focal {
                        FocalSphere::new(e, s)
                    } else {
                        FocalSphere::unguarded(e, s)
                    };
                }
                out
            }
            _ => &[],
        };
        let planes: &'a [FocalPlane] = match eye {
            Some(e) => {
                let out = plane_store
                    .get_mut(..scene.planes.len())
                    .ok_or(SetupError::PlaneStorage)?;
                for (o, p) in out.iter_mut().zip(scene.planes) {
                    *o = FocalPlane::new(e, p);
                }
                out
            }
            None => &[],
        };
        let mut pieces = [None; MAX_PARTS];
        for (slot, part) in pieces.iter_mut().zip(scene.parts) {
            let (first, n) = (part.first as usize, part.count as usize);
            let indices = scene
                .indices
                .get(first..first.saturating_add(n))
                .ok_or(SetupError::BadPart)?;
            let mesh = Mesh::bounded(scene.positions, indices);
            let focal = match eye {
                Some(e) => {
                    let (head, rest) = core::mem::take(&mut tri_store)
                        .split_at_mut_checked(n)
                        .ok_or(SetupError::TriangleStorage)?;
                    tri_store = rest;
                    Some(
                        mesh.focus(e, head)
                            .map_err(|_| SetupError::TriangleStorage)?,
                    )
                }
                None => None,
            };
            *slot = Some(Piece {
                mesh,
                focal,
                paint: part.paint,
                cull: part.cull,
            });
        }
        Ok(Frame {
            scene,
            camera,
            method,
            spheres,
            planes,
            pieces,
        })
    }

    /// The camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> &Scene<'a> {
        &self.scene
    }

    /// The sphere method.
    #[must_use]
    pub fn method(&self) -> Method {
        self.method
    }

    /// Renders the whole image into `rgb` (`3·width·height` bytes) and, if given, `ids`
    /// (`width·height` bytes).
    pub fn render<L: Lane<Scalar = f32>>(&self, rgb: &mut [u8], ids: Option<&mut [u8]>) -> Stats {
        self.render_tile::<L>(Tile::all(&self.camera), rgb, ids)
    }

    /// Renders `tile` (clipped to the image) with `L::LANES` rays per packet into `rgb`
    /// (`3·tile.width·tile.height` bytes, row-major within the tile) and, if given, `ids`
    /// (one byte per pixel). Pixels that do not fit the buffers are skipped.
    pub fn render_tile<L: Lane<Scalar = f32>>(
        &self,
        tile: Tile,
        rgb: &mut [u8],
        mut ids: Option<&mut [u8]>,
    ) -> Stats {
        let mut stats = Stats::default();
        let x_end = tile.x.saturating_add(tile.width).min(self.camera.width());
        let y_end = tile.y.saturating_add(tile.height).min(self.camera.height());
        let lanes = L::LANES.min(MAX_LANES);
        for y in tile.y..y_end {
            let mut x = tile.x;
            while x < x_end {
                let mut rays = self.camera.row_packet::<L>(x, y);
                // Lanes past the tile: empty interval, never hit, not counted.
                let n = ((x_end - x) as usize).min(lanes);
                if n < L::LANES {
                    let mut outside = L::Mask::splat(false);
                    for i in n..L::LANES {
                        outside = outside.with_lane(i, true);
                    }
                    rays = rays.shrink(outside, L::from_f32(0.0));
                }
                let best = self.trace(&rays, &mut stats);
                for i in 0..n {
                    let px =
                        (y - tile.y) as usize * tile.width as usize + (x - tile.x) as usize + i;
                    let (o, d) = (rays.origin().lane(i), rays.dir().lane(i));
                    let c = self.shade(o, d, &best, i);
                    if let Some(out) = rgb.get_mut(3 * px..3 * px + 3) {
                        out.copy_from_slice(&c);
                    }
                    if let Some(slot) = ids.as_deref_mut().and_then(|b| b.get_mut(px)) {
                        *slot = best.id[i];
                    }
                }
                x = x.saturating_add(lanes as u32);
            }
        }
        stats
    }

    /// The closest hit of each lane over every primitive. (Each kind of primitive is traced by
    /// its own out-of-line function: smaller functions, much quicker to compile for every lane
    /// width.)
    fn trace<L: Lane<Scalar = f32>>(&self, rays: &RayPacket<L>, stats: &mut Stats) -> Best {
        crate::lane::assert_fits::<L>();
        let k = count(rays);
        stats.rays += k;
        let mut best = Best::new();
        // 1. Spheres, with the frame's method.
        if !self.scene.spheres.is_empty() {
            stats.sphere_tests += k * self.scene.spheres.len() as u64;
            best.merge(&self.spheres::<L>(rays), ID_SPHERE, 0);
        }
        // 2. Planes.
        if !self.scene.planes.is_empty() {
            stats.plane_tests += k * self.scene.planes.len() as u64;
            let r = best.shrink(rays);
            let h = match self.camera {
                Camera::Pinhole(_) => plane::closest_focal(&r, self.planes),
                Camera::Ortho(_) => plane::closest(&r, self.scene.planes),
            };
            best.merge(&h, ID_PLANE, 0);
        }
        // 3. Mesh parts: the bounding sphere first, then the triangles.
        if self.pieces[0].is_some() {
            self.meshes(&best.shrink(rays), k, stats, &mut best);
        }
        best
    }

    /// The closest sphere hit with the frame's method.
    #[inline(never)]
    fn spheres<L: Lane<Scalar = f32>>(&self, rays: &RayPacket<L>) -> Hit<L> {
        let s = self.scene.spheres;
        match (self.method, self.camera) {
            (Method::Focal, Camera::Pinhole(_)) => sf::closest::<Focal, L>(rays, self.spheres),
            (Method::FocalUnguarded, Camera::Pinhole(_)) => {
                sf::closest::<FocalUnguarded, L>(rays, self.spheres)
            }
            (Method::Focal, Camera::Ortho(_)) => self.focal_per_ray::<Focal, L>(rays, true),
            (Method::FocalUnguarded, Camera::Ortho(_)) => {
                self.focal_per_ray::<FocalUnguarded, L>(rays, false)
            }
            (Method::Quadratic, _) => closest_spheres::<Quadratic, L>(rays, s),
            (Method::QuadraticUnit, _) => closest_spheres::<QuadraticUnit, L>(rays, s),
            (Method::Geometric, _) => closest_spheres::<Geometric, L>(rays, s),
            (Method::Robust, _) => closest_spheres::<Robust, L>(rays, s),
        }
    }

    /// Every mesh part: the bounding sphere, then (unless the packet misses it) the triangles.
    #[inline(never)]
    fn meshes<L: Lane<Scalar = f32>>(
        &self,
        r: &RayPacket<L>,
        k: u64,
        stats: &mut Stats,
        best: &mut Best,
    ) {
        let fr = matches!(self.camera, Camera::Pinhole(_)).then(|| FocalRays::new(r));
        for (p, piece) in self.pieces.iter().enumerate() {
            let Some(piece) = piece else { break };
            let tris = k * piece.mesh.len() as u64;
            stats.bound_tests += k;
            let h = match (&fr, &piece.focal) {
                (Some(fr), Some(fm)) => fm.try_closest(fr, piece.cull),
                _ => closest_triangles::<L>(&piece.mesh, r, piece.cull),
            };
            let Some(h) = h else {
                stats.triangle_tests_saved += tris;
                continue;
            };
            stats.triangle_tests += tris;
            best.merge(&h, ID_TRIANGLE, p as u8);
        }
    }

    /// Spheres for rays with different origins: one focal cache entry per ray and sphere, with
    /// the ray's own origin as the eye, gathered into lanes.
    #[inline(never)]
    fn focal_per_ray<K: FocalKernel, L: Lane<Scalar = f32>>(
        &self,
        rays: &RayPacket<L>,
        guarded: bool,
    ) -> Hit<L> {
        let mut best = Hit::<L>::none();
        crate::lane::assert_fits::<L>();
        let mut entries = [empty_sphere(); MAX_LANES];
        for (j, s) in self.scene.spheres.iter().enumerate() {
            for (i, e) in entries.iter_mut().enumerate().take(L::LANES) {
                let o = rays.origin().lane(i);
                *e = if guarded {
                    FocalSphere::new(o, s)
                } else {
                    FocalSphere::unguarded(o, s)
                };
            }
            let cache = FocalSphere::<L>::gather(&entries[..L::LANES.min(MAX_LANES)]);
            let h = K::roots(rays, &cache).first();
            let take = h.mask & h.t.lt(best.t);
            best.t = L::select(take, h.t, best.t);
            best.mask = best.mask | take;
            let mut bits = take.bits();
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if let Some(slot) = best.index.as_mut().get_mut(i) {
                    *slot = j as u32;
                }
            }
        }
        best
    }

    /// The colour of lane `i` (origin `o`, direction `d`), as RGB8.
    fn shade(&self, o: Vec3, d: Vec3, best: &Best, i: usize) -> [u8; 3] {
        let (o, d) = (V3::<f32>::from(o), V3::<f32>::from(d));
        let grey = Paint::Flat([0.7; 3]);
        let t = best.t[i];
        let p = o + d.scale(t);
        let (n, paint) = match best.id[i] {
            ID_SPHERE => {
                let j = best.index[i] as usize;
                let Some(s) = self.scene.spheres.get(j) else {
                    return to_rgb(sky(d));
                };
                let paint = self.scene.sphere_paints.get(j).copied().unwrap_or(grey);
                ((p - V3::from(s.center())).div_by(s.radius()), paint)
            }
            ID_PLANE => {
                let j = best.index[i] as usize;
                let Some(pl) = self.scene.planes.get(j) else {
                    return to_rgb(sky(d));
                };
                let paint = self.scene.plane_paints.get(j).copied().unwrap_or(grey);
                (V3::from(unit(pl.normal)), paint)
            }
            ID_TRIANGLE => {
                let piece = self.pieces.get(best.part[i] as usize).copied().flatten();
                let tri = piece.and_then(|pc| pc.mesh.triangle(best.index[i] as usize));
                let (Some(pc), Some(tri)) = (piece, tri) else {
                    return to_rgb(sky(d));
                };
                let (a, b, c) = (V3::from(tri.a()), V3::from(tri.b()), V3::from(tri.c()));
                let n = V3::from(unit((b - a).cross(c - a).into()));
                (n, pc.paint)
            }
            _ => return to_rgb(sky(d)),
        };
        // Face the viewer.
        let n = if n.dot(d) > 0.0 { -n } else { n };
        let base = match paint {
            Paint::Flat(c) => c,
            Paint::Checker { a, b, size } => {
                if floor(p.x / size).wrapping_add(floor(p.z / size)) & 1 == 0 {
                    a
                } else {
                    b
                }
            }
            Paint::Normal => {
                // The usual normal-map colours, stored as they are (no gamma).
                let c = |x: f32| ((x * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                return [c(n.x), c(n.y), c(n.z)];
            }
        };
        let lambert = n.dot(self.scene.light.into()).max(0.0);
        let k = 0.2 + 0.8 * lambert;
        to_rgb([base[0] * k, base[1] * k, base[2] * k])
    }
}

/// [`sphere::closest`] out of line.
#[inline(never)]
fn closest_spheres<K: SphereKernel, L: Lane>(rays: &RayPacket<L>, s: &[Sphere]) -> Hit<L> {
    sphere::closest::<K, L>(rays, s)
}

/// [`Mesh::try_closest`] with [`Watertight`], out of line.
#[inline(never)]
fn closest_triangles<L: Lane>(mesh: &Mesh, rays: &RayPacket<L>, cull: Cull) -> Option<Hit<L>> {
    mesh.try_closest::<Watertight, L>(rays, cull)
}

/// `⌊x⌋` by truncation (exact), saturating.
fn floor(x: f32) -> i32 {
    let i = x as i32;
    if (i as f32) > x { i.wrapping_sub(1) } else { i }
}

/// The sky for a ray that hits nothing: white at the horizon to blue overhead.
fn sky(d: V3<f32>) -> [f32; 3] {
    let a = d.y.max(0.0);
    let b = 1.0 - a;
    [0.95 * b + 0.35 * a, 0.97 * b + 0.55 * a, 1.0 * b + 0.9 * a]
}

/// Linear RGB in `[0, 1]` to RGB8 with a gamma of 2 (a square root).
fn to_rgb(c: [f32; 3]) -> [u8; 3] {
    c.map(|x| (sqrt_f32(x.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
}

/// FNV-1a (64 bits) of `bytes`: the digest the tests pin and the firmware prints.
#[must_use]
pub fn fnv1a(bytes: &[u8]) -> u64 {
    use core::hash::Hasher;
    let mut h = fnv::FnvHasher::default();
    h.write(bytes);
    h.finish()
}

/// Writes the header of a binary PPM (`P6`) image of `width × height` RGB8 pixels into `out`
/// and returns its length (at most 27 bytes), or `None` when `out` is too short. The host and
/// the firmware write the same bytes.
pub fn ppm_header(width: u32, height: u32, out: &mut [u8]) -> Option<usize> {
    let mut n = 0;
    let mut put = |b: u8| -> Option<()> {
        *out.get_mut(n)? = b;
        n += 1;
        Some(())
    };
    for &b in b"P6\n" {
        put(b)?;
    }
    for (v, end) in [(width, b' '), (height, b'\n'), (255, b'\n')] {
        let mut digits = [0u8; 10];
        let (mut v, mut k) = (v, 0);
        loop {
            digits[k] = b'0' + (v % 10) as u8;
            k += 1;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        for &dg in digits[..k].iter().rev() {
            put(dg)?;
        }
        put(end)?;
    }
    Some(n)
}
