//! The host test suite, as one test binary (every kernel is monomorphised once for all tests,
//! which keeps builds quick for each CPU configuration and for the AArch64 run).

mod accuracy;
mod bad_input;
mod bunny;
mod bvh;
mod doc_counts;
mod exact_ref;
mod focal_accuracy;
mod focal_precision;
mod focal_rules;
mod fuzz;
mod lanes;
mod layers;
mod opcount;
mod query;
mod readme;
mod render;
mod robust;
mod rules;
mod study;
mod triangles;
mod vectors;
mod watertight;
mod watertight_range;
