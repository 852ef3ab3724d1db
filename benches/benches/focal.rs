//! The focal guard's cost on general scenes: guarded vs unguarded focal caches, closest hit of
//! 8-ray packets of primary rays over N spheres (issue 2: within 10% of the unguarded speed).
//!
//! Each variant is one out-of-line function ([`guard_frame`]) called by its benchmark.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raylane::sphere::focal::{Focal, FocalUnguarded};
use raylane_bench::{GuardScene, guard_frame};

fn bench(c: &mut Criterion) {
    for n in [16usize, 64, 256] {
        let s = GuardScene::new(n);
        let mut g = c.benchmark_group(format!("focal-guard/{n}"));
        g.throughput(Throughput::Elements(s.tests() as u64));
        g.bench_function("unguarded", |b| {
            b.iter(|| guard_frame::<FocalUnguarded>(&s.packets, &s.unguarded))
        });
        g.bench_function("guarded", |b| {
            b.iter(|| guard_frame::<Focal>(&s.packets, &s.guarded))
        });
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
