//! [`X8`]: eight `f32` lanes as a plain array, whose element-wise operations the compiler turns
//! into the widest registers of the code they are inlined into. The BVH's one-ray node test
//! runs a node's 8 children in it on x86-64: inside a query entered at
//! [`simd::Level::Avx2`](crate::simd::Level) it is one AVX register, where `wide::f32x8`,
//! whose representation `wide` chose when it was compiled (SSE2 in a default x86-64 build),
//! stays two SSE halves. (Packets, whose kernels are larger, run in the levels' own vector
//! types instead: element-wise code there was not always vectorized, see
//! [`simd`](crate::simd).)
//!
//! Every operation is the IEEE operation of each lane (no fused multiply-add, no
//! approximation): the same bits as `wide`'s vectors and the scalar path. The few operations
//! a compiler does not find from element-wise code use the baseline's 4-lane instructions
//! (SSE2 or NEON) on each half, which it merges where the level is wider: the square root,
//! and the sign-bit masks ([`Mask::bits`], [`Mask::any`]).

use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

#[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
use super::sqrt_f32;
use super::{Lane, Mask};

/// Implements an `N`-lane vector type over `[f32; N]`: arithmetic, [`Mask`], [`Lane`].
macro_rules! portable {
    ($(#[$doc:meta])* $t:ident, $n:literal, $align:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        #[repr(C, align($align))]
        pub struct $t(pub [f32; $n]);

        impl $t {
            /// The lanes.
            #[inline(always)]
            #[must_use]
            pub const fn new(lanes: [f32; $n]) -> Self {
                $t(lanes)
            }

            /// `x` in every lane.
            #[inline(always)]
            #[must_use]
            pub const fn splat(x: f32) -> Self {
                $t([x; $n])
            }

            /// The lanes as an array.
            #[inline(always)]
            #[must_use]
            pub const fn to_array(self) -> [f32; $n] {
                self.0
            }

            // Plain loops, not `core::array::from_fn`: a call the compiler may leave out of
            // line in a large query would run at the baseline (see the module docs).
            #[inline(always)]
            fn map(self, f: impl Fn(f32) -> f32) -> Self {
                let mut out = self.0;
                for x in &mut out {
                    *x = f(*x);
                }
                $t(out)
            }

            #[inline(always)]
            fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
                let mut out = self.0;
                for (x, y) in out.iter_mut().zip(o.0) {
                    *x = f(*x, y);
                }
                $t(out)
            }

            #[inline(always)]
            fn compare(self, o: Self, f: impl Fn(f32, f32) -> bool) -> Self {
                self.zip(o, |a, b| all_ones(f(a, b)))
            }

            /// Lane-wise `if self < o { self } else { o }` (`o` where either is NaN: x86's
            /// `minps`).
            #[inline(always)]
            #[must_use]
            pub fn fast_min(self, o: Self) -> Self {
                self.zip(o, |a, b| if a < b { a } else { b })
            }

            /// Lane-wise `if self > o { self } else { o }` (`o` where either is NaN).
            #[inline(always)]
            #[must_use]
            pub fn fast_max(self, o: Self) -> Self {
                self.zip(o, |a, b| if a > b { a } else { b })
            }

            /// Lanes where `self <= o`, as a mask.
            #[inline(always)]
            #[must_use]
            pub fn simd_le(self, o: Self) -> Self {
                self.compare(o, |a, b| a <= b)
            }

            /// The sign bits, lane `i` as bit `i`.
            #[inline(always)]
            #[must_use]
            pub fn to_bitmask(self) -> u32 {
                Mask::bits(self)
            }

            /// `self·a + b`, rounded once where the build targets FMA, twice elsewhere (as
            /// `wide`'s): the BVH's box test, which only prunes, calls it only fused.
            #[cfg(not(all(target_arch = "x86_64", target_feature = "fma")))]
            #[inline(always)]
            #[must_use]
            pub fn mul_add(self, a: Self, b: Self) -> Self {
                self * a + b
            }

            /// `self·a + b` rounded once (the build targets FMA): the BVH's box test, which
            /// only prunes.
            #[cfg(all(target_arch = "x86_64", target_feature = "fma"))]
            #[inline(always)]
            #[must_use]
            pub fn mul_add(self, a: Self, b: Self) -> Self {
                use core::arch::x86_64::{_mm256_fmadd_ps, _mm256_loadu_ps, _mm256_storeu_ps};
                let mut out = [0.0f32; $n];
                for k in (0..$n).step_by(8) {
                    // SAFETY: the build targets FMA (and so AVX); each access is 8 lanes in
                    // bounds of the arrays.
                    unsafe {
                        let r = _mm256_fmadd_ps(
                            _mm256_loadu_ps(self.0.as_ptr().add(k)),
                            _mm256_loadu_ps(a.0.as_ptr().add(k)),
                            _mm256_loadu_ps(b.0.as_ptr().add(k)),
                        );
                        _mm256_storeu_ps(out.as_mut_ptr().add(k), r);
                    }
                }
                $t(out)
            }
        }

        impl Add for $t {
            type Output = Self;
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                self.zip(o, |a, b| a + b)
            }
        }

        impl Sub for $t {
            type Output = Self;
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                self.zip(o, |a, b| a - b)
            }
        }

        impl Mul for $t {
            type Output = Self;
            #[inline(always)]
            fn mul(self, o: Self) -> Self {
                self.zip(o, |a, b| a * b)
            }
        }

        impl Mul<f32> for $t {
            type Output = Self;
            #[inline(always)]
            fn mul(self, o: f32) -> Self {
                self.map(|a| a * o)
            }
        }

        impl Div for $t {
            type Output = Self;
            #[inline(always)]
            fn div(self, o: Self) -> Self {
                self.zip(o, |a, b| a / b)
            }
        }

        impl Neg for $t {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                self.map(|a| f32::from_bits(a.to_bits() ^ 0x8000_0000))
            }
        }

        impl BitAnd for $t {
            type Output = Self;
            #[inline(always)]
            fn bitand(self, o: Self) -> Self {
                self.zip(o, |a, b| f32::from_bits(a.to_bits() & b.to_bits()))
            }
        }

        impl BitOr for $t {
            type Output = Self;
            #[inline(always)]
            fn bitor(self, o: Self) -> Self {
                self.zip(o, |a, b| f32::from_bits(a.to_bits() | b.to_bits()))
            }
        }

        impl Not for $t {
            type Output = Self;
            #[inline(always)]
            fn not(self) -> Self {
                self.map(|a| f32::from_bits(!a.to_bits()))
            }
        }

        /// A mask is a vector whose lanes are all ones (true) or all zeros (false).
        impl Mask for $t {
            #[inline(always)]
            fn splat(b: bool) -> Self {
                $t([all_ones(b); $n])
            }
            #[inline(always)]
            fn any(self) -> bool {
                any_sign(&self.0)
            }
            #[inline(always)]
            fn all(self) -> bool {
                self.bits() == (1u32 << $n) - 1
            }
            #[inline(always)]
            fn bits(self) -> u32 {
                sign_bits(&self.0)
            }
            #[inline(always)]
            fn with_lane(mut self, i: usize, b: bool) -> Self {
                if let Some(x) = self.0.get_mut(i) {
                    *x = all_ones(b);
                }
                self
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
                $t([x; $n])
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $t(sqrt_lanes(self.0))
            }
            #[inline(always)]
            fn lt(self, rhs: Self) -> Self {
                self.compare(rhs, |a, b| a < b)
            }
            #[inline(always)]
            fn le(self, rhs: Self) -> Self {
                self.compare(rhs, |a, b| a <= b)
            }
            #[inline(always)]
            fn gt(self, rhs: Self) -> Self {
                self.compare(rhs, |a, b| a > b)
            }
            #[inline(always)]
            fn ge(self, rhs: Self) -> Self {
                self.compare(rhs, |a, b| a >= b)
            }
            #[inline(always)]
            fn select(mask: Self, a: Self, b: Self) -> Self {
                let mut out = b.0;
                for i in 0..$n {
                    let m = mask.0[i].to_bits();
                    out[i] = f32::from_bits((m & a.0[i].to_bits()) | (!m & out[i].to_bits()));
                }
                $t(out)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                self.map(|a| f32::from_bits(a.to_bits() & 0x7fff_ffff))
            }
            #[inline(always)]
            #[allow(clippy::eq_op)] // `x − x`: +0 for every finite x, NaN otherwise
            fn is_finite(self) -> Self {
                self.map(|a| all_ones(a - a == 0.0))
            }
            #[inline(always)]
            fn lane(self, i: usize) -> f32 {
                self.0[i]
            }
            #[inline(always)]
            fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
                let mut out = [0.0f32; $n];
                for (i, x) in out.iter_mut().enumerate() {
                    *x = f(i);
                }
                $t(out)
            }
            #[inline(always)]
            fn indices(v: u32) -> [u32; $n] {
                [v; $n]
            }
            #[inline(always)]
            fn select_indices(mask: Self, a: u32, b: &mut [u32; $n]) {
                for (x, m) in b.iter_mut().zip(mask.0) {
                    let m = m.to_bits();
                    *x = (m & a) | (!m & *x);
                }
            }
            #[inline(always)]
            fn precise_lane(self, i: usize) -> f64 {
                self.0[i] as f64
            }
            #[inline(always)]
            fn with_lane(mut self, i: usize, v: f32) -> Self {
                if let Some(x) = self.0.get_mut(i) {
                    *x = v;
                }
                self
            }
            #[inline(always)]
            fn max_lane(self) -> f32 {
                let mut v = self.0;
                let mut n = $n;
                while n > 1 {
                    n /= 2;
                    for i in 0..n {
                        if v[i + n] > v[i] {
                            v[i] = v[i + n];
                        }
                    }
                }
                v[0]
            }
        }
    };
}

portable!(
    /// Eight `f32` lanes (see the module docs of `lane::portable`).
    X8,
    8,
    32
);

/// All ones (a true lane) or all zeros.
#[inline(always)]
fn all_ones(b: bool) -> f32 {
    f32::from_bits(if b { u32::MAX } else { 0 })
}

/// Correctly rounded square roots of every lane: the baseline's 4-lane instruction per quarter
/// (x86-64 `sqrtps`, AArch64 `fsqrt`), the scalar root elsewhere.
#[inline(always)]
fn sqrt_lanes<const N: usize>(x: [f32; N]) -> [f32; N] {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_mm_loadu_ps, _mm_sqrt_ps, _mm_storeu_ps};
        let mut out = [0.0f32; N];
        for k in (0..N).step_by(4) {
            // SAFETY: SSE is part of x86-64; each access is 4 lanes in bounds (N is 8 or 16).
            unsafe {
                _mm_storeu_ps(
                    out.as_mut_ptr().add(k),
                    _mm_sqrt_ps(_mm_loadu_ps(x.as_ptr().add(k))),
                )
            };
        }
        out
    }
    #[cfg(target_arch = "aarch64")]
    {
        use core::arch::aarch64::{vld1q_f32, vsqrtq_f32, vst1q_f32};
        let mut out = [0.0f32; N];
        for k in (0..N).step_by(4) {
            // SAFETY: NEON is part of AArch64; each access is 4 lanes in bounds.
            unsafe {
                vst1q_f32(
                    out.as_mut_ptr().add(k),
                    vsqrtq_f32(vld1q_f32(x.as_ptr().add(k))),
                )
            };
        }
        out
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        x.map(sqrt_f32)
    }
}

/// Bit `i` is the sign bit of lane `i`: the baseline's 4-lane `movmskps` per quarter on
/// x86-64 (a wider level merges them), the bits one by one elsewhere.
#[inline(always)]
fn sign_bits<const N: usize>(x: &[f32; N]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_mm_loadu_ps, _mm_movemask_ps};
        let mut bits = 0u32;
        for k in (0..N).step_by(4) {
            // SAFETY: SSE is part of x86-64; 4 lanes in bounds.
            bits |= (unsafe { _mm_movemask_ps(_mm_loadu_ps(x.as_ptr().add(k))) } as u32) << k;
        }
        bits
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let mut bits = 0u32;
        for (i, v) in x.iter().enumerate() {
            bits |= (v.to_bits() >> 31) << i;
        }
        bits
    }
}

/// True when some lane's sign bit is set: the quarters or-ed, then one 4-lane `movmskps` on
/// x86-64 (one `vtestps` where the level is AVX), the bits elsewhere.
#[inline(always)]
fn any_sign<const N: usize>(x: &[f32; N]) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_mm_loadu_ps, _mm_movemask_ps, _mm_or_ps};
        // SAFETY: SSE is part of x86-64; every access is 4 lanes in bounds.
        unsafe {
            let mut acc = _mm_loadu_ps(x.as_ptr());
            for k in (4..N).step_by(4) {
                acc = _mm_or_ps(acc, _mm_loadu_ps(x.as_ptr().add(k)));
            }
            _mm_movemask_ps(acc) != 0
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        x.iter().any(|v| v.to_bits() >> 31 != 0)
    }
}
