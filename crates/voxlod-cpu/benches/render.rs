//! Renderers: the voxel baseline at 256×256 (4 rays per pixel, shadows on) on the bunny
//! voxelized at 128³ and 256³, its record build, and the ground truth at 128×128 with 16 rays
//! per pixel. Frames per second are 1 / time; each figure uses every core (rayon's pool).
//!
//! `cargo bench -p voxlod-cpu --bench render`; before the criterion runs it prints single-core
//! CPU times, which other processes on the machine do not distort.

mod support;

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use voxlod_cpu::render::{baseline, ground_truth};
use voxlod_cpu::voxelize::{self, voxelize};
use voxlod_format::GridSpec;

use support::{bunny, framing, prepare, single_core};

fn renders(c: &mut Criterion) {
    let scene = bunny();
    let (geometry, bvh) = prepare(&scene);
    let camera = framing(&scene);
    let light = scene.light();
    let (lo, hi) = scene.bounds().expect("a non-empty scene");

    let mut group = c.benchmark_group("baseline");
    group.sample_size(20);
    for res in [128, 256] {
        let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res).expect("a valid grid");
        let v = voxelize(&geometry, &grid, &voxelize::Options::default()).expect("voxelized");
        let voxels = baseline::build(&scene, &geometry, &v).expect("baseline records");
        eprintln!(
            "bunny at {res}³: {} voxels, {} bytes of records ({} bytes/voxel)",
            voxels.len(),
            voxels.len() * size_of::<baseline::BaselineVoxel>(),
            size_of::<baseline::BaselineVoxel>()
        );
        group.throughput(Throughput::Elements(voxels.len() as u64));
        group.bench_function(format!("build/bunny-{res}"), |b| {
            b.iter(|| black_box(baseline::build(&scene, &geometry, &v).expect("built")))
        });
        let options = baseline::Options { width: 256, height: 256, ..Default::default() };
        let mut t: Vec<_> = (0..5)
            .map(|_| {
                single_core(|| {
                    baseline::render(&grid, &voxels, &camera, &light, scene.background, &options)
                })
                .1
            })
            .collect();
        t.sort();
        eprintln!(
            "baseline render, bunny at {res}³, 256×256: {:.1} ms per frame on one core (CPU time)",
            t[2].as_secs_f64() * 1e3
        );
        group.throughput(Throughput::Elements(256 * 256));
        group.bench_function(format!("render/bunny-{res}/256x256"), |b| {
            b.iter(|| {
                black_box(
                    baseline::render(&grid, &voxels, &camera, &light, scene.background, &options)
                        .expect("rendered"),
                )
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("ground_truth");
    group.sample_size(10);
    let options = ground_truth::Options { width: 128, height: 128, spp: 16, ..Default::default() };
    let (_, t) = single_core(|| ground_truth::render(&scene, &geometry, &bvh, &camera, &options));
    eprintln!(
        "ground truth, bunny, 128×128 × 16 spp: {:.1} ms on one core (CPU time), {:.2} M camera \
         rays per CPU-second (plus shadow rays)",
        t.as_secs_f64() * 1e3,
        128.0 * 128.0 * 16.0 / t.as_secs_f64() / 1e6
    );
    group.throughput(Throughput::Elements(128 * 128 * 16));
    group.bench_function("bunny/128x128/16spp", |b| {
        b.iter(|| {
            black_box(ground_truth::render(&scene, &geometry, &bvh, &camera, &options).expect("ok"))
        })
    });
    group.finish();
}

criterion_group!(render, renders);
criterion_main!(render);
