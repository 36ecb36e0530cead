//! Generation time of the procedural scenes: the default forest, the 1.2 M-triangle forest (the
//! scale the voxelizer benchmarks use), the default island and blinds. Throughput is in
//! triangles.
//!
//! `cargo bench -p voxlod-scene --bench procedural`

use std::hint::black_box;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_group, criterion_main};
use voxlod_scene::Scene;
use voxlod_scene::procedural::{BlindsParams, ForestParams, IslandParams, blinds, forest, island};

/// Benchmarks `build`, with its triangle count as the throughput.
fn case(g: &mut BenchmarkGroup<'_, WallTime>, name: &str, build: impl Fn() -> Scene) {
    g.throughput(Throughput::Elements(build().triangle_count() as u64));
    g.bench_function(name, |b| b.iter(|| black_box(build())));
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("procedural");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    let p = ForestParams::default();
    case(&mut g, "forest_default", || forest(&p).unwrap());
    let p = ForestParams::with_target_triangles(1_200_000);
    case(&mut g, "forest_1.2M", || forest(&p).unwrap());
    let p = IslandParams::default();
    case(&mut g, "island_default", || island(&p).unwrap());
    let p = BlindsParams::default();
    case(&mut g, "blinds_default", || blinds(&p).unwrap());
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
