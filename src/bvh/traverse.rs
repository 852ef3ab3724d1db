//! The traversal, written once: one loop for one ray ([`one`]: children in `f32x8` lanes,
//! nearest first) and one for a packet of any width ([`many`]: a node's children in one
//! interval test when the directions share their signs, otherwise one child box per lane
//! operation), generic over the node [`Layout`], the [`Collector`] (closest, any, all) and
//! what happens at a leaf (a closure: kernels over primitives, or instances traversed in turn).
//!
//! A leaf closure offers its candidates to the collector and returns true when the collector
//! asked to stop; the loops read the collector's `t_max` to prune. A packet's leaf closure
//! also gets the packet's [`Cone`] (where it has one), to skip the primitives whose boxes no
//! lane may enter. A one-ray traversal whose short stack overflows runs again with the full
//! one (keeping what the collector found: a closest hit found is still a candidate, and `any`
//! had found nothing), except for collectors that report every hit, which start with the full
//! stack.
//!
//! A packet's stack entries carry the lanes that entered each box, so a subtree only a few
//! lanes reach continues as single rays ([`many`]'s `single`: the caller's one-ray traversal
//! from that node, lane by lane; Embree's hybrid traversal does the same): a packet then
//! never does much more work than its rays traced one by one, whatever their coherence.

use super::node::{Entries, Frustum, Layout, PacketSlab, Slab, Stack, highest};
use super::{EMPTY, LEAF, STACK, WIDTH};
use crate::hit::Collector;
use crate::lane::{Lane, Mask, Scalar};
use crate::ray::{Ray, RayPacket};

/// Pushes the children of `n` in `bits` but the nearest, farthest first by `tn`, child `k`
/// with the key `key(k)`, and returns the nearest (its reference and key), which the caller
/// visits next without a push (or pushes last).
#[inline(always)]
fn push_sorted<N: Layout, S: Entries>(
    stack: &mut S,
    n: &N,
    mut bits: u32,
    tn: &[f32; WIDTH],
    key: impl Fn(usize) -> u32,
) -> Option<(u32, u32)> {
    if bits == 0 {
        return None;
    }
    // One or two children (most nodes a ray enters) without the sort's loops: the same order.
    let first = bits.trailing_zeros() as usize;
    let rest = bits & (bits - 1);
    if rest == 0 {
        return Some((n.child(first), key(first)));
    }
    if rest & (rest - 1) == 0 {
        let second = rest.trailing_zeros() as usize;
        let (near, far) = if tn[first] < tn[second] {
            (first, second)
        } else {
            (second, first)
        };
        stack.push(n.child(far), key(far));
        return Some((n.child(near), key(near)));
    }
    let mut list = [(0u32, 0.0f32); WIDTH];
    let mut m = 0;
    while bits != 0 {
        let k = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let item = (k as u32, tn[k]);
        // Insertion sort, descending entry parameter.
        let mut j = m;
        while j > 0 && list[j - 1].1 < item.1 {
            list[j] = list[j - 1];
            j -= 1;
        }
        list[j] = item;
        m += 1;
    }
    let (&(near, _), rest) = list[..m].split_last()?;
    for &(k, _) in rest {
        stack.push(n.child(k as usize), key(k as usize));
    }
    Some((n.child(near as usize), key(near as usize)))
}

/// One ray through the tree `nodes` (root first; `reach`: the largest coordinate of the
/// root's children) from the node reference `start` (0: the root; an inner node or a leaf):
/// `leaf(i, c)` for every leaf `i` reached whose box the interval meets, nearest first,
/// until it returns true (then so does this).
#[inline(always)]
pub(crate) fn one<N: Layout, C: Collector<f32>>(
    nodes: &[N],
    reach: f32,
    ray: &Ray,
    start: u32,
    c: &mut C,
    leaf: impl FnMut(u32, &mut C) -> bool,
) -> bool {
    one_fetching(nodes, reach, ray, start, c, None::<&fn(u32)>, leaf)
}

/// [`one`], with `fetch(r)` called on the reference `r` of every child a node's test lets
/// through, as soon as the test is made (before the nearest is entered): a caller whose
/// children are far in memory prefetches them there, so that their misses overlap (the owned
/// scene's top level). `None`: nothing more than [`one`].
#[inline(always)]
pub(crate) fn one_fetching<N: Layout, C: Collector<f32>>(
    nodes: &[N],
    reach: f32,
    ray: &Ray,
    start: u32,
    c: &mut C,
    fetch: Option<&impl Fn(u32)>,
    mut leaf: impl FnMut(u32, &mut C) -> bool,
) -> bool {
    if start & LEAF != 0 {
        return start != EMPTY && ray.is_valid() && leaf(start & !LEAF, c);
    }
    if !C::EVERY
        && size_of::<N::Short>() < size_of::<N::Full>()
        && let Some(stop) =
            one_with::<N::Short, N, C>(nodes, reach, ray, start, c, fetch, &mut leaf)
    {
        return stop;
    }
    one_with::<N::Full, N, C>(nodes, reach, ray, start, c, fetch, &mut leaf).unwrap_or(false)
}

/// [`one`] from the inner node `start` with the stack `S`: `None` when it overflowed (never
/// with the layout's full stack, by the depth bound).
#[inline(always)]
fn one_with<S: Entries, N: Layout, C: Collector<f32>>(
    nodes: &[N],
    reach: f32,
    ray: &Ray,
    start: u32,
    c: &mut C,
    fetch: Option<&impl Fn(u32)>,
    leaf: &mut impl FnMut(u32, &mut C) -> bool,
) -> Option<bool> {
    if !ray.is_valid() {
        return Some(false);
    }
    let slab = Slab::new(ray.origin(), ray.dir(), reach);
    // The first node is tested before the stack is set up: a ray that meets none of the
    // root's children (most rays leaving a convex part) costs one node test.
    let Some(first) = nodes.get(start as usize) else {
        return Some(false);
    };
    let (bits, tn) = first.test_one(&slab, ray.t_min(), c.t_max());
    if bits == 0 {
        return Some(false);
    }
    fetch_children(first, bits, fetch);
    let mut stack = S::new();
    // The nearest child entered is visited next, without a push (Embree's order).
    let Some((mut r, _)) = push_sorted(&mut stack, first, bits, &tn, |k| tn[k].to_bits()) else {
        return Some(false);
    };
    loop {
        if r & LEAF == 0 {
            if let Some(n) = nodes.get(r as usize) {
                let (bits, tn) = n.test_one(&slab, ray.t_min(), c.t_max());
                fetch_children(n, bits, fetch);
                if let Some((near, _)) = push_sorted(&mut stack, n, bits, &tn, |k| tn[k].to_bits())
                {
                    r = near;
                    continue;
                }
            }
        } else if leaf(r & !LEAF, c) {
            return Some(true);
        }
        r = loop {
            match stack.pop() {
                Some((r, key)) if !(C::SHRINKS && f32::from_bits(key) > c.t_max()) => break r,
                Some(_) => {}
                None => return (!stack.overflowed()).then_some(false),
            }
        };
    }
}

/// `fetch(r)` for the references `r` of the children of `n` in `bits`.
#[inline(always)]
fn fetch_children<N: Layout>(n: &N, mut bits: u32, fetch: Option<&impl Fn(u32)>) {
    let Some(fetch) = fetch else {
        return;
    };
    while bits != 0 {
        fetch(n.child(bits.trailing_zeros() as usize));
        bits &= bits - 1;
    }
}

/// A packet through the tree `nodes` (as [`one`]): `leaf(i, rays, c)` for every leaf `i` more
/// than `split` active lanes reach, with the rays' `t_max` the collector's, and
/// `single(r, lane, c)` for each lane of a subtree `r` (inner node or leaf) that `split` or
/// fewer active lanes reach (`split = 0`: never), until one returns true. `single` runs the
/// lane as one ray from `r` and returns true when the packet may stop.
#[inline(always)]
pub(crate) fn many<N: Layout, L: Lane, C: Collector<L>>(
    nodes: &[N],
    reach: f32,
    rays: &RayPacket<L>,
    c: &mut C,
    mut leaf: impl FnMut(u32, &RayPacket<L>, Option<&Cone>, &mut C) -> bool,
    split: u32,
    mut single: impl FnMut(u32, usize, &mut C) -> bool,
) -> bool {
    if !C::EVERY
        && let Some(stop) =
            many_with::<Stack<SHORT>, N, L, C>(nodes, reach, rays, c, &mut leaf, split, &mut single)
    {
        return stop;
    }
    many_with::<Stack<STACK>, N, L, C>(nodes, reach, rays, c, &mut leaf, split, &mut single)
        .unwrap_or(false)
}

/// Entries of a packet's first stack (a traversal that overflows it runs again with
/// [`STACK`]).
const SHORT: usize = 32;

/// [`many`] with the stack `S`: `None` when it overflowed.
#[inline(always)]
fn many_with<S: Entries, N: Layout, L: Lane, C: Collector<L>>(
    nodes: &[N],
    reach: f32,
    rays: &RayPacket<L>,
    c: &mut C,
    leaf: &mut impl FnMut(u32, &RayPacket<L>, Option<&Cone>, &mut C) -> bool,
    split: u32,
    single: &mut impl FnMut(u32, usize, &mut C) -> bool,
) -> Option<bool> {
    crate::lane::assert_fits::<L>();
    let valid = c.active() & rays.valid();
    if valid.none() || nodes.is_empty() {
        return Some(false);
    }
    let slab = PacketSlab::new(rays, reach);
    let mut r = RayPacket {
        t_max: L::select(valid, c.t_max(), rays.t_max),
        ..*rays
    };
    let mut fr = frustum(&slab, &r, valid);
    // A camera's packet never splits (its frustum is tight down to the leaves); one whose
    // directions' signs differ (no frustum: every child is tested lane by lane) splits at
    // twice `split` (diffuse rays on a 940k-triangle mesh: packets of 8 from 0.75× to 0.86×
    // Embree's one-ray speed, of 16 from 0.83× to 0.93×; twice `split` for frustum packets
    // cost shadow rays 1.07× → 0.96× on a 69k one).
    let split = match &fr {
        Some(f) if f.one_eye => 0,
        Some(_) => split,
        None => (2 * split).min(L::LANES as u32),
    };
    let mut stack = S::new();
    stack.push(0, valid.bits());
    while let Some((n, lanes)) = stack.pop() {
        // The lanes that entered this box and still look for hits.
        let active = c.active() & valid;
        let lanes = lanes & active.bits();
        if lanes == 0 {
            continue;
        }
        if lanes.count_ones() <= split {
            let mut b = lanes;
            while b != 0 {
                let i = b.trailing_zeros() as usize;
                b &= b - 1;
                if single(n, i, c) {
                    return Some(true);
                }
            }
            continue;
        }
        if n & LEAF == 0 {
            if let Some(node) = nodes.get(n as usize) {
                visit(&mut stack, node, &slab, &r, active, lanes, fr.as_ref());
            }
            continue;
        }
        if leaf(n & !LEAF, &r, fr.as_ref(), c) {
            return Some(true);
        }
        // Shrink the intervals (and the frustum's) to the collector's.
        let t = L::select(valid, c.t_max(), rays.t_max);
        if t.lt(r.t_max).any() {
            r.t_max = t;
            if let Some(f) = fr.as_mut() {
                f.t_hi = highest(t, valid);
            }
        }
    }
    (!stack.overflowed()).then_some(false)
}

/// True when the `valid` lanes of `rays` share their origin, bit for bit.
#[inline(always)]
fn same_origin<L: Lane>(rays: &RayPacket<L>, valid: L::Mask) -> bool {
    let o = rays.origin();
    let Some(first) = (0..L::LANES).find(|&i| valid.test(i)) else {
        return false;
    };
    let (x, y, z) = (o.x.lane(first), o.y.lane(first), o.z.lane(first));
    let same =
        o.x.ge(L::splat(x)) & o.x.le(L::splat(x)) & o.y.ge(L::splat(y)) & o.y.le(L::splat(y));
    (same & o.z.ge(L::splat(z)) & o.z.le(L::splat(z)) | !valid).all()
}

/// A packet's [`Frustum`], tested against a node's children for the whole packet at once.
pub(crate) struct Cone {
    f: Frustum,
    /// The lanes' lowest `t_min` and highest `t_max`.
    t_lo: f32,
    t_hi: f32,
    /// Rays from one point (a camera's): the frustum is tight, and the lanes of a child it
    /// enters are not tested one by one (a leaf's primitives are tested against the frustum,
    /// then by the kernels; callgrind, x86-64-v3, the vendored bunny's primary rays: testing
    /// a leaf child's lanes too cost 278 against 265 instructions per ray in packets of 16,
    /// 344 against 320 in packets of 8).
    one_eye: bool,
}

impl Cone {
    /// Bit `k` set when some lane may enter the box of a leaf's primitive `k` (rows as
    /// [`Leaf::boxes`](super::Leaf::boxes)).
    #[inline(always)]
    pub(crate) fn enters(&self, b: [wide::f32x4; 6]) -> u32 {
        self.f.test4(b, self.t_lo, self.t_hi)
    }
}

/// A packet's [`Cone`], where it has more than one lane.
#[inline(always)]
fn frustum<L: Lane>(slab: &PacketSlab<L>, rays: &RayPacket<L>, valid: L::Mask) -> Option<Cone> {
    // One lane: its own per-child test is as tight and, where `f32x8` is emulated (Cortex-M),
    // cheaper (4,941 against 9,447 instructions per primary ray on the M4F).
    if L::LANES == 1 {
        return None;
    }
    Some(Cone {
        f: Frustum::new(slab, valid)?,
        t_lo: -highest(-rays.t_min, valid),
        t_hi: highest(rays.t_max, valid),
        one_eye: same_origin(rays, valid),
    })
}

/// Pushes the children of node `n` some of the lanes `lanes` enter, each with the lanes that
/// enter it, nearest (by the first such lane's entry, or the frustum's) on top. With a
/// [`Cone`], the children are first tested for the whole packet at once, and those it enters
/// lane by lane unless the packet's rays share one eye.
#[inline(always)]
fn visit<N: Layout, L: Lane, S: Entries>(
    stack: &mut S,
    n: &N,
    slab: &PacketSlab<L>,
    r: &RayPacket<L>,
    active: L::Mask,
    lanes: u32,
    fr: Option<&Cone>,
) {
    let one_eye = fr.is_some_and(|c| c.one_eye);
    let (mut bits, mut key) = match fr {
        Some(c) => n.test_frustum(&c.f, c.t_lo, c.t_hi),
        None => (
            (0..WIDTH).fold(0, |b, k| b | (u32::from(n.child(k) != EMPTY) << k)),
            [0.0; WIDTH],
        ),
    };
    let mut entered = [0u32; WIDTH];
    let mut todo = bits;
    while todo != 0 {
        let k = todo.trailing_zeros() as usize;
        todo &= todo - 1;
        if one_eye {
            entered[k] = lanes;
            continue;
        }
        let (m, tn) = n.test_lanes(slab, k, r.t_min, r.t_max, active);
        let mb = m.bits() & lanes;
        if mb == 0 {
            bits &= !(1 << k);
        } else {
            entered[k] = mb;
            key[k] = tn.lane(mb.trailing_zeros() as usize).to_f64() as f32;
        }
    }
    if let Some((r, lanes)) = push_sorted(stack, n, bits, &key, |k| entered[k]) {
        stack.push(r, lanes);
    }
}
