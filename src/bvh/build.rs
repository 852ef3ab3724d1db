//! The binned-SAH builder of 8-wide nodes over caller storage, and the refit.

use super::{
    BINS, BuildError, Bvh, EMPTY, LEAF, LEAF_WIDTH, MAX_PRIMITIVES, Node, Packed, Primitives,
    SAH_DEPTH, Scratch, WIDTH, area, max, min, reach, sizes,
};
use crate::set::TooSmall;
use wide::f32x4;

type Box3 = ([f32; 3], [f32; 3]);

const EMPTY_BOX: Box3 = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);

#[inline(always)]
fn grow(b: &mut Box3, lo: &[f32; 3], hi: &[f32; 3]) {
    for a in 0..3 {
        b.0[a] = min(b.0[a], lo[a]);
        b.1[a] = max(b.1[a], hi[a]);
    }
}

/// A box as 8 lanes: min x, y, z, 0, then −max x, y, z, 0. The union of two boxes is one
/// lane-wise [`min`] (one 8-lane operation where the target has it); negation is exact and
/// `min(−a, −b) = −max(a, b)` bit for bit, so the boxes are those of [`grow`].
type Lanes = [f32; 8];

const EMPTY_LANES: Lanes = [
    f32::INFINITY,
    f32::INFINITY,
    f32::INFINITY,
    0.0,
    f32::INFINITY,
    f32::INFINITY,
    f32::INFINITY,
    0.0,
];

#[inline(always)]
fn union(b: &mut Lanes, o: &Lanes) {
    for l in 0..8 {
        b[l] = min(b[l], o[l]);
    }
}

/// `(min, max)` of a box in lanes.
#[inline(always)]
fn unlanes(b: &Lanes) -> Box3 {
    ([b[0], b[1], b[2]], [-b[4], -b[5], -b[6]])
}

#[inline(always)]
fn lanes_area(b: &Lanes) -> f32 {
    let (lo, hi) = unlanes(b);
    area(lo, hi)
}

/// A range's box (in lanes) and its centroids' box.
type Boxes = (Lanes, Box3);

/// The box of `s`'s primitives and the box of their centroids, in one pass.
fn range_boxes(s: &[Scratch]) -> Boxes {
    let (mut b, mut cb) = (EMPTY_LANES, EMPTY_BOX);
    for p in s {
        union(&mut b, &p.b);
        grow(&mut cb, &p.c, &p.c);
    }
    (b, cb)
}

/// Bin of centroid coordinate `c`: `⌊(c − cmin)·k⌋` clamped to `0…BINS−1`, NaN giving 0 (`as`
/// saturates and maps NaN to 0: the same bin on every target, without branches).
#[inline(always)]
fn bin(c: f32, cmin: f32, k: f32) -> usize {
    const TOP: f32 = (BINS - 1) as f32;
    let x = (c - cmin) * k;
    (if x >= TOP { TOP } else { x }) as u8 as usize
}

/// [`bin`] on the three axes at once, in lanes: the same operations, so the same bins.
#[inline(always)]
fn bins(c: &[f32; 3], cmin: &[f32; 3], k: &[f32; 3]) -> [usize; 3] {
    let top = f32x4::splat((BINS - 1) as f32);
    let v = |a: &[f32; 3]| f32x4::new([a[0], a[1], a[2], 0.0]);
    let x = (v(c) - v(cmin)) * v(k);
    // NaN and negatives to 0 (as `as u8` maps them), then at most the top bin: the
    // truncation of what is left is its floor, an integer from 0 to BINS − 1.
    let x = (x & x.simd_ge(f32x4::ZERO)).fast_min(top);
    let i = x.fast_trunc_int().to_array();
    [0, 1, 2].map(|a| (i[a] as usize).min(BINS - 1))
}

/// Counts and boxes of the bins of the three axes.
struct Bins {
    count: [[u32; BINS]; 3],
    boxes: [[Lanes; BINS]; 3],
}

impl Bins {
    const EMPTY: Bins = Bins {
        count: [[0; BINS]; 3],
        boxes: [[EMPTY_LANES; BINS]; 3],
    };

    /// Adds `p` (centroid bins from the minimum `cmin` and scales `k`).
    #[inline(always)]
    fn add(&mut self, p: &Scratch, cmin: &[f32; 3], k: &[f32; 3]) {
        for (axis, b) in bins(&p.c, cmin, k).into_iter().enumerate() {
            self.count[axis][b] += 1;
            union(&mut self.boxes[axis][b], &p.b);
        }
    }

    /// Adds the primitives of `o`.
    fn merge(&mut self, o: &Bins) {
        for axis in 0..3 {
            for i in 0..BINS {
                if o.count[axis][i] != 0 {
                    self.count[axis][i] += o.count[axis][i];
                    union(&mut self.boxes[axis][i], &o.boxes[axis][i]);
                }
            }
        }
    }
}

/// Ranges of at least this many primitives are binned into two copies of the bins.
const PAIRED: usize = 64;

/// A child range under construction: `s[start..end]`, the box of its primitives and the box
/// of their centroids.
#[derive(Clone, Copy)]
struct Part {
    start: u32,
    end: u32,
    b: Lanes,
    cb: Box3,
}

/// The binned SAH split of `s` (Wald 2007) given its centroids' box `cb`: after partitioning
/// `s` in place, `Some((mid, left, right))` with both sides non-empty and their boxes and
/// centroid boxes, or `None` when no plane separates the centroids (or every cost is NaN).
///
/// One pass bins the centroids on all three axes at once (16 bins each: count and box); a
/// sweep per axis gives every plane's `A_L·N_L + A_R·N_R`; the children's boxes are unions
/// of the chosen axis's bins, and the partition pass gathers their centroid boxes.
fn sah_split(s: &mut [Scratch], cb: &Box3, leaf: usize) -> Option<(usize, Boxes, Boxes)> {
    let (cmin, cmax) = *cb;
    let mut k = [0.0f32; 3];
    let mut any = false;
    for axis in 0..3 {
        let ext = cmax[axis] - cmin[axis];
        // Also skips NaN extents (k stays 0: every centroid in bin 0).
        if ext > 0.0 {
            k[axis] = BINS as f32 / ext;
            any = true;
        }
    }
    if !any {
        return None;
    }
    let mut bins = Bins::EMPTY;
    if s.len() >= PAIRED {
        // Two copies filled by turns, then merged: consecutive primitives often fall in the
        // same bin, and the copies let their read-modify-writes overlap.
        let mut odd = Bins::EMPTY;
        let mut pairs = s.chunks_exact(2);
        for pair in &mut pairs {
            bins.add(&pair[0], &cmin, &k);
            odd.add(&pair[1], &cmin, &k);
        }
        for p in pairs.remainder() {
            bins.add(p, &cmin, &k);
        }
        bins.merge(&odd);
    } else {
        for p in s.iter() {
            bins.add(p, &cmin, &k);
        }
    }
    let Bins { count, boxes } = &bins;
    // (cost, axis, last bin of the left side)
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if k[axis] == 0.0 {
            continue;
        }
        let (count, boxes) = (&count[axis], &boxes[axis]);
        // Sweeps over the non-empty bins only: an empty bin changes nothing (the plane after
        // it costs what the plane before it costs, which wins the tie). Right sides from the
        // top (the bins from `j` up, stored at each non-empty `j ≥ 1`), then left sides
        // upward, each plane after a non-empty bin `i` against the right side from the next
        // non-empty bin `j`.
        let mut used = 0u32;
        for (i, &c) in count.iter().enumerate() {
            used |= u32::from(c != 0) << i;
        }
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0u32; BINS];
        let (mut acc, mut n) = (EMPTY_LANES, 0);
        let mut top = used & !1;
        while top != 0 {
            let j = (31 - top.leading_zeros()) as usize;
            top &= !(1 << j);
            union(&mut acc, &boxes[j]);
            n += count[j];
            right_area[j] = lanes_area(&acc);
            right_count[j] = n;
        }
        let (mut acc, mut n) = (EMPTY_LANES, 0);
        let mut rest = used;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            if rest == 0 {
                break;
            }
            let j = rest.trailing_zeros() as usize;
            union(&mut acc, &boxes[i]);
            n += count[i];
            // Primitives count in whole leaves (Embree's blocks): a side of 5 costs as 8.
            let cost =
                lanes_area(&acc) * blocks(n, leaf) + right_area[j] * blocks(right_count[j], leaf);
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i));
            }
        }
    }
    let (cost, axis, last) = best?;
    if cost.is_nan() {
        return None;
    }
    let (mut lb, mut rb) = (EMPTY_LANES, EMPTY_LANES);
    for b in &boxes[axis][..=last] {
        union(&mut lb, b);
    }
    for b in boxes[axis][last + 1..].iter().rev() {
        union(&mut rb, b);
    }
    // Partition in place (Hoare: scan from both ends, swap the misplaced pairs): bins ≤ last
    // to the left; the centroid boxes on the way.
    let left = |p: &Scratch| bin(p.c[axis], cmin[axis], k[axis]) <= last;
    let (mut lc, mut rc) = (EMPTY_BOX, EMPTY_BOX);
    let (mut i, mut j) = (0, s.len());
    loop {
        while i < j && left(&s[i]) {
            grow(&mut lc, &s[i].c, &s[i].c);
            i += 1;
        }
        while i < j && !left(&s[j - 1]) {
            j -= 1;
            grow(&mut rc, &s[j].c, &s[j].c);
        }
        if i == j {
            break;
        }
        j -= 1;
        s.swap(i, j);
        grow(&mut lc, &s[i].c, &s[i].c);
        grow(&mut rc, &s[j].c, &s[j].c);
        i += 1;
    }
    Some((i, (lb, lc), (rb, rc)))
}

/// `n` primitives as the leaves of up to `leaf` they fill: `⌈n / leaf⌉`.
#[inline(always)]
fn blocks(n: u32, leaf: usize) -> f32 {
    n.div_ceil(leaf as u32) as f32
}

/// Splits `s` (more than `leaf` primitives, centroid box `cb`) into two non-empty parts;
/// returns the size of the first and both parts' boxes and centroid boxes. Binned SAH above
/// [`SAH_DEPTH`], the middle index (rounded up to a multiple of `leaf`) below it or when SAH
/// finds no plane.
fn split(s: &mut [Scratch], cb: &Box3, depth: u32, leaf: usize) -> (usize, Boxes, Boxes) {
    if depth < SAH_DEPTH
        && let Some(r) = sah_split(s, cb, leaf)
    {
        return r;
    }
    // The middle, rounded up to whole leaves where that leaves both sides non-empty.
    let half = s.len() / 2;
    let whole = half.div_ceil(leaf) * leaf;
    let mid = if whole < s.len() { whole } else { half };
    (mid, range_boxes(&s[..mid]), range_boxes(&s[mid..]))
}

/// The end of the pending-node stack.
const NONE: u32 = u32::MAX;

/// A pending node's job, kept in its own slot until the node is built: `[start, end, depth,
/// next pending node]` in `child[0..4]`, the range's box in `bounds[0]`, its centroids' box
/// in `bounds[1][0..3]` (min) and `bounds[2][0..3]` (max).
fn job(w: [u32; 4], b: &Lanes, cb: &Box3) -> Node {
    let mut j = Node::EMPTY;
    j.child[..4].copy_from_slice(&w);
    j.bounds[0] = *b;
    j.bounds[1][..3].copy_from_slice(&cb.0);
    j.bounds[2][..3].copy_from_slice(&cb.1);
    j
}

/// The job in a pending node's slot (see [`job`]).
fn unjob(j: &Node) -> ([u32; 4], Lanes, Box3) {
    let w = [j.child[0], j.child[1], j.child[2], j.child[3]];
    let lo = [j.bounds[1][0], j.bounds[1][1], j.bounds[1][2]];
    let hi = [j.bounds[2][0], j.bounds[2][1], j.bounds[2][2]];
    (w, j.bounds[0], (lo, hi))
}

/// [`Bvh::build`]: [`topology`], then [`fill`] when `leaves` holds the leaves it counted.
pub(crate) fn build<'s, P: Primitives + ?Sized>(
    prims: &P,
    nodes: &'s mut [Node],
    leaves: &'s mut [P::Leaf],
    scratch: &mut [Scratch],
) -> Result<Bvh<'s, P::Leaf>, BuildError> {
    let (used_nodes, used_leaves) = topology(prims, nodes, scratch, WIDTH, LEAF_WIDTH, false)?;
    if leaves.len() < used_leaves {
        return Err(BuildError::Leaves(TooSmall {
            needed: used_leaves,
        }));
    }
    fill(prims, &scratch[..prims.count()], leaves);
    let nodes: &'s [Node] = &nodes[..used_nodes];
    let leaves: &'s [P::Leaf] = &leaves[..used_leaves];
    Ok(Bvh {
        nodes,
        leaves,
        reach: reach(&nodes[0]),
    })
}

/// The first pass of a build: the nodes, and in `scratch` the primitives in leaf order, the
/// first entry of each leaf marked with the leaf's number and size (see [`fill`]). Returns the
/// numbers of nodes and leaves used, so that the leaves can be stored in exactly as many
/// slots. At most `width` (2 to [`WIDTH`]) children per node, the others empty (4: the base
/// of the layout a bake converts), and at most `per_leaf` primitives per leaf ([`LEAF_WIDTH`];
/// or 1: every primitive a child of its node, referred to by its own index, `LEAF | i`, so
/// that there are no leaves to fill: an owned scene's top level, see [`refit_direct`]).
pub(crate) fn topology<P: Primitives + ?Sized>(
    prims: &P,
    nodes: &mut [Node],
    scratch: &mut [Scratch],
    width: usize,
    per_leaf: usize,
    threads: bool,
) -> Result<(usize, usize), BuildError> {
    let width = width.clamp(2, WIDTH);
    let per_leaf = per_leaf.clamp(1, LEAF_WIDTH);
    let n = prims.count();
    if n > MAX_PRIMITIVES {
        return Err(BuildError::TooMany);
    }
    let need = sizes(n);
    let short = |needed| TooSmall { needed };
    // With one primitive per leaf, every inner node but a lone root has two children or more.
    let need_nodes = if per_leaf == 1 { n.max(1) } else { need.nodes };
    if nodes.len() < need_nodes {
        return Err(BuildError::Nodes(short(need_nodes)));
    }
    if scratch.len() < need.scratch {
        return Err(BuildError::Scratch(short(need.scratch)));
    }
    let s = &mut scratch[..n];
    let (mut b, mut cb) = (EMPTY_LANES, EMPTY_BOX);
    for (i, p) in s.iter_mut().enumerate() {
        let (lo, hi) = prims.bounds(i as u32);
        let mut c = [0.0f32; 3];
        for a in 0..3 {
            let x = lo[a] * 0.5 + hi[a] * 0.5;
            c[a] = if x.is_finite() { x } else { 0.0 };
        }
        *p = Scratch {
            b: [lo[0], lo[1], lo[2], 0.0, -hi[0], -hi[1], -hi[2], 0.0],
            c,
            index: i as u32,
        };
        union(&mut b, &p.b);
        grow(&mut cb, &c, &c);
    }
    nodes[0] = Node::EMPTY;
    if n == 0 {
        return Ok((1, 0));
    }
    nodes[0] = job([0, n as u32, 1, NONE], &b, &cb);
    // Below this many primitives threads did not pay on 2 cores (the scenes benchmark:
    // 58,784 triangles 0.93× one thread, 69,451 1.13×).
    // (Threads renumber the leaves, which a direct tree does not have.)
    #[cfg(feature = "std")]
    if threads && per_leaf == LEAF_WIDTH && n >= 1 << 16 {
        return threaded(nodes, s, width);
    }
    let _ = threads;
    let g = expand(nodes, s, width, per_leaf, Grown::ROOT, usize::MAX)?;
    Ok((g.nodes, g.leaves))
}

/// [`topology`] on every core (feature `std`): the root first, then the subtrees of its
/// inner children, each over its own part of the scratch and into nodes of its own, on up to
/// `available_parallelism` threads; then each subtree's nodes and leaf numbers are moved to
/// where the one-thread build puts them (that build finishes the last child's subtree, then
/// the one before: each subtree's nodes and leaves are a run of numbers). Every decision
/// depends only on a node's range and depth, so the tree is the one-thread tree, bit for bit.
#[cfg(feature = "std")]
fn threaded(
    nodes: &mut [Node],
    s: &mut [Scratch],
    width: usize,
) -> Result<(usize, usize), BuildError> {
    use std::sync::Mutex;
    use std::vec::Vec;

    let root = expand(nodes, s, width, LEAF_WIDTH, Grown::ROOT, 1)?;
    // The root's inner children, in the order the one-thread build takes them.
    let mut kids = Vec::new();
    let mut t = root.top;
    while t != NONE {
        let ([start, end, depth, next], b, cb) = unjob(&nodes[t as usize]);
        kids.push((t, start, end, job([0, end - start, depth, NONE], &b, &cb)));
        t = next;
    }
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    if cores < 2 || kids.len() < 2 {
        let g = expand(nodes, s, width, LEAF_WIDTH, root, usize::MAX)?;
        return Ok((g.nodes, g.leaves));
    }
    // Each child's part of the scratch (disjoint ranges), the largest first.
    let mut by_start: Vec<usize> = (0..kids.len()).collect();
    by_start.sort_by_key(|&i| kids[i].1);
    let mut work = Vec::with_capacity(kids.len());
    let (mut rest, mut at) = (&mut *s, 0usize);
    for i in by_start {
        let (_, start, end, _) = kids[i];
        let tail = core::mem::take(&mut rest);
        let (_, tail) = tail.split_at_mut(start as usize - at);
        let (part, tail) = tail.split_at_mut((end - start) as usize);
        rest = tail;
        at = end as usize;
        work.push((i, part));
    }
    work.sort_by_key(|(_, part)| part.len());
    let work = Mutex::new(work);
    type Built = (usize, Result<(Vec<Node>, usize), BuildError>);
    let mut built: Vec<Built> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..cores.min(kids.len()))
            .map(|_| {
                scope.spawn(|| {
                    let mut out: Vec<Built> = Vec::new();
                    loop {
                        let next = work.lock().map(|mut w| w.pop()).ok().flatten();
                        let Some((i, part)) = next else { break };
                        let mut local = std::vec![Node::EMPTY; sizes(part.len()).nodes];
                        local[0] = kids[i].3;
                        let g =
                            expand(&mut local, part, width, LEAF_WIDTH, Grown::ROOT, usize::MAX);
                        out.push((
                            i,
                            g.map(|g| {
                                local.truncate(g.nodes);
                                (local, g.leaves)
                            }),
                        ));
                    }
                    out
                })
            })
            .collect();
        // `expand` does not panic; were a worker to, its panic is the caller's.
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    // Every child was taken by exactly one worker: in the children's order again.
    built.sort_by_key(|&(i, _)| i);
    // In the one-thread order: each subtree's nodes after the ones before, its root in the
    // child's slot; its leaf numbers likewise (and in the marks `fill` reads).
    let (mut base, mut leaf_base) = (root.nodes, root.leaves);
    for (&(slot, start, end, _), (_, sub)) in kids.iter().zip(built) {
        let (local, leaves) = sub?;
        let moved = |mut n: Node| {
            for c in &mut n.child {
                if *c == EMPTY {
                } else if *c & LEAF != 0 {
                    *c = LEAF | ((*c & !LEAF) + leaf_base as u32);
                } else {
                    *c = *c - 1 + base as u32;
                }
            }
            n
        };
        let room = nodes
            .get_mut(base..base + local.len() - 1)
            .ok_or(BuildError::Nodes(TooSmall {
                needed: base + local.len() - 1,
            }))?;
        for (to, &from) in room.iter_mut().zip(&local[1..]) {
            *to = moved(from);
        }
        nodes[slot as usize] = moved(local[0]);
        let part = &mut s[start as usize..end as usize];
        // Each leaf's mark renumbered in place (the run's first entry is at 0).
        let mut p = 0;
        while let Some((_, id, size)) = part.get(p..).and_then(|r| runs(r).next()) {
            if let Some(first) = part.get_mut(p) {
                mark(first, id + leaf_base as u32, size);
            }
            p += (size as usize).max(1);
        }
        base += local.len() - 1;
        leaf_base += leaves;
    }
    Ok((base, leaf_base))
}

/// Where [`expand`] stands: nodes and leaves used so far, and the last pending node.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grown {
    pub(crate) nodes: usize,
    pub(crate) leaves: usize,
    /// The pending node built next (its job in its slot, linked to the next pending one), or
    /// `NONE`.
    pub(crate) top: u32,
}

impl Grown {
    /// A subtree whose root's job is in slot 0 of its nodes.
    pub(crate) const ROOT: Grown = Grown {
        nodes: 1,
        leaves: 0,
        top: 0,
    };
}

/// Builds up to `limit` pending nodes, last pushed first: each node's children are ranges of
/// `s` (the job's range is relative to `s`); inner children get the next slots of `nodes`
/// (with their jobs, pushed), leaves the next leaf numbers (their first entry marked for
/// [`fill`]).
pub(crate) fn expand(
    nodes: &mut [Node],
    s: &mut [Scratch],
    width: usize,
    per_leaf: usize,
    from: Grown,
    limit: usize,
) -> Result<Grown, BuildError> {
    let Grown {
        nodes: mut used_nodes,
        leaves: mut used_leaves,
        mut top,
    } = from;
    let mut built = 0;
    while top != NONE && built < limit {
        built += 1;
        let node = top as usize;
        let ([start, end, depth, next], b, cb) = unjob(&nodes[node]);
        top = next;
        if per_leaf == 1 && (end - start) as usize <= width {
            // Every primitive a child: where the splits below would end, without them.
            let mut out = Node::EMPTY;
            for (k, p) in s[start as usize..end as usize].iter().enumerate() {
                let (lo, hi) = unlanes(&p.b);
                for axis in 0..3 {
                    out.bounds[axis][k] = lo[axis];
                    out.bounds[3 + axis][k] = hi[axis];
                }
                out.child[k] = LEAF | p.index;
                used_leaves += 1;
            }
            nodes[node] = out;
            continue;
        }
        // Children as ranges; split the one of largest area until WIDTH or all are leaves.
        let mut kids = [Part { start, end, b, cb }; WIDTH];
        let mut nk = 1;
        while nk < width {
            // SAH levels split the largest area, middle-index levels the largest count (so
            // that each level divides the largest range by 8: the depth bound).
            // Equal areas (coincident primitives): the larger count.
            let mut pick: Option<usize> = None;
            let mut best = f32::NEG_INFINITY;
            let mut best_count = 0;
            for (k, kid) in kids[..nk].iter().enumerate() {
                let count = (kid.end - kid.start) as usize;
                if count <= per_leaf {
                    continue;
                }
                let a = if depth < SAH_DEPTH {
                    lanes_area(&kid.b)
                } else {
                    count as f32
                };
                if pick.is_none() || a > best || (a == best && count > best_count) {
                    pick = Some(k);
                    best = a;
                    best_count = count;
                }
            }
            let Some(k) = pick else { break };
            let Part {
                start: a,
                end: b,
                cb,
                ..
            } = kids[k];
            let (mid, (lb, lcb), (rb, rcb)) =
                split(&mut s[a as usize..b as usize], &cb, depth, per_leaf);
            let mid = a + mid as u32;
            kids.copy_within(k + 1..nk, k + 2);
            kids[k] = Part {
                start: a,
                end: mid,
                b: lb,
                cb: lcb,
            };
            kids[k + 1] = Part {
                start: mid,
                end: b,
                b: rb,
                cb: rcb,
            };
            nk += 1;
        }
        let mut out = Node::EMPTY;
        for (k, kid) in kids[..nk].iter().enumerate() {
            let (a, b) = (kid.start, kid.end);
            let (lo, hi) = unlanes(&kid.b);
            for axis in 0..3 {
                out.bounds[axis][k] = lo[axis];
                out.bounds[3 + axis][k] = hi[axis];
            }
            if (b - a) as usize <= per_leaf {
                out.child[k] = if per_leaf == 1 {
                    LEAF | s[a as usize].index // the primitive itself, no leaf to fill
                } else {
                    mark(&mut s[a as usize], used_leaves as u32, b - a);
                    LEAF | used_leaves as u32
                };
                used_leaves += 1;
            } else {
                if used_nodes >= nodes.len() {
                    return Err(BuildError::Nodes(TooSmall {
                        needed: used_nodes + 1,
                    }));
                }
                nodes[used_nodes] = job([a, b, depth + 1, top], &kid.b, &kid.cb);
                out.child[k] = used_nodes as u32;
                top = used_nodes as u32;
                used_nodes += 1;
            }
        }
        nodes[node] = out;
    }
    Ok(Grown {
        nodes: used_nodes,
        leaves: used_leaves,
        top,
    })
}

/// The second pass of a build: writes each leaf from the primitives [`topology`] left in
/// `s` (every leaf a run of entries, the first marked with its number and size).
pub(crate) fn fill<P: Primitives + ?Sized>(prims: &P, s: &[Scratch], leaves: &mut [P::Leaf]) {
    for (p, id, size) in runs(s) {
        let (Some(slot), Some(run)) = (leaves.get_mut(id as usize), s.get(p..p + size as usize))
        else {
            return;
        };
        *slot = P::Leaf::EMPTY;
        for (lane, q) in run.iter().enumerate() {
            prims.put(q.index, slot, lane);
        }
    }
}

/// Marks `first` as the first entry of leaf `id` of `size` primitives: a leaf's range is final
/// once made, so its first centroid (no longer read) can hold the two.
fn mark(first: &mut Scratch, id: u32, size: u32) {
    first.c[0] = f32::from_bits(id);
    first.c[1] = f32::from_bits(size);
}

/// The leaves [`mark`]ed in `s`, in order: (first entry, leaf number, size).
fn runs(s: &[Scratch]) -> impl Iterator<Item = (usize, u32, u32)> + '_ {
    let mut p = 0;
    core::iter::from_fn(move || {
        let first = s.get(p)?;
        let (id, size) = (first.c[0].to_bits(), first.c[1].to_bits());
        let at = p;
        p += (size as usize).max(1);
        Some((at, id, size))
    })
}

/// [`Bvh::refit`].
pub(crate) fn refit<'s, P: Primitives + ?Sized>(
    prims: &P,
    nodes: &'s mut [Node],
    leaves: &'s mut [P::Leaf],
) -> Result<Bvh<'s, P::Leaf>, BuildError> {
    if nodes.is_empty() {
        return Err(BuildError::Mismatch);
    }
    let n = prims.count();
    let held: usize = leaves
        .iter()
        .map(|l| l.indices().iter().filter(|&&i| i != EMPTY).count())
        .sum();
    if held != n {
        return Err(BuildError::Mismatch);
    }
    for leaf in leaves.iter_mut() {
        let idx = *leaf.indices();
        *leaf = P::Leaf::EMPTY;
        for (lane, &i) in idx.iter().enumerate() {
            if i == EMPTY {
                continue;
            }
            if i as usize >= n {
                return Err(BuildError::Mismatch);
            }
            prims.put(i, leaf, lane);
        }
    }
    refit_nodes(nodes, |l, b| {
        let leaf = leaves.get(l as usize).ok_or(BuildError::Mismatch)?;
        for lane in 0..LEAF_WIDTH {
            if leaf.indices()[lane] != EMPTY {
                let (lo, hi) = leaf.bounds(lane);
                grow(b, &lo, &hi);
            }
        }
        Ok(())
    })?;
    let nodes: &'s [Node] = nodes;
    let leaves: &'s [P::Leaf] = leaves;
    Ok(Bvh {
        nodes,
        leaves,
        reach: reach(&nodes[0]),
    })
}

/// [`refit`] for a tree whose leaves are its primitives (built with one primitive per leaf,
/// see [`topology`]): every box recomputed from `prims`, children before parents; returns the
/// root's reach. [`BuildError::Mismatch`] for an empty `nodes`, a primitive index past
/// `prims` or a child index out of range. (Its one caller, the owned scene, needs `alloc`.)
#[cfg(feature = "alloc")]
pub(crate) fn refit_direct<P: Primitives + ?Sized>(
    prims: &P,
    nodes: &mut [Node],
) -> Result<f32, BuildError> {
    let n = prims.count();
    refit_nodes(nodes, |i, b| {
        if i as usize >= n {
            return Err(BuildError::Mismatch);
        }
        let (lo, hi) = prims.bounds(i);
        grow(b, &lo, &hi);
        Ok(())
    })?;
    nodes.first().map(reach).ok_or(BuildError::Mismatch)
}

/// Recomputes every node's boxes, children before parents: a leaf child `LEAF | l` from
/// `leaf(l, box)`, which grows the box by the leaf's primitives.
fn refit_nodes(
    nodes: &mut [Node],
    mut leaf: impl FnMut(u32, &mut Box3) -> Result<(), BuildError>,
) -> Result<(), BuildError> {
    if nodes.is_empty() {
        return Err(BuildError::Mismatch);
    }
    for i in (0..nodes.len()).rev() {
        let mut out = nodes[i];
        for k in 0..WIDTH {
            let c = out.child[k];
            let mut b = EMPTY_BOX;
            if c == EMPTY {
            } else if c & LEAF != 0 {
                leaf(c & !LEAF, &mut b)?;
            } else {
                if c as usize <= i {
                    return Err(BuildError::Mismatch);
                }
                let child = nodes.get(c as usize).ok_or(BuildError::Mismatch)?;
                for j in 0..WIDTH {
                    if child.child[j] != EMPTY {
                        let lo = [child.bounds[0][j], child.bounds[1][j], child.bounds[2][j]];
                        let hi = [child.bounds[3][j], child.bounds[4][j], child.bounds[5][j]];
                        grow(&mut b, &lo, &hi);
                    }
                }
            }
            for axis in 0..3 {
                out.bounds[axis][k] = b.0[axis];
                out.bounds[3 + axis][k] = b.1[axis];
            }
        }
        nodes[i] = out;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The three-axis binning in lanes gives [`bin`]'s bins, on centroids inside, below and
    /// above the range, NaN products (`0 · inf`), infinite scales and signed zeros.
    #[test]
    fn lanes_bin_as_one_axis_does() {
        let xs = [
            0.0,
            -0.0,
            1e-30,
            0.49,
            0.5,
            0.999_999_9,
            1.0,
            2.0,
            -1.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1e30,
        ];
        let ks = [16.0, 1.0, 1e-3, 3.7, f32::INFINITY, 0.0];
        let mins = [0.0, -0.5, 0.25];
        for &x in &xs {
            for &k in &ks {
                for &m in &mins {
                    let c = [x, x * 0.5 + m, -x];
                    let (cmin, kk) = ([m, -m, 0.0], [k, k * 0.5, k]);
                    let want = [0, 1, 2].map(|a| bin(c[a], cmin[a], kk[a]));
                    assert_eq!(bins(&c, &cmin, &kk), want, "c {c:?} min {cmin:?} k {kk:?}");
                }
            }
        }
    }

    /// Boxes as primitives (empty boxes included).
    #[cfg(feature = "std")]
    struct Boxes(std::vec::Vec<Box3>);

    #[cfg(feature = "std")]
    impl Primitives for Boxes {
        type Leaf = crate::bvh::Inst4;
        fn count(&self) -> usize {
            self.0.len()
        }
        fn bounds(&self, i: u32) -> Box3 {
            self.0[i as usize]
        }
        fn put(&self, i: u32, leaf: &mut Self::Leaf, k: usize) {
            leaf.put(k, i, self.bounds(i));
        }
    }

    /// Every primitive exactly once as a child (`LEAF | i`) with its own box, every inner
    /// child's box the union of its children's; within `n` nodes.
    #[cfg(feature = "std")]
    fn check_direct(nodes: &[Node], prims: &Boxes) {
        let mut seen = std::vec![0u32; prims.0.len()];
        for (i, n) in nodes.iter().enumerate() {
            for k in 0..WIDTH {
                let c = n.child[k];
                let lo = [n.bounds[0][k], n.bounds[1][k], n.bounds[2][k]];
                let hi = [n.bounds[3][k], n.bounds[4][k], n.bounds[5][k]];
                if c == EMPTY {
                } else if c & LEAF != 0 {
                    seen[(c & !LEAF) as usize] += 1;
                    assert_eq!((lo, hi), prims.bounds(c & !LEAF));
                } else {
                    assert!(c as usize > i);
                    let mut b = EMPTY_BOX;
                    let child = &nodes[c as usize];
                    for j in (0..WIDTH).filter(|&j| child.child[j] != EMPTY) {
                        let l = [child.bounds[0][j], child.bounds[1][j], child.bounds[2][j]];
                        let h = [child.bounds[3][j], child.bounds[4][j], child.bounds[5][j]];
                        grow(&mut b, &l, &h);
                    }
                    assert_eq!((lo, hi), b);
                }
            }
        }
        assert!(seen.iter().all(|&k| k == 1), "{seen:?}");
        assert!(nodes.len() <= prims.0.len().max(1));
    }

    /// One primitive per leaf (an owned scene's top level): every primitive a child of its
    /// node by its own index, and `refit_direct` after the boxes move.
    #[cfg(feature = "std")]
    #[test]
    fn direct_trees_hold_every_primitive_once() {
        let mut x = 12345u32;
        let mut r = move || {
            x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (x >> 8) as f32 / (1u32 << 24) as f32
        };
        for n in [0usize, 1, 2, 7, 8, 9, 17, 100, 1000] {
            let mut boxes: std::vec::Vec<Box3> = (0..n)
                .map(|i| {
                    if i % 13 == 5 {
                        return EMPTY_BOX; // a free slot
                    }
                    let lo = [r() * 100.0, r() * 100.0, r() * 10.0];
                    let s = [r() * 5.0, r() * 5.0, r() * 5.0];
                    (lo, [lo[0] + s[0], lo[1] + s[1], lo[2] + s[2]])
                })
                .collect();
            let mut nodes = std::vec![Node::EMPTY; n.max(1)];
            let mut scratch = std::vec![Scratch::default(); n];
            let prims = Boxes(boxes.clone());
            let (used, leaves) =
                topology(&prims, &mut nodes, &mut scratch, WIDTH, 1, true).unwrap();
            assert_eq!(leaves, n);
            nodes.truncate(used.max(1));
            check_direct(&nodes, &prims);
            for b in boxes.iter_mut().step_by(3) {
                b.0[0] += 7.0;
                b.1[0] += 7.0;
            }
            let moved = Boxes(boxes);
            refit_direct(&moved, &mut nodes).unwrap();
            check_direct(&nodes, &moved);
            assert_eq!(
                refit_direct(&Boxes(std::vec::Vec::new()), &mut nodes).is_err(),
                n > 0
            );
        }
    }
}
