//! The lanes of packets at the x86-64 SIMD levels above the baseline ([`crate::simd`]): [`Y8`]
//! (8 lanes in one AVX register) and [`Y16`] (16 in two), at the AVX2 and the AVX-512 level
//! alike (a type of 16 lanes in one AVX-512 register, its masks in a mask register, was
//! measured and removed: see docs/design.md).
//!
//! **Only where the CPU has them.** Their operations are the level's instructions, so a value
//! of these types may exist only in a program whose CPU has that level: the types are private
//! to the crate, and [`simd::with_lanes`](crate::simd::with_lanes) is the one way code outside
//! it meets them (as a type parameter, after detecting the level). Every operation is the IEEE
//! operation of each lane (no fused multiply-add): the same bits as the scalar path and as
//! `wide`'s vectors.

use core::arch::x86_64::*;
use core::fmt;
use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use super::{Lane, Mask};

/// All ones (a true lane) or all zeros, as an `f32`.
#[inline(always)]
fn ones(b: bool) -> f32 {
    f32::from_bits(if b { u32::MAX } else { 0 })
}

/// Eight `f32` lanes in one AVX register (the AVX2 level's packets of 8).
#[derive(Clone, Copy)]
pub struct Y8(__m256);

/// Sixteen `f32` lanes in two AVX registers (the AVX2 level's packets of 16).
#[derive(Clone, Copy)]
pub struct Y16([__m256; 2]);

// SAFETY (every `unsafe` block below): the AVX, AVX2 and AVX-512 instructions these use exist
// on the CPU, because a value of these types exists only there (see the module docs); loads
// and stores access arrays of exactly the register's size.

// `array` and `from_array` are bit casts, not the `storeu`/`loadu` intrinsics: those are
// `#[inline]` functions the compiler left out of line inside a level's large copies (a call
// per lane read: measured on the render's BVH primary rays at AVX-512).
impl Y8 {
    #[inline(always)]
    fn array(self) -> [f32; 8] {
        // SAFETY: `__m256` and `[f32; 8]` are 32 bytes of plain data, every bit pattern valid.
        unsafe { core::mem::transmute::<__m256, [f32; 8]>(self.0) }
    }
    #[inline(always)]
    fn from_array(a: [f32; 8]) -> Self {
        // SAFETY: as above.
        Y8(unsafe { core::mem::transmute::<[f32; 8], __m256>(a) })
    }
}

impl Y16 {
    #[inline(always)]
    fn array(self) -> [f32; 16] {
        // SAFETY: two `__m256` and `[f32; 16]` are 64 bytes of plain data.
        unsafe { core::mem::transmute::<[__m256; 2], [f32; 16]>(self.0) }
    }
    #[inline(always)]
    fn from_array(a: [f32; 16]) -> Self {
        // SAFETY: as above.
        Y16(unsafe { core::mem::transmute::<[f32; 16], [__m256; 2]>(a) })
    }
}

macro_rules! debug {
    ($t:ty) => {
        impl fmt::Debug for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                self.array().fmt(f)
            }
        }
    };
}
debug!(Y8);
debug!(Y16);

/// The arithmetic operators of a type from one intrinsic per register.
macro_rules! binary {
    ($t:ident, $tr:ident, $f:ident, $y:ident) => {
        impl $tr for $t {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                binary!(@ $t, self, o, $y)
            }
        }
    };
    (@ Y8, $a:ident, $b:ident, $y:ident) => {
        Y8(unsafe { $y($a.0, $b.0) })
    };
    (@ Y16, $a:ident, $b:ident, $y:ident) => {
        Y16(unsafe { [$y($a.0[0], $b.0[0]), $y($a.0[1], $b.0[1])] })
    };
}

macro_rules! arithmetic {
    ($t:ident) => {
        binary!($t, Add, add, _mm256_add_ps);
        binary!($t, Sub, sub, _mm256_sub_ps);
        binary!($t, Mul, mul, _mm256_mul_ps);
        binary!($t, Div, div, _mm256_div_ps);
        impl Neg for $t {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                self ^ -0.0
            }
        }
    };
}
arithmetic!(Y8);
arithmetic!(Y16);

/// Bitwise operations of the vector masks (Y8, Y16: all-ones lanes).
macro_rules! vector_mask {
    ($t:ident) => {
        binary!($t, BitAnd, bitand, _mm256_and_ps);
        binary!($t, BitOr, bitor, _mm256_or_ps);
        impl Not for $t {
            type Output = Self;
            #[inline(always)]
            fn not(self) -> Self {
                self ^ f32::from_bits(u32::MAX)
            }
        }
    };
}
vector_mask!(Y8);
vector_mask!(Y16);

impl core::ops::BitXor<f32> for Y8 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: f32) -> Self {
        Y8(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(o)) })
    }
}

impl core::ops::BitXor<f32> for Y16 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: f32) -> Self {
        let k = unsafe { _mm256_set1_ps(o) };
        Y16(unsafe { [_mm256_xor_ps(self.0[0], k), _mm256_xor_ps(self.0[1], k)] })
    }
}

impl Mask for Y8 {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        Y8(unsafe { _mm256_set1_ps(ones(b)) })
    }
    #[inline(always)]
    fn any(self) -> bool {
        unsafe { _mm256_testz_ps(self.0, self.0) == 0 }
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.bits() == 0xff
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
    #[inline(always)]
    fn with_lane(self, i: usize, b: bool) -> Self {
        let mut a = self.array();
        if let Some(x) = a.get_mut(i) {
            *x = ones(b);
        }
        Y8::from_array(a)
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        let mut a = [0.0f32; 8];
        for (i, x) in a.iter_mut().enumerate() {
            *x = ones(bits >> i & 1 != 0);
        }
        Y8::from_array(a)
    }
}

impl Mask for Y16 {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        let v = unsafe { _mm256_set1_ps(ones(b)) };
        Y16([v, v])
    }
    #[inline(always)]
    fn any(self) -> bool {
        unsafe {
            let o = _mm256_or_ps(self.0[0], self.0[1]);
            _mm256_testz_ps(o, o) == 0
        }
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.bits() == 0xffff
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        unsafe {
            (_mm256_movemask_ps(self.0[0]) as u32) | ((_mm256_movemask_ps(self.0[1]) as u32) << 8)
        }
    }
    #[inline(always)]
    fn with_lane(self, i: usize, b: bool) -> Self {
        let mut a = self.array();
        if let Some(x) = a.get_mut(i) {
            *x = ones(b);
        }
        Y16::from_array(a)
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        let mut a = [0.0f32; 16];
        for (i, x) in a.iter_mut().enumerate() {
            *x = ones(bits >> i & 1 != 0);
        }
        Y16::from_array(a)
    }
}

/// The comparisons, select, and the rest of [`Lane`] for a type, given how it compares.
macro_rules! lane {
    ($t:ident, $n:literal, $mask:ty) => {
        impl Lane for $t {
            type Scalar = f32;
            type Mask = $mask;
            type Precise = f64;
            type Indices = [u32; $n];
            const LANES: usize = $n;
            const PLAIN_F32: bool = true;

            #[inline(always)]
            fn splat(x: f32) -> Self {
                $t::from_array([x; $n])
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                lane!(@sqrt $t, self)
            }
            #[inline(always)]
            fn lt(self, rhs: Self) -> $mask {
                lane!(@cmp $t, self, rhs, _CMP_LT_OQ)
            }
            #[inline(always)]
            fn le(self, rhs: Self) -> $mask {
                lane!(@cmp $t, self, rhs, _CMP_LE_OQ)
            }
            #[inline(always)]
            fn gt(self, rhs: Self) -> $mask {
                lane!(@cmp $t, self, rhs, _CMP_GT_OQ)
            }
            #[inline(always)]
            fn ge(self, rhs: Self) -> $mask {
                lane!(@cmp $t, self, rhs, _CMP_GE_OQ)
            }
            #[inline(always)]
            fn select(mask: $mask, a: Self, b: Self) -> Self {
                lane!(@select $t, mask, a, b)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                lane!(@abs $t, self)
            }
            #[inline(always)]
            #[allow(clippy::eq_op)] // `x − x`: +0 for every finite x, NaN otherwise
            fn is_finite(self) -> $mask {
                let d = self - self;
                lane!(@cmp $t, d, d, _CMP_ORD_Q)
            }
            #[inline(always)]
            fn lane(self, i: usize) -> f32 {
                self.array()[i]
            }
            #[inline(always)]
            fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
                let mut a = [0.0f32; $n];
                for (i, x) in a.iter_mut().enumerate() {
                    *x = f(i);
                }
                $t::from_array(a)
            }
            #[inline(always)]
            fn indices(v: u32) -> [u32; $n] {
                [v; $n]
            }
            #[inline(always)]
            fn select_indices(mask: $mask, a: u32, b: &mut [u32; $n]) {
                // The indices travel as the bits of f32 lanes (loads, stores and blends move
                // bits unchanged).
                let old: [f32; $n] = bytemuck::cast(*b);
                let new = Self::select(mask, <Self as Lane>::splat(f32::from_bits(a)), $t::from_array(old));
                *b = bytemuck::cast(new.array());
            }
            #[inline(always)]
            fn precise_lane(self, i: usize) -> f64 {
                f64::from(self.array()[i])
            }
            #[inline(always)]
            fn with_lane(self, i: usize, v: f32) -> Self {
                let mut a = self.array();
                if let Some(x) = a.get_mut(i) {
                    *x = v;
                }
                $t::from_array(a)
            }
            #[inline(always)]
            fn max_lane(self) -> f32 {
                lane!(@max $t, self)
            }
        }
    };
    (@max Y8, $a:ident) => { max8($a.0) };
    (@max Y16, $a:ident) => { max8(unsafe { _mm256_max_ps($a.0[1], $a.0[0]) }) };
    (@sqrt Y8, $a:ident) => { Y8(unsafe { _mm256_sqrt_ps($a.0) }) };
    (@sqrt Y16, $a:ident) => { Y16(unsafe { [_mm256_sqrt_ps($a.0[0]), _mm256_sqrt_ps($a.0[1])] }) };
    (@cmp Y8, $a:ident, $b:ident, $p:ident) => { Y8(unsafe { _mm256_cmp_ps::<$p>($a.0, $b.0) }) };
    (@cmp Y16, $a:ident, $b:ident, $p:ident) => {
        Y16(unsafe { [_mm256_cmp_ps::<$p>($a.0[0], $b.0[0]), _mm256_cmp_ps::<$p>($a.0[1], $b.0[1])] })
    };
    (@select Y8, $m:ident, $a:ident, $b:ident) => { Y8(unsafe { _mm256_blendv_ps($b.0, $a.0, $m.0) }) };
    (@select Y16, $m:ident, $a:ident, $b:ident) => {
        Y16(unsafe { [_mm256_blendv_ps($b.0[0], $a.0[0], $m.0[0]), _mm256_blendv_ps($b.0[1], $a.0[1], $m.0[1])] })
    };
    (@abs Y8, $a:ident) => { Y8(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), $a.0) }) };
    (@abs Y16, $a:ident) => {
        Y16(unsafe {
            let s = _mm256_set1_ps(-0.0);
            [_mm256_andnot_ps(s, $a.0[0]), _mm256_andnot_ps(s, $a.0[1])]
        })
    };
}
lane!(Y8, 8, Y8);
lane!(Y16, 16, Y16);

/// The largest of 8 lanes, as the halving tree `v[i] = v[i + n] > v[i] ? v[i + n] : v[i]` for
/// `n` = 4, 2, 1 (the portable lanes' order, bit for bit: `max_ps(a, b)` is `a > b ? a : b`),
/// in vector halves rather than lane by lane (callgrind, x86-64-v3, the vendored bunny's
/// primary packets of 16: the scalar tree cost about 50 instructions per ray).
#[inline(always)]
fn max8(v: __m256) -> f32 {
    unsafe {
        let h = _mm_max_ps(_mm256_extractf128_ps::<1>(v), _mm256_castps256_ps128(v));
        let h = _mm_max_ps(_mm_movehl_ps(h, h), h);
        _mm_cvtss_f32(_mm_max_ss(_mm_shuffle_ps::<1>(h, h), h))
    }
}
