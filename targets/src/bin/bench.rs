//! Executed instructions per ray–primitive test of every kernel on the microcontroller, counted
//! by QEMU's TCG plugin `targets/plugin/insncount.c` (run it with `scripts/count-m4f.sh`).
//!
//! The scene is the host's (`benches/src/scene.rs`, included below): 64 spheres, triangles and
//! planes, a 32 × 32 camera; `coherent` is every primary ray, `miss` the primary rays whose
//! lines clearly miss every sphere and triangle. For each kernel and ray set, one frame of
//! closest-hit queries runs between [`bench_begin`] and [`bench_end`] — once over the 64
//! primitives and once over none — so the plugin's windows differ by exactly the tests.
//!
//! What is counted is what firmware calls: the library's `Query::closest` for one `Ray` on the
//! kernel's set (a slice with `using::<K>()`, `FocalSpheres`, `FocalMesh`, `FocalPlanes`), as
//! the host's `count` example does; the unguarded focal sphere, which has no public set, runs
//! the lab's loop (the kernel alone).
//!
//! Output (semihosting): `scene RAYS DIGEST` (the host's `count digest` prints the same), then
//! one `cfg KERNEL 1 SHAPE RAYS USED TESTS` line per window (`query`, or `loop` for the lab's
//! loop), in window order. Scalar lanes (`f32`), the lane firmware uses.
#![no_std]
#![no_main]

use core::hint::black_box;

use raylane::focal::{FocalMesh, FocalPlanes, FocalSpheres};
use raylane::glam::Vec3;
use raylane::mesh::Mesh;
use raylane::plane::{FocalPlane, Plane};
use raylane::sphere::focal::FocalUnguarded;
use raylane::sphere::{FocalSphere, Geometric, Quadratic, QuadraticUnit, Robust, Sphere};
use raylane::triangle::{Cramer, FocalTriangle, Moller, Triangle, Watertight};
use raylane::{Mask, Pinhole, Query, Ray, RayPacket};
use raylane_fw::semihosting::hprintln;
use raylane_fw::{entry, exit};
use raylane_lab::loops as internals;

raylane_fw::panic_exits!();

#[path = "../../../benches/src/scene.rs"]
#[allow(dead_code)]
mod scene;

/// Primitives of each kind.
const N: usize = 64;
/// The camera's side.
const SIDE: u32 = 32;
/// Room for the rays.
const RAYS: usize = (SIDE * SIDE) as usize;

/// Start of a counted window (the plugin's `start=` address): out of line, with a body of its
/// own so that it is not merged with [`bench_end`].
#[inline(never)]
#[unsafe(no_mangle)]
pub extern "C" fn bench_begin() {
    // SAFETY: an assembler comment; no effect.
    unsafe {
        core::arch::asm!(
            "/* bench_begin */",
            options(nomem, nostack, preserves_flags)
        )
    }
}

/// End of a counted window (the plugin's `stop=` address).
#[inline(never)]
#[unsafe(no_mangle)]
pub extern "C" fn bench_end() {
    // SAFETY: an assembler comment; no effect.
    unsafe { core::arch::asm!("/* bench_end */", options(nomem, nostack, preserves_flags)) }
}

/// Rays as pixels of the camera, made as they are traced (the 64 KB of RAM the M4F's part is
/// linked with hold no array of 1,024 rays beside the scene): making one costs the same in
/// a window over 64 primitives and over none, so it cancels out of the count per test.
#[derive(Clone, Copy)]
struct Pixels<'a> {
    cam: &'a Pinhole,
    /// Pixel `y·SIDE + x` of each ray.
    index: &'a [u16],
}

impl Pixels<'_> {
    fn len(&self) -> usize {
        self.index.len()
    }

    fn rays(&self) -> impl Iterator<Item = Ray> + '_ {
        self.index.iter().map(|&i| {
            let i = i as u32;
            scene::pixel_ray(self.cam, i % SIDE, i / SIDE)
        })
    }
}

/// One frame of closest-hit queries, one ray at a time; returns the rays hit.
#[inline(never)]
fn frame<F: Fn(&Ray) -> bool>(rays: Pixels, f: F) -> u32 {
    let mut n = 0;
    for r in rays.rays() {
        n += f(black_box(&r)) as u32;
    }
    n
}

/// The scene's primitives, caches and the triangle soup as a mesh.
struct Scene {
    spheres: [Sphere; N],
    unguarded: [FocalSphere<f32>; N],
    tris: [Triangle; N],
    positions: [Vec3; 3 * N],
    indices: [[u32; 3]; N],
    planes: [Plane; N],
    eye: Vec3,
}

/// Runs every kernel over `rays`, each once over `N` primitives and once over none.
fn measure(s: &Scene, rays: Pixels, name: &str) {
    macro_rules! kernel {
        ($k:expr, $shape:expr, $u:ident => $set:expr) => {
            for $u in [N, 0] {
                hprintln!(
                    "cfg {} 1 {} {} {} {}",
                    $k,
                    $shape,
                    name,
                    $u,
                    rays.len() * $u
                );
                bench_begin();
                black_box(frame(rays, $set));
                bench_end();
            }
        };
    }
    let mut cache_s = [FocalSphere::gather(&[]); N];
    let mut cache_t = [FocalTriangle::never(); N];
    let mut cache_p = [FocalPlane::new(s.eye, &s.planes[0]); N];
    kernel!("quadratic", "query", u => |r| s.spheres[..u].using::<Quadratic>().closest(r).is_some());
    kernel!("quadratic-unit", "query", u => |r| s.spheres[..u].using::<QuadraticUnit>().closest(r).is_some());
    kernel!("geometric", "query", u => |r| s.spheres[..u].using::<Geometric>().closest(r).is_some());
    kernel!("robust", "query", u => |r| s.spheres[..u].using::<Robust>().closest(r).is_some());
    for u in [N, 0] {
        let Ok(set) = FocalSpheres::new(&s.spheres[..u], s.eye, &mut cache_s) else {
            exit(false)
        };
        hprintln!("cfg focal 1 query {} {} {}", name, u, rays.len() * u);
        bench_begin();
        black_box(frame(rays, |r| set.closest(r).is_some()));
        bench_end();
    }
    kernel!("focal-unguarded", "loop", u => |r: &Ray| {
        let p = RayPacket::<f32>::splat(r);
        internals::sphere::focal::closest::<FocalUnguarded, f32>(&p, &s.unguarded[..u]).mask.any()
    });
    kernel!("plane", "query", u => |r| s.planes[..u].closest(r).is_some());
    for u in [N, 0] {
        let Ok(set) = FocalPlanes::new(&s.planes[..u], s.eye, &mut cache_p) else {
            exit(false)
        };
        hprintln!("cfg plane-focal 1 query {} {} {}", name, u, rays.len() * u);
        bench_begin();
        black_box(frame(rays, |r| set.closest(r).is_some()));
        bench_end();
    }
    kernel!("cramer", "query", u => |r| s.tris[..u].using::<Cramer>().closest(r).is_some());
    kernel!("moller", "query", u => |r| s.tris[..u].using::<Moller>().closest(r).is_some());
    kernel!("watertight", "query", u => |r| s.tris[..u].using::<Watertight>().closest(r).is_some());
    for u in [N, 0] {
        let mesh = Mesh::new(&s.positions, &s.indices[..u]);
        let Ok(set) = FocalMesh::new(&mesh, s.eye, &mut cache_t) else {
            exit(false)
        };
        hprintln!(
            "cfg triangle-focal 1 query {} {} {}",
            name,
            u,
            rays.len() * u
        );
        bench_begin();
        black_box(frame(rays, |r| set.closest(r).is_some()));
        bench_end();
    }
}

fn digest(rays: Pixels, s: &Scene) -> u64 {
    let mut d = scene::Digest::default();
    rays.rays().for_each(|r| d.ray(&r));
    s.spheres.iter().for_each(|x| d.sphere(x));
    s.tris.iter().for_each(|x| d.triangle(x));
    s.planes.iter().for_each(|x| d.plane(x));
    d.0
}

#[entry]
fn main() -> ! {
    let cam = scene::camera(SIDE, SIDE);
    let aspect = 1.0;
    let eye = cam.eye;
    let mut spheres = scene::spheres(scene::SPHERE_SEED, aspect);
    let spheres: [Sphere; N] =
        core::array::from_fn(|_| spheres.next().unwrap_or(Sphere::new(eye, f32::NAN)));
    let mut tris = scene::triangles(scene::TRIANGLE_SEED, aspect);
    let tris: [Triangle; N] = core::array::from_fn(|_| tris.next().unwrap_or(Triangle::never()));
    let mut planes = scene::planes(scene::PLANE_SEED, aspect);
    let planes: [Plane; N] =
        core::array::from_fn(|_| planes.next().unwrap_or(Plane::new(eye, eye)));
    let s = Scene {
        unguarded: core::array::from_fn(|i| FocalSphere::unguarded(eye, &spheres[i])),
        positions: core::array::from_fn(|k| {
            let t = &tris[k / 3];
            [t.a(), t.b(), t.c()][k % 3]
        }),
        indices: core::array::from_fn(|i| {
            let i = i as u32;
            [3 * i, 3 * i + 1, 3 * i + 2]
        }),
        spheres,
        tris,
        planes,
        eye,
    };
    // Every primary ray, row by row, and those whose lines miss everything.
    let all: [u16; RAYS] = core::array::from_fn(|i| i as u16);
    let coherent = Pixels {
        cam: &cam,
        index: &all,
    };
    let mut index = [0u16; RAYS];
    let mut m = 0;
    for (i, r) in coherent.rays().enumerate() {
        if s.spheres.iter().all(|x| scene::line_misses_sphere(&r, x))
            && s.tris.iter().all(|x| scene::line_misses_triangle(&r, x))
        {
            index[m] = i as u16;
            m += 1;
        }
    }
    let miss = Pixels {
        cam: &cam,
        index: &index[..m / 16 * 16],
    };
    hprintln!("scene miss {:016x}", digest(miss, &s));
    hprintln!("scene coherent {:016x}", digest(coherent, &s));
    measure(&s, miss, "miss");
    measure(&s, coherent, "coherent");
    exit(true)
}
