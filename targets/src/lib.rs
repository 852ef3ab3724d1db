//! Shared by the firmware binaries:
//!
//! * the platform: [`entry`], [`semihosting`] (printing, host files, exit codes) and [`exit`]
//!   for Cortex-M (cortex-m-rt, cortex-m-semihosting) and RISC-V (riscv-rt,
//!   riscv-semihosting), and [`panic_exits!`], a panic handler that prints and fails;
//! * [`Cases`], the test vectors as `build.rs` encodes them;
//! * [`every_kernel`], which calls every kernel of raylane's registry at one lane width (and
//!   every other entry point), with inputs from volatile reads and results to a volatile
//!   sink so nothing is folded away.
#![no_std]

use core::ptr::{addr_of, addr_of_mut, read_volatile, write_volatile};

use glam::Vec3;
use raylane::mesh::Mesh;
use raylane::plane::{FocalPlane, Plane};
use raylane::sphere::focal::{Focal, FocalKernel};
use raylane::sphere::{FocalSphere, Robust, Sphere, SphereKernel, SpherePacket};
use raylane::triangle::{
    FocalTriangle, Moller, Triangle, TriangleKernel, TrianglePacket, Watertight,
};
use raylane::{Cull, Lane, Mask, Query, Ray, RayPacket};
use raylane_lab::loops as internals;
use raylane_lab::loops::Best;
use raylane_lab::registry::{Kernel, Visitor};
use raylane_lab::vectors::{Case, Kind, Values};

// The critical-section implementations the semihosting crates need (single core / hart).
#[cfg(target_arch = "arm")]
use cortex_m as _;
#[cfg(target_arch = "riscv32")]
use riscv as _;

/// The program's entry point (`#[entry] fn main() -> !`).
#[cfg(target_arch = "arm")]
pub use cortex_m_rt::entry;
/// Semihosting: `hprintln!`, `syscall!`, `nr`, `debug`.
#[cfg(target_arch = "arm")]
pub use cortex_m_semihosting as semihosting;
/// The program's entry point (`#[entry] fn main() -> !`).
#[cfg(target_arch = "riscv32")]
pub use riscv_rt::entry;
/// Semihosting: `hprintln!`, `syscall!`, `nr`, `debug`.
#[cfg(target_arch = "riscv32")]
pub use riscv_semihosting as semihosting;

/// Ends the QEMU run through semihosting: exit status 0 on `success`, else 1.
pub fn exit(success: bool) -> ! {
    use semihosting::debug;
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    // Not reached: the semihosting exit ends the QEMU run.
    loop {
        core::hint::spin_loop();
    }
}

/// Defines the panic handler: prints the panic through semihosting and exits with failure.
#[macro_export]
macro_rules! panic_exits {
    () => {
        #[panic_handler]
        fn panic(info: &core::panic::PanicInfo) -> ! {
            $crate::semihosting::hprintln!("{}", info);
            $crate::exit(false)
        }
    };
}

/// The word [`paint_stack`] fills free RAM with.
const PAINT: u32 = 0x5A5A_A5A5;

unsafe extern "C" {
    /// The end of `.bss` (cortex-m-rt and riscv-rt): the stack may grow down to here.
    static __sheap: u32;
    /// The top of the stack.
    static _stack_start: u32;
}

/// The stack pointer.
#[inline(always)]
pub fn stack_pointer() -> usize {
    let sp: usize;
    // SAFETY: reads a register; no memory access.
    #[cfg(target_arch = "arm")]
    unsafe {
        core::arch::asm!("mov {}, sp", out(reg) sp, options(nomem, nostack, preserves_flags))
    };
    // SAFETY: as above.
    #[cfg(target_arch = "riscv32")]
    unsafe {
        core::arch::asm!("mv {}, sp", out(reg) sp, options(nomem, nostack, preserves_flags))
    };
    sp
}

/// Stack painting, for a measured peak: fills the free RAM between the end of `.bss` and
/// 64 bytes below the current stack pointer with a pattern; [`stack_touched`] then finds the
/// lowest word anything wrote.
#[inline(never)]
pub fn paint_stack() {
    let lo = addr_of!(__sheap) as usize;
    let hi = stack_pointer().saturating_sub(64) & !3;
    let mut p = lo;
    while p < hi {
        // SAFETY: free RAM between the end of .bss and the live stack (4-byte aligned words).
        unsafe { write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
}

/// The lowest address written since [`paint_stack`] (the deepest the stack grew).
#[inline(never)]
pub fn stack_touched() -> usize {
    let lo = addr_of!(__sheap) as usize;
    let top = addr_of!(_stack_start) as usize;
    let mut p = lo;
    // SAFETY: reads the RAM that paint_stack painted.
    while p < top && unsafe { read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    p
}

/// The stack below its top at `_stack_start` the program has used since [`paint_stack`].
pub fn peak_stack() -> usize {
    (addr_of!(_stack_start) as usize).saturating_sub(stack_touched())
}

/// A host file opened for writing through semihosting (`path` NUL-terminated), or `None`.
pub fn create(path: &str) -> Option<isize> {
    // SAFETY: semihosting calls with a valid NUL-terminated name; QEMU runs with semihosting
    // enabled (see .cargo/config.toml).
    let fd = unsafe {
        semihosting::syscall!(
            OPEN,
            path.as_ptr(),
            semihosting::nr::open::W_TRUNC_BINARY,
            path.len() - 1
        )
    } as isize;
    (fd != -1).then_some(fd)
}

/// Writes `bytes` to the host file `fd`; true when all were written.
pub fn write(fd: isize, bytes: &[u8]) -> bool {
    // SAFETY: a valid buffer of `bytes.len()` bytes and a handle from `create`.
    unsafe { semihosting::syscall!(WRITE, fd, bytes.as_ptr(), bytes.len()) == 0 }
}

/// Closes the host file `fd`; true on success.
pub fn close(fd: isize) -> bool {
    // SAFETY: a handle from `create`.
    unsafe { semihosting::syscall!(CLOSE, fd) == 0 }
}

/// One vector file's cases, encoded by `build.rs` (parsed there by raylane's own parser): per
/// case, little-endian, the kind (u8: 0 sphere, 1 plane, 2 triangle), the number of expected
/// values (u8), the line (u16), the kind's inputs and the expected values (f32 bits each).
/// About a third of the text's size, and nothing to parse on the target.
#[derive(Clone, Copy)]
pub struct Cases(pub &'static [u8]);

impl Cases {
    /// Decodes the case at `*pos` and moves past it; `None` at the end or on a truncated or
    /// malformed record (then `*pos` stays put, short of the end).
    pub fn next(&self, pos: &mut usize) -> Option<Case> {
        let b = self.0.get(*pos..)?;
        let (&[kind, n, l0, l1], rest) = b.split_first_chunk::<4>()?;
        let kind = match kind {
            0 => Kind::Sphere,
            1 => Kind::Plane,
            2 => Kind::Triangle,
            _ => return None,
        };
        // The low nibble counts the expected values, the high nibble their conditioning.
        let (inputs, m, n) = (kind.inputs(), (n >> 4) as usize, (n & 15) as usize);
        if n > 3 || m > 3 || rest.len() < 4 * (inputs + n + m) {
            return None;
        }
        let f = |i: usize| {
            let mut w = [0u8; 4];
            w.copy_from_slice(&rest[4 * i..4 * i + 4]);
            f32::from_bits(u32::from_le_bytes(w))
        };
        let mut c = Case {
            kind,
            line: u16::from_le_bytes([l0, l1]) as u32,
            expect: Values {
                n: n as u8,
                v: [0.0; 3],
            },
            ..Case::default()
        };
        for i in 0..inputs {
            c.input[i] = f(i);
        }
        for k in 0..n {
            c.expect.v[k] = f(inputs + k);
        }
        c.cond.n = m as u8;
        for k in 0..m {
            c.cond.v[k] = f(inputs + n + k);
        }
        *pos += 4 + 4 * (inputs + n + m);
        Some(c)
    }

    /// True when `pos` is exactly the end (every record decoded).
    pub fn done(&self, pos: usize) -> bool {
        pos == self.0.len()
    }
}

static INPUT: [f32; 16] = [
    0.0, 1.0, 2.0, -1.0, 0.5, 5.0, 3.0, -10.0, 0.25, 4.0, 0.1, -0.3, 7.0, 1.5, -2.0, 0.75,
];
static mut SINK: u32 = 0;

pub fn x(i: usize) -> f32 {
    // SAFETY: a read of an initialised static.
    unsafe { read_volatile(addr_of!(INPUT[i % 16])) }
}

pub fn v(i: usize) -> Vec3 {
    Vec3::new(x(i), x(i + 1), x(i + 2))
}

fn sink(bits: u32) {
    // SAFETY: single-threaded firmware; volatile so the result counts as used.
    unsafe { write_volatile(addr_of_mut!(SINK), read_volatile(addr_of!(SINK)) ^ bits) }
}

fn hits<L: Lane<Scalar = f32>>(h: &Best<L>) {
    sink(h.mask.bits() ^ h.t.lane(0).to_bits() ^ h.u.lane(0).to_bits());
}

fn query_hits<L: Lane<Scalar = f32>>(h: &raylane::Hits<L>) {
    sink(h.mask.bits() ^ h.t.lane(0).to_bits() ^ h.normal.x.lane(0).to_bits());
}

fn rec(r: Option<raylane_lab::loops::HitRecord>) {
    sink(r.map_or(7, |h| h.t.to_bits() ^ h.index));
}

/// One call of each kernel of raylane's registry: its closest-hit query of `rays` over a few
/// primitives (caches built with the eye at `eye`).
struct Closest<'a, L: Lane> {
    rays: &'a RayPacket<L>,
    eye: Vec3,
    balls: &'a [Sphere; 3],
    walls: &'a [Plane; 2],
    tris: &'a [Triangle; 2],
}

impl<L: Lane<Scalar = f32>> Visitor for Closest<'_, L> {
    type Output = ();
    fn sphere<K: SphereKernel>(self, _: Kernel) {
        hits(&internals::sphere::closest::<K, L>(self.rays, self.balls));
    }
    fn focal_sphere<K: FocalKernel>(self, _: Kernel, guarded: bool) {
        let mut cache = [FocalSphere::new(self.eye, &self.balls[0]); 3];
        for (slot, s) in cache.iter_mut().zip(self.balls) {
            *slot = if guarded {
                FocalSphere::new(self.eye, s)
            } else {
                FocalSphere::unguarded(self.eye, s)
            };
        }
        hits(&internals::sphere::focal::closest::<K, L>(
            self.rays, &cache,
        ));
    }
    fn plane(self, _: Kernel) {
        hits(&internals::plane::closest::<L>(self.rays, self.walls));
    }
    fn focal_plane(self, _: Kernel) {
        let cache = [FocalPlane::new(self.eye, &self.walls[0])];
        hits(&internals::plane::closest_focal::<L>(self.rays, &cache));
    }
    fn triangle<K: TriangleKernel>(self, _: Kernel) {
        hits(&internals::triangle::closest::<K, L>(
            self.rays,
            self.tris,
            Cull::None,
        ));
    }
    fn focal_triangle(self, _: Kernel) {
        let mut cache = [FocalTriangle::never(); 2];
        internals::triangle::focal::focus(self.eye, self.tris, &mut cache);
        hits(&internals::triangle::focal::closest(
            self.rays,
            &cache,
            Cull::None,
        ));
    }
}

pub fn every_kernel<L: Lane<Scalar = f32>>(rays: &RayPacket<L>, ray: &Ray) {
    let balls = [
        Sphere::new(v(5), x(6)),
        Sphere::new(v(0), x(4)),
        Sphere::new(v(8), x(9)),
    ];
    let walls = [Plane::new(v(3), v(7)), Plane::new(v(1), v(2))];
    let tris = [
        Triangle::new(v(0), v(3), v(6)),
        Triangle::new(v(2), v(9), v(12)),
    ];
    let eye = ray.origin();
    // Every kernel of the registry: N rays × its primitives.
    for k in Kernel::ALL {
        k.visit(Closest {
            rays,
            eye,
            balls: &balls,
            walls: &walls,
            tris: &tris,
        });
    }
    // The other entry points: 1 ray × N primitives in lanes, any, all, one ray, meshes.
    sink(internals::sphere::any::<Robust, L>(rays, &balls).bits());
    internals::sphere::all::<Robust, L>(rays, &balls, |i, r| sink(i ^ r.any().bits()));
    let mut packed = [SpherePacket::<L>::from_spheres(&[]); 1];
    SpherePacket::pack(&balls, &mut packed);
    rec(internals::sphere::closest_soa::<Robust, L>(ray, &packed));
    rec(internals::sphere::intersect::<Robust>(ray, &balls[0]));
    let mut cache = [FocalSphere::new(eye, &balls[0]); 3];
    internals::sphere::focal::focus(eye, &balls, &mut cache);
    sink(internals::sphere::focal::any::<Focal, L>(rays, &cache).bits());
    let mut fpacked = [FocalSphere::<L>::gather(&[]); 1];
    FocalSphere::pack(&cache, &mut fpacked);
    rec(internals::sphere::focal::closest_soa::<Focal, L>(
        ray, &fpacked,
    ));
    hits(&internals::triangle::closest::<Moller, L>(
        rays,
        &tris,
        Cull::Back,
    ));
    sink(internals::triangle::any::<Watertight, L>(rays, &tris, Cull::None).bits());
    internals::triangle::all::<Moller, L>(rays, &tris, Cull::None, |i, h| sink(i ^ h.mask.bits()));
    let mut tpacked = [TrianglePacket::<L>::from_triangles(&[]); 1];
    TrianglePacket::pack(&tris, &mut tpacked);
    rec(internals::triangle::closest_soa::<Watertight, L>(
        ray,
        &tpacked,
        Cull::None,
    ));
    let mut tcache = [FocalTriangle::never(); 2];
    internals::triangle::focal::focus(eye, &tris, &mut tcache);
    sink(internals::triangle::focal::any(rays, &tcache, Cull::None).bits());
    let positions = [v(0), v(3), v(6), v(9)];
    let indices = [[0u32, 1, 2], [1, 3, 2], [0, 3, 9]];
    let mesh = Mesh::bounded(&positions, &indices);
    query_hits(&mesh.closest(rays));
    sink(mesh.using::<Moller>().any(rays).bits());
    let mut mcache = [FocalTriangle::never(); 3];
    if let Ok(fm) = raylane::focal::FocalMesh::new(&mesh, eye, &mut mcache) {
        query_hits(&fm.closest(rays));
    }
}
