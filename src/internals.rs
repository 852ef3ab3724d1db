//! raylane's own internals: the per-set loops, lane-wise records and entry points that its
//! benchmarks (`raylane-bench`), its firmware (`targets/`), its vector runner and its tests
//! reach below [`Query`](crate::Query).
//!
//! **Not covered by semver.** Anything here may change or disappear in any release; it is
//! hidden from the documentation on purpose. User code asks through [`Query`](crate::Query)
//! and reads [`Hit`](crate::Hit) / [`Hits`](crate::Hits).

pub use crate::hit::{Best, HitRecord, LaneHit};
pub use crate::sphere::focal::FocalLanes;
pub use crate::triangle::focal::FocalRays;

/// Sphere entry points below [`Query`](crate::Query): one ray × one sphere, packets × a slice,
/// one ray × spheres packed in lanes.
pub mod sphere {
    pub use crate::sphere::{all, any, any_soa, closest, closest_soa, intersect};

    /// Entry points over a sphere focal cache.
    pub mod focal {
        pub use crate::sphere::focal::{Splat, all, any, any_soa, closest, closest_soa, focus};
    }
}

/// Triangle entry points below [`Query`](crate::Query).
pub mod triangle {
    pub use crate::triangle::{all, any, any_soa, closest, closest_soa, intersect};

    /// Entry points over a triangle focal cache.
    pub mod focal {
        pub use crate::triangle::focal::{
            FocalRays, all, any, any_soa, closest, closest_soa, focus, intersect, intersect_lanes,
        };
    }
}

/// Plane entry points below [`Query`](crate::Query).
pub mod plane {
    pub use crate::plane::{
        all, any, closest, closest_focal, closest_soa, focal_lanes, intersect, intersect_lanes,
    };
}
