//! The operation-count study: every ray–triangle and ray–sphere method, published or
//! raylane's own, measured by the same counting lane (issue 13).
//!
//! [`entries`] measures each method with [`Counted<f32>`](crate::opcount::Counted) on the same
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
//! them with the vector files and the watertight harness).

use core::fmt;
use core::mem::size_of;

use glam::Vec3;

use crate::opcount::{Counted, OpCounts, measure, table};
use crate::ray::{Ray, RayPacket};
use crate::sphere::{self, EmbreeSphere, FocalSphere, Pbrt, SphereKernel, SpherePacket};
use crate::triangle::{
    Badouel, BaldwinWeber, Cramer, Cull, FocalTriangle, HavelHerout, KenslerShirley, Moller,
    Plucker, PrecomputedKernel, Triangle, TriangleKernel, TrianglePacket, Wald, Watertight,
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

/// Miss and hit of a sphere kernel on the lecture's examples.
fn sphere_counts<K: SphereKernel>() -> [OpCounts; 2] {
    let ball = SpherePacket::<C>::splat(&sphere::Sphere::new(Vec3::splat(5.0), 3.0));
    let miss = Ray::new(Vec3::ZERO, Vec3::new(1.0, 3.0, 4.0).normalize());
    let hit = Ray::new(
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 2.0, 1.0).normalize(),
    );
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
        "| method | source | miss | hit | behind | per ray | bytes | precompute | largest t error per class | leaks | double hits |"
    )?;
    writeln!(
        f,
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: |"
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
