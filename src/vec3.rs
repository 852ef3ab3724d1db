//! `V3<L>`: a 3-vector with one lane value per axis (structure of arrays).
//!
//! `V3<f32>` is one vector; `V3<f32x8>` is eight vectors, one per lane. The operations fix the
//! order of evaluation (`dot` is `(x·x' + y·y') + z·z'`), which is what makes every width return
//! the scalar path's bits.

use core::ops::{Add, Neg, Sub};

use glam::Vec3;

use crate::lane::{Lane, MAX_LANES};

/// Three lanes, one per axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct V3<L> {
    /// x in every lane.
    pub x: L,
    /// y in every lane.
    pub y: L,
    /// z in every lane.
    pub z: L,
}

impl<L: Lane> V3<L> {
    /// From three lane values.
    #[inline(always)]
    #[must_use]
    pub fn new(x: L, y: L, z: L) -> Self {
        V3 { x, y, z }
    }

    /// The same vector in every lane.
    #[inline(always)]
    #[must_use]
    pub fn splat(v: Vec3) -> Self {
        V3 {
            x: L::from_f32(v.x),
            y: L::from_f32(v.y),
            z: L::from_f32(v.z),
        }
    }

    /// Gathers one vector per lane: lane `i` holds `f(i)`.
    #[inline(always)]
    #[must_use]
    pub fn from_fn(mut f: impl FnMut(usize) -> Vec3) -> Self {
        crate::lane::assert_fits::<L>();
        let mut xs = [0f32; MAX_LANES];
        let mut ys = [0f32; MAX_LANES];
        let mut zs = [0f32; MAX_LANES];
        for i in 0..L::LANES {
            let v = f(i);
            xs[i] = v.x;
            ys[i] = v.y;
            zs[i] = v.z;
        }
        V3 {
            x: L::from_f32_fn(|i| xs[i]),
            y: L::from_f32_fn(|i| ys[i]),
            z: L::from_f32_fn(|i| zs[i]),
        }
    }

    /// Dot product `(x·x' + y·y') + z·z'`: 3 mul, 2 add.
    #[inline(always)]
    #[must_use]
    pub fn dot(self, o: Self) -> L {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Squared length: 3 mul, 2 add.
    #[inline(always)]
    #[must_use]
    pub fn length_squared(self) -> L {
        self.dot(self)
    }

    /// Cross product: 6 mul, 3 add.
    #[inline(always)]
    #[must_use]
    pub fn cross(self, o: Self) -> Self {
        V3 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    /// Each axis times `s`: 3 mul.
    #[inline(always)]
    #[must_use]
    pub fn scale(self, s: L) -> Self {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    /// Each axis divided by `s`: 3 div.
    #[inline(always)]
    #[must_use]
    pub fn div_by(self, s: L) -> Self {
        V3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }

    /// `self + d·t`, the point at `t` along direction `d` from `self`: 3 mul, 3 add, each
    /// rounded (not a fused multiply-add: the same bits on every target).
    #[inline(always)]
    #[must_use]
    pub fn along(self, d: Self, t: L) -> Self {
        V3 {
            x: self.x + d.x * t,
            y: self.y + d.y * t,
            z: self.z + d.z * t,
        }
    }

    /// Per-lane `if mask { a } else { b }`.
    #[inline(always)]
    #[must_use]
    pub fn select(mask: L::Mask, a: Self, b: Self) -> Self {
        V3 {
            x: L::select(mask, a.x, b.x),
            y: L::select(mask, a.y, b.y),
            z: L::select(mask, a.z, b.z),
        }
    }

    /// True where all three axes are finite (bit tests, not counted).
    #[inline(always)]
    #[must_use]
    pub fn is_finite(self) -> L::Mask {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }

    /// Lane `i` as a glam vector (for `f32` elements).
    #[inline(always)]
    #[must_use]
    pub fn lane(self, i: usize) -> Vec3
    where
        L: Lane<Scalar = f32>,
    {
        Vec3::new(self.x.lane(i), self.y.lane(i), self.z.lane(i))
    }

    /// Lane `i` as a single higher-precision lane (exact).
    #[inline(always)]
    #[must_use]
    pub fn precise_lane(self, i: usize) -> V3<L::Precise> {
        V3 {
            x: self.x.precise_lane(i),
            y: self.y.precise_lane(i),
            z: self.z.precise_lane(i),
        }
    }
}

impl<L: Lane> Add for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<L: Lane> Sub for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<L: Lane> Neg for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl From<Vec3> for V3<f32> {
    #[inline(always)]
    fn from(v: Vec3) -> Self {
        V3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

impl From<V3<f32>> for Vec3 {
    #[inline(always)]
    fn from(v: V3<f32>) -> Self {
        Vec3::new(v.x, v.y, v.z)
    }
}

macro_rules! from_array {
    ($t:ty, $n:literal) => {
        impl From<[Vec3; $n]> for V3<$t> {
            #[inline(always)]
            fn from(a: [Vec3; $n]) -> Self {
                V3::from_fn(|i| a[i])
            }
        }
        impl From<V3<$t>> for [Vec3; $n] {
            #[inline(always)]
            fn from(v: V3<$t>) -> Self {
                core::array::from_fn(|i| v.lane(i))
            }
        }
    };
}

from_array!(wide::f32x4, 4);
from_array!(wide::f32x8, 8);
from_array!(wide::f32x16, 16);
