//! The filtered voxel renderer: the bunny voxelized at 256³, its Averages, \[VJK21\] (SGGX) and
//! virtual-mesh grids (150 rays per voxel), rendered at 256×256 with 4 rays per pixel and
//! shadows: cache cold (every cached value forgotten before the frame), warm (the same
//! camera again) and new-view (view slots forgotten, shadows kept: a camera that moved under
//! an unchanged light, the paper's "shadows precomputed"). Frames per second are 1 / time;
//! the criterion figures use every core (rayon's pool).
//!
//! `cargo bench -p voxlod-cpu --bench filtered`; before the criterion runs it prints the
//! precompute times, the cache build times, and single-core CPU times of cold, warm and
//! new-view frames, which other processes on the machine distort less than wall time.
//! `VOXLOD_BENCH_ONLY=averages` (or `vjk21`, `virtual-mesh`; comma-separated) skips the
//! precompute and frames of the other representations, e.g. for profiling one of them.

mod support;

use std::hint::black_box;
use std::time::Instant;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_group, criterion_main};
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::virtual_mesh::VirtualMeshGrid;
use voxlod_cpu::appearance::{Appearance, averages, sggx, virtual_mesh};
use voxlod_cpu::render::filtered::{self, FrameCache};
use voxlod_cpu::voxelize::{self, voxelize};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::{Camera, Light, Scene};

use support::{bunny, framing, prepare, single_core};

/// Image edge and grid resolution: 256² pixels of a 256³ grid.
const SIZE: u32 = 256;
const RES: u32 = 256;

/// What one representation's frames need.
struct View<'a> {
    scene: &'a Scene,
    camera: Camera,
    light: Light,
    options: filtered::Options,
}

/// Prints single-core cold and warm frame times of `app`, then benches both on all threads.
fn bench_representation<A: Appearance + ?Sized, T>(
    group: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    app: &A,
    layout: &BrickMap<T>,
    view: &View<'_>,
) {
    let start = Instant::now();
    let scanned = FrameCache::new(app).expect("a cache").memory_bytes();
    let scan = start.elapsed();
    let start = Instant::now();
    let mut cache = FrameCache::with_layout(app, layout).expect("a cache");
    let built = start.elapsed();
    assert_eq!(scanned, cache.memory_bytes());
    let bg = view.scene.background;
    let frame = |cache: &mut FrameCache<'_, A>| {
        filtered::render(cache, &view.camera, &view.light, bg, &view.options).expect("rendered")
    };
    let (mut cold, mut warm, mut moved) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..5 {
        cache.clear();
        cold.push(single_core(|| frame(&mut cache)).1);
        warm.push(single_core(|| frame(&mut cache)).1);
        cache.clear_view();
        moved.push(single_core(|| frame(&mut cache)).1);
    }
    cold.sort();
    warm.sort();
    moved.sort();
    eprintln!(
        "{name}: {} voxels, cache built in {:.1} ms from the layout, {:.1} ms by scanning the \
         grid ({:.1} MB); one core (CPU time, median of 5): cold {:.1} ms, warm {:.1} ms, \
         new view {:.1} ms per frame; {} voxels shaded, {} shadow rays",
        app.len(),
        built.as_secs_f64() * 1e3,
        scan.as_secs_f64() * 1e3,
        cache.memory_bytes() as f64 / 1e6,
        cold[2].as_secs_f64() * 1e3,
        warm[2].as_secs_f64() * 1e3,
        moved[2].as_secs_f64() * 1e3,
        cache.cached_views(),
        cache.cached_shadows(),
    );
    group.bench_function(format!("{name}/bunny-{RES}/{SIZE}x{SIZE}/warm"), |b| {
        frame(&mut cache);
        b.iter(|| black_box(frame(&mut cache)))
    });
    group.bench_function(format!("{name}/bunny-{RES}/{SIZE}x{SIZE}/cold"), |b| {
        b.iter(|| {
            cache.clear();
            black_box(frame(&mut cache))
        })
    });
    group.bench_function(format!("{name}/bunny-{RES}/{SIZE}x{SIZE}/new-view"), |b| {
        b.iter(|| {
            cache.clear_view();
            black_box(frame(&mut cache))
        })
    });
}

fn renders(c: &mut Criterion) {
    let scene = bunny();
    let (geometry, _) = prepare(&scene);
    let (lo, hi) = scene.bounds().expect("a non-empty scene");
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), RES).expect("a valid grid");
    let vox = voxelize(&geometry, &grid, &voxelize::Options::default()).expect("voxelized");
    let ctx = SamplingContext::new(&scene, &geometry, &vox).expect("a sampling context");
    let options = PrecomputeOptions::default();
    let view = View {
        scene: &scene,
        camera: framing(&scene),
        light: scene.light(),
        options: filtered::Options { width: SIZE, height: SIZE, ..Default::default() },
    };
    let mut group = c.benchmark_group("filtered");
    group.sample_size(10);
    group.throughput(Throughput::Elements(u64::from(SIZE * SIZE)));

    let only = std::env::var("VOXLOD_BENCH_ONLY").ok();
    let wanted = |name: &str| only.as_ref().is_none_or(|o| o.split(',').any(|w| w.trim() == name));

    if wanted("averages") {
        let start = Instant::now();
        let averages = precompute(&ctx, &options, averages::fit).expect("averages");
        eprintln!("averages precompute: {:.2} s on all cores", start.elapsed().as_secs_f64());
        bench_representation(&mut group, "averages", &averages, &averages.records, &view);
    }
    if wanted("vjk21") {
        let start = Instant::now();
        let sggx = precompute(&ctx, &options, sggx::fit).expect("sggx");
        eprintln!("vjk21 precompute: {:.2} s on all cores", start.elapsed().as_secs_f64());
        bench_representation(&mut group, "vjk21", &sggx, &sggx.records, &view);
    }
    if wanted("virtual-mesh") {
        let start = Instant::now();
        let mesh =
            VirtualMeshGrid::new(precompute(&ctx, &options, virtual_mesh::fit).expect("vmesh"));
        eprintln!("virtual mesh precompute: {:.2} s on all cores", start.elapsed().as_secs_f64());
        bench_representation(&mut group, "virtual-mesh", &mesh, &mesh.grid.records, &view);
    }
    group.finish();
}

criterion_group!(filtered_benches, renders);
criterion_main!(filtered_benches);
