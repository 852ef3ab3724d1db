//! A bounding volume hierarchy over caller storage: 8-wide nodes, leaves of 4 primitives packed
//! for the "1 ray × N primitives" kernels, traversed by the same lanes, and **bit-identical to
//! brute force**.
//!
//! # Build
//!
//! [`Bvh::needed`] gives the storage for `n` primitives; [`Bvh::build`] writes the tree into the
//! caller's slices ([`Node`]s, leaves, [`Scratch`]) and returns a [`Bvh`] that borrows them:
//! no allocation, no recursion, `no_std`. Short storage is an error value ([`BuildError`]).
//!
//! * **Binned SAH** (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies",
//!   2007): primitive centroids in 16 bins per axis (all three axes in one pass), a sweep over
//!   the 15 planes per axis for the cheapest `A_L·N_L + A_R·N_R`, an in-place partition. The
//!   children's boxes are unions of bins and their centroid boxes are gathered by the
//!   partition, so a split reads its range twice.
//! * **Built wide directly**: a node starts with its whole range as one child and splits the
//!   child of largest surface area (more than 4 primitives) until it has 8 children (as
//!   Embree's wide builders do); a child of at most 4 primitives is one leaf.
//! * **Deterministic.** Only IEEE-exact operations (comparisons, `+ − ×` in a fixed order, no
//!   fused multiply-add) and fixed tie-breaking (lowest axis, lowest bin, lowest slot): the
//!   same tree, bit for bit, on every target.
//! * **Bounded depth.** From depth [`SAH_DEPTH`] on, ranges are split at their middle index
//!   (largest range first), so the depth never exceeds [`MAX_DEPTH`] (for up to
//!   [`MAX_PRIMITIVES`]), and the traversal's fixed-size stack ([`STACK`] entries, 2 KB) cannot
//!   overflow; [`Bvh::from_parts`] refuses deeper trees.
//! * **Bad input.** A primitive that no kernel can hit (NaN or infinite coordinates, zero area,
//!   non-positive radius) gets an empty box and is never visited; coincident primitives are
//!   split by index; nothing panics or loops.
//! * [`Bvh::refit`] recomputes every box after vertices move (same topology, same leaves,
//!   the same number of primitives).
//!
//! # Scenes
//!
//! [`Scene`] places objects (trees over a mesh or a sphere set) by affine transforms under a
//! top-level tree of [`Inst4`] leaves; a query returns the closest hit over the scene with
//! the instance id in [`Hit::set`](crate::Hit::set) (see [`scene`]).
//!
//! # Layout (plain data, `#[repr(C)]`)
//!
//! A tree is two slices: `nodes` ([`Node`], 224 bytes, root at index 0) and `leaves`
//! ([`Tri4`], 160 bytes, or [`Sphere4`], 80 bytes). Children are numbered `child[k]`:
//! [`EMPTY`] for an unused slot (its box is empty: `min = +inf`, `max = −inf`), `LEAF | i` for
//! leaf `i`, otherwise the index of an inner node, always greater than the parent's, in the
//! order the builder writes them. [`Bvh::from_parts`] reopens such slices after checking them
//! (a tree, boxes that contain their children, unused lanes never hit: [`PartsError`]
//! otherwise). For firmware, trees are baked into a compact format instead ([`bake`]: 4-wide
//! quantized nodes over indexed triangles, 21.1 bytes per triangle against this layout's
//! 65.7 on the bunny).
//!
//! # Traversal and exactness
//!
//! A [`Bvh`] is a set like any other ([`Query`](crate::Query)): `closest`, `any`, `all` for
//! one [`Ray`] (children in lanes: one `f32x8` slab test per node, nearest child
//! first; leaves with one `f32x4` kernel call: 1 ray × 4 primitives) or a
//! [`RayPacket`] of any width (1, 4, 8, 16 rays, inactive lanes masked;
//! N rays × 1 primitive in the leaves). A packet whose directions share their signs tests all
//! 8 children of a node at once, for the whole packet, with interval bounds of its lanes'
//! slab values (conservative because rounding is monotonic; a leaf child is then checked lane
//! by lane); other packets test one child box per lane operation. Triangles use
//! [`Watertight`](crate::triangle::Watertight), spheres [`Robust`](crate::sphere::Robust),
//! two-sided, unless the query names another kernel or culls:
//! `tree.using::<Moller>().culled(Cull::Back)`, exactly as on a slice. The traversal is one
//! loop per ray shape (`traverse.rs`), generic over the node [`Layout`], the leaf (kernels
//! over [`Tri4`]/[`Sphere4`], or [`Instance`]s) and the collector ([`crate::hit`]).
//!
//! ```
//! use raylane::bvh::{Bvh, Node, Packed, Scratch, Tri4, TriangleBvh};
//! use raylane::glam::Vec3;
//! use raylane::triangle::Triangle;
//! use raylane::{Query, Ray};
//!
//! let tris: Vec<Triangle> = (0..100)
//!     .map(|i| {
//!         let x = i as f32;
//!         Triangle::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 0.0, 0.0), Vec3::new(x, 1.0, 0.0))
//!     })
//!     .collect();
//! let need = TriangleBvh::needed(tris.len());
//! let mut nodes = vec![Node::EMPTY; need.nodes];
//! let mut leaves = vec![Tri4::EMPTY; need.leaves];
//! let mut scratch = vec![Scratch::default(); need.scratch];
//! let tree = Bvh::build(&tris[..], &mut nodes, &mut leaves, &mut scratch).unwrap();
//! let ray = Ray::new(Vec3::new(42.25, 0.25, 1.0), Vec3::new(0.0, 0.0, -1.0));
//! let hit = tree.closest(&ray).unwrap();
//! assert_eq!((hit.index, hit.t), (42, 1.0));
//! assert_eq!(Some(hit), tris[..].closest(&ray)); // the flat set's answer, bit for bit
//! ```
//!
//! The closest hit is the one brute force finds with the same kernel: the smallest rounded `t`,
//! ties to the lowest primitive index, with the same `t`, `u`, `v`, index bits (and so the same
//! point, normal and face), whatever order the tree is visited in. Two things make it so:
//!
//! 1. **One tie rule.** A candidate wins on `(t, set, index, loc)` (`loc`, the leaf and lane,
//!    decides only between lanes that share an index, as [`Bvh::from_parts`] allows), and
//!    kernels are asked with `t_max` relaxed after each hit, by the collector that brute force
//!    uses too ([`crate::hit`]), so a kernel's pre-division test never drops a would-be
//!    winner.
//! 2. **Conservative boxes** (in the spirit of Ize, "Robust BVH Ray Traversal", JCGT 2013).
//!    Each box is widened by `m = 2^-17·(R + |o|∞)`, with `R` the largest coordinate in the
//!    tree and `o` the ray's origin: the Watertight kernel's edge tests and `t` are exact up to
//!    a few `2^-24·|V − o|∞` (its sheared vertices and a convex combination of their depths),
//!    and the slab test's own roundings are of the same order (about `4·2^-24·(R + |o|∞)`:
//!    `o ± m`, `b − o`, `1/d` and the product each rounded once), so a reported hit always lies
//!    well inside the widened box and its rounded `t` inside the slab interval. Measured: over
//!    rays aimed at vertices and edge midpoints of spot, fandisk and the vendored bunny, and
//!    their primary, bounce and shadow rays, the farthest a Watertight hit point lies outside
//!    its triangle's box is `3.0·2^-24·(R + |o|∞)`, 1/40 of `m`. (A wider `m` is not free:
//!    rays leaving a surface, offset by less than `m`, enter the boxes around their origin;
//!    with `2^-14` fandisk's bounce and shadow rays visited 5.2 nodes and 1.6 leaves each,
//!    with `2^-17` 1.04 nodes and 0.01 leaves.) The widening
//!    costs nothing per node: it is folded into two origins per ray (`o ± m` per axis, by the
//!    sign of `d`). A zero direction component gives a `±2^100` inverse (never NaN), and rays
//!    whose `|d|∞` lies outside `2^-64…2^64` or whose `R + |o|∞` exceeds `2^100` visit every
//!    non-empty child (still exact, only slower). Where `f32x8::mul_add` is one fused
//!    instruction (x86-64 with FMA, AArch64), the one-ray test is `fma(b, 1/d, −(o ± m)/d)`
//!    with `(o ± m)·(1/d)` rounded once per ray: as many roundings, 6 fewer instructions per
//!    node (callgrind, x86-64-v3, the vendored bunny: 2–4 % fewer per ray). It needs
//!    `(o ± m)·(1/d)` finite, so on those targets (for packets too) the limits are `2^63` for
//!    `R + |o|∞`, `±2^64` for the inverses and `2^-45` for `|d|∞`: the product stays below
//!    `2^127·(1 + 2^-17)`, and the clamp stays at or above `2^19/|d|∞`, so a ray whose
//!    inverse it cuts moves less than `m/4` along that axis over any `t` a hit can have
//!    (`|t| ≤ (R + |o|∞)/|d|∞`), and its slab on that axis spans those `t` (the test
//!    `far_scenes_with_flat_directions` fails with the clamp at `2^40`). The argument is per
//!    primitive's box, so a packet with a frustum also tests the boxes of a leaf's primitives
//!    (`Leaf::boxes`, as the builder bounds them) before their kernels run: a pure prune as
//!    well.
//!
//! The interval is decided by the collector alone — a hit counts when its rounded `t` lies in
//! `(t_min, t_max)` — so the tree and brute force agree for every `t_max`, finite or not, and
//! `any`, `all` and `closest` agree with each other.

pub mod bake;
mod build;
mod leaf;
pub mod node;
#[cfg(feature = "alloc")]
pub mod owned_scene;
pub mod scene;
mod traverse;

pub use leaf::{Leaf, Packed, Primitives, Sphere4, Tri4};
pub use node::{Layout, Node, Node4};
#[cfg(feature = "alloc")]
pub use owned_scene::{Commit, InstanceId, Object, ObjectId, OwnedScene, SceneError, WithKernels};
pub use scene::{Inst4, Instance, Scene};

use wide::f32x4;

use crate::hit::{At, Collector, Hits, Record, Winners, alone};
use crate::kernel::{Cull, Kernel, LaneHit, admit, admits};
use crate::lane::{Lane, Mask};
use crate::ray::{Ray, RayPacket};
use crate::set::{Set, TooSmall, mine};

/// Children per node (the lanes of one slab test).
pub const WIDTH: usize = 8;
/// Primitives per leaf (the lanes of one "1 ray × N primitives" kernel call).
pub const LEAF_WIDTH: usize = 4;
/// Bins per axis of the binned SAH.
pub const BINS: usize = 16;
/// Depth from which ranges are split at their middle index instead of by SAH.
pub const SAH_DEPTH: u32 = 24;
/// The deepest a built tree gets: the root is depth 1; from [`SAH_DEPTH`] on, a node splits
/// its largest range 7 times at the middle index, so each level divides the largest range by
/// 8, and [`MAX_PRIMITIVES`] reach leaves of at most 4 within 10 more levels.
pub const MAX_DEPTH: u32 = SAH_DEPTH + 11;
/// Entries of the traversal stack: at most `WIDTH − 1` siblings wait per level, plus one.
pub const STACK: usize = (WIDTH - 1) * MAX_DEPTH as usize + 1;
/// The most primitives a tree holds: `2^30 − 1`.
pub const MAX_PRIMITIVES: usize = (1 << 30) - 1;
/// `child[k]` of an unused slot.
pub const EMPTY: u32 = u32::MAX;
/// The bit that marks `child[k]` as a leaf index.
pub const LEAF: u32 = 1 << 31;

/// The builder's working memory for one primitive (48 bytes; not needed after the build).
#[derive(Clone, Copy, Debug, Default)]
pub struct Scratch {
    /// The primitive's box: min x, y, z, 0, −max x, y, z, 0.
    pub(crate) b: [f32; 8],
    /// Its centroid (0 for a non-finite coordinate).
    pub(crate) c: [f32; 3],
    pub(crate) index: u32,
}

/// Storage sizes for a tree over `n` primitives (upper bounds; [`Bvh::nodes`] and
/// [`Bvh::leaves`] give what a build used, so a host can keep only that).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sizes {
    /// [`Node`]s.
    pub nodes: usize,
    /// Leaves ([`Tri4`], [`Sphere4`] or [`Inst4`]).
    pub leaves: usize,
    /// [`Scratch`] entries.
    pub scratch: usize,
}

/// Why a build failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildError {
    /// Fewer nodes than [`Bvh::needed`] gives.
    Nodes(TooSmall),
    /// Fewer leaves than the tree uses (the exact count: see [`Bvh::needed`]).
    Leaves(TooSmall),
    /// Less scratch than [`Bvh::needed`] gives.
    Scratch(TooSmall),
    /// More than [`MAX_PRIMITIVES`].
    TooMany,
    /// [`Bvh::refit`]: the leaves do not hold the primitives (an index out of range, or a
    /// different number of primitives than the build's).
    Mismatch,
}

impl core::fmt::Display for BuildError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            BuildError::Nodes(t) => write!(f, "BVH build needs {} nodes", t.needed),
            BuildError::Leaves(t) => write!(f, "BVH build needs {} leaves", t.needed),
            BuildError::Scratch(t) => write!(f, "BVH build needs {} scratch entries", t.needed),
            BuildError::TooMany => write!(f, "BVH build: more than 2^30 - 1 primitives"),
            BuildError::Mismatch => write!(f, "BVH refit: leaves do not match the primitives"),
        }
    }
}

/// Why [`Bvh::from_parts`] refused its slices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PartsError {
    /// No nodes.
    Empty,
    /// Node `.0` has a child that is not where a build puts it: an inner child not the next
    /// node in the build's order (out of range, before its parent, reached twice), or a leaf
    /// not the next leaf; or nodes or leaves are left over, reached from nowhere.
    Order(u32),
    /// The tree is deeper than [`MAX_DEPTH`].
    TooDeep,
    /// Node `.0` has a NaN box, or an unused slot whose box is not the empty one.
    Node(u32),
    /// Leaf `.0` has an unused lane ([`EMPTY`] index) whose primitive could be hit, or a NaN
    /// box.
    Leaf(u32),
    /// A box of node `.0` does not contain its child's boxes or primitives.
    Outside(u32),
}

impl core::fmt::Display for PartsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PartsError::Empty => write!(f, "BVH parts: no nodes"),
            PartsError::Order(i) => write!(f, "BVH parts: node {i}'s children out of order"),
            PartsError::TooDeep => write!(f, "BVH parts: deeper than {MAX_DEPTH}"),
            PartsError::Node(i) => {
                write!(f, "BVH parts: node {i} has a NaN or non-empty unused box")
            }
            PartsError::Leaf(i) => write!(f, "BVH parts: leaf {i} has a bad lane"),
            PartsError::Outside(i) => write!(f, "BVH parts: a box of node {i} is too small"),
        }
    }
}

/// A built hierarchy: nodes of layout `N` and leaves `P`, borrowed from the caller.
#[derive(Clone, Copy, Debug)]
pub struct Bvh<'s, P: Packed, N: Layout = Node> {
    pub(crate) nodes: &'s [N],
    pub(crate) leaves: &'s [P],
    /// The largest coordinate magnitude of the root's children (`R` in the margin).
    pub(crate) reach: f32,
}

/// A BVH over triangles ([`Watertight`](crate::triangle::Watertight) by default).
pub type TriangleBvh<'s> = Bvh<'s, Tri4>;
/// A BVH over spheres ([`Robust`](crate::sphere::Robust) by default).
pub type SphereBvh<'s> = Bvh<'s, Sphere4>;

impl<'s, P: Packed> Bvh<'s, P, Node> {
    /// The storage a tree over `n` primitives needs: `max(n/4, 1)` nodes, `n` leaves and `n`
    /// scratch entries (`TriangleBvh::needed(n)`, `SphereBvh::needed(n)`).
    ///
    /// These are bounds for any input. The leaves a build uses are far fewer (about `n/4`
    /// on real meshes, whose leaves hold 3.7–3.8 primitives): [`build`](Self::build) counts
    /// them before it writes one, so a caller may pass fewer and, when they are short, gets
    /// [`BuildError::Leaves`] with the exact count to build again with.
    /// `OwnedBvh` (feature `alloc`) allocates exactly that count.
    ///
    /// The nodes' bound: a node stops splitting before [`WIDTH`] children only when every child
    /// is a leaf, so a node with an inner child has 8 children. Of the `I = F + B` inner nodes,
    /// the `B` without inner children hold disjoint ranges of more than [`LEAF_WIDTH`]
    /// primitives (`B ≤ n/5`), and the `F` others have `8F − (I − 1)` leaf children of at least
    /// one primitive each: `n ≥ 7F + 4B + 1`, so `I ≤ (n − 1 + 3B)/7 ≤ (8n − 5)/35 < n/4`.
    #[must_use]
    pub const fn needed(n: usize) -> Sizes {
        sizes(n)
    }

    /// Builds a tree over `prims` into `nodes`, `leaves` (sizes from [`needed`](Self::needed))
    /// using `scratch` as working memory. See the [module docs](self) for the algorithm.
    ///
    /// # Errors
    ///
    /// [`BuildError`] when `nodes` or `scratch` is shorter than [`needed`](Self::needed) gives,
    /// `leaves` shorter than the tree uses ([`BuildError::Leaves`] then holds the exact count;
    /// `nodes` and `scratch` hold a first pass, to be discarded), or for more than
    /// [`MAX_PRIMITIVES`].
    pub fn build<Q: Primitives<Leaf = P> + ?Sized>(
        prims: &Q,
        nodes: &'s mut [Node],
        leaves: &'s mut [P],
        scratch: &mut [Scratch],
    ) -> Result<Self, BuildError> {
        build::build(prims, nodes, leaves, scratch)
    }

    /// Rewrites the leaves from `prims` (same indices, new coordinates) and recomputes every
    /// box, children before parents. `nodes` and `leaves` must be the slices a build over a set
    /// of the same size returned ([`Bvh::nodes`], [`Bvh::leaves`]). The topology stays the
    /// build's: after large moves a rebuild gives a cheaper tree, but the answers are exact
    /// either way.
    ///
    /// # Errors
    ///
    /// [`BuildError::Mismatch`] when `prims` has a different number of primitives than the
    /// leaves hold, a leaf holds an index past it, or a child index is out of range (nothing
    /// is then guaranteed about the slices' boxes).
    pub fn refit<Q: Primitives<Leaf = P> + ?Sized>(
        prims: &Q,
        nodes: &'s mut [Node],
        leaves: &'s mut [P],
    ) -> Result<Self, BuildError> {
        build::refit(prims, nodes, leaves)
    }
}

/// [`Bvh::needed`] for `n` primitives.
pub(crate) const fn sizes(n: usize) -> Sizes {
    Sizes {
        nodes: if n < 4 { 1 } else { n / 4 },
        leaves: n,
        scratch: n,
    }
}

impl<'s, P: Packed, N: Layout> Bvh<'s, P, N> {
    /// Reopens a tree from its two slices (a tree a build or refit wrote, e.g. kept from an
    /// earlier run), checked in one pass over the nodes with the traversal's stack: the nodes
    /// and leaves in the order a build writes them (so every node and leaf is reached exactly
    /// once from the root: a tree, not a DAG; every child index in range and after its
    /// parent), the depth within [`MAX_DEPTH`], no NaN box, unused slots canonically empty,
    /// every unused leaf lane ([`EMPTY`] index) never hit (an empty box), and every child's
    /// box containing its node's children's boxes or its leaf's primitives — so the answers
    /// are brute force's over the leaves' primitives. Anything else is an error value.
    ///
    /// # Errors
    ///
    /// [`PartsError`]: what is wrong, and where.
    pub fn from_parts(nodes: &'s [N], leaves: &'s [P]) -> Result<Self, PartsError> {
        let root = nodes.first().ok_or(PartsError::Empty)?;
        check_parts(nodes, leaves)?;
        Ok(Bvh {
            nodes,
            leaves,
            reach: reach(root),
        })
    }

    /// The nodes (root first).
    #[must_use]
    pub fn nodes(&self) -> &'s [N] {
        self.nodes
    }

    /// The leaves.
    #[must_use]
    pub fn leaves(&self) -> &'s [P] {
        self.leaves
    }

    /// The box of the root (the union of its children's boxes).
    #[must_use]
    pub fn root_box(&self) -> ([f32; 3], [f32; 3]) {
        root_box(self.nodes)
    }

    /// Depth, node and leaf counts and SAH cost of the tree (walks every node).
    #[must_use]
    pub fn stats(&self) -> Stats {
        let held = |l: u32| {
            self.leaves
                .get(l as usize)
                .map_or(0, |l| l.indices().iter().filter(|&&i| i != EMPTY).count())
        };
        let bytes = core::mem::size_of_val(self.nodes) + core::mem::size_of_val(self.leaves);
        stats(self.nodes, held, self.leaves.len(), bytes)
    }
}

/// The box of the root of `nodes` (the union of its children's boxes).
pub(crate) fn root_box<N: Layout>(nodes: &[N]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    if let Some(n) = nodes.first() {
        for k in 0..WIDTH {
            if n.child(k) == EMPTY {
                continue;
            }
            let (l, h) = n.bounds(k);
            for a in 0..3 {
                lo[a] = min(lo[a], l[a]);
                hi[a] = max(hi[a], h[a]);
            }
        }
    }
    (lo, hi)
}

/// [`Bvh::stats`] of the tree `nodes` whose leaf child `LEAF | l` holds `held(l)` primitives
/// (`leaves` leaves and `bytes` bytes in all).
pub(crate) fn stats<N: Layout>(
    nodes: &[N],
    held: impl Fn(u32) -> usize,
    leaves: usize,
    bytes: usize,
) -> Stats {
    let (lo, hi) = root_box(nodes);
    let root_area = area(lo, hi) as f64;
    let mut sah = 1.0f64; // the root's traversal
    let mut prims = 0usize;
    for n in nodes {
        for k in 0..WIDTH {
            let c = n.child(k);
            if c == EMPTY {
                continue;
            }
            let (lo, hi) = n.bounds(k);
            let rel = if root_area > 0.0 {
                area(lo, hi) as f64 / root_area
            } else {
                1.0
            };
            if c & LEAF != 0 {
                let count = held(c & !LEAF);
                prims += count;
                sah += rel * count as f64;
            } else {
                sah += rel;
            }
        }
    }
    Stats {
        nodes: nodes.len(),
        leaves,
        primitives: prims,
        depth: depth(nodes).unwrap_or(0),
        sah,
        bytes,
    }
}

/// [`Bvh::from_parts`]'s one pass: the nodes in the order the builder processes them (a stack:
/// the last inner child first), each node's inner children the next nodes and its leaves the
/// next leaves, in slot order.
fn check_parts<P: Packed, N: Layout>(nodes: &[N], leaves: &[P]) -> Result<(), PartsError> {
    let empty = |(lo, hi): ([f32; 3], [f32; 3])| (0..3).any(|a| lo[a] > hi[a]);
    let nan = |(lo, hi): ([f32; 3], [f32; 3])| lo.iter().chain(&hi).any(|x| x.is_nan());
    let inside = |(lo, hi): ([f32; 3], [f32; 3]), (blo, bhi): ([f32; 3], [f32; 3])| {
        (0..3).all(|a| blo[a] <= lo[a] && hi[a] <= bhi[a])
    };
    let mut stack = [(0u32, 1u32); STACK];
    let (mut sp, mut next_node, mut next_leaf) = (1usize, 1usize, 0usize);
    while sp > 0 {
        sp -= 1;
        let (i, d) = stack[sp];
        if d > N::MAX_DEPTH.min(MAX_DEPTH) {
            return Err(PartsError::TooDeep);
        }
        let n = nodes.get(i as usize).ok_or(PartsError::Order(i))?;
        for k in 0..WIDTH {
            let (c, b) = (n.child(k), n.bounds(k));
            if c == EMPTY {
                if b != ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]) {
                    return Err(PartsError::Node(i));
                }
                continue;
            }
            if nan(b) {
                return Err(PartsError::Node(i));
            }
            if c & LEAF != 0 {
                let l = (c & !LEAF) as usize;
                if l != next_leaf {
                    return Err(PartsError::Order(i));
                }
                next_leaf += 1;
                let leaf = leaves.get(l).ok_or(PartsError::Order(i))?;
                for (lane, &index) in leaf.indices().iter().enumerate() {
                    let lb = leaf.bounds(lane);
                    if nan(lb) || (index == EMPTY && !empty(lb)) {
                        return Err(PartsError::Leaf(l as u32));
                    }
                    if !empty(lb) && !inside(lb, b) {
                        return Err(PartsError::Outside(i));
                    }
                }
                continue;
            }
            if c as usize != next_node {
                return Err(PartsError::Order(i));
            }
            next_node += 1;
            let child = nodes.get(c as usize).ok_or(PartsError::Order(i))?;
            for j in 0..WIDTH {
                let cb = child.bounds(j);
                if child.child(j) != EMPTY && !nan(cb) && !empty(cb) && !inside(cb, b) {
                    return Err(PartsError::Outside(i));
                }
            }
            *stack.get_mut(sp).ok_or(PartsError::TooDeep)? = (c, d + 1);
            sp += 1;
        }
    }
    if next_node != nodes.len() || next_leaf != leaves.len() {
        return Err(PartsError::Order(0));
    }
    Ok(())
}

/// The depth of the tree under `nodes[0]` (the root alone is 1), or `None` when a node is
/// reached twice (more visits than nodes), the depth exceeds [`MAX_DEPTH`], or an inner
/// child does not follow its parent.
fn depth<N: Layout>(nodes: &[N]) -> Option<u32> {
    let mut stack = [(0u32, 1u32); STACK];
    let max_depth = N::MAX_DEPTH.min(MAX_DEPTH);
    let (mut sp, mut visits, mut deepest) = (1usize, 0usize, 0u32);
    while sp > 0 {
        sp -= 1;
        let (i, d) = stack[sp];
        visits += 1;
        if visits > nodes.len() || d > max_depth {
            return None;
        }
        deepest = deepest.max(d);
        let n = nodes.get(i as usize)?;
        for k in 0..WIDTH {
            let c = n.child(k);
            if c != EMPTY && c & LEAF == 0 {
                if c <= i {
                    return None;
                }
                *stack.get_mut(sp)? = (c, d + 1);
                sp += 1;
            }
        }
    }
    Some(deepest)
}

/// What [`Bvh::stats`] reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    /// Inner nodes.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Primitives in the leaves.
    pub primitives: usize,
    /// Inner-node levels (the root alone is 1).
    pub depth: u32,
    /// SAH cost relative to the root's area: `1 + Σ A(inner child)/A(root) + Σ A(leaf)/A(root)·n(leaf)`
    /// (traversal and intersection weighted 1).
    pub sah: f64,
    /// Bytes of nodes and leaves.
    pub bytes: usize,
}

impl<P: Leaf, N: Layout> Bvh<'_, P, N> {
    /// One ray from the node reference `start` (0: the root) into `c`: children in lanes,
    /// nearest first, a leaf's primitives in `f32x4` lanes (1 ray × 4 primitives). The one-ray
    /// query, and the packets' lanes that continue alone.
    #[inline(always)]
    fn trace_from<K: Kernel<P::Prim>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        start: u32,
        set: u32,
        c: &mut C,
    ) -> bool {
        let r4 = RayPacket::<f32x4>::splat(ray).shrink(Mask::splat(true), f32x4::splat(c.t_max()));
        // The kernel's per-ray set-up (Watertight: the shear, 3 divisions), made at the first
        // leaf: most rays that leave a surface reach none.
        let mut pre = None;
        traverse::one(
            self.nodes,
            self.reach,
            ray,
            start,
            c,
            #[inline(always)]
            |li, c| {
                let Some(leaf) = self.leaves.get(li as usize) else {
                    return false;
                };
                let r = if C::SHRINKS {
                    r4.shrink(Mask::splat(true), f32x4::splat(c.t_max()))
                } else {
                    r4
                };
                // Not `get_or_insert_with`: a call the compiler may leave out of line, which
                // then runs at the baseline inside a query entered at a wider level.
                let (pre, order) = match pre {
                    Some(made) => made,
                    None => {
                        let p = K::prepare(&r4);
                        let made = (p, K::order(&p));
                        pre = Some(made);
                        made
                    }
                };
                let pre = &pre;
                let four = leaf.four(order);
                if C::EACH {
                    // Every root of the four (a filter may reject an entry root).
                    return K::each_one(
                        &r,
                        pre,
                        &four,
                        cull,
                        #[inline(always)]
                        |h| offer_four(h, leaf, li, set, c),
                    );
                }
                let Some(h) = K::first_one(&r, pre, &four, cull) else {
                    return false;
                };
                offer_four(&h, leaf, li, set, c)
            },
        )
    }
}

/// The hits of one ray against the four primitives of leaf `li` (lane `j`: primitive `j`),
/// offered to `c` one by one; true when `c` asked to stop.
#[inline(always)]
fn offer_four<P: Packed, C: Collector<f32>>(
    h: &LaneHit<f32x4>,
    leaf: &P,
    li: u32,
    set: u32,
    c: &mut C,
) -> bool {
    let mut bits = h.mask.bits();
    while bits != 0 {
        let j = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let one = LaneHit {
            t: h.t.lane(j),
            u: h.u.lane(j),
            v: h.v.lane(j),
            w: h.w.lane(j),
            mask: true,
        };
        let at = At {
            set,
            index: leaf.indices().get(j).copied().unwrap_or(EMPTY),
            loc: li * LEAF_WIDTH as u32 + j as u32,
        };
        if c.offer(&one, at, |_| Hits::miss()) {
            return true;
        }
    }
    false
}

/// Lanes at or below which a packet's subtree continues lane by lane as single rays (`0`:
/// never): for plain `f32` packets and collectors that keep one hit per lane (closest, any);
/// a quarter of the lanes, twice that for packets whose directions' signs differ (see
/// `traverse::many`). Measured on the bunny and its subdivisions
/// (`benches/examples/scenes.rs`): see `docs/benchmarks.md`.
#[inline(always)]
pub(crate) const fn split<L: Lane, C: Collector<L>>() -> u32 {
    if L::PLAIN_F32 && !C::EVERY && L::LANES > 1 {
        (L::LANES / 4) as u32
    } else {
        0
    }
}

impl Stats {
    /// Children per inner node (of [`WIDTH`]): `(nodes − 1 + leaves) / nodes`.
    #[must_use]
    pub fn children_per_node(&self) -> f64 {
        (self.nodes + self.leaves).saturating_sub(1) as f64 / self.nodes.max(1) as f64
    }

    /// Primitives per leaf (of [`LEAF_WIDTH`]).
    #[must_use]
    pub fn primitives_per_leaf(&self) -> f64 {
        self.primitives as f64 / self.leaves.max(1) as f64
    }
}

/// A BVH answers as the flat set it was built over, with the same kernel and culling: the
/// same closest [`Hit`](crate::Hit) bit for bit (see the [module docs](self)), for one ray
/// (children in `f32x8` lanes, leaves in `f32x4` lanes: 1 ray × 4 primitives) and for packets
/// of every width (N rays × 1 primitive in the leaves); `any` agrees; `all` reports each hit
/// primitive's records as the flat set does, in traversal order.
impl<P: Leaf, N: Layout> Set for Bvh<'_, P, N> {
    type Prim = P::Prim;
    type Kernel = P::Kernel;

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_with<K: Kernel<P::Prim>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        let rays = admit(rays, K::UNIT_DIRECTIONS);
        let pre = K::prepare(&rays);
        traverse::many(
            self.nodes,
            self.reach,
            &rays,
            c,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |li, r, cone, c| {
                leaf_many::<P, K, L, C>(self.leaves, li, &rays, r, cone, &pre, cull, set, c)
            },
            split::<L, C>(),
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |start, i, c| {
                alone(
                    c,
                    i,
                    #[cfg_attr(target_arch = "x86_64", inline(always))]
                    |one| self.trace_from::<K, _>(cull, &rays.lane_ray(i), start, set, one),
                )
            },
        )
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray_with<K: Kernel<P::Prim>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        if C::EVERY {
            return self.trace_with::<K, f32, C>(cull, &RayPacket::splat(ray), set, c);
        }
        if !admits(ray, K::UNIT_DIRECTIONS) {
            return false;
        }
        self.trace_from::<K, C>(cull, ray, 0, set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records_with<L: Lane>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        w: &Winners<L>,
    ) -> Hits<L> {
        P::Prim::records(
            rays,
            &mine(w, set),
            cull,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |loc| {
                let loc = loc as usize;
                Some(self.leaves.get(loc / LEAF_WIDTH)?.prim(loc % LEAF_WIDTH))
            },
        )
    }
}

/// The primitives of leaf `li` against a packet: N rays × 1 primitive per lane of the leaf,
/// in order, each offered to `c`. With the packet's `cone`, only the primitives whose boxes
/// it may enter (one `f32x4` interval test for the four; a pure prune, see the module docs):
/// in a camera's 4 × 4 blocks a leaf's box is met far more often than each of its triangles'
/// (callgrind, x86-64-v3, the vendored bunny: 348 → 284 instructions per primary ray in
/// packets of 16, 377 → 335 in packets of 8, shadow packets of 8 510 → 467; time on the
/// benchmark's AVX-512 build within the noise, on a default SSE2 build primary packets of 16
/// 1.18–1.39× faster).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn leaf_many<P: Leaf, K: Kernel<P::Prim>, L: Lane, C: Collector<L>>(
    leaves: &[P],
    li: u32,
    rays: &RayPacket<L>,
    r: &RayPacket<L>,
    cone: Option<&traverse::Cone>,
    pre: &K::Rays<L>,
    cull: Cull,
    set: u32,
    c: &mut C,
) -> bool {
    let Some(leaf) = leaves.get(li as usize) else {
        return false;
    };
    let keep = cone.map_or(u32::MAX, |f| f.enters(leaf.boxes()));
    let mut r = *r;
    for (k, &index) in leaf.indices().iter().enumerate() {
        if index == EMPTY || keep & (1 << k) == 0 {
            continue;
        }
        r.t_max = c.t_max();
        let p = leaf.splat::<L>(k);
        let at = At {
            set,
            index,
            loc: li * LEAF_WIDTH as u32 + k as u32,
        };
        let record = |w: &Winners<L>| P::Prim::records(rays, w, cull, |_| Some(leaf.prim(k)));
        let stop = if C::EACH {
            K::each(&r, pre, &p, cull, |h| c.offer(h, at, record))
        } else {
            K::first(&r, pre, &p, cull).is_some_and(|h| h.mask.any() && c.offer(&h, at, record))
        };
        if stop {
            return true;
        }
    }
    false
}

/// `a < b ? a : b` (NaN in `b` ignored).
#[inline(always)]
pub(crate) fn min(a: f32, b: f32) -> f32 {
    if b < a { b } else { a }
}

/// `a > b ? a : b` (NaN in `b` ignored).
#[inline(always)]
pub(crate) fn max(a: f32, b: f32) -> f32 {
    if b > a { b } else { a }
}

/// Half the surface area of a box; 0 for an empty or NaN box (extents below 0 count as 0).
#[inline]
pub(crate) fn area(lo: [f32; 3], hi: [f32; 3]) -> f32 {
    let e = |a: usize| {
        let x = hi[a] - lo[a];
        if x > 0.0 { x } else { 0.0 }
    };
    let (x, y, z) = (e(0), e(1), e(2));
    x * y + y * z + z * x
}

/// The largest finite coordinate magnitude of a node's non-empty children (`+inf` when a box
/// has an infinite coordinate, which sends every ray to the visit-all path).
pub(crate) fn reach<N: Layout>(n: &N) -> f32 {
    let mut r = 0.0f32;
    for k in 0..WIDTH {
        if n.child(k) == EMPTY {
            continue;
        }
        let (lo, hi) = n.bounds(k);
        for x in lo.into_iter().chain(hi) {
            r = max(r, x.abs());
        }
    }
    r
}

/// A tree that owns its storage (feature `alloc`): one call builds it, as a game engine
/// expects. It answers exactly as the [`Bvh`] over caller storage that [`view`](Self::view)
/// gives (a [`Set`] like every other).
///
/// ```
/// use raylane::bvh::OwnedBvh;
/// use raylane::glam::Vec3;
/// use raylane::triangle::Triangle;
/// use raylane::{Query, Ray};
///
/// let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
/// let tree = OwnedBvh::new(&tris[..]).unwrap();
/// let hit = tree.closest(&Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z)).unwrap();
/// assert_eq!((hit.t, hit.index), (1.0, 0));
/// ```
#[cfg(feature = "alloc")]
#[derive(Clone, Debug)]
pub struct OwnedBvh<P: Packed> {
    nodes: alloc::vec::Vec<Node>,
    leaves: alloc::vec::Vec<P>,
    reach: f32,
}

#[cfg(feature = "alloc")]
impl<P: Packed> OwnedBvh<P> {
    /// Builds the tree over `prims` (a slice of triangles or spheres, a
    /// [`Mesh`](crate::mesh::Mesh)), keeping only the storage the build used. With feature
    /// `std` it builds on every core (from 65,536 primitives): the same tree as one core's,
    /// bit for bit.
    ///
    /// # Errors
    ///
    /// [`BuildError::TooMany`] for more than [`MAX_PRIMITIVES`].
    pub fn new<Q: Primitives<Leaf = P> + ?Sized>(prims: &Q) -> Result<Self, BuildError> {
        use alloc::vec;
        let need = sizes(prims.count());
        let mut nodes = vec![Node::EMPTY; need.nodes];
        let mut scratch = vec![Scratch::default(); need.scratch];
        // The leaves are allocated once the first pass has counted them (about n/4).
        let (n, l) = build::topology(prims, &mut nodes, &mut scratch, WIDTH, LEAF_WIDTH, true)?;
        let mut leaves = vec![P::EMPTY; l];
        build::fill(prims, &scratch[..prims.count()], &mut leaves);
        drop(scratch);
        nodes.truncate(n);
        nodes.shrink_to_fit();
        let reach = reach(&nodes[0]);
        Ok(OwnedBvh {
            nodes,
            leaves,
            reach,
        })
    }

    /// The tree as a [`Bvh`] over this storage.
    #[must_use]
    pub fn view(&self) -> Bvh<'_, P> {
        Bvh {
            nodes: &self.nodes,
            leaves: &self.leaves,
            reach: self.reach,
        }
    }
}

#[cfg(feature = "alloc")]
impl<P: Leaf> Set for OwnedBvh<P> {
    type Prim = P::Prim;
    type Kernel = P::Kernel;

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_with<K: Kernel<P::Prim>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        self.view().trace_with::<K, L, C>(cull, rays, set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray_with<K: Kernel<P::Prim>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        self.view().trace_ray_with::<K, C>(cull, ray, set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records_with<L: Lane>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        w: &Winners<L>,
    ) -> Hits<L> {
        self.view().records_with(cull, rays, set, w)
    }
}
