//! The focal guard's cost on general scenes: guarded vs unguarded focal caches, closest hit of
//! 8-ray packets of primary rays over N spheres (issue 2: within 10% of the unguarded speed).
//!
//! Each variant is one out-of-line function called by its benchmark, so both are compiled once
//! and the comparison is not at the mercy of how each closure happens to be inlined and placed.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raylane::Ray8;
use raylane::sphere::FocalSphere;
use raylane::sphere::focal::{self, Focal, FocalKernel, FocalUnguarded};
use raylane_bench::sphere_scene;

/// Closest hits of every packet over every cached sphere; returns the number of lanes hit.
#[inline(never)]
fn frame<K: FocalKernel>(packets: &[Ray8], cache: &[FocalSphere<f32>]) -> u32 {
    packets
        .iter()
        .map(|p| {
            focal::closest::<K, _>(black_box(p), cache)
                .mask
                .to_bitmask()
                .count_ones()
        })
        .sum()
}

fn bench(c: &mut Criterion) {
    for n in [16usize, 64, 256] {
        let (cam, spheres) = sphere_scene(n, 7, 128, 96);
        let packets: Vec<Ray8> = (0..cam.height)
            .flat_map(|y| (0..cam.width).step_by(8).map(move |x| (x, y)))
            .map(|(x, y)| cam.row_packet(x, y))
            .collect();
        let guarded: Vec<FocalSphere<f32>> = spheres
            .iter()
            .map(|s| FocalSphere::new(cam.eye, s))
            .collect();
        let unguarded: Vec<FocalSphere<f32>> = spheres
            .iter()
            .map(|s| FocalSphere::unguarded(cam.eye, s))
            .collect();
        let mut g = c.benchmark_group(format!("focal-guard/{n}"));
        g.throughput(Throughput::Elements((packets.len() * 8 * n) as u64));
        g.bench_function("unguarded", |b| {
            b.iter(|| frame::<FocalUnguarded>(&packets, &unguarded))
        });
        g.bench_function("guarded", |b| b.iter(|| frame::<Focal>(&packets, &guarded)));
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
