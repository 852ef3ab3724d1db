//! A scene a game engine keeps (feature `alloc`): objects built once (triangle meshes and
//! sphere sets, in one scene), instances added, moved and removed every frame through stable
//! handles, each with a 32-bit layer mask, and one commit per frame that refits or rebuilds the
//! top level only. Queries run between commits, on any number of threads (`&OwnedScene` is
//! `Sync`: nothing changes while it is shared), through the one vocabulary
//! ([`Query`](crate::Query)), with layer masks, an ignored instance and hit filters through
//! [`Filtered`] ([`masked`](OwnedScene::masked), [`ignoring`](OwnedScene::ignoring),
//! [`filtered`](OwnedScene::filtered)).
//!
//! ```
//! use raylane::bvh::{OwnedBvh, OwnedScene};
//! use raylane::glam::Vec3;
//! use raylane::sphere::Sphere;
//! use raylane::triangle::Triangle;
//! use raylane::{Query, Ray};
//!
//! let at = |x: f32, y: f32, z: f32| [[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, y], [0.0, 0.0, 1.0, z]];
//! let mut scene = OwnedScene::new();
//! let quad = [
//!     Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0)),
//!     Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(-1.0, 1.0, 0.0)),
//! ];
//! let wall = scene.add_object(OwnedBvh::new(&quad[..]).unwrap());
//! let ball = scene.add_object(OwnedBvh::new(&[Sphere::new(Vec3::ZERO, 0.5)][..]).unwrap());
//! const WALLS: u32 = 1;
//! const AGENTS: u32 = 2;
//! let w = scene.add(wall, at(0.0, 0.0, -10.0), WALLS).unwrap();
//! let me = scene.add(ball, at(0.0, 0.0, -2.0), AGENTS).unwrap();
//! scene.commit();
//!
//! let ray = Ray::new(Vec3::ZERO, Vec3::NEG_Z);
//! let hit = scene.closest(&ray).unwrap();
//! assert_eq!((scene.instance(hit.set), hit.t), (Some(me), 1.5));
//! // Walls only (a layer), or everything but the shooter (a filter): the wall behind.
//! assert_eq!(scene.masked(WALLS).closest(&ray).unwrap().t, 10.0);
//! let hit = scene.filtered(|c| c.set != me.slot()).closest(&ray).unwrap();
//! assert_eq!(scene.instance(hit.set), Some(w));
//!
//! // A frame: move, remove, commit; queries see the last commit.
//! scene.set_transform(me, at(0.0, 0.0, -20.0)).unwrap();
//! scene.remove(w).unwrap();
//! assert_eq!(scene.closest(&ray).unwrap().t, 1.5); // not committed yet
//! scene.commit();
//! assert_eq!(scene.closest(&ray).unwrap().t, 19.5);
//! assert!(scene.remove(w).is_err()); // a removed handle is an error, never a panic
//! ```
//!
//! **Handles.** An instance is a slot and a generation ([`InstanceId`]); removing it frees the
//! slot for a later [`add`](OwnedScene::add) under the next generation, so an old handle is
//! refused ([`SceneError::Stale`]) by every method that takes one, and never reaches another
//! instance. `Hit::set` is the slot ([`InstanceId::slot`], [`OwnedScene::instance`]).
//!
//! **Frames.** Changes ([`add`](OwnedScene::add), [`remove`](OwnedScene::remove),
//! [`set_transform`](OwnedScene::set_transform), [`set_mask`](OwnedScene::set_mask)) are
//! staged (a transform's inverse is made when it is set); queries see the scene as of the last
//! [`commit`](OwnedScene::commit), which moves the staged changes in (the changed instances'
//! world boxes) and then refits or rebuilds the top level, never an object:
//!
//! * **Rebuild** (binned SAH over the instances' world boxes, as the caller-storage
//!   [`Scene`](super::Scene) is built, but with every instance a child of its node: the tree
//!   has no leaves of instance boxes, so a node's test is the test of its instances' own
//!   boxes and an instance it enters is read at once) when the number of slots changed (an
//!   `add` past the free slots), or when the refitted tree's SAH cost exceeds
//!   [`REBUILD_RATIO`] times the cost it had when it was last built;
//! * **Refit** (every box recomputed from the world boxes, the topology kept) otherwise — also
//!   after removals and after adds into freed slots (a free slot is an instance with an empty
//!   box).
//!
//! The rule was chosen by measurement (`examples/game`, 10,000 instances moving every frame):
//! see [`REBUILD_RATIO`]; an engine may set its own ([`OwnedScene::set_rebuild_ratio`]).
//!
//! **Answers.** Those of the caller-storage [`Scene`](super::Scene): the closest hit over
//! every instance's object with its default kernel (triangles
//! [`Watertight`], spheres [`Robust`],
//! two-sided), ties to the lower slot, then the lower primitive; the record in world space.
//! Layers: an instance is seen by a ray only when their masks share a bit (a query without a
//! mask has every bit, so an instance whose mask is 0 is never seen) and the ray does not
//! ignore it ([`ignoring`](OwnedScene::ignoring)); a lane that does not see an instance does
//! not trace it. Masks live at instances (an object is one layer; split it into objects for
//! more): per-primitive masks would widen every leaf for every query. Bad input:
//!
//! * a removed or stale handle: [`SceneError::Stale`], nothing changes;
//! * a NaN or infinite transform (or one whose inverse is not finite: a singular one): the
//!   instance is kept but never hit (its rays would be NaN), until a finite transform is set;
//!   a finite transform not invertible to within `2^-16` gets an infinite box (exact, only
//!   slower), as in [`Scene`](super::Scene);
//! * an empty scene, or one emptied during a frame: every query misses once committed.

use alloc::vec::Vec;
use core::marker::PhantomData;

use super::scene::{instance_records, object_packet, object_ray, world_record};
use super::{
    Inst4, Instance, LEAF, Node, OwnedBvh, Primitives, Scratch, Sphere4, Stats, Tri4, WIDTH, build,
    reach, split, stats, traverse,
};
use crate::hit::{Candidate, Collector, Hit, Hits, Winners, alone};
use crate::kernel::{Cull, Kernel};
use crate::lane::{Lane, Mask};
use crate::ray::{Ray, RayPacket};
use crate::set::{Filtered, Set, Trace, only};
use crate::sphere::{Robust, Sphere};
use crate::triangle::{Triangle, Watertight};

/// The factor of SAH cost over the cost at the last rebuild beyond which a commit rebuilds
/// the top level instead of refitting it.
///
/// Measured with `examples/game` (10,000 instances of 7 objects, all moving every frame; one
/// thread; `--speed 3`: frames of 1/20 s): a rebuild costs 3–4 ms against a refit's 0.4–0.6
/// ms (3.7–5 ms and 0.45–0.6 ms since the instances are the nodes' children), and the frame's
/// queries (about 10 ms: a pick, 1,000 sight lines, 10,000 bullets, a
/// shadow ray per impact) cost about half the SAH ratio's excess more on a refitted tree
/// (ratio 1.08: +1.5 %; 1.21: +12 %; 1.57: +21 %; 2.4: +98 %). Rebuilding every `N` frames
/// while the loss grows by `g` per frame costs `R/N + g·N/2` per frame on average, least when
/// the loss at the rebuild is `√(2·R·g)`: about 0.3–0.45 ms here, a ratio of 1.08–1.1. Over
/// 200 frames (two runs) the mean frame took 11.9 and 12.8 ms at 1.1 (6 rebuilds), 12.8 and
/// 11.9 at 1.2 (4), 12.7 and 13.1 at 1.05 (8), 14.1 and 13.3 at 1.5 (2), 18.5 and 16.3
/// refitting only, 19.1 and 15.5 rebuilding every frame; with the instances as the nodes'
/// children, 10.6 and 10.6 at 1.05 (6 rebuilds), 10.7 and 10.6 at 1.1 (4), 11.0 and 11.0 at
/// 1.2 (3). See `docs/design.md`, "An engine's scene".
pub const REBUILD_RATIO: f64 = 1.1;

/// An object of an [`OwnedScene`]: a BVH over a triangle mesh or over spheres, built once and
/// shared by any number of instances.
#[derive(Clone, Debug)]
pub enum Object {
    /// Triangles ([`Watertight`], two-sided).
    Mesh(OwnedBvh<Tri4>),
    /// Spheres ([`Robust`]).
    Spheres(OwnedBvh<Sphere4>),
}

impl From<OwnedBvh<Tri4>> for Object {
    fn from(tree: OwnedBvh<Tri4>) -> Self {
        Object::Mesh(tree)
    }
}

impl From<OwnedBvh<Sphere4>> for Object {
    fn from(tree: OwnedBvh<Sphere4>) -> Self {
        Object::Spheres(tree)
    }
}

impl Object {
    /// The object-space box of everything in it.
    #[must_use]
    pub fn root_box(&self) -> ([f32; 3], [f32; 3]) {
        match self {
            Object::Mesh(t) => t.view().root_box(),
            Object::Spheres(t) => t.view().root_box(),
        }
    }

    #[inline(always)]
    fn trace<T: Kernel<Triangle>, S: Kernel<Sphere>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        match self {
            Object::Mesh(t) => t.trace_with::<T, L, C>(cull, rays, set, c),
            Object::Spheres(t) => t.trace_with::<S, L, C>(cull, rays, set, c),
        }
    }

    #[inline(always)]
    fn trace_ray<T: Kernel<Triangle>, S: Kernel<Sphere>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        match self {
            Object::Mesh(t) => t.trace_ray_with::<T, C>(cull, ray, set, c),
            Object::Spheres(t) => t.trace_ray_with::<S, C>(cull, ray, set, c),
        }
    }

    /// The record of the winner `one` (set 0) of the object-space ray `local`.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    fn record(&self, cull: Cull, local: &Ray, one: &Winners<f32>) -> Option<Hit> {
        let rays = RayPacket::splat(local);
        match self {
            Object::Mesh(t) => t.records_with(cull, &rays, 0, one).lane(0),
            Object::Spheres(t) => t.records_with(cull, &rays, 0, one).lane(0),
        }
    }
}

/// An object of an [`OwnedScene`] (from [`add_object`](OwnedScene::add_object)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObjectId(u32);

impl ObjectId {
    /// Its position among the scene's objects (0, 1, 2, … in the order they were added).
    #[must_use]
    pub fn index(self) -> u32 {
        self.0
    }
}

/// An instance of an [`OwnedScene`]: its slot and the slot's generation when it was added
/// (see the [module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct InstanceId {
    slot: u32,
    generation: u32,
}

impl InstanceId {
    /// The slot: [`Hit::set`] and [`Candidate::set`] of this instance's hits (unique among
    /// the live instances; a removed instance's slot may later hold another).
    #[must_use]
    pub fn slot(self) -> u32 {
        self.slot
    }
}

/// Why an [`OwnedScene`] refused a change (nothing was changed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneError {
    /// The handle's instance was removed (or the handle is another scene's).
    Stale,
    /// No such object in this scene.
    NoObject,
    /// More than [`MAX_PRIMITIVES`](super::MAX_PRIMITIVES) slots.
    Full,
}

impl core::fmt::Display for SceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SceneError::Stale => write!(f, "scene: the instance was removed"),
            SceneError::NoObject => write!(f, "scene: no such object"),
            SceneError::Full => write!(f, "scene: more than 2^30 - 1 instance slots"),
        }
    }
}

/// What a [`commit`](OwnedScene::commit) did to the top level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Commit {
    /// Nothing was staged: nothing changed.
    Unchanged,
    /// Every box recomputed, the tree's topology kept.
    Refit,
    /// The tree built again over the instances' world boxes.
    Rebuild,
}

/// An instance as the engine last set it (applied at the next commit); its inverse transform
/// is made when it is set.
#[derive(Clone, Copy, Debug)]
struct Staged {
    inst: Instance,
    mask: u32,
    generation: u32,
    live: bool,
    dirty: bool,
}

/// An instance as queries see it (the last commit), in one cache line: `object` is [`HIDDEN`]
/// for a slot that is free or never hit (mask 0, a non-finite transform).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Placed {
    /// World→object ([`Instance::to_object`]).
    to_object: [[f32; 4]; 3],
    object: u32,
    mask: u32,
    mirror: bool,
}

/// The object index of a committed slot that nothing sees.
const HIDDEN: u32 = u32::MAX;

/// The empty box.
const NO_BOX: ([f32; 3], [f32; 3]) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);

/// The committed world boxes, as the top level's primitives.
struct Boxes<'a>(&'a [([f32; 3], [f32; 3])]);

impl Primitives for Boxes<'_> {
    type Leaf = Inst4;
    fn count(&self) -> usize {
        self.0.len()
    }
    fn bounds(&self, i: u32) -> ([f32; 3], [f32; 3]) {
        self.0.get(i as usize).copied().unwrap_or(NO_BOX)
    }
    fn put(&self, i: u32, leaf: &mut Inst4, k: usize) {
        leaf.put(k, i, self.bounds(i));
    }
}

/// A scene that owns its objects and instances, updated every frame (see the
/// [module docs](self)).
#[derive(Clone, Debug)]
pub struct OwnedScene {
    objects: Vec<Object>,
    /// The objects' root boxes.
    object_boxes: Vec<([f32; 3], [f32; 3])>,
    staged: Vec<Staged>,
    free: Vec<u32>,
    dirty: Vec<u32>,
    live: usize,
    placed: Vec<Placed>,
    /// The committed slots' generations.
    generations: Vec<u32>,
    boxes: Vec<([f32; 3], [f32; 3])>,
    top: Top,
    /// The top level's SAH cost when it was last built.
    built_sah: f64,
    /// [`REBUILD_RATIO`] or the engine's own ([`set_rebuild_ratio`](Self::set_rebuild_ratio)).
    ratio: f64,
}

impl Default for OwnedScene {
    fn default() -> Self {
        Self::new()
    }
}

impl OwnedScene {
    /// An empty scene (every query misses).
    #[must_use]
    pub fn new() -> Self {
        let top = Top::build(&Boxes(&[]));
        OwnedScene {
            objects: Vec::new(),
            object_boxes: Vec::new(),
            staged: Vec::new(),
            free: Vec::new(),
            dirty: Vec::new(),
            live: 0,
            placed: Vec::new(),
            generations: Vec::new(),
            boxes: Vec::new(),
            built_sah: 1.0,
            ratio: REBUILD_RATIO,
            top,
        }
    }

    /// Adds an object (an [`OwnedBvh`] over triangles or spheres, built once) for instances
    /// to share. Objects stay for the scene's life.
    pub fn add_object(&mut self, object: impl Into<Object>) -> ObjectId {
        let object = object.into();
        self.object_boxes.push(object.root_box());
        self.objects.push(object);
        ObjectId(self.objects.len() as u32 - 1)
    }

    /// Object `id`.
    #[must_use]
    pub fn object(&self, id: ObjectId) -> Option<&Object> {
        self.objects.get(id.0 as usize)
    }

    /// Places `object` by `to_world` (rows `[a0, a1, a2, b]`: `world = A·p + b`, as
    /// [`Instance::new`]) on the layers `mask`; seen by queries after the next commit.
    ///
    /// # Errors
    ///
    /// [`SceneError::NoObject`] when `object` is not this scene's, [`SceneError::Full`] past
    /// [`MAX_PRIMITIVES`](super::MAX_PRIMITIVES) slots.
    pub fn add(
        &mut self,
        object: ObjectId,
        to_world: [[f32; 4]; 3],
        mask: u32,
    ) -> Result<InstanceId, SceneError> {
        if object.0 as usize >= self.objects.len() {
            return Err(SceneError::NoObject);
        }
        let inst = Instance::new(object.0, to_world);
        let slot = match self.free.pop() {
            Some(s) => s,
            None if self.staged.len() >= super::MAX_PRIMITIVES => return Err(SceneError::Full),
            None => {
                self.staged.push(Staged {
                    inst,
                    mask: 0,
                    generation: 0,
                    live: false,
                    dirty: false,
                });
                self.staged.len() as u32 - 1
            }
        };
        let Some(s) = self.staged.get_mut(slot as usize) else {
            return Err(SceneError::Full);
        };
        s.inst = inst;
        s.mask = mask;
        s.live = true;
        let generation = s.generation;
        self.live += 1;
        self.touch(slot);
        Ok(InstanceId { slot, generation })
    }

    /// Removes instance `id` (from queries at the next commit); its slot is reused by a later
    /// [`add`](Self::add) under a new generation.
    ///
    /// # Errors
    ///
    /// [`SceneError::Stale`] when `id` was removed already.
    pub fn remove(&mut self, id: InstanceId) -> Result<(), SceneError> {
        let s = self.get_mut(id)?;
        s.live = false;
        s.generation = s.generation.wrapping_add(1);
        // A slot whose generations ran out is retired: an old handle never meets a new one.
        let retire = s.generation == u32::MAX;
        self.live -= 1;
        if !retire {
            self.free.push(id.slot);
        }
        self.touch(id.slot);
        Ok(())
    }

    /// Moves instance `id` to `to_world` (as [`add`](Self::add)) at the next commit.
    ///
    /// # Errors
    ///
    /// [`SceneError::Stale`] when `id` was removed.
    pub fn set_transform(
        &mut self,
        id: InstanceId,
        to_world: [[f32; 4]; 3],
    ) -> Result<(), SceneError> {
        let s = self.get_mut(id)?;
        s.inst = Instance::new(s.inst.object, to_world);
        self.touch(id.slot);
        Ok(())
    }

    /// Puts instance `id` on the layers `mask` at the next commit (0: seen by no query).
    ///
    /// # Errors
    ///
    /// [`SceneError::Stale`] when `id` was removed.
    pub fn set_mask(&mut self, id: InstanceId, mask: u32) -> Result<(), SceneError> {
        self.get_mut(id)?.mask = mask;
        self.touch(id.slot);
        Ok(())
    }

    /// Instance `id`'s transform as last set (`None` when removed).
    #[must_use]
    pub fn transform(&self, id: InstanceId) -> Option<[[f32; 4]; 3]> {
        self.get(id).map(|s| s.inst.to_world)
    }

    /// Instance `id`'s layers as last set (`None` when removed).
    #[must_use]
    pub fn mask(&self, id: InstanceId) -> Option<u32> {
        self.get(id).map(|s| s.mask)
    }

    /// Instance `id`'s object (`None` when removed).
    #[must_use]
    pub fn object_of(&self, id: InstanceId) -> Option<ObjectId> {
        self.get(id).map(|s| ObjectId(s.inst.object))
    }

    /// True while `id` is live (added, not removed).
    #[must_use]
    pub fn contains(&self, id: InstanceId) -> bool {
        self.get(id).is_some()
    }

    /// Live instances (as staged).
    #[must_use]
    pub fn len(&self) -> usize {
        self.live
    }

    /// True when no instance is live (as staged).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// The instance whose hits carry `set` (a [`Hit::set`] or [`Candidate::set`] of this
    /// scene, as of the last commit), if one was there and visible.
    #[must_use]
    pub fn instance(&self, set: u32) -> Option<InstanceId> {
        let p = self.placed.get(set as usize)?;
        let generation = *self.generations.get(set as usize)?;
        (p.object != HIDDEN).then_some(InstanceId {
            slot: set,
            generation,
        })
    }

    /// Applies the staged changes and refits or rebuilds the top level by the rule of the
    /// [module docs](self); returns which.
    pub fn commit(&mut self) -> Commit {
        self.apply(false)
    }

    /// [`commit`](Self::commit), always rebuilding the top level.
    pub fn commit_rebuilt(&mut self) -> Commit {
        self.apply(true)
    }

    /// The factor of SAH cost over the last build's beyond which a commit rebuilds
    /// ([`REBUILD_RATIO`] by default; `0.0`: rebuild at every commit; `f64::INFINITY`: refit
    /// unless the number of slots changed).
    pub fn set_rebuild_ratio(&mut self, ratio: f64) {
        self.ratio = ratio;
    }

    /// The top level's size, depth and SAH cost (see [`Stats`]).
    #[must_use]
    pub fn stats(&self) -> Stats {
        self.top.stats()
    }

    /// This scene seen by queries on the layers `mask` ([`Filtered::mask`]; per lane:
    /// [`Filtered::masks`]).
    #[must_use]
    pub fn masked(&self, mask: u32) -> Filtered<'_, Self> {
        Filtered::new(self).mask(mask)
    }

    /// This scene as instance `id` sees it: its hits do not count, and no ray traces it
    /// ([`Filtered::ignore`]; per lane: [`Filtered::ignores`] with slots). A removed `id`
    /// ignores nothing that is still in the scene (its slot may hold another instance after
    /// the next commit: ignore by live handles).
    #[must_use]
    pub fn ignoring(&self, id: InstanceId) -> Filtered<'_, Self> {
        Filtered::new(self).ignore(id.slot)
    }

    /// This scene seen through the hit filter `filter` ([`Filtered::filter`]; add layers with
    /// [`Filtered::mask`]). `Candidate::set` is the instance's slot.
    #[must_use]
    pub fn filtered<F: Fn(&Candidate) -> bool>(&self, filter: F) -> Filtered<'_, Self, F> {
        Filtered::new(self).filter(filter)
    }

    fn get(&self, id: InstanceId) -> Option<&Staged> {
        self.staged
            .get(id.slot as usize)
            .filter(|s| s.live && s.generation == id.generation)
    }

    fn get_mut(&mut self, id: InstanceId) -> Result<&mut Staged, SceneError> {
        self.staged
            .get_mut(id.slot as usize)
            .filter(|s| s.live && s.generation == id.generation)
            .ok_or(SceneError::Stale)
    }

    /// Marks `slot` for the next commit.
    fn touch(&mut self, slot: u32) {
        if let Some(s) = self.staged.get_mut(slot as usize)
            && !s.dirty
        {
            s.dirty = true;
            self.dirty.push(slot);
        }
    }

    fn apply(&mut self, rebuild: bool) -> Commit {
        let grown = self.placed.len() != self.staged.len();
        if self.dirty.is_empty() && !grown && !rebuild {
            return Commit::Unchanged;
        }
        let hidden = Placed {
            to_object: [[0.0; 4]; 3],
            object: HIDDEN,
            mask: 0,
            mirror: false,
        };
        self.placed.resize(self.staged.len(), hidden);
        self.generations.resize(self.staged.len(), 0);
        self.boxes.resize(self.staged.len(), NO_BOX);
        for slot in self.dirty.drain(..) {
            let (Some(s), Some(p), Some(b), Some(g)) = (
                self.staged.get_mut(slot as usize),
                self.placed.get_mut(slot as usize),
                self.boxes.get_mut(slot as usize),
                self.generations.get_mut(slot as usize),
            ) else {
                continue;
            };
            s.dirty = false;
            *g = s.generation;
            let inst = &s.inst;
            let mut finite = inst.to_object.iter().chain(&inst.to_world).flatten();
            let shown = s.live && s.mask != 0 && finite.all(|x| x.is_finite());
            let object = self
                .object_boxes
                .get(inst.object as usize)
                .filter(|_| shown);
            (*p, *b) = match object {
                Some(&(lo, hi)) => {
                    let p = Placed {
                        to_object: inst.to_object,
                        object: inst.object,
                        mask: s.mask,
                        mirror: inst.mirror,
                    };
                    (p, inst.world_box(lo, hi))
                }
                None => (hidden, NO_BOX),
            };
        }
        let prims = Boxes(&self.boxes);
        if !rebuild
            && !grown
            && self.top.refit(&prims)
            && self.top.stats().sah <= self.ratio * self.built_sah
        {
            return Commit::Refit;
        }
        self.top = Top::build(&prims);
        self.built_sah = self.top.stats().sah;
        Commit::Rebuild
    }

    /// This scene with the triangle kernel `T` and the sphere kernel `S` instead of
    /// [`Watertight`] and [`Robust`] (any [`Kernel`] of each primitive, e.g.
    /// [`Moller`](crate::triangle::Moller), Embree's method), queried like the scene itself;
    /// [`culled`](WithKernels::culled) drops back faces.
    #[must_use]
    pub fn with_kernels<T: Kernel<Triangle>, S: Kernel<Sphere>>(&self) -> WithKernels<'_, T, S> {
        WithKernels {
            scene: self,
            cull: Cull::None,
            kernels: PhantomData,
        }
    }

    /// The packet query with kernels `T`, `S` and culling `cull`.
    fn trace_with<T: Kernel<Triangle>, S: Kernel<Sphere>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        traverse::many(
            &self.top.nodes,
            self.top.reach,
            rays,
            c,
            |i, r, _, c| {
                let Some((p, object)) = self.placed(i) else {
                    return false;
                };
                let keep = c.sees(set + i, p.mask);
                if keep.none() {
                    return false;
                }
                let local = object_packet(&p.to_object, r);
                if keep.all() {
                    object.trace::<T, S, L, C>(cull, &local, set + i, c)
                } else {
                    object.trace::<T, S, L, C>(cull, &only(&local, keep), set + i, c)
                }
            },
            split::<L, C>(),
            |start, i, c| {
                alone(
                    c,
                    i,
                    #[cfg_attr(target_arch = "x86_64", inline(always))]
                    |one| self.trace_from::<T, S, _>(cull, start, &rays.lane_ray(i), set, one),
                )
            },
        )
    }

    /// The one-ray query with kernels `T`, `S` and culling `cull`. The top level's traversal
    /// is inlined (with the query's `trace_ray`) into the query's SIMD level
    /// ([`crate::simd`]); the instance closure is left to the compiler (forced inline, it made
    /// every object's traversal a copy per level and per stack, and the test suite compiled
    /// more than twice as long), and enters the level again for the object's traversal. See
    /// docs/design.md.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    fn trace_ray_with<T: Kernel<Triangle>, S: Kernel<Sphere>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        if C::EVERY {
            return self.trace_with::<T, S, f32, C>(cull, &RayPacket::splat(ray), set, c);
        }
        self.trace_from::<T, S, C>(cull, 0, ray, set, c)
    }

    /// One ray from the top level's node reference `start` (0: the root): the one-ray query,
    /// and a packet's lanes that continue alone.
    #[inline(always)]
    fn trace_from<T: Kernel<Triangle>, S: Kernel<Sphere>, C: Collector<f32>>(
        &self,
        cull: Cull,
        start: u32,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        // The entries and nodes a node test lets through are prefetched at once: 10,000
        // instances' entries and the top level's nodes do not stay in the caches between
        // frames, and without it the first read of each was a miss the ray waited for.
        let fetch = |r: u32| {
            if r & LEAF != 0 {
                if let Some(p) = self.placed.get((r & !LEAF) as usize) {
                    crate::simd::prefetch(p);
                }
            } else if let Some(n) = self.top.nodes.get(r as usize) {
                crate::simd::prefetch(n);
            }
        };
        traverse::one_fetching(
            &self.top.nodes,
            self.top.reach,
            ray,
            start,
            c,
            Some(&fetch),
            |i, c| {
                let Some((p, object)) = self.placed(i) else {
                    return false;
                };
                let local = || object_ray(&p.to_object, ray);
                // The object's traversal enters the query's level again: the closure is left
                // out of line (inlined, it is copied into every stack of every level), where
                // it would run at the baseline.
                c.sees(set + i, p.mask)
                    && crate::simd::run(
                        #[inline(always)]
                        || object.trace_ray::<T, S, C>(cull, &local(), set + i, c),
                    )
            },
        )
    }

    /// The records of the winners `w` of a query culled by `cull`.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    fn records_with<L: Lane>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        w: &Winners<L>,
    ) -> Hits<L> {
        instance_records(
            rays,
            set,
            Trace::sets(self),
            w,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |i, ray, one| {
                let (p, object) = self.placed(i)?;
                let h = object.record(cull, &object_ray(&p.to_object, ray), one)?;
                Some(world_record(&p.to_object, p.mirror, set + i, ray, h))
            },
        )
    }

    /// Committed slot `i` and its object, when something sees it.
    #[inline(always)]
    fn placed(&self, i: u32) -> Option<(&Placed, &Object)> {
        let p = self.placed.get(i as usize)?;
        Some((p, self.objects.get(p.object as usize)?))
    }
}

/// The top level: a tree whose leaves are the committed slots themselves, each a child of its
/// node (`LEAF | slot`), so that a node's test is the test of its instances' world boxes and
/// entering an instance reads its entry straight away (no leaf of instance boxes between).
#[derive(Clone, Debug)]
struct Top {
    nodes: Vec<Node>,
    /// The largest coordinate of the root's children (the slab test's margin).
    reach: f32,
}

impl Top {
    /// The binned SAH build over `prims`, one slot per leaf (an empty root when there is none).
    fn build(prims: &Boxes) -> Top {
        let n = prims.count();
        let mut nodes = alloc::vec![Node::EMPTY; n.max(1)];
        let mut scratch = alloc::vec![Scratch::default(); n];
        match build::topology(prims, &mut nodes, &mut scratch, WIDTH, 1, false) {
            Ok((used, _)) => nodes.truncate(used.max(1)),
            Err(_) => nodes = alloc::vec![Node::EMPTY],
        }
        nodes.shrink_to_fit();
        let reach = nodes.first().map_or(0.0, reach);
        Top { nodes, reach }
    }

    /// Every box recomputed from `prims` (the same slots), the topology kept; false when it
    /// does not fit them (then the caller rebuilds).
    fn refit(&mut self, prims: &Boxes) -> bool {
        match build::refit_direct(prims, &mut self.nodes) {
            Ok(reach) => {
                self.reach = reach;
                true
            }
            Err(_) => false,
        }
    }

    /// Size, depth and SAH cost (a slot counts as a leaf of one primitive).
    fn stats(&self) -> Stats {
        let s = stats(
            &self.nodes,
            |_| 1,
            0,
            core::mem::size_of_val(&self.nodes[..]),
        );
        Stats {
            leaves: s.primitives,
            ..s
        }
    }
}

/// An owned scene answers like the caller-storage [`Scene`](super::Scene) over its visible
/// instances (see the [module docs](self)); the top level's leaves are instances, traversed by
/// the one traversal, and a packet's lanes that do not see an instance (its mask, an ignored
/// instance) trace past it with an empty interval.
impl Trace for OwnedScene {
    const LEVEL_LANES: bool = false;
    #[inline]
    fn sets(&self) -> u32 {
        self.placed.len() as u32
    }

    #[inline]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        self.trace_with::<Watertight, Robust, L, C>(Cull::None, rays, set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray<C: Collector<f32>>(&self, ray: &Ray, set: u32, c: &mut C) -> bool {
        self.trace_ray_with::<Watertight, Robust, C>(Cull::None, ray, set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        self.records_with(Cull::None, rays, set, w)
    }
}

/// An [`OwnedScene`] with other kernels and culling ([`OwnedScene::with_kernels`]), queried
/// like the scene itself (also through [`Filtered`]).
#[derive(Debug)]
pub struct WithKernels<'a, T, S> {
    scene: &'a OwnedScene,
    cull: Cull,
    kernels: PhantomData<(T, S)>,
}

impl<T, S> Clone for WithKernels<'_, T, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T, S> Copy for WithKernels<'_, T, S> {}

impl<T, S> WithKernels<'_, T, S> {
    /// The same query culled ([`Cull::Back`]: front faces only, as a set's
    /// [`culled`](crate::Query::culled)).
    #[must_use]
    pub fn culled(self, cull: Cull) -> Self {
        WithKernels { cull, ..self }
    }
}

impl<T: Kernel<Triangle>, S: Kernel<Sphere>> Trace for WithKernels<'_, T, S> {
    const LEVEL_LANES: bool = false;
    #[inline]
    fn sets(&self) -> u32 {
        Trace::sets(self.scene)
    }

    #[inline]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        self.scene.trace_with::<T, S, L, C>(self.cull, rays, set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray<C: Collector<f32>>(&self, ray: &Ray, set: u32, c: &mut C) -> bool {
        self.scene.trace_ray_with::<T, S, C>(self.cull, ray, set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        self.scene.records_with(self.cull, rays, set, w)
    }
}
