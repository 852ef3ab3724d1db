//! The host test suite, as one test binary (every kernel is monomorphised once for all tests,
//! which keeps builds quick for each CPU configuration and for the AArch64 run).

mod bad_input;
mod focal_precision;
mod fuzz;
mod lanes;
mod opcount;
mod readme;
#[cfg(feature = "demo")]
mod render;
mod robust;
mod triangles;
#[cfg(feature = "vectors")]
mod vectors;
mod watertight;
#[cfg(feature = "demo")]
mod watertight_range;
