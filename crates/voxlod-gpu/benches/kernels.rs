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
//! - `ground_truth`: the cornell box, 128×128 at 16 rays per pixel with shadows; CPU reference
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
//! - `volume`: the metavoxel pipeline (seed 001) on the smoke preset (2000 particles) at 64³
//!   voxels, M = 16, 128×128 pixels, Beer–Lambert: each stage on its own (binning; fill of the
//!   binned metavoxels; propagation, the fill included as its input; march of the built volume)
//!   and the whole frame, CPU reference (rayon, all cores) against the GPU path (uploads,
//!   dispatches and readback included). On lavapipe: CPU timings of the GPU path.
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
    let scene = voxlod_scene::procedural::builtin("cornell", &[]).unwrap();
    let g = scene.geometry();
    let bvh = Bvh::new(&g).unwrap();
    let camera = scene.default_camera().unwrap();
    let options = Options { width: 128, height: 128, spp: 16, ..Options::default() };
    let mut group = c.benchmark_group("ground_truth_128x128_16spp");
    group.sample_size(10);
    group.throughput(Throughput::Elements(128 * 128 * 16));
    group.bench_function("cornell/cpu", |b| {
        b.iter(|| black_box(render(&scene, &g, &bvh, &camera, &options).unwrap()))
    });
    if let Some(ctx) = &ctx {
        let kernel = GroundTruthKernel::new(ctx).unwrap();
        let gpu = kernel.upload(&scene, &g, &bvh).unwrap();
        group.bench_function("cornell/gpu-path", |b| {
            b.iter(|| black_box(kernel.render(&gpu, &camera, &options).unwrap()))
        });
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

fn volume(c: &mut Criterion) {
    use voxlod_cpu::volume::{self as cpu, BuildSettings, MarchOptions, VolumeSpec};
    use voxlod_gpu::volume::VolumeKernels;
    let ctx = context();
    let kernels = ctx.as_ref().map(|ctx| VolumeKernels::new(ctx).expect("kernels compile"));
    let system = voxlod_scene::particles::smoke_column(&voxlod_scene::particles::SmokeParams {
        count: 2000,
        ..Default::default()
    })
    .unwrap();
    let spheres = system.at(system.time);
    let map = &system.displacement;
    let (lo, hi) = voxlod_scene::particles::bounds(&spheres).unwrap();
    let spec = VolumeSpec::fit(lo, hi, Vec3::new(0.3, 1.0, 0.2), 4, 16).unwrap();
    let settings = BuildSettings::default();
    let camera =
        Camera::framing(Vec3::new(0.4, 0.3, 1.0), (lo + hi) * 0.5, (hi - lo).length() * 0.5, 45.0);
    let options = MarchOptions { width: 128, height: 128, step: 1.0 };
    let binning = cpu::binning::bin(&spheres, &spec);
    let built = cpu::build(&spheres, map, &spec, &settings, None, None).unwrap();
    let mut group = c.benchmark_group("volume_smoke_2000");
    group.sample_size(10);
    group.bench_function("binning/cpu", |b| {
        b.iter(|| black_box(cpu::binning::bin(&spheres, &spec)))
    });
    group.bench_function("fill/cpu", |b| {
        b.iter(|| {
            let p = &binning.prepared;
            let filled: Vec<_> = binning
                .bins
                .iter()
                .map(|bin| cpu::fill::fill(&spheres, p, map, &spec, bin))
                .collect();
            black_box(filled)
        })
    });
    group.bench_function("fill+propagation/cpu", |b| {
        b.iter(|| {
            let p = &binning.prepared;
            let mut f: Vec<_> = binning
                .bins
                .iter()
                .map(|bin| cpu::fill::fill(&spheres, p, map, &spec, bin))
                .collect();
            cpu::propagate::propagate(&mut f, &spec, &settings, None);
            black_box(f)
        })
    });
    group.bench_function("march/cpu", |b| {
        b.iter(|| black_box(cpu::march::render(&built, &camera, &options, None).unwrap()))
    });
    group.bench_function("frame/cpu", |b| {
        b.iter(|| {
            let view = camera.frame(options.width, options.height);
            let v = cpu::build(&spheres, map, &spec, &settings, Some(&view), None).unwrap();
            black_box(cpu::march::render(&v, &camera, &options, None).unwrap())
        })
    });
    if let Some(k) = &kernels {
        group.bench_function("binning/gpu-path", |b| {
            b.iter(|| black_box(k.bin(&spheres, &spec).unwrap()))
        });
        group.bench_function("fill/gpu-path", |b| {
            b.iter(|| {
                black_box(k.fill(&spheres, &binning.prepared, map, &spec, &binning.bins).unwrap())
            })
        });
        group.bench_function("fill+propagation/gpu-path", |b| {
            b.iter(|| {
                let mut v = k.fill(&spheres, &binning.prepared, map, &spec, &binning.bins).unwrap();
                k.propagate(&mut v, &settings, None).unwrap();
                black_box(v)
            })
        });
        let uploaded = k.upload(&built).unwrap();
        group.bench_function("march/gpu-path", |b| {
            b.iter(|| black_box(k.render(&uploaded, &camera, &options, None).unwrap()))
        });
        group.bench_function("frame/gpu-path", |b| {
            b.iter(|| {
                black_box(
                    k.frame(&spheres, map, &spec, &settings, None, &camera, &options, None)
                        .unwrap(),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, voxelize, raycast, ground_truth, filtered, volume);
criterion_main!(benches);
