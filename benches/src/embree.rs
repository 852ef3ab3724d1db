//! Embree 3 (Debian's libembree3, 3.13.x) through the `embree3` crate: a scene of sphere points
//! or of a triangle mesh, closest hits of single rays (`Scene::intersect`, i.e. `rtcIntersect1`)
//! and of 8-ray packets (`Scene::intersect8`, i.e. `rtcIntersect8`).
//!
//! Two things the crate leaves to us: its `ValidMaskN` is 16-byte aligned, but `rtcIntersect8`
//! loads the mask with an aligned AVX load (`Valid8` aligns it to 32); and its device
//! constructor sets FTZ/DAZ on the calling thread for good (`FlushDenormals` restores MXCSR).

use embree3::{
    BufferUsage, Config, Device, DeviceProperty, Error, Format, Geometry, GeometryKind, Hit8,
    INVALID_ID, IntersectContext, Ray8, RayHit, RayHit8, ValidMask, ValidMaskN,
};
use raylane::Ray;
use raylane::sphere::Sphere;
use raylane::triangle::Triangle;

/// The valid mask of `rtcIntersect8`, 32-byte aligned (see the module doc; a mask that is only
/// 16-byte aligned crashes whenever it lands on an odd 16 bytes).
#[repr(C, align(32))]
struct Valid8(ValidMaskN<8>);

const _: () = assert!(align_of::<Valid8>() == 32 && align_of::<RayHit8>() == 32);

/// Flush-to-zero and denormals-are-zero while it lives, as Embree asks of every thread that
/// calls it ("can have a severe performance impact" otherwise); the previous MXCSR comes back
/// on drop, so raylane and the other peers run with IEEE denormals.
pub struct FlushDenormals(u32);

impl FlushDenormals {
    /// FTZ/DAZ on until the value is dropped.
    #[allow(deprecated)] // _mm_getcsr/_mm_setcsr: still the plain way to save and restore MXCSR
    pub fn on() -> Self {
        // SAFETY: reads this thread's MXCSR (SSE2 is baseline).
        let old = unsafe { std::arch::x86_64::_mm_getcsr() };
        embree3::enable_ftz_and_daz();
        FlushDenormals(old)
    }
}

impl Drop for FlushDenormals {
    #[allow(deprecated)]
    fn drop(&mut self) {
        // SAFETY: restores the value read in `on`.
        unsafe { std::arch::x86_64::_mm_setcsr(self.0) }
    }
}

/// An Embree device and one committed scene, with the rays of a frame laid out for
/// `rtcIntersect1` and `rtcIntersect8` (initialised once; each query copies its template, as
/// a renderer fills a ray structure per query).
pub struct Scene {
    scene: embree3::Scene<'static>,
    coherent: bool,
    singles: Vec<RayHit>,
    packets: Vec<(Valid8, RayHit8)>,
}

impl Scene {
    fn new(rays: &[Ray], coherent: bool, build: impl FnOnce(&Device) -> Geometry<'static>) -> Self {
        // Also undoes the FTZ/DAZ that `Device::with_config` leaves on this thread.
        let _ftz = FlushDenormals::on();
        let device = Device::with_config(Config {
            threads: 1,
            ..Config::default()
        })
        .expect("rtcNewDevice failed");
        let mut scene = device.create_scene().expect("rtcNewScene failed");
        scene.attach_geometry(&build(&device));
        scene.commit();
        let e = device.get_error();
        assert!(e == Error::NONE, "Embree error {e:?} in scene build");
        let singles = rays
            .iter()
            .map(|r| {
                let (o, d) = (r.origin().to_array(), r.dir().to_array());
                RayHit::from(embree3::Ray::segment(o, d, r.t_min(), r.t_max()))
            })
            .collect();
        let packets = rays
            .chunks(8)
            .map(|chunk| {
                let mut valid = [ValidMask::Invalid; 8];
                let mut p = RayHit8 {
                    ray: Ray8::empty(),
                    hit: Hit8::new(),
                };
                for (i, r) in chunk.iter().enumerate() {
                    valid[i] = ValidMask::Valid;
                    let (o, d) = (r.origin(), r.dir());
                    (p.ray.org_x[i], p.ray.org_y[i], p.ray.org_z[i]) = (o.x, o.y, o.z);
                    (p.ray.dir_x[i], p.ray.dir_y[i], p.ray.dir_z[i]) = (d.x, d.y, d.z);
                    (p.ray.tnear[i], p.ray.tfar[i]) = (r.t_min(), r.t_max());
                }
                (Valid8(ValidMaskN::new(valid)), p)
            })
            .collect();
        Scene {
            scene,
            coherent,
            singles,
            packets,
        }
    }

    /// Spheres as Embree sphere points (`RTC_GEOMETRY_TYPE_SPHERE_POINT`, x y z r).
    pub fn spheres(spheres: &[Sphere], rays: &[Ray], coherent: bool) -> Self {
        Self::new(rays, coherent, |device| {
            let mut g = device
                .create_geometry(GeometryKind::SPHERE_POINT)
                .expect("rtcNewGeometry failed");
            let n = spheres.len();
            let mut vb = g
                .set_new_buffer::<[f32; 4]>(BufferUsage::VERTEX, 0, Format::FLOAT4, 16, n)
                .expect("vertex buffer");
            for (v, s) in vb.iter_mut().zip(spheres) {
                let c = s.center();
                *v = [c.x, c.y, c.z, s.radius()];
            }
            g.commit()
        })
    }

    /// Triangles as one triangle mesh (three vertices each, no sharing).
    pub fn triangles(tris: &[Triangle], rays: &[Ray], coherent: bool) -> Self {
        Self::new(rays, coherent, |device| {
            let mut g = device
                .create_geometry(GeometryKind::TRIANGLE)
                .expect("rtcNewGeometry failed");
            let n = tris.len();
            let mut vb = g
                .set_new_buffer::<[f32; 3]>(BufferUsage::VERTEX, 0, Format::FLOAT3, 12, 3 * n)
                .expect("vertex buffer");
            for (v, t) in vb.chunks_exact_mut(3).zip(tris) {
                v.copy_from_slice(&[t.a().to_array(), t.b().to_array(), t.c().to_array()]);
            }
            let mut ib = g
                .set_new_buffer::<[u32; 3]>(BufferUsage::INDEX, 0, Format::UINT3, 12, n)
                .expect("index buffer");
            for (i, k) in ib.iter_mut().zip((0..).step_by(3)) {
                *i = [k, k + 1, k + 2];
            }
            g.commit()
        })
    }

    /// True when this Embree build culls back faces (then triangles are one-sided).
    pub fn backface_culling(&self) -> bool {
        self.scene
            .device()
            .get_property(DeviceProperty::BACKFACE_CULLING_ENABLED)
            .expect("rtcGetDeviceProperty failed")
            != 0
    }

    fn context(&self) -> IntersectContext {
        if self.coherent {
            IntersectContext::coherent()
        } else {
            IntersectContext::incoherent()
        }
    }

    /// One frame of `rtcIntersect1`: returns the number of rays hit.
    #[inline(never)]
    pub fn frame1(&self) -> u32 {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        let mut n = 0;
        for template in &self.singles {
            let mut rh = *template;
            self.scene.intersect(&mut ctx, &mut rh);
            n += (rh.hit.geomID != INVALID_ID) as u32;
            std::hint::black_box(&rh);
        }
        n
    }

    /// One frame of `rtcIntersect8`: returns the number of rays hit.
    #[inline(never)]
    pub fn frame8(&self) -> u32 {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        let mut n = 0;
        for (valid, template) in &self.packets {
            let mut p = *template;
            self.scene.intersect8(&mut ctx, &mut p, &valid.0);
            n += p.hit.geomID.iter().filter(|&&g| g != INVALID_ID).count() as u32;
            std::hint::black_box(&p);
        }
        n
    }

    /// Closest hit `(t, primitive)` of every ray with `rtcIntersect1`.
    pub fn answers1(&self) -> Vec<Option<(f32, u32)>> {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        self.singles
            .iter()
            .map(|template| {
                let mut rh = *template;
                self.scene.intersect(&mut ctx, &mut rh);
                (rh.hit.geomID != INVALID_ID).then_some((rh.ray.tfar, rh.hit.primID))
            })
            .collect()
    }

    /// Closest hit `(t, primitive)` of every ray with `rtcIntersect8`.
    pub fn answers8(&self) -> Vec<Option<(f32, u32)>> {
        let mut ctx = self.context();
        let _ftz = FlushDenormals::on();
        let mut out = Vec::new();
        for (valid, template) in &self.packets {
            let mut p = *template;
            self.scene.intersect8(&mut ctx, &mut p, &valid.0);
            for i in 0..8 {
                let hit = p.hit.geomID[i] != INVALID_ID;
                out.push(hit.then_some((p.ray.tfar[i], p.hit.primID[i])));
            }
        }
        // Only the last packet has idle lanes, at its end.
        out.truncate(self.singles.len());
        out
    }
}

/// A shape of an instanced Embree scene: a triangle mesh or sphere points.
pub enum Shape<'a> {
    /// Triangles (one mesh, three vertices each).
    Triangles(&'a [Triangle]),
    /// Spheres (`RTC_GEOMETRY_TYPE_SPHERE_POINT`).
    Spheres(&'a [Sphere]),
}

/// A 3×4 object→world transform (rows `[a0, a1, a2, b]`) as Embree's column-major 4×4.
fn column_major(rows: &[[f32; 4]; 3]) -> [f32; 16] {
    let r = rows;
    [
        r[0][0], r[1][0], r[2][0], 0.0, r[0][1], r[1][1], r[2][1], 0.0, r[0][2], r[1][2], r[2][2],
        0.0, r[0][3], r[1][3], r[2][3], 1.0,
    ]
}

/// An engine's scene in Embree 3's instance API (issue 30): one scene per shape (its own BVH,
/// built once), a top-level scene of `RTC_GEOMETRY_TYPE_INSTANCE` geometries (geometry `i` is
/// instance `i`) whose transforms move every frame (`rtcSetGeometryTransform`,
/// `rtcCommitGeometry`, then `rtcCommitScene`), on a one-thread device.
///
/// Layers: instance masks (`rtcSetGeometryMask`) tested against the ray's mask when this
/// Embree was built with ray masks (`RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED`); otherwise an
/// occlusion filter callback on every shape rejects hits of instances whose layers share no bit
/// with the ray's mask, the same job. Bullets ignore their shooter through an intersection
/// filter callback on every shape: a hit whose instance (`instID`) is the ray's `id` is
/// rejected.
pub struct Instances {
    // Dropped first: the instances reference the shapes' scenes.
    top: embree3::Scene<'static>,
    shapes: Vec<embree3::Scene<'static>>,
    masks: bool,
    count: u32,
}

impl Instances {
    /// `instances` `(shape, layers, transform)` of `shapes`; `dynamic`: the top level with
    /// `RTC_SCENE_FLAG_DYNAMIC` and `RTC_BUILD_QUALITY_LOW` (Embree's advice for scenes rebuilt
    /// every frame), else the defaults.
    pub fn new(shapes: &[Shape], instances: &[(usize, u32, [[f32; 4]; 3])], dynamic: bool) -> Self {
        use embree3::{SoAHit, SoARay};
        use std::sync::Arc;
        let _ftz = FlushDenormals::on();
        let device = Device::with_config(Config {
            threads: 1,
            ..Config::default()
        })
        .expect("rtcNewDevice failed");
        let masks = device
            .get_property(DeviceProperty::RAY_MASK_SUPPORTED)
            .expect("rtcGetDeviceProperty failed")
            != 0;
        let layers: Arc<Vec<u32>> = Arc::new(instances.iter().map(|i| i.1).collect());
        let scenes: Vec<embree3::Scene<'static>> = shapes
            .iter()
            .map(|shape| {
                let mut g = match shape {
                    Shape::Triangles(tris) => {
                        let mut g = device
                            .create_geometry(GeometryKind::TRIANGLE)
                            .expect("rtcNewGeometry failed");
                        let n = tris.len();
                        let mut vb = g
                            .set_new_buffer::<[f32; 3]>(
                                BufferUsage::VERTEX,
                                0,
                                Format::FLOAT3,
                                12,
                                3 * n,
                            )
                            .expect("vertex buffer");
                        for (v, t) in vb.chunks_exact_mut(3).zip(tris.iter()) {
                            v.copy_from_slice(&[
                                t.a().to_array(),
                                t.b().to_array(),
                                t.c().to_array(),
                            ]);
                        }
                        let mut ib = g
                            .set_new_buffer::<[u32; 3]>(BufferUsage::INDEX, 0, Format::UINT3, 12, n)
                            .expect("index buffer");
                        for (i, k) in ib.iter_mut().zip((0..).step_by(3)) {
                            *i = [k, k + 1, k + 2];
                        }
                        g
                    }
                    Shape::Spheres(balls) => {
                        let mut g = device
                            .create_geometry(GeometryKind::SPHERE_POINT)
                            .expect("rtcNewGeometry failed");
                        let mut vb = g
                            .set_new_buffer::<[f32; 4]>(
                                BufferUsage::VERTEX,
                                0,
                                Format::FLOAT4,
                                16,
                                balls.len(),
                            )
                            .expect("vertex buffer");
                        for (v, s) in vb.iter_mut().zip(balls.iter()) {
                            let c = s.center();
                            *v = [c.x, c.y, c.z, s.radius()];
                        }
                        g
                    }
                };
                // Bullets: the shooter's own hits are not hits.
                g.set_intersect_filter_function(
                    |ray: embree3::RayN,
                     hit: embree3::HitN,
                     mut valid: embree3::ValidityN,
                     _: &mut IntersectContext,
                     _: Option<&()>| {
                        for i in 0..ray.len() {
                            if valid[i] != 0 && hit.inst_id(i) == ray.id(i) {
                                valid[i] = 0;
                            }
                        }
                    },
                );
                if !masks {
                    // Layers without ray masks: the same job in an occlusion filter.
                    let layers = Arc::clone(&layers);
                    g.set_occluded_filter_function(
                        move |ray: embree3::RayN,
                              hit: embree3::HitN,
                              mut valid: embree3::ValidityN,
                              _: &mut IntersectContext,
                              _: Option<&()>| {
                            for i in 0..ray.len() {
                                let l = layers.get(hit.inst_id(i) as usize).copied();
                                if valid[i] != 0 && l.unwrap_or(0) & ray.mask(i) == 0 {
                                    valid[i] = 0;
                                }
                            }
                        },
                    );
                }
                let g = g.commit();
                let mut scene = device.create_scene().expect("rtcNewScene failed");
                scene.attach_geometry(&g);
                scene.commit();
                scene
            })
            .collect();
        let mut top = device.create_scene().expect("rtcNewScene failed");
        if dynamic {
            top.set_flags(embree3::SceneFlags::DYNAMIC);
            top.set_build_quality(embree3::BuildQuality::LOW);
        }
        for (i, (shape, layer, rows)) in instances.iter().enumerate() {
            let mut g = device
                .create_geometry(GeometryKind::INSTANCE)
                .expect("rtcNewGeometry failed");
            g.set_instanced_scene(&scenes[*shape]);
            g.set_transform(0, &column_major(rows));
            if masks {
                g.set_mask(*layer);
            }
            let id = top.attach_geometry(&g.commit());
            assert_eq!(id, i as u32, "instance ids in order");
        }
        top.commit();
        let e = device.get_error();
        assert!(
            e == Error::NONE,
            "Embree error {e:?} in the instanced scene"
        );
        Instances {
            top,
            shapes: scenes,
            masks,
            count: instances.len() as u32,
        }
    }

    /// True when this Embree has ray masks (layers are then instance masks, else filters).
    pub fn ray_masks(&self) -> bool {
        self.masks
    }

    /// Moves every instance (`rtcSetGeometryTransform`, `rtcCommitGeometry`).
    pub fn set_transforms<'a>(&mut self, rows: impl Iterator<Item = &'a [[f32; 4]; 3]>) {
        for (i, r) in (0..self.count).zip(rows) {
            self.top.set_geometry_transform(i, 0, &column_major(r));
            self.top.commit_geometry(i);
        }
    }

    /// `rtcCommitScene` of the top level.
    pub fn commit(&mut self) {
        let _ftz = FlushDenormals::on();
        self.top.commit();
    }

    /// The closest hit of `ray` (`rtcIntersect1`) that is not instance `ignore`
    /// (`u32::MAX`: none): `(t, instance, primitive)`.
    pub fn closest(&self, ray: &Ray, ignore: u32) -> Option<(f32, u32, u32)> {
        let mut ctx = IntersectContext::incoherent();
        let (o, d) = (ray.origin().to_array(), ray.dir().to_array());
        let mut rh = RayHit::from(embree3::Ray::segment_with_id(
            o,
            d,
            ray.t_min(),
            ray.t_max(),
            ignore,
        ));
        self.top.intersect(&mut ctx, &mut rh);
        (rh.hit.geomID != INVALID_ID).then_some((rh.ray.tfar, rh.hit.instID[0], rh.hit.primID))
    }

    /// Whether `ray` on the layers `mask` hits anything (`rtcOccluded1`).
    pub fn occluded(&self, ray: &Ray, mask: u32) -> bool {
        let mut ctx = IntersectContext::incoherent();
        let (o, d) = (ray.origin().to_array(), ray.dir().to_array());
        let mut r = embree3::Ray::segment_with_id(o, d, ray.t_min(), ray.t_max(), INVALID_ID);
        r.mask = mask;
        self.top.occluded(&mut ctx, &mut r)
    }

    /// The shapes' scenes (kept alive for the instances).
    pub fn shapes(&self) -> usize {
        self.shapes.len()
    }
}
