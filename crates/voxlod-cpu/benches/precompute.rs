//! Appearance precompute: ray sampling (150 lines per voxel) plus the Averages fit, on the
//! bunny at 256³ and the forest (~200 k triangles) at 256³, on one thread and on every core.
//! Throughput is in voxels per second (criterion's elements).
//!
//! `cargo bench -p voxlod-cpu --bench precompute`; before the criterion runs it prints
//! single-core CPU times (which other processes on the machine do not distort) and the
//! target, 50 000 voxels/s per core on the bunny at 256³. Set
//! `VOXLOD_BENCH_FITS=subgrid,vjk21,virtual-mesh` (any of them, comma-separated) to also time,
//! on one core, sampling plus that fit: the subgrid alone, \[VJK21\] (SGGX + transmittance),
//! the virtual mesh (SGGX, faces, subgrid).

mod support;

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::{averages, sggx, subgrid, virtual_mesh};
use voxlod_scene::Scene;

use support::{bunny, forest_of, pool, single_core, voxelized};

/// The precompute's throughput target on the bunny at 256³, voxels per second per core.
const TARGET_PER_CORE: f64 = 50_000.0;

fn bench_scene(c: &mut Criterion, name: &str, scene: &Scene, res: u32, samples: usize) {
    let geometry = scene.geometry();
    let vox = voxelized(scene, &geometry, res);
    let ctx = SamplingContext::new(scene, &geometry, &vox).expect("a valid scene");
    let opts = PrecomputeOptions::default();
    let voxels = ctx.voxel_count() as u64;
    let (grid, cpu) = single_core(|| precompute(&ctx, &opts, averages::fit).expect("fitted"));
    let per_core = voxels as f64 / cpu.as_secs_f64();
    eprintln!(
        "{name} at {res}³ ({} triangles): {voxels} voxels ({:.2} triangles each), {} records; \
         sampling + Averages at {} rays: {:.0} ms on one core (CPU time) = {per_core:.0} \
         voxels/s per core{}",
        geometry.triangle_count(),
        vox.triangles.len() as f64 / voxels.max(1) as f64,
        grid.records.len(),
        opts.rays,
        cpu.as_secs_f64() * 1e3,
        if name == "bunny" {
            format!(" (target {TARGET_PER_CORE:.0}: {:.2}×)", per_core / TARGET_PER_CORE)
        } else {
            String::new()
        }
    );
    let fits = std::env::var("VOXLOD_BENCH_FITS").unwrap_or_default();
    let wanted = |fit: &str| fits.split(',').any(|f| f.trim() == fit);
    let report = |fit: &str, cpu: std::time::Duration| {
        eprintln!(
            "{name} at {res}³: sampling + {fit}: {:.0} ms on one core (CPU time) = {:.0} \
                 voxels/s per core",
            cpu.as_secs_f64() * 1e3,
            voxels as f64 / cpu.as_secs_f64()
        )
    };
    if wanted("subgrid") {
        let build = |s: &_| Some(subgrid::build(s));
        report("subgrid build", single_core(|| precompute(&ctx, &opts, build).expect("built")).1);
    }
    if wanted("vjk21") {
        report(
            "[VJK21] fit",
            single_core(|| precompute(&ctx, &opts, sggx::fit).expect("fitted")).1,
        );
    }
    if wanted("virtual-mesh") {
        let fit = || precompute(&ctx, &opts, virtual_mesh::fit).expect("fitted");
        report("virtual-mesh fit", single_core(fit).1);
    }

    let mut group = c.benchmark_group("precompute");
    group.sample_size(samples);
    group.throughput(Throughput::Elements(voxels));
    let one = pool(1);
    group.bench_function(format!("averages/{name}-{res}/1-thread"), |b| {
        b.iter(|| one.install(|| black_box(precompute(&ctx, &opts, averages::fit).unwrap())))
    });
    group.bench_function(format!("averages/{name}-{res}/all-threads"), |b| {
        b.iter(|| black_box(precompute(&ctx, &opts, averages::fit).unwrap()))
    });
    group.finish();
}

fn precomputes(c: &mut Criterion) {
    bench_scene(c, "bunny", &bunny(), 256, 10);
    bench_scene(c, "forest", &forest_of(200_000), 256, 10);
}

criterion_group!(benches, precomputes);
criterion_main!(benches);
