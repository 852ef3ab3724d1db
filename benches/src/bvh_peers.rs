//! The peers of the BVH benchmark (`examples/scenes.rs`), each with its own acceleration
//! structure over the same mesh or sphere field, answering the same rays:
//!
//! * Embree 3 ([`EmbreeBvh`]): one indexed triangle mesh (shared vertices) or sphere points,
//!   built by a one-thread device; `rtcIntersect1/8/16` and `rtcOccluded1/8`.
//! * obvhs 0.4 ([`ObvhsBvh`]): its compressed wide BVH8 (`build_cwbvh_from_tris`, medium
//!   preset; `build_cwbvh` over sphere boxes), `ray_traverse` with `Triangle::intersect` and
//!   `ray_traverse_miss` for shadows.
//! * parry3d 0.31 ([`ParryMesh`]): `TriMesh` (its own BVH) with `cast_local_ray` and
//!   `intersects_local_ray`.
//!
//! Every query returns `(t, primitive)` per ray (shadow rays: `t = 0` when occluded) so the
//! harness can check it against the reference before timing. Rays are converted into each
//! peer's types once, outside the timings; Embree runs with flush-to-zero (as it asks) and the
//! rest with IEEE denormals.

use std::hint::black_box;
use std::sync::Arc;
use std::sync::atomic::{AtomicIsize, Ordering};
use std::time::{Duration, Instant};

use embree3::{
    BufferUsage, Config, Device, Error, Format, GeometryKind, Hit8, Hit16, INVALID_ID,
    IntersectContext, Ray8, Ray16, RayHit, RayHit8, RayHit16, ValidMask, ValidMaskN,
};
use glam::Vec3A;
use raylane::Ray;
use raylane::sphere::Sphere;

use crate::embree::FlushDenormals;
use crate::meshes::MeshData;

pub use crate::meshes::Answers;

#[repr(C, align(32))]
struct Valid8(ValidMaskN<8>);
#[repr(C, align(64))]
struct Valid16(ValidMaskN<16>);

fn mask<const N: usize>(n: usize) -> ValidMaskN<N> {
    ValidMaskN::new(std::array::from_fn(|i| {
        if i < n {
            ValidMask::Valid
        } else {
            ValidMask::Invalid
        }
    }))
}

fn ray8(chunk: &[Ray]) -> Ray8 {
    let mut p = Ray8::empty();
    for (i, r) in chunk.iter().enumerate() {
        let (o, d) = (r.origin(), r.dir());
        (p.org_x[i], p.org_y[i], p.org_z[i]) = (o.x, o.y, o.z);
        (p.dir_x[i], p.dir_y[i], p.dir_z[i]) = (d.x, d.y, d.z);
        (p.tnear[i], p.tfar[i]) = (r.t_min(), r.t_max());
    }
    p
}

fn ray16(chunk: &[Ray]) -> Ray16 {
    let mut p = Ray16::empty();
    for (i, r) in chunk.iter().enumerate() {
        let (o, d) = (r.origin(), r.dir());
        (p.org_x[i], p.org_y[i], p.org_z[i]) = (o.x, o.y, o.z);
        (p.dir_x[i], p.dir_y[i], p.dir_z[i]) = (d.x, d.y, d.z);
        (p.tnear[i], p.tfar[i]) = (r.t_min(), r.t_max());
    }
    p
}

/// A ray set laid out for Embree's single-ray and packet queries.
pub struct EmbreeRays {
    n: usize,
    singles: Vec<embree3::Ray>,
    p8: Vec<(Valid8, Ray8)>,
    p16: Vec<(Valid16, Ray16)>,
}

impl EmbreeRays {
    /// From raylane rays.
    pub fn new(rays: &[Ray]) -> Self {
        EmbreeRays {
            n: rays.len(),
            singles: rays
                .iter()
                .map(|r| {
                    let (o, d) = (r.origin().to_array(), r.dir().to_array());
                    embree3::Ray::segment(o, d, r.t_min(), r.t_max())
                })
                .collect(),
            p8: rays
                .chunks(8)
                .map(|c| (Valid8(mask(c.len())), ray8(c)))
                .collect(),
            p16: rays
                .chunks(16)
                .map(|c| (Valid16(mask(c.len())), ray16(c)))
                .collect(),
        }
    }
}

/// Embree's BVH over one scene.
pub struct EmbreeBvh {
    scene: embree3::Scene<'static>,
    /// Seconds to build (scene creation, buffers, commit).
    pub build: Duration,
    /// Bytes Embree allocated for the scene, its buffers included (memory monitor).
    pub bytes: usize,
    /// Bytes of the vertex and index buffers among them.
    pub buffer_bytes: usize,
    coherent: bool,
}

impl EmbreeBvh {
    fn new(
        coherent: bool,
        buffer_bytes: usize,
        fill: impl FnOnce(&Device) -> embree3::Geometry<'static>,
    ) -> Self {
        let _ftz = FlushDenormals::on();
        let device = Device::with_config(Config {
            threads: 1,
            ..Config::default()
        })
        .expect("rtcNewDevice failed");
        let used = Arc::new(AtomicIsize::new(0));
        let u = used.clone();
        device.set_memory_monitor_function(move |bytes, _post| {
            u.fetch_add(bytes, Ordering::Relaxed);
            true
        });
        let start = Instant::now();
        let mut scene = device.create_scene().expect("rtcNewScene failed");
        scene.attach_geometry(&fill(&device));
        scene.commit();
        let build = start.elapsed();
        let e = device.get_error();
        assert!(e == Error::NONE, "Embree error {e:?} in scene build");
        EmbreeBvh {
            scene,
            build,
            bytes: used.load(Ordering::Relaxed).max(0) as usize,
            buffer_bytes,
            coherent,
        }
    }

    /// An indexed triangle mesh (`coherent`: the intersect context's hint).
    pub fn mesh(m: &MeshData, coherent: bool) -> Self {
        let (nv, nt) = (m.positions.len(), m.indices.len());
        Self::new(coherent, 12 * nv + 12 * nt, |device| {
            let mut g = device
                .create_geometry(GeometryKind::TRIANGLE)
                .expect("rtcNewGeometry failed");
            let mut vb = g
                .set_new_buffer::<[f32; 3]>(BufferUsage::VERTEX, 0, Format::FLOAT3, 12, nv)
                .expect("vertex buffer");
            for (v, p) in vb.iter_mut().zip(&m.positions) {
                *v = p.to_array();
            }
            let mut ib = g
                .set_new_buffer::<[u32; 3]>(BufferUsage::INDEX, 0, Format::UINT3, 12, nt)
                .expect("index buffer");
            ib.copy_from_slice(&m.indices);
            g.commit()
        })
    }

    /// Sphere points (x, y, z, r).
    pub fn spheres(spheres: &[Sphere], coherent: bool) -> Self {
        Self::new(coherent, 16 * spheres.len(), |device| {
            let mut g = device
                .create_geometry(GeometryKind::SPHERE_POINT)
                .expect("rtcNewGeometry failed");
            let mut vb = g
                .set_new_buffer::<[f32; 4]>(
                    BufferUsage::VERTEX,
                    0,
                    Format::FLOAT4,
                    16,
                    spheres.len(),
                )
                .expect("vertex buffer");
            for (v, s) in vb.iter_mut().zip(spheres) {
                let c = s.center();
                *v = [c.x, c.y, c.z, s.radius()];
            }
            g.commit()
        })
    }

    /// Sets the intersect context's hint for the next queries (coherent primary rays or
    /// incoherent secondary rays).
    pub fn set_coherent(&mut self, coherent: bool) {
        self.coherent = coherent;
    }

    fn context(&self) -> IntersectContext {
        if self.coherent {
            IntersectContext::coherent()
        } else {
            IntersectContext::incoherent()
        }
    }

    /// `rtcIntersect1` over every ray; `out` receives the answers when given.
    #[inline(never)]
    pub fn intersect1(&self, rays: &EmbreeRays, mut out: Option<&mut Answers>) -> u32 {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        let mut n = 0;
        for r in &rays.singles {
            let mut rh = RayHit::from(*r);
            self.scene.intersect(&mut ctx, &mut rh);
            let hit = rh.hit.geomID != INVALID_ID;
            n += hit as u32;
            if let Some(o) = out.as_deref_mut() {
                o.push(hit.then_some((rh.ray.tfar, rh.hit.primID)));
            }
            black_box(&rh);
        }
        n
    }

    /// `rtcIntersect8` over every packet.
    #[inline(never)]
    pub fn intersect8(&self, rays: &EmbreeRays, mut out: Option<&mut Answers>) -> u32 {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        let mut n = 0;
        for (valid, r) in &rays.p8 {
            let mut p = RayHit8 {
                ray: *r,
                hit: Hit8::new(),
            };
            self.scene.intersect8(&mut ctx, &mut p, &valid.0);
            for i in 0..8 {
                let hit = p.hit.geomID[i] != INVALID_ID;
                n += hit as u32;
                if let Some(o) = out.as_deref_mut() {
                    o.push(hit.then_some((p.ray.tfar[i], p.hit.primID[i])));
                }
            }
            black_box(&p);
        }
        if let Some(o) = out {
            o.truncate(rays.n);
        }
        n
    }

    /// `rtcIntersect16` over every packet.
    #[inline(never)]
    pub fn intersect16(&self, rays: &EmbreeRays, mut out: Option<&mut Answers>) -> u32 {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        let mut n = 0;
        for (valid, r) in &rays.p16 {
            let mut p = RayHit16 {
                ray: *r,
                hit: Hit16::new(),
            };
            self.scene.intersect16(&mut ctx, &mut p, &valid.0);
            for i in 0..16 {
                let hit = p.hit.geomID[i] != INVALID_ID;
                n += hit as u32;
                if let Some(o) = out.as_deref_mut() {
                    o.push(hit.then_some((p.ray.tfar[i], p.hit.primID[i])));
                }
            }
            black_box(&p);
        }
        if let Some(o) = out {
            o.truncate(rays.n);
        }
        n
    }

    /// `rtcOccluded1` over every ray.
    #[inline(never)]
    pub fn occluded1(&self, rays: &EmbreeRays, mut out: Option<&mut Answers>) -> u32 {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        let mut n = 0;
        for r in &rays.singles {
            let mut r = *r;
            let hit = self.scene.occluded(&mut ctx, &mut r);
            n += hit as u32;
            if let Some(o) = out.as_deref_mut() {
                o.push(hit.then_some((0.0, 0)));
            }
        }
        n
    }

    /// `rtcOccluded8` over every packet.
    #[inline(never)]
    pub fn occluded8(&self, rays: &EmbreeRays, mut out: Option<&mut Answers>) -> u32 {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        let mut n = 0;
        for (valid, r) in &rays.p8 {
            let mut p = *r;
            self.scene.occluded8(&mut ctx, &mut p, &valid.0);
            for i in 0..8 {
                let hit = p.tfar[i] == f32::NEG_INFINITY;
                n += hit as u32;
                if let Some(o) = out.as_deref_mut() {
                    o.push(hit.then_some((0.0, 0)));
                }
            }
        }
        if let Some(o) = out {
            o.truncate(rays.n);
        }
        n
    }
}

/// obvhs's CWBVH over triangles or sphere boxes.
pub struct ObvhsBvh {
    bvh: obvhs::cwbvh::CwBvh,
    tris: Vec<obvhs::triangle::Triangle>,
    spheres: Vec<(Vec3A, f32)>,
    /// Seconds to build (from the primitives to the CWBVH).
    pub build: Duration,
}

/// A ray set in obvhs's type.
pub fn obvhs_rays(rays: &[Ray]) -> Vec<obvhs::ray::Ray> {
    rays.iter()
        .map(|r| {
            obvhs::ray::Ray::new(
                Vec3A::from(r.origin()),
                Vec3A::from(r.dir()),
                r.t_min(),
                r.t_max(),
            )
        })
        .collect()
}

/// The nearer root of a ray with a sphere inside the ray's interval (geometric form), or
/// `+inf`: the sphere test given to obvhs's traversal.
#[inline(always)]
fn sphere_t(r: &obvhs::ray::Ray, c: Vec3A, rad: f32) -> f32 {
    let oc = c - r.origin;
    let dd = r.direction.length_squared();
    let b = oc.dot(r.direction) / dd;
    let q = oc - r.direction * b;
    let h = rad * rad - q.length_squared();
    if h < 0.0 {
        return f32::INFINITY;
    }
    let s = (h / dd).sqrt();
    for t in [b - s, b + s] {
        if t > r.tmin && t < r.tmax {
            return t;
        }
    }
    f32::INFINITY
}

impl ObvhsBvh {
    /// The medium build preset over the mesh's triangles.
    pub fn mesh(m: &MeshData) -> Self {
        let start = Instant::now();
        let p = |i: u32| Vec3A::from(m.positions[i as usize]);
        let tris: Vec<obvhs::triangle::Triangle> = m
            .indices
            .iter()
            .map(|&[a, b, c]| obvhs::triangle::Triangle {
                v0: p(a),
                v1: p(b),
                v2: p(c),
            })
            .collect();
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            obvhs::BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        ObvhsBvh {
            bvh,
            tris,
            spheres: Vec::new(),
            build: start.elapsed(),
        }
    }

    /// The medium build preset over the spheres' boxes.
    pub fn spheres(spheres: &[Sphere]) -> Self {
        let start = Instant::now();
        let s: Vec<(Vec3A, f32)> = spheres
            .iter()
            .map(|s| (Vec3A::from(s.center()), s.radius()))
            .collect();
        let boxes: Vec<obvhs::aabb::Aabb> = s
            .iter()
            .map(|&(c, r)| obvhs::aabb::Aabb::new(c - Vec3A::splat(r), c + Vec3A::splat(r)))
            .collect();
        let bvh = obvhs::cwbvh::builder::build_cwbvh(
            &boxes,
            obvhs::BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        ObvhsBvh {
            bvh,
            tris: Vec::new(),
            spheres: s,
            build: start.elapsed(),
        }
    }

    /// Bytes of the structure: nodes (80 B each) and the primitive order (4 B each), plus
    /// the copy of the primitives its traversal reads.
    pub fn bytes(&self) -> usize {
        80 * self.bvh.nodes.len()
            + 4 * self.bvh.primitive_indices.len()
            + size_of::<obvhs::triangle::Triangle>() * self.tris.len()
            + size_of::<(Vec3A, f32)>() * self.spheres.len()
    }

    #[inline(always)]
    fn prim_t(&self, r: &obvhs::ray::Ray, id: usize) -> f32 {
        let i = self.bvh.primitive_indices[id] as usize;
        if self.tris.is_empty() {
            let (c, rad) = self.spheres[i];
            sphere_t(r, c, rad)
        } else {
            self.tris[i].intersect(r)
        }
    }

    /// Closest hits.
    #[inline(never)]
    pub fn closest(&self, rays: &[obvhs::ray::Ray], mut out: Option<&mut Answers>) -> u32 {
        let mut n = 0;
        for r in rays {
            let mut hit = obvhs::ray::RayHit::none();
            let yes = self
                .bvh
                .ray_traverse(*black_box(r), &mut hit, |r, id| self.prim_t(r, id));
            n += yes as u32;
            if let Some(o) = out.as_deref_mut() {
                let prim = |id: u32| self.bvh.primitive_indices[id as usize];
                o.push(yes.then(|| (hit.t, prim(hit.primitive_id))));
            }
            black_box(&hit);
        }
        n
    }

    /// Any hit (shadow rays).
    #[inline(never)]
    pub fn occluded(&self, rays: &[obvhs::ray::Ray], mut out: Option<&mut Answers>) -> u32 {
        let mut n = 0;
        for r in rays {
            let hit = !self
                .bvh
                .ray_traverse_miss(*black_box(r), |r, id| self.prim_t(r, id));
            n += hit as u32;
            if let Some(o) = out.as_deref_mut() {
                o.push(hit.then_some((0.0, 0)));
            }
        }
        n
    }
}

/// parry3d's `TriMesh` (with its BVH).
pub struct ParryMesh {
    mesh: parry3d::shape::TriMesh,
    /// Seconds to build (`TriMesh::new`).
    pub build: Duration,
}

fn pv(v: glam::Vec3) -> parry3d::math::Vector {
    parry3d::math::Vector::new(v.x, v.y, v.z)
}

/// A ray set in parry3d's type, with each ray's `t_max`.
pub fn parry_rays(rays: &[Ray]) -> Vec<(parry3d::query::Ray, f32)> {
    rays.iter()
        .map(|r| {
            let t = if r.t_max().is_finite() {
                r.t_max()
            } else {
                f32::MAX
            };
            (parry3d::query::Ray::new(pv(r.origin()), pv(r.dir())), t)
        })
        .collect()
}

impl ParryMesh {
    /// The mesh (vertices and indices copied into parry3d's types).
    pub fn new(m: &MeshData) -> Self {
        let start = Instant::now();
        let mesh = parry3d::shape::TriMesh::new(
            m.positions.iter().map(|&p| pv(p)).collect(),
            m.indices.clone(),
        )
        .expect("parry3d TriMesh");
        ParryMesh {
            mesh,
            build: start.elapsed(),
        }
    }

    /// Closest hits (`cast_local_ray_and_get_normal`, two-sided, for the triangle index).
    #[inline(never)]
    pub fn closest(
        &self,
        rays: &[(parry3d::query::Ray, f32)],
        mut out: Option<&mut Answers>,
    ) -> u32 {
        use parry3d::query::RayCast;
        use parry3d::shape::FeatureId;
        let mut n = 0;
        for (r, tmax) in rays {
            let h = self
                .mesh
                .cast_local_ray_and_get_normal(black_box(r), *tmax, false);
            n += h.is_some() as u32;
            if let Some(o) = out.as_deref_mut() {
                o.push(h.map(|h| {
                    let id = match h.feature {
                        FeatureId::Face(i) => i % self.mesh.num_triangles() as u32,
                        _ => u32::MAX,
                    };
                    (h.time_of_impact, id)
                }));
            }
            black_box(&h);
        }
        n
    }

    /// Any hit (`intersects_local_ray`).
    #[inline(never)]
    pub fn occluded(
        &self,
        rays: &[(parry3d::query::Ray, f32)],
        mut out: Option<&mut Answers>,
    ) -> u32 {
        use parry3d::query::RayCast;
        let mut n = 0;
        for (r, tmax) in rays {
            let hit = self.mesh.intersects_local_ray(black_box(r), *tmax);
            n += hit as u32;
            if let Some(o) = out.as_deref_mut() {
                o.push(hit.then_some((0.0, 0)));
            }
        }
        n
    }
}
