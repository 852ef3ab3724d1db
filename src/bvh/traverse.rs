//! Traversal: one ray (children in `f32x8` lanes, leaves in `f32x4` lanes) and packets of any
//! width (one child box per lane operation).

use glam::Vec3;
use wide::{f32x4, f32x8};

use super::{Bvh, EMPTY, LEAF, Leaf, Node, STACK, WIDTH};
use crate::hit::{Best, LaneHit, relax};
use crate::lane::MAX_LANES;
use crate::lane::{Lane, Mask};
use crate::query::Hits;
use crate::ray::{Ray, RayPacket};

/// The box widening relative to `R + |o|∞`: `2^-17` (see the [module docs](super) for why it
/// is conservative).
const MARGIN: f32 = 1.0 / 131072.0;
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
        let mut s = Slab {
            near: [0, 1, 2],
            far: [3, 4, 5],
            on: [0.0; 3],
            of: [0.0; 3],
            inv: [0.0; 3],
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
        if self.all {
            let mut bits = 0;
            for (k, &c) in n.child.iter().enumerate() {
                if c != EMPTY {
                    bits |= 1 << k;
                }
            }
            return (bits, f32x8::splat(t_min));
        }
        let b = &n.bounds;
        let plane = |p: usize, o: f32, inv: f32| (f32x8::new(b[p]) - f32x8::splat(o)) * inv;
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
    pub(crate) fn closest_one(&self, ray: &Ray) -> Option<Winner<P>> {
        match self.closest_with::<SHORT>(ray) {
            Ok(h) => h,
            Err(()) => self.closest_with::<STACK>(ray).ok().flatten(),
        }
    }

    /// [`closest_one`](Self::closest_one) with a stack of `N` entries: `Err` when it
    /// overflowed (never with `N = STACK`, by the depth bound).
    #[inline(always)]
    fn closest_with<const N: usize>(&self, ray: &Ray) -> Result<Option<Winner<P>>, ()> {
        if !ray.is_valid() {
            return Ok(None);
        }
        let slab = Slab::new(ray.origin(), ray.dir(), self.reach);
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
        let (bits, tn) = slab.test(root, ray.t_min(), t_max);
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
                let (bits, tn) = slab.test(n, ray.t_min(), t_max);
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
            let h = leaf.test_four(&r, pre, self.cull);
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
    pub(crate) fn any_one(&self, ray: &Ray) -> bool {
        match self.any_with::<SHORT>(ray) {
            Some(hit) => hit,
            None => self.any_with::<STACK>(ray).unwrap_or(false),
        }
    }

    /// [`any_one`](Self::any_one) with a stack of `N` entries: `None` when it overflowed
    /// before finding a hit.
    #[inline(always)]
    fn any_with<const N: usize>(&self, ray: &Ray) -> Option<bool> {
        if !ray.is_valid() {
            return Some(false);
        }
        let slab = Slab::new(ray.origin(), ray.dir(), self.reach);
        let r4 = RayPacket::<f32x4>::splat(ray);
        // Made at the first leaf, as in `closest_with`.
        let mut pre = None;
        let Some(root) = self.nodes.first() else {
            return Some(false);
        };
        let (bits, tn) = slab.test(root, ray.t_min(), ray.t_max());
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
                let (bits, tn) = slab.test(n, ray.t_min(), ray.t_max());
                stack.push_sorted(n, bits, &tn.to_array());
            } else if let Some(leaf) = self.leaves.get((c & !LEAF) as usize)
                && leaf
                    .test_four(&r4, pre.get_or_insert_with(|| P::prepare(&r4)), self.cull)
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
struct PacketSlab<L: Lane> {
    neg: [L::Mask; 3],
    on: [L; 3],
    of: [L; 3],
    inv: [L; 3],
    all: L::Mask,
}

#[inline(always)]
fn lmax<L: Lane>(a: L, b: L) -> L {
    L::select(b.gt(a), b, a)
}

#[inline(always)]
fn lmin<L: Lane>(a: L, b: L) -> L {
    L::select(b.lt(a), b, a)
}

impl<L: Lane> PacketSlab<L> {
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
            all: !ok,
        }
    }

    /// Lanes of `active` whose interval meets child `k`'s widened box, and their entry
    /// parameters.
    #[inline(always)]
    fn test(&self, n: &Node, k: usize, t_min: L, t_max: L, active: L::Mask) -> (L::Mask, L) {
        let p = |i: usize| L::from_f32(n.bounds[i][k]);
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

/// Pushes the children of `n` some lane of `active` enters, nearest (by the first such lane's
/// entry) on top.
#[inline(always)]
fn visit<L: Lane>(
    stack: &mut Stack,
    n: &Node,
    slab: &PacketSlab<L>,
    r: &RayPacket<L>,
    active: L::Mask,
) {
    let mut bits = 0u32;
    let mut key = [0.0f32; WIDTH];
    for (k, key) in key.iter_mut().enumerate() {
        if n.child[k] == EMPTY {
            continue;
        }
        let (m, tn) = slab.test(n, k, r.t_min, r.t_max, active);
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
    pub(crate) fn closest_lanes<L: Lane>(
        &self,
        rays: &RayPacket<L>,
    ) -> (Best<L>, [u32; MAX_LANES]) {
        crate::lane::assert_fits::<L>();
        let valid = rays.valid();
        let mut best = Best::<L>::miss();
        let mut win = [0u32; MAX_LANES];
        if valid.none() {
            return (best, win);
        }
        let slab = PacketSlab::new(rays, self.reach);
        let pre = P::prepare(rays);
        let t_end = rays.t_max;
        let mut r = RayPacket {
            t_max: L::select(valid, relax(rays.t_max), rays.t_max),
            ..*rays
        };
        let mut stack = Stack::<STACK>::new();
        while let Some((c, _)) = stack.pop() {
            if c & LEAF == 0 {
                if let Some(n) = self.nodes.get(c as usize) {
                    visit(&mut stack, n, &slab, &r, valid);
                }
                continue;
            }
            let li = c & !LEAF;
            let Some(leaf) = self.leaves.get(li as usize) else {
                continue;
            };
            for (k, &index) in leaf.indices().iter().enumerate() {
                if index == EMPTY {
                    continue;
                }
                let h = leaf.test_one(k, &r, &pre, self.cull);
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
        (best.finish(), win)
    }

    /// Lanes whose ray hits some primitive (occlusion); stops when every valid lane has hit.
    pub(crate) fn any_lanes<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        let valid = rays.valid();
        let mut hit = L::Mask::splat(false);
        if valid.none() {
            return hit;
        }
        let slab = PacketSlab::new(rays, self.reach);
        let pre = P::prepare(rays);
        let mut stack = Stack::<STACK>::new();
        while let Some((c, _)) = stack.pop() {
            let active = valid.and_not(hit);
            if c & LEAF == 0 {
                if let Some(n) = self.nodes.get(c as usize) {
                    visit(&mut stack, n, &slab, rays, active);
                }
                continue;
            }
            let Some(leaf) = self.leaves.get((c & !LEAF) as usize) else {
                continue;
            };
            for (k, &index) in leaf.indices().iter().enumerate() {
                if index != EMPTY {
                    hit = hit | (leaf.test_one(k, rays, &pre, self.cull).mask & valid);
                }
            }
            if valid.and_not(hit).none() {
                break;
            }
        }
        hit
    }

    /// Every hit, as the flat set's `all` reports each primitive's, in traversal order (leaves
    /// nearest-first by the first lane's entry, lanes of a leaf in order).
    pub(crate) fn all_lanes<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        let valid = rays.valid();
        if valid.none() {
            return;
        }
        let slab = PacketSlab::new(rays, self.reach);
        let pre = P::prepare(rays);
        let mut stack = Stack::<STACK>::new();
        while let Some((c, _)) = stack.pop() {
            if c & LEAF == 0 {
                if let Some(n) = self.nodes.get(c as usize) {
                    visit(&mut stack, n, &slab, rays, valid);
                }
                continue;
            }
            let Some(leaf) = self.leaves.get((c & !LEAF) as usize) else {
                continue;
            };
            for (k, &index) in leaf.indices().iter().enumerate() {
                if index == EMPTY {
                    continue;
                }
                if leaf.test_one(k, rays, &pre, self.cull).mask.any() {
                    P::all(&leaf.prim(k), index, rays, self.cull, f);
                }
            }
        }
    }
}
