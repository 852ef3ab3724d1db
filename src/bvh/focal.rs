//! Focal mode: a tree traversed by rays from one eye, with per-eye values cached where they pay.
//!
//! For rays from one point `E` (primary rays, picking), every slab test subtracts the same
//! origin from the same box planes: `t = (b − E)·(1/d)`. A [`FocalBvh`] computes the planes
//! minus the eye once per eye — for every node, `(b_min − E) − m` and `(b_max − E) + m`, the
//! box already widened by the margin `m` the world traversal folds into its origins — so a
//! child box costs **6 multiplications** per ray instead of 6 subtractions and 6
//! multiplications (plus, both ways, 3 selects by the direction's signs per bound in packets,
//! 6 max/min and a compare). Triangle leaves keep their vertices minus the eye (`A − E`,
//! `B − E`, `C − E`: the [`Watertight`] kernel's first step, the same rounded bits), built
//! **lazily**, the first time a ray of this eye reaches the leaf: 9 subtractions fewer per
//! triangle test, and no work for leaves no ray reaches. Sphere leaves are tested as in the
//! world traversal: the [`Robust`] kernel's `f64` fallback needs the centre itself, so `C − E`
//! alone would not give the same bits.
//!
//! **What it buys, measured.** Executed instructions per primary ray (callgrind, x86-64-v3,
//! the vendored bunny, 640×480 from `examples/bvh_speed.rs`'s eye, the focus and the lazy
//! leaf fill counted, set-up subtracted):
//!
//! | traversal | 1 ray | packets of 8 | packets of 16 |
//! | --- | ---: | ---: | ---: |
//! | world ([`Bvh`]) | 1,047 | 404 | 409 |
//! | focal, planes minus the eye ([`FocalNode`], the default) | 1,060 | 401 | 419 |
//! | focal, the lecture's focal sphere test ([`SphereNode`]) | 1,720 | 875 | 836 |
//!
//! The lecture's focal sphere test (a sphere around each child's box, `C − E` and
//! `|C − E|² − r²` cached: 4 mul and 2 add per child for unit directions, 1 more mul
//! otherwise, plus 2 mul and 2 add for the entry and exit distances the nearest-first order
//! and the pruning need) is the cheaper test per child but far looser than the box, and
//! packets cannot test a node's children together with it: 1.6–2.2× the instructions. The
//! relative slab test is kept. It saves little over the world
//! traversal (within ±3 %, wall-clock within this machine's noise): the subtractions it
//! removes are few beside the stack, the child ordering and the leaf kernels' other
//! operations, and copying a leaf's cached vertices costs about what subtracting the eye
//! did. Measured, so stated: on this host a plain [`Bvh`] is as fast; other targets were
//! not measured.
//!
//! **Exactly the world traversal's answers.** The leaf tests compute the same bits as the
//! world traversal's (the relative vertices are the kernel's own first step), and the
//! cached planes are conservative as the world's are: `fl(fl(b − E) ∓ m)` differs from the
//! widened plane by two roundings of at most `2^-24·(R + |E|∞)`, far inside the margin
//! `m = 2^-17·(R + |E|∞)` (see the [module docs](super)). So every query equals brute force
//! with the same kernel, bit for bit.
//!
//! **Rays from elsewhere.** A ray (or a packet with a valid lane) whose origin is not the
//! eye, bit for bit, is traversed in the world mode: the answer is the same, only without the
//! cache.
//!
//! **Threads.** The leaf cache is filled through shared references ([`Cell`]): a `FocalBvh`
//! is not `Sync`; give each thread its own cache storage (each fills only what its rays
//! reach).
//!
//! [`Watertight`]: crate::triangle::Watertight
//! [`Robust`]: crate::sphere::Robust

use core::cell::Cell;

use glam::Vec3;
use wide::{f32x4, f32x8};

use super::query::{closest_packet, closest_ray};
use super::traverse::{Frustum, LeafTest, MARGIN, PacketSlab, Slab, View, World, lmax, lmin};
use super::{BuildError, Bvh, EMPTY, Leaf, Node, WIDTH};
use crate::hit::LaneHit;
use crate::lane::{Lane, Mask, Scalar};
use crate::query::{Hit, Hits, Query};
use crate::ray::{Ray, RayPacket};
use crate::triangle::Cull;
use crate::vec3::V3;

/// The per-eye planes of one node's children: rows as [`Node::bounds`] (minimum x, y, z,
/// maximum x, y, z; `[axis][child]`), minus the eye and widened by the margin. 192 bytes.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FocalNode {
    /// `(b_min − E) − m` (rows 0–2) and `(b_max − E) + m` (rows 3–5).
    pub rows: [[f32; WIDTH]; 6],
}

impl FocalNode {
    /// A node not yet computed.
    pub const EMPTY: Self = FocalNode {
        rows: [[0.0; WIDTH]; 6],
    };
}

impl Default for FocalNode {
    fn default() -> Self {
        FocalNode::EMPTY
    }
}

/// What a per-eye cache keeps of a node: [`FocalNode`] (the children's planes minus the eye,
/// the slab test without subtractions; the default) or [`SphereNode`] (the lecture's focal
/// sphere test, kept for the measurement).
pub trait NodeCache: Copy + core::fmt::Debug {
    /// An entry not yet computed.
    const EMPTY: Self;
    /// The entry of `n` for the eye `e` and the margin `m`.
    fn make(n: &Node, e: [f32; 3], m: f32) -> Self;
    /// The cached rows, by kind.
    #[doc(hidden)]
    fn rows(&self) -> NodeRows<'_>;
}

/// The rows of a [`NodeCache`] entry, by kind.
#[doc(hidden)]
#[derive(Clone, Copy, Debug)]
pub enum NodeRows<'a> {
    /// [`FocalNode::rows`].
    Boxes(&'a [[f32; WIDTH]; 6]),
    /// [`SphereNode::rows`].
    Spheres(&'a [[f32; WIDTH]; 5]),
}

impl NodeCache for FocalNode {
    const EMPTY: Self = FocalNode::EMPTY;
    fn make(n: &Node, e: [f32; 3], m: f32) -> Self {
        let mut f = FocalNode::EMPTY;
        for (a, &ea) in e.iter().enumerate() {
            f.rows[a] = n.bounds[a].map(|b| (b - ea) - m);
            f.rows[3 + a] = n.bounds[3 + a].map(|b| (b - ea) + m);
        }
        f
    }
    #[inline(always)]
    fn rows(&self) -> NodeRows<'_> {
        NodeRows::Boxes(&self.rows)
    }
}

/// The lecture's focal sphere test per child (measured against [`FocalNode`], not the
/// default): the sphere around the child's box, centre minus the eye `c`, radius `r` and
/// `k = |c|² − r²` cached; per ray `|d|` and `1/|d|²`; a child is entered when
/// `!((d·c)² < k·|d|²)` (4 mul, 2 add and a compare for unit directions, one more mul
/// otherwise), between `(d·c ∓ r·|d|)/|d|²` (2 mul, 2 add). Conservative: `r` is the
/// half-diagonal plus the margin, enlarged by `2^-10·|c|` to cover the roundings of the
/// squares (a non-finite value visits the child).
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereNode {
    /// `c` (x, y, z), `r`, `k` per child; empty slots have `k = +inf`.
    pub rows: [[f32; WIDTH]; 5],
}

impl NodeCache for SphereNode {
    const EMPTY: Self = SphereNode {
        rows: [[0.0; WIDTH]; 5],
    };
    fn make(n: &Node, e: [f32; 3], m: f32) -> Self {
        let mut s = <Self as NodeCache>::EMPTY;
        for k in 0..WIDTH {
            let lo = [0, 1, 2].map(|a| f64::from(n.bounds[a][k]));
            let hi = [3, 4, 5].map(|a| f64::from(n.bounds[a][k]));
            let c = [0, 1, 2].map(|a| (lo[a] + hi[a]) * 0.5 - f64::from(e[a]));
            let h2: f64 = (0..3)
                .map(|a| (hi[a] - lo[a]) * (hi[a] - lo[a]) * 0.25)
                .sum();
            let cc: f64 = c.iter().map(|x| x * x).sum();
            let r =
                (libm::sqrt(h2) + f64::from(m)) * (1.0 + 1.0 / 65536.0) + libm::sqrt(cc) / 1024.0;
            let kk = cc - r * r;
            let empty = n.child[k] == EMPTY || lo[0].partial_cmp(&hi[0]).is_none_or(|o| o.is_gt());
            for (row, &ca) in s.rows.iter_mut().zip(&c) {
                row[k] = if empty { 0.0 } else { ca as f32 };
            }
            s.rows[3][k] = if empty { 0.0 } else { r as f32 };
            s.rows[4][k] = if empty { f32::INFINITY } else { kk as f32 };
        }
        s
    }
    #[inline(always)]
    fn rows(&self) -> NodeRows<'_> {
        NodeRows::Spheres(&self.rows)
    }
}

/// One ray against a [`SphereNode`]'s children (`x`: `|d|`, `1/|d|²`).
#[inline(always)]
fn spheres_one(
    r: &[[f32; WIDTH]; 5],
    x: (f32, f32),
    d: [f32; 3],
    t_min: f32,
    t_max: f32,
) -> (u32, f32x8) {
    let b = f32x8::new(r[0]) * d[0] + f32x8::new(r[1]) * d[1] + f32x8::new(r[2]) * d[2];
    let dd = 1.0 / x.1;
    let hit = !(b * b).simd_lt(f32x8::new(r[4]) * dd);
    let rd = f32x8::new(r[3]) * x.0;
    let tn = f32x8::splat(t_min).fast_max((b - rd) * x.1);
    let tf = f32x8::splat(t_max).fast_min((b + rd) * x.1);
    ((hit & tn.simd_le(tf)).to_bitmask(), tn)
}

/// Packet lanes against child `k` of a [`SphereNode`] (`x`: `|d|`, `1/|d|²` per lane).
#[inline(always)]
fn spheres_many<L: Lane>(
    r: &[[f32; WIDTH]; 5],
    k: usize,
    x: (L, L),
    d: V3<L>,
    t_min: L,
    t_max: L,
) -> (L::Mask, L) {
    let p = |i: usize| L::from_f32(r[i][k]);
    let b = d.x * p(0) + d.y * p(1) + d.z * p(2);
    let dd = L::from_f32(1.0) / x.1;
    let hit = !(b * b).lt(p(4) * dd);
    let rd = p(3) * x.0;
    let tn = lmax(t_min, (b - rd) * x.1);
    let tf = lmin(t_max, (b + rd) * x.1);
    (hit & tn.le(tf), tn)
}

/// The per-eye cache entry of one leaf: filled the first time a ray from the eye reaches it.
pub struct FocalLeaf<P: Leaf> {
    rel: P::Rel,
    ready: bool,
}

impl<P: Leaf> FocalLeaf<P> {
    /// An entry not yet filled.
    pub const EMPTY: Self = FocalLeaf {
        rel: P::REL_EMPTY,
        ready: false,
    };
}

impl<P: Leaf> Clone for FocalLeaf<P> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<P: Leaf> Copy for FocalLeaf<P> {}

impl<P: Leaf> Default for FocalLeaf<P> {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl<P: Leaf> core::fmt::Debug for FocalLeaf<P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FocalLeaf")
            .field("rel", &self.rel)
            .field("ready", &self.ready)
            .finish()
    }
}

/// A tree with a per-eye cache: answers every [`Query`] as the tree itself does, bit for
/// bit, faster for rays from the eye (see [`focal`](self)). Made by [`Bvh::focus`].
pub struct FocalBvh<'s, 'c, P: Leaf, N: NodeCache = FocalNode> {
    bvh: Bvh<'s, P>,
    eye: Vec3,
    /// The eye is finite (otherwise every query runs in the world mode).
    on: bool,
    nodes: &'c [N],
    leaves: &'c [Cell<FocalLeaf<P>>],
}

impl<P: Leaf, N: NodeCache> core::fmt::Debug for FocalBvh<'_, '_, P, N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FocalBvh")
            .field("eye", &self.eye)
            .field("nodes", &self.nodes.len())
            .field("leaves", &self.leaves.len())
            .finish()
    }
}

/// The per-eye storage a [`FocalBvh`] of `bvh` needs: `(nodes, leaves)` — one [`FocalNode`]
/// per node, one [`FocalLeaf`] per leaf.
#[must_use]
pub fn focal_needed<P: Leaf>(bvh: &Bvh<'_, P>) -> (usize, usize) {
    (bvh.nodes.len(), bvh.leaves.len())
}

impl<'s, P: Leaf> Bvh<'s, P> {
    /// The tree with a per-eye cache for rays from `eye` in the caller's storage (sizes from
    /// [`focal_needed`]): every node's planes are computed now (48 subtractions and 48
    /// additions of the margin per node), the leaves' entries are reset and filled lazily.
    /// Short storage is an error ([`BuildError::Nodes`], [`BuildError::Leaves`] with the sizes
    /// needed; nothing is written). A non-finite eye gives a tree that runs every query in
    /// the world mode.
    pub fn focus<'c>(
        &self,
        eye: Vec3,
        nodes: &'c mut [FocalNode],
        leaves: &'c mut [FocalLeaf<P>],
    ) -> Result<FocalBvh<'s, 'c, P>, BuildError> {
        self.focus_with(eye, nodes, leaves)
    }

    /// [`focus`](Self::focus) with another node cache ([`SphereNode`]: the lecture's focal
    /// sphere test, for measurements).
    pub fn focus_with<'c, N: NodeCache>(
        &self,
        eye: Vec3,
        nodes: &'c mut [N],
        leaves: &'c mut [FocalLeaf<P>],
    ) -> Result<FocalBvh<'s, 'c, P, N>, BuildError> {
        let (nn, nl) = focal_needed(self);
        if nodes.len() < nn {
            return Err(BuildError::Nodes(nn));
        }
        let (Some(nodes), Some(leaves)) = (nodes.get_mut(..nn), leaves.get_mut(..nl)) else {
            return Err(BuildError::Leaves(nl));
        };
        let on = eye.is_finite();
        if on {
            // The margin of the world traversal's `Slab::new` for an origin at the eye.
            let e = eye.to_array();
            let m = (self.reach + eye.abs().max_element()) * MARGIN;
            for (f, n) in nodes.iter_mut().zip(self.nodes) {
                *f = N::make(n, e, m);
            }
        }
        leaves.fill(FocalLeaf::EMPTY);
        Ok(FocalBvh {
            bvh: *self,
            eye,
            on,
            nodes,
            leaves: Cell::from_mut(leaves).as_slice_of_cells(),
        })
    }
}

impl<'s, P: Leaf, N: NodeCache> FocalBvh<'s, '_, P, N> {
    /// The eye.
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The tree.
    #[must_use]
    pub fn tree(&self) -> &Bvh<'s, P> {
        &self.bvh
    }

    /// The leaves filled so far (reached by a ray from the eye).
    #[must_use]
    pub fn filled(&self) -> usize {
        self.leaves.iter().filter(|c| c.get().ready).count()
    }

    /// True when every valid lane of `rays` starts at the eye, bit for bit.
    fn at_eye<L: Lane>(&self, rays: &RayPacket<L>) -> bool {
        if !self.on {
            return false;
        }
        let valid = rays.valid();
        let o = rays.origin;
        let e = self.eye.to_array().map(f32::to_bits);
        (0..L::LANES).all(|i| {
            let bits = |x: L| (x.lane(i).to_f64() as f32).to_bits();
            !valid.test(i) || [bits(o.x), bits(o.y), bits(o.z)] == e
        })
    }

    /// True when `ray` starts at the eye, bit for bit.
    fn ray_from_eye(&self, ray: &Ray) -> bool {
        self.on
            && ray.origin().to_array().map(f32::to_bits) == self.eye.to_array().map(f32::to_bits)
    }
}

/// A leaf with its per-eye entry.
pub(crate) struct RelLeaf<'a, P: Leaf>(&'a P, P::Rel);

impl<P: Leaf> LeafTest<P> for RelLeaf<'_, P> {
    #[inline(always)]
    fn four(&self, ray: &RayPacket<f32x4>, pre: &P::Rays<f32x4>, cull: Cull) -> LaneHit<f32x4> {
        self.0.test_four_rel(&self.1, ray, pre, cull)
    }
    #[inline(always)]
    fn one<L: Lane>(
        &self,
        k: usize,
        rays: &RayPacket<L>,
        pre: &P::Rays<L>,
        cull: Cull,
    ) -> LaneHit<L> {
        self.0.test_one_rel(&self.1, k, rays, pre, cull)
    }
}

impl<P: Leaf, N: NodeCache> View<P> for FocalBvh<'_, '_, P, N> {
    /// `|d|` and `1/|d|²` for [`SphereNode`]s.
    type One = (f32, f32);
    type Many<L: Lane> = (L, L);
    #[inline(always)]
    fn one(&self, ray: &Ray) -> (f32, f32) {
        match N::EMPTY.rows() {
            NodeRows::Boxes(_) => (0.0, 0.0),
            NodeRows::Spheres(_) => {
                let dd = ray.dir().length_squared();
                (libm::sqrtf(dd), 1.0 / dd)
            }
        }
    }
    #[inline(always)]
    fn many<L: Lane>(&self, rays: &RayPacket<L>) -> (L, L) {
        match N::EMPTY.rows() {
            NodeRows::Boxes(_) => (L::from_f32(0.0), L::from_f32(0.0)),
            NodeRows::Spheres(_) => {
                let dd = rays.dir.length_squared();
                (dd.sqrt(), L::from_f32(1.0) / dd)
            }
        }
    }
    /// A node index beyond the cache (which `focus` rules out) is tested by its own boxes, as
    /// is every node for a ray whose slab test visits every child.
    #[inline(always)]
    fn node_one(
        &self,
        x: &(f32, f32),
        slab: &Slab,
        c: u32,
        n: &Node,
        t_min: f32,
        t_max: f32,
    ) -> (u32, f32x8) {
        match self.nodes.get(c as usize).map(N::rows) {
            Some(NodeRows::Boxes(r)) => slab.test_rows::<true>(n, r, t_min, t_max),
            Some(NodeRows::Spheres(r)) if !slab.all => spheres_one(r, *x, slab.dir(), t_min, t_max),
            _ => slab.test(n, t_min, t_max),
        }
    }
    #[inline(always)]
    fn node_many<L: Lane>(
        &self,
        x: &(L, L),
        slab: &PacketSlab<L>,
        c: u32,
        n: &Node,
        k: usize,
        t_min: L,
        t_max: L,
        active: L::Mask,
    ) -> (L::Mask, L) {
        match self.nodes.get(c as usize).map(N::rows) {
            Some(NodeRows::Boxes(r)) => slab.test::<true>(r, k, t_min, t_max, active),
            Some(NodeRows::Spheres(r)) => {
                let (m, tn) = spheres_many(r, k, *x, slab.dir(), t_min, t_max);
                ((m | slab.all) & active, tn)
            }
            None => slab.test::<false>(&n.bounds, k, t_min, t_max, active),
        }
    }
    /// A node index beyond the cache, and [`SphereNode`]s, are tested child by child.
    #[inline(always)]
    fn node_frustum(
        &self,
        f: &Frustum,
        c: u32,
        _: &Node,
        t_lo: f32,
        t_hi: f32,
    ) -> Option<(u32, f32x8)> {
        match self.nodes.get(c as usize).map(N::rows) {
            Some(NodeRows::Boxes(r)) => Some(f.test::<true>(r, t_lo, t_hi)),
            _ => None,
        }
    }
    type Test<'a>
        = RelLeaf<'a, P>
    where
        Self: 'a,
        P: 'a;

    #[inline(always)]
    fn leaf<'a>(&'a self, li: u32, leaf: &'a P) -> RelLeaf<'a, P> {
        let Some(cell) = self.leaves.get(li as usize) else {
            return RelLeaf(leaf, leaf.relative(self.eye));
        };
        let mut x = cell.get();
        if !x.ready {
            x = FocalLeaf {
                rel: leaf.relative(self.eye),
                ready: true,
            };
            cell.set(x);
        }
        RelLeaf(leaf, x.rel)
    }
}

/// Answers as the tree does ([`Bvh`]'s [`Query`]), bit for bit; rays from the eye use the
/// cache.
impl<P: Leaf, N: NodeCache> Query for FocalBvh<'_, '_, P, N> {
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        if self.at_eye(rays) {
            closest_packet(&self.bvh, self, rays)
        } else {
            closest_packet(&self.bvh, &World, rays)
        }
    }

    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        if self.at_eye(rays) {
            self.bvh.any_lanes(self, rays)
        } else {
            self.bvh.any_lanes(&World, rays)
        }
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        if self.at_eye(rays) {
            self.bvh.all_lanes(self, rays, f)
        } else {
            self.bvh.all_lanes(&World, rays, f)
        }
    }

    fn closest_ray(&self, ray: &Ray) -> Option<Hit> {
        if self.ray_from_eye(ray) {
            closest_ray(&self.bvh, self, ray)
        } else {
            closest_ray(&self.bvh, &World, ray)
        }
    }

    fn any_ray(&self, ray: &Ray) -> bool {
        if self.ray_from_eye(ray) {
            self.bvh.any_one(self, ray)
        } else {
            self.bvh.any_one(&World, ray)
        }
    }
}
