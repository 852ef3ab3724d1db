//! Kernel loops for tests and measurements: one ray × one primitive, packets × a slice
//! (N rays × 1 primitive) and one ray × primitives packed in lanes (1 ray × N primitives),
//! for every kernel family, built on the library's public kernels and its [`Closest`]
//! collector (the one tie rule). The library asks through `Query`; these loops let the tests
//! compare the two packet shapes and the benchmarks time a kernel alone.

use raylane::Cull;
use raylane::hit::{At, Closest, Collector, Hits, Winners};
use raylane::kernel::LaneHit;
use raylane::lane::{Lane, Mask};
use raylane::ray::{Ray, RayPacket};

/// The closest hits of a packet (a finished [`Closest`]).
pub type Best<L> = Winners<L>;

/// One hit of one ray: `t`, the barycentrics (0 for spheres) and the primitive's index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitRecord {
    /// Ray parameter.
    pub t: f32,
    /// Barycentric weight of B.
    pub u: f32,
    /// Barycentric weight of C.
    pub v: f32,
    /// Index of the primitive.
    pub index: u32,
}

/// Lane `i` of finished closest hits as a [`HitRecord`].
pub trait LaneRecords {
    /// Lane `i`, or `None` when it missed.
    fn lane(&self, i: usize) -> Option<HitRecord>;
    /// Lane 0.
    fn get(&self) -> Option<HitRecord> {
        self.lane(0)
    }
}

impl<L: Lane<Scalar = f32>> LaneRecords for Winners<L> {
    fn lane(&self, i: usize) -> Option<HitRecord> {
        self.mask.test(i).then(|| HitRecord {
            t: self.t.lane(i),
            u: self.u.lane(i),
            v: self.v.lane(i),
            index: self.index.as_ref().get(i).copied().unwrap_or(u32::MAX),
        })
    }
}

/// Where candidate `i` of a flat loop comes from.
fn at(i: usize) -> At {
    At {
        set: 0,
        index: i as u32,
        loc: i as u32,
    }
}

/// Closest-hit loops make no records of single candidates.
fn none<L: Lane>(_: &Winners<L>) -> Hits<L> {
    Hits::miss()
}

/// `rays` with the collector's upper ends.
fn with<L: Lane>(rays: &RayPacket<L>, t_max: L) -> RayPacket<L> {
    rays.shrink(Mask::splat(true), t_max)
}

/// N rays × 1 primitive: `test(rays, p)` for the primitives `p` in order (primitive `i` the
/// `i`-th), the closest hit per lane. `test` returns `None` when no lane passed the kernel's
/// early exits; the rays' upper ends follow the collector's only when it took a candidate.
pub fn closest_with<L: Lane, P>(
    rays: &RayPacket<L>,
    prims: impl IntoIterator<Item = P>,
    mut test: impl FnMut(&RayPacket<L>, P) -> Option<LaneHit<L>>,
) -> Best<L> {
    let mut c = Closest::new(rays);
    let mut r = with(rays, c.t_max());
    for (i, p) in prims.into_iter().enumerate() {
        if let Some(h) = test(&r, p)
            && h.mask.any()
        {
            c.offer(&h, at(i), none);
            r = with(rays, c.t_max());
        }
    }
    c.finish()
}

/// N rays × 1 primitive: the lanes that hit something inside their interval.
pub fn any_with<L: Lane, P>(
    rays: &RayPacket<L>,
    prims: impl IntoIterator<Item = P>,
    mut test: impl FnMut(&RayPacket<L>, P) -> Option<LaneHit<L>>,
) -> L::Mask {
    let mut c = raylane::hit::Any::new(rays);
    let r = with(rays, c.t_max());
    for (i, p) in prims.into_iter().enumerate() {
        if let Some(h) = test(&r, p)
            && h.mask.any()
            && c.offer(&h, at(i), none)
        {
            break;
        }
    }
    c.finish()
}

/// 1 ray × N primitives: `test(ray in every lane, chunk)` for each chunk of `L::LANES`
/// primitives (primitive `j` of chunk `c` has index `c·L::LANES + j`), the closest hit.
pub fn closest_soa_with<L: Lane<Scalar = f32>, P>(
    ray: &Ray,
    chunks: &[P],
    mut test: impl FnMut(&RayPacket<L>, &P) -> Option<LaneHit<L>>,
) -> Option<HitRecord> {
    let one = RayPacket::<f32>::splat(ray);
    let lanes = RayPacket::<L>::splat(ray);
    let mut c = Closest::new(&one);
    let mut r = with(&lanes, L::from_f32(c.t_max()));
    for (k, p) in chunks.iter().enumerate() {
        let Some(h) = test(&r, p) else {
            continue;
        };
        let mut bits = h.mask.bits();
        if bits == 0 {
            continue;
        }
        while bits != 0 {
            let j = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let h1 = LaneHit {
                t: h.t.lane(j),
                u: h.u.lane(j),
                v: h.v.lane(j),
                w: h.w.lane(j),
                mask: true,
            };
            c.offer(&h1, at(k * L::LANES + j), none);
        }
        r = with(&lanes, L::from_f32(c.t_max()));
    }
    c.finish().get()
}

/// 1 ray × N primitives: whether the ray hits one of them inside its interval.
pub fn any_soa_with<L: Lane<Scalar = f32>, P>(
    ray: &Ray,
    chunks: &[P],
    mut test: impl FnMut(&RayPacket<L>, &P) -> Option<LaneHit<L>>,
) -> bool {
    closest_soa_with(ray, chunks, &mut test).is_some()
}

/// One ray against one primitive: its first hit as the kernel reports it.
pub fn one(h: LaneHit<f32>) -> Option<HitRecord> {
    h.mask.then_some(HitRecord {
        t: h.t,
        u: h.u,
        v: h.v,
        index: 0,
    })
}

/// Sphere loops with a sphere kernel `K` (first roots, two-sided).
pub mod sphere {
    use super::*;
    use raylane::sphere::{Roots, Sphere, SphereKernel, SpherePacket};

    /// One ray and one sphere.
    pub fn intersect<K: SphereKernel>(ray: &Ray, s: &Sphere) -> Option<HitRecord> {
        let r = RayPacket::<f32>::splat(ray);
        one(K::roots(&r, &SpherePacket::splat(s)).first())
    }

    /// N rays × 1 sphere.
    pub fn closest<K: SphereKernel, L: Lane>(rays: &RayPacket<L>, s: &[Sphere]) -> Best<L> {
        closest_with(rays, s, |r, x| {
            K::maybe_roots(r, &SpherePacket::splat(x)).map(|x| x.first())
        })
    }

    /// N rays × 1 sphere: occlusion.
    pub fn any<K: SphereKernel, L: Lane>(rays: &RayPacket<L>, s: &[Sphere]) -> L::Mask {
        any_with(rays, s, |r, x| {
            K::maybe_roots(r, &SpherePacket::splat(x)).map(|x| x.first())
        })
    }

    /// Every root of every sphere: `f(index, roots)` for each sphere some lane hits.
    pub fn all<K: SphereKernel, L: Lane>(
        rays: &RayPacket<L>,
        s: &[Sphere],
        mut f: impl FnMut(u32, &Roots<L>),
    ) {
        for (i, x) in s.iter().enumerate() {
            let r = K::roots(rays, &SpherePacket::splat(x));
            if r.any().any() {
                f(i as u32, &r);
            }
        }
    }

    /// 1 ray × spheres packed in lanes.
    pub fn closest_soa<K: SphereKernel, L: Lane<Scalar = f32>>(
        ray: &Ray,
        s: &[SpherePacket<L>],
    ) -> Option<HitRecord> {
        closest_soa_with(ray, s, |r, p| K::maybe_roots(r, p).map(|x| x.first()))
    }

    /// 1 ray × spheres packed in lanes: occlusion.
    pub fn any_soa<K: SphereKernel, L: Lane<Scalar = f32>>(
        ray: &Ray,
        s: &[SpherePacket<L>],
    ) -> bool {
        any_soa_with(ray, s, |r, p| K::maybe_roots(r, p).map(|x| x.first()))
    }

    /// Loops over sphere focal caches (rays from the cache's eye, unit directions).
    pub mod focal {
        use super::*;
        use raylane::sphere::FocalSphere;
        use raylane::sphere::focal::FocalKernel;
        pub use raylane::sphere::focal::{Splat, focus};

        /// N rays × 1 entry.
        pub fn closest<K: FocalKernel, L: Lane>(
            rays: &RayPacket<L>,
            cache: &[FocalSphere<f32>],
        ) -> Best<L> {
            closest_with(rays, cache, |r, e| {
                K::maybe_roots(r, &Splat(e)).map(|x| x.first())
            })
        }

        /// N rays × 1 entry: occlusion.
        pub fn any<K: FocalKernel, L: Lane>(
            rays: &RayPacket<L>,
            cache: &[FocalSphere<f32>],
        ) -> L::Mask {
            any_with(rays, cache, |r, e| {
                K::maybe_roots(r, &Splat(e)).map(|x| x.first())
            })
        }

        /// Every root of every entry some lane hits: `f(index, roots)`.
        pub fn all<K: FocalKernel, L: Lane>(
            rays: &RayPacket<L>,
            cache: &[FocalSphere<f32>],
            mut f: impl FnMut(u32, &Roots<L>),
        ) {
            for (i, e) in cache.iter().enumerate() {
                let r = K::roots(rays, &Splat(e));
                if r.any().any() {
                    f(i as u32, &r);
                }
            }
        }

        /// 1 ray × entries packed in lanes.
        pub fn closest_soa<K: FocalKernel, L: Lane<Scalar = f32>>(
            ray: &Ray,
            cache: &[FocalSphere<L>],
        ) -> Option<HitRecord> {
            closest_soa_with(ray, cache, |r, e| K::maybe_roots(r, e).map(|x| x.first()))
        }

        /// 1 ray × entries packed in lanes: occlusion.
        pub fn any_soa<K: FocalKernel, L: Lane<Scalar = f32>>(
            ray: &Ray,
            cache: &[FocalSphere<L>],
        ) -> bool {
            any_soa_with(ray, cache, |r, e| K::maybe_roots(r, e).map(|x| x.first()))
        }
    }
}

/// Triangle loops with a triangle kernel `K`.
pub mod triangle {
    use super::*;
    use raylane::triangle::{Triangle, TriangleKernel, TrianglePacket};

    /// One ray and one triangle.
    pub fn intersect<K: TriangleKernel>(ray: &Ray, t: &Triangle, cull: Cull) -> Option<HitRecord> {
        let r = RayPacket::<f32>::splat(ray);
        one(K::intersect(&r, &K::prepare(&r), &TrianglePacket::splat(t), cull).normalized())
    }

    /// N rays × 1 triangle.
    pub fn closest<K: TriangleKernel, L: Lane>(
        rays: &RayPacket<L>,
        t: &[Triangle],
        cull: Cull,
    ) -> Best<L> {
        let pre = K::prepare(rays);
        closest_with(rays, t, |r, x| {
            K::maybe_intersect(r, &pre, &TrianglePacket::splat(x), cull)
        })
    }

    /// N rays × 1 triangle: occlusion.
    pub fn any<K: TriangleKernel, L: Lane>(
        rays: &RayPacket<L>,
        t: &[Triangle],
        cull: Cull,
    ) -> L::Mask {
        let pre = K::prepare(rays);
        any_with(rays, t, |r, x| {
            K::maybe_intersect(r, &pre, &TrianglePacket::splat(x), cull)
        })
    }

    /// Every hit: `f(index, hit)` (divided) for each triangle some lane hits.
    pub fn all<K: TriangleKernel, L: Lane>(
        rays: &RayPacket<L>,
        t: &[Triangle],
        cull: Cull,
        mut f: impl FnMut(u32, &LaneHit<L>),
    ) {
        let pre = K::prepare(rays);
        for (i, x) in t.iter().enumerate() {
            let h = K::intersect(rays, &pre, &TrianglePacket::splat(x), cull);
            if h.mask.any() {
                f(i as u32, &h.normalized());
            }
        }
    }

    /// 1 ray × triangles packed in lanes.
    pub fn closest_soa<K: TriangleKernel, L: Lane<Scalar = f32>>(
        ray: &Ray,
        t: &[TrianglePacket<L>],
        cull: Cull,
    ) -> Option<HitRecord> {
        let pre = K::prepare(&RayPacket::<L>::splat(ray));
        closest_soa_with(ray, t, |r, p| K::maybe_intersect(r, &pre, p, cull))
    }

    /// 1 ray × triangles packed in lanes: occlusion.
    pub fn any_soa<K: TriangleKernel, L: Lane<Scalar = f32>>(
        ray: &Ray,
        t: &[TrianglePacket<L>],
        cull: Cull,
    ) -> bool {
        let pre = K::prepare(&RayPacket::<L>::splat(ray));
        any_soa_with(ray, t, |r, p| K::maybe_intersect(r, &pre, p, cull))
    }

    /// Loops over triangle focal caches (rays from the cache's eye).
    pub mod focal {
        use super::*;
        use raylane::triangle::FocalTriangle;
        use raylane::triangle::focal::{FocalRays, Splat, kernel, maybe_hit};
        pub use raylane::triangle::focal::{focus, intersect_lanes};

        /// One ray from the eye and one entry.
        pub fn intersect(ray: &Ray, e: &FocalTriangle<f32>, cull: Cull) -> Option<HitRecord> {
            let fr = FocalRays::new(&RayPacket::<f32>::splat(ray));
            one(fr.unscale(kernel(fr.scaled(), e, cull)).normalized())
        }

        /// N rays × 1 entry (the kernel in its scaled units, `t` back in the rays' own).
        pub fn closest<L: Lane>(
            rays: &RayPacket<L>,
            cache: &[FocalTriangle<f32>],
            cull: Cull,
        ) -> Best<L> {
            let fr = FocalRays::new(rays);
            let mut w = closest_with(fr.scaled(), cache, |r, e| maybe_hit(r, &Splat(e), cull));
            w.t = fr.own_units(w.t);
            w
        }

        /// N rays × 1 entry: occlusion.
        pub fn any<L: Lane>(
            rays: &RayPacket<L>,
            cache: &[FocalTriangle<f32>],
            cull: Cull,
        ) -> L::Mask {
            let fr = FocalRays::new(rays);
            any_with(fr.scaled(), cache, |r, e| maybe_hit(r, &Splat(e), cull))
        }

        /// Every hit: `f(index, hit)` (divided, `t` in the rays' own units).
        pub fn all<L: Lane>(
            rays: &RayPacket<L>,
            cache: &[FocalTriangle<f32>],
            cull: Cull,
            mut f: impl FnMut(u32, &LaneHit<L>),
        ) {
            let fr = FocalRays::new(rays);
            for (i, e) in cache.iter().enumerate() {
                let h = kernel(fr.scaled(), &Splat(e), cull);
                if h.mask.any() {
                    f(i as u32, &fr.unscale(h).normalized());
                }
            }
        }

        /// 1 ray × entries packed in lanes.
        pub fn closest_soa<L: Lane<Scalar = f32>>(
            ray: &Ray,
            cache: &[FocalTriangle<L>],
            cull: Cull,
        ) -> Option<HitRecord> {
            let fr = FocalRays::<f32>::new(&RayPacket::splat(ray));
            let scaled = fr.scaled().ray(0);
            closest_soa_with(&scaled, cache, |r, e| maybe_hit(r, e, cull)).map(|h| HitRecord {
                t: fr.own_units(h.t),
                ..h
            })
        }

        /// 1 ray × entries packed in lanes: occlusion.
        pub fn any_soa<L: Lane<Scalar = f32>>(
            ray: &Ray,
            cache: &[FocalTriangle<L>],
            cull: Cull,
        ) -> bool {
            let fr = FocalRays::<f32>::new(&RayPacket::splat(ray));
            any_soa_with(&fr.scaled().ray(0), cache, |r, e| maybe_hit(r, e, cull))
        }
    }
}

/// Plane loops.
pub mod plane {
    use super::*;
    use raylane::plane::{FocalPlane, Plane, PlanePacket};
    pub use raylane::plane::{focal_lanes, intersect_lanes};

    /// One ray and one plane.
    pub fn intersect(ray: &Ray, p: &Plane) -> Option<HitRecord> {
        one(intersect_lanes(
            &RayPacket::<f32>::splat(ray),
            &PlanePacket::splat(p),
        ))
    }

    /// N rays × 1 plane.
    pub fn closest<L: Lane>(rays: &RayPacket<L>, p: &[Plane]) -> Best<L> {
        closest_with(rays, p, |r, x| {
            Some(intersect_lanes(r, &PlanePacket::splat(x)))
        })
    }

    /// N rays × 1 plane: occlusion.
    pub fn any<L: Lane>(rays: &RayPacket<L>, p: &[Plane]) -> L::Mask {
        any_with(rays, p, |r, x| {
            Some(intersect_lanes(r, &PlanePacket::splat(x)))
        })
    }

    /// Every plane some lane hits: `f(index, hit)`.
    pub fn all<L: Lane>(rays: &RayPacket<L>, p: &[Plane], mut f: impl FnMut(u32, &LaneHit<L>)) {
        for (i, x) in p.iter().enumerate() {
            let h = intersect_lanes(rays, &PlanePacket::splat(x));
            if h.mask.any() {
                f(i as u32, &h);
            }
        }
    }

    /// N rays from the eye × 1 cached plane.
    pub fn closest_focal<L: Lane>(rays: &RayPacket<L>, cache: &[FocalPlane]) -> Best<L> {
        closest_with(rays, cache, |r, e| Some(e.intersect_lanes(r)))
    }

    /// 1 ray × planes packed in lanes.
    pub fn closest_soa<L: Lane<Scalar = f32>>(
        ray: &Ray,
        p: &[PlanePacket<L>],
    ) -> Option<HitRecord> {
        closest_soa_with(ray, p, |r, x| Some(intersect_lanes(r, x)))
    }
}
