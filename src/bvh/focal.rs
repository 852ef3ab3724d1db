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
//! **Which node test.** The lecture's focal sphere test (a bounding sphere per node, `C − E`
//! and `|C − E|² − r²` cached: 4 mul and 2 add per node for unit directions) was measured
//! against the relative slab test (`examples/bvh_speed.rs`, vendored bunny, see the README):
//! a sphere around a box is looser (more nodes visited) and still needs an entry distance for
//! the nearest-first order; the relative slab test is kept.
//!
//! **Exactly the world traversal's answers.** The leaf tests compute the same bits as the
//! world traversal's (the relative vertices are the kernel's own first step), and the
//! cached planes are conservative as the world's are: `fl(fl(b − E) ∓ m)` differs from the
//! widened plane by two roundings of at most `2^-24·(R + |E|∞)`, far inside the margin
//! `m = 2^-14·(R + |E|∞)` (see the [module docs](super)). So every query equals brute force
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
use wide::f32x4;

use super::query::{closest_packet, closest_ray};
use super::traverse::{LeafTest, MARGIN, View, World};
use super::{BuildError, Bvh, Leaf, Node, WIDTH};
use crate::hit::LaneHit;
use crate::lane::{Lane, Mask, Scalar};
use crate::query::{Hit, Hits, Query};
use crate::ray::{Ray, RayPacket};
use crate::triangle::Cull;

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
pub struct FocalBvh<'s, 'c, P: Leaf> {
    bvh: Bvh<'s, P>,
    eye: Vec3,
    /// The eye is finite (otherwise every query runs in the world mode).
    on: bool,
    nodes: &'c [FocalNode],
    leaves: &'c [Cell<FocalLeaf<P>>],
}

impl<P: Leaf> core::fmt::Debug for FocalBvh<'_, '_, P> {
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
                for a in 0..3 {
                    f.rows[a] = n.bounds[a].map(|b| (b - e[a]) - m);
                    f.rows[3 + a] = n.bounds[3 + a].map(|b| (b - e[a]) + m);
                }
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

impl<'s, P: Leaf> FocalBvh<'s, '_, P> {
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
    fn from_eye<L: Lane>(&self, rays: &RayPacket<L>) -> bool {
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

/// Rows that admit every ray (only for a node index beyond the cache, which `focus` rules
/// out): still exact, only slower.
const OPEN: [[f32; WIDTH]; 6] = [
    [f32::NEG_INFINITY; WIDTH],
    [f32::NEG_INFINITY; WIDTH],
    [f32::NEG_INFINITY; WIDTH],
    [f32::INFINITY; WIDTH],
    [f32::INFINITY; WIDTH],
    [f32::INFINITY; WIDTH],
];

impl<P: Leaf> View<P> for FocalBvh<'_, '_, P> {
    const REL: bool = true;
    type Test<'a>
        = RelLeaf<'a, P>
    where
        Self: 'a,
        P: 'a;

    #[inline(always)]
    fn rows<'a>(&'a self, c: u32, _: &'a Node) -> &'a [[f32; WIDTH]; 6] {
        self.nodes.get(c as usize).map_or(&OPEN, |f| &f.rows)
    }

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
impl<P: Leaf> Query for FocalBvh<'_, '_, P> {
    fn closest_packet<L: Lane>(&self, rays: &RayPacket<L>) -> Hits<L> {
        if self.from_eye(rays) {
            closest_packet(&self.bvh, self, rays)
        } else {
            closest_packet(&self.bvh, &World, rays)
        }
    }

    fn any_packet<L: Lane>(&self, rays: &RayPacket<L>) -> L::Mask {
        if self.from_eye(rays) {
            self.bvh.any_lanes(self, rays)
        } else {
            self.bvh.any_lanes(&World, rays)
        }
    }

    fn all_packet<L: Lane>(&self, rays: &RayPacket<L>, f: &mut dyn FnMut(&Hits<L>)) {
        if self.from_eye(rays) {
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
