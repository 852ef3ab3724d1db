//! The tile loop and the closest hit of each lane over every kind of primitive.

use super::empty_sphere;
use super::frame::Surface;
use super::{Camera, Frame, ID_NONE, ID_PLANE, ID_SPHERE, ID_TRIANGLE, Stats, Tile};
use crate::registry::{Kernel, Visitor};
use raylane::Cull;
use raylane::hit::{At, Closest, Collector, Hits, Winners};
use raylane::lane::{Lane, MAX_LANES, Mask};
use raylane::mesh::Mesh;
use raylane::plane::FocalPlane;
use raylane::ray::RayPacket;
use raylane::set::{Trace, Using};
use raylane::sphere::focal::{FocalKernel, Splat};
use raylane::sphere::{FocalSphere, Sphere, SphereKernel, first_root};
use raylane::triangle::focal::FocalRays;
use raylane::triangle::{TriangleKernel, Watertight};

/// What is hit in each lane of a packet, merged over the kinds of primitive.
#[derive(Clone, Copy, Debug)]
pub(super) struct Best {
    pub(super) t: [f32; MAX_LANES],
    pub(super) id: [u8; MAX_LANES],
    /// Sphere, plane or triangle index (within its part).
    pub(super) index: [u32; MAX_LANES],
    pub(super) part: [u8; MAX_LANES],
}

impl Best {
    fn new() -> Self {
        Best {
            t: [f32::INFINITY; MAX_LANES],
            id: [ID_NONE; MAX_LANES],
            index: [0; MAX_LANES],
            part: [0; MAX_LANES],
        }
    }

    /// Takes the lanes of `h` that are strictly closer.
    fn merge<L: Lane<Scalar = f32>>(&mut self, h: &Winners<L>, id: u8, part: u8) {
        let mut bits = h.mask.bits();
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let t = h.t.lane(i);
            if i < MAX_LANES && t < self.t[i] {
                self.t[i] = t;
                self.id[i] = id;
                self.index[i] = h.index.as_ref().get(i).copied().unwrap_or(0);
                self.part[i] = part;
            }
        }
    }

    /// The rays with `t_max` relaxed to the closest hit so far (as the closest-hit loops do).
    fn shrink<L: Lane<Scalar = f32>>(&self, rays: &RayPacket<L>) -> RayPacket<L> {
        let mut hit = L::Mask::splat(false);
        for i in 0..L::LANES.min(MAX_LANES) {
            if self.id[i] != ID_NONE {
                hit = hit.with_lane(i, true);
            }
        }
        let t = L::from_f32_fn(|i| {
            let t = self.t[i.min(MAX_LANES - 1)];
            t + f32::from_bits(t.to_bits() & 0x7fff_ffff) * (1.0 / 2_097_152.0)
        });
        rays.shrink(hit, t)
    }
}

/// Valid lanes of a packet.
fn count<L: Lane>(rays: &RayPacket<L>) -> u64 {
    u64::from(rays.valid().bits().count_ones())
}

impl<const P: usize> Frame<'_, P> {
    /// Renders the whole image into `rgb` (`3·width·height` bytes) and, if given, `ids`
    /// (`width·height` bytes).
    pub fn render<L: Lane<Scalar = f32>>(&self, rgb: &mut [u8], ids: Option<&mut [u8]>) -> Stats {
        self.render_tile::<L>(Tile::all(&self.camera), rgb, ids)
    }

    /// Renders `tile` (clipped to the image) with `L::LANES` rays per packet into `rgb`
    /// (`3·tile.width·tile.height` bytes, row-major within the tile) and, if given, `ids`
    /// (one byte per pixel). Pixels that do not fit the buffers are skipped.
    pub fn render_tile<L: Lane<Scalar = f32>>(
        &self,
        tile: Tile,
        rgb: &mut [u8],
        mut ids: Option<&mut [u8]>,
    ) -> Stats {
        let mut stats = Stats::default();
        let x_end = tile.x.saturating_add(tile.width).min(self.camera.width());
        let y_end = tile.y.saturating_add(tile.height).min(self.camera.height());
        let lanes = L::LANES.min(MAX_LANES);
        for y in tile.y..y_end {
            let mut x = tile.x;
            while x < x_end {
                let mut rays = self.camera.row_packet::<L>(x, y);
                // Lanes past the tile: empty interval, never hit, not counted.
                let n = ((x_end - x) as usize).min(lanes);
                if n < L::LANES {
                    let mut outside = L::Mask::splat(false);
                    for i in n..L::LANES {
                        outside = outside.with_lane(i, true);
                    }
                    rays = rays.shrink(outside, L::from_f32(0.0));
                }
                let best = self.trace(&rays, &mut stats);
                for i in 0..n {
                    let px =
                        (y - tile.y) as usize * tile.width as usize + (x - tile.x) as usize + i;
                    let (o, d) = (rays.origin().lane(i), rays.dir().lane(i));
                    let c = self.shade(o, d, &best, i);
                    if let Some(out) = rgb.get_mut(3 * px..3 * px + 3) {
                        out.copy_from_slice(&c);
                    }
                    if let Some(slot) = ids.as_deref_mut().and_then(|b| b.get_mut(px)) {
                        *slot = best.id[i];
                    }
                }
                x = x.saturating_add(lanes as u32);
            }
        }
        stats
    }

    /// The closest hit of each lane over every primitive. (Each kind of primitive is traced by
    /// its own out-of-line function: smaller functions, much quicker to compile for every lane
    /// width.)
    fn trace<L: Lane<Scalar = f32>>(&self, rays: &RayPacket<L>, stats: &mut Stats) -> Best {
        raylane::lane::assert_fits::<L>();
        let k = count(rays);
        stats.rays += k;
        let mut best = Best::new();
        // 1. Spheres, with the frame's method.
        if !self.scene.spheres.is_empty() {
            stats.sphere_tests += k * self.scene.spheres.len() as u64;
            best.merge(&self.spheres::<L>(rays), ID_SPHERE, 0);
        }
        // 2. Planes.
        if !self.scene.planes.is_empty() {
            stats.plane_tests += k * self.scene.planes.len() as u64;
            let r = best.shrink(rays);
            let h = match self.camera {
                Camera::Pinhole(_) => closest_focal_planes(&r, self.planes),
                Camera::Ortho(_) => closest_in(self.scene.planes, &r),
            };
            best.merge(&h, ID_PLANE, 0);
        }
        // 3. Mesh parts: the bounding sphere first, then the triangles.
        if self.pieces[0].is_some() {
            self.meshes(&best.shrink(rays), k, stats, &mut best);
        }
        best
    }

    /// The closest sphere hit with the frame's kernel.
    #[inline(never)]
    fn spheres<L: Lane<Scalar = f32>>(&self, rays: &RayPacket<L>) -> Winners<L> {
        self.kernel.visit(SphereHits { frame: self, rays })
    }

    /// Every mesh part: the bounding sphere, then (unless the packet misses it) the triangles.
    #[inline(never)]
    fn meshes<L: Lane<Scalar = f32>>(
        &self,
        r: &RayPacket<L>,
        k: u64,
        stats: &mut Stats,
        best: &mut Best,
    ) {
        let fr = matches!(self.camera, Camera::Pinhole(_)).then(|| FocalRays::new(r));
        for (p, piece) in self.pieces.iter().enumerate() {
            let Some(piece) = piece else { break };
            let tris = k * piece.mesh().len() as u64;
            stats.bound_tests += k;
            let keep = match (&fr, &piece.surface) {
                (Some(fr), Surface::Focal(fm)) => fm.may_hit(fr) & r.valid(),
                _ => piece.mesh().may_hit(r) & r.valid(),
            };
            if keep.none() {
                stats.triangle_tests_saved += tris;
                continue;
            }
            let h = match &piece.surface {
                Surface::Focal(fm) if fr.is_some() => closest_in(&fm.culled(piece.cull), r),
                _ => closest_triangles::<L>(piece.mesh(), r, piece.cull),
            };
            stats.triangle_tests += tris;
            best.merge(&h, ID_TRIANGLE, p as u8);
        }
    }

    /// Spheres for rays with different origins: one focal cache entry per ray and sphere, with
    /// the ray's own origin as the eye, gathered into lanes.
    #[inline(never)]
    pub(super) fn focal_per_ray<K: FocalKernel, L: Lane<Scalar = f32>>(
        &self,
        rays: &RayPacket<L>,
        guarded: bool,
    ) -> Winners<L> {
        let mut best = Closest::new(rays);
        raylane::lane::assert_fits::<L>();
        let mut entries = [empty_sphere(); MAX_LANES];
        for (j, s) in self.scene.spheres.iter().enumerate() {
            for (i, e) in entries.iter_mut().enumerate().take(L::LANES) {
                let o = rays.origin().lane(i);
                *e = if guarded {
                    FocalSphere::new(o, s)
                } else {
                    FocalSphere::unguarded(o, s)
                };
            }
            let cache = FocalSphere::<L>::gather(&entries[..L::LANES.min(MAX_LANES)]);
            let r = rays.shrink(Mask::splat(true), best.t_max());
            let h = first_root(&K::roots(&r, &cache), Cull::None);
            if h.mask.any() {
                best.offer(&h, at(j), no_records);
            }
        }
        best.finish()
    }
}

/// The frame's sphere kernel over a packet, with its type: the closest sphere hit.
struct SphereHits<'f, 'a, L: Lane, const P: usize> {
    frame: &'f Frame<'a, P>,
    rays: &'f RayPacket<L>,
}

impl<L: Lane<Scalar = f32>, const P: usize> Visitor for SphereHits<'_, '_, L, P> {
    type Output = Winners<L>;

    fn sphere<K: SphereKernel>(self, _: Kernel) -> Winners<L> {
        closest_spheres::<K, L>(self.rays, self.frame.scene.spheres)
    }

    fn focal_sphere<K: FocalKernel>(self, _: Kernel, guarded: bool) -> Winners<L> {
        match self.frame.camera {
            Camera::Pinhole(_) => closest_focal_spheres::<K, L>(self.rays, self.frame.spheres),
            Camera::Ortho(_) => self.frame.focal_per_ray::<K, L>(self.rays, guarded),
        }
    }

    // Not sphere kernels: `Frame::new` refuses them.
    fn plane(self, _: Kernel) -> Winners<L> {
        Closest::new(self.rays).finish()
    }
    fn focal_plane(self, _: Kernel) -> Winners<L> {
        Closest::new(self.rays).finish()
    }
    fn triangle<K: TriangleKernel>(self, _: Kernel) -> Winners<L> {
        Closest::new(self.rays).finish()
    }
    fn focal_triangle(self, _: Kernel) -> Winners<L> {
        Closest::new(self.rays).finish()
    }
}

/// Where candidate `j` of a flat loop comes from.
fn at(j: usize) -> At {
    At {
        set: 0,
        index: j as u32,
        loc: j as u32,
    }
}

/// A closest-hit loop makes no records of single candidates.
fn no_records<L: Lane>(_: &Winners<L>) -> Hits<L> {
    Hits::miss()
}

/// The closest hits of `rays` in `set`, before records are made.
fn closest_in<T: Trace + ?Sized, L: Lane>(set: &T, rays: &RayPacket<L>) -> Winners<L> {
    let mut c = Closest::new(rays);
    set.trace(rays, 0, &mut c);
    c.finish()
}

/// The spheres with kernel `K`, out of line.
#[inline(never)]
fn closest_spheres<K: SphereKernel, L: Lane>(rays: &RayPacket<L>, s: &[Sphere]) -> Winners<L> {
    closest_in(&Using::<[Sphere], K>::new(s), rays)
}

/// Sphere cache entries (guarded or not) with the focal kernel `K`, out of line.
#[inline(never)]
fn closest_focal_spheres<K: FocalKernel, L: Lane>(
    rays: &RayPacket<L>,
    cache: &[FocalSphere<f32>],
) -> Winners<L> {
    let mut best = Closest::new(rays);
    for (j, e) in cache.iter().enumerate() {
        if K::candidate(rays, &Splat(e)).none() {
            continue;
        }
        let r = rays.shrink(Mask::splat(true), best.t_max());
        if let Some(x) = K::maybe_roots(&r, &Splat(e)) {
            let h = first_root(&x, Cull::None);
            if h.mask.any() {
                best.offer(&h, at(j), no_records);
            }
        }
    }
    best.finish()
}

/// Plane cache entries for rays from their eye, out of line.
#[inline(never)]
fn closest_focal_planes<L: Lane>(rays: &RayPacket<L>, cache: &[FocalPlane]) -> Winners<L> {
    let mut best = Closest::new(rays);
    for (j, p) in cache.iter().enumerate() {
        let r = rays.shrink(Mask::splat(true), best.t_max());
        let h = p.intersect_lanes(&r);
        if h.mask.any() {
            best.offer(&h, at(j), no_records);
        }
    }
    best.finish()
}

/// A mesh with [`Watertight`], culled by `cull`, out of line.
#[inline(never)]
fn closest_triangles<L: Lane>(mesh: &Mesh, rays: &RayPacket<L>, cull: Cull) -> Winners<L> {
    closest_in(&Using::<Mesh, Watertight>::new(mesh).culled(cull), rays)
}
