//! The binned-SAH builder of 8-wide nodes over caller storage, and the refit.

use super::{
    BINS, BuildError, Bvh, EMPTY, LEAF, LEAF_WIDTH, MAX_PRIMITIVES, Node, Packed, Primitives,
    SAH_DEPTH, Scratch, WIDTH, area, max, min, needed, reach,
};
use crate::triangle::Cull;

type Box3 = ([f32; 3], [f32; 3]);

const EMPTY_BOX: Box3 = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);

#[inline(always)]
fn grow(b: &mut Box3, lo: &[f32; 3], hi: &[f32; 3]) {
    for a in 0..3 {
        b.0[a] = min(b.0[a], lo[a]);
        b.1[a] = max(b.1[a], hi[a]);
    }
}

fn range_box(s: &[Scratch]) -> Box3 {
    let mut b = EMPTY_BOX;
    for p in s {
        grow(&mut b, &p.lo, &p.hi);
    }
    b
}

/// Bin of centroid coordinate `c`: `⌊(c − cmin)·k⌋` clamped to `0…BINS−1` (`as` saturates,
/// NaN gives 0: the same bin on every target).
#[inline(always)]
fn bin(c: f32, cmin: f32, k: f32) -> usize {
    let b = ((c - cmin) * k) as usize;
    if b < BINS { b } else { BINS - 1 }
}

/// The binned SAH split of `s` (Wald 2007): `Some(mid)` with both sides non-empty, after
/// partitioning `s` in place, or `None` when no plane separates the centroids (or every
/// cost is NaN).
fn sah_split(s: &mut [Scratch]) -> Option<usize> {
    let mut cb = EMPTY_BOX;
    for p in s.iter() {
        grow(&mut cb, &p.c, &p.c);
    }
    let (cmin, cmax) = cb;
    // (cost, axis, last bin of the left side, scale)
    let mut best: Option<(f32, usize, usize, f32)> = None;
    for axis in 0..3 {
        let ext = cmax[axis] - cmin[axis];
        // Also skips NaN extents.
        if ext.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            continue;
        }
        let k = BINS as f32 / ext;
        let mut count = [0u32; BINS];
        let mut boxes = [EMPTY_BOX; BINS];
        for p in s.iter() {
            let b = bin(p.c[axis], cmin[axis], k);
            count[b] += 1;
            grow(&mut boxes[b], &p.lo, &p.hi);
        }
        // Sweep: right-side areas and counts from the top, then left sides upward.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0u32; BINS];
        let mut acc = EMPTY_BOX;
        let mut n = 0;
        for i in (1..BINS).rev() {
            grow(&mut acc, &boxes[i].0, &boxes[i].1);
            n += count[i];
            right_area[i] = area(acc.0, acc.1);
            right_count[i] = n;
        }
        let mut acc = EMPTY_BOX;
        let mut n = 0;
        for i in 0..BINS - 1 {
            grow(&mut acc, &boxes[i].0, &boxes[i].1);
            n += count[i];
            let nr = right_count[i + 1];
            if n == 0 || nr == 0 {
                continue;
            }
            let cost = area(acc.0, acc.1) * n as f32 + right_area[i + 1] * nr as f32;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i, k));
            }
        }
    }
    let (cost, axis, last, k) = best?;
    if cost.is_nan() {
        return None;
    }
    // Partition in place: bins ≤ last to the left.
    let (mut i, mut j) = (0, s.len());
    while i < j {
        if bin(s[i].c[axis], cmin[axis], k) <= last {
            i += 1;
        } else {
            j -= 1;
            s.swap(i, j);
        }
    }
    Some(i)
}

/// Splits `s` (more than [`LEAF_WIDTH`] primitives) into two non-empty parts; returns the size
/// of the first. Binned SAH above [`SAH_DEPTH`], the middle index (rounded up to a multiple of
/// [`LEAF_WIDTH`]) below it or when SAH finds no plane.
fn split(s: &mut [Scratch], depth: u32) -> usize {
    if depth < SAH_DEPTH
        && let Some(mid) = sah_split(s)
    {
        return mid;
    }
    // The middle, rounded up to whole leaves where that leaves both sides non-empty.
    let half = s.len() / 2;
    let whole = half.div_ceil(LEAF_WIDTH) * LEAF_WIDTH;
    if whole < s.len() { whole } else { half }
}

/// Builds a tree over `prims` into `nodes`, `leaves` (sizes from [`needed`]) using `scratch`
/// as working memory. See the [module docs](super) for the algorithm and layout.
///
/// # Errors
///
/// [`BuildError`] when a slice is shorter than [`needed`] gives, or for more than
/// [`MAX_PRIMITIVES`]. Nothing is written to `leaves` beyond the first error.
pub fn build<'s, P: Primitives + ?Sized>(
    prims: &P,
    nodes: &'s mut [Node],
    leaves: &'s mut [P::Leaf],
    scratch: &mut [Scratch],
) -> Result<Bvh<'s, P::Leaf>, BuildError> {
    let n = prims.count();
    if n > MAX_PRIMITIVES {
        return Err(BuildError::TooMany);
    }
    let need = needed(n);
    if nodes.len() < need.nodes {
        return Err(BuildError::Nodes(need.nodes));
    }
    if leaves.len() < need.leaves {
        return Err(BuildError::Leaves(need.leaves));
    }
    if scratch.len() < need.scratch {
        return Err(BuildError::Scratch(need.scratch));
    }
    let s = &mut scratch[..n];
    for (i, p) in s.iter_mut().enumerate() {
        let (lo, hi) = prims.bounds(i as u32);
        let mut c = [0.0f32; 3];
        for a in 0..3 {
            let x = lo[a] * 0.5 + hi[a] * 0.5;
            c[a] = if x.is_finite() { x } else { 0.0 };
        }
        *p = Scratch {
            lo,
            hi,
            c,
            index: i as u32,
            job: [0; 4],
        };
    }
    nodes[0] = Node::EMPTY;
    let (mut used_nodes, mut used_leaves) = (1usize, 0usize);
    // Pending nodes: [node, start, end, depth] in `s[0..jobs].job` (disjoint ranges of more
    // than LEAF_WIDTH primitives each, so fewer than n of them).
    let mut jobs = 0usize;
    if n > 0 {
        s[0].job = [0, 0, n as u32, 1];
        jobs = 1;
    }
    while jobs > 0 {
        jobs -= 1;
        let [node, start, end, depth] = s[jobs].job;
        // Children as ranges; split the one of largest area until WIDTH or all are leaves.
        let mut kids = [(0u32, 0u32); WIDTH];
        let mut boxes = [EMPTY_BOX; WIDTH];
        kids[0] = (start, end);
        boxes[0] = range_box(&s[start as usize..end as usize]);
        let mut nk = 1;
        while nk < WIDTH {
            // SAH levels split the largest area, middle-index levels the largest count (so
            // that each level divides the largest range by 8: the depth bound).
            // Equal areas (coincident primitives): the larger count.
            let mut pick: Option<usize> = None;
            let mut best = f32::NEG_INFINITY;
            let mut best_count = 0;
            for k in 0..nk {
                let count = (kids[k].1 - kids[k].0) as usize;
                if count <= LEAF_WIDTH {
                    continue;
                }
                let a = if depth < SAH_DEPTH {
                    area(boxes[k].0, boxes[k].1)
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
            let (a, b) = kids[k];
            let mid = a + split(&mut s[a as usize..b as usize], depth) as u32;
            for j in (k + 1..nk).rev() {
                kids[j + 1] = kids[j];
                boxes[j + 1] = boxes[j];
            }
            kids[k] = (a, mid);
            kids[k + 1] = (mid, b);
            boxes[k] = range_box(&s[a as usize..mid as usize]);
            boxes[k + 1] = range_box(&s[mid as usize..b as usize]);
            nk += 1;
        }
        let mut out = Node::EMPTY;
        for k in 0..nk {
            let (a, b) = kids[k];
            for axis in 0..3 {
                out.bounds[axis][k] = boxes[k].0[axis];
                out.bounds[3 + axis][k] = boxes[k].1[axis];
            }
            if (b - a) as usize <= LEAF_WIDTH {
                let slot = leaves
                    .get_mut(used_leaves)
                    .ok_or(BuildError::Leaves(used_leaves + 1))?;
                *slot = P::Leaf::EMPTY;
                for (lane, p) in s[a as usize..b as usize].iter().enumerate() {
                    prims.put(p.index, slot, lane);
                }
                out.child[k] = LEAF | used_leaves as u32;
                used_leaves += 1;
            } else {
                if used_nodes >= nodes.len() {
                    return Err(BuildError::Nodes(used_nodes + 1));
                }
                nodes[used_nodes] = Node::EMPTY;
                out.child[k] = used_nodes as u32;
                s[jobs].job = [used_nodes as u32, a, b, depth + 1];
                jobs += 1;
                used_nodes += 1;
            }
        }
        nodes[node as usize] = out;
    }
    let nodes: &'s [Node] = &nodes[..used_nodes];
    let leaves: &'s [P::Leaf] = &leaves[..used_leaves];
    Ok(Bvh {
        nodes,
        leaves,
        reach: reach(&nodes[0]),
        cull: Cull::None,
    })
}

/// Rewrites the leaves from `prims` (same indices, new coordinates) and recomputes every box,
/// children before parents (inner children always follow their parent). `nodes` and `leaves`
/// must be exactly the slices a [`build`] over a set of the same size returned
/// ([`Bvh::nodes`], [`Bvh::leaves`]). The topology stays the build's: after large moves a
/// rebuild gives a cheaper tree, but the answers are exact either way.
///
/// # Errors
///
/// [`BuildError::Mismatch`] when a leaf holds an index past `prims.count()` or a child index is
/// out of range (nothing is then guaranteed about the slices' boxes).
pub fn refit<'s, P: Primitives + ?Sized>(
    prims: &P,
    nodes: &'s mut [Node],
    leaves: &'s mut [P::Leaf],
) -> Result<Bvh<'s, P::Leaf>, BuildError> {
    if nodes.is_empty() {
        return Err(BuildError::Mismatch);
    }
    let n = prims.count();
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
    for i in (0..nodes.len()).rev() {
        let mut out = nodes[i];
        for k in 0..WIDTH {
            let c = out.child[k];
            let mut b = EMPTY_BOX;
            if c == EMPTY {
            } else if c & LEAF != 0 {
                let leaf = leaves
                    .get((c & !LEAF) as usize)
                    .ok_or(BuildError::Mismatch)?;
                for lane in 0..LEAF_WIDTH {
                    if leaf.indices()[lane] != EMPTY {
                        let (lo, hi) = leaf.bounds(lane);
                        grow(&mut b, &lo, &hi);
                    }
                }
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
    let nodes: &'s [Node] = nodes;
    let leaves: &'s [P::Leaf] = leaves;
    Ok(Bvh {
        nodes,
        leaves,
        reach: reach(&nodes[0]),
        cull: Cull::None,
    })
}
