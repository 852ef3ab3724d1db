//! Sets: what a query runs over. Every set traces rays into a [`Collector`]
//! ([`crate::hit`]), which alone decides what counts (the interval, the tie rule, stopping):
//!
//! * [`Set`]: a set of one kind of primitive whose kernel is a type parameter — flat slices
//!   (`[Sphere]`, `[Triangle]`, `[Plane]`, here), [`Mesh`](crate::mesh::Mesh),
//!   [`Bvh`](crate::bvh::Bvh) and [`Scene`](crate::bvh::Scene). [`Using`] names another
//!   kernel and the culling ([`Query::using`](crate::Query::using),
//!   [`Query::culled`](crate::Query::culled));
//! * [`Trace`]: anything a query can run, with its kernel chosen: every [`Set`] (with its
//!   default kernel), a [`Using`], the focal caches ([`crate::focal`]), tuples of up to four
//!   of them and [`Sets`] (a slice of them), a scene whose hits carry the member's position in
//!   [`Hit::set`](crate::Hit::set);
//! * [`Filtered`]: any of them seen through layer masks and a hit filter
//!   ([`Screen`]).
//!
//! Flat sets test N rays × 1 primitive, in index order; `all` reports hits in that order
//! (spheres: per sphere, its entry roots, then its exit roots).

use core::marker::PhantomData;

use crate::hit::{
    At, Candidate, Collector, Filter, Hits, Record, Screen, Unfiltered, Visibility, Winners,
};
use crate::kernel::{Cull, Kernel, admit};
use crate::lane::{Lane, Mask};
use crate::plane::{Plane, PlaneTest};
use crate::ray::{Ray, RayPacket};
use crate::sphere::{Robust, Sphere};
use crate::triangle::{Triangle, Watertight};

/// Anything a query runs, its kernel chosen (see the [module docs](self)).
pub trait Trace {
    /// Whether a packet query on it runs in the [SIMD level](crate::simd)'s own lane types:
    /// true where its traversal is inlined whole into the level's copy of the query. A
    /// scene's is not (its nested traversals inlined whole made the compile time explode, see
    /// docs/design.md): its packets run in the caller's lanes, at the build's own level,
    /// rather than in the level's types outside the level's copy (every vector operation
    /// then a call).
    const LEVEL_LANES: bool = true;

    /// How many values of [`Hit::set`](crate::Hit::set) it uses from its `set` on: 1 for a set,
    /// the instances of a [`Scene`](crate::bvh::Scene), the sum for a tuple.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn sets(&self) -> u32 {
        1
    }

    /// Offers every candidate of `rays` to `c`, as set `set` (its first). Returns true when `c`
    /// asked to stop.
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool;

    /// [`trace`](Self::trace) for one ray (sets with a faster one-ray path override it).
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray<C: Collector<f32>>(&self, ray: &Ray, set: u32, c: &mut C) -> bool {
        self.trace(&RayPacket::<f32>::splat(ray), set, c)
    }

    /// The records of the winners `w` of a traversal started at `set` (lanes whose winner is
    /// not this set's are a miss).
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L>;
}

/// A set of one kind of primitive, traced with a kernel given as a type parameter (see the
/// [module docs](self)).
pub trait Set {
    /// The primitive; [`Query::using`](crate::Query::using) accepts only its kernels.
    type Prim: Record;
    /// The kernel of a plain query.
    type Kernel: Kernel<Self::Prim>;

    /// As [`Trace::LEVEL_LANES`].
    const LEVEL_LANES: bool = true;

    /// As [`Trace::sets`].
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn sets(&self) -> u32 {
        1
    }

    /// [`Trace::trace`] with kernel `K`, culled by `cull`.
    fn trace_with<K: Kernel<Self::Prim>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool;

    /// [`Trace::trace_ray`] with kernel `K`, culled by `cull`.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray_with<K: Kernel<Self::Prim>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        self.trace_with::<K, f32, C>(cull, &RayPacket::splat(ray), set, c)
    }

    /// [`Trace::records`] of a query culled by `cull`.
    fn records_with<L: Lane>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        w: &Winners<L>,
    ) -> Hits<L>;
}

/// A set with kernel `K` and culling: made by [`Query::using`](crate::Query::using) and
/// [`Query::culled`](crate::Query::culled), traced like the set itself.
#[derive(Debug)]
pub struct Using<'a, S: ?Sized, K> {
    set: &'a S,
    cull: Cull,
    kernel: PhantomData<K>,
}

impl<S: ?Sized, K> Clone for Using<'_, S, K> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: ?Sized, K> Copy for Using<'_, S, K> {}

impl<'a, S: ?Sized, K> Using<'a, S, K> {
    /// `set` with kernel `K`, two-sided.
    #[inline]
    #[must_use]
    pub fn new(set: &'a S) -> Self {
        Using {
            set,
            cull: Cull::None,
            kernel: PhantomData,
        }
    }

    /// The same query culled: [`Cull::Back`] keeps front faces only (triangles: `d·N < 0`;
    /// spheres: entry roots, so a ray from inside misses; planes: `d·n < 0`).
    #[inline]
    #[must_use]
    pub fn culled(self, cull: Cull) -> Self {
        Using { cull, ..self }
    }

    /// The set.
    #[inline]
    #[must_use]
    pub fn set(&self) -> &'a S {
        self.set
    }
}

impl<S: Set + ?Sized> Trace for S {
    const LEVEL_LANES: bool = S::LEVEL_LANES;
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn sets(&self) -> u32 {
        Set::sets(self)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        self.trace_with::<S::Kernel, L, C>(Cull::None, rays, set, c)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray<C: Collector<f32>>(&self, ray: &Ray, set: u32, c: &mut C) -> bool {
        self.trace_ray_with::<S::Kernel, C>(Cull::None, ray, set, c)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        self.records_with(Cull::None, rays, set, w)
    }
}

impl<S: Set + ?Sized, K: Kernel<S::Prim>> Trace for Using<'_, S, K> {
    const LEVEL_LANES: bool = S::LEVEL_LANES;
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn sets(&self) -> u32 {
        Set::sets(self.set)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        self.set.trace_with::<K, L, C>(self.cull, rays, set, c)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray<C: Collector<f32>>(&self, ray: &Ray, set: u32, c: &mut C) -> bool {
        self.set.trace_ray_with::<K, C>(self.cull, ray, set, c)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        self.set.records_with(self.cull, rays, set, w)
    }
}

impl<S: Set + ?Sized> Set for &S {
    type Prim = S::Prim;
    type Kernel = S::Kernel;
    const LEVEL_LANES: bool = S::LEVEL_LANES;
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn sets(&self) -> u32 {
        (**self).sets()
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_with<K: Kernel<S::Prim>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        (**self).trace_with::<K, L, C>(cull, rays, set, c)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray_with<K: Kernel<S::Prim>, C: Collector<f32>>(
        &self,
        cull: Cull,
        ray: &Ray,
        set: u32,
        c: &mut C,
    ) -> bool {
        (**self).trace_ray_with::<K, C>(cull, ray, set, c)
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
        (**self).records_with(cull, rays, set, w)
    }
}

/// A set as a query with layer masks, an ignored set and a hit filter sees it (see
/// [`Screen`]): made by [`Filtered::new`], given [`mask`](Self::mask) (one per query) or
/// [`masks`](Self::masks) (one per ray lane), [`ignore`](Self::ignore) or
/// [`ignores`](Self::ignores), and [`filter`](Self::filter), and queried like the set itself,
/// for a ray, a packet or a tile. An instance whose mask shares no bit with a ray's is not
/// seen by that ray; a set that carries no masks counts as carrying every bit; a rejected
/// candidate is as if it did not exist (`closest` continues past it, `any` does not stop on
/// it, `all` does not report it).
///
/// ```
/// use raylane::glam::Vec3;
/// use raylane::set::Filtered;
/// use raylane::sphere::Sphere;
/// use raylane::{Query, Ray};
///
/// let balls = [Sphere::new(Vec3::new(0.0, 0.0, -3.0), 1.0), Sphere::new(Vec3::new(0.0, 0.0, -6.0), 1.0)];
/// let ray = Ray::new(Vec3::ZERO, Vec3::NEG_Z);
/// assert_eq!(balls.closest(&ray).unwrap().t, 2.0);
/// // Glass: sphere 0 lets the ray through; the closest hit is then sphere 1's.
/// let seen = Filtered::new(&balls[..]).filter(|c| c.index != 0);
/// assert_eq!(seen.closest(&ray).unwrap().t, 5.0);
/// // A filter rejecting entry roots (u = 0 for spheres) leaves the exit root of sphere 0.
/// let exits = Filtered::new(&balls[..]).filter(|c| c.u == 1.0);
/// assert_eq!(exits.closest(&ray).unwrap().t, 4.0);
/// // A query mask of 0 sees nothing.
/// assert!(!Filtered::new(&balls[..]).mask(0).any(&ray));
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Filtered<'a, T: ?Sized, F = Unfiltered> {
    set: &'a T,
    sight: Visibility,
    filter: F,
}

impl<'a, T: ?Sized> Filtered<'a, T> {
    /// `set` seen by every mask bit and no filter (the set's own answers).
    #[inline]
    #[must_use]
    pub fn new(set: &'a T) -> Self {
        Filtered {
            set,
            sight: Visibility::ALL,
            filter: Unfiltered,
        }
    }
}

impl<'a, T: ?Sized, F> Filtered<'a, T, F> {
    /// Every ray (every lane of a packet, every pixel of a tile) with the layer mask `mask`.
    #[inline]
    #[must_use]
    pub fn mask(self, mask: u32) -> Self {
        Filtered {
            sight: self.sight.mask(mask),
            ..self
        }
    }

    /// Lane `i` of a packet with the layer mask `masks[i]` (lanes past the slice: 0, nothing
    /// seen); a ray is lane 0, and every packet of a tile gets the same lanes.
    #[inline]
    #[must_use]
    pub fn masks(self, masks: &[u32]) -> Self {
        Filtered {
            sight: self.sight.masks(masks),
            ..self
        }
    }

    /// Every ray ignores the set `set` (a [`Hit::set`](crate::Hit::set): an instance of a
    /// scene, a member of a tuple): its candidates do not count, and a scene does not trace
    /// it ("ignore self").
    #[inline]
    #[must_use]
    pub fn ignore(self, set: u32) -> Self {
        Filtered {
            sight: self.sight.ignore(set),
            ..self
        }
    }

    /// Lane `i` of a packet ignores the set `sets[i]` (lanes past the slice ignore nothing).
    #[inline]
    #[must_use]
    pub fn ignores(self, sets: &[u32]) -> Self {
        Filtered {
            sight: self.sight.ignores(sets),
            ..self
        }
    }

    /// The same query with the filter `filter` (true to keep a candidate; see [`Filter`])
    /// instead of this one.
    #[inline]
    #[must_use]
    pub fn filter<G: Fn(&Candidate) -> bool>(self, filter: G) -> Filtered<'a, T, G> {
        Filtered {
            set: self.set,
            sight: self.sight,
            filter,
        }
    }

    /// The set.
    #[inline]
    #[must_use]
    pub fn set(&self) -> &'a T {
        self.set
    }
}

impl<T: Trace + ?Sized, F: Filter> Trace for Filtered<'_, T, F> {
    const LEVEL_LANES: bool = T::LEVEL_LANES;
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn sets(&self) -> u32 {
        self.set.sets()
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        let mut screen = Screen::new(c, &self.sight, &self.filter);
        self.set.trace(rays, set, &mut screen)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray<C: Collector<f32>>(&self, ray: &Ray, set: u32, c: &mut C) -> bool {
        let mut screen = Screen::new(c, &self.sight, &self.filter);
        self.set.trace_ray(ray, set, &mut screen)
    }
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        self.set.records(rays, set, w)
    }
}

/// Caller storage too small: `needed` entries are required (nothing was written). The one
/// error of every constructor that writes into caller storage (the focal caches; a BVH build
/// says which of its slices in [`BuildError`](crate::bvh::BuildError)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooSmall {
    /// The number of entries the storage must hold.
    pub needed: usize,
}

impl core::fmt::Display for TooSmall {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "caller storage too small: {} entries needed",
            self.needed
        )
    }
}

/// Empties the interval of the lanes outside `keep` (`t_min = +inf`, `t_max = −inf`).
#[inline(always)]
pub(crate) fn only<L: Lane>(rays: &RayPacket<L>, keep: L::Mask) -> RayPacket<L> {
    RayPacket {
        t_min: L::select(keep, rays.t_min, L::from_f32(f32::INFINITY)),
        t_max: L::select(keep, rays.t_max, L::from_f32(f32::NEG_INFINITY)),
        ..*rays
    }
}

/// The loop of every flat set: N rays × 1 primitive, `prims` in order (primitive `i` is the
/// `i`-th), kernel `K`, the lanes of `keep` only (the others keep an empty interval).
#[inline(always)]
pub(crate) fn flat<P: Record, K: Kernel<P>, L: Lane, C: Collector<L>>(
    rays: &RayPacket<L>,
    keep: L::Mask,
    cull: Cull,
    set: u32,
    c: &mut C,
    prims: impl IntoIterator<Item = P>,
) -> bool {
    let rays = admit(rays, K::UNIT_DIRECTIONS);
    let keep = keep & rays.valid();
    if keep.none() {
        return false;
    }
    let pre = K::prepare(&rays);
    let mut r = only(&rays, keep);
    let neg = L::from_f32(f32::NEG_INFINITY);
    // The collector's upper end changes only when it takes a candidate: read it then.
    r.t_max = L::select(keep, c.t_max(), neg);
    for (i, p) in prims.into_iter().enumerate() {
        let at = At {
            set,
            index: i as u32,
            loc: i as u32,
        };
        let packet = p.splat::<L>();
        let stop = if C::EACH {
            K::each(&r, &pre, &packet, cull, |h| {
                c.offer(h, at, |w| P::records(&rays, w, cull, |_| Some(p)))
            })
        } else {
            let Some(h) = K::first(&r, &pre, &packet, cull) else {
                continue;
            };
            if h.mask.none() {
                continue;
            }
            let stop = c.offer(&h, at, |w| P::records(&rays, w, cull, |_| Some(p)));
            r.t_max = L::select(keep, c.t_max(), neg);
            stop
        };
        if stop {
            return true;
        }
    }
    false
}

/// Bit `j` set when some lane of `rays` may hit `block[j]` (at most 64 primitives). The
/// primitives go in pairs with one branch per pair, not one per primitive: most pairs hold no
/// candidate, and the branch is most of the cost of a certain miss.
#[inline(always)]
fn candidates<L: Lane, E>(
    rays: &RayPacket<L>,
    block: &[E],
    candidate: &mut impl FnMut(&RayPacket<L>, &E) -> L::Mask,
) -> u64 {
    let mut bits = 0u64;
    let mut pairs = block.chunks_exact(2);
    let mut j = 0;
    for pair in &mut pairs {
        if let [p0, p1] = pair {
            let (m0, m1) = (candidate(rays, p0), candidate(rays, p1));
            if (m0 | m1).any() {
                bits |= ((m0.any() as u64) << j) | ((m1.any() as u64) << (j + 1));
            }
        }
        j += 2;
    }
    for p in pairs.remainder() {
        if candidate(rays, p).any() {
            bits |= 1 << j;
        }
    }
    bits
}

/// The loop of the focal caches: `test(rays, i, entry, c)` for the entries in order, in two
/// passes per block of 64 — `candidate` (a kernel's cheap first step, with no calls, so the
/// rays stay in registers) gives the lanes that may hit each entry, then `test` runs on the
/// entries some lane may hit. `test` must miss wherever `candidate` has no lane, and
/// `candidate` must not depend on `t_max`. `test` returns `None` when it offered nothing,
/// else whether `c` asked to stop. The lanes of `keep` get `c`'s `t_max` (read again after
/// each offer, the only time it changes), the others an empty interval. One lane takes a
/// single pass (LLVM turns a one-lane first pass into gathers across entries, 4× slower on
/// x86-64). Returns true when `c` asked to stop.
#[inline(always)]
pub(crate) fn filtered<L: Lane, E, C: Collector<L>>(
    rays: &RayPacket<L>,
    keep: L::Mask,
    entries: &[E],
    c: &mut C,
    mut candidate: impl FnMut(&RayPacket<L>, &E) -> L::Mask,
    mut test: impl FnMut(&RayPacket<L>, usize, &E, &mut C) -> Option<bool>,
) -> bool {
    let mut r = only(rays, keep);
    let neg = L::from_f32(f32::NEG_INFINITY);
    r.t_max = L::select(keep, c.t_max(), neg);
    // A function, not a let-bound closure, which may be left out of line (crate::simd).
    #[inline(always)]
    fn one<L: Lane, E, C: Collector<L>>(
        test: &mut impl FnMut(&RayPacket<L>, usize, &E, &mut C) -> Option<bool>,
        (keep, neg): (L::Mask, L),
        r: &mut RayPacket<L>,
        i: usize,
        e: &E,
        c: &mut C,
    ) -> bool {
        match test(r, i, e, c) {
            None => false,
            Some(stop) => {
                r.t_max = L::select(keep, c.t_max(), neg);
                stop
            }
        }
    }
    if L::LANES == 1 {
        for (i, e) in entries.iter().enumerate() {
            if one(&mut test, (keep, neg), &mut r, i, e, c) {
                return true;
            }
        }
        return false;
    }
    for (b, block) in entries.chunks(64).enumerate() {
        let mut bits = candidates(&r, block, &mut candidate);
        while bits != 0 {
            let j = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if let Some(e) = block.get(j)
                && one(&mut test, (keep, neg), &mut r, b * 64 + j, e, c)
            {
                return true;
            }
        }
    }
    false
}

impl Set for [Sphere] {
    type Prim = Sphere;
    type Kernel = Robust;
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_with<K: Kernel<Sphere>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        let all = Mask::splat(true);
        flat::<Sphere, K, L, C>(rays, all, cull, set, c, self.iter().copied())
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
        Sphere::records(
            rays,
            &mine(w, set),
            cull,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |loc| self.get(loc as usize).copied(),
        )
    }
}

impl Set for [Triangle] {
    type Prim = Triangle;
    type Kernel = Watertight;
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_with<K: Kernel<Triangle>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        let all = Mask::splat(true);
        flat::<Triangle, K, L, C>(rays, all, cull, set, c, self.iter().copied())
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
        Triangle::records(
            rays,
            &mine(w, set),
            cull,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |loc| self.get(loc as usize).copied(),
        )
    }
}

impl Set for [Plane] {
    type Prim = Plane;
    type Kernel = PlaneTest;
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_with<K: Kernel<Plane>, L: Lane, C: Collector<L>>(
        &self,
        cull: Cull,
        rays: &RayPacket<L>,
        set: u32,
        c: &mut C,
    ) -> bool {
        let all = Mask::splat(true);
        flat::<Plane, K, L, C>(rays, all, cull, set, c, self.iter().copied())
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
        Plane::records(
            rays,
            &mine(w, set),
            cull,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |loc| self.get(loc as usize).copied(),
        )
    }
}

/// The winners of `w` whose set is `set` (the others cleared).
#[inline(always)]
pub(crate) fn mine<L: Lane>(w: &Winners<L>, set: u32) -> Winners<L> {
    owned(w, set, 1)
}

/// The winners of `w` whose set lies in `set..set + n` (the others cleared).
#[inline(always)]
pub(crate) fn owned<L: Lane>(w: &Winners<L>, set: u32, n: u32) -> Winners<L> {
    let mut mask = w.mask;
    let mut bits = w.mask.bits();
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let s = w.set.as_ref().get(i).copied().unwrap_or(u32::MAX);
        if s.wrapping_sub(set) >= n {
            mask = mask.with_lane(i, false);
        }
    }
    Winners { mask, ..*w }
}

/// `a` in the lanes of `m`, `b` elsewhere.
#[inline(always)]
pub(crate) fn select_hits<L: Lane>(m: L::Mask, a: &Hits<L>, b: &Hits<L>) -> Hits<L> {
    let pick = |x: &L::Indices, y: &L::Indices| {
        let mut out = *y;
        let mut bits = m.bits();
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if let (Some(o), Some(v)) = (out.as_mut().get_mut(i), x.as_ref().get(i)) {
                *o = *v;
            }
        }
        out
    };
    Hits {
        t: L::select(m, a.t, b.t),
        point: crate::vec3::V3::select(m, a.point, b.point),
        normal: crate::vec3::V3::select(m, a.normal, b.normal),
        front: (m & a.front) | b.front.and_not(m),
        index: pick(&a.index, &b.index),
        set: pick(&a.set, &b.set),
        u: L::select(m, a.u, b.u),
        v: L::select(m, a.v, b.v),
        mask: (m & a.mask) | b.mask.and_not(m),
    }
}

/// Tuples of sets as one scene: member `k` is traced as the sets after those of members
/// `0..k` (its position, for members of one set each), in order; a hit of a later member wins
/// only when strictly closer (the tie rule's lower set).
macro_rules! tuple {
    ($($q:ident $i:tt),+) => {
        impl<$($q: Trace),+> Trace for ($($q,)+) {
            const LEVEL_LANES: bool = true $(&& $q::LEVEL_LANES)+;
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            #[cfg_attr(not(target_arch = "x86_64"), inline)]
            fn sets(&self) -> u32 {
                0 $(+ self.$i.sets())+
            }

            #[cfg_attr(target_arch = "x86_64", inline(always))]
            #[cfg_attr(not(target_arch = "x86_64"), inline)]
            fn trace<L: Lane, Co: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut Co) -> bool {
                let mut base = set;
                $(
                    if self.$i.trace(rays, base, c) {
                        return true;
                    }
                    base += self.$i.sets();
                )+
                let _ = base;
                false
            }

            #[cfg_attr(target_arch = "x86_64", inline(always))]
            #[cfg_attr(not(target_arch = "x86_64"), inline)]
            fn trace_ray<Co: Collector<f32>>(&self, ray: &Ray, set: u32, c: &mut Co) -> bool {
                let mut base = set;
                $(
                    if self.$i.trace_ray(ray, base, c) {
                        return true;
                    }
                    base += self.$i.sets();
                )+
                let _ = base;
                false
            }

            fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
                let mut out = Hits::miss();
                let mut base = set;
                $(
                    let n = self.$i.sets();
                    let own = owned(w, base, n);
                    if own.mask.any() {
                        out = select_hits(own.mask, &self.$i.records(rays, base, &own), &out);
                    }
                    base += n;
                )+
                let _ = base;
                out
            }
        }
    };
}

tuple!(A 0, B 1);
tuple!(A 0, B 1, C 2);
tuple!(A 0, B 1, C 2, D 3);

/// A slice of sets as one scene, like a tuple of any length: member `k` is traced as the sets
/// after those of members `0..k` (its index, for members of one set each, such as
/// [`Mesh`](crate::mesh::Mesh) or [`FocalMesh`](crate::focal::FocalMesh)), in order; a hit of
/// a later member wins only when strictly closer (the tie rule's lower set). A mesh split into
/// parts with a bounding sphere each is one query over the parts:
///
/// ```
/// use raylane::glam::Vec3;
/// use raylane::mesh::Mesh;
/// use raylane::set::Sets;
/// use raylane::{Query, Ray};
///
/// let positions = [Vec3::new(-1.0, -1.0, -2.0), Vec3::new(1.0, -1.0, -2.0),
///                  Vec3::new(0.0, 1.0, -2.0)];
/// let near = [[0, 1, 2]];
/// let far: Vec<Vec3> = positions.iter().map(|p| *p - Vec3::Z).collect();
/// let parts = [Mesh::bounded(&far, &near), Mesh::bounded(&positions, &near)];
/// let hit = Sets(&parts).closest(&Ray::new(Vec3::ZERO, -Vec3::Z)).unwrap();
/// assert_eq!((hit.set, hit.index, hit.t), (1, 0, 2.0));
/// ```
///
/// (A slice itself is not a [`Trace`]: `[Sphere]` and `[Triangle]` are sets of primitives.)
#[derive(Debug)]
pub struct Sets<'a, T>(pub &'a [T]);

impl<T> Clone for Sets<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Sets<'_, T> {}

impl<T: Trace> Trace for Sets<'_, T> {
    const LEVEL_LANES: bool = T::LEVEL_LANES;
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn sets(&self) -> u32 {
        self.0.iter().map(Trace::sets).sum()
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        let mut base = set;
        for m in self.0 {
            if m.trace(rays, base, c) {
                return true;
            }
            base += m.sets();
        }
        false
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace_ray<C: Collector<f32>>(&self, ray: &Ray, set: u32, c: &mut C) -> bool {
        let mut base = set;
        for m in self.0 {
            if m.trace_ray(ray, base, c) {
                return true;
            }
            base += m.sets();
        }
        false
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        // One pass over the members, asking only those that own a winner: `next` is the
        // lowest set among the winners not yet recorded.
        let lowest = |mask: L::Mask| {
            let mut bits = mask.bits();
            let mut low = u32::MAX;
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                low = low.min(w.set.as_ref().get(i).copied().unwrap_or(u32::MAX));
            }
            low
        };
        let mut out = Hits::miss();
        let mut left = w.mask;
        let mut next = lowest(left);
        let mut base = set;
        for m in self.0 {
            if !left.any() {
                break;
            }
            let n = m.sets();
            if next.wrapping_sub(base) < n {
                let own = owned(w, base, n);
                out = select_hits(own.mask, &m.records(rays, base, &own), &out);
                left = left.and_not(own.mask);
                next = lowest(left);
            }
            base += n;
        }
        out
    }
}
