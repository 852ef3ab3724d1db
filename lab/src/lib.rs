//! raylane's lab: what tests, measures and demonstrates the library, kept out of it.
//!
//! The library (`raylane`) is what a user links: kernels, lanes, rays, hits, sets, the query
//! API, the camera and the counting lane. This crate holds the machinery around it, shared by
//! raylane's examples, host tests, benchmarks and firmware (`targets/`), `no_std` and without
//! allocation so that the firmware runs the same code:
//!
//! * [`registry`]: the one list of kernels, which every tool below walks;
//! * [`loops`]: every kernel over slices in both packet shapes (N rays × 1 primitive, 1 ray ×
//!   N primitives), for the tests that compare them and the benchmarks that time a kernel;
//! * [`vectors`]: the test-vector parser, the batched runner and the result digest that every
//!   target must reproduce;
//! * [`opcount`]: the op-count report (every kernel's paths measured with the counting lane);
//! * [`study`]: the op-count study of every published method;
//! * [`demo`]: the lectures' scenes and their tile renderer (the `render` example, the
//!   firmware's `render` and `bvh` binaries).

#![no_std]
#![deny(missing_docs)]

pub mod demo;
pub mod loops;
pub mod opcount;
pub mod registry;
pub mod study;
pub mod vectors;
