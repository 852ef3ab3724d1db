//! The op-count report: every kernel of the [registry](crate::registry) measured with the
//! library's counting lane ([`Counted`]) on the lectures' worked examples.

use core::fmt;

use raylane::opcount::{Counted, OpCounts, measure};

/// One row of the operation-count report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Row {
    /// Kernel name.
    pub kernel: &'static str,
    /// `miss`, `hit`, or a named path (e.g. `doubtful`).
    pub path: &'static str,
    /// What one test of one lane performed.
    pub counts: OpCounts,
}

/// Most rows the report holds.
pub const MAX_ROWS: usize = 96;

/// The report's rows: see [`table`]. Derefs to `[Row]`.
#[derive(Clone, Copy, Debug)]
pub struct Table {
    rows: [Row; MAX_ROWS],
    len: usize,
}

impl Table {
    fn new() -> Self {
        let empty = Row {
            kernel: "",
            path: "",
            counts: OpCounts::default(),
        };
        Table {
            rows: [empty; MAX_ROWS],
            len: 0,
        }
    }
}

/// Where the report's rows go: a [`Table`], or a callback ([`each_row`]).
trait Rows {
    /// One row.
    fn push(&mut self, kernel: &'static str, path: &'static str, counts: OpCounts);
}

impl Rows for Table {
    /// Adds a row (dropped past [`MAX_ROWS`]; a test checks the report fits).
    fn push(&mut self, kernel: &'static str, path: &'static str, counts: OpCounts) {
        if let Some(slot) = self.rows.get_mut(self.len) {
            *slot = Row {
                kernel,
                path,
                counts,
            };
            self.len += 1;
        }
    }
}

impl core::ops::Deref for Table {
    type Target = [Row];
    fn deref(&self) -> &[Row] {
        self.rows.get(..self.len).unwrap_or(&[])
    }
}

impl IntoIterator for Table {
    type Item = Row;
    type IntoIter = core::iter::Take<core::array::IntoIter<Row, MAX_ROWS>>;
    fn into_iter(self) -> Self::IntoIter {
        self.rows.into_iter().take(self.len)
    }
}

/// The report: every kernel of the [registry](crate::registry) on a miss and on a hit (and its
/// other paths), measured with `Counted<f32>` on the lectures' worked examples (sphere centre
/// (5,5,5), radius 3; the miss ray from the origin along (1,3,4)/√26, the hit ray from (1,0,1)
/// along (1,2,1)/√6), spheres, then planes, then triangles.
///
/// Triangles: A = (0,0,0), B = (4,0,0), C = (0,3,0) and rays along (0,0,−1) (`Ray::new`,
/// interval (0, inf)): the hit from (1,1,5) (t = 5, u = 1/4, v = 1/3), the miss from (3,2,5)
/// (beyond edge BC: the latest exit of every kernel), `miss (β)` from (−1,1,5) (Cramer's
/// first exit), `behind` from (1,1,−5) along (0,0,−1) (the edges pass, the interval fails:
/// everything before the division), `zero edge` and `doubtful` from (1,1,5) through the point
/// (2,0,0) of edge AB (the exact fallbacks, both hits: the watertight kernel's `f64` edge
/// functions are counted, the focal kernel's exact predicate is not), and `per ray` the setup
/// a query does once per ray (where there is any: [`Shear::new`](raylane::triangle::Shear::new),
/// `FocalRays::new`). The precomputed methods are counted
/// as their [`TriangleKernel`](raylane::triangle::TriangleKernel) runs them, precomputing on
/// the fly (the study separates the two). Besides the kernels: `geometric-prepared` (the
/// geometric test with `T` and `c²` prepared per eye), `sphere-point` and `sphere-surface`
/// (the hit point, and the point with its normal), and `bound`, the conservative line–sphere
/// culling test of [`Bound::may_hit`](raylane::bounds::Bound::may_hit), per ray and mesh.
#[must_use]
pub fn table() -> Table {
    let mut t = Table::new();
    fill(&mut t);
    t
}

/// The rows of [`table`], one call of `f` each, in order, without storing them (the firmware
/// prints them as they come: a [`Table`] is 3.5 KB, a fifth of a Cortex-M0's RAM).
pub fn each_row(f: impl FnMut(Row)) {
    struct Each<F>(F);
    impl<F: FnMut(Row)> Rows for Each<F> {
        fn push(&mut self, kernel: &'static str, path: &'static str, counts: OpCounts) {
            (self.0)(Row {
                kernel,
                path,
                counts,
            });
        }
    }
    fill(&mut Each(f));
}

/// Every row of the report into `t`.
fn fill(t: &mut dyn Rows) {
    use crate::registry::{Kernel, Prim};
    let ex = examples::Examples::new();
    for prim in Prim::ALL {
        for k in Kernel::of(prim) {
            k.visit(examples::Paths { t, ex: &ex });
        }
        if prim == Prim::Sphere {
            examples::sphere_extras(t, &ex);
        }
    }
    examples::bound(t, &ex);
}

mod examples {
    //! The worked examples of [`table`](super::table) and the measurement of each path.

    use glam::Vec3;

    use super::{Counted, OpCounts, Rows, measure};
    use crate::registry::{Kernel, Visitor};
    use raylane::Cull;
    use raylane::plane::{self, FocalPlane, Plane, PlanePacket};
    use raylane::ray::{Ray, RayPacket};
    use raylane::sphere::focal::FocalKernel;
    use raylane::sphere::{self as sp, FocalSphere, Geometric, SphereKernel, SpherePacket};
    use raylane::triangle::focal as tf;
    use raylane::triangle::focal::FocalRays;
    use raylane::triangle::{FocalTriangle, Triangle, TriangleKernel, TrianglePacket};

    type C = Counted<f32>;

    /// The lectures' sphere and rays, and the triangle and its rays.
    pub(super) struct Examples {
        ball: sp::Sphere,
        miss: Ray,
        hit: Ray,
        /// A sphere 2^16 radii away and a ray grazing its rim: the guard cannot decide it.
        far: sp::Sphere,
        graze: Ray,
        wall: Plane,
        behind: Plane,
        tri: Triangle,
        t_hit: Ray,
        t_miss: Ray,
        t_beta: Ray,
        t_behind: Ray,
        t_edge: Ray,
    }

    impl Examples {
        pub(super) fn new() -> Self {
            let down = Vec3::new(0.0, 0.0, -1.0);
            Examples {
                ball: sp::Sphere::new(Vec3::splat(5.0), 3.0),
                miss: Ray::new(Vec3::ZERO, Vec3::new(1.0, 3.0, 4.0).normalize()),
                hit: Ray::new(
                    Vec3::new(1.0, 0.0, 1.0),
                    Vec3::new(1.0, 2.0, 1.0).normalize(),
                ),
                far: sp::Sphere::new(Vec3::new(65536.0, 1.0, 0.0), 1.0),
                graze: Ray::new(Vec3::ZERO, Vec3::X),
                wall: Plane::new(Vec3::new(2.0, 0.0, 0.0), Vec3::X),
                behind: Plane::new(Vec3::new(-2.0, 0.0, 0.0), Vec3::X),
                tri: Triangle::new(
                    Vec3::ZERO,
                    Vec3::new(4.0, 0.0, 0.0),
                    Vec3::new(0.0, 3.0, 0.0),
                ),
                t_hit: Ray::new(Vec3::new(1.0, 1.0, 5.0), down),
                t_miss: Ray::new(Vec3::new(3.0, 2.0, 5.0), down),
                t_beta: Ray::new(Vec3::new(-1.0, 1.0, 5.0), down),
                t_behind: Ray::new(Vec3::new(1.0, 1.0, -5.0), down),
                t_edge: Ray::new(Vec3::new(1.0, 1.0, 5.0), Vec3::new(1.0, -1.0, -5.0)),
            }
        }
    }

    fn sphere<K: SphereKernel>(r: &Ray, s: &sp::Sphere) -> OpCounts {
        let (rp, sp) = (RayPacket::<C>::splat(r), SpherePacket::<C>::splat(s));
        measure(|| K::roots(&rp, &sp)).1
    }

    fn focal<K: FocalKernel>(r: &Ray, s: &sp::Sphere, guarded: bool) -> OpCounts {
        let e = if guarded {
            FocalSphere::new(r.origin(), s)
        } else {
            FocalSphere::unguarded(r.origin(), s)
        };
        let (rp, ep) = (RayPacket::<C>::splat(r), FocalSphere::<C>::splat(&e));
        measure(|| K::roots(&rp, &ep)).1
    }

    fn plane(p: &Plane, focal: bool) -> OpCounts {
        let rp = RayPacket::<C>::splat(&Ray::new(Vec3::ZERO, Vec3::X));
        if focal {
            let f = FocalPlane::new(Vec3::ZERO, p);
            measure(|| f.intersect_lanes(&rp)).1
        } else {
            let pp = PlanePacket::<C>::splat(p);
            measure(|| plane::intersect_lanes(&rp, &pp)).1
        }
    }

    // Setup on counted lanes runs inside `measure` too (counts discarded): the counters are
    // global, and only what runs under its lock stays out of concurrent measurements.
    fn triangle<K: TriangleKernel>(r: &Ray, t: &Triangle) -> OpCounts {
        let rp = RayPacket::<C>::splat(r);
        let pre = measure(|| K::prepare(&rp)).0;
        let tp = TrianglePacket::<C>::splat(t);
        measure(|| K::intersect(&rp, &pre, &tp, Cull::None)).1
    }

    fn focal_triangle(r: &Ray, t: &Triangle) -> OpCounts {
        let e = FocalTriangle::<C>::splat(&FocalTriangle::new(r.origin(), t));
        let fr = measure(|| FocalRays::<C>::new(&RayPacket::splat(r))).0;
        measure(|| tf::kernel(fr.scaled(), &e, Cull::None)).1
    }

    /// Every path of one kernel into the table.
    pub(super) struct Paths<'a> {
        pub(super) t: &'a mut dyn Rows,
        pub(super) ex: &'a Examples,
    }

    impl Visitor for Paths<'_> {
        type Output = ();

        fn sphere<K: SphereKernel>(self, k: Kernel) {
            let ex = self.ex;
            self.t
                .push(k.name(), "miss", sphere::<K>(&ex.miss, &ex.ball));
            self.t.push(k.name(), "hit", sphere::<K>(&ex.hit, &ex.ball));
        }

        fn focal_sphere<K: FocalKernel>(self, k: Kernel, guarded: bool) {
            let ex = self.ex;
            let n = k.name();
            self.t
                .push(n, "miss", focal::<K>(&ex.miss, &ex.ball, guarded));
            self.t
                .push(n, "hit", focal::<K>(&ex.hit, &ex.ball, guarded));
            if guarded {
                let doubtful = focal::<K>(&ex.graze, &ex.far, guarded);
                self.t.push(n, "doubtful", doubtful);
            }
        }

        fn plane(self, k: Kernel) {
            self.t.push(k.name(), "miss", plane(&self.ex.behind, false));
            self.t.push(k.name(), "hit", plane(&self.ex.wall, false));
        }

        fn focal_plane(self, k: Kernel) {
            self.t.push(k.name(), "miss", plane(&self.ex.behind, true));
            self.t.push(k.name(), "hit", plane(&self.ex.wall, true));
        }

        fn triangle<K: TriangleKernel>(self, k: Kernel) {
            let (ex, n) = (self.ex, k.name());
            let per_ray = measure(|| K::prepare(&RayPacket::<C>::splat(&ex.t_hit))).1;
            if per_ray != OpCounts::default() {
                self.t.push(n, "per ray", per_ray);
            }
            if k == Kernel::Cramer {
                self.t
                    .push(n, "miss (β)", triangle::<K>(&ex.t_beta, &ex.tri));
            }
            self.t.push(n, "miss", triangle::<K>(&ex.t_miss, &ex.tri));
            self.t
                .push(n, "behind", triangle::<K>(&ex.t_behind, &ex.tri));
            self.t.push(n, "hit", triangle::<K>(&ex.t_hit, &ex.tri));
            if k == Kernel::Watertight {
                self.t
                    .push(n, "zero edge", triangle::<K>(&ex.t_edge, &ex.tri));
            }
        }

        fn focal_triangle(self, k: Kernel) {
            let (ex, n) = (self.ex, k.name());
            let rp = RayPacket::<C>::splat(&ex.t_hit);
            self.t.push(n, "per ray", measure(|| FocalRays::new(&rp)).1);
            self.t.push(n, "miss", focal_triangle(&ex.t_miss, &ex.tri));
            self.t
                .push(n, "behind", focal_triangle(&ex.t_behind, &ex.tri));
            self.t.push(n, "hit", focal_triangle(&ex.t_hit, &ex.tri));
            self.t
                .push(n, "doubtful", focal_triangle(&ex.t_edge, &ex.tri));
        }
    }

    /// The prepared geometric test and the hit point with and without its normal.
    pub(super) fn sphere_extras(t: &mut dyn Rows, ex: &Examples) {
        let ball = ex.ball;
        let prepared = |r: &Ray| {
            let rp = RayPacket::<C>::splat(r);
            let p = measure(|| Geometric::prepare(rp.origin(), &SpherePacket::splat(&ball))).0;
            measure(|| Geometric::roots_prepared(&rp, &p)).1
        };
        let surface = |r: &Ray, t: f32, with: bool| {
            let rp = RayPacket::<C>::splat(r);
            let s = SpherePacket::<C>::splat(&ball);
            let tc = Counted(t);
            measure(|| {
                if with {
                    let _ = sp::surface(&rp, &s, tc);
                } else {
                    let _ = rp.origin().along(rp.dir(), tc);
                }
            })
            .1
        };
        t.push("geometric-prepared", "miss", prepared(&ex.miss));
        t.push("geometric-prepared", "hit", prepared(&ex.hit));
        t.push("sphere-point", "hit", surface(&ex.hit, 4.898979, false));
        t.push("sphere-surface", "hit", surface(&ex.hit, 4.898979, true));
    }

    /// The bounding-sphere test per ray and mesh.
    pub(super) fn bound(t: &mut dyn Rows, ex: &Examples) {
        let b = raylane::bounds::Bound::new(&sp::Sphere::new(Vec3::new(2.0, 1.5, 0.0), 2.5));
        let rp = RayPacket::<C>::splat(&ex.t_hit);
        t.push("bound", "per mesh", measure(|| b.may_hit(&rp)).1);
    }
}

/// Writes the report as a Markdown table (the README's) or, with `csv`, as
/// `kernel,path,mul,add,div,sqrt,cmp` lines with a header.
pub fn write_report(out: &mut impl fmt::Write, rows: &[Row], csv: bool) -> fmt::Result {
    if csv {
        writeln!(out, "kernel,path,mul,add,div,sqrt,cmp")?;
    } else {
        writeln!(out, "| kernel | path | mul | add | div | sqrt | cmp |")?;
        writeln!(out, "| --- | --- | ---: | ---: | ---: | ---: | ---: |")?;
    }
    for r in rows {
        let c = r.counts;
        let (k, p) = (r.kernel, r.path);
        if csv {
            writeln!(
                out,
                "{k},{p},{},{},{},{},{}",
                c.mul, c.add, c.div, c.sqrt, c.cmp
            )?;
        } else {
            writeln!(
                out,
                "| {k} | {p} | {} | {} | {} | {} | {} |",
                c.mul, c.add, c.div, c.sqrt, c.cmp
            )?;
        }
    }
    Ok(())
}
