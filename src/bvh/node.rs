//! Node layouts: how a node keeps its children's boxes and references, and how rays test
//! them. The traversal (`traverse.rs`) is written once over the [`Layout`] trait; a new
//! layout (4-wide, quantized boxes) is a new type implementing it, not a new loop.
//!
//! **Conservative, not exact.** A node test only decides which children a ray may enter: the
//! hits come from the leaf kernels and the collector's tie rule ([`crate::hit`]), so a layout
//! may widen boxes, quantize them outward or test children in any order without changing an
//! answer, as long as it never rejects a child whose box the ray's interval meets. [`Node`]
//! widens every box by the margin of the [module docs](super) and tests them with plain
//! IEEE operations; packets whose directions share their signs test all children at once by
//! interval arithmetic ([`Frustum`]), conservative by monotonic rounding.

use glam::Vec3;
use wide::{f32x4, i32x4};

/// A node's 8 children in lanes: raylane's own [`X8`](crate::lane::X8) on x86-64, which the
/// query's [run-time level](crate::simd) compiles to one AVX register; `wide`'s elsewhere.
#[cfg(target_arch = "x86_64")]
type F8 = crate::lane::X8;
#[cfg(not(target_arch = "x86_64"))]
type F8 = wide::f32x8;

use super::{EMPTY, MAX_DEPTH, STACK, WIDTH};
use crate::lane::{Lane, Mask};
use crate::ray::RayPacket;

/// A node layout (see the [module docs](self)).
pub trait Layout: Copy + core::fmt::Debug {
    /// A node with no children.
    const EMPTY: Self;
    /// The deepest tree of this layout a traversal takes (the root alone is 1).
    const MAX_DEPTH: u32;
    /// The stack a traversal tries first (one that overflows it runs again with [`Full`]).
    ///
    /// [`Full`]: Self::Full
    type Short: Entries;
    /// The stack no tree of at most [`MAX_DEPTH`](Self::MAX_DEPTH) levels overflows.
    type Full: Entries;
    /// Child `k`'s reference: [`EMPTY`], `LEAF | leaf index`, or an inner node's index.
    fn child(&self, k: usize) -> u32;
    /// Child `k`'s box (`min > max` for an empty slot).
    fn bounds(&self, k: usize) -> ([f32; 3], [f32; 3]);
    /// One ray: bit `k` set when its interval `(t_min, t_max)` meets child `k`'s box, and the
    /// entry parameters per child.
    fn test_one(&self, slab: &Slab, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]);
    /// A packet whose directions share their signs: bit `k` set when some lane may enter
    /// child `k` within `(t_lo, t_hi)`, and lower bounds of the lanes' entry parameters.
    fn test_frustum(&self, f: &Frustum, t_lo: f32, t_hi: f32) -> (u32, [f32; WIDTH]);
    /// A packet against child `k`: the lanes of `active` whose interval meets its box, and
    /// their entry parameters.
    fn test_lanes<L: Lane>(
        &self,
        slab: &PacketSlab<L>,
        k: usize,
        t_min: L,
        t_max: L,
        active: L::Mask,
    ) -> (L::Mask, L);
}

/// What a traversal needs of its stack: node references with a 32-bit key each (a ray's
/// entry parameter's bits, or a packet's lanes), last in first out; a push that does not fit
/// is recorded (the traversal then runs again with a larger stack).
pub trait Entries {
    /// An empty stack.
    fn new() -> Self;
    /// The last entry pushed, removed.
    fn pop(&mut self) -> Option<(u32, u32)>;
    /// Pushes an entry (or records the overflow).
    fn push(&mut self, node: u32, key: u32);
    /// True when a push did not fit.
    fn overflowed(&self) -> bool;
}

/// A stack of `N` node references alone (4 bytes each; a popped entry's key is `−inf`'s
/// bits, so a one-ray traversal prunes at the node's own test rather than before it): the
/// small stack of [`Node4`] traversals.
#[derive(Debug)]
pub struct Refs<const N: usize> {
    node: [u32; N],
    len: usize,
    overflow: bool,
}

impl<const N: usize> Entries for Refs<N> {
    #[inline(always)]
    fn new() -> Self {
        Refs {
            node: [0; N],
            len: 0,
            overflow: false,
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, u32)> {
        self.len = self.len.checked_sub(1)?;
        Some((*self.node.get(self.len)?, f32::NEG_INFINITY.to_bits()))
    }

    #[inline(always)]
    fn push(&mut self, node: u32, _: u32) {
        if let Some(a) = self.node.get_mut(self.len) {
            *a = node;
            self.len += 1;
        } else {
            self.overflow = true;
        }
    }

    #[inline(always)]
    fn overflowed(&self) -> bool {
        self.overflow
    }
}

/// A traversal stack of `N` entries, 8 bytes each, on the call stack.
#[derive(Debug)]
pub struct Stack<const N: usize> {
    node: [u32; N],
    key: [u32; N],
    len: usize,
    overflow: bool,
}

impl<const N: usize> Entries for Stack<N> {
    #[inline(always)]
    fn new() -> Self {
        Stack {
            node: [0; N],
            key: [0; N],
            len: 0,
            overflow: false,
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, u32)> {
        self.len = self.len.checked_sub(1)?;
        Some((*self.node.get(self.len)?, *self.key.get(self.len)?))
    }

    #[inline(always)]
    fn push(&mut self, node: u32, key: u32) {
        if let (Some(a), Some(b)) = (self.node.get_mut(self.len), self.key.get_mut(self.len)) {
            *a = node;
            *b = key;
            self.len += 1;
        } else {
            self.overflow = true;
        }
    }

    #[inline(always)]
    fn overflowed(&self) -> bool {
        self.overflow
    }
}

/// One inner node of 8 children, their boxes in structure-of-arrays lanes: one `f32x8` slab
/// test per ray tests them all.
///
/// `bounds[0..3]` are the children's minimum x, y, z, `bounds[3..6]` their maximum x, y, z
/// (`bounds[axis][k]` is child `k`'s). Unused slots have `min = +inf`, `max = −inf` and
/// `child = EMPTY`. 224 bytes, aligned to 32.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Children's boxes: min x, y, z, then max x, y, z; lane `k` is child `k`.
    pub bounds: [[f32; WIDTH]; 6],
    /// Children: [`EMPTY`], `LEAF | leaf index`, or an inner node's index (greater than this
    /// node's).
    pub child: [u32; WIDTH],
}

impl Node {
    /// A node with no children.
    pub const EMPTY: Node = Node {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
    };
}

impl Default for Node {
    fn default() -> Self {
        Node::EMPTY
    }
}

impl Layout for Node {
    const EMPTY: Self = Node::EMPTY;
    const MAX_DEPTH: u32 = MAX_DEPTH;
    type Short = Stack<32>;
    type Full = Stack<STACK>;

    #[inline(always)]
    fn child(&self, k: usize) -> u32 {
        self.child.get(k).copied().unwrap_or(EMPTY)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn bounds(&self, k: usize) -> ([f32; 3], [f32; 3]) {
        let b = &self.bounds;
        let get = |a: usize| b[a].get(k).copied().unwrap_or(f32::NAN);
        ([get(0), get(1), get(2)], [get(3), get(4), get(5)])
    }

    #[inline(always)]
    fn test_one(&self, slab: &Slab, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        slab.test(&self.bounds, &self.child, t_min, t_max)
    }

    #[inline(always)]
    fn test_frustum(&self, f: &Frustum, t_lo: f32, t_hi: f32) -> (u32, [f32; WIDTH]) {
        f.test(&self.bounds, t_lo, t_hi)
    }

    #[inline(always)]
    fn test_lanes<L: Lane>(
        &self,
        slab: &PacketSlab<L>,
        k: usize,
        t_min: L,
        t_max: L,
        active: L::Mask,
    ) -> (L::Mask, L) {
        slab.test(&self.bounds, k, t_min, t_max, active)
    }
}

/// The deepest [`Node4`] tree (the root alone is 1; a binned-SAH tree of a million triangles
/// in 4-wide nodes is about 12 deep): its traversal stack is [`STACK4`] node references, 196
/// bytes.
pub const MAX_DEPTH4: u32 = 16;
/// Entries of a [`Node4`] traversal's stack: at most 3 siblings wait per level, plus one.
pub const STACK4: usize = 3 * MAX_DEPTH4 as usize + 1;

/// A compact node of up to 4 children (56 bytes, 14 per child, against [`Node`]'s 28): the
/// children's boxes quantized to 8 bits inside the node's own box, rounded outward — for
/// trees baked on a host and traced from a microcontroller's flash ([`super::bake`]).
///
/// Child `k`'s box on axis `a` decodes as `origin[a] + q·2^exp[a]` with `q = lo[a][k]` and
/// `hi[a][k]` (`q` converted exactly, the product exact, one rounded addition: the same bits
/// on every target). The baker picks the largest `lo` and the smallest `hi` whose decoded
/// values still enclose the child's box, computing the decoding exactly as the traversal
/// does, so every decoded box contains its child: a traversal over decoded boxes is as
/// conservative as one over the exact boxes, and every answer stays brute force's. An unused
/// slot has `child = EMPTY`, `lo = 255`, `hi = 0` (an empty box).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Node4 {
    /// The node box's minimum x, y, z: the decoding's origin.
    pub origin: [f32; 3],
    /// Per axis, the exponent `e` of the quantum `2^e` (`−126…127`).
    pub exp: [i8; 3],
    /// Zero.
    pub pad: u8,
    /// Children's quantized minimum x, y, z: `lo[axis][k]`.
    pub lo: [[u8; 4]; 3],
    /// Children's quantized maximum x, y, z.
    pub hi: [[u8; 4]; 3],
    /// Children: [`EMPTY`], an inner node's index, or a leaf: `LEAF | first << 2 | (count −
    /// 1)`, triangles `first .. first + count` of the baked mesh (1 to 4 of them).
    pub child: [u32; 4],
}

/// `2^e` for `−126 ≤ e ≤ 127` (other `e` give 0 or +inf).
#[inline(always)]
pub(crate) fn pow2(e: i8) -> f32 {
    let e = i32::from(e);
    if (-126..=127).contains(&e) {
        f32::from_bits(((127 + e) as u32) << 23)
    } else if e > 127 {
        f32::INFINITY
    } else {
        0.0
    }
}

impl Node4 {
    /// A node with no children.
    pub const EMPTY: Node4 = Node4 {
        origin: [0.0; 3],
        exp: [0; 3],
        pad: 0,
        lo: [[255; 4]; 3],
        hi: [[0; 4]; 3],
        child: [EMPTY; 4],
    };

    /// The decoded value of `q` on axis `a` (see the type's docs).
    #[inline(always)]
    #[must_use]
    pub fn decode(&self, a: usize, q: u8) -> f32 {
        let (o, e) = (
            self.origin.get(a).copied().unwrap_or(f32::NAN),
            self.exp.get(a).copied().unwrap_or(0),
        );
        o + f32::from(q) * pow2(e)
    }

    /// The children's decoded boxes as [`Node::bounds`] rows (min x, y, z, max x, y, z;
    /// lanes 4 to 7 and unused slots empty: `+inf`, `−inf`).
    #[inline(always)]
    #[must_use]
    pub fn rows(&self) -> [[f32; WIDTH]; 6] {
        let mut r = Node::EMPTY.bounds;
        for (k, &c) in self.child.iter().enumerate() {
            if c == EMPTY {
                continue;
            }
            for a in 0..3 {
                r[a][k] = self.decode(a, self.lo[a][k]);
                r[3 + a][k] = self.decode(a, self.hi[a][k]);
            }
        }
        r
    }

    /// The children's decoded boxes in four lanes, rows as [`rows`](Self::rows) (unused slots
    /// decode to their canonical `lo = 255`, `hi = 0`: [`Slab::test4`] leaves them out by
    /// `child`). One decoding per row in lanes, each lane's value [`decode`](Self::decode)'s.
    #[inline(always)]
    #[must_use]
    pub fn rows4(&self) -> [f32x4; 6] {
        let row = |a: usize, q: &[u8; 4]| {
            let q = i32x4::new(q.map(i32::from)).round_float();
            f32x4::splat(self.origin[a]) + q * f32x4::splat(pow2(self.exp[a]))
        };
        [
            row(0, &self.lo[0]),
            row(1, &self.lo[1]),
            row(2, &self.lo[2]),
            row(0, &self.hi[0]),
            row(1, &self.hi[1]),
            row(2, &self.hi[2]),
        ]
    }
}

impl Default for Node4 {
    fn default() -> Self {
        Node4::EMPTY
    }
}

impl Layout for Node4 {
    const EMPTY: Self = Node4::EMPTY;
    const MAX_DEPTH: u32 = MAX_DEPTH4;
    type Short = Refs<STACK4>;
    type Full = Refs<STACK4>;

    #[inline(always)]
    fn child(&self, k: usize) -> u32 {
        self.child.get(k).copied().unwrap_or(EMPTY)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn bounds(&self, k: usize) -> ([f32; 3], [f32; 3]) {
        if k >= 4 || self.child[k] == EMPTY {
            return ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        }
        let lo = core::array::from_fn(|a| self.decode(a, self.lo[a][k]));
        let hi = core::array::from_fn(|a| self.decode(a, self.hi[a][k]));
        (lo, hi)
    }

    #[inline(always)]
    fn test_one(&self, slab: &Slab, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        if SIMD {
            slab.test4(&self.rows4(), &self.child, t_min, t_max)
        } else {
            slab.test4_scalar(self, t_min, t_max)
        }
    }

    #[inline(always)]
    fn test_frustum(&self, f: &Frustum, t_lo: f32, t_hi: f32) -> (u32, [f32; WIDTH]) {
        f.test(&self.rows(), t_lo, t_hi)
    }

    #[inline(always)]
    fn test_lanes<L: Lane>(
        &self,
        slab: &PacketSlab<L>,
        k: usize,
        t_min: L,
        t_max: L,
        active: L::Mask,
    ) -> (L::Mask, L) {
        let (lo, hi) = self.bounds(k);
        let mut b = [[f32::INFINITY; WIDTH]; 6];
        for a in 0..3 {
            b[a][0] = lo[a];
            b[3 + a][0] = hi[a];
        }
        slab.test(&b, 0, t_min, t_max, active)
    }
}

/// True where `wide`'s lanes are SIMD registers (x86-64, AArch64); elsewhere (Cortex-M,
/// RISC-V 32) they are arrays in memory, and a loop over scalars is faster.
pub(crate) const SIMD: bool = cfg!(any(target_feature = "sse2", target_feature = "neon"));

/// The box widening relative to `R + |o|∞`: `2^-17` (see the [module docs](super) for why it
/// is conservative).
pub(crate) const MARGIN: f32 = 1.0 / 131072.0;

/// The one-ray slab test in the fused form, `fma(b, 1/d, −(o ± m)/d)`: where `f32x8::mul_add`
/// is one fused instruction (x86-64 with AVX and FMA, AArch64). A node test only prunes (see
/// the [module docs](super)), so a target may take either form; the answers are the same.
const FUSED: bool = cfg!(any(
    all(
        any(target_arch = "x86_64", target_arch = "x86"),
        target_feature = "avx",
        target_feature = "fma"
    ),
    all(target_arch = "aarch64", target_feature = "neon")
));
/// The largest `R + |o|∞` the slab test handles (`2^100`; `2^63` fused); beyond it every child
/// is visited.
const FAR: f32 = crate::lane::pow2(if FUSED { 63 } else { 100 });
/// Inverse direction components are clamped to `±2^100` (`±2^64` fused; a zero component
/// gives the clamp). Fused, `(o ± m)·inv` stays below `2^63·(1 + 2^-17)·2^64`: finite.
const INV_MAX: f32 = crate::lane::pow2(if FUSED { 64 } else { 100 });
/// `|d|∞` must lie in `2^-64…2^64` (`2^-45…2^64` fused: the clamp stays at or above
/// `2^19/|d|∞`) for the slab test; outside, every child is visited.
const D_LO: f32 = crate::lane::pow2(if FUSED { -45 } else { -64 });
const D_HI: f32 = crate::lane::pow2(64);

/// The per-ray constants of the slab test, for one ray: which plane is near on each axis
/// (a row of [`Node::bounds`]), the two widened origins and the clamped inverse direction.
#[derive(Clone, Copy, Debug)]
pub struct Slab {
    near: [usize; 3],
    far: [usize; 3],
    on: [f32; 3],
    of: [f32; 3],
    inv: [f32; 3],
    /// `on·inv`, `of·inv` (rounded once), for the fused form ([`FUSED`]).
    qn: [f32; 3],
    qf: [f32; 3],
    /// Visit every non-empty child (the slab test's range is exceeded).
    all: bool,
}

impl Slab {
    #[inline(always)]
    pub(crate) fn new(o: Vec3, d: Vec3, reach: f32) -> Self {
        let (o, d) = (o.to_array(), d.to_array());
        let omax = o[0].abs().max(o[1].abs()).max(o[2].abs());
        let dmax = d[0].abs().max(d[1].abs()).max(d[2].abs());
        let span = reach + omax;
        let all = !(span <= FAR && (D_LO..=D_HI).contains(&dmax));
        let m = span * MARGIN;
        // The three axes in the lanes of one `f32x4` (lane 3 unused): the same operations
        // as one axis at a time, so the same bits. `+ 0` makes −0 positive, so the plane
        // choice and the inverse's sign agree.
        let zero = f32x4::splat(0.0);
        let da = f32x4::new([d[0], d[1], d[2], 1.0]) + zero;
        let neg = Lane::lt(da, zero);
        let inv =
            (f32x4::splat(1.0) / da).fast_clamp(f32x4::splat(-INV_MAX), f32x4::splat(INV_MAX));
        // `±m` (a sign flip, exact), so `o + ms` and `o − ms` are `o ± m` bit for bit; a
        // select rather than branches (an incoherent ray's signs are unpredictable).
        let ms = Lane::select(neg, f32x4::splat(-m), f32x4::splat(m));
        let o4 = f32x4::new([o[0], o[1], o[2], 0.0]);
        let (on, of) = (o4 + ms, o4 - ms);
        let (qn, qf) = if FUSED {
            (on * inv, of * inv)
        } else {
            (zero, zero)
        };
        // Functions and plain values, not closures: a closure may be left out of line (see
        // crate::simd).
        #[inline(always)]
        fn xyz(v: f32x4) -> [f32; 3] {
            let v = v.to_array();
            [v[0], v[1], v[2]]
        }
        let bits = neg.bits();
        let (kx, ky, kz) = (bits & 1, bits >> 1 & 1, bits >> 2 & 1);
        let (kx, ky, kz) = (kx as usize, ky as usize, kz as usize);
        Slab {
            near: [3 * kx, 1 + 3 * ky, 2 + 3 * kz],
            far: [3 - 3 * kx, 4 - 3 * ky, 5 - 3 * kz],
            on: xyz(on),
            of: xyz(of),
            inv: xyz(inv),
            qn: xyz(qn),
            qf: xyz(qf),
            all,
        }
    }

    /// Bit `k` set when the ray's interval `(t_min, t_max)` meets the widened box of child `k`
    /// (rows `b`: minimum x, y, z, maximum x, y, z; `[row][child]`), and the entry parameters
    /// per child; `child` marks the empty slots ([`EMPTY`]) for rays that visit every child.
    #[inline(always)]
    pub fn test(
        &self,
        b: &[[f32; WIDTH]; 6],
        child: &[u32; WIDTH],
        t_min: f32,
        t_max: f32,
    ) -> (u32, [f32; WIDTH]) {
        if self.all {
            let mut bits = 0;
            for (k, &c) in child.iter().enumerate() {
                if c != EMPTY {
                    bits |= 1 << k;
                }
            }
            return (bits, [t_min; WIDTH]);
        }
        // `(b − o)·inv`, or fused `b·inv − o·inv` with `o·inv` made once per ray: 6 fewer
        // instructions per node.
        // A function, not a closure: called six times, a closure may be left out of line, and
        // then run at the baseline inside a query entered at a wider level (crate::simd).
        #[inline(always)]
        fn plane(b: &[f32; WIDTH], o: f32, q: f32, inv: f32) -> F8 {
            let b = F8::new(*b);
            if FUSED {
                b.mul_add(F8::splat(inv), F8::splat(-q))
            } else {
                (b - F8::splat(o)) * inv
            }
        }
        let (n, f) = (self.near, self.far);
        let (on, of, qn, qf, inv) = (self.on, self.of, self.qn, self.qf, self.inv);
        let tn = F8::splat(t_min)
            .fast_max(plane(&b[n[0]], on[0], qn[0], inv[0]))
            .fast_max(plane(&b[n[1]], on[1], qn[1], inv[1]))
            .fast_max(plane(&b[n[2]], on[2], qn[2], inv[2]));
        let tf = F8::splat(t_max)
            .fast_min(plane(&b[f[0]], of[0], qf[0], inv[0]))
            .fast_min(plane(&b[f[1]], of[1], qf[1], inv[1]))
            .fast_min(plane(&b[f[2]], of[2], qf[2], inv[2]));
        (tn.simd_le(tf).to_bitmask(), tn.to_array())
    }

    /// [`test`](Self::test) for four children (rows of 4 lanes; slots 4 to 7 of the result
    /// empty; the slots whose `child` is [`EMPTY`] never set): half the work and the stack of
    /// 8 lanes where lanes are arrays (Cortex-M).
    #[inline(always)]
    pub fn test4(
        &self,
        b: &[f32x4; 6],
        child: &[u32; 4],
        t_min: f32,
        t_max: f32,
    ) -> (u32, [f32; WIDTH]) {
        let mut out = [f32::INFINITY; WIDTH];
        let mut used = 0;
        for (k, &c) in child.iter().enumerate() {
            used |= u32::from(c != EMPTY) << k;
        }
        if self.all {
            out[..4].copy_from_slice(&[t_min; 4]);
            return (used, out);
        }
        let plane = |p: usize, o: f32, inv: f32| (b[p] - f32x4::splat(o)) * inv;
        let tn = f32x4::splat(t_min)
            .fast_max(plane(self.near[0], self.on[0], self.inv[0]))
            .fast_max(plane(self.near[1], self.on[1], self.inv[1]))
            .fast_max(plane(self.near[2], self.on[2], self.inv[2]));
        let tf = f32x4::splat(t_max)
            .fast_min(plane(self.far[0], self.of[0], self.inv[0]))
            .fast_min(plane(self.far[1], self.of[1], self.inv[1]))
            .fast_min(plane(self.far[2], self.of[2], self.inv[2]));
        out[..4].copy_from_slice(&tn.to_array());
        (tn.simd_le(tf).to_bitmask() & used, out)
    }

    /// [`test4`](Self::test4) one child at a time in scalars, the same bits (where lanes
    /// are arrays: a [`Node4`] on a microcontroller).
    #[inline(always)]
    fn test4_scalar(&self, n: &Node4, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        let mut out = [f32::INFINITY; WIDTH];
        let mut bits = 0;
        let scale = n.exp.map(pow2);
        for (k, &c) in n.child.iter().enumerate() {
            if c == EMPTY {
                continue;
            }
            if self.all {
                bits |= 1 << k;
                out[k] = t_min;
                continue;
            }
            // `fast_max` and `fast_min` of the lanes: `if a < b { b } else { a }`, and so on.
            let (mut tn, mut tf) = (t_min, t_max);
            for (a, &s) in scale.iter().enumerate() {
                let lo = n.origin[a] + f32::from(n.lo[a][k]) * s;
                let hi = n.origin[a] + f32::from(n.hi[a][k]) * s;
                let (near, far) = if self.near[a] == a {
                    (lo, hi)
                } else {
                    (hi, lo)
                };
                let p = (near - self.on[a]) * self.inv[a];
                tn = if tn < p { p } else { tn };
                let p = (far - self.of[a]) * self.inv[a];
                tf = if tf < p { tf } else { p };
            }
            if tn <= tf {
                bits |= 1 << k;
            }
            out[k] = tn;
        }
        (bits, out)
    }
}

/// The per-lane constants of the slab test for a packet (as [`Slab`], lane by lane).
#[derive(Clone, Copy, Debug)]
pub struct PacketSlab<L: Lane> {
    neg: [L::Mask; 3],
    on: [L; 3],
    of: [L; 3],
    inv: [L; 3],
    all: L::Mask,
}

#[inline(always)]
pub(crate) fn lmax<L: Lane>(a: L, b: L) -> L {
    L::select(b.gt(a), b, a)
}

#[inline(always)]
pub(crate) fn lmin<L: Lane>(a: L, b: L) -> L {
    L::select(b.lt(a), b, a)
}

impl<L: Lane> PacketSlab<L> {
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    pub(crate) fn new(rays: &RayPacket<L>, reach: f32) -> Self {
        let (o, d) = (rays.origin, rays.dir);
        let omax = lmax(lmax(o.x.abs(), o.y.abs()), o.z.abs());
        let dmax = lmax(lmax(d.x.abs(), d.y.abs()), d.z.abs());
        let span = L::from_f32(reach) + omax;
        let ok =
            span.le(L::from_f32(FAR)) & dmax.ge(L::from_f32(D_LO)) & dmax.le(L::from_f32(D_HI));
        let m = span * L::from_f32(MARGIN);
        let (ov, dv) = ([o.x, o.y, o.z], [d.x, d.y, d.z]);
        let zero = L::from_f32(0.0);
        // Per axis in a loop, not with `map` or `from_fn`: their closures may be left out of
        // line, and so run without the target features of a level's copy.
        let mut neg = [L::Mask::splat(false); 3];
        let (mut inv, mut on, mut of) = ([zero; 3], [zero; 3], [zero; 3]);
        for a in 0..3 {
            neg[a] = (dv[a] + zero).lt(zero);
            let i = L::from_f32(1.0) / (dv[a] + zero);
            inv[a] = lmax(lmin(i, L::from_f32(INV_MAX)), L::from_f32(-INV_MAX));
            on[a] = L::select(neg[a], ov[a] - m, ov[a] + m);
            of[a] = L::select(neg[a], ov[a] + m, ov[a] - m);
        }
        PacketSlab {
            neg,
            on,
            of,
            inv,
            all: !ok,
        }
    }

    /// Lanes of `active` whose interval meets child `k`'s widened box (rows `b`, as
    /// [`Slab::test`]), and their entry parameters.
    #[inline(always)]
    pub fn test(
        &self,
        b: &[[f32; WIDTH]; 6],
        k: usize,
        t_min: L,
        t_max: L,
        active: L::Mask,
    ) -> (L::Mask, L) {
        let p = |i: usize| L::from_f32(b[i][k]);
        let mut tn = t_min;
        let mut tf = t_max;
        for a in 0..3 {
            let (lo, hi) = (p(a), p(3 + a));
            let near = L::select(self.neg[a], hi, lo);
            let far = L::select(self.neg[a], lo, hi);
            tn = lmax(tn, (near - self.on[a]) * self.inv[a]);
            tf = lmin(tf, (far - self.of[a]) * self.inv[a]);
        }
        ((tn.le(tf) | self.all) & active, tn)
    }
}

/// A packet's slab constants as intervals over its valid lanes, for packets whose directions
/// share their sign on every axis (and whose lanes all pass the slab test's range checks):
/// one `f32x8` interval test per node tests all 8 children for the whole packet.
///
/// Each lane's entry on an axis is `fl(fl(p − o_i)·v_i)`, with the near plane `p` the same
/// for every lane (the signs agree). Rounding is monotonic, so `fl(p − o_i)` lies between
/// `fl(p − max o)` and `fl(p − min o)`, and `fl(x·v_i)` between the rounded products of the
/// interval's corners: with `v > 0` the lowest entry is `min(x_lo·v_min, x_lo·v_max)`, with
/// `v < 0` `min(x_hi·v_min, x_hi·v_max)`, and the exits likewise from above. So a child some
/// lane's own slab test enters passes the interval test (never the converse: a pass only
/// means "look closer"), and every answer stays the per-lane traversal's.
#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    near: [usize; 3],
    far: [usize; 3],
    /// Per axis: the near origin that gives the lowest entries (the highest with positive
    /// directions, the lowest with negative ones), the far origin that gives the highest
    /// exits, and the inverse directions' (min, max).
    on: [f32; 3],
    of: [f32; 3],
    inv: [(f32, f32); 3],
}

impl Frustum {
    /// The intervals of the `valid` lanes of `s`, or `None` when their directions' signs
    /// differ on some axis or a lane visits every child.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    pub(crate) fn new<L: Lane>(s: &PacketSlab<L>, valid: L::Mask) -> Option<Frustum> {
        if (s.all & valid).any() || valid.none() {
            return None;
        }
        // Lanes with a non-finite constant take the per-child test (the bounds skip NaN).
        let mut finite = valid;
        for a in 0..3 {
            finite = finite & s.on[a].is_finite() & s.of[a].is_finite() & s.inv[a].is_finite();
        }
        if valid.and_not(finite).any() {
            return None;
        }
        let hi = |x: L| highest(x, valid);
        let lo = |x: L| -highest(-x, valid);
        let mut f = Frustum {
            near: [0, 1, 2],
            far: [3, 4, 5],
            on: [0.0; 3],
            of: [0.0; 3],
            inv: [(0.0, 0.0); 3],
        };
        for a in 0..3 {
            let neg = s.neg[a] & valid;
            if neg.any() && valid.and_not(neg).any() {
                return None;
            }
            if neg.any() {
                f.near[a] = 3 + a;
                f.far[a] = a;
                (f.on[a], f.of[a]) = (lo(s.on[a]), hi(s.of[a]));
            } else {
                (f.on[a], f.of[a]) = (hi(s.on[a]), lo(s.of[a]));
            }
            f.inv[a] = (lo(s.inv[a]), hi(s.inv[a]));
        }
        Some(f)
    }

    /// Bit `k` set when some lane may enter child `k` of the rows `b` within `(t_lo, t_hi)`
    /// (the lanes' lowest `t_min` and highest `t_max`); lower bounds of the lanes' entry
    /// parameters.
    #[inline(always)]
    pub fn test(&self, b: &[[f32; WIDTH]; 6], t_lo: f32, t_hi: f32) -> (u32, [f32; WIDTH]) {
        let (bits, tn) = self.test_rows(|r| F8::new(b[r]), t_lo, t_hi);
        (bits, tn.to_array())
    }

    /// [`Frustum::test`] on the boxes of a leaf's four primitives (minimum x, y, z, maximum
    /// x, y, z, a primitive per lane): bit `k` set when some lane may enter box `k`.
    #[inline(always)]
    pub(crate) fn test4(&self, b: [f32x4; 6], t_lo: f32, t_hi: f32) -> u32 {
        self.test_rows(|r| b[r], t_lo, t_hi).0
    }

    /// The interval test of [`Frustum::test`], a box per lane of `R` (`b(r)`: row `r`).
    #[inline(always)]
    fn test_rows<R: Row>(&self, b: impl Fn(usize) -> R, t_lo: f32, t_hi: f32) -> (u32, R) {
        let mut tn = R::splat(t_lo);
        let mut tf = R::splat(t_hi);
        for a in 0..3 {
            let (near, far) = (b(self.near[a]), b(self.far[a]));
            let (vl, vh) = (R::splat(self.inv[a].0), R::splat(self.inv[a].1));
            // The near planes' lowest and the far planes' highest offsets.
            let (x, y) = (near - R::splat(self.on[a]), far - R::splat(self.of[a]));
            tn = tn.max((x * vl).min(x * vh));
            tf = tf.min((y * vl).max(y * vh));
        }
        (tn.le_bits(tf), tn)
    }
}

/// The `wide` vectors the frustum test runs on: a node's 8 children, a leaf's 4 primitives.
trait Row: Copy + core::ops::Sub<Output = Self> + core::ops::Mul<Output = Self> {
    fn splat(x: f32) -> Self;
    /// Lane-wise minimum and maximum (either operand where one is NaN).
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    /// Bit `k` set where lane `k` of `self` is at most `o`'s.
    fn le_bits(self, o: Self) -> u32;
}

macro_rules! row {
    ($t:ty) => {
        impl Row for $t {
            #[inline(always)]
            fn splat(x: f32) -> Self {
                <$t>::splat(x)
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                self.fast_min(o)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                self.fast_max(o)
            }
            #[inline(always)]
            fn le_bits(self, o: Self) -> u32 {
                self.simd_le(o).to_bitmask() as u32
            }
        }
    };
}
row!(f32x4);
row!(F8);

/// The highest value of the `valid` lanes (none NaN: valid rays have no NaN constants).
#[inline(always)]
pub(crate) fn highest<L: Lane>(t: L, valid: L::Mask) -> f32 {
    L::select(valid, t, L::from_f32(f32::NEG_INFINITY)).max_lane()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scalar node test (microcontrollers) gives the lanes' bits and entry parameters, on
    /// random nodes (empty slots, tiny and huge quanta) and rays (axis-parallel, zero and
    /// negative components, rays that visit every child).
    #[test]
    fn the_scalar_node_test_is_the_lanes() {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut f = |scale: f32| ((next() >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * scale;
        let mut entered = 0;
        for case in 0..20_000 {
            let mut n = Node4::EMPTY;
            for a in 0..3 {
                n.origin[a] = f(8.0);
                n.exp[a] = [-20i8, -8, -3, 0, 4][case % 5];
            }
            for k in 0..4 {
                if (case >> k) & 3 == 0 {
                    continue;
                }
                n.child[k] = k as u32 + 1;
                for a in 0..3 {
                    let (x, y) = ((f(510.0) + 255.0) as u8, (f(510.0) + 255.0) as u8);
                    n.lo[a][k] = x.min(y);
                    n.hi[a][k] = x.max(y);
                }
            }
            let pick = |x: f32, c: usize| match case / 7 % 4 {
                0 if c == 1 => 0.0,
                1 if c == 2 => -0.0,
                _ => x,
            };
            let o = Vec3::new(f(20.0), f(20.0), f(20.0));
            // Most rays aim at the node's first quanta, where its children are.
            let q = 64.0 * pow2(n.exp[0]);
            let at = Vec3::from_array(n.origin) + Vec3::new(f(q) + q, f(q) + q, f(q) + q);
            let d = if case % 3 == 0 {
                Vec3::new(f(2.0), f(2.0), f(2.0))
            } else {
                at - o
            };
            let d = Vec3::new(pick(d.x, 0), pick(d.y, 1), pick(d.z, 2));
            let reach = if case % 97 == 0 { 1e31 } else { 40.0 };
            let slab = Slab::new(o, d, reach);
            let (t_min, t_max) = (f(1.0), 3.0 + f(4.0));
            let (lanes, tn) = slab.test4(&n.rows4(), &n.child, t_min, t_max);
            let (scalar, ts) = slab.test4_scalar(&n, t_min, t_max);
            assert_eq!(lanes, scalar, "case {case}");
            entered += lanes.count_ones();
            for k in 0..4 {
                if lanes & (1 << k) != 0 {
                    assert_eq!(tn[k].to_bits(), ts[k].to_bits(), "case {case}, child {k}");
                }
            }
        }
        assert!(entered > 5_000, "too few children entered: {entered}");
    }
}
