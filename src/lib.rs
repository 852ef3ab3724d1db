//! # raylane
//!
//! Ray–sphere, ray–plane and ray–triangle intersection kernels that test many rays at once in
//! SIMD lanes, spend as few floating-point operations as the mathematics allows, and give the
//! same bits on x86-64, AArch64 and Cortex-M.
//!
//! * **One body of math per kernel.** Every kernel is a generic function over [`Lane`]:
//!   `f32` (the scalar reference), `f64`, `wide::f32x4`/`f32x8`/`f32x16` packets, and
//!   [`Counted`](opcount::Counted), which counts the operations the body performs.
//! * **Same bits everywhere.** Only correctly rounded IEEE-754 operations, in an order the
//!   generic body fixes, no fused multiply-add: every lane of every width equals the scalar
//!   path bit for bit, on every target.
//! * **No panics, no allocation.** Bad input (NaN, infinity, zero direction, non-positive
//!   radius, degenerate primitives) is a documented miss; caches live in caller storage.
//!
//! ## Conventions
//!
//! * A ray is `o + t·d` over an open interval: a hit needs `t_min < t < t_max`
//!   ([`Ray::new`] uses `(0, +inf)`). `t` is in units of `|d|`.
//! * Directions need not be unit length, except for the methods that say so:
//!   [`sphere::QuadraticUnit`], [`sphere::Geometric`] and the sphere focal kernels
//!   ([`sphere::focal`]). Those normalise nothing; through a query, other rays are a miss for
//!   the first two and are answered in world mode by [`focal::FocalSpheres`].
//! * Sphere kernels return every root inside the interval, ascending.
//! * Triangle hits carry barycentrics: `u` weighs vertex B, `v` vertex C. Triangles are
//!   two-sided unless back faces are culled ([`Cull`]); the `watertight` and `focal`
//!   kernels never let a ray slip between triangles that share an edge or a vertex.
//! * Misses are canonical: `t = +inf`, index `u32::MAX`; no hit record ever holds a NaN.
//!
//! ## Layout
//!
//! [`lane`] (the abstraction), [`vec3`] (`V3<L>`, SoA vectors), [`ray`] (rays and packets),
//! [`camera`] (pinhole primary rays from one focal point), [`sphere`], [`plane`], [`triangle`],
//! [`mesh`] (triangles over shared vertex slices), [`bounds`] (bounding spheres and culling),
//! [`bvh`] (the bounding volume hierarchy and its instances), [`query`] (the one way to ask:
//! [`Query`], [`Hit`], [`Hits`]) and [`opcount`] (the counting lane). `ARCHITECTURE.md` draws
//! the layers. The kernel registry, the test-vector runner, the op-count report and study and
//! the demo scenes live in the workspace's `lab` crate, beside the library.
//!
//! ## Example
//!
//! ```
//! use glam::Vec3;
//! use raylane::{Query, Ray, sphere::{Sphere, Robust}};
//!
//! let ray = Ray::new(Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 2.0, 1.0));
//! let ball = [Sphere::new(Vec3::splat(5.0), 3.0)];
//! let hit = ball[..].using::<Robust>().closest(&ray).unwrap();
//! assert!((ray.at(hit.t) - Vec3::new(3.0, 4.0, 3.0)).length() < 1e-5);
//! ```

#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_op_in_unsafe_fn)]

#[cfg(feature = "alloc")]
extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub mod bounds;
pub mod bvh;
pub mod camera;
pub mod focal;
pub mod hit;
pub mod kernel;
pub mod lane;
pub mod mesh;
pub mod opcount;
pub mod plane;
pub mod query;
pub mod ray;
pub mod set;
pub mod simd;
pub mod sphere;
pub mod triangle;
pub mod vec3;

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

/// The design notes' examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../docs/design.md")]
struct DesignDoctests;

pub use camera::{Pinhole, Tile};
pub use hit::{Hit, Hits};
pub use kernel::Cull;
pub use lane::{Lane, Mask};
pub use query::{Query, Rays};
pub use ray::{Dir, Ray, Ray4, Ray8, Ray16, RayPacket};
pub use vec3::V3;

/// The vector library of the API (`raylane::glam::Vec3`): no need to pin its version.
pub use glam;
/// The SIMD library of the packets (`raylane::wide::f32x8`).
pub use wide;
