//! The traversal, written once: one loop for one ray ([`one`]: children in `f32x8` lanes,
//! nearest first) and one for a packet of any width ([`many`]: a node's children in one
//! interval test when the directions share their signs, otherwise one child box per lane
//! operation), generic over the node [`Layout`], the [`Collector`] (closest, any, all) and
//! what happens at a leaf (a closure: kernels over primitives, or instances traversed in turn).
//!
//! A leaf closure offers its candidates to the collector and returns true when the collector
//! asked to stop; the loops read the collector's `t_max` to prune. A traversal whose short
//! stack overflows runs again with the full one (keeping what the collector found: a closest
//! hit found is still a candidate, and `any` had found nothing), except for collectors that
//! report every hit, which start with the full stack.

use super::node::{Entries, Frustum, Layout, PacketSlab, Slab, highest};
use super::{EMPTY, LEAF, WIDTH};
use crate::hit::Collector;
use crate::lane::{Lane, Mask, Scalar};
use crate::ray::{Ray, RayPacket};

/// Pushes the children of `n` in `bits` farthest first (so the nearest is popped first).
#[inline(always)]
fn push_sorted<N: Layout, S: Entries>(stack: &mut S, n: &N, mut bits: u32, tn: &[f32; WIDTH]) {
    let mut list = [(0u32, 0.0f32); WIDTH];
    let mut m = 0;
    while bits != 0 {
        let k = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let item = (n.child(k), tn[k]);
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
        stack.push(c, t);
    }
}

/// One ray through the tree `nodes` (root first; `reach`: the largest coordinate of the
/// root's children): `leaf(i, c)` for every leaf `i` reached whose box the interval meets,
/// nearest first, until it returns true (then so does this).
#[inline(always)]
pub(crate) fn one<N: Layout, C: Collector<f32>>(
    nodes: &[N],
    reach: f32,
    ray: &Ray,
    c: &mut C,
    mut leaf: impl FnMut(u32, &mut C) -> bool,
) -> bool {
    if !C::EVERY
        && size_of::<N::Short>() < size_of::<N::Full>()
        && let Some(stop) = one_with::<N::Short, N, C>(nodes, reach, ray, c, &mut leaf)
    {
        return stop;
    }
    one_with::<N::Full, N, C>(nodes, reach, ray, c, &mut leaf).unwrap_or(false)
}

/// [`one`] with the stack `S`: `None` when it overflowed (never with the layout's full stack,
/// by the depth bound).
#[inline(always)]
fn one_with<S: Entries, N: Layout, C: Collector<f32>>(
    nodes: &[N],
    reach: f32,
    ray: &Ray,
    c: &mut C,
    leaf: &mut impl FnMut(u32, &mut C) -> bool,
) -> Option<bool> {
    if !ray.is_valid() {
        return Some(false);
    }
    let slab = Slab::new(ray.origin(), ray.dir(), reach);
    // The root is tested before the stack is set up: a ray that meets none of its children
    // (most rays leaving a convex part) costs one node test.
    let Some(root) = nodes.first() else {
        return Some(false);
    };
    let (bits, tn) = root.test_one(&slab, ray.t_min(), c.t_max());
    if bits == 0 {
        return Some(false);
    }
    let mut stack = S::new();
    push_sorted(&mut stack, root, bits, &tn);
    while let Some((r, tn)) = stack.pop() {
        if C::SHRINKS && tn > c.t_max() {
            continue;
        }
        if r & LEAF == 0 {
            if let Some(n) = nodes.get(r as usize) {
                let (bits, tn) = n.test_one(&slab, ray.t_min(), c.t_max());
                push_sorted(&mut stack, n, bits, &tn);
            }
            continue;
        }
        if leaf(r & !LEAF, c) {
            return Some(true);
        }
    }
    (!stack.overflowed()).then_some(false)
}

/// A packet through the tree `nodes` (as [`one`]): `leaf(i, rays, c)` for every leaf `i` some
/// active lane reaches, with the rays' `t_max` the collector's, until it returns true.
#[inline(always)]
pub(crate) fn many<N: Layout, L: Lane, C: Collector<L>>(
    nodes: &[N],
    reach: f32,
    rays: &RayPacket<L>,
    c: &mut C,
    mut leaf: impl FnMut(u32, &RayPacket<L>, &mut C) -> bool,
) -> bool {
    if !C::EVERY
        && size_of::<N::Short>() < size_of::<N::Full>()
        && let Some(stop) = many_with::<N::Short, N, L, C>(nodes, reach, rays, c, &mut leaf)
    {
        return stop;
    }
    many_with::<N::Full, N, L, C>(nodes, reach, rays, c, &mut leaf).unwrap_or(false)
}

/// [`many`] with the stack `S`: `None` when it overflowed.
#[inline(always)]
fn many_with<S: Entries, N: Layout, L: Lane, C: Collector<L>>(
    nodes: &[N],
    reach: f32,
    rays: &RayPacket<L>,
    c: &mut C,
    leaf: &mut impl FnMut(u32, &RayPacket<L>, &mut C) -> bool,
) -> Option<bool> {
    crate::lane::assert_fits::<L>();
    let valid = c.active() & rays.valid();
    if valid.none() {
        return Some(false);
    }
    let slab = PacketSlab::new(rays, reach);
    let mut r = RayPacket {
        t_max: L::select(valid, c.t_max(), rays.t_max),
        ..*rays
    };
    let mut fr = frustum(&slab, &r, valid);
    let mut stack = S::new();
    if let Some(root) = nodes.first() {
        visit(&mut stack, root, &slab, &r, valid, fr.as_ref());
    }
    while let Some((n, _)) = stack.pop() {
        if n & LEAF == 0 {
            if let Some(node) = nodes.get(n as usize) {
                let active = c.active() & valid;
                visit(&mut stack, node, &slab, &r, active, fr.as_ref());
            }
            continue;
        }
        if leaf(n & !LEAF, &r, c) {
            return Some(true);
        }
        // Shrink the intervals (and the frustum's) to the collector's.
        let t = L::select(valid, c.t_max(), rays.t_max);
        if t.lt(r.t_max).any() {
            r.t_max = t;
            if let Some(f) = fr.as_mut() {
                f.2 = highest(t, valid);
            }
        }
    }
    (!stack.overflowed()).then_some(false)
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

/// Pushes the children of node `n` some lane of `active` enters, nearest (by the first such
/// lane's entry) on top. With a [`Frustum`], the children are tested for the whole packet at
/// once (`t_lo`, `t_hi`: the lanes' lowest `t_min` and highest `t_max`), and a leaf child only
/// if some lane's own test enters it.
#[inline(always)]
fn visit<N: Layout, L: Lane, S: Entries>(
    stack: &mut S,
    n: &N,
    slab: &PacketSlab<L>,
    r: &RayPacket<L>,
    active: L::Mask,
    fr: Option<&(Frustum, f32, f32)>,
) {
    if let Some((f, t_lo, t_hi)) = fr {
        let (mut bits, tn) = n.test_frustum(f, *t_lo, *t_hi);
        let mut leaves = bits;
        while leaves != 0 {
            let k = leaves.trailing_zeros() as usize;
            leaves &= leaves - 1;
            if n.child(k) & LEAF != 0 {
                let (m, _) = n.test_lanes(slab, k, r.t_min, r.t_max, active);
                if m.none() {
                    bits &= !(1 << k);
                }
            }
        }
        push_sorted(stack, n, bits, &tn);
        return;
    }
    let mut bits = 0u32;
    let mut key = [0.0f32; WIDTH];
    for (k, key) in key.iter_mut().enumerate() {
        if n.child(k) == EMPTY {
            continue;
        }
        let (m, tn) = n.test_lanes(slab, k, r.t_min, r.t_max, active);
        let mb = m.bits();
        if mb != 0 {
            bits |= 1 << k;
            *key = tn.lane(mb.trailing_zeros() as usize).to_f64() as f32;
        }
    }
    push_sorted(stack, n, bits, &key);
}
