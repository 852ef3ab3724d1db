//! Demo scenes and their renderer (feature `demo`): what the kernels do, as pictures.
//!
//! The lectures' scenes ([`scenes`]) are rendered by the crate's packet kernels into
//! caller-provided buffers: `no_std`, no allocation, one [`Tile`] at a time, so the host's
//! `render` example can spread tiles over threads, the tests can render small images and check
//! them, and the firmware under `targets/` can render scene 4 on a Cortex-M4F. Every pixel is
//! computed lane by lane with the same operations at every lane width, so an image does not
//! depend on the packet width or the target: the firmware's `f32` image equals the host's
//! `f32x8` one byte for byte.
//!
//! **Rays.** A [`Camera::Pinhole`] makes packets of primary rays from one focal point
//! ([`Pinhole::row_packet`]); a [`Frame`] then builds the focal caches once, in caller
//! [`Storage`]: [`FocalSphere`] per sphere (guarded, or unguarded for
//! [`Kernel::FocalUnguarded`]), [`FocalPlane`] per plane and, per mesh part, a
//! [`FocalMesh`] whose bounding sphere ([`Mesh::bounded`]) is tested before its triangles.
//! The sphere kernel is chosen per frame: any of the [registry](crate::registry)'s sphere
//! kernels ([`sphere_kernels`]), the focal caches or `quadratic`, `geometric`, `robust`,
//! `pbrt`, `embree` over the same packets. A [`Camera::Ortho`] makes parallel rays with
//! different origins (the precision lecture's orthographic camera): there the non-focal
//! kernels run per packet ([`Watertight`](raylane::triangle::Watertight) for triangles), and
//! [`Kernel::Focal`] builds a focal
//! cache *per ray*, with the ray's own origin as the eye, gathered into lanes — which shows
//! what the guard decides, not how fast the cache is.
//!
//! **Closest hit.** Spheres, then planes, then each mesh part; a kind's hit replaces the best
//! so far only where its `t` is strictly smaller (ties keep the earlier kind and index), and
//! each kind sees the rays' `t_max` relaxed to the best so far (`t + |t|·2^-21`, as in
//! [`hit`](raylane::hit)).
//!
//! **Shading** uses `+ − × ÷ √` and compares only (no transcendental functions, whose library
//! implementations may differ between targets): Lambert's law under one directional light with
//! an ambient term, a checkerboard for [`Paint::Checker`], a sky gradient for rays that hit
//! nothing, and a gamma of 2 (a square root); [`Paint::Normal`] stores the normal map's
//! colours as they are. Triangle normals are the face normals `(B − A) × (C − A)`; every normal is turned
//! towards the viewer.
//!
//! **Output.** RGB8, row-major, for the tile's pixels, and optionally one [`ID_NONE`],
//! [`ID_SPHERE`], [`ID_PLANE`] or [`ID_TRIANGLE`] byte per pixel (what the tests count).
//! [`Stats`] counts rays and ray–primitive tests per lane (a packet of `k` rays against one
//! triangle counts `k`) and the triangle tests that bounding spheres saved.

//!
//! **Files.** Scene types and cameras (`scene.rs`), frame setup and caller
//! storage (`frame.rs`), the tile loop and closest hits (`render.rs`), shading (`shade.rs`),
//! tiles and counts (`tile.rs`), image output (`image.rs`); the vendored bunny through the
//! BVH, the picture the firmware `bvh` and the host's `render --scene bunny-fw` share
//! ([`bunny`]).
//!
//! [`Pinhole::row_packet`]: raylane::camera::Pinhole::row_packet
//! [`FocalSphere`]: raylane::sphere::FocalSphere
//! [`FocalPlane`]: raylane::plane::FocalPlane
//! [`FocalMesh`]: raylane::focal::FocalMesh
//! [`Mesh::bounded`]: raylane::mesh::Mesh::bounded

pub mod bunny;
mod frame;
mod image;
mod render;
mod scene;
pub mod scenes;
mod shade;
pub mod shapes;
mod tile;

pub use frame::{Frame, SetupError, Storage, empty_plane, empty_sphere};
pub use image::{fnv1a, ppm_header};
pub use scene::{Camera, Ortho, Paint, Part, Scene};
pub use tile::{Stats, Tile, tiles};

use crate::registry::{Kernel, Prim};

/// Largest number of mesh parts in a [`Scene`].
pub const MAX_PARTS: usize = 80;

/// Pixel id: the ray hit nothing.
pub const ID_NONE: u8 = 0;
/// Pixel id: the closest hit is a sphere.
pub const ID_SPHERE: u8 = 1;
/// Pixel id: the closest hit is a plane.
pub const ID_PLANE: u8 = 2;
/// Pixel id: the closest hit is a triangle.
pub const ID_TRIANGLE: u8 = 3;

/// The kernels a frame can test spheres with: the [registry](crate::registry)'s sphere
/// kernels, in its order.
pub fn sphere_kernels() -> impl Iterator<Item = Kernel> {
    Kernel::of(Prim::Sphere)
}
