//! Benchmarks of the image metrics at report sizes: SSIM (the hot path: two separable 11-tap
//! Gaussian passes over five moment images per channel) and MSE, on 512² and 1024² images.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use voxlod_eval::patterns;

fn metrics(c: &mut Criterion) {
    let mut group = c.benchmark_group("metrics");
    group.sample_size(20);
    for size in [512u32, 1024] {
        let a = patterns::noise(size, size, 1);
        let b = patterns::box_blur(&a);
        group.bench_function(format!("ssim_{size}"), |bench| {
            bench.iter(|| voxlod_eval::ssim(black_box(&a), black_box(&b)).unwrap())
        });
        group.bench_function(format!("mse_{size}"), |bench| {
            bench.iter(|| voxlod_eval::mse(black_box(&a), black_box(&b)).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, metrics);
criterion_main!(benches);
