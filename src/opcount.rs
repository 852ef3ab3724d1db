//! Operation counting: a lane type that counts what a kernel does.
//!
//! [`Counted<L>`] wraps any [`Lane`] and forwards every operation to it, adding one to a
//! counter per multiply, addition or subtraction, division, square root and comparison. Because
//! every kernel is one generic body, running it with `Counted<f32>` measures exactly the
//! operations the scalar and SIMD paths perform per lane. (A fused multiply-add, if a kernel
//! ever used one, would count as one multiply and one addition.) Negation, absolute value,
//! `select` and mask logic are sign or bit operations and are not counted.
//!
//! [`measure`] runs a closure and returns what it counted (the difference of the counters
//! before and after). The counters are global atomics; nothing here is used by the uncounted
//! lane types.
//!
//! * Where the target has atomic read-modify-write operations (`target_has_atomic = "32"`:
//!   x86-64, AArch64, Cortex-M3/M4/M7/M33, RISC-V with the A extension), each count is a
//!   `fetch_add` and a spin lock serialises concurrent measurements, so tests may call
//!   [`measure`] from many threads. The lock is held by a guard that releases it when dropped,
//!   so a closure that panics (and unwinds) does not leave it taken.
//! * Where atomics only load and store (Cortex-M0/M0+, `thumbv6m-none-eabi`), each count is
//!   a load and a store and there is no lock: such a core runs one thread, so measurements
//!   cannot overlap (and nested ones simply include the inner counts). Counting from an
//!   interrupt handler while the main thread counts may lose increments there.

use core::fmt;
use core::ops::{Add, Div, Mul, Neg, Sub};
use core::sync::atomic::{AtomicU32, Ordering};

use crate::lane::Lane;

/// Counts of floating-point operations (per lane per test when measured with `Counted<f32>`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct OpCounts {
    /// Multiplications (squares included).
    pub mul: u32,
    /// Additions and subtractions.
    pub add: u32,
    /// Divisions.
    pub div: u32,
    /// Square roots.
    pub sqrt: u32,
    /// Comparisons (each `<`, `<=`, `>`, `>=`).
    pub cmp: u32,
}

impl OpCounts {
    /// Builds a count (handy in tests: `OpCounts::new(8, 9, 0, 1, 1)`).
    #[must_use]
    pub const fn new(mul: u32, add: u32, div: u32, sqrt: u32, cmp: u32) -> Self {
        OpCounts {
            mul,
            add,
            div,
            sqrt,
            cmp,
        }
    }

    /// Floating-point arithmetic operations (everything except compares).
    #[must_use]
    pub const fn flops(&self) -> u32 {
        self.mul + self.add + self.div + self.sqrt
    }

    /// Component-wise difference `self - earlier` (saturating at zero).
    #[must_use]
    pub const fn minus(&self, earlier: &OpCounts) -> OpCounts {
        OpCounts {
            mul: self.mul.saturating_sub(earlier.mul),
            add: self.add.saturating_sub(earlier.add),
            div: self.div.saturating_sub(earlier.div),
            sqrt: self.sqrt.saturating_sub(earlier.sqrt),
            cmp: self.cmp.saturating_sub(earlier.cmp),
        }
    }
}

impl fmt::Display for OpCounts {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} mul, {} add, {} div, {} sqrt, {} cmp",
            self.mul, self.add, self.div, self.sqrt, self.cmp
        )
    }
}

static MUL: AtomicU32 = AtomicU32::new(0);
static ADD: AtomicU32 = AtomicU32::new(0);
static DIV: AtomicU32 = AtomicU32::new(0);
static SQRT: AtomicU32 = AtomicU32::new(0);
static CMP: AtomicU32 = AtomicU32::new(0);

/// One more on counter `c`.
#[cfg(target_has_atomic = "32")]
#[inline(always)]
fn bump(c: &AtomicU32) {
    c.fetch_add(1, Ordering::Relaxed);
}

/// One more on counter `c`: a load and a store (no read-modify-write on this target; one
/// thread of execution, see the [module docs](self)).
#[cfg(not(target_has_atomic = "32"))]
#[inline(always)]
fn bump(c: &AtomicU32) {
    c.store(c.load(Ordering::Relaxed).wrapping_add(1), Ordering::Relaxed);
}

fn snapshot() -> OpCounts {
    OpCounts {
        mul: MUL.load(Ordering::Relaxed),
        add: ADD.load(Ordering::Relaxed),
        div: DIV.load(Ordering::Relaxed),
        sqrt: SQRT.load(Ordering::Relaxed),
        cmp: CMP.load(Ordering::Relaxed),
    }
}

/// The measurement lock: held by a [`Held`] guard.
#[cfg(target_has_atomic = "32")]
static LOCK: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

/// Holds the measurement lock; dropping it (also while unwinding) releases the lock.
struct Held;

impl Held {
    #[cfg(target_has_atomic = "32")]
    fn take() -> Held {
        while LOCK
            .compare_exchange_weak(false, true, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            core::hint::spin_loop();
        }
        Held
    }

    /// No lock where atomics only load and store: one thread of execution.
    #[cfg(not(target_has_atomic = "32"))]
    fn take() -> Held {
        Held
    }
}

impl Drop for Held {
    fn drop(&mut self) {
        #[cfg(target_has_atomic = "32")]
        LOCK.store(false, Ordering::Release);
    }
}

/// Runs `f` and returns its result with the operations it performed on [`Counted`] lanes.
///
/// Measurements are serialised by a spin lock, so concurrent callers do not mix their counts;
/// the lock is released when `f` returns or panics. (On targets without atomic
/// read-modify-write there is no lock: see the [module docs](self).)
pub fn measure<R>(f: impl FnOnce() -> R) -> (R, OpCounts) {
    let held = Held::take();
    let before = snapshot();
    let r = f();
    let counts = snapshot().minus(&before);
    drop(held);
    (r, counts)
}

/// A lane that counts its operations: see the [module docs](self).
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct Counted<L>(pub L);

impl<L: Lane> Add for Counted<L> {
    type Output = Self;
    #[inline]
    fn add(self, rhs: Self) -> Self {
        bump(&ADD);
        Counted(self.0 + rhs.0)
    }
}

impl<L: Lane> Sub for Counted<L> {
    type Output = Self;
    #[inline]
    fn sub(self, rhs: Self) -> Self {
        bump(&ADD);
        Counted(self.0 - rhs.0)
    }
}

impl<L: Lane> Mul for Counted<L> {
    type Output = Self;
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        bump(&MUL);
        Counted(self.0 * rhs.0)
    }
}

impl<L: Lane> Div for Counted<L> {
    type Output = Self;
    #[inline]
    fn div(self, rhs: Self) -> Self {
        bump(&DIV);
        Counted(self.0 / rhs.0)
    }
}

impl<L: Lane> Neg for Counted<L> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Counted(-self.0)
    }
}

impl<L: Lane> Lane for Counted<L> {
    type Scalar = L::Scalar;
    type Mask = L::Mask;
    type Precise = Counted<L::Precise>;
    type Indices = L::Indices;
    const LANES: usize = L::LANES;

    #[inline]
    fn splat(x: Self::Scalar) -> Self {
        Counted(L::splat(x))
    }
    #[inline]
    fn sqrt(self) -> Self {
        bump(&SQRT);
        Counted(self.0.sqrt())
    }
    #[inline]
    fn lt(self, rhs: Self) -> Self::Mask {
        bump(&CMP);
        self.0.lt(rhs.0)
    }
    #[inline]
    fn le(self, rhs: Self) -> Self::Mask {
        bump(&CMP);
        self.0.le(rhs.0)
    }
    #[inline]
    fn gt(self, rhs: Self) -> Self::Mask {
        bump(&CMP);
        self.0.gt(rhs.0)
    }
    #[inline]
    fn ge(self, rhs: Self) -> Self::Mask {
        bump(&CMP);
        self.0.ge(rhs.0)
    }
    #[inline]
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self {
        Counted(L::select(mask, a.0, b.0))
    }
    #[inline]
    fn abs(self) -> Self {
        Counted(self.0.abs())
    }
    #[inline]
    fn is_finite(self) -> Self::Mask {
        self.0.is_finite()
    }
    #[inline]
    fn lane(self, i: usize) -> Self::Scalar {
        self.0.lane(i)
    }
    #[inline]
    fn from_fn(f: impl FnMut(usize) -> Self::Scalar) -> Self {
        Counted(L::from_fn(f))
    }
    #[inline]
    fn indices(v: u32) -> Self::Indices {
        L::indices(v)
    }
    #[inline]
    fn precise_lane(self, i: usize) -> Self::Precise {
        Counted(self.0.precise_lane(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_each_kind() {
        let ((), c) = measure(|| {
            let a = Counted(2.0f32);
            let b = Counted(3.0f32);
            let s = (a * b + a - b) / a;
            let _ = s.sqrt().gt(a);
            let _ = -s;
            let _ = Counted::select(true, a, b);
        });
        assert_eq!(c, OpCounts::new(1, 2, 1, 1, 1));
    }
}

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
/// a query does once per ray (where there is any: [`Shear::new`](crate::triangle::Shear::new),
/// `FocalRays::new`). The precomputed methods are counted
/// as their [`TriangleKernel`](crate::triangle::TriangleKernel) runs them, precomputing on
/// the fly (the study separates the two). Besides the kernels: `geometric-prepared` (the
/// geometric test with `T` and `c²` prepared per eye), `sphere-point` and `sphere-surface`
/// (the hit point, and the point with its normal), and `bound`, the conservative line–sphere
/// culling test of [`Bound::may_hit`](crate::bounds::Bound::may_hit), per ray and mesh.
#[must_use]
pub fn table() -> Table {
    use crate::registry::{Kernel, Prim};
    let mut t = Table::new();
    let ex = examples::Examples::new();
    for prim in Prim::ALL {
        for k in Kernel::of(prim) {
            k.visit(examples::Paths { t: &mut t, ex: &ex });
        }
        if prim == Prim::Sphere {
            examples::sphere_extras(&mut t, &ex);
        }
    }
    examples::bound(&mut t, &ex);
    t
}

mod examples {
    //! The worked examples of [`table`](super::table) and the measurement of each path.

    use glam::Vec3;

    use super::{Counted, OpCounts, Table, measure};
    use crate::plane::{self, FocalPlane, Plane, PlanePacket};
    use crate::ray::{Ray, RayPacket};
    use crate::registry::{Kernel, Visitor};
    use crate::sphere::focal::FocalKernel;
    use crate::sphere::{self as sp, FocalSphere, Geometric, SphereKernel, SpherePacket};
    use crate::triangle::focal as tf;
    use crate::triangle::focal::FocalRays;
    use crate::triangle::{Cull, FocalTriangle, Triangle, TriangleKernel, TrianglePacket};

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
        pub(super) t: &'a mut Table,
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
    pub(super) fn sphere_extras(t: &mut Table, ex: &Examples) {
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
    pub(super) fn bound(t: &mut Table, ex: &Examples) {
        let b = crate::bounds::Bound::new(&sp::Sphere::new(Vec3::new(2.0, 1.5, 0.0), 2.5));
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
