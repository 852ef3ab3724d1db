//! Executed instructions per ray–primitive test of every kernel on the microcontroller, counted
//! by QEMU's TCG plugin `targets/plugin/insncount.c` (run it with `scripts/count-m4f.sh`).
//!
//! The scene is the host's (`benches/src/scene.rs`, included below): 64 spheres, triangles and
//! planes, a 32 × 32 camera; `coherent` is every primary ray, `miss` the primary rays whose
//! lines clearly miss every sphere and triangle. For each kernel and ray set, one frame of
//! closest-hit queries runs between [`bench_begin`] and [`bench_end`] — once over the 64
//! primitives and once over none — so the plugin's windows differ by exactly the tests.
//!
//! Output (semihosting): `scene RAYS DIGEST` (the host's `count digest` prints the same), then
//! one `cfg KERNEL 1 packets RAYS USED TESTS` line per window, in window order. Scalar lanes
//! (`f32`), the lane firmware uses.
#![no_std]
#![no_main]

use core::hint::black_box;

use raylane::Cull;
use raylane::plane::{FocalPlane, Plane};
use raylane::sphere::focal::{Focal, FocalUnguarded};
use raylane::sphere::{FocalSphere, Geometric, Quadratic, QuadraticUnit, Robust, Sphere};
use raylane::triangle::{Cramer, FocalTriangle, Moller, Triangle, Watertight};
use raylane::{Mask, Ray, RayPacket};
use raylane_fw::semihosting::hprintln;
use raylane_fw::{entry, exit};
use raylane_lab::loops as internals;
use raylane_lab::loops::Best;

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

/// One frame of closest-hit queries, one ray at a time; returns the rays hit.
#[inline(never)]
fn frame<F: Fn(&RayPacket<f32>) -> Best<f32>>(rays: &[Ray], f: F) -> u32 {
    let mut n = 0;
    for r in rays {
        let h = f(black_box(&RayPacket::splat(r)));
        n += h.mask.bits();
        black_box(&h);
    }
    n
}

/// The scene's primitives and caches.
struct Scene {
    spheres: [Sphere; N],
    focal: [FocalSphere<f32>; N],
    unguarded: [FocalSphere<f32>; N],
    tris: [Triangle; N],
    focal_tris: [FocalTriangle<f32>; N],
    planes: [Plane; N],
    focal_planes: [FocalPlane; N],
}

/// Runs every kernel over `rays`, each once over `N` primitives and once over none.
fn measure(s: &Scene, rays: &[Ray], name: &str) {
    macro_rules! kernel {
        ($k:expr, $r:ident, $u:ident => $body:expr) => {
            for $u in [N, 0] {
                hprintln!("cfg {} 1 packets {} {} {}", $k, name, $u, rays.len() * $u);
                bench_begin();
                black_box(frame(rays, |$r: &RayPacket<f32>| $body));
                bench_end();
            }
        };
    }
    let none = Cull::None;
    kernel!("quadratic", r, u => internals::sphere::closest::<Quadratic, _>(r, &s.spheres[..u]));
    kernel!("quadratic-unit", r, u => internals::sphere::closest::<QuadraticUnit, _>(r, &s.spheres[..u]));
    kernel!("geometric", r, u => internals::sphere::closest::<Geometric, _>(r, &s.spheres[..u]));
    kernel!("robust", r, u => internals::sphere::closest::<Robust, _>(r, &s.spheres[..u]));
    kernel!("focal", r, u => internals::sphere::focal::closest::<Focal, _>(r, &s.focal[..u]));
    kernel!("focal-unguarded", r, u => internals::sphere::focal::closest::<FocalUnguarded, _>(r, &s.unguarded[..u]));
    kernel!("plane", r, u => internals::plane::closest(r, &s.planes[..u]));
    kernel!("plane-focal", r, u => internals::plane::closest_focal(r, &s.focal_planes[..u]));
    kernel!("cramer", r, u => internals::triangle::closest::<Cramer, _>(r, &s.tris[..u], none));
    kernel!("moller", r, u => internals::triangle::closest::<Moller, _>(r, &s.tris[..u], none));
    kernel!("watertight", r, u => internals::triangle::closest::<Watertight, _>(r, &s.tris[..u], none));
    kernel!("triangle-focal", r, u => internals::triangle::focal::closest(r, &s.focal_tris[..u], none));
}

fn digest(rays: &[Ray], s: &Scene) -> u64 {
    let mut d = scene::Digest::default();
    rays.iter().for_each(|r| d.ray(r));
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
        focal: core::array::from_fn(|i| FocalSphere::new(eye, &spheres[i])),
        unguarded: core::array::from_fn(|i| FocalSphere::unguarded(eye, &spheres[i])),
        focal_tris: core::array::from_fn(|i| FocalTriangle::new(eye, &tris[i])),
        focal_planes: core::array::from_fn(|i| FocalPlane::new(eye, &planes[i])),
        spheres,
        tris,
        planes,
    };
    // Every primary ray, row by row, and those whose lines miss everything.
    let coherent: [Ray; RAYS] =
        core::array::from_fn(|i| scene::pixel_ray(&cam, i as u32 % SIDE, i as u32 / SIDE));
    let mut miss = [coherent[0]; RAYS];
    let mut m = 0;
    for r in &coherent {
        if s.spheres.iter().all(|x| scene::line_misses_sphere(r, x))
            && s.tris.iter().all(|x| scene::line_misses_triangle(r, x))
        {
            miss[m] = *r;
            m += 1;
        }
    }
    let miss = &miss[..m / 16 * 16];
    hprintln!("scene miss {:016x}", digest(miss, &s));
    hprintln!("scene coherent {:016x}", digest(&coherent, &s));
    measure(&s, miss, "miss");
    measure(&s, &coherent, "coherent");
    exit(true)
}
