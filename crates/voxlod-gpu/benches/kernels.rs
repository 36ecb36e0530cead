//! Each GPU kernel against its CPU reference, on the adapter `Context::new` picks
//! (`VOXLOD_ADAPTER` selects another).
//!
//! **On a CPU adapter (Mesa's lavapipe, llvmpipe) the "GPU" figures are CPU timings of the GPU
//! path** — the WGSL compiled by LLVM for this CPU, run by lavapipe's own thread pool — never
//! GPU speed; the bench prints which adapter it used. GPU figures include the host-side
//! preparation, the uploads, the dispatches and the readback (the whole call a user makes).
//!
//! - `voxelize`: the bunny (3.7 k triangles) and a 50 k-triangle forest, occupancy only, at
//!   128³ and 256³; CPU reference `voxlod_cpu::voxelize` (rayon, all cores).
//! - `raycast`: 256×256 primary rays on the bunny, framing view; CPU reference
//!   `Bvh::intersect` in a loop on one thread; GPU with the BVH already uploaded.
//!
//! - `ground_truth`: the cornell box and a forest with alpha-masked textured leaves (20 trees,
//!   1 500 leaves each), 128×128 at 16 rays per pixel with shadows; CPU reference
//!   `voxlod_cpu::render::ground_truth::render` (rayon, all cores); both also fill the
//!   pixel-centre G-buffer (one extra ray per pixel); GPU with the scene already uploaded.
//!
//! - `filtered`: the filtered voxel renderer, the bunny at 64³ with Averages and \[VJK21\]
//!   records (32 lines per voxel), 128×128 at 4 rays per pixel, directional light with shadows;
//!   CPU reference `voxlod_cpu::render::filtered::render` (rayon, all cores) with its cache
//!   cleared before every frame (cold: the GPU kernel keeps no cache, so each GPU frame is a
//!   cold frame); GPU with the records already uploaded. On lavapipe: CPU timings of the GPU
//!   path. Also the virtual mesh (Lines rule) and an Adaptive grid (τ = 0.08, errors from 64
//!   held-out lines), whose GPU frames are the three passes of `filtered::voxels`.
//!
//! `cargo bench -p voxlod-gpu --bench kernels` (one group: append its name, e.g. `ground_truth`)

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{UVec3, Vec3};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::voxelize::{Mode, Options};
use voxlod_format::GridSpec;
use voxlod_gpu::Context;
use voxlod_gpu::raycast::{RayCaster, primary_rays};
use voxlod_gpu::voxelize::{VoxelizeOptions, Voxelizer};
use voxlod_scene::{Camera, Geometry};

fn bunny() -> Geometry {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
    voxlod_scene::Scene::load(&path).expect("bunny").geometry()
}

fn forest() -> Geometry {
    let p = voxlod_scene::procedural::forest::ForestParams::with_target_triangles(50_000);
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

fn voxelize(c: &mut Criterion) {
    let ctx = context();
    let voxelizer = ctx.as_ref().map(|ctx| Voxelizer::new(ctx).expect("kernel compiles"));
    let mut group = c.benchmark_group("voxelize_occupancy");
    group.sample_size(10);
    for (name, g) in [("bunny", bunny()), ("forest-50k", forest())] {
        let (lo, hi) = g.bounds().unwrap();
        group.throughput(Throughput::Elements(g.triangle_count() as u64));
        for res in [128, 256] {
            let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res).unwrap();
            let opts =
                Options { mode: Mode::Conservative, triangle_lists: false, ..Default::default() };
            group.bench_function(format!("{name}/{res}/cpu"), |b| {
                b.iter(|| black_box(voxlod_cpu::voxelize::voxelize(&g, &grid, &opts).unwrap()))
            });
            if let Some(v) = &voxelizer {
                let opts = VoxelizeOptions::default();
                group.bench_function(format!("{name}/{res}/gpu-path"), |b| {
                    b.iter(|| black_box(v.voxelize(&g, &grid, &opts).unwrap()))
                });
            }
        }
    }
    group.finish();
}

fn raycast(c: &mut Criterion) {
    let ctx = context();
    let g = bunny();
    let bvh = Bvh::new(&g).unwrap();
    let (lo, hi) = g.bounds().unwrap();
    let cam =
        Camera::framing(Vec3::new(0.3, 0.2, 1.0), (lo + hi) * 0.5, (hi - lo).length() * 0.5, 40.0);
    let size = UVec3::new(256, 256, 1);
    let rays = primary_rays(&cam.frame(size.x, size.y));
    let mut group = c.benchmark_group("primary_rays_256x256");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function("bunny/cpu-1-thread", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| {
                    let (o, d) = (Vec3::from_slice(&r.origin[..3]), Vec3::from_slice(&r.dir[..3]));
                    bvh.intersect(o, d, r.origin[3], r.dir[3]).is_some()
                })
                .count()
        })
    });
    if let Some(ctx) = &ctx {
        let caster = RayCaster::new(ctx).unwrap();
        let gpu = caster.upload(&bvh, &g).unwrap();
        group.bench_function("bunny/gpu-path", |b| {
            b.iter(|| black_box(caster.intersect(&gpu, &rays).unwrap()))
        });
    }
    group.finish();
}

fn ground_truth(c: &mut Criterion) {
    use voxlod_cpu::render::ground_truth::{Options, render};
    use voxlod_gpu::ground_truth::GroundTruthKernel;
    let ctx = context();
    let kernel = ctx.as_ref().map(|ctx| GroundTruthKernel::new(ctx).unwrap());
    let options = Options { width: 128, height: 128, spp: 16, ..Options::default() };
    let mut group = c.benchmark_group("ground_truth_128x128_16spp");
    group.sample_size(10);
    group.throughput(Throughput::Elements(128 * 128 * 16));
    // cornell: opaque, untextured; forest: the default forest's alpha-masked textured leaves
    // (every candidate hit on a leaf samples its texture), 20 trees of 1 500 leaves.
    let forest = [("trees", "20"), ("leaves", "1500"), ("alpha", "true")];
    for (name, kv) in [("cornell", &[][..]), ("forest-alpha", &forest[..])] {
        let scene = voxlod_scene::procedural::builtin(name.split('-').next().unwrap(), kv).unwrap();
        let g = scene.geometry();
        let bvh = Bvh::new(&g).unwrap();
        let camera = scene.default_camera().unwrap();
        group.bench_function(format!("{name}/cpu"), |b| {
            b.iter(|| black_box(render(&scene, &g, &bvh, &camera, &options).unwrap()))
        });
        if let Some(kernel) = &kernel {
            let gpu = kernel.upload(&scene, &g, &bvh).unwrap();
            group.bench_function(format!("{name}/gpu-path"), |b| {
                b.iter(|| black_box(kernel.render(&gpu, &camera, &options).unwrap()))
            });
        }
    }
    group.finish();
}

fn filtered(c: &mut Criterion) {
    use voxlod_cpu::appearance::adaptive::{AdaptiveOptions, Candidates};
    use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
    use voxlod_cpu::appearance::sampler::SamplingContext;
    use voxlod_cpu::appearance::vmesh::{self, VirtualMeshGrid};
    use voxlod_cpu::appearance::{averages, sggx};
    use voxlod_cpu::render::filtered::{FrameCache, Options, render};
    use voxlod_gpu::filtered::FilteredKernel;
    let ctx = context();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
    let scene = voxlod_scene::Scene::load(&path).expect("bunny");
    let g = scene.geometry();
    let (lo, hi) = scene.bounds().unwrap();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 64).unwrap();
    let vox = voxlod_cpu::voxelize::voxelize(&g, &grid, &Default::default()).unwrap();
    let sampling = SamplingContext::new(&scene, &g, &vox).unwrap();
    let opts = PrecomputeOptions { rays: 32, seed: 0 };
    let avg = precompute(&sampling, &opts, averages::fit).unwrap();
    let vjk = precompute(&sampling, &opts, sggx::fit).unwrap();
    let vm = VirtualMeshGrid::new(precompute(&sampling, &opts, vmesh::fit).unwrap());
    let adaptive_options = AdaptiveOptions { rays: 32, heldout: 64, ..Default::default() };
    let candidates = Candidates::build(&sampling, &adaptive_options).unwrap();
    let adaptive = candidates.select(0.08).unwrap();
    let camera = scene.default_camera().unwrap();
    let light = scene.light();
    let bg = scene.background;
    let options = Options { width: 128, height: 128, ..Options::default() };
    let mut group = c.benchmark_group("filtered_bunny64_128x128");
    group.sample_size(10);
    group.throughput(Throughput::Elements(128 * 128));
    let mut cache = FrameCache::with_layout(&avg, &avg.records).unwrap();
    group.bench_function("averages/cpu-cold", |b| {
        b.iter(|| {
            cache.clear();
            black_box(render(&mut cache, &camera, &light, bg, &options).unwrap())
        })
    });
    let mut cache = FrameCache::with_layout(&vjk, &vjk.records).unwrap();
    group.bench_function("vjk21/cpu-cold", |b| {
        b.iter(|| {
            cache.clear();
            black_box(render(&mut cache, &camera, &light, bg, &options).unwrap())
        })
    });
    let mut cache = FrameCache::new(&vm).unwrap();
    group.bench_function("vmesh/cpu-cold", |b| {
        b.iter(|| {
            cache.clear();
            black_box(render(&mut cache, &camera, &light, bg, &options).unwrap())
        })
    });
    let mut cache = FrameCache::new(&adaptive).unwrap();
    group.bench_function("adaptive/cpu-cold", |b| {
        b.iter(|| {
            cache.clear();
            black_box(render(&mut cache, &camera, &light, bg, &options).unwrap())
        })
    });
    if let Some(ctx) = &ctx {
        let kernel = FilteredKernel::new(ctx).unwrap();
        let up = kernel.upload_averages(&avg).unwrap();
        group.bench_function("averages/gpu-path", |b| {
            b.iter(|| black_box(kernel.render(&up, &camera, &light, bg, &options).unwrap()))
        });
        let up = kernel.upload_vjk21(&vjk).unwrap();
        group.bench_function("vjk21/gpu-path", |b| {
            b.iter(|| black_box(kernel.render(&up, &camera, &light, bg, &options).unwrap()))
        });
        let up = kernel.upload_virtual_mesh(&vm).unwrap();
        group.bench_function("vmesh/gpu-path", |b| {
            b.iter(|| black_box(kernel.render(&up, &camera, &light, bg, &options).unwrap()))
        });
        let up = kernel.upload_adaptive(&adaptive).unwrap();
        group.bench_function("adaptive/gpu-path", |b| {
            b.iter(|| black_box(kernel.render(&up, &camera, &light, bg, &options).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, voxelize, raycast, ground_truth, filtered);
criterion_main!(benches);
