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
    fn finite_or_nan(self) -> Self {
        Counted(self.0.finite_or_nan())
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
