//! The operation-count study: every ray–triangle and ray–sphere method, published or
//! raylane's own, measured by the same counting lane (issue 13).
//!
//! The methods are the [registry](crate::registry)'s kernels of triangles and spheres
//! ([`KERNELS`]: triangles first, then spheres, each in [`Kernel::ALL`]'s order; the plane
//! tests are not methods of the study), each named by its checker's method (the focal caches
//! of both shapes are `focal`) and its [`Kernel::source`]. Every function below takes a
//! [`Kernel`] and reaches the kernel's type through [`Kernel::visit`].
//!
//! [`entries`] measures each method with [`Counted<f32>`](raylane::opcount::Counted) on the same
//! worked examples as the op-count report ([`opcount::table`](crate::opcount::table), whose
//! rows it reuses for the sphere kernels and the focal caches): a **miss** (triangles: beyond
//! edge BC, every method's latest exit; spheres: the lecture's miss ray), a **hit**, and for
//! triangles a triangle **behind** the origin (where the methods that find the plane first exit
//! early). It adds the **per-ray** setup (once per ray and query), the **bytes** each test reads
//! per primitive (the three vertices, 36, or the method's precomputed record; for the focal
//! caches, per primitive *and per eye*), and the **precomputation**'s own count, measured by
//! running [`PrecomputedKernel::precompute`] under `Counted` (the focal caches are built with
//! exact `f64` arithmetic and not counted).
//!
//! [`write_table`] writes the README's table; the accuracy per input class and the
//! watertightness counts come from the caller (`examples/opcount.rs` and its pin test measure
//! them with the vector files and the watertight harness), and so do the executed-instruction
//! counts ([`Insns`]): `scripts/count-study.sh` measures [`repeat`], the one timed loop of
//! every method (x86-64-v3 under callgrind, Cortex-M4F under QEMU), into
//! `docs/study-insns.txt`.

use core::fmt;
use core::hint::black_box;
use core::marker::PhantomData;
use core::mem::size_of;

use glam::Vec3;

use crate::opcount::{Table, table};
use crate::registry::{Family, Kernel, Prim, Visitor};
use raylane::Cull;
use raylane::kernel::LaneHit;
use raylane::lane::{Lane, Mask};
use raylane::opcount::{Counted, OpCounts, measure};
use raylane::plane::{FocalPlane, Plane};
use raylane::ray::{Ray, RayPacket};
use raylane::sphere::focal::FocalKernel;
use raylane::sphere::{self, FocalSphere, SphereKernel, SpherePacket};
use raylane::triangle::focal::FocalRays;
use raylane::triangle::{
    FocalTriangle, PrecomputedKernel, Triangle, TriangleKernel, TrianglePacket, focal as tf,
};

type C = Counted<f32>;

/// What a method tests: the registry's [`Prim`] (the study's methods test triangles or
/// spheres).
pub use crate::registry::Prim as Shape;

/// True for the kernels the study measures: those of triangles and spheres (the plane tests are
/// not methods of the study).
#[must_use]
pub const fn studied(k: Kernel) -> bool {
    !matches!(k.prim(), Prim::Plane)
}

/// How many kernels of the registry the study measures.
const fn studied_count() -> usize {
    let mut n = 0;
    let mut i = 0;
    while i < Kernel::ALL.len() {
        if studied(Kernel::ALL[i]) {
            n += 1;
        }
        i += 1;
    }
    n
}

/// [`KERNELS`], collected from the registry at compile time.
const fn studied_kernels() -> [Kernel; studied_count()] {
    let mut out = [Kernel::ALL[0]; studied_count()];
    let mut n = 0;
    let mut triangles = true;
    loop {
        let mut i = 0;
        while i < Kernel::ALL.len() {
            let k = Kernel::ALL[i];
            if studied(k) && matches!(k.prim(), Prim::Triangle) == triangles {
                out[n] = k;
                n += 1;
            }
            i += 1;
        }
        if !triangles {
            return out;
        }
        triangles = false;
    }
}

/// The study's methods, in its table's order: the registry's kernels of triangles, then those
/// of spheres, each in [`Kernel::ALL`]'s order (see [`studied`]). [`entries`] measures them
/// and [`repeat`] times them in this order.
pub const KERNELS: [Kernel; studied_count()] = studied_kernels();

/// The precomputation a method needs per primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precompute {
    /// None: the test reads the primitive itself.
    None,
    /// Once per primitive, counted.
    Counted(OpCounts),
    /// Once per primitive and eye, in exact `f64` arithmetic (not counted).
    PerEye,
}

/// One method of the study.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Entry {
    /// The registry's kernel.
    pub kernel: Kernel,
    /// The method's name (as the checker spells it: [`Kernel::method`]'s name, `focal` for the
    /// focal caches of both shapes).
    pub method: &'static str,
    /// Triangles or spheres ([`Kernel::prim`]).
    pub shape: Shape,
    /// The source, short ([`Kernel::source`]).
    pub source: &'static str,
    /// A miss.
    pub miss: OpCounts,
    /// A hit.
    pub hit: OpCounts,
    /// Triangles: a triangle behind the origin (the edges pass where they are tested first).
    pub behind: Option<OpCounts>,
    /// Setup once per ray and query.
    pub per_ray: OpCounts,
    /// Bytes the test reads per primitive.
    pub bytes: usize,
    /// The precomputation.
    pub pre: Precompute,
}

/// The figures the caller measures for a method: the largest relative `t` error per input class
/// with the number of wrong hit/miss decisions (in the class order of `vectors::accuracy`,
/// feature `vectors`, for the method's kind), and the watertightness counts (rays, leaks,
/// double hits).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Measured {
    /// `(largest relative t error, wrong decisions)` per class; `None` past the last class.
    pub accuracy: [Option<(f64, u32)>; 6],
    /// `(rays, leaks, double hits)` on the closed meshes; `None` for spheres.
    pub watertight: Option<(usize, usize, usize)>,
    /// Executed instructions on x86-64-v3 (8 lanes), as measured by `scripts/count-study.sh`
    /// ([`repeat`]); `None` if not measured.
    pub x86: Option<Insns>,
    /// The same on a Cortex-M4F (scalar lane, QEMU's TCG plugin).
    pub m4f: Option<Insns>,
}

/// Executed instructions of a method on one target (see [`repeat`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Insns {
    /// Per ray–primitive test on the miss.
    pub miss: f64,
    /// Per test on the hit.
    pub hit: f64,
    /// Per record built (per primitive), or per focal cache built (per primitive and eye);
    /// `None` without a precomputation.
    pub precompute: Option<f64>,
}

/// The counts of the report's row `path` of kernel `kernel`, if it has one.
fn row(table: &Table, kernel: &str, path: &str) -> Option<OpCounts> {
    table
        .iter()
        .find(|r| r.kernel == kernel && r.path == path)
        .map(|r| r.counts)
}

/// The report's worked triangle, rays and sphere (see [`opcount::table`](crate::opcount::table)).
fn triangle() -> Triangle {
    Triangle::new(
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
    )
}

/// The miss (beyond edge BC), the hit and the triangle behind the origin.
fn triangle_rays() -> [Ray; 3] {
    let down = Vec3::new(0.0, 0.0, -1.0);
    [
        Ray::new(Vec3::new(3.0, 2.0, 5.0), down),
        Ray::new(Vec3::new(1.0, 1.0, 5.0), down),
        Ray::new(Vec3::new(1.0, 1.0, -5.0), down),
    ]
}

/// Miss, hit, behind of a kernel without precomputation.
fn plain<K: TriangleKernel>() -> [OpCounts; 3] {
    let tp = TrianglePacket::<C>::splat(&triangle());
    triangle_rays().map(|r| {
        let rp = RayPacket::<C>::splat(&r);
        // The per-ray setup runs under the lock too (counts discarded: see opcount::table).
        let pre = measure(|| K::prepare(&rp)).0;
        measure(|| K::intersect(&rp, &pre, &tp, Cull::None)).1
    })
}

/// Miss, hit, behind of a precomputed kernel's test, and its precomputation.
fn precomputed<K: PrecomputedKernel>() -> ([OpCounts; 3], OpCounts) {
    let tp = TrianglePacket::<C>::splat(&triangle());
    let (rec, pre) = measure(|| K::precompute(&tp));
    let tests = triangle_rays().map(|r| {
        let rp = RayPacket::<C>::splat(&r);
        measure(|| K::test(&rp, &rec, Cull::None)).1
    });
    (tests, pre)
}

/// The lecture's sphere.
fn ball() -> sphere::Sphere {
    sphere::Sphere::new(Vec3::splat(5.0), 3.0)
}

/// The lecture's miss and hit rays.
fn sphere_rays() -> (Ray, Ray) {
    let miss = Ray::new(Vec3::ZERO, Vec3::new(1.0, 3.0, 4.0).normalize());
    let hit = Ray::new(
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 2.0, 1.0).normalize(),
    );
    (miss, hit)
}

/// [`entries`]'s visitor: one kernel's entry.
#[derive(Clone, Copy)]
struct Study<'a> {
    /// The op-count report, measured once.
    table: &'a Table,
}

impl Study<'_> {
    /// Bytes of the three vertices.
    const VERTICES: usize = 3 * size_of::<Vec3>();
    /// Bytes of a sphere: centre and radius.
    const BALL: usize = 4 * size_of::<f32>();

    /// Kernel `k`'s entry with the counts of its rows in the op-count report (`behind` and
    /// `per ray` where it has them).
    fn report(self, k: Kernel, bytes: usize, pre: Precompute) -> Entry {
        let row = |path| row(self.table, k.name(), path);
        Entry {
            kernel: k,
            method: k.method().name(),
            shape: k.prim(),
            source: k.source(),
            miss: row("miss").unwrap_or_default(),
            hit: row("hit").unwrap_or_default(),
            behind: row("behind"),
            per_ray: row("per ray").unwrap_or_default(),
            bytes,
            pre,
        }
    }

    /// A triangle kernel's entry with its miss, hit and behind counted here.
    fn counted(self, k: Kernel, c: [OpCounts; 3], bytes: usize, pre: Precompute) -> Entry {
        let [miss, hit, behind] = c;
        Entry {
            miss,
            hit,
            behind: Some(behind),
            ..self.report(k, bytes, pre)
        }
    }
}

impl Visitor for Study<'_> {
    type Output = Entry;

    fn sphere<K: SphereKernel>(self, k: Kernel) -> Entry {
        self.report(k, Self::BALL, Precompute::None)
    }

    fn focal_sphere<K: FocalKernel>(self, k: Kernel, _: bool) -> Entry {
        self.report(k, size_of::<FocalSphere<f32>>(), Precompute::PerEye)
    }

    fn plane(self, k: Kernel) -> Entry {
        self.report(k, size_of::<Plane>(), Precompute::None)
    }

    fn focal_plane(self, k: Kernel) -> Entry {
        self.report(k, size_of::<FocalPlane>(), Precompute::PerEye)
    }

    fn triangle<K: TriangleKernel>(self, k: Kernel) -> Entry {
        self.counted(k, plain::<K>(), Self::VERTICES, Precompute::None)
    }

    fn precomputed<K: TriangleKernel + PrecomputedKernel>(self, k: Kernel) -> Entry {
        let (c, pre) = precomputed::<K>();
        self.counted(k, c, K::BYTES, Precompute::Counted(pre))
    }

    fn focal_triangle(self, k: Kernel) -> Entry {
        self.report(k, size_of::<FocalTriangle<f32>>(), Precompute::PerEye)
    }
}

/// Every method of the study, one per kernel of [`KERNELS`], in its order (triangles first).
#[must_use]
pub fn entries() -> [Entry; KERNELS.len()] {
    let table = table();
    KERNELS.map(|k| k.visit(Study { table: &table }))
}

/// `mul·add·div·sqrt·cmp`, compact.
fn write_counts(f: &mut impl fmt::Write, c: &OpCounts) -> fmt::Result {
    write!(f, "{}·{}·{}·{}·{}", c.mul, c.add, c.div, c.sqrt, c.cmp)
}

/// The study table: one row per method, `measured(entry)` giving its accuracy and
/// watertightness figures.
pub fn write_table(
    f: &mut impl fmt::Write,
    entries: &[Entry],
    mut measured: impl FnMut(&Entry) -> Measured,
) -> fmt::Result {
    writeln!(
        f,
        "| method | source | miss | hit | behind | per ray | bytes | precompute | x86-64-v3 insns: miss / hit / precompute | M4F insns: miss / hit / precompute | largest t error per class | leaks | double hits |"
    )?;
    writeln!(
        f,
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: |"
    )?;
    for e in entries {
        let m = measured(e);
        write!(f, "| {} | {} | ", e.method, e.source)?;
        write_counts(f, &e.miss)?;
        f.write_str(" | ")?;
        write_counts(f, &e.hit)?;
        f.write_str(" | ")?;
        match &e.behind {
            Some(c) => write_counts(f, c)?,
            None => f.write_str("–")?,
        }
        f.write_str(" | ")?;
        write_counts(f, &e.per_ray)?;
        match e.pre {
            Precompute::PerEye => write!(f, " | {} per eye | exact, per eye", e.bytes)?,
            Precompute::None => write!(f, " | {} | –", e.bytes)?,
            Precompute::Counted(c) => {
                write!(f, " | {} | ", e.bytes)?;
                write_counts(f, &c)?;
            }
        }
        for insns in [m.x86, m.m4f] {
            match insns {
                Some(i) => {
                    write!(f, " | {:.1} / {:.1} / ", i.miss, i.hit)?;
                    match i.precompute {
                        Some(p) => write!(f, "{p:.0}")?,
                        None => f.write_str("–")?,
                    }
                }
                None => f.write_str(" | –")?,
            }
        }
        f.write_str(" |")?;
        for (i, a) in m.accuracy.iter().flatten().enumerate() {
            f.write_str(if i == 0 { " " } else { " / " })?;
            write!(f, "{:.1e}", a.0)?;
            if a.1 > 0 {
                write!(f, " ({} wrong)", a.1)?;
            }
        }
        match m.watertight {
            Some((_, leaks, doubles)) => writeln!(f, " | {leaks} | {doubles} |")?,
            None => writeln!(f, " | – | – |")?,
        }
    }
    Ok(())
}

/// The worked example a timed test runs on (see [`repeat`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// The miss of [`entries`] (triangles: beyond edge BC; spheres: the lecture's miss ray).
    Miss,
    /// The hit.
    Hit,
    /// The precomputation instead of the test: the record of [`PrecomputedKernel::precompute`]
    /// (one per lane) or the focal cache (`FocalTriangle::new`, `FocalSphere::new`: one per
    /// call, for the hit's eye), for the methods that have one ([`precomputes`]).
    Precompute,
}

/// The paths with their names in `docs/study-insns.txt`, in the order they are measured.
pub const PATHS: [(Path, &str); 3] = [
    (Path::Miss, "miss"),
    (Path::Hit, "hit"),
    (Path::Precompute, "precompute"),
];

/// Whether method `k` of [`KERNELS`] has a precomputation (a record per primitive or a cache
/// per primitive and eye) that [`repeat`] times; false for a kernel outside the study.
#[must_use]
pub const fn precomputes(k: Kernel) -> bool {
    studied(k)
        && matches!(
            k.family(),
            Family::Precomputed | Family::FocalSphere { .. } | Family::FocalTriangle
        )
}

/// What one iteration of [`repeat`]'s loop does in lanes `L` for kernel `k`: `L::LANES`
/// ray–primitive tests or records, or one focal cache (built per primitive, not per lane).
#[must_use]
pub fn units<L: Lane>(k: Kernel, path: Path) -> usize {
    if path == Path::Precompute && k.is_focal() {
        1
    } else {
        L::LANES
    }
}

/// `n` tests of one ray packet against one primitive that the compiler must reload from memory
/// each time (as from a list of primitives), each result stored (so that `t`, `u`, `v` are
/// computed); returns the number of lane hits.
#[inline(always)]
fn tests<P, R>(n: usize, prim: &P, test: impl Fn(&P) -> R, hits: impl Fn(&R) -> u32) -> u32 {
    let mut count = 0;
    for _ in 0..n {
        let r = test(black_box(prim));
        count += hits(&r);
        black_box(&r);
    }
    count
}

/// Runs the test of method `k` of [`KERNELS`] `n` times on the worked example `path`, in
/// lanes `L` (every lane the same ray and primitive), with the per-ray setup and the
/// precomputation (records, focal caches) done once before the loop. Returns the lane hits
/// (`n · L::LANES` on [`Path::Hit`], 0 on a miss; on [`Path::Precompute`], `n ·`
/// [`units`] records or caches built, 0 for a method without any), or `None` for a kernel the
/// study does not measure (the plane tests: see [`studied`]).
///
/// This is the unit the study's instruction counts are measured on (`scripts/count-study.sh`):
/// the instructions executed inside one call with `n = 64`, minus those of a call with
/// `n = 0`, divided by `64 · L::LANES`, are one ray–primitive test's, the loop's own
/// bookkeeping (a counter, the hit count and the stored result) included.
#[inline(never)]
pub fn repeat<L: Lane<Scalar = f32>>(k: Kernel, path: Path, n: usize) -> Option<u32> {
    match path {
        Path::Precompute => build::<L>(k, n),
        Path::Miss | Path::Hit => k.visit(Timed::<L> {
            hit: path == Path::Hit,
            n,
            lanes: PhantomData,
        }),
    }
}

/// Lane hits of a triangle test.
fn lane_hits<L: Lane>(h: &LaneHit<L>) -> u32 {
    h.mask.bits().count_ones()
}

/// Lane hits of a sphere test (either root).
fn root_hits<L: Lane>(r: &sphere::Roots<L>) -> u32 {
    (r.m0 | r.m1).bits().count_ones()
}

/// The timed loop of each family of kernels, on the packets, records and caches [`Timed`]
/// sets up: each instance out of line, a function of its own, as the study's counts were
/// measured (inlined into [`repeat`], a loop's registers would follow the dispatch around it).
mod timed {
    use super::{Cull, Lane, SpherePacket, lane_hits, root_hits, tests};
    use super::{FocalKernel, FocalRays, FocalSphere, FocalTriangle, tf};
    use super::{PrecomputedKernel, RayPacket, SphereKernel, TriangleKernel, TrianglePacket};

    /// A triangle kernel's test, its per-ray setup before the loop.
    #[inline(never)]
    pub(super) fn plain<K: TriangleKernel, L: Lane<Scalar = f32>>(
        n: usize,
        rp: &RayPacket<L>,
        tp: &TrianglePacket<L>,
    ) -> u32 {
        let pre = K::prepare(rp);
        tests(n, tp, |t| K::intersect(rp, &pre, t, Cull::None), lane_hits)
    }

    /// A precomputed kernel's test on its record, built before the loop.
    #[inline(never)]
    pub(super) fn record<K: PrecomputedKernel, L: Lane<Scalar = f32>>(
        n: usize,
        rp: &RayPacket<L>,
        tp: &TrianglePacket<L>,
    ) -> u32 {
        let rec = K::precompute(tp);
        tests(
            n,
            &rec,
            |r| K::test(rp, r, Cull::None).unwrap_or_else(raylane::kernel::LaneHit::miss),
            lane_hits,
        )
    }

    /// A sphere kernel's roots.
    #[inline(never)]
    pub(super) fn roots<K: SphereKernel, L: Lane<Scalar = f32>>(
        n: usize,
        rp: &RayPacket<L>,
        sp: &SpherePacket<L>,
    ) -> u32 {
        tests(n, sp, |s| K::roots(rp, s), root_hits)
    }

    /// A focal kernel's roots on a sphere's cache, built before the loop.
    #[inline(never)]
    pub(super) fn focal_roots<K: FocalKernel, L: Lane<Scalar = f32>>(
        n: usize,
        rp: &RayPacket<L>,
        e: &FocalSphere<L>,
    ) -> u32 {
        tests(n, e, |e| K::roots(rp, e), root_hits)
    }

    /// The focal test on a triangle's cache, built before the loop, its per-ray setup before
    /// the loop.
    #[inline(never)]
    pub(super) fn focal<L: Lane<Scalar = f32>>(
        n: usize,
        rp: &RayPacket<L>,
        e: &FocalTriangle<L>,
    ) -> u32 {
        let fr = FocalRays::new(rp);
        tests(n, e, |e| tf::kernel(fr.scaled(), e, Cull::None), lane_hits)
    }
}

/// [`repeat`]'s visitor on the miss and the hit: one kernel's timed loop.
struct Timed<L> {
    /// The hit (else the miss).
    hit: bool,
    /// Iterations.
    n: usize,
    /// The lane type.
    lanes: PhantomData<L>,
}

impl<L: Lane<Scalar = f32>> Timed<L> {
    /// The triangle ray of the path, in lanes the compiler cannot see through.
    fn triangle_ray(&self) -> (Ray, RayPacket<L>) {
        let [miss, hit, _] = triangle_rays();
        let ray = if self.hit { hit } else { miss };
        (ray, black_box(RayPacket::<L>::splat(&ray)))
    }

    /// The sphere ray of the path, in lanes the compiler cannot see through.
    fn sphere_ray(&self) -> (Ray, RayPacket<L>) {
        let (miss, hit) = sphere_rays();
        let ray = if self.hit { hit } else { miss };
        (ray, black_box(RayPacket::<L>::splat(&ray)))
    }
}

impl<L: Lane<Scalar = f32>> Visitor for Timed<L> {
    type Output = Option<u32>;

    fn sphere<K: SphereKernel>(self, _: Kernel) -> Option<u32> {
        let (_, rp) = self.sphere_ray();
        let sp = SpherePacket::<L>::splat(&ball());
        Some(timed::roots::<K, L>(self.n, &rp, &sp))
    }

    fn focal_sphere<K: FocalKernel>(self, _: Kernel, guarded: bool) -> Option<u32> {
        let (ray, rp) = self.sphere_ray();
        let ball = ball();
        let cache = if guarded {
            FocalSphere::new(ray.origin(), &ball)
        } else {
            FocalSphere::unguarded(ray.origin(), &ball)
        };
        let e = FocalSphere::<L>::splat(&cache);
        Some(timed::focal_roots::<K, L>(self.n, &rp, &e))
    }

    fn plane(self, _: Kernel) -> Option<u32> {
        None
    }

    fn focal_plane(self, _: Kernel) -> Option<u32> {
        None
    }

    fn triangle<K: TriangleKernel>(self, _: Kernel) -> Option<u32> {
        let (_, rp) = self.triangle_ray();
        let tp = TrianglePacket::<L>::splat(&triangle());
        Some(timed::plain::<K, L>(self.n, &rp, &tp))
    }

    fn precomputed<K: TriangleKernel + PrecomputedKernel>(self, _: Kernel) -> Option<u32> {
        let (_, rp) = self.triangle_ray();
        let tp = TrianglePacket::<L>::splat(&triangle());
        Some(timed::record::<K, L>(self.n, &rp, &tp))
    }

    fn focal_triangle(self, _: Kernel) -> Option<u32> {
        let (ray, rp) = self.triangle_ray();
        let e = FocalTriangle::<L>::splat(&FocalTriangle::new(ray.origin(), &triangle()));
        Some(timed::focal(self.n, &rp, &e))
    }
}

/// [`repeat`] on [`Path::Precompute`]: `n` records or caches of the worked primitive, each
/// from a primitive the compiler must reload; returns how many were built (0 for a method
/// without a precomputation, `None` outside the study).
fn build<L: Lane<Scalar = f32>>(k: Kernel, n: usize) -> Option<u32> {
    k.visit(Build::<L> {
        n,
        lanes: PhantomData,
    })
}

/// [`build`]'s visitor.
struct Build<L> {
    /// Records or caches to build.
    n: usize,
    /// The lane type.
    lanes: PhantomData<L>,
}

impl<L: Lane<Scalar = f32>> Visitor for Build<L> {
    type Output = Option<u32>;

    fn sphere<K: SphereKernel>(self, _: Kernel) -> Option<u32> {
        Some(0)
    }

    fn focal_sphere<K: FocalKernel>(self, _: Kernel, guarded: bool) -> Option<u32> {
        let eye = sphere_rays().1.origin();
        let n = self.n;
        Some(if guarded {
            tests(n, &ball(), |b| FocalSphere::new(eye, b), |_| 1)
        } else {
            tests(n, &ball(), |b| FocalSphere::unguarded(eye, b), |_| 1)
        })
    }

    fn plane(self, _: Kernel) -> Option<u32> {
        None
    }

    fn focal_plane(self, _: Kernel) -> Option<u32> {
        None
    }

    fn triangle<K: TriangleKernel>(self, _: Kernel) -> Option<u32> {
        Some(0)
    }

    fn precomputed<K: TriangleKernel + PrecomputedKernel>(self, _: Kernel) -> Option<u32> {
        let tp = TrianglePacket::<L>::splat(&triangle());
        Some(tests(
            self.n,
            &tp,
            |t| K::precompute(t),
            |_| L::LANES as u32,
        ))
    }

    fn focal_triangle(self, _: Kernel) -> Option<u32> {
        let [_, hit, _] = triangle_rays();
        let eye = hit.origin();
        Some(tests(
            self.n,
            &triangle(),
            |t| FocalTriangle::new(eye, t),
            |_| 1,
        ))
    }
}
