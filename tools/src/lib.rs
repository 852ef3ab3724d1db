//! Tools around raylane that need heavier dependencies than its tests should compile:
//! `cargo run --release -p raylane-tools --example precision` writes `docs/precision.svg`.
