//! The operation-count study: every ray–triangle and ray–sphere method, published or
//! raylane's own, measured by the same counting lane (issue 13).
//!
//! [`entries`] measures each method with [`Counted<f32>`](raylane::opcount::Counted) on the same
//! worked examples as the op-count report ([`opcount::table`](crate::opcount::table), whose
//! rows it reuses for raylane's own kernels): a **miss** (triangles: beyond edge BC, every
//! method's latest exit; spheres: the lecture's miss ray), a **hit**, and for triangles a
//! triangle **behind** the origin (where the methods that find the plane first exit early).
//! It adds the **per-ray** setup (once per ray and query), the **bytes** each test reads per
//! primitive (the three vertices, 36, or the method's precomputed record; for the focal
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
use core::mem::size_of;

use glam::Vec3;

use crate::opcount::table;
use raylane::Cull;
use raylane::lane::{Lane, Mask};
use raylane::opcount::{Counted, OpCounts, measure};
use raylane::ray::{Ray, RayPacket};
use raylane::sphere::focal::{Focal, FocalKernel, FocalUnguarded};
use raylane::sphere::{
    self, EmbreeSphere, FocalSphere, Geometric, Pbrt, Quadratic, QuadraticUnit, Robust,
    SphereKernel, SpherePacket,
};
use raylane::triangle::focal::FocalRays;
use raylane::triangle::{
    Badouel, BaldwinWeber, Cramer, FocalTriangle, HavelHerout, KenslerShirley, Moller, Plucker,
    PrecomputedKernel, Triangle, TriangleKernel, TrianglePacket, Wald, Watertight, focal as tf,
};

type C = Counted<f32>;

/// What a method tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Ray–triangle.
    Triangle,
    /// Ray–sphere.
    Sphere,
}

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
    /// The method's name (as the checker spells it).
    pub method: &'static str,
    /// Triangles or spheres.
    pub shape: Shape,
    /// The source, short.
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

fn row(kernel: &str, path: &str) -> OpCounts {
    table()
        .iter()
        .find(|r| r.kernel == kernel && r.path == path)
        .map_or(OpCounts::default(), |r| r.counts)
}

/// The report's worked triangle, rays and sphere (see [`opcount::table`](crate::opcount::table)).
fn triangle() -> Triangle {
    Triangle::new(
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
    )
}

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

/// Miss and hit of a sphere kernel on the lecture's examples.
fn sphere_counts<K: SphereKernel>() -> [OpCounts; 2] {
    let ball = SpherePacket::<C>::splat(&ball());
    let (miss, hit) = sphere_rays();
    [miss, hit].map(|r| measure(|| K::roots(&RayPacket::<C>::splat(&r), &ball)).1)
}

/// Every method of the study, triangles first.
#[must_use]
pub fn entries() -> [Entry; 18] {
    let none = OpCounts::default();
    let vertices = 3 * size_of::<Vec3>();
    let ball = 4 * size_of::<f32>();
    let tri = |method: &'static str,
               source: &'static str,
               c: [OpCounts; 3],
               bytes: usize,
               pre: Precompute| Entry {
        method,
        shape: Shape::Triangle,
        source,
        miss: c[0],
        hit: c[1],
        behind: Some(c[2]),
        per_ray: none,
        bytes,
        pre,
    };
    let plain_entry = |method, source, c| tri(method, source, c, vertices, Precompute::None);
    let pre_entry = |method, source, (c, pre): ([OpCounts; 3], OpCounts), bytes| {
        tri(method, source, c, bytes, Precompute::Counted(pre))
    };
    let sphere = |method: &'static str,
                  source: &'static str,
                  c: [OpCounts; 2],
                  bytes: usize,
                  pre: Precompute| Entry {
        method,
        shape: Shape::Sphere,
        source,
        miss: c[0],
        hit: c[1],
        behind: None,
        per_ray: none,
        bytes,
        pre,
    };
    let sphere_own = |method, kernel: &'static str, source, bytes, pre| {
        sphere(
            method,
            source,
            [row(kernel, "miss"), row(kernel, "hit")],
            bytes,
            pre,
        )
    };
    let sphere_new = |method, source, c| sphere(method, source, c, ball, Precompute::None);
    let focal_tri = Entry {
        method: "focal",
        shape: Shape::Triangle,
        source: "raylane: rays from one eye",
        miss: row("triangle-focal", "miss"),
        hit: row("triangle-focal", "hit"),
        behind: Some(row("triangle-focal", "behind")),
        per_ray: row("triangle-focal", "per ray"),
        bytes: size_of::<FocalTriangle<f32>>(),
        pre: Precompute::PerEye,
    };
    let focal_bytes = size_of::<FocalSphere<f32>>();
    [
        plain_entry(
            Cramer::NAME,
            "lecture 002 (Cramer's rule)",
            plain::<Cramer>(),
        ),
        plain_entry(
            Moller::NAME,
            "Möller–Trumbore 1997, division deferred",
            plain::<Moller>(),
        ),
        Entry {
            per_ray: row("watertight", "per ray"),
            ..plain_entry(
                Watertight::NAME,
                "Woop–Benthin–Wald 2013",
                plain::<Watertight>(),
            )
        },
        focal_tri,
        pre_entry(
            Badouel::NAME,
            "Badouel 1990",
            precomputed::<Badouel>(),
            Badouel::BYTES,
        ),
        plain_entry(
            Plucker::NAME,
            "Segura–Feito 1998 (Embree's Plücker)",
            plain::<Plucker>(),
        ),
        pre_entry(Wald::NAME, "Wald 2004", precomputed::<Wald>(), Wald::BYTES),
        pre_entry(
            HavelHerout::NAME,
            "Havel–Herout 2010",
            precomputed::<HavelHerout>(),
            HavelHerout::BYTES,
        ),
        plain_entry(
            KenslerShirley::NAME,
            "Kensler–Shirley 2006",
            plain::<KenslerShirley>(),
        ),
        pre_entry(
            BaldwinWeber::NAME,
            "Baldwin–Weber 2016",
            precomputed::<BaldwinWeber>(),
            BaldwinWeber::BYTES,
        ),
        sphere_own(
            "quadratic",
            "quadratic",
            "the quadratic (lecture 004)",
            ball,
            Precompute::None,
        ),
        sphere_own(
            "quadratic-unit",
            "quadratic-unit",
            "lecture 000, unit d",
            ball,
            Precompute::None,
        ),
        sphere_own(
            "geometric",
            "geometric",
            "Glassner's geometric test, unit d",
            ball,
            Precompute::None,
        ),
        sphere_own(
            "robust",
            "robust",
            "Ray Tracing Gems ch. 7",
            ball,
            Precompute::None,
        ),
        sphere_new(
            Pbrt::NAME,
            "pbrt-v4, intervals aside",
            sphere_counts::<Pbrt>(),
        ),
        sphere_new(
            EmbreeSphere::NAME,
            "Embree sphere_intersector",
            sphere_counts::<EmbreeSphere>(),
        ),
        sphere_own(
            "focal",
            "focal",
            "raylane: rays from one eye, unit d",
            focal_bytes,
            Precompute::PerEye,
        ),
        sphere_own(
            "focal-unguarded",
            "focal-unguarded",
            "the same without the precision guard",
            focal_bytes,
            Precompute::PerEye,
        ),
    ]
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

/// Every method of [`entries`], in its order: what [`repeat`] runs (`tests/suite/kernels/op_count_study.rs`
/// checks that the two lists agree).
pub const METHODS: [(Shape, &str); 18] = [
    (Shape::Triangle, Cramer::NAME),
    (Shape::Triangle, Moller::NAME),
    (Shape::Triangle, Watertight::NAME),
    (Shape::Triangle, "focal"),
    (Shape::Triangle, Badouel::NAME),
    (Shape::Triangle, Plucker::NAME),
    (Shape::Triangle, Wald::NAME),
    (Shape::Triangle, HavelHerout::NAME),
    (Shape::Triangle, KenslerShirley::NAME),
    (Shape::Triangle, BaldwinWeber::NAME),
    (Shape::Sphere, "quadratic"),
    (Shape::Sphere, "quadratic-unit"),
    (Shape::Sphere, "geometric"),
    (Shape::Sphere, "robust"),
    (Shape::Sphere, Pbrt::NAME),
    (Shape::Sphere, EmbreeSphere::NAME),
    (Shape::Sphere, "focal"),
    (Shape::Sphere, "focal-unguarded"),
];

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

/// Whether method `index` of [`METHODS`] has a precomputation (a record per primitive or a
/// cache per primitive and eye).
#[must_use]
pub const fn precomputes(index: usize) -> bool {
    matches!(index, 3 | 4 | 6 | 7 | 9 | 16 | 17)
}

/// What one iteration of [`repeat`]'s loop does in lanes `L`: `L::LANES` ray–primitive tests
/// or records, or one focal cache (built per primitive, not per lane).
#[must_use]
pub fn units<L: Lane>(index: usize, path: Path) -> usize {
    match (path, index) {
        (Path::Precompute, 3 | 16 | 17) => 1,
        _ => L::LANES,
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

/// Runs the test of method `index` of [`METHODS`] `n` times on the worked example `path`, in
/// lanes `L` (every lane the same ray and primitive), with the per-ray setup and the
/// precomputation (records, focal caches) done once before the loop. Returns the lane hits
/// (`n · L::LANES` on [`Path::Hit`], 0 on a miss; on [`Path::Precompute`], `n ·`
/// [`units`] records or caches built, 0 for a method without any), or `None` past the last
/// method.
///
/// This is the unit the study's instruction counts are measured on (`scripts/count-study.sh`):
/// the instructions executed inside one call with `n = 64`, minus those of a call with
/// `n = 0`, divided by `64 · L::LANES`, are one ray–primitive test's, the loop's own
/// bookkeeping (a counter, the hit count and the stored result) included.
#[inline(never)]
pub fn repeat<L: Lane<Scalar = f32>>(index: usize, path: Path, n: usize) -> Option<u32> {
    let (shape, _) = *METHODS.get(index)?;
    if path == Path::Precompute {
        return Some(if precomputes(index) {
            build::<L>(index, n)
        } else {
            0
        });
    }
    let hit = path == Path::Hit;
    Some(match shape {
        Shape::Triangle => {
            let ray = triangle_rays()[usize::from(hit)];
            let rp = black_box(RayPacket::<L>::splat(&ray));
            let tp = TrianglePacket::<L>::splat(&triangle());
            let lane_hits = |h: &raylane::kernel::LaneHit<L>| h.mask.bits().count_ones();
            fn plain<K: TriangleKernel, L: Lane<Scalar = f32>>(
                n: usize,
                rp: &RayPacket<L>,
                tp: &TrianglePacket<L>,
            ) -> u32 {
                let pre = K::prepare(rp);
                tests(
                    n,
                    tp,
                    |t| K::intersect(rp, &pre, t, Cull::None),
                    |h| h.mask.bits().count_ones(),
                )
            }
            fn record<K: PrecomputedKernel, L: Lane<Scalar = f32>>(
                n: usize,
                rp: &RayPacket<L>,
                tp: &TrianglePacket<L>,
            ) -> u32 {
                let rec = K::precompute(tp);
                tests(
                    n,
                    &rec,
                    |r| K::test(rp, r, Cull::None),
                    |h| h.mask.bits().count_ones(),
                )
            }
            match index {
                0 => plain::<Cramer, L>(n, &rp, &tp),
                1 => plain::<Moller, L>(n, &rp, &tp),
                2 => plain::<Watertight, L>(n, &rp, &tp),
                3 => {
                    let e =
                        FocalTriangle::<L>::splat(&FocalTriangle::new(ray.origin(), &triangle()));
                    let fr = FocalRays::new(&rp);
                    tests(n, &e, |e| tf::kernel(fr.scaled(), e, Cull::None), lane_hits)
                }
                4 => record::<Badouel, L>(n, &rp, &tp),
                5 => plain::<Plucker, L>(n, &rp, &tp),
                6 => record::<Wald, L>(n, &rp, &tp),
                7 => record::<HavelHerout, L>(n, &rp, &tp),
                8 => plain::<KenslerShirley, L>(n, &rp, &tp),
                _ => record::<BaldwinWeber, L>(n, &rp, &tp),
            }
        }
        Shape::Sphere => {
            let (miss, hit_ray) = sphere_rays();
            let ray = if hit { hit_ray } else { miss };
            let rp = black_box(RayPacket::<L>::splat(&ray));
            let ball = ball();
            let sp = SpherePacket::<L>::splat(&ball);
            let root_hits = |r: &sphere::Roots<L>| (r.m0 | r.m1).bits().count_ones();
            fn roots<K: SphereKernel, L: Lane<Scalar = f32>>(
                n: usize,
                rp: &RayPacket<L>,
                sp: &SpherePacket<L>,
            ) -> u32 {
                tests(
                    n,
                    sp,
                    |s| K::roots(rp, s),
                    |r| (r.m0 | r.m1).bits().count_ones(),
                )
            }
            match index {
                10 => roots::<Quadratic, L>(n, &rp, &sp),
                11 => roots::<QuadraticUnit, L>(n, &rp, &sp),
                12 => roots::<Geometric, L>(n, &rp, &sp),
                13 => roots::<Robust, L>(n, &rp, &sp),
                14 => roots::<Pbrt, L>(n, &rp, &sp),
                15 => roots::<EmbreeSphere, L>(n, &rp, &sp),
                16 => {
                    let e = FocalSphere::<L>::splat(&FocalSphere::new(ray.origin(), &ball));
                    tests(n, &e, |e| Focal::roots(&rp, e), root_hits)
                }
                _ => {
                    let e = FocalSphere::<L>::splat(&FocalSphere::unguarded(ray.origin(), &ball));
                    tests(n, &e, |e| FocalUnguarded::roots(&rp, e), root_hits)
                }
            }
        }
    })
}

/// [`repeat`] on [`Path::Precompute`]: `n` records or caches of the worked primitive, each
/// from a primitive the compiler must reload; returns how many were built.
fn build<L: Lane<Scalar = f32>>(index: usize, n: usize) -> u32 {
    fn record<K: PrecomputedKernel, L: Lane<Scalar = f32>>(n: usize) -> u32 {
        let tp = TrianglePacket::<L>::splat(&triangle());
        tests(n, &tp, |t| K::precompute(t), |_| L::LANES as u32)
    }
    let eye = triangle_rays()[1].origin();
    let sphere_eye = sphere_rays().1.origin();
    match index {
        3 => tests(n, &triangle(), |t| FocalTriangle::new(eye, t), |_| 1),
        4 => record::<Badouel, L>(n),
        6 => record::<Wald, L>(n),
        7 => record::<HavelHerout, L>(n),
        9 => record::<BaldwinWeber, L>(n),
        16 => tests(n, &ball(), |b| FocalSphere::new(sphere_eye, b), |_| 1),
        17 => tests(n, &ball(), |b| FocalSphere::unguarded(sphere_eye, b), |_| 1),
        _ => 0,
    }
}
