//! Hit records and the loops shared by every primitive: closest hit, any hit.
//!
//! A kernel tests ray lanes against primitive lanes and reports a [`LaneHit`]: the parameter
//! `t`, two surface parameters `u`, `v` (barycentrics for triangles, zero otherwise) and the
//! lanes that hit. The loops here run a kernel over a slice of primitives:
//!
//! * **N rays × 1 primitive** (`closest`, `any`): the primitive is splatted into every lane
//!   and the rays' `t_max` shrinks as hits are found, so later primitives must be closer;
//! * **1 ray × N primitives** (`closest_soa`, `any_soa`): primitives sit in lanes (structure
//!   of arrays), the ray is splatted, and the lanes are reduced at the end.
//!
//! Both shapes return the same hit, bit for bit, whatever the order the primitives are visited
//! in: a candidate is taken only when its rounded `t` is strictly below the best so far (ties
//! go to the lowest primitive index), and after each hit the rays' `t_max` is relaxed to
//! `t + |t|·2^-21` rather than set to `t`. A kernel may then reject `t ≥ t_max` before its
//! division as `num < t_max·den` (one multiply, rounded): the relaxation makes that test
//! conservative, so no would-be winner is dropped and the division runs only for the hits that
//! win so far.
//!
//! Kernels with a deferred division report `u`, `v` unscaled with their denominator (see
//! [`LaneHit::deferred`]); the loops divide once per ray, for the winner, and every record a
//! caller sees is normalised.
//!
//! Misses are canonical: `t = +inf`, `u = v = 0`, index `u32::MAX`. No record ever holds a NaN,
//! and none holds `−0`: records carry `+0`.

use crate::lane::{Lane, Mask, Scalar, select_indices};
use crate::ray::{Ray, RayPacket};

/// One lane-wise test result (see the [module docs](self)).
#[derive(Clone, Copy, Debug)]
pub struct LaneHit<L: Lane> {
    /// Ray parameter of the hit; `+inf` where `mask` is clear.
    pub t: L,
    /// First surface parameter (barycentric weight of vertex B for triangles).
    pub u: L,
    /// Second surface parameter (barycentric weight of vertex C for triangles).
    pub v: L,
    /// Lanes that hit inside the ray interval.
    pub mask: L::Mask,
    /// Denominator of `u` and `v` while a query runs (1 once normalised).
    pub(crate) w: L,
}

impl<L: Lane> LaneHit<L> {
    /// No lane hits.
    #[inline(always)]
    #[must_use]
    pub fn miss() -> Self {
        let zero = L::from_f32(0.0);
        LaneHit {
            t: L::from_f32(f32::INFINITY),
            u: zero,
            v: zero,
            mask: Mask::splat(false),
            w: L::from_f32(1.0),
        }
    }

    /// Canonicalises: lanes outside `mask` get `t = +inf`, `u = v = 0`.
    #[inline(always)]
    #[must_use]
    pub fn new(t: L, u: L, v: L, mask: L::Mask) -> Self {
        Self::deferred(t, u, v, L::from_f32(1.0), mask)
    }

    /// A hit whose barycentrics are `u/w`, `v/w`: the division is left to the loops, which do
    /// it once per ray for the winner ([`normalized`](Self::normalized)).
    #[inline(always)]
    #[must_use]
    pub fn deferred(t: L, u: L, v: L, w: L, mask: L::Mask) -> Self {
        let zero = L::from_f32(0.0);
        LaneHit {
            t: L::select(mask, t, L::from_f32(f32::INFINITY)),
            u: L::select(mask, u, zero),
            v: L::select(mask, v, zero),
            mask,
            w: L::select(mask, w, L::from_f32(1.0)),
        }
    }

    /// `u/w`, `v/w` (2 div): the record as callers see it, with `−0` made `+0` in `t`, `u`,
    /// `v` (`x + 0`).
    #[inline(always)]
    #[must_use]
    pub fn normalized(self) -> Self {
        LaneHit {
            t: plus_zero(self.t),
            u: plus_zero(self.u / self.w),
            v: plus_zero(self.v / self.w),
            w: L::from_f32(1.0),
            ..self
        }
    }
}

impl LaneHit<f32> {
    /// The scalar record (index 0), or `None` on a miss. `u`, `v` as stored: normalise first
    /// where they are deferred.
    #[inline(always)]
    #[must_use]
    pub fn record(self) -> Option<HitRecord> {
        self.mask.then_some(HitRecord {
            t: self.t,
            u: self.u,
            v: self.v,
            index: 0,
        })
    }
}

/// The closest hit per lane over a set of primitives, with the primitive's index: the state of
/// the closest-hit loops, finished into [`Hits`](crate::Hits) by the queries.
#[derive(Clone, Copy, Debug)]
pub struct Best<L: Lane> {
    /// Ray parameter; `+inf` where `mask` is clear.
    pub t: L,
    /// First surface parameter (barycentric weight of B for triangles).
    pub u: L,
    /// Second surface parameter (barycentric weight of C for triangles).
    pub v: L,
    /// Index of the primitive hit in each lane (`u32::MAX` where `mask` is clear).
    pub index: L::Indices,
    /// Lanes that hit.
    pub mask: L::Mask,
    /// Denominator of `u` and `v` while a query runs (1 once finished).
    pub(crate) w: L,
}

/// One hit of one ray, as the scalar API reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitRecord {
    /// Ray parameter: the point is `origin + t·dir`.
    pub t: f32,
    /// First surface parameter (barycentric weight of B for triangles; 0 otherwise).
    pub u: f32,
    /// Second surface parameter (barycentric weight of C for triangles; 0 otherwise).
    pub v: f32,
    /// Index of the primitive in the slice that was searched.
    pub index: u32,
}

impl<L: Lane> Best<L> {
    /// No hit in any lane.
    #[inline]
    #[must_use]
    pub fn miss() -> Self {
        let m = LaneHit::<L>::miss();
        Best {
            t: m.t,
            u: m.u,
            v: m.v,
            index: L::indices(u32::MAX),
            mask: m.mask,
            w: m.w,
        }
    }

    /// Lane `i` as a scalar record, or `None` when it missed.
    #[inline]
    #[must_use]
    pub fn lane(&self, i: usize) -> Option<HitRecord>
    where
        L: Lane<Scalar = f32>,
    {
        self.mask.test(i).then(|| HitRecord {
            t: self.t.lane(i),
            u: self.u.lane(i),
            v: self.v.lane(i),
            index: self.index.as_ref()[i],
        })
    }

    /// The finished record of one candidate `h` of primitive `index` (for queries that report
    /// every hit).
    #[inline(always)]
    #[must_use]
    pub(crate) fn single(h: &LaneHit<L>, index: u32) -> Self {
        let mut b = Self::miss();
        b.take(h, h.mask, index);
        b.finish()
    }

    /// Takes the hits of `h` in the lanes of `take` for primitive `index`.
    #[inline(always)]
    pub(crate) fn take(&mut self, h: &LaneHit<L>, take: L::Mask, index: u32) {
        self.t = L::select(take, h.t, self.t);
        self.u = L::select(take, h.u, self.u);
        self.v = L::select(take, h.v, self.v);
        self.w = L::select(take, h.w, self.w);
        self.mask = self.mask | take;
        select_indices::<L>(take, index, &mut self.index);
    }

    /// Divides the winners' barycentrics by their denominators (once per ray), with `−0`
    /// made `+0` in `t`, `u`, `v` (`x + 0`).
    #[inline(always)]
    pub(crate) fn finish(mut self) -> Self {
        self.t = plus_zero(self.t);
        self.u = plus_zero(self.u / self.w);
        self.v = plus_zero(self.v / self.w);
        self.w = L::from_f32(1.0);
        self
    }
}

/// `x + 0`: `−0` becomes `+0` (IEEE round-to-nearest), every other value (NaN aside) is
/// unchanged. Kernels that fold a sign into their numerators (`select(back, −x, x)`) return
/// `−0` for a zero barycentric on a back face, or for `t = 0`; records carry `+0`, so that
/// `u == 0.0` and the bits agree whichever side a ray comes from. One add per field, at the
/// one place records are made (never in a kernel's counted path).
#[inline(always)]
fn plus_zero<L: Lane>(x: L) -> L {
    x + L::from_f32(0.0)
}

/// Lanes of `h` strictly closer than `best` (ties keep the earlier, lower-index hit).
#[inline(always)]
fn closer<L: Lane>(h: &LaneHit<L>, best: &Best<L>) -> L::Mask {
    h.mask & h.t.lt(best.t)
}

/// The relaxed upper end after a hit at `t`: `t + |t|·2^-21` (> t after rounding), so that a
/// kernel's rounded `num < t_max·den` never rejects a hit that rounds below `t`.
#[inline(always)]
pub(crate) fn relax<L: Lane>(t: L) -> L {
    t + t.abs() * L::from_f32(1.0 / 2_097_152.0)
}

impl Best<f32> {
    /// The record, or `None` for a miss.
    #[inline]
    #[must_use]
    pub fn get(&self) -> Option<HitRecord> {
        self.lane(0)
    }
}

/// Closest hit of ray lanes over primitives tested one at a time (N rays × 1 primitive).
///
/// `test` sees the rays with `t_max` already shrunk to the closest hit so far, so it reports
/// only closer hits; it returns `None` when no lane can hit (a kernel's early exit), which lets
/// the miss path skip the merge with the hit path entirely.
#[inline]
pub(crate) fn closest<L: Lane, P>(
    rays: &RayPacket<L>,
    prims: impl IntoIterator<Item = P>,
    mut test: impl FnMut(&RayPacket<L>, P) -> Option<LaneHit<L>>,
) -> Best<L> {
    let mut r = *rays;
    let mut best = Best::miss();
    for (i, p) in prims.into_iter().enumerate() {
        // `None`: no lane passed the kernel's first test (nothing to merge on the miss path).
        if let Some(h) = test(&r, p) {
            let take = closer(&h, &best);
            if take.any() {
                best.take(&h, take, i as u32);
                r = r.shrink(take, relax(h.t));
            }
        }
    }
    best.finish()
}

/// True in lanes where some primitive is hit (occlusion); stops when every valid lane is hit.
#[inline]
pub(crate) fn any<L: Lane, P>(
    rays: &RayPacket<L>,
    prims: impl IntoIterator<Item = P>,
    mut test: impl FnMut(&RayPacket<L>, P) -> Option<LaneHit<L>>,
) -> L::Mask {
    let valid = rays.valid();
    let mut hit = L::Mask::splat(false);
    for p in prims {
        if let Some(h) = test(rays, p) {
            hit = hit | h.mask;
        }
        if valid.and_not(hit).none() {
            break;
        }
    }
    hit & valid
}

/// Bit `j` set when some lane of `rays` may hit `block[j]` (at most 64 primitives). The
/// primitives go in pairs with one branch per pair, not one per primitive: most pairs hold no
/// candidate, and the branch is most of the cost of a certain miss.
#[inline(always)]
fn candidates<L: Lane, P>(
    rays: &RayPacket<L>,
    block: &[P],
    candidate: &mut impl FnMut(&RayPacket<L>, &P) -> L::Mask,
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

/// [`closest`] in two passes per block of 64 primitives: `candidate` (a kernel's cheap first
/// step, with no calls, so the rays stay in registers) gives the lanes that may hit each
/// primitive, then `test` runs on the primitives some lane may hit, in order. Same result as
/// [`closest`] with `test`, provided `test` returns `None` wherever `candidate` has no lane
/// set and `candidate` does not depend on `t_max`.
///
/// One lane takes a single pass ([`closest`]): `test` stops where the first pass would, and
/// LLVM turns a one-lane first pass into gathers across primitives (4× slower on x86-64).
#[inline]
pub(crate) fn closest_filtered<L: Lane, P>(
    rays: &RayPacket<L>,
    prims: &[P],
    mut candidate: impl FnMut(&RayPacket<L>, &P) -> L::Mask,
    mut test: impl FnMut(&RayPacket<L>, &P) -> Option<LaneHit<L>>,
) -> Best<L> {
    if L::LANES == 1 {
        return closest(rays, prims, test);
    }
    let mut r = *rays;
    let mut best = Best::miss();
    for (b, block) in prims.chunks(64).enumerate() {
        let mut bits = candidates(&r, block, &mut candidate);
        while bits != 0 {
            let j = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if let Some(h) = block.get(j).and_then(|p| test(&r, p)) {
                let take = closer(&h, &best);
                if take.any() {
                    best.take(&h, take, (b * 64 + j) as u32);
                    r = r.shrink(take, relax(h.t));
                }
            }
        }
    }
    best.finish()
}

/// [`any`] in two passes per block of 64 primitives (one lane: a single pass), as
/// [`closest_filtered`].
#[inline]
pub(crate) fn any_filtered<L: Lane, P>(
    rays: &RayPacket<L>,
    prims: &[P],
    mut candidate: impl FnMut(&RayPacket<L>, &P) -> L::Mask,
    mut test: impl FnMut(&RayPacket<L>, &P) -> Option<LaneHit<L>>,
) -> L::Mask {
    if L::LANES == 1 {
        return any(rays, prims, test);
    }
    let valid = rays.valid();
    let mut hit = L::Mask::splat(false);
    for block in prims.chunks(64) {
        let mut bits = candidates(rays, block, &mut candidate);
        while bits != 0 {
            let j = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if let Some(h) = block.get(j).and_then(|p| test(rays, p)) {
                hit = hit | h.mask;
                if valid.and_not(hit).none() {
                    return hit & valid;
                }
            }
        }
    }
    hit & valid
}

/// Closest hit of one ray over primitives stored `L::LANES` to a chunk (1 ray × N primitives).
///
/// `test` gets the ray splatted into lanes (with per-lane shrinking `t_max`) and the chunk
/// index; primitive `j` of chunk `c` has index `c·L::LANES + j`. Lanes past `count` must miss
/// (padding), which the primitive packets guarantee.
#[inline]
pub(crate) fn closest_soa<L: Lane, P>(
    ray: &Ray,
    chunks: impl IntoIterator<Item = P>,
    mut test: impl FnMut(&RayPacket<L>, P) -> Option<LaneHit<L>>,
) -> Option<HitRecord>
where
    L::Scalar: Scalar,
{
    let mut r = RayPacket::<L>::splat(ray);
    let mut best = Best::<L>::miss();
    for (c, p) in chunks.into_iter().enumerate() {
        let Some(h) = test(&r, p) else { continue };
        let take = closer(&h, &best);
        if take.any() {
            let mut bits = take.bits();
            while bits != 0 {
                let j = bits.trailing_zeros() as usize;
                if let Some(slot) = best.index.as_mut().get_mut(j) {
                    *slot = (c * L::LANES + j) as u32;
                }
                bits &= bits - 1;
            }
            best.t = L::select(take, h.t, best.t);
            best.u = L::select(take, h.u, best.u);
            best.v = L::select(take, h.v, best.v);
            best.w = L::select(take, h.w, best.w);
            best.mask = best.mask | take;
            r = r.shrink(take, relax(h.t));
        }
    }
    let best = best.finish();
    // Reduce across lanes: smallest t, ties to the lowest index.
    let mut out: Option<HitRecord> = None;
    for j in 0..L::LANES {
        if !best.mask.test(j) {
            continue;
        }
        let rec = HitRecord {
            t: best.t.lane(j).to_f64() as f32,
            u: best.u.lane(j).to_f64() as f32,
            v: best.v.lane(j).to_f64() as f32,
            index: best.index.as_ref()[j],
        };
        out = match out {
            Some(o) if o.t < rec.t || (o.t == rec.t && o.index < rec.index) => Some(o),
            _ => Some(rec),
        };
    }
    out
}

/// True when one ray hits some primitive stored in lanes (1 ray × N primitives).
#[inline]
pub(crate) fn any_soa<L: Lane, P>(
    ray: &Ray,
    chunks: impl IntoIterator<Item = P>,
    mut test: impl FnMut(&RayPacket<L>, P) -> Option<LaneHit<L>>,
) -> bool {
    let r = RayPacket::<L>::splat(ray);
    chunks
        .into_iter()
        .any(|p| test(&r, p).is_some_and(|h| h.mask.any()))
}
