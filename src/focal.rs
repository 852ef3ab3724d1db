//! Sets cached for one eye: a [`FocalMesh`], [`FocalSpheres`] and [`FocalPlanes`], built once
//! per eye into caller storage and queried like the sets they were made from.
//!
//! Primary rays of a camera all start at its eye `E`; the focal kernels keep per primitive
//! what does not change from ray to ray (lecture 000, "Rays from Focal Point"): the triangles'
//! edge normals relative to `E` ([`FocalTriangle`]), the spheres' `C − E` and thresholds
//! ([`FocalSphere`]), the planes' numerators `(a − E)·n` ([`FocalPlane`]).
//!
//! **One contract.** A focal set answers every ray. Rays from its eye (origin equal to `E`,
//! bit for bit; for spheres also with a unit direction, `||d|² − 1| ≤ 2^-20`) are answered by
//! the focal kernel; every other ray, or lane of a packet, is answered by the set it was
//! made from with that set's default kernel ([`Watertight`], [`Robust`], the plane test), the
//! same bits as asking that set. Both
//! follow the same interval, tie rule and records ([`crate::hit`]).
//!
//! **Storage.** `needed(set)` says how many entries the cache needs; `new(set, eye, storage)`
//! fills them and returns the set, or [`TooSmall`] when the storage is short (nothing is
//! written). A focal set borrows its cache and its source set.
//!
//! ```
//! use raylane::focal::FocalMesh;
//! use raylane::glam::Vec3;
//! use raylane::mesh::Mesh;
//! use raylane::triangle::FocalTriangle;
//! use raylane::{Query, Ray};
//!
//! let positions = [Vec3::new(-1.0, -1.0, -5.0), Vec3::new(1.0, -1.0, -5.0), Vec3::new(0.0, 1.0, -5.0)];
//! let indices = [[0u32, 1, 2]];
//! let mesh = Mesh::new(&positions, &indices);
//! let mut cache = [FocalTriangle::never(); 1];
//! assert_eq!(FocalMesh::new(&mesh, Vec3::ZERO, &mut []).unwrap_err().needed, 1);
//! let focal = FocalMesh::new(&mesh, Vec3::ZERO, &mut cache).unwrap();
//! let from_eye = focal.closest(&Ray::new(Vec3::ZERO, Vec3::NEG_Z)).unwrap();
//! assert_eq!((from_eye.t, from_eye.index), (5.0, 0));
//! // A ray from elsewhere gets the mesh's own answer.
//! let other = Ray::new(Vec3::new(0.0, 0.0, 1.0), Vec3::NEG_Z);
//! assert_eq!(focal.closest(&other), mesh.closest(&other));
//! ```

use glam::Vec3;

use crate::hit::{At, Closest, Collector, Hits, Record, Winners};
use crate::kernel::{Cull, LaneHit};
use crate::lane::{Lane, Mask};
use crate::mesh::Mesh;
use crate::plane::{FocalPlane, Plane, PlaneTest};
use crate::ray::{RayPacket, UNIT_TOLERANCE};
use crate::set::{Set, TooSmall, Trace, filtered, flat, mine, only};
use crate::sphere::focal::{Focal, FocalKernel, Splat};
use crate::sphere::{FocalSphere, Robust, Sphere, each_root, first_root};
use crate::triangle::focal::{self as tf, FocalRays, FocalTriangle};
use crate::triangle::{Triangle, Watertight};
use crate::vec3::V3;

/// The valid lanes whose origin is exactly `eye` (6 cmp).
#[inline(always)]
fn at_eye<L: Lane>(rays: &RayPacket<L>, eye: Vec3) -> L::Mask {
    let e = V3::<L>::splat(eye);
    let o = rays.origin;
    let same = o.x.ge(e.x) & o.x.le(e.x) & o.y.ge(e.y) & o.y.le(e.y) & o.z.ge(e.z) & o.z.le(e.z);
    same & rays.valid()
}

/// Offers the finished winners `w` of a sub-query (one set, `t` given in the rays' own units)
/// to `c`, one primitive index at a time.
#[inline(always)]
fn offer_winners<L: Lane, C: Collector<L>>(c: &mut C, w: &Winners<L>, t: L, set: u32) -> bool {
    let mut left = w.mask;
    while left.any() {
        let j = left.bits().trailing_zeros() as usize;
        let at_j = |x: &L::Indices| x.as_ref().get(j).copied().unwrap_or(u32::MAX);
        let (index, loc) = (at_j(&w.index), at_j(&w.loc));
        let mut same = L::Mask::splat(false);
        let mut bits = left.bits();
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if w.index.as_ref().get(k) == Some(&index) {
                same = same.with_lane(k, true);
            }
        }
        left = left.and_not(same);
        let h = LaneHit::new(t, w.u, w.v, same);
        if c.offer(&h, At { set, index, loc }, |_| Hits::miss()) {
            return true;
        }
    }
    false
}

/// A mesh's focal cache for one eye, with its bounding sphere as a [`FocalSphere`] tested
/// first (see the [module docs](self)).
#[derive(Clone, Copy, Debug)]
pub struct FocalMesh<'c> {
    mesh: Mesh<'c>,
    cache: &'c [FocalTriangle<f32>],
    bound: Option<FocalSphere<f32>>,
    eye: Vec3,
    cull: Cull,
}

impl<'c> FocalMesh<'c> {
    /// The entries [`new`](Self::new) needs for `mesh`: one per triangle.
    #[inline]
    #[must_use]
    pub fn needed(mesh: &Mesh) -> usize {
        mesh.len()
    }

    /// Builds the entry of every triangle of `mesh` for rays from `eye` into `out` (entry `i`
    /// for triangle `i`, from the shared positions, which makes shared edges watertight;
    /// invalid triangles get entries that are never hit).
    ///
    /// # Errors
    ///
    /// [`TooSmall`] when `out` is shorter than [`needed`](Self::needed) (nothing is written).
    pub fn new(
        mesh: &Mesh<'c>,
        eye: Vec3,
        out: &'c mut [FocalTriangle<f32>],
    ) -> Result<Self, TooSmall> {
        let needed = Self::needed(mesh);
        let Some(out) = out.get_mut(..needed) else {
            return Err(TooSmall { needed });
        };
        for (i, slot) in out.iter_mut().enumerate() {
            *slot = match mesh.triangle(i) {
                Some(t) => FocalTriangle::new(eye, &t),
                None => FocalTriangle::never(),
            };
        }
        Ok(FocalMesh {
            mesh: *mesh,
            cache: out,
            bound: mesh.bound().map(|b| b.focal(eye)),
            eye,
            cull: Cull::None,
        })
    }

    /// The eye.
    #[inline]
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The entries (entry `i` for triangle `i`).
    #[inline]
    #[must_use]
    pub fn cache(&self) -> &'c [FocalTriangle<f32>] {
        self.cache
    }

    /// The mesh it was made from.
    #[inline]
    #[must_use]
    pub fn mesh(&self) -> &Mesh<'c> {
        &self.mesh
    }

    /// The same set with its queries culled ([`Cull::Back`]: front faces only).
    #[inline]
    #[must_use]
    pub fn culled(self, cull: Cull) -> Self {
        FocalMesh { cull, ..self }
    }

    /// The lanes of rays from the eye (prepared) the bounding sphere cannot exclude (every
    /// lane without a bound): the guarded focal sphere test's first step on the unit
    /// directions, `v² > k_lo` with `v = T·U` (4 mul, 2 add, 1 cmp). Over the whole line, the
    /// cached `k_lo` (`c² − r²` lowered by its rounding bound) makes a rejected lane a certain
    /// miss, and an eye inside the sphere (`k_lo < 0`) rejects none.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    #[must_use]
    pub fn may_hit<L: Lane>(&self, rays: &FocalRays<L>) -> L::Mask {
        match &self.bound {
            Some(b) => Focal::candidate(&rays.unit_lines(), &Splat(b)),
            None => Mask::splat(true),
        }
    }

    /// The lanes `at` (from the eye) through the focal kernel.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn focal<L: Lane, C: Collector<L>>(
        &self,
        rays: &RayPacket<L>,
        at: L::Mask,
        set: u32,
        c: &mut C,
    ) -> bool {
        let r = RayPacket {
            t_max: c.t_max(),
            ..*rays
        };
        let fr = FocalRays::new(&only(&r, at));
        let keep = self.may_hit(&fr) & fr.scaled().valid();
        if keep.none() {
            return false;
        }
        let scaled = only(fr.scaled(), keep);
        let cull = self.cull;
        if C::EVERY {
            for (i, e) in self.cache.iter().enumerate() {
                let h = tf::kernel(&scaled, &tf::Splat(e), cull);
                if h.mask.any() {
                    let at = At {
                        set,
                        index: i as u32,
                        loc: i as u32,
                    };
                    let record = |w: &Winners<L>| {
                        Triangle::records(rays, w, cull, |_| Some(self.mesh.prepared(i)))
                    };
                    if c.offer(&fr.unscale(h), at, record) {
                        return true;
                    }
                }
            }
            return false;
        }
        // The closest hit in the kernel's units, then offered in the rays' own.
        let mut inner = Closest::new(&scaled);
        filtered(
            &scaled,
            keep,
            self.cache,
            &mut inner,
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |r, e| tf::candidate(r, &tf::Splat(e), cull),
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            |r, i, e, inner| {
                let h = tf::maybe_hit(r, &tf::Splat(e), cull)?;
                let at = At {
                    set,
                    index: i as u32,
                    loc: i as u32,
                };
                h.mask.any().then(|| inner.offer(&h, at, |_| Hits::miss()))
            },
        );
        let w = inner.finish();
        offer_winners(c, &w, fr.own_units(w.t), set)
    }
}

/// Focal meshes (see the [module docs](self)): rays from the eye are culled by the bound and
/// tested against the entries in index order (two passes per block of 64: the edge signs
/// first); others go to the mesh.
impl Trace for FocalMesh<'_> {
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        let at = at_eye(rays, self.eye);
        if at.any() && self.focal(rays, at, set, c) {
            return true;
        }
        let other = rays.valid().and_not(at);
        other.any()
            && self
                .mesh
                .trace_with::<Watertight, L, C>(self.cull, &only(rays, other), set, c)
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        self.mesh.records_with(self.cull, rays, set, w)
    }
}

/// A guarded sphere cache for one eye (see the [module docs](self)).
#[derive(Clone, Copy, Debug)]
pub struct FocalSpheres<'c> {
    spheres: &'c [Sphere],
    cache: &'c [FocalSphere<f32>],
    eye: Vec3,
    cull: Cull,
}

impl<'c> FocalSpheres<'c> {
    /// The entries [`new`](Self::new) needs for `spheres`: one per sphere.
    #[inline]
    #[must_use]
    pub fn needed(spheres: &[Sphere]) -> usize {
        spheres.len()
    }

    /// Builds the guarded entry of every sphere for rays from `eye` into `out` (entry `i` for
    /// sphere `i`).
    ///
    /// # Errors
    ///
    /// [`TooSmall`] when `out` is shorter than [`needed`](Self::needed) (nothing is written).
    pub fn new(
        spheres: &'c [Sphere],
        eye: Vec3,
        out: &'c mut [FocalSphere<f32>],
    ) -> Result<Self, TooSmall> {
        let needed = Self::needed(spheres);
        let Some(out) = out.get_mut(..needed) else {
            return Err(TooSmall { needed });
        };
        for (s, slot) in spheres.iter().zip(out.iter_mut()) {
            *slot = FocalSphere::new(eye, s);
        }
        Ok(FocalSpheres {
            spheres,
            cache: out,
            eye,
            cull: Cull::None,
        })
    }

    /// The eye.
    #[inline]
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The same set with its queries culled ([`Cull::Back`]: entry roots only).
    #[inline]
    #[must_use]
    pub fn culled(self, cull: Cull) -> Self {
        FocalSpheres { cull, ..self }
    }
}

/// Focal spheres (see the [module docs](self)): rays from the eye with unit directions are
/// tested against the entries in index order (two passes per block of 64: the cheap test
/// first); others go to the spheres with [`Robust`].
impl Trace for FocalSpheres<'_> {
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        let e = rays.dir.length_squared() - L::from_f32(1.0);
        let at = at_eye(rays, self.eye) & e.abs().le(L::from_f32(UNIT_TOLERANCE));
        let cull = self.cull;
        if at.any() {
            let stop = filtered(
                &only(rays, at),
                at,
                self.cache,
                c,
                |r, e| Focal::candidate(r, &Splat(e)),
                #[cfg_attr(target_arch = "x86_64", inline(always))]
                |r, i, e, c| {
                    let at = At {
                        set,
                        index: i as u32,
                        loc: i as u32,
                    };
                    let roots = Focal::maybe_roots(r, &Splat(e))?;
                    // The record as a function, not a let-bound closure, which may be left
                    // out of line (crate::simd).
                    #[inline(always)]
                    fn record<L: Lane>(
                        rays: &RayPacket<L>,
                        w: &Winners<L>,
                        cull: Cull,
                        sphere: Option<&Sphere>,
                    ) -> Hits<L> {
                        Sphere::records(
                            rays,
                            w,
                            cull,
                            #[cfg_attr(target_arch = "x86_64", inline(always))]
                            |_| sphere.copied(),
                        )
                    }
                    let sphere = self.spheres.get(i);
                    if C::EACH {
                        Some(each_root(
                            &roots,
                            cull,
                            #[cfg_attr(target_arch = "x86_64", inline(always))]
                            |h| {
                                c.offer(
                                    h,
                                    at,
                                    #[cfg_attr(target_arch = "x86_64", inline(always))]
                                    |w: &Winners<L>| record(rays, w, cull, sphere),
                                )
                            },
                        ))
                    } else {
                        let h = first_root(&roots, cull);
                        h.mask.any().then(
                            #[cfg_attr(target_arch = "x86_64", inline(always))]
                            || {
                                c.offer(
                                    &h,
                                    at,
                                    #[cfg_attr(target_arch = "x86_64", inline(always))]
                                    |w: &Winners<L>| record(rays, w, cull, sphere),
                                )
                            },
                        )
                    }
                },
            );
            if stop {
                return true;
            }
        }
        let other = rays.valid().and_not(at);
        other.any()
            && flat::<Sphere, Robust, L, C>(rays, other, cull, set, c, self.spheres.iter().copied())
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        Sphere::records(rays, &mine(w, set), self.cull, |loc| {
            self.spheres.get(loc as usize).copied()
        })
    }
}

/// A plane cache for one eye: the numerators `(a − E)·n` (see the [module docs](self)).
#[derive(Clone, Copy, Debug)]
pub struct FocalPlanes<'c> {
    planes: &'c [Plane],
    cache: &'c [FocalPlane],
    eye: Vec3,
    cull: Cull,
}

impl<'c> FocalPlanes<'c> {
    /// The entries [`new`](Self::new) needs for `planes`: one per plane.
    #[inline]
    #[must_use]
    pub fn needed(planes: &[Plane]) -> usize {
        planes.len()
    }

    /// Builds the entry of every plane for rays from `eye` into `out` (entry `i` for plane
    /// `i`).
    ///
    /// # Errors
    ///
    /// [`TooSmall`] when `out` is shorter than [`needed`](Self::needed) (nothing is written).
    pub fn new(
        planes: &'c [Plane],
        eye: Vec3,
        out: &'c mut [FocalPlane],
    ) -> Result<Self, TooSmall> {
        let needed = Self::needed(planes);
        let Some(out) = out.get_mut(..needed) else {
            return Err(TooSmall { needed });
        };
        for (p, slot) in planes.iter().zip(out.iter_mut()) {
            *slot = FocalPlane::new(eye, p);
        }
        Ok(FocalPlanes {
            planes,
            cache: out,
            eye,
            cull: Cull::None,
        })
    }

    /// The eye.
    #[inline]
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The same set with its queries culled ([`Cull::Back`]: `d·n < 0` only).
    #[inline]
    #[must_use]
    pub fn culled(self, cull: Cull) -> Self {
        FocalPlanes { cull, ..self }
    }
}

/// Focal planes (see the [module docs](self)): N rays × 1 plane in index order; rays from
/// elsewhere go to the planes.
impl Trace for FocalPlanes<'_> {
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn trace<L: Lane, C: Collector<L>>(&self, rays: &RayPacket<L>, set: u32, c: &mut C) -> bool {
        let eyed = at_eye(rays, self.eye);
        let cull = self.cull;
        if eyed.any() {
            let mut r = only(rays, eyed);
            let neg = L::from_f32(f32::NEG_INFINITY);
            // The collector's upper end changes only when it takes a candidate: read it then.
            r.t_max = L::select(eyed, c.t_max(), neg);
            for (i, p) in self.cache.iter().enumerate() {
                let mut h = p.intersect_lanes(&r);
                if cull.back() && h.mask.any() {
                    let front = r.dir.dot(V3::splat(p.normal())).lt(L::from_f32(0.0));
                    h = LaneHit::new(h.t, h.u, h.v, h.mask & front);
                }
                let at = At {
                    set,
                    index: i as u32,
                    loc: i as u32,
                };
                let record =
                    |w: &Winners<L>| Plane::records(rays, w, cull, |_| self.planes.get(i).copied());
                if h.mask.any() {
                    if c.offer(&h, at, record) {
                        return true;
                    }
                    r.t_max = L::select(eyed, c.t_max(), neg);
                }
            }
        }
        let other = rays.valid().and_not(eyed);
        other.any()
            && flat::<Plane, PlaneTest, L, C>(
                rays,
                other,
                cull,
                set,
                c,
                self.planes.iter().copied(),
            )
    }

    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn records<L: Lane>(&self, rays: &RayPacket<L>, set: u32, w: &Winners<L>) -> Hits<L> {
        Plane::records(rays, &mine(w, set), self.cull, |loc| {
            self.planes.get(loc as usize).copied()
        })
    }
}
