//! Frame setup: the focal caches in caller storage and each mesh part's bounding sphere.

use glam::Vec3;

use super::{Camera, MAX_PARTS, Paint, Scene};
use crate::registry::{Family, Kernel, Prim};
use raylane::Cull;
use raylane::focal::FocalMesh;
use raylane::mesh::Mesh;
use raylane::plane::{FocalPlane, Plane};
use raylane::sphere::{FocalSphere, Sphere};
use raylane::triangle::FocalTriangle;

/// Caller storage for a frame's focal caches. Pinhole frames need one sphere entry per sphere
/// (focal methods only), one plane entry per plane and one triangle entry per triangle of every
/// part; orthographic frames need none ([`Storage::none`]).
#[derive(Debug)]
pub struct Storage<'c> {
    /// Sphere entries.
    pub spheres: &'c mut [FocalSphere<f32>],
    /// Plane entries.
    pub planes: &'c mut [FocalPlane],
    /// Triangle entries.
    pub triangles: &'c mut [FocalTriangle<f32>],
}

impl Storage<'static> {
    /// No storage (orthographic frames).
    #[must_use]
    pub fn none() -> Self {
        Storage {
            spheres: &mut [],
            planes: &mut [],
            triangles: &mut [],
        }
    }
}

/// An unused sphere cache entry (never hit), to fill storage arrays with.
#[must_use]
pub fn empty_sphere() -> FocalSphere<f32> {
    FocalSphere::new(Vec3::ZERO, &Sphere::new(Vec3::ZERO, f32::NAN))
}

/// An unused plane cache entry (never hit), to fill storage arrays with.
#[must_use]
pub fn empty_plane() -> FocalPlane {
    FocalPlane::new(Vec3::ZERO, &Plane::new(Vec3::ZERO, Vec3::ZERO))
}

/// Why a frame cannot be set up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetupError {
    /// More than [`MAX_PARTS`] mesh parts.
    TooManyParts,
    /// A part's triangles lie outside the scene's index triples.
    BadPart,
    /// Too few sphere entries in the storage.
    SphereStorage,
    /// Too few plane entries in the storage.
    PlaneStorage,
    /// Too few triangle entries in the storage.
    TriangleStorage,
    /// The frame's kernel does not test spheres.
    NotSphereKernel,
}

/// One mesh part, ready to render: the mesh, or its focal cache (which holds the mesh).
#[derive(Clone, Copy, Debug)]
pub(super) struct Piece<'a> {
    pub(super) surface: Surface<'a>,
    pub(super) paint: Paint,
    pub(super) cull: Cull,
}

/// A part's triangles: the mesh alone (orthographic frames) or with its focal cache.
#[derive(Clone, Copy, Debug)]
pub(super) enum Surface<'a> {
    Plain(Mesh<'a>),
    Focal(FocalMesh<'a>),
}

impl<'a> Piece<'a> {
    /// The part's mesh.
    pub(super) fn mesh(&self) -> &Mesh<'a> {
        match &self.surface {
            Surface::Plain(m) => m,
            Surface::Focal(f) => f.mesh(),
        }
    }
}

/// A scene seen by one camera with one sphere kernel, its caches built (see the
/// [module docs](super)). Shared by reference between the threads that render its tiles.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a, const P: usize = MAX_PARTS> {
    pub(super) scene: Scene<'a>,
    pub(super) camera: Camera,
    pub(super) kernel: Kernel,
    pub(super) spheres: &'a [FocalSphere<f32>],
    pub(super) planes: &'a [FocalPlane],
    pub(super) pieces: [Option<Piece<'a>>; P],
}

impl<'a, const P: usize> Frame<'a, P> {
    /// Sets up `scene` for `camera` and the sphere kernel `kernel` (one of
    /// [`sphere_kernels`](super::sphere_kernels)): builds the focal caches in `storage` (pinhole
    /// cameras) and each part's bounding sphere.
    pub fn new(
        scene: Scene<'a>,
        camera: Camera,
        kernel: Kernel,
        storage: Storage<'a>,
    ) -> Result<Self, SetupError> {
        if kernel.prim() != Prim::Sphere {
            return Err(SetupError::NotSphereKernel);
        }
        if scene.parts.len() > P {
            return Err(SetupError::TooManyParts);
        }
        let eye = match camera {
            Camera::Pinhole(p) => Some(p.eye),
            Camera::Ortho(_) => None,
        };
        let spheres = match (eye, kernel.family()) {
            (Some(e), Family::FocalSphere { guarded }) => {
                focus_spheres(e, scene.spheres, guarded, storage.spheres)?
            }
            _ => &[],
        };
        let planes = match eye {
            Some(e) => focus_planes(e, scene.planes, storage.planes)?,
            None => &[],
        };
        Ok(Frame {
            scene,
            camera,
            kernel,
            spheres,
            planes,
            pieces: pieces(&scene, eye, storage.triangles)?,
        })
    }

    /// The camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> &Scene<'a> {
        &self.scene
    }

    /// The sphere kernel.
    #[must_use]
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }
}

/// The sphere caches for rays from `eye` (guarded or not) in `store`.
fn focus_spheres<'a>(
    eye: Vec3,
    spheres: &[Sphere],
    guarded: bool,
    store: &'a mut [FocalSphere<f32>],
) -> Result<&'a [FocalSphere<f32>], SetupError> {
    let out = store
        .get_mut(..spheres.len())
        .ok_or(SetupError::SphereStorage)?;
    for (o, s) in out.iter_mut().zip(spheres) {
        *o = if guarded {
            FocalSphere::new(eye, s)
        } else {
            FocalSphere::unguarded(eye, s)
        };
    }
    Ok(out)
}

/// The plane caches for rays from `eye` in `store`.
fn focus_planes<'a>(
    eye: Vec3,
    planes: &[Plane],
    store: &'a mut [FocalPlane],
) -> Result<&'a [FocalPlane], SetupError> {
    let out = store
        .get_mut(..planes.len())
        .ok_or(SetupError::PlaneStorage)?;
    for (o, p) in out.iter_mut().zip(planes) {
        *o = FocalPlane::new(eye, p);
    }
    Ok(out)
}

/// Every part of `scene` as a bounded mesh and, for rays from `eye`, its triangle caches (taken
/// from `store` in part order).
fn pieces<'a, const P: usize>(
    scene: &Scene<'a>,
    eye: Option<Vec3>,
    mut store: &'a mut [FocalTriangle<f32>],
) -> Result<[Option<Piece<'a>>; P], SetupError> {
    let mut pieces = [None; P];
    for (slot, part) in pieces.iter_mut().zip(scene.parts) {
        let (first, n) = (part.first as usize, part.count as usize);
        let indices = scene
            .indices
            .get(first..first.saturating_add(n))
            .ok_or(SetupError::BadPart)?;
        let mesh = Mesh::bounded(scene.positions, indices);
        let surface = match eye {
            Some(e) => {
                let (head, rest) = core::mem::take(&mut store)
                    .split_at_mut_checked(n)
                    .ok_or(SetupError::TriangleStorage)?;
                store = rest;
                Surface::Focal(
                    FocalMesh::new(&mesh, e, head).map_err(|_| SetupError::TriangleStorage)?,
                )
            }
            None => Surface::Plain(mesh),
        };
        *slot = Some(Piece {
            surface,
            paint: part.paint,
            cull: part.cull,
        });
    }
    Ok(pieces)
}
