//! Traversal: one ray (children in `f32x8` lanes, leaves in `f32x4` lanes) and packets of any
//! width (a node's 8 children in one interval test when the directions share their signs,
//! otherwise one child box per lane operation), over the tree's boxes or a per-eye cache
//! ([`View`]).

use glam::Vec3;
use wide::{f32x4, f32x8};

use super::{Bvh, EMPTY, LEAF, Leaf, Node, STACK, WIDTH};
use crate::hit::{Best, LaneHit, relax};
use crate::lane::MAX_LANES;
use crate::lane::{Lane, Mask};
use crate::query::Hits;
use crate::ray::{Ray, RayPacket};
use crate::triangle::Cull;
use crate::vec3::V3;

/// Where a traversal reads the children's boxes and the leaves' geometry: the tree itself
/// ([`World`]) or a per-eye cache ([`FocalBvh`](super::FocalBvh)).
pub(crate) trait View<P: Leaf> {
    /// Per-ray constants of the node test beyond the slab's, for one ray.
    type One: Copy;
    /// The same for a packet.
    type Many<L: Lane>: Copy;
    /// The node test's constants for `ray`.
    fn one(&self, ray: &Ray) -> Self::One;
    /// The node test's constants for `rays`.
    fn many<L: Lane>(&self, rays: &RayPacket<L>) -> Self::Many<L>;
    /// One ray against the children of node `c` (`n`): the bits of the children its interval
    /// meets and their entry parameters.
    fn node_one(
        &self,
        x: &Self::One,
        slab: &Slab,
        c: u32,
        n: &Node,
        t_min: f32,
        t_max: f32,
    ) -> (u32, f32x8);
    /// The lanes of `active` whose interval meets child `k` of node `c` (`n`), and their
    /// entry parameters.
    #[allow(clippy::too_many_arguments)]
    fn node_many<L: Lane>(
        &self,
        x: &Self::Many<L>,
        slab: &PacketSlab<L>,
        c: u32,
        n: &Node,
        k: usize,
        t_min: L,
        t_max: L,
        active: L::Mask,
    ) -> (L::Mask, L);
    /// A packet's [`Frustum`] against the children of node `c` (`n`): a superset of the
    /// children some lane enters, and lower bounds of the lanes' entry parameters (`None`:
    /// test child by child).
    fn node_frustum(
        &self,
        f: &Frustum,
        c: u32,
        n: &Node,
        t_lo: f32,
        t_hi: f32,
    ) -> Option<(u32, f32x8)>;
    /// What the kernels test for a leaf.
    type Test<'a>: LeafTest<P>
    where
        Self: 'a,
        P: 'a;
    /// What the kernels test for leaf `li` (`leaf`).
    fn leaf<'a>(&'a self, li: u32, leaf: &'a P) -> Self::Test<'a>;
}

/// A leaf's kernel calls: 1 ray × 4 primitives and N rays × primitive `k`.
pub(crate) trait LeafTest<P: Leaf> {
    fn four(&self, ray: &RayPacket<f32x4>, pre: &P::Rays<f32x4>, cull: Cull) -> LaneHit<f32x4>;
    fn one<L: Lane>(
        &self,
        k: usize,
        rays: &RayPacket<L>,
        pre: &P::Rays<L>,
        cull: Cull,
    ) -> LaneHit<L>;
}

impl<P: Leaf> LeafTest<P> for &P {
    #[inline(always)]
    fn four(&self, ray: &RayPacket<f32x4>, pre: &P::Rays<f32x4>, cull: Cull) -> LaneHit<f32x4> {
        self.test_four(ray, pre, cull)
    }
    #[inline(always)]
    fn one<L: Lane>(
        &self,
        k: usize,
        rays: &RayPacket<L>,
        pre: &P::Rays<L>,
        cull: Cull,
    ) -> LaneHit<L> {
        self.test_one(k, rays, pre, cull)
    }
}

/// The tree's own boxes and leaves.
pub(crate) struct World;

impl<P: Leaf> View<P> for World {
    type One = ();
    type Many<L: Lane> = ();
    #[inline(always)]
    fn one(&self, _: &Ray) {}
    #[inline(always)]
    fn many<L: Lane>(&self, _: &RayPacket<L>) {}
    #[inline(always)]
    fn node_one(
        &self,
        _: &(),
        slab: &Slab,
        _: u32,
        n: &Node,
        t_min: f32,
        t_max: f32,
    ) -> (u32, f32x8) {
        slab.test(n, t_min, t_max)
    }
    #[inline(always)]
    fn node_many<L: Lane>(
        &self,
        _: &(),
        slab: &PacketSlab<L>,
        _: u32,
        n: &Node,
        k: usize,
        t_min: L,
        t_max: L,
        active: L::Mask,
    ) -> (L::Mask, L) {
        slab.test::<false>(&n.bounds, k, t_min, t_max, active)
    }
    #[inline(always)]
    fn node_frustum(
        &self,
        f: &Frustum,
        _: u32,
        n: &Node,
        t_lo: f32,
        t_hi: f32,
    ) -> Option<(u32, f32x8)> {
        Some(f.test::<false>(&n.bounds, t_lo, t_hi))
    }
    type Test<'a>
        = &'a P
    where
        P: 'a;
    #[inline(always)]
    fn leaf<'a>(&'a self, _: u32, leaf: &'a P) -> &'a P {
        leaf
    }
}

/// The box widening relative to `R + |o|∞`: `2^-17` (see the [module docs](super) for why it
/// is conservative).
pub(crate) const MARGIN: f32 = 1.0 / 131072.0;
/// The largest `R + |o|∞` the slab test handles (`2^100`); beyond it every child is visited.
const FAR: f32 = 1.2676506e30;
/// Inverse direction components are clamped to `±2^100` (a zero component gives `±2^100`).
const INV_MAX: f32 = 1.2676506e30;
/// `|d|∞` must lie in `2^-64…2^64` for the slab test; outside, every child is visited.
const D_LO: f32 = 5.421011e-20;
const D_HI: f32 = 1.8446744e19;

/// The per-ray constants of the slab test, for one ray: which plane is near on each axis
/// (index into [`Node::bounds`]), the two widened origins and the clamped inverse direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slab {
    near: [usize; 3],
    far: [usize; 3],
    on: [f32; 3],
    of: [f32; 3],
    inv: [f32; 3],
    dir: [f32; 3],
    /// Visit every non-empty child (the slab test's range is exceeded).
    pub(crate) all: bool,
}

impl Slab {
    /// The ray's direction.
    #[inline(always)]
    pub(crate) fn dir(&self) -> [f32; 3] {
        self.dir
    }

    #[inline(always)]
    pub(crate) fn new(o: Vec3, d: Vec3, reach: f32) -> Self {
        let (o, d) = (o.to_array(), d.to_array());
        let omax = o[0].abs().max(o[1].abs()).max(o[2].abs());
        let dmax = d[0].abs().max(d[1].abs()).max(d[2].abs());
        let span = reach + omax;
        let all = !(span <= FAR && (D_LO..=D_HI).contains(&dmax));
        let m = span * MARGIN;
        let mut s = Slab {
            near: [0, 1, 2],
            far: [3, 4, 5],
            on: [0.0; 3],
            of: [0.0; 3],
            inv: [0.0; 3],
            dir: d,
            all,
        };
        for a in 0..3 {
            // `+ 0` makes −0 positive, so the plane choice and the inverse's sign agree.
            let da = d[a] + 0.0;
            let neg = da < 0.0;
            s.inv[a] = (1.0 / da).clamp(-INV_MAX, INV_MAX);
            // Arithmetic rather than branches or selects (which the compiler may turn into
            // branches): the sign of an incoherent ray's direction is unpredictable. `ms` is
            // `±m` (a sign flip, exact), so `o + ms` and `o − ms` are `o ± m` bit for bit.
            let k = neg as usize;
            let ms = f32::from_bits(m.to_bits() ^ ((neg as u32) << 31));
            s.near[a] = a + 3 * k;
            s.far[a] = 3 + a - 3 * k;
            s.on[a] = o[a] + ms;
            s.of[a] = o[a] - ms;
        }
        s
    }

    /// Bit `k` set when the ray's interval `(t_min, t_max)` meets child `k`'s widened box; the
    /// entry parameters per child.
    #[inline(always)]
    pub(crate) fn test(&self, n: &Node, t_min: f32, t_max: f32) -> (u32, f32x8) {
        self.test_rows::<false>(n, &n.bounds, t_min, t_max)
    }

    /// [`test`](Self::test) on the boxes `b` of `n`'s children: the node's own (`REL` false),
    /// or the per-eye rows `bounds − eye` widened by the margin (`REL` true: no subtraction,
    /// the origins are not used).
    #[inline(always)]
    pub(crate) fn test_rows<const REL: bool>(
        &self,
        n: &Node,
        b: &[[f32; WIDTH]; 6],
        t_min: f32,
        t_max: f32,
    ) -> (u32, f32x8) {
        if self.all {
            let mut bits = 0;
            for (k, &c) in n.child.iter().enumerate() {
                if c != EMPTY {
                    bits |= 1 << k;
                }
            }
            return (bits, f32x8::splat(t_min));
        }
        let plane = |p: usize, o: f32, inv: f32| {
            if REL {
                f32x8::new(b[p]) * inv
            } else {
                (f32x8::new(b[p]) - f32x8::splat(o)) * inv
            }
        };
        let tn = f32x8::splat(t_min)
            .fast_max(plane(self.near[0], self.on[0], self.inv[0]))
            .fast_max(plane(self.near[1], self.on[1], self.inv[1]))
            .fast_max(plane(self.near[2], self.on[2], self.inv[2]));
        let tf = f32x8::splat(t_max)
            .fast_min(plane(self.far[0], self.of[0], self.inv[0]))
            .fast_min(plane(self.far[1], self.of[1], self.inv[1]))
            .fast_min(plane(self.far[2], self.of[2], self.inv[2]));
        (tn.simd_le(tf).to_bitmask(), tn)
    }
}

/// Entries of the short stack the one-ray queries try first (a query that would overflow it
/// runs again with the full [`STACK`]: initialising 2 KB per ray cost about a fifth of a
/// primary ray's time).
const SHORT: usize = 32;

/// The traversal stack: node references with the entry parameter of their box (the root
/// first, with `−inf`). With `N < STACK` a push may not fit: the stack then records the
/// overflow and the query is run again with a full stack.
pub(crate) struct Stack<const N: usize = STACK> {
    node: [u32; N],
    tn: [f32; N],
    len: usize,
    /// An entry was dropped: the answer is incomplete.
    pub(crate) overflow: bool,
}

impl<const N: usize> Stack<N> {
    #[inline(always)]
    pub(crate) fn new() -> Self {
        let mut s = Self::empty();
        s.len = 1;
        if let Some(t) = s.tn.first_mut() {
            *t = f32::NEG_INFINITY;
        }
        s
    }

    /// A stack without the root (the one-ray queries test the root first).
    #[inline(always)]
    pub(crate) fn empty() -> Self {
        Stack {
            node: [0; N],
            tn: [0.0; N],
            len: 0,
            overflow: false,
        }
    }

    #[inline(always)]
    pub(crate) fn pop(&mut self) -> Option<(u32, f32)> {
        self.len = self.len.checked_sub(1)?;
        Some((*self.node.get(self.len)?, *self.tn.get(self.len)?))
    }

    /// Pushes the children in `bits` farthest first (so the nearest is popped first).
    #[inline(always)]
    pub(crate) fn push_sorted(&mut self, n: &Node, mut bits: u32, tn: &[f32; WIDTH]) {
        let mut list = [(0u32, 0.0f32); WIDTH];
        let mut m = 0;
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let item = (n.child[k], tn[k]);
            // Insertion sort, descending entry parameter.
            let mut j = m;
            while j > 0 && list[j - 1].1 < item.1 {
                list[j] = list[j - 1];
                j -= 1;
            }
            list[j] = item;
            m += 1;
        }
        for &(c, t) in &list[..m] {
            if let (Some(a), Some(b)) = (self.node.get_mut(self.len), self.tn.get_mut(self.len)) {
                *a = c;
                *b = t;
                self.len += 1;
            } else {
                self.overflow = true;
            }
        }
    }
}

/// One ray's finished closest hit and its primitive.
pub(crate) type Winner<P> = (Best<f32>, <P as Leaf>::Prim);

/// The best hit of one ray so far, and where its primitive sits (leaf, lane).
#[derive(Clone, Copy, Debug)]
struct One {
    t: f32,
    u: f32,
    v: f32,
    w: f32,
    index: u32,
    leaf: u32,
    lane: usize,
}

impl<P: Leaf> Bvh<'_, P> {
    /// The closest hit of one ray (finished, as a one-lane [`Best`]) and its primitive: the
    /// brute-force answer with the same kernel, bit for bit (see the [module docs](super)).
    pub(crate) fn closest_one<V: View<P>>(&self, view: &V, ray: &Ray) -> Option<Winner<P>> {
        match self.closest_with::<SHORT, V>(view, ray) {
            Ok(h) => h,
            Err(()) => self.closest_with::<STACK, V>(view, ray).ok().flatten(),
        }
    }

    /// [`closest_one`](Self::closest_one) with a stack of `N` entries: `Err` when it
    /// overflowed (never with `N = STACK`, by the depth bound).
    #[inline(always)]
    fn closest_with<const N: usize, V: View<P>>(
        &self,
        view: &V,
        ray: &Ray,
    ) -> Result<Option<Winner<P>>, ()> {
        if !ray.is_valid() {
            return Ok(None);
        }
        let slab = Slab::new(ray.origin(), ray.dir(), self.reach);
        let x = view.one(ray);
        let r4 = RayPacket::<f32x4>::splat(ray);
        // The leaf kernel's per-ray set-up (Watertight: the shear, 3 divisions), made at the
        // first leaf: most rays that leave a surface reach none.
        let mut pre = None;
        let t_end = ray.t_max();
        let mut t_max = relax(t_end);
        let mut best = One {
            t: f32::INFINITY,
            u: 0.0,
            v: 0.0,
            w: 1.0,
            index: EMPTY,
            leaf: 0,
            lane: 0,
        };
        // The root is tested before the stack is set up: a ray that meets none of its
        // children (most rays leaving a convex part) costs one slab test.
        let Some(root) = self.nodes.first() else {
            return Ok(None);
        };
        let (bits, tn) = view.node_one(&x, &slab, 0, root, ray.t_min(), t_max);
        if bits == 0 {
            return Ok(None);
        }
        let mut stack = Stack::<N>::empty();
        stack.push_sorted(root, bits, &tn.to_array());
        while let Some((c, tn)) = stack.pop() {
            if tn > t_max {
                continue;
            }
            if c & LEAF == 0 {
                let Some(n) = self.nodes.get(c as usize) else {
                    continue;
                };
                let (bits, tn) = view.node_one(&x, &slab, c, n, ray.t_min(), t_max);
                stack.push_sorted(n, bits, &tn.to_array());
                continue;
            }
            let li = c & !LEAF;
            let Some(leaf) = self.leaves.get(li as usize) else {
                continue;
            };
            let r = RayPacket {
                t_max: f32x4::splat(t_max),
                ..r4
            };
            let pre = pre.get_or_insert_with(|| P::prepare(&r4));
            let h = view.leaf(li, leaf).four(&r, pre, self.cull);
            let mut bits = h.mask.bits();
            while bits != 0 {
                let j = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let (t, index) = (h.t.lane(j), leaf.indices()[j]);
                if t < t_end && (t < best.t || (t == best.t && index < best.index)) {
                    best = One {
                        t,
                        u: h.u.lane(j),
                        v: h.v.lane(j),
                        w: h.w.lane(j),
                        index,
                        leaf: li,
                        lane: j,
                    };
                    t_max = relax(t);
                }
            }
        }
        if stack.overflow {
            return Err(());
        }
        if best.index == EMPTY {
            return Ok(None);
        }
        let Some(leaf) = self.leaves.get(best.leaf as usize) else {
            return Ok(None);
        };
        let h = LaneHit::deferred(best.t, best.u, best.v, best.w, true);
        Ok(Some((Best::single(&h, best.index), leaf.prim(best.lane))))
    }

    /// True when one ray hits some primitive (stops at the first hit).
    pub(crate) fn any_one<V: View<P>>(&self, view: &V, ray: &Ray) -> bool {
        match self.any_with::<SHORT, V>(view, ray) {
            Some(hit) => hit,
            None => self.any_with::<STACK, V>(view, ray).unwrap_or(false),
        }
    }

    /// [`any_one`](Self::any_one) with a stack of `N` entries: `None` when it overflowed
    /// before finding a hit.
    #[inline(always)]
    fn any_with<const N: usize, V: View<P>>(&self, view: &V, ray: &Ray) -> Option<bool> {
        if !ray.is_valid() {
            return Some(false);
        }
        let slab = Slab::new(ray.origin(), ray.dir(), self.reach);
        let x = view.one(ray);
        let r4 = RayPacket::<f32x4>::splat(ray);
        // Made at the first leaf, as in `closest_with`.
        let mut pre = None;
        let Some(root) = self.nodes.first() else {
            return Some(false);
        };
        let (bits, tn) = view.node_one(&x, &slab, 0, root, ray.t_min(), ray.t_max());
        if bits == 0 {
            return Some(false);
        }
        let mut stack = Stack::<N>::empty();
        stack.push_sorted(root, bits, &tn.to_array());
        while let Some((c, _)) = stack.pop() {
            if c & LEAF == 0 {
                let Some(n) = self.nodes.get(c as usize) else {
                    continue;
                };
                let (bits, tn) = view.node_one(&x, &slab, c, n, ray.t_min(), ray.t_max());
                stack.push_sorted(n, bits, &tn.to_array());
            } else if let Some(leaf) = self.leaves.get((c & !LEAF) as usize)
                && view
                    .leaf(c & !LEAF, leaf)
                    .four(&r4, pre.get_or_insert_with(|| P::prepare(&r4)), self.cull)
                    .mask
                    .any()
            {
                return Some(true);
            }
        }
        (!stack.overflow).then_some(false)
    }
}

/// The per-lane constants of the slab test for a packet (as [`Slab`], lane by lane).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PacketSlab<L: Lane> {
    neg: [L::Mask; 3],
    on: [L; 3],
    of: [L; 3],
    inv: [L; 3],
    dir: V3<L>,
    pub(crate) all: L::Mask,
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
    /// The rays' directions.
    #[inline(always)]
    pub(crate) fn dir(&self) -> V3<L> {
        self.dir
    }

    fn new(rays: &RayPacket<L>, reach: f32) -> Self {
        let (o, d) = (rays.origin, rays.dir);
        let omax = lmax(lmax(o.x.abs(), o.y.abs()), o.z.abs());
        let dmax = lmax(lmax(d.x.abs(), d.y.abs()), d.z.abs());
        let span = L::from_f32(reach) + omax;
        let ok =
            span.le(L::from_f32(FAR)) & dmax.ge(L::from_f32(D_LO)) & dmax.le(L::from_f32(D_HI));
        let m = span * L::from_f32(MARGIN);
        let (ov, dv) = ([o.x, o.y, o.z], [d.x, d.y, d.z]);
        let zero = L::from_f32(0.0);
        let neg = dv.map(|x| (x + zero).lt(zero));
        let inv = dv.map(|x| {
            let i = L::from_f32(1.0) / (x + zero);
            lmax(lmin(i, L::from_f32(INV_MAX)), L::from_f32(-INV_MAX))
        });
        let on = core::array::from_fn(|a| L::select(neg[a], ov[a] - m, ov[a] + m));
        let of = core::array::from_fn(|a| L::select(neg[a], ov[a] + m, ov[a] - m));
        PacketSlab {
            neg,
            on,
            of,
            inv,
            dir: d,
            all: !ok,
        }
    }

    /// Lanes of `active` whose interval meets child `k`'s widened box, and their entry
    /// parameters (`b`: the node's boxes, or with `REL` the per-eye rows, as
    /// [`Slab::test_rows`]).
    #[inline(always)]
    pub(crate) fn test<const REL: bool>(
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
            if REL {
                tn = lmax(tn, near * self.inv[a]);
                tf = lmin(tf, far * self.inv[a]);
            } else {
                tn = lmax(tn, (near - self.on[a]) * self.inv[a]);
                tf = lmin(tf, (far - self.of[a]) * self.inv[a]);
            }
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
pub(crate) struct Frustum {
    near: [usize; 3],
    far: [usize; 3],
    /// Per axis: the near origins' (min, max), the far origins' (min, max), the inverse
    /// directions' (min, max), and whether they are negative.
    on: [(f32, f32); 3],
    of: [(f32, f32); 3],
    inv: [(f32, f32); 3],
    neg: [bool; 3],
}

impl Frustum {
    /// The intervals of the `valid` lanes of `s`, or `None` when their directions' signs
    /// differ on some axis or a lane visits every child.
    pub(crate) fn new<L: Lane>(s: &PacketSlab<L>, valid: L::Mask) -> Option<Frustum> {
        if (s.all & valid).any() || valid.none() {
            return None;
        }
        let mut f = Frustum {
            near: [0, 1, 2],
            far: [3, 4, 5],
            on: [(0.0, 0.0); 3],
            of: [(0.0, 0.0); 3],
            inv: [(0.0, 0.0); 3],
            neg: [false; 3],
        };
        // Lanes with a non-finite constant take the per-child test (the ranges skip NaN).
        let finite = |x: L| valid.and_not(x.is_finite()).none();
        if !(0..3).all(|a| finite(s.on[a]) && finite(s.of[a]) && finite(s.inv[a])) {
            return None;
        }
        let range = |x: L| (-highest(-x, valid), highest(x, valid));
        for a in 0..3 {
            let neg = s.neg[a] & valid;
            if neg.any() && valid.and_not(neg).any() {
                return None;
            }
            f.neg[a] = neg.any();
            if f.neg[a] {
                f.near[a] = 3 + a;
                f.far[a] = a;
            }
            f.on[a] = range(s.on[a]);
            f.of[a] = range(s.of[a]);
            f.inv[a] = range(s.inv[a]);
        }
        Some(f)
    }

    /// Bit `k` set when some lane may enter child `k` of the rows `b` (the node's boxes, or
    /// with `REL` the per-eye rows: no subtraction) within `(t_lo, t_hi)` (the lanes' lowest
    /// `t_min` and highest `t_max`); lower bounds of the lanes' entry parameters.
    #[inline(always)]
    pub(crate) fn test<const REL: bool>(
        &self,
        b: &[[f32; WIDTH]; 6],
        t_lo: f32,
        t_hi: f32,
    ) -> (u32, f32x8) {
        let mut tn = f32x8::splat(t_lo);
        let mut tf = f32x8::splat(t_hi);
        for a in 0..3 {
            let (near, far) = (f32x8::new(b[self.near[a]]), f32x8::new(b[self.far[a]]));
            let (vl, vh) = self.inv[a];
            // The near planes' lowest and the far planes' highest offsets that matter.
            let (x, y) = if REL {
                (near, far)
            } else if self.neg[a] {
                (near - self.on[a].0, far - self.of[a].1)
            } else {
                (near - self.on[a].1, far - self.of[a].0)
            };
            tn = tn.fast_max((x * vl).fast_min(x * vh));
            tf = tf.fast_min((y * vl).fast_max(y * vh));
        }
        (tn.simd_le(tf).to_bitmask(), tn)
    }
}

/// The highest value of the `valid` lanes (none NaN: valid rays have no NaN constants).
#[inline(always)]
fn highest<L: Lane>(t: L, valid: L::Mask) -> f32 {
    let t = L::select(valid, t, L::from_f32(f32::NEG_INFINITY));
    let mut r = f32::NEG_INFINITY;
    for i in 0..L::LANES {
        let v = lane_f32(t, i);
        if v > r {
            r = v;
        }
    }
    r
}

/// A packet's [`Frustum`] with its lanes' lowest `t_min` and highest `t_max`.
#[inline(always)]
fn frustum<L: Lane>(
    slab: &PacketSlab<L>,
    rays: &RayPacket<L>,
    valid: L::Mask,
) -> Option<(Frustum, f32, f32)> {
    // One lane: its own per-child test is as tight and, where `f32x8` is emulated (Cortex-M),
    // cheaper (4,941 against 9,447 instructions per primary ray on the M4F).
    if L::LANES == 1 {
        return None;
    }
    let f = Frustum::new(slab, valid)?;
    let lo = -highest(-rays.t_min, valid);
    Some((f, lo, highest(rays.t_max, valid)))
}

/// Pushes the children of node `c` (`n`) some lane of `active` enters, nearest (by the first
/// such lane's entry) on top. With a [`Frustum`], the children are tested for the whole
/// packet at once (`t_lo`, `t_hi`: the lanes' lowest `t_min` and highest `t_max`), and a leaf
/// child only if some lane's own slab test enters it.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn visit<P: Leaf, V: View<P>, L: Lane, const N: usize>(
    view: &V,
    x: &V::Many<L>,
    stack: &mut Stack<N>,
    c: u32,
    n: &Node,
    slab: &PacketSlab<L>,
    r: &RayPacket<L>,
    active: L::Mask,
    fr: Option<&(Frustum, f32, f32)>,
) {
    if let Some((f, t_lo, t_hi)) = fr
        && let Some((mut bits, tn)) = view.node_frustum(f, c, n, *t_lo, *t_hi)
    {
        let mut leaves = bits;
        while leaves != 0 {
            let k = leaves.trailing_zeros() as usize;
            leaves &= leaves - 1;
            if n.child[k] & LEAF != 0 {
                let (m, _) = view.node_many(x, slab, c, n, k, r.t_min, r.t_max, active);
                if m.none() {
                    bits &= !(1 << k);
                }
            }
        }
        stack.push_sorted(n, bits, &tn.to_array());
        return;
    }
    let mut bits = 0u32;
    let mut key = [0.0f32; WIDTH];
    for (k, key) in key.iter_mut().enumerate() {
        if n.child[k] == EMPTY {
            continue;
        }
        let (m, tn) = view.node_many(x, slab, c, n, k, r.t_min, r.t_max, active);
        let mb = m.bits();
        if mb != 0 {
            bits |= 1 << k;
            *key = lane_f32(tn, mb.trailing_zeros() as usize);
        }
    }
    stack.push_sorted(n, bits, &key);
}

/// Lane `i` as an `f32` (only ordering uses it).
#[inline(always)]
fn lane_f32<L: Lane>(x: L, i: usize) -> f32 {
    use crate::lane::Scalar;
    x.lane(i).to_f64() as f32
}

impl<P: Leaf> Bvh<'_, P> {
    /// The closest hit of each ray lane (finished) and where each lane's winner sits
    /// (`4·leaf + lane`): the brute-force answer with the same kernel, bit for bit, at every
    /// width (see the [module docs](super)).
    pub(crate) fn closest_lanes<V: View<P>, L: Lane>(
        &self,
        view: &V,
        rays: &RayPacket<L>,
    ) -> (Best<L>, [u32; MAX_LANES]) {
        // A short stack first (initialising 2 KB per packet is a tenth of a shadow packet's
        // work); a packet that would overflow it runs again with the full one.
        match self.closest_lanes_with::<SHORT, V, L>(view, rays) {
            Some(r) => r,
            None => self
                .closest_lanes_with::<STACK, V, L>(view, rays)
                .unwrap_or((Best::<L>::miss(), [0; MAX_LANES])),
        }
    }

    /// [`closest_lanes`](Self::closest_lanes) with a stack of `N` entries: `None` when it
    /// overflowed (never with `N = STACK`).
    #[inline(always)]
    fn closest_lanes_with<const N: usize, V: View<P>, L: Lane>(
        &self,
        view: &V,
        rays: &RayPacket<L>,
    ) -> Option<(Best<L>, [u32; MAX_LANES])> {
        crate::lane::assert_fits::<L>();
        let valid = rays.valid();
        let mut best = Best::<L>::miss();
        let mut win = [0u32; MAX_LANES];
        if valid.none() {
            return Some((best, win));
        }
        let slab = PacketSlab::new(rays, self.reach);
        let x = view.many(rays);
        let pre = P::prepare(rays);
        let t_end = rays.t_max;
        let mut r = RayPacket {
            t_max: L::select(valid, relax(rays.t_max), rays.t_max),
            ..*rays
        };
        let mut fr = frustum(&slab, &r, valid);
        let mut stack = Stack::<N>::new();
        while let Some((c, _)) = stack.pop() {
            if c & LEAF == 0 {
                if let Some(n) = self.nodes.get(c as usize) {
                    visit(view, &x, &mut stack, c, n, &slab, &r, valid, fr.as_ref());
                }
                continue;
            }
            let li = c & !LEAF;
            let Some(leaf) = self.leaves.get(li as usize) else {
                continue;
            };
            let test = view.leaf(li, leaf);
            for (k, &index) in leaf.indices().iter().enumerate() {
                if index == EMPTY {
                    continue;
                }
                let h = test.one(k, &r, &pre, self.cull);
                if h.mask.none() {
                    continue;
                }
                let mut take = h.mask & h.t.lt(t_end) & h.t.lt(best.t);
                let tie = h.mask & h.t.le(best.t) & h.t.ge(best.t);
                if tie.any() {
                    let mut bits = tie.bits();
                    while bits != 0 {
                        let j = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        if index < best.index.as_ref()[j] {
                            take = take.with_lane(j, true);
                        }
                    }
                }
                if take.any() {
                    best.take(&h, take, index);
                    r = r.shrink(take, relax(h.t));
                    if let Some(f) = fr.as_mut() {
                        f.2 = highest(r.t_max, valid);
                    }
                    let mut bits = take.bits();
                    while bits != 0 {
                        let j = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        if let Some(w) = win.get_mut(j) {
                            *w = li * 4 + k as u32;
                        }
                    }
                }
            }
        }
        (!stack.overflow).then(|| (best.finish(), win))
    }

    /// Lanes whose ray hits some primitive (occlusion); stops when every valid lane has hit.
    pub(crate) fn any_lanes<V: View<P>, L: Lane>(&self, view: &V, rays: &RayPacket<L>) -> L::Mask {
        match self.any_lanes_with::<SHORT, V, L>(view, rays) {
            Some(m) => m,
            None => self
                .any_lanes_with::<STACK, V, L>(view, rays)
                .unwrap_or(L::Mask::splat(false)),
        }
    }

    /// [`any_lanes`](Self::any_lanes) with a stack of `N` entries: `None` when it overflowed
    /// before every valid lane had hit.
    #[inline(always)]
    fn any_lanes_with<const N: usize, V: View<P>, L: Lane>(
        &self,
        view: &V,
        rays: &RayPacket<L>,
    ) -> Option<L::Mask> {
        let valid = rays.valid();
        let mut hit = L::Mask::splat(false);
        if valid.none() {
            return Some(hit);
        }
        let slab = PacketSlab::new(rays, self.reach);
        let x = view.many(rays);
        let pre = P::prepare(rays);
        let fr = frustum(&slab, rays, valid);
        let mut stack = Stack::<N>::new();
        while let Some((c, _)) = stack.pop() {
            let active = valid.and_not(hit);
            if c & LEAF == 0 {
                if let Some(n) = self.nodes.get(c as usize) {
                    visit(view, &x, &mut stack, c, n, &slab, rays, active, fr.as_ref());
                }
                continue;
            }
            let Some(leaf) = self.leaves.get((c & !LEAF) as usize) else {
                continue;
            };
            let test = view.leaf(c & !LEAF, leaf);
            for (k, &index) in leaf.indices().iter().enumerate() {
                if index != EMPTY {
                    hit = hit | (test.one(k, rays, &pre, self.cull).mask & valid);
                }
            }
            if valid.and_not(hit).none() {
                return Some(hit);
            }
        }
        (!stack.overflow).then_some(hit)
    }

    /// Every hit, as the flat set's `all` reports each primitive's, in traversal order (leaves
    /// nearest-first by the first lane's entry, lanes of a leaf in order).
    pub(crate) fn all_lanes<V: View<P>, L: Lane>(
        &self,
        view: &V,
        rays: &RayPacket<L>,
        f: &mut dyn FnMut(&Hits<L>),
    ) {
        let valid = rays.valid();
        if valid.none() {
            return;
        }
        let slab = PacketSlab::new(rays, self.reach);
        let x = view.many(rays);
        let pre = P::prepare(rays);
        let fr = frustum(&slab, rays, valid);
        let mut stack = Stack::<STACK>::new();
        while let Some((c, _)) = stack.pop() {
            if c & LEAF == 0 {
                if let Some(n) = self.nodes.get(c as usize) {
                    visit(view, &x, &mut stack, c, n, &slab, rays, valid, fr.as_ref());
                }
                continue;
            }
            let Some(leaf) = self.leaves.get((c & !LEAF) as usize) else {
                continue;
            };
            let test = view.leaf(c & !LEAF, leaf);
            for (k, &index) in leaf.indices().iter().enumerate() {
                if index == EMPTY {
                    continue;
                }
                if test.one(k, rays, &pre, self.cull).mask.any() {
                    P::all(&leaf.prim(k), index, rays, self.cull, f);
                }
            }
        }
    }
}
