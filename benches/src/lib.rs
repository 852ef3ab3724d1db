//! Benchmarks of raylane: seeded scenes shared by every contender, every kernel behind one
//! dispatcher, and (feature `peers`) the peer libraries on the same data.
//!
//! * [`scene`]: the generators (no_std; the firmware's instruction counts include the file).
//! * [`Frame`]: one scene of N primitives of each kind (spheres, triangles, planes, and their
//!   focal caches) with one set of rays; [`Lanes`] the same data packed for one lane width.
//! * [`Kernel`] (raylane's registry), [`Shape`] and [`run`]: every raylane kernel at every width in either packet
//!   shape (N rays × 1 primitive: ray packets over a slice; 1 ray × N primitives: one ray over
//!   primitives packed in lanes), each frame one out-of-line function ([`packets_frame`],
//!   [`soa_frame`]) so that timings do not depend on how a closure happens to be inlined.
//! * [`answers`]: the closest hit of every ray, to check contenders against each other.
//! * [`parts`]: the triangles in parts of 16 with bounding spheres (raylane's answer to a BVH).
//! * `peers` (feature): parry3d, bevy, obvhs and Embree on a [`Frame`].

use std::hint::black_box;

use glam::Vec3;
use raylane::Cull;
use raylane::focal::{FocalMesh, FocalPlanes, FocalSpheres};
use raylane::mesh::Mesh;
use raylane::plane::{FocalPlane, Plane, PlanePacket};
use raylane::set::Trace;
use raylane::sphere::focal::{self as sf, FocalKernel};
use raylane::sphere::{FocalSphere, Sphere, SphereKernel, SpherePacket};
use raylane::triangle::{FocalTriangle, Triangle, TriangleKernel, TrianglePacket};
use raylane::{Hit, Hits, Lane, Mask, Pinhole, Query, Ray, RayPacket};
use raylane_lab::loops as internals;
use raylane_lab::loops::HitRecord;
use raylane_lab::loops::{Best, LaneRecords};

pub mod bvh_raylane;
pub mod meshes;
pub mod parts;
pub mod scene;
pub mod subdivide;

#[cfg(feature = "peers")]
pub mod bvh_peers;
#[cfg(feature = "peers")]
pub mod embree;
#[cfg(feature = "peers")]
pub mod peers;

pub use scene::Rng;

/// The scene of the guarded-vs-unguarded focal bench (issue 2; `benches/focal.rs` and the
/// examples `focal_time` and `doubtful`): 8-ray packets of primary rays of a 128 × 96 camera
/// over `n` spheres (seed 7), with both focal caches.
pub struct GuardScene {
    /// The camera.
    pub cam: Pinhole,
    /// Its primary rays, 8 to a packet, row by row.
    pub packets: Vec<raylane::Ray8>,
    /// Guarded caches.
    pub guarded: Vec<FocalSphere<f32>>,
    /// Unguarded caches.
    pub unguarded: Vec<FocalSphere<f32>>,
}

impl GuardScene {
    /// The scene of `n` spheres.
    pub fn new(n: usize) -> Self {
        let (cam, spheres) = sphere_scene(n, 7, 128, 96);
        let packets = (0..cam.height)
            .flat_map(|y| (0..cam.width).step_by(8).map(move |x| (x, y)))
            .map(|(x, y)| cam.row_packet(x, y))
            .collect();
        let cache = |f: fn(Vec3, &Sphere) -> FocalSphere<f32>| {
            spheres.iter().map(|s| f(cam.eye, s)).collect()
        };
        GuardScene {
            packets,
            guarded: cache(FocalSphere::new),
            unguarded: cache(FocalSphere::unguarded),
            cam,
        }
    }

    /// Ray–sphere tests per frame.
    pub fn tests(&self) -> usize {
        self.packets.len() * 8 * self.guarded.len()
    }
}

/// One frame of the guard scene: the closest hit of every packet over `cache` with kernel `K`;
/// returns the number of lanes hit. Out of line, so both variants are compiled once and the
/// comparison does not depend on how a closure happens to be inlined and placed.
#[inline(never)]
pub fn guard_frame<K: sf::FocalKernel>(
    packets: &[raylane::Ray8],
    cache: &[FocalSphere<f32>],
) -> u32 {
    packets
        .iter()
        .map(|p| {
            internals::sphere::focal::closest::<K, _>(black_box(p), cache)
                .mask
                .bits()
                .count_ones()
        })
        .sum()
}

/// `n` spheres, seed `seed`, a `width × height` camera (kept bit for bit as it was, so the
/// guard bench's numbers stay comparable).
fn sphere_scene(n: usize, seed: u64, width: u32, height: u32) -> (Pinhole, Vec<Sphere>) {
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

/// Scene sizes (primitives of each kind).
pub const SIZES: [usize; 4] = [16, 64, 256, 1024];

/// Ray–primitive tests per frame: the image shrinks as N grows so that every frame does
/// about the same work (N = 16: 128 × 128 rays; 1024: 16 × 16).
pub const TESTS_PER_FRAME: usize = 1 << 18;

/// The side of the square image for scenes of `n` primitives (a multiple of 16).
pub fn image_side(n: usize) -> u32 {
    let side = ((TESTS_PER_FRAME / n.max(1)) as f64).sqrt() as u32;
    (side / 16).max(1) * 16
}

/// Which rays a frame shoots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rays {
    /// Primary rays of the pinhole camera, one per pixel, row by row (one focal point).
    Coherent,
    /// Random origins and directions ([`scene::random_rays`]), none starting inside a sphere.
    Incoherent,
    /// The coherent rays whose lines clearly miss every sphere and every triangle of the
    /// scene: every test takes its kernel's miss path (instruction counts).
    Miss,
}

impl Rays {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Rays::Coherent => "coherent",
            Rays::Incoherent => "incoherent",
            Rays::Miss => "miss",
        }
    }
}

/// One scene: `n` primitives of each kind, their focal caches for the camera's eye, and rays.
pub struct Frame {
    /// Primitives of each kind.
    pub n: usize,
    /// Which rays.
    pub kind: Rays,
    /// The camera (its eye is every coherent ray's origin).
    pub cam: Pinhole,
    /// The rays, row by row for coherent ones.
    pub rays: Vec<Ray>,
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Guarded focal caches of the spheres.
    pub focal_spheres: Vec<FocalSphere<f32>>,
    /// Unguarded focal caches of the spheres.
    pub unguarded: Vec<FocalSphere<f32>>,
    /// Triangles.
    pub tris: Vec<Triangle>,
    /// Focal caches of the triangles.
    pub focal_tris: Vec<FocalTriangle<f32>>,
    /// Planes.
    pub planes: Vec<Plane>,
    /// Focal caches of the planes.
    pub focal_planes: Vec<FocalPlane>,
}

impl Frame {
    /// The scene of `n` primitives of each kind seen by an `image_side(n)²` camera.
    pub fn new(n: usize, kind: Rays) -> Self {
        let side = image_side(n);
        Self::with_image(n, kind, side, side)
    }

    /// The scene of `n` primitives with a `width × height` camera (and as many incoherent
    /// rays as pixels).
    pub fn with_image(n: usize, kind: Rays, width: u32, height: u32) -> Self {
        let cam = scene::camera(width, height);
        let aspect = height as f32 / width as f32;
        let spheres: Vec<Sphere> = scene::spheres(scene::SPHERE_SEED, aspect).take(n).collect();
        let tris: Vec<Triangle> = scene::triangles(scene::TRIANGLE_SEED, aspect)
            .take(n)
            .collect();
        let planes: Vec<Plane> = scene::planes(scene::PLANE_SEED, aspect).take(n).collect();
        let pixels =
            || (0..height).flat_map(move |y| (0..width).map(move |x| scene::pixel_ray(&cam, x, y)));
        let rays: Vec<Ray> = match kind {
            Rays::Coherent => pixels().collect(),
            Rays::Incoherent => scene::random_rays(scene::RAY_SEED, aspect)
                .filter(|r| {
                    spheres
                        .iter()
                        .all(|s| (r.origin() - s.center()).length() > s.radius() * 1.01)
                })
                .take((width * height) as usize)
                .collect(),
            Rays::Miss => {
                let mut rays: Vec<Ray> = pixels()
                    .filter(|r| {
                        spheres.iter().all(|s| scene::line_misses_sphere(r, s))
                            && tris.iter().all(|t| scene::line_misses_triangle(r, t))
                    })
                    .collect();
                rays.truncate(rays.len() / 16 * 16); // whole packets at every width
                rays
            }
        };
        let eye = cam.eye;
        Frame {
            n,
            kind,
            cam,
            rays,
            focal_spheres: spheres.iter().map(|s| FocalSphere::new(eye, s)).collect(),
            unguarded: spheres
                .iter()
                .map(|s| FocalSphere::unguarded(eye, s))
                .collect(),
            focal_tris: tris.iter().map(|t| FocalTriangle::new(eye, t)).collect(),
            focal_planes: planes.iter().map(|p| FocalPlane::new(eye, p)).collect(),
            spheres,
            tris,
            planes,
        }
    }

    /// Ray–primitive tests of one frame (every ray against every primitive of one kind).
    pub fn tests(&self) -> usize {
        self.rays.len() * self.n
    }
}

/// A frame's data packed for lane type `L`: ray packets (N rays × 1 primitive) and primitives
/// in lanes (1 ray × N primitives), `used` primitives of each kind.
pub struct Lanes<L: Lane> {
    /// The rays, `L::LANES` to a packet.
    pub packets: Vec<RayPacket<L>>,
    /// Spheres in lanes.
    pub spheres: Vec<SpherePacket<L>>,
    /// Guarded focal caches in lanes.
    pub focal_spheres: Vec<FocalSphere<L>>,
    /// Unguarded focal caches in lanes.
    pub unguarded: Vec<FocalSphere<L>>,
    /// Triangles in lanes.
    pub tris: Vec<TrianglePacket<L>>,
    /// Triangle focal caches in lanes.
    pub focal_tris: Vec<FocalTriangle<L>>,
    /// Planes in lanes.
    pub planes: Vec<PlanePacket<L>>,
    /// Primitives of each kind in use (the first `used` of the frame's).
    pub used: usize,
}

fn packed<T: Copy, P: Copy>(
    items: &[T],
    lanes: usize,
    dummy: P,
    pack: impl Fn(&[T], &mut [P]) -> usize,
) -> Vec<P> {
    let mut out = vec![dummy; items.len().div_ceil(lanes)];
    let n = pack(items, &mut out);
    out.truncate(n);
    out
}

impl<L: Lane> Lanes<L> {
    /// Packs `frame` using its first `used` primitives of each kind (0 for the baseline runs
    /// of the instruction counts).
    pub fn new(frame: &Frame, used: usize) -> Self {
        let used = used.min(frame.n);
        let w = L::LANES;
        let nan = Sphere::new(Vec3::ZERO, f32::NAN);
        let never = FocalSphere::gather(&[]);
        Lanes {
            packets: frame.rays.chunks(w).map(RayPacket::from_rays).collect(),
            spheres: packed(
                &frame.spheres[..used],
                w,
                SpherePacket::splat(&nan),
                SpherePacket::pack,
            ),
            focal_spheres: packed(&frame.focal_spheres[..used], w, never, FocalSphere::pack),
            unguarded: packed(&frame.unguarded[..used], w, never, FocalSphere::pack),
            tris: packed(
                &frame.tris[..used],
                w,
                TrianglePacket::splat(&Triangle::never()),
                TrianglePacket::pack,
            ),
            focal_tris: packed(
                &frame.focal_tris[..used],
                w,
                FocalTriangle::gather(&[]),
                FocalTriangle::pack,
            ),
            planes: frame.planes[..used]
                .chunks(w)
                .map(PlanePacket::from_planes)
                .collect(),
            used,
        }
    }
}

pub use raylane_lab::registry::{Kernel, Prim};

/// What the benchmarks need to know about a kernel of the registry, beyond its metadata.
pub trait BenchKernel {
    /// True when the kernel can run on `rays` (focal kernels need rays from the eye).
    fn runs_on(self, rays: Rays) -> bool;
    /// True when the kernel has the 1 ray × N primitives shape (the focal plane has none).
    fn has_soa(self) -> bool;
    /// True when the library has a public set for the kernel, which the packet shape then
    /// queries; false for the unguarded focal sphere (the lab's loop).
    fn has_query(self) -> bool;
    /// Primitive fields the miss path must read per test (the loads of the op-count
    /// minimum): a sphere's centre and radius (4), a focal sphere's `T` and `k_lo` (4), a
    /// plane's point and normal (6), a focal plane's numerator and normal (4), a triangle's
    /// vertices (9; the precomputed methods build their record from them per test here), a
    /// focal triangle's three edge normals and their three bounds (12).
    fn miss_loads(self) -> u32;
}

impl BenchKernel for Kernel {
    fn runs_on(self, rays: Rays) -> bool {
        !self.is_focal() || rays != Rays::Incoherent
    }

    fn has_soa(self) -> bool {
        self != Kernel::PlaneFocal
    }

    fn has_query(self) -> bool {
        self != Kernel::FocalUnguarded
    }

    fn miss_loads(self) -> u32 {
        match self.prim() {
            Prim::Sphere => 4,
            Prim::Plane if self.is_focal() => 4,
            Prim::Plane => 6,
            Prim::Triangle if self.is_focal() => 12,
            Prim::Triangle => 9,
        }
    }
}

/// The two packet shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// N rays × 1 primitive: what a user calls, the library's [`Query`] (`closest`) on the
    /// kernel's set — a slice with `using::<K>()`, or a focal cache — for one [`Ray`] (x1) or a
    /// packet of `L::LANES` rays. Kernels without a public set (the study's precomputed
    /// triangle methods, the unguarded focal sphere) run the lab's loop instead
    /// ([`Kernel::has_query`]).
    Packets,
    /// 1 ray × N primitives: one ray splatted, primitives packed `L::LANES` to a lane value
    /// (the lab's loop: the kernel alone, for the op-count study).
    Soa,
}

impl Shape {
    /// Short name (`""` for packets, `"-soa"` for the other shape), as a suffix of `xW`.
    pub fn suffix(self) -> &'static str {
        match self {
            Shape::Packets => "",
            Shape::Soa => "-soa",
        }
    }
}

/// What a frame's query returns, reduced to what the benchmarks read.
pub trait Answer {
    /// The lanes (or the ray) that hit.
    fn hits(&self) -> u32;
    /// Lane `i` as a record.
    fn record(&self, i: usize) -> Option<HitRecord>;
}

impl<L: Lane<Scalar = f32>> Answer for Hits<L> {
    #[inline(always)]
    fn hits(&self) -> u32 {
        self.mask.bits().count_ones()
    }
    fn record(&self, i: usize) -> Option<HitRecord> {
        self.lane(i).map(|h| HitRecord {
            t: h.t,
            u: h.u,
            v: h.v,
            index: h.index,
        })
    }
}

impl<L: Lane<Scalar = f32>> Answer for Best<L> {
    #[inline(always)]
    fn hits(&self) -> u32 {
        self.mask.bits().count_ones()
    }
    fn record(&self, i: usize) -> Option<HitRecord> {
        LaneRecords::lane(self, i)
    }
}

impl Answer for Option<Hit> {
    #[inline(always)]
    fn hits(&self) -> u32 {
        self.is_some() as u32
    }
    fn record(&self, _: usize) -> Option<HitRecord> {
        self.map(|h| HitRecord {
            t: h.t,
            u: h.u,
            v: h.v,
            index: h.index,
        })
    }
}

impl Answer for Option<HitRecord> {
    #[inline(always)]
    fn hits(&self) -> u32 {
        self.is_some() as u32
    }
    fn record(&self, _: usize) -> Option<HitRecord> {
        *self
    }
}

/// One frame of closest-hit queries of ray packets; returns the number of lanes hit. Out of
/// line, one copy per kernel and width (the closure is inlined into it).
#[inline(never)]
pub fn packets_frame<L: Lane, A: Answer, F: Fn(&RayPacket<L>) -> A>(
    packets: &[RayPacket<L>],
    f: F,
) -> u32 {
    let mut n = 0;
    for p in packets {
        let h = f(black_box(p));
        n += h.hits();
        black_box(&h);
    }
    n
}

/// One frame of closest-hit queries of single rays (one [`Ray`] through the library's query,
/// or one ray over primitives in lanes); returns the number of rays hit. Out of line, one
/// copy per kernel and width.
#[inline(never)]
pub fn rays_frame<A: Answer, F: Fn(&Ray) -> A>(rays: &[Ray], f: F) -> u32 {
    let mut n = 0;
    for r in rays {
        let h = f(black_box(r));
        n += h.hits();
        black_box(&h);
    }
    n
}

/// A frame's primitives as the library's sets: the focal caches for the camera's eye (built
/// here, not in a frame: set-up is not timed) and the triangle soup as a mesh.
pub struct Sets {
    cache_spheres: Vec<FocalSphere<f32>>,
    cache_tris: Vec<FocalTriangle<f32>>,
    cache_planes: Vec<FocalPlane>,
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
}

impl Sets {
    /// Storage for the sets over the first `used` primitives of `frame`.
    pub fn new(frame: &Frame, used: usize) -> Self {
        let tris = &frame.tris[..used];
        Sets {
            cache_spheres: vec![FocalSphere::gather(&[]); used],
            cache_tris: vec![FocalTriangle::never(); used],
            cache_planes: vec![FocalPlane::new(Vec3::ZERO, &Plane::new(Vec3::ZERO, Vec3::Z)); used],
            positions: tris.iter().flat_map(|t| [t.a(), t.b(), t.c()]).collect(),
            indices: (0..tris.len() as u32)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .collect(),
        }
    }
}

/// Code run with one kernel's two queries: `set`, the library's set of the kernel over the
/// frame's primitives (the first `used`), or `None` when the kernel has no public set; then
/// `packets`, the lab's N rays × 1 primitive loop (the kernel alone), and `soa`, the closest
/// hit of one ray over the primitives packed in lanes.
pub trait WithKernel<L: Lane> {
    /// What it returns.
    type Output;
    /// Runs with the kernel's queries.
    fn run<T: Trace + ?Sized>(
        self,
        set: Option<&T>,
        packets: impl Fn(&RayPacket<L>) -> Best<L>,
        soa: impl Fn(&Ray) -> Option<HitRecord>,
    ) -> Self::Output;
}

/// The [`raylane_lab::registry::Visitor`] that binds a kernel's queries over a frame and its lanes
/// and hands them to a [`WithKernel`].
struct Queries<'a, L: Lane, B> {
    frame: &'a Frame,
    lanes: &'a Lanes<L>,
    body: B,
}

impl<L: Lane<Scalar = f32>, B: WithKernel<L>> raylane_lab::registry::Visitor for Queries<'_, L, B> {
    type Output = B::Output;

    fn sphere<K: SphereKernel>(self, _: Kernel) -> B::Output {
        let (f, l, u) = (self.frame, self.lanes, self.lanes.used);
        self.body.run(
            Some(&f.spheres[..u].using::<K>()),
            |r| internals::sphere::closest::<K, _>(r, &f.spheres[..u]),
            |r| internals::sphere::closest_soa::<K, _>(r, &l.spheres),
        )
    }

    fn focal_sphere<K: FocalKernel>(self, _: Kernel, guarded: bool) -> B::Output {
        let (f, l, u) = (self.frame, self.lanes, self.lanes.used);
        let (cache, packed) = if guarded {
            (&f.focal_spheres, &l.focal_spheres)
        } else {
            (&f.unguarded, &l.unguarded)
        };
        // The library's focal spheres are the guarded cache (`FocalSpheres`); the unguarded
        // kernel, measured for the study, has no public set.
        let mut s = Sets::new(f, u);
        let set = guarded
            .then(|| FocalSpheres::new(&f.spheres[..u], f.cam.eye, &mut s.cache_spheres).ok())
            .flatten();
        self.body.run(
            set.as_ref(),
            |r| internals::sphere::focal::closest::<K, _>(r, &cache[..u]),
            |r| internals::sphere::focal::closest_soa::<K, _>(r, packed),
        )
    }

    fn plane(self, _: Kernel) -> B::Output {
        let (f, l, u) = (self.frame, self.lanes, self.lanes.used);
        self.body.run(
            Some(&f.planes[..u]),
            |r| internals::plane::closest(r, &f.planes[..u]),
            |r| internals::plane::closest_soa(r, &l.planes),
        )
    }

    fn focal_plane(self, _: Kernel) -> B::Output {
        let (f, u) = (self.frame, self.lanes.used);
        let mut s = Sets::new(f, u);
        let set = FocalPlanes::new(&f.planes[..u], f.cam.eye, &mut s.cache_planes).ok();
        // No 1 ray × N shape: the packet query of the ray splatted (not run).
        self.body.run(
            set.as_ref(),
            |r| internals::plane::closest_focal(r, &f.focal_planes[..u]),
            |r| {
                internals::plane::closest_focal(&RayPacket::<f32>::splat(r), &f.focal_planes[..u])
                    .lane(0)
            },
        )
    }

    fn triangle<K: TriangleKernel>(self, _: Kernel) -> B::Output {
        let (f, l, u) = (self.frame, self.lanes, self.lanes.used);
        self.body.run(
            Some(&f.tris[..u].using::<K>()),
            |r| internals::triangle::closest::<K, _>(r, &f.tris[..u], Cull::None),
            |r| internals::triangle::closest_soa::<K, _>(r, &l.tris, Cull::None),
        )
    }

    fn focal_triangle(self, _: Kernel) -> B::Output {
        let (f, l, u) = (self.frame, self.lanes, self.lanes.used);
        let mut s = Sets::new(f, u);
        let mesh = Mesh::new(&s.positions, &s.indices);
        let set = FocalMesh::new(&mesh, f.cam.eye, &mut s.cache_tris).ok();
        self.body.run(
            set.as_ref(),
            |r| internals::triangle::focal::closest(r, &f.focal_tris[..u], Cull::None),
            |r| internals::triangle::focal::closest_soa(r, &l.focal_tris, Cull::None),
        )
    }
}

/// Runs `body` with kernel `k`'s queries over `frame` and `lanes` (built from it).
pub fn with_kernel<L: Lane<Scalar = f32>, B: WithKernel<L>>(
    k: Kernel,
    frame: &Frame,
    lanes: &Lanes<L>,
    body: B,
) -> B::Output {
    k.visit(Queries { frame, lanes, body })
}

/// Runs one frame of kernel `k` in shape `shape` over `lanes` (built from `frame`); returns
/// the number of rays hit.
pub fn run<L: Lane<Scalar = f32>>(k: Kernel, shape: Shape, frame: &Frame, lanes: &Lanes<L>) -> u32 {
    struct Run<'a, L: Lane>(Shape, &'a Frame, &'a Lanes<L>);
    impl<L: Lane<Scalar = f32>> WithKernel<L> for Run<'_, L> {
        type Output = u32;
        fn run<T: Trace + ?Sized>(
            self,
            set: Option<&T>,
            p: impl Fn(&RayPacket<L>) -> Best<L>,
            s: impl Fn(&Ray) -> Option<HitRecord>,
        ) -> u32 {
            match (self.0, set) {
                (Shape::Packets, Some(set)) if L::LANES == 1 => {
                    rays_frame(&self.1.rays, |r| set.closest(r))
                }
                (Shape::Packets, Some(set)) => packets_frame(&self.2.packets, |r| set.closest(r)),
                (Shape::Packets, None) => packets_frame(&self.2.packets, p),
                (Shape::Soa, _) => rays_frame(&self.1.rays, s),
            }
        }
    }
    with_kernel(k, frame, lanes, Run(shape, frame, lanes))
}

/// The closest hit of every ray of `frame` with kernel `k` in shape `shape` (for checks).
pub fn answers<L: Lane<Scalar = f32>>(
    k: Kernel,
    shape: Shape,
    frame: &Frame,
    lanes: &Lanes<L>,
) -> Vec<Option<HitRecord>> {
    struct Answers<'a, L: Lane>(Shape, &'a Frame, &'a Lanes<L>);
    fn each<L: Lane, A: Answer>(
        packets: &[RayPacket<L>],
        rays: usize,
        f: impl Fn(&RayPacket<L>) -> A,
    ) -> Vec<Option<HitRecord>> {
        packets
            .iter()
            .flat_map(|r| {
                let h = f(r);
                (0..L::LANES).map(move |i| h.record(i))
            })
            .take(rays)
            .collect()
    }
    impl<L: Lane<Scalar = f32>> WithKernel<L> for Answers<'_, L> {
        type Output = Vec<Option<HitRecord>>;
        fn run<T: Trace + ?Sized>(
            self,
            set: Option<&T>,
            p: impl Fn(&RayPacket<L>) -> Best<L>,
            s: impl Fn(&Ray) -> Option<HitRecord>,
        ) -> Self::Output {
            let (rays, packets) = (&self.1.rays, &self.2.packets);
            match (self.0, set) {
                (Shape::Packets, Some(set)) if L::LANES == 1 => {
                    rays.iter().map(|r| set.closest(r).record(0)).collect()
                }
                (Shape::Packets, Some(set)) => each(packets, rays.len(), |r| set.closest(r)),
                (Shape::Packets, None) => each(packets, rays.len(), p),
                (Shape::Soa, _) => rays.iter().map(s).collect(),
            }
        }
    }
    with_kernel(k, frame, lanes, Answers(shape, frame, lanes))
}

/// The floating-point operations (mul, add, div, sqrt, cmp) of one frame of kernel `k` in the
/// packet shape over the first `used` primitives, counted with the op-counting lane
/// `Counted<f32>`: one ray at a time, so each ray takes its own path and no lane idles in a
/// packet. (Counts over N primitives minus counts over none, divided by the tests, are the
/// work per test the kernel's mathematics needs.)
pub fn frame_ops(k: Kernel, frame: &Frame, used: usize) -> raylane::opcount::OpCounts {
    use raylane::opcount::{Counted, measure};
    struct Count<'a>(&'a Lanes<Counted<f32>>);
    impl WithKernel<Counted<f32>> for Count<'_> {
        type Output = ();
        fn run<T: Trace + ?Sized>(
            self,
            _: Option<&T>,
            p: impl Fn(&RayPacket<Counted<f32>>) -> Best<Counted<f32>>,
            _: impl Fn(&Ray) -> Option<HitRecord>,
        ) {
            for r in &self.0.packets {
                black_box(p(r));
            }
        }
    }
    let lanes = Lanes::<Counted<f32>>::new(frame, used);
    measure(|| with_kernel(k, frame, &lanes, Count(&lanes))).1
}

/// Runs `$body` with `$L` bound to the lane type of width `$w` (1, 4, 8 or 16).
#[macro_export]
macro_rules! with_width {
    ($w:expr, $L:ident => $body:expr) => {
        match $w {
            1 => {
                type $L = f32;
                $body
            }
            4 => {
                type $L = wide::f32x4;
                $body
            }
            8 => {
                type $L = wide::f32x8;
                $body
            }
            16 => {
                type $L = wide::f32x16;
                $body
            }
            w => panic!("no lane width {w}"),
        }
    };
}

/// Lane widths.
pub const WIDTHS: [usize; 4] = [1, 4, 8, 16];

/// Compares two sets of answers: returns (hit/miss disagreements, largest relative difference
/// of `t` where both hit).
pub fn compare(a: &[Option<f32>], b: &[Option<f32>]) -> (usize, f64) {
    let mut bad = 0;
    let mut worst = 0f64;
    for (x, y) in a.iter().zip(b) {
        match (x, y) {
            (Some(s), Some(t)) => {
                let d = (*s as f64 - *t as f64).abs() / (*s as f64).abs().max(1e-30);
                worst = worst.max(d);
            }
            (None, None) => {}
            _ => bad += 1,
        }
    }
    bad += a.len().abs_diff(b.len());
    (bad, worst)
}

/// The CPU's model name and SIMD level (from /proc/cpuinfo).
pub fn cpu() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = info
        .lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split(':').nth(1))
        .map_or("unknown CPU".to_string(), |s| s.trim().to_string());
    let flags = info
        .lines()
        .find(|l| l.starts_with("flags"))
        .unwrap_or_default();
    let simd = ["avx512f", "avx2", "avx", "sse4_2"]
        .into_iter()
        .find(|f| flags.split_whitespace().any(|x| x == *f))
        .unwrap_or("sse2");
    let cores = info.lines().filter(|l| l.starts_with("processor")).count();
    let compiled = if cfg!(target_feature = "avx512f") {
        "AVX-512 (target-cpu)"
    } else if cfg!(target_feature = "avx2") {
        "AVX2 (target-cpu)"
    } else {
        "the baseline (a default build)"
    };
    format!(
        "{model}, {cores} cores, up to {simd}; raylane compiled for {compiled}, queries at the \
         SIMD level {} (chosen at run time)",
        raylane::simd::level()
    )
}

/// The digest of a frame's rays and primitives (the firmware computes the same).
pub fn digest(f: &Frame) -> u64 {
    let mut d = scene::Digest::default();
    f.rays.iter().for_each(|r| d.ray(r));
    f.spheres.iter().for_each(|s| d.sphere(s));
    f.tris.iter().for_each(|t| d.triangle(t));
    f.planes.iter().for_each(|p| d.plane(p));
    d.0
}
