//! Shared by the criterion benches: settings, and a record of every measurement for the
//! summary tables printed after criterion's own report.
//!
//! Each benchmark times one frame per iteration through `iter_custom`; the time per frame of
//! each sample is kept, and the summary reports the median of the last `SAMPLES` samples
//! (criterion's measurement phase; the warm-up comes first).
#![allow(dead_code)] // each bench uses part of this module

use std::collections::BTreeMap;
use std::hint::black_box;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use criterion::{Bencher, Criterion};

/// Samples per benchmark.
pub const SAMPLES: usize = 10;

/// Short runs (every benchmark is one frame of about 2^18 tests, and the matrices are large):
/// `SAMPLES` samples over `measure_ms` after a warm-up of a third of that.
pub fn criterion(measure_ms: u64) -> Criterion {
    Criterion::default()
        .sample_size(SAMPLES)
        .warm_up_time(Duration::from_millis(measure_ms / 3))
        .measurement_time(Duration::from_millis(measure_ms))
        .configure_from_args()
}

/// What one benchmark measured.
#[derive(Clone, Debug, Default)]
pub struct Record {
    /// Ray–primitive tests per frame (0 when not meaningful, e.g. Embree's BVH).
    pub tests: u64,
    /// Rays per frame.
    pub rays: u64,
    /// Seconds per frame of each sample.
    pub secs: Vec<f64>,
}

impl Record {
    /// Median seconds per frame over the measurement samples.
    pub fn median(&self) -> f64 {
        let k = self.secs.len().saturating_sub(SAMPLES);
        let mut s = self.secs[k..].to_vec();
        s.sort_by(f64::total_cmp);
        s.get(s.len() / 2).copied().unwrap_or(f64::NAN)
    }

    /// Tests per second.
    pub fn tests_per_sec(&self) -> f64 {
        self.tests as f64 / self.median()
    }

    /// Rays per second.
    pub fn rays_per_sec(&self) -> f64 {
        self.rays as f64 / self.median()
    }
}

static RECORDS: Mutex<BTreeMap<(String, String), Record>> = Mutex::new(BTreeMap::new());

/// Times `frame` as criterion's routine (one frame per iteration) and records each sample
/// under `(group, id)`.
pub fn timed<R>(
    b: &mut Bencher,
    key: (&str, &str),
    tests: u64,
    rays: u64,
    mut frame: impl FnMut() -> R,
) {
    b.iter_custom(|iters| {
        let start = Instant::now();
        for _ in 0..iters {
            black_box(frame());
        }
        let e = start.elapsed();
        let mut map = RECORDS.lock().unwrap();
        let r = map
            .entry((key.0.to_string(), key.1.to_string()))
            .or_default();
        r.tests = tests;
        r.rays = rays;
        r.secs.push(e.as_secs_f64() / iters.max(1) as f64);
        e
    });
}

/// Every record so far, by (group, id).
pub fn records() -> BTreeMap<(String, String), Record> {
    RECORDS.lock().unwrap().clone()
}

/// `x` with an SI prefix and 3 significant digits (`1.23 G`).
pub fn si(x: f64) -> String {
    if !x.is_finite() {
        return "-".into();
    }
    let (v, p) = if x >= 1e9 {
        (x / 1e9, "G")
    } else if x >= 1e6 {
        (x / 1e6, "M")
    } else if x >= 1e3 {
        (x / 1e3, "k")
    } else {
        (x, "")
    };
    let digits = if v >= 100.0 {
        0
    } else if v >= 10.0 {
        1
    } else {
        2
    };
    format!("{v:.digits$} {p}")
}
