//! Slicemap voxelization time: the CPU reference (`voxlod_cpu::voxelize::slicemap::build`,
//! rayon on all cores) against the GPU path (`voxlod_gpu::slicemap::SlicemapRenderer::build`:
//! host preparation, uploads, the render passes and the readback — the whole call), on the
//! adapter `Context::new` picks. **On a CPU adapter (Mesa's lavapipe) the GPU figures are CPU
//! timings of the GPU path**, never GPU speed; the bench prints the adapter it used.
//!
//! - `slicemap_512x512`: the bunny (3 674 triangles) and the forest's leaves and wood
//!   (`ForestParams::with_target_triangles(200_000)`), a 512 × 512 map from the scene's
//!   framing direction (perspective), at 32, 128 and 512 slices: uniform slicing, local slicing
//!   (one more pass), and conservative coverage (uniform).
//! - `slicemap_grid_256`: aligned orthographic maps of a 256³ grid fitted to the scene, one
//!   axis (z) against the three-axis merge (three maps, ORed into a voxel set) and the exact
//!   conservative voxelizer (`voxlod_cpu::voxelize`, occupancy only) for scale.
//!
//! `cargo bench -p voxlod-gpu --bench slicemap` (one group: append its name).

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use voxlod_cpu::voxelize::slicemap::compare::{aligned_map, map_voxels, merged_voxels};
use voxlod_cpu::voxelize::slicemap::{self as cpu, Coverage, Options, SliceCamera, Slicing};
use voxlod_cpu::voxelize::{Mode, voxelize};
use voxlod_format::GridSpec;
use voxlod_gpu::Context;
use voxlod_gpu::slicemap::SlicemapRenderer;
use voxlod_scene::{Camera, Geometry};

fn bunny() -> Geometry {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
    voxlod_scene::Scene::load(&path).expect("bunny").geometry()
}

fn forest() -> Geometry {
    let p = voxlod_scene::procedural::forest::ForestParams::with_target_triangles(200_000);
    voxlod_scene::procedural::forest::forest(&p).expect("forest").geometry()
}

fn context() -> Option<Context> {
    match Context::new() {
        Ok(ctx) => {
            eprintln!("GPU path on: {}", ctx.summary());
            if ctx.is_cpu() {
                eprintln!("  (a CPU adapter: its figures are CPU timings of the GPU path)");
            }
            Some(ctx)
        }
        Err(e) => {
            eprintln!("no GPU adapter, CPU only: {e}");
            None
        }
    }
}

/// A perspective map framing the scene's bounds, near and far touching its bounding sphere.
fn framing(g: &Geometry, size: u32) -> SliceCamera {
    let (lo, hi) = g.bounds().unwrap();
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length() * 0.5;
    let cam = Camera::framing(Vec3::new(0.45, 0.35, 1.0), c, r, 40.0);
    let dist = (cam.eye - c).length() as f64;
    SliceCamera::from_camera(&cam, size, size, dist - r as f64, dist + r as f64)
}

fn maps(c: &mut Criterion) {
    let ctx = context();
    let renderer = ctx.as_ref().map(|ctx| SlicemapRenderer::new(ctx).expect("pipelines compile"));
    let mut group = c.benchmark_group("slicemap_512x512");
    group.sample_size(10);
    for (name, g) in [("bunny", bunny()), ("forest-200k", forest())] {
        let cam = framing(&g, 512);
        group.throughput(Throughput::Elements(g.triangle_count() as u64));
        for slices in [32, 128, 512] {
            for (label, slicing, coverage) in [
                ("uniform", Slicing::Uniform, Coverage::Standard),
                ("local", Slicing::Local, Coverage::Standard),
                ("conservative", Slicing::Uniform, Coverage::Conservative),
            ] {
                let o = Options { slices, slicing, coverage, ..Options::default() };
                group.bench_function(format!("{name}/{slices}/{label}/cpu"), |b| {
                    b.iter(|| black_box(cpu::build(&g, &cam, &o).unwrap()))
                });
                if let Some(r) = &renderer {
                    group.bench_function(format!("{name}/{slices}/{label}/gpu-path"), |b| {
                        b.iter(|| black_box(r.build(&g, &cam, &o).unwrap()))
                    });
                }
            }
        }
    }
    group.finish();
}

fn grid(c: &mut Criterion) {
    let ctx = context();
    let renderer = ctx.as_ref().map(|ctx| SlicemapRenderer::new(ctx).expect("pipelines compile"));
    let mut group = c.benchmark_group("slicemap_grid_256");
    group.sample_size(10);
    for (name, g) in [("bunny", bunny()), ("forest-200k", forest())] {
        let (lo, hi) = g.bounds().unwrap();
        let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 256).unwrap();
        group.throughput(Throughput::Elements(g.triangle_count() as u64));
        group.bench_function(format!("{name}/one-axis/cpu"), |b| {
            b.iter(|| black_box(aligned_map(&g, &grid, 2, Coverage::Standard).unwrap()))
        });
        group.bench_function(format!("{name}/three-axes/cpu"), |b| {
            b.iter(|| black_box(merged_voxels(&g, &grid, Coverage::Standard).unwrap()))
        });
        if let Some(r) = &renderer {
            group.bench_function(format!("{name}/three-axes/gpu-path"), |b| {
                b.iter(|| {
                    let mut v = None;
                    for axis in 0..3 {
                        let cam = SliceCamera::aligned(&grid, axis).unwrap();
                        let o = Options { slices: grid.dims[axis], ..Options::default() };
                        let m = map_voxels(&r.build(&g, &cam, &o).unwrap(), &grid, axis);
                        match &mut v {
                            None => v = Some(m),
                            Some(acc) => acc.union_with(&m),
                        }
                    }
                    black_box(v)
                })
            });
        }
        let o = voxlod_cpu::voxelize::Options {
            mode: Mode::Conservative,
            triangle_lists: false,
            ..Default::default()
        };
        group.bench_function(format!("{name}/exact-conservative/cpu"), |b| {
            b.iter(|| black_box(voxelize(&g, &grid, &o).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, maps, grid);
criterion_main!(benches);
