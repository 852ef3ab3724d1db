//! Lanes: the one abstraction every kernel is written over.
//!
//! A kernel in this crate is a generic function over [`Lane`]. The same body then runs as
//!
//! * the scalar reference (`f32`), a higher-precision scalar (`f64`),
//! * packets of 4, 8 or 16 rays or primitives (`wide::f32x4`, `f32x8`, `f32x16`),
//! * the op-counting type [`Counted`](crate::opcount::Counted), which counts every multiply,
//!   addition, division, square root and compare the body performs.
//!
//! Only correctly rounded IEEE-754 operations (`+ - * /`, `sqrt`, compares) are offered, and a
//! generic body fixes their order, so every lane of every width returns the same bits as the
//! scalar path, on every target. No fused multiply-add is used.
//!
//! Branches become masks: a comparison yields a [`Mask`], [`Lane::select`] picks per lane, and a
//! kernel returns early when [`Mask::any`] says no lane is left (for `f32` the mask is `bool`,
//! so the scalar path simply branches).

use core::fmt::Debug;
use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use wide::{f32x4, f32x8, f32x16};

mod portable;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use portable::X8;
#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{Y8, Y16};

/// The element type of a lane: `f32` or `f64`.
pub trait Scalar: Copy + Debug + PartialOrd + Default + 'static {
    /// Widens to `f64` (exact for both `f32` and `f64`).
    fn to_f64(self) -> f64;
    /// Rounds an `f64` to this type (to nearest, ties to even).
    fn from_f64(x: f64) -> Self;
    /// Converts an `f32` exactly.
    fn from_f32(x: f32) -> Self;
}

impl Scalar for f32 {
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn from_f32(x: f32) -> Self {
        x
    }
}

impl Scalar for f64 {
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn from_f32(x: f32) -> Self {
        x as f64
    }
}

/// A per-lane boolean: `bool` for scalar lanes, an all-ones/all-zeros SIMD vector for packets.
pub trait Mask:
    Copy + Debug + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self>
{
    /// The same value in every lane.
    fn splat(b: bool) -> Self;
    /// True when some lane is set.
    fn any(self) -> bool;
    /// True when every lane is set.
    fn all(self) -> bool;
    /// Bit `i` is lane `i`.
    fn bits(self) -> u32;
    /// Returns `self` with lane `i` set to `b` (unchanged when there is no lane `i`).
    fn with_lane(self, i: usize, b: bool) -> Self;
    /// The mask whose lane `i` is bit `i` of `bits` (bits past the lanes ignored).
    #[inline(always)]
    fn from_bits(mut bits: u32) -> Self {
        let mut m = Self::splat(false);
        while bits != 0 {
            m = m.with_lane(bits.trailing_zeros() as usize, true);
            bits &= bits - 1;
        }
        m
    }
    /// True when no lane is set.
    #[inline(always)]
    fn none(self) -> bool {
        !self.any()
    }
    /// Lane `i`.
    #[inline(always)]
    fn test(self, i: usize) -> bool {
        (self.bits() >> i) & 1 != 0
    }
    /// `self & !other`.
    #[inline(always)]
    fn and_not(self, other: Self) -> Self {
        self & !other
    }
}

impl Mask for bool {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        b
    }
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn all(self) -> bool {
        self
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self as u32
    }
    #[inline(always)]
    fn with_lane(self, _i: usize, b: bool) -> Self {
        b
    }
}

/// The most lanes a [`Lane`] type may have: 16 (`wide::f32x16`).
///
/// Lane-sized scratch arrays (in [`V3::from_fn`](crate::vec3::V3::from_fn),
/// [`TrianglePacket::from_fn`](crate::triangle::TrianglePacket::from_fn),
/// `FocalRays::new`, the vector runner and the demo) have
/// this length, and each of them checks `L::LANES <= MAX_LANES` at compile time
/// ([`assert_fits`]): a wider lane type is a compile error, never a wrong result.
///
/// ```compile_fail,E0080
/// # use raylane::{Lane, V3, lane::MAX_LANES};
/// # use glam::Vec3;
/// // A 32-lane type (here a scalar that claims 32 lanes) is refused where lanes are gathered.
/// #[derive(Clone, Copy, Debug)]
/// struct Wide32(f32);
/// # use core::ops::*;
/// # impl Add for Wide32 { type Output = Self; fn add(self, o: Self) -> Self { Wide32(self.0 + o.0) } }
/// # impl Sub for Wide32 { type Output = Self; fn sub(self, o: Self) -> Self { Wide32(self.0 - o.0) } }
/// # impl Mul for Wide32 { type Output = Self; fn mul(self, o: Self) -> Self { Wide32(self.0 * o.0) } }
/// # impl Div for Wide32 { type Output = Self; fn div(self, o: Self) -> Self { Wide32(self.0 / o.0) } }
/// # impl Neg for Wide32 { type Output = Self; fn neg(self) -> Self { Wide32(-self.0) } }
/// impl Lane for Wide32 {
///     const LANES: usize = 32;
///     // ... every other item as for f32 ...
/// #   type Scalar = f32; type Mask = bool; type Precise = f64; type Indices = [u32; 1];
/// #   fn splat(x: f32) -> Self { Wide32(x) }
/// #   fn sqrt(self) -> Self { self }
/// #   fn lt(self, r: Self) -> bool { self.0 < r.0 }
/// #   fn le(self, r: Self) -> bool { self.0 <= r.0 }
/// #   fn gt(self, r: Self) -> bool { self.0 > r.0 }
/// #   fn ge(self, r: Self) -> bool { self.0 >= r.0 }
/// #   fn select(m: bool, a: Self, b: Self) -> Self { if m { a } else { b } }
/// #   fn abs(self) -> Self { self }
/// #   fn is_finite(self) -> bool { true }
/// #   fn lane(self, _: usize) -> f32 { self.0 }
/// #   fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self { Wide32(f(0)) }
/// #   fn indices(v: u32) -> [u32; 1] { [v] }
/// #   fn precise_lane(self, _: usize) -> f64 { self.0 as f64 }
/// }
/// let _ = V3::<Wide32>::from_fn(|_| Vec3::ZERO);
/// ```
pub const MAX_LANES: usize = 16;

/// An exact power of two, `2^e` (for `-126 ≤ e ≤ 127`), in constants and kernels alike.
#[inline(always)]
pub(crate) const fn pow2(e: i32) -> f32 {
    f32::from_bits(((127 + e) as u32) << 23)
}

/// Compile-time check that `L` has at most [`MAX_LANES`] lanes: called by every function that
/// gathers lanes into a `[_; MAX_LANES]` array, it fails the build (error E0080) when that
/// function is instantiated with a wider lane type.
#[inline(always)]
pub const fn assert_fits<L: Lane>() {
    const {
        assert!(
            L::LANES <= MAX_LANES,
            "raylane supports at most MAX_LANES (16) lanes per lane type"
        )
    }
}

/// A lane of floating-point values: the type every kernel is generic over.
///
/// Arithmetic (`+ - * /`, [`sqrt`](Lane::sqrt)) and comparisons are the operations a kernel may
/// count on; they are all correctly rounded. [`select`](Lane::select), [`abs`](Lane::abs),
/// negation and mask operations are sign or bit manipulations and are not counted as
/// floating-point work.
pub trait Lane:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The element type.
    type Scalar: Scalar;
    /// The per-lane boolean.
    type Mask: Mask;
    /// A single `f64` lane used for rare higher-precision fallbacks of one lane
    /// (`f64` itself, or `Counted<f64>` when counting): a lane whose f32 products would under-
    /// or overflow is recomputed in it, so the fallback is counted like the rest of a kernel.
    type Precise: Lane<Scalar = f64>;
    /// One `u32` per lane, for primitive indices in hit records.
    type Indices: Copy + Debug + PartialEq + AsRef<[u32]> + AsMut<[u32]>;
    /// Number of lanes.
    const LANES: usize;
    /// True for lanes of plain `f32` values (the scalar lane and `wide`'s vectors): a packet
    /// of them may continue lane by lane through the one-ray traversal (the same answers).
    /// False for counting and higher-precision lanes, whose work stays in the lane type.
    const PLAIN_F32: bool = false;

    /// The same value in every lane.
    fn splat(x: Self::Scalar) -> Self;
    /// An `f32` constant in every lane (exact).
    #[inline(always)]
    fn from_f32(x: f32) -> Self {
        Self::splat(Self::Scalar::from_f32(x))
    }
    /// Correctly rounded square root.
    fn sqrt(self) -> Self;
    /// `self < rhs` per lane (false when either is NaN).
    fn lt(self, rhs: Self) -> Self::Mask;
    /// `self <= rhs` per lane (false when either is NaN).
    fn le(self, rhs: Self) -> Self::Mask;
    /// `self > rhs` per lane (false when either is NaN).
    fn gt(self, rhs: Self) -> Self::Mask;
    /// `self >= rhs` per lane (false when either is NaN).
    fn ge(self, rhs: Self) -> Self::Mask;
    /// `if mask { a } else { b }` per lane.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// Absolute value (clears the sign bit; not counted).
    fn abs(self) -> Self;
    /// True where the value is neither NaN nor infinite (a bit test; not counted).
    fn is_finite(self) -> Self::Mask;
    /// The value where it is finite, NaN where it is infinite (or NaN): a kernel's early
    /// exit `x.finite_or_nan().lt(0)` is then one compare that sends infinite values on, as
    /// `!(x < 0) | !finite(x)` does (not counted). By default `x + (x − x)` (`x − x` is `+0`
    /// for every finite `x`, NaN otherwise: the same value, exactly, or NaN), where arithmetic
    /// is hardware; a bit test where it is software.
    #[inline(always)]
    #[allow(clippy::eq_op)] // `x − x`: +0 for every finite x, NaN otherwise
    fn finite_or_nan(self) -> Self {
        self + (self - self)
    }
    /// Lane `i`.
    fn lane(self, i: usize) -> Self::Scalar;
    /// Builds a lane value from its elements.
    fn from_fn(f: impl FnMut(usize) -> Self::Scalar) -> Self;
    /// Every index set to `v`.
    fn indices(v: u32) -> Self::Indices;
    /// `b` set to `a` in the lanes of `mask` (the others unchanged): the winners' indices of
    /// a closest-hit collector. By default lane by lane over `mask`'s bits; packets of `f32`
    /// lanes blend them as one vector.
    #[inline(always)]
    fn select_indices(mask: Self::Mask, a: u32, b: &mut Self::Indices) {
        let mut bits = mask.bits();
        let out = b.as_mut();
        while bits != 0 {
            if let Some(slot) = out.get_mut(bits.trailing_zeros() as usize) {
                *slot = a;
            }
            bits &= bits - 1;
        }
    }
    /// Lane `i` as a single higher-precision lane (exact widening).
    fn precise_lane(self, i: usize) -> Self::Precise;

    /// Builds a lane value from `f32` elements (exact).
    #[inline(always)]
    fn from_f32_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        Self::from_fn(|i| Self::Scalar::from_f32(f(i)))
    }
    /// Returns `self` with lane `i` replaced by `v`.
    #[inline(always)]
    fn with_lane(self, i: usize, v: Self::Scalar) -> Self {
        Self::from_fn(|j| if j == i { v } else { self.lane(j) })
    }
    /// The largest lane, as `f32` (for lanes without NaN; a comparison, not counted). The
    /// traversal's packet bounds use it: halves compared as vectors where the lanes are one.
    #[inline(always)]
    fn max_lane(self) -> f32 {
        let mut r = f32::NEG_INFINITY;
        for i in 0..Self::LANES {
            let v = self.lane(i).to_f64() as f32;
            if v > r {
                r = v;
            }
        }
        r
    }
}

/// Correctly rounded `f32` square root for the scalar lane.
///
/// x86-64 (`sqrtss`) and AArch64 (`fsqrt`) get the instruction through `libm`; on Cortex-M
/// with a hard-float FPU the `vsqrt.f32` instruction is used directly, and on RISC-V with the
/// F extension `fsqrt.s`. Cores without a floating-point square root (Cortex-M0/M3, RISC-V
/// without F) use `libm`'s correctly rounded software root. All of them are IEEE-754
/// correctly rounded, so all targets agree to the bit.
#[inline(always)]
pub fn sqrt_f32(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        arm_vsqrt(x)
    }
    #[cfg(all(any(target_arch = "riscv32", target_arch = "riscv64"), raylane_riscv_f))]
    {
        riscv_fsqrt(x)
    }
    #[cfg(not(any(
        all(target_arch = "arm", target_abi = "eabihf"),
        all(any(target_arch = "riscv32", target_arch = "riscv64"), raylane_riscv_f)
    )))]
    {
        libm::sqrtf(x)
    }
}

#[cfg(all(any(target_arch = "riscv32", target_arch = "riscv64"), raylane_riscv_f))]
#[inline(always)]
fn riscv_fsqrt(x: f32) -> f32 {
    let root: f32;
    // SAFETY: fsqrt.s reads and writes only the given float registers and the accrued
    // exception flags in fcsr; the F extension has it (build.rs sets `raylane_riscv_f` only
    // then). Rounding: the dynamic mode, round to nearest even unless software changes frm.
    unsafe {
        core::arch::asm!(
            "fsqrt.s {r}, {x}",
            r = lateout(freg) root,
            x = in(freg) x,
            options(pure, nomem, nostack, preserves_flags),
        );
    }
    root
}

#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
#[inline(always)]
fn arm_vsqrt(x: f32) -> f32 {
    // Stable Rust refuses the `sreg` register class on thumb targets, but accepts `s0` named
    // as a discarded output, which LLVM treats as a clobber: the value travels through a core
    // register and nothing live is kept in s0.
    let mut bits = x.to_bits();
    // SAFETY: vsqrt.f32 reads and writes only s0 (declared clobbered) and FPSCR's cumulative
    // exception flags; every eabihf target has the FPU.
    unsafe {
        core::arch::asm!(
            "vmov s0, {v}",
            "vsqrt.f32 s0, s0",
            "vmov {v}, s0",
            v = inout(reg) bits,
            out("s0") _,
            options(pure, nomem, nostack, preserves_flags),
        );
    }
    f32::from_bits(bits)
}

/// True on targets whose `f32` arithmetic is hardware: x86-64, AArch64, Arm with a hard-float
/// ABI (Cortex-M4F, M7, M33) and RISC-V with the F extension. Elsewhere (Cortex-M0, M3, RISC-V
/// without F) an add is a library call, and bit tests are cheaper.
const HARD_FLOAT: bool = cfg!(any(
    target_arch = "x86_64",
    target_arch = "aarch64",
    all(target_arch = "arm", target_abi = "eabihf"),
    raylane_riscv_f
));

/// True where `x` is neither NaN nor infinite. Where floating-point arithmetic is hardware
/// (x86-64, AArch64) as `x − x == 0` (`±0` exactly for every finite `x`, NaN otherwise): one
/// subtraction and one compare, which LLVM keeps as such (the bit test combines with a
/// kernel's own compare of the same value into a class test that x86-64 lowers to a dozen
/// integer instructions). Elsewhere (Cortex-M, RISC-V, possibly without an FPU) the bit
/// test. The same answer for every input; not counted as floating-point work.
#[inline(always)]
#[allow(clippy::eq_op)] // `x − x`: +0 for every finite x, NaN otherwise
fn finite_f32(x: f32) -> bool {
    #[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
    {
        x - x == 0.0
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        x.to_bits() & 0x7f80_0000 != 0x7f80_0000
    }
}

impl Lane for f32 {
    const PLAIN_F32: bool = true;
    type Scalar = f32;
    type Mask = bool;
    type Precise = f64;
    type Indices = [u32; 1];
    const LANES: usize = 1;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        sqrt_f32(self)
    }
    #[inline(always)]
    fn lt(self, rhs: Self) -> bool {
        self < rhs
    }
    #[inline(always)]
    fn le(self, rhs: Self) -> bool {
        self <= rhs
    }
    #[inline(always)]
    fn gt(self, rhs: Self) -> bool {
        self > rhs
    }
    #[inline(always)]
    fn ge(self, rhs: Self) -> bool {
        self >= rhs
    }
    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask { a } else { b }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::from_bits(self.to_bits() & 0x7fff_ffff)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        finite_f32(self)
    }
    #[inline(always)]
    #[allow(clippy::eq_op)] // `x − x`: +0 for every finite x, NaN otherwise
    fn finite_or_nan(self) -> Self {
        if HARD_FLOAT {
            self + (self - self)
        } else if finite_f32(self) {
            self
        } else {
            f32::NAN
        }
    }
    #[inline(always)]
    fn lane(self, _i: usize) -> f32 {
        self
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        f(0)
    }
    #[inline(always)]
    fn indices(v: u32) -> [u32; 1] {
        [v]
    }
    #[inline(always)]
    fn precise_lane(self, _i: usize) -> f64 {
        self as f64
    }
}

impl Lane for f64 {
    type Scalar = f64;
    type Mask = bool;
    type Precise = f64;
    type Indices = [u32; 1];
    const LANES: usize = 1;

    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        libm::sqrt(self)
    }
    #[inline(always)]
    fn lt(self, rhs: Self) -> bool {
        self < rhs
    }
    #[inline(always)]
    fn le(self, rhs: Self) -> bool {
        self <= rhs
    }
    #[inline(always)]
    fn gt(self, rhs: Self) -> bool {
        self > rhs
    }
    #[inline(always)]
    fn ge(self, rhs: Self) -> bool {
        self >= rhs
    }
    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask { a } else { b }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::from_bits(self.to_bits() & 0x7fff_ffff_ffff_ffff)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        self.to_bits() & 0x7ff0_0000_0000_0000 != 0x7ff0_0000_0000_0000
    }
    #[inline(always)]
    fn lane(self, _i: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        f(0)
    }
    #[inline(always)]
    fn indices(v: u32) -> [u32; 1] {
        [v]
    }
    #[inline(always)]
    fn precise_lane(self, _i: usize) -> f64 {
        self
    }
}

/// Implements [`Mask`] and [`Lane`] for a `wide` f32 vector type: one macro, so the widths
/// cannot drift apart.
macro_rules! wide_lane {
    ($t:ident, $n:literal, $max:ident) => {
        impl Mask for $t {
            #[inline(always)]
            fn splat(b: bool) -> Self {
                $t::splat(f32::from_bits(if b { u32::MAX } else { 0 }))
            }
            #[inline(always)]
            fn any(self) -> bool {
                $t::any(self)
            }
            #[inline(always)]
            fn all(self) -> bool {
                $t::all(self)
            }
            #[inline(always)]
            fn bits(self) -> u32 {
                self.to_bitmask()
            }
            #[inline(always)]
            fn with_lane(self, i: usize, b: bool) -> Self {
                let mut a = self.to_array();
                if let Some(x) = a.get_mut(i) {
                    *x = f32::from_bits(if b { u32::MAX } else { 0 });
                }
                $t::new(a)
            }
        }

        impl Lane for $t {
            type Scalar = f32;
            type Mask = $t;
            type Precise = f64;
            type Indices = [u32; $n];
            const LANES: usize = $n;
            const PLAIN_F32: bool = true;

            #[inline(always)]
            fn splat(x: f32) -> Self {
                $t::splat(x)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                #[cfg(any(
                    all(target_arch = "arm", target_abi = "eabihf"),
                    all(any(target_arch = "riscv32", target_arch = "riscv64"), raylane_riscv_f)
                ))]
                {
                    // wide's portable fallback is a software f64 root; use the FPU per lane.
                    let a = self.to_array();
                    $t::new(core::array::from_fn(|i| sqrt_f32(a[i])))
                }
                #[cfg(not(any(
                    all(target_arch = "arm", target_abi = "eabihf"),
                    all(any(target_arch = "riscv32", target_arch = "riscv64"), raylane_riscv_f)
                )))]
                {
                    $t::sqrt(self)
                }
            }
            #[inline(always)]
            fn lt(self, rhs: Self) -> Self {
                self.simd_lt(rhs)
            }
            #[inline(always)]
            fn le(self, rhs: Self) -> Self {
                self.simd_le(rhs)
            }
            #[inline(always)]
            fn gt(self, rhs: Self) -> Self {
                self.simd_gt(rhs)
            }
            #[inline(always)]
            fn ge(self, rhs: Self) -> Self {
                self.simd_ge(rhs)
            }
            #[inline(always)]
            fn select(mask: Self, a: Self, b: Self) -> Self {
                mask.select(a, b)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                $t::abs(self)
            }
            #[inline(always)]
            fn is_finite(self) -> Self {
                // As for `f32` (see `finite_f32`): `x − x == 0` where arithmetic is hardware.
                #[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
                {
                    (self - self).simd_eq($t::ZERO)
                }
                #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
                {
                    $t::is_finite(self)
                }
            }
            #[inline(always)]
            #[allow(clippy::eq_op)] // `x − x`: +0 for every finite x, NaN otherwise
            fn finite_or_nan(self) -> Self {
                if HARD_FLOAT {
                    self + (self - self)
                } else {
                    Lane::select(Lane::is_finite(self), self, $t::splat(f32::NAN))
                }
            }
            #[inline(always)]
            fn lane(self, i: usize) -> f32 {
                self.as_array()[i]
            }
            #[inline(always)]
            fn from_fn(f: impl FnMut(usize) -> f32) -> Self {
                // On x86-64 a loop, not `core::array::from_fn`: that stays out of line inside a
                // SIMD level's copy, and `f`'s reads of the level's vectors with it (a call
                // per lane: the records of AVX-512 packets converted out cost half the
                // render's primary rays). Elsewhere unchanged (code sizes).
                #[cfg(target_arch = "x86_64")]
                {
                    let mut f = f;
                    let mut a = [0.0f32; $n];
                    for (i, x) in a.iter_mut().enumerate() {
                        *x = f(i);
                    }
                    $t::new(a)
                }
                #[cfg(not(target_arch = "x86_64"))]
                {
                    $t::new(core::array::from_fn(f))
                }
            }
            #[inline(always)]
            fn indices(v: u32) -> [u32; $n] {
                [v; $n]
            }
            #[inline(always)]
            fn select_indices(mask: Self, a: u32, b: &mut [u32; $n]) {
                // A bitwise blend: the indices travel as the bits of f32 lanes.
                let old: $t = bytemuck::cast(*b);
                *b = bytemuck::cast(mask.select($t::splat(f32::from_bits(a)), old));
            }
            #[inline(always)]
            fn precise_lane(self, i: usize) -> f64 {
                self.as_array()[i] as f64
            }
            #[inline(always)]
            fn with_lane(self, i: usize, v: f32) -> Self {
                let mut a = self.to_array();
                a[i] = v;
                $t::new(a)
            }
            #[inline(always)]
            fn max_lane(self) -> f32 {
                $max(self)
            }
        }
    };
}

/// The largest of 4 lanes: pairs, then the pair's maxima.
#[inline(always)]
fn max4(v: f32x4) -> f32 {
    let a = v.to_array();
    let (x, y) = (
        if a[1] > a[0] { a[1] } else { a[0] },
        if a[3] > a[2] { a[3] } else { a[2] },
    );
    if y > x { y } else { x }
}

/// The largest of 8 lanes: the halves' lane-wise maxima, then 4 lanes.
#[inline(always)]
fn max8(v: f32x8) -> f32 {
    let a = v.to_array();
    let (lo, hi) = (
        f32x4::new([a[0], a[1], a[2], a[3]]),
        f32x4::new([a[4], a[5], a[6], a[7]]),
    );
    max4(hi.simd_gt(lo).select(hi, lo))
}

/// The largest of 16 lanes: the halves' lane-wise maxima, then 8 lanes.
#[inline(always)]
fn max16(v: f32x16) -> f32 {
    let a = v.to_array();
    let lo = f32x8::new(core::array::from_fn(|i| a[i]));
    let hi = f32x8::new(core::array::from_fn(|i| a[8 + i]));
    max8(hi.simd_gt(lo).select(hi, lo))
}

wide_lane!(f32x4, 4, max4);
wide_lane!(f32x8, 8, max8);
wide_lane!(f32x16, 16, max16);

#[cfg(test)]
mod tests {
    use super::*;

    fn check_width<L: Lane<Scalar = f32>>() {
        let a = L::from_fn(|i| i as f32 - 1.5);
        let b = L::splat(0.25);
        let m = a.gt(b);
        for i in 0..L::LANES {
            assert_eq!(m.test(i), (i as f32 - 1.5) > 0.25);
            assert_eq!(
                L::select(m, a, b).lane(i),
                if m.test(i) { a.lane(i) } else { 0.25 }
            );
        }
        assert_eq!((<L::Mask as Mask>::splat(true) & m).bits(), m.bits());
        let nan = L::splat(f32::NAN);
        assert!(nan.lt(nan).none() && nan.ge(nan).none());
        assert!(nan.is_finite().none() && L::splat(f32::INFINITY).is_finite().none());
        assert!(b.is_finite().all());
        assert_eq!(
            L::splat(2.0).sqrt().lane(L::LANES - 1),
            core::f32::consts::SQRT_2
        );
        assert_eq!(a.with_lane(0, 7.0).lane(0), 7.0);
    }

    #[test]
    fn widths_agree_with_scalar() {
        check_width::<f32>();
        check_width::<f32x4>();
        check_width::<f32x8>();
        check_width::<f32x16>();
    }
}
