//! The host test suite, as one test binary (every kernel is monomorphised once for all tests,
//! which keeps builds quick for each CPU configuration and for the AArch64 run), grouped by
//! subject: the kernels, the sets and their queries, the BVH, what the targets must reproduce,
//! and the docs that cannot drift.

mod kernels {
    pub mod accuracy_pinned;
    pub mod bad_input_misses;
    pub mod exact_reference;
    pub mod focal_sphere_guard;
    pub mod focal_triangle_accuracy;
    pub mod focal_triangle_ends;
    pub mod fuzz_every_width;
    pub mod lanes_equal_scalar;
    pub mod magnitude_regressions;
    pub mod op_count_study;
    pub mod op_counts_pinned;
    pub mod triangle_lanes_and_culling;
    pub mod vectors_every_width;
    pub mod watertight_no_leaks;
    pub mod watertight_range_ends;
}

mod sets {
    pub mod bunny_visible_surface;
    pub mod camera_tiles;
    pub mod interval_ties_and_stopping;
    pub mod masks_and_filters;
    pub mod query_records_every_width;
}

mod bvh {
    pub mod baked_trees;
    pub mod equals_brute_force;
    pub mod from_parts_checked;
    pub mod owned_scenes;
}

mod targets {
    pub mod render_same_bytes;
}

mod docs {
    pub mod doc_op_counts;
    pub mod layers_hold;
    pub mod op_count_table;
    pub mod readme_firmware;
}
