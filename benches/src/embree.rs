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
pub(crate) struct FlushDenormals(u32);

impl FlushDenormals {
    #[allow(deprecated)] // _mm_getcsr/_mm_setcsr: still the plain way to save and restore MXCSR
    pub(crate) fn on() -> Self {
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
