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
//! - `octree_build_shell256`: the octree of the sphere shell voxlod-octree's own bench builds
//!   (~200 k voxels in 256³, radius 126, default options: dense down to 64³, two sparse
//!   levels), Averages payloads, voxels in Morton order. CPU: the reference
//!   `Octree::build` + `FlatOctree::from_octree`, and the emulated lock-free build
//!   `FlatOctree::build_level_by_level` (rayon, all cores); GPU: `OctreeBuilder::build_buffers`
//!   (upload, build, no readback) and `OctreeBuilder::build` (with the readback). On lavapipe
//!   these are CPU timings of the GPU path.
//! - `precompute`: the Averages precompute of the bunny at 64³ (150 lines per voxel): CPU
//!   reference `voxlod_cpu::appearance::precompute::precompute` with `averages::fit` (rayon,
//!   all cores) against `voxlod_gpu::precompute::Precomputer::run` (host preparation of the
//!   voxels' local triangles, uploads, dispatches, readback and the host fit from the sums);
//!   throughput in lines.
//! - `cone`: cone tracing (voxlod-cone's `ConeTracer` vs voxlod-gpu's cone kernel) of a
//!   1280×720 frame on builtin:cornell — 6 diffuse cones of 30° (AO and `E/π` from the same
//!   marches, AO radius 0.1 of the scene's diagonal) and 1 specular cone (glossiness 0.5) per
//!   pixel, from the ground-truth G-buffer, through the radiance octree at 64³ (Averages from
//!   32 lines per voxel, light injected with marched shadows); CPU reference on rayon (all
//!   cores); GPU with the octree already uploaded (the call uploads the shading points,
//!   dispatches and reads back). `VOXLOD_BENCH_ONCE=1` times one frame of each path and
//!   skips criterion's ten samples (a frame takes minutes on lavapipe) and prints how far the
//!   two frames agree (largest |ΔAO| or |ΔE/π| channel).
//! - `volume`: the metavoxel pipeline (McNabb 2015) on the smoke preset (2000 particles) at 64³
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
use voxlod_cpu::voxelize::Voxelization;
use voxlod_cpu::voxelize::{Mode, Options};
use voxlod_format::GridSpec;
use voxlod_gpu::Context;
use voxlod_gpu::raycast::{RayCaster, primary_rays};
use voxlod_gpu::voxelize::{VoxelizeOptions, Voxelizer};
use voxlod_scene::{Camera, Geometry, Scene};

fn bunny_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
    Scene::load(&path).expect("bunny")
}

fn bunny() -> Geometry {
    bunny_scene().geometry()
}

/// `scene`'s geometry, a 64-voxel grid fitted to it and its conservative voxelization.
fn voxelized_64(scene: &Scene) -> (Geometry, GridSpec, Voxelization) {
    let g = scene.geometry();
    let (lo, hi) = scene.bounds().unwrap();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 64).unwrap();
    let vox = voxlod_cpu::voxelize::voxelize(&g, &grid, &Default::default()).unwrap();
    (g, grid, vox)
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
    use voxlod_cpu::appearance::line_sampler::SamplingContext;
    use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
    use voxlod_cpu::appearance::virtual_mesh::{self, VirtualMeshGrid};
    use voxlod_cpu::appearance::{averages, sggx};
    use voxlod_cpu::render::filtered::{FrameCache, Options, render};
    use voxlod_gpu::filtered::FilteredKernel;
    let ctx = context();
    let scene = bunny_scene();
    let (g, _, vox) = voxelized_64(&scene);
    let sampling = SamplingContext::new(&scene, &g, &vox).unwrap();
    let opts = PrecomputeOptions { rays: 32, seed: 0 };
    let avg = precompute(&sampling, &opts, averages::fit).unwrap();
    let vjk = precompute(&sampling, &opts, sggx::fit).unwrap();
    let vm = VirtualMeshGrid::new(precompute(&sampling, &opts, virtual_mesh::fit).unwrap());
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

/// The sphere shell of voxlod-octree's build bench: voxel centres within half a voxel of a
/// sphere of radius 126 in 256³, Morton-sorted, radial normals, colour by position.
fn shell256() -> Vec<(UVec3, voxlod_octree::AveragePayload)> {
    let (res, radius) = (256u32, 126.0f32);
    let c = Vec3::splat(res as f32 / 2.0);
    let mut v = Vec::new();
    for z in 0..res {
        for y in 0..res {
            for x in 0..res {
                let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5 - c;
                if (p.length() - radius).abs() <= 0.5 {
                    let colour = (p / radius) * 0.5 + 0.5;
                    let payload = voxlod_octree::AveragePayload::new(colour, p, 0.8);
                    v.push((UVec3::new(x, y, z), payload));
                }
            }
        }
    }
    v.sort_unstable_by_key(|e| voxlod_format::morton::encode(e.0));
    v
}

fn octree(c: &mut Criterion) {
    use voxlod_octree::{BuildOptions, FlatOctree, Octree};
    let ctx = context();
    let voxels = shell256();
    let grid =
        GridSpec::new(glam::DVec3::ZERO, 1.0 / 256.0, UVec3::splat(256)).expect("valid grid");
    let options = BuildOptions::default();
    let mut group = c.benchmark_group("octree_build_shell256");
    group.sample_size(10);
    group.throughput(Throughput::Elements(voxels.len() as u64));
    group.bench_function("reference/cpu", |b| {
        b.iter(|| {
            let tree = Octree::build(grid, voxels.iter().copied(), &options).unwrap();
            black_box(FlatOctree::from_octree(&tree).unwrap())
        })
    });
    group.bench_function("level-by-level/cpu", |b| {
        b.iter(|| black_box(FlatOctree::build_level_by_level(grid, &voxels, &options).unwrap()))
    });
    if let Some(ctx) = &ctx {
        let builder = voxlod_gpu::octree::OctreeBuilder::new(ctx).unwrap();
        group.bench_function("level-by-level/gpu-path", |b| {
            b.iter(|| {
                black_box(builder.build_buffers(&grid, &voxels, &options).unwrap().node_count)
            })
        });
        group.bench_function("level-by-level+readback/gpu-path", |b| {
            b.iter(|| black_box(builder.build(&grid, &voxels, &options).unwrap()))
        });
    }
    group.finish();
}

fn precompute(c: &mut Criterion) {
    use voxlod_cpu::appearance::averages;
    use voxlod_cpu::appearance::line_sampler::SamplingContext;
    use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
    use voxlod_gpu::precompute::{Outputs, Precomputer};
    let ctx = context();
    let scene = bunny_scene();
    let (g, _, vox) = voxelized_64(&scene);
    let sampling = SamplingContext::new(&scene, &g, &vox).unwrap();
    let opts = PrecomputeOptions::default();
    let mut group = c.benchmark_group("precompute_averages_bunny64_150");
    group.sample_size(10);
    group.throughput(Throughput::Elements(sampling.voxel_count() as u64 * opts.rays as u64));
    group.bench_function("cpu", |b| {
        b.iter(|| black_box(precompute(&sampling, &opts, averages::fit).unwrap()))
    });
    if let Some(ctx) = &ctx {
        let kernel = Precomputer::new(ctx).unwrap();
        group.bench_function("gpu-path", |b| {
            b.iter(|| black_box(kernel.run(&scene, &g, &vox, &opts, Outputs::default()).unwrap()))
        });
    }
    group.finish();
}

fn cone(c: &mut Criterion) {
    use rayon::prelude::*;
    use voxlod_cone::{ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
    use voxlod_cpu::appearance::averages;
    use voxlod_cpu::appearance::line_sampler::SamplingContext;
    use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
    use voxlod_gpu::cone::{ConeKernel, ConeQuery, ShadingPoint, reference};
    use voxlod_octree::{AveragePayload, BuildOptions, Octree};
    let (width, height) = (1280, 720);
    let ctx = context();
    let scene = voxlod_scene::procedural::builtin("cornell", &[]).unwrap();
    let g = scene.geometry();
    let bvh = Bvh::new(&g).unwrap();
    let camera = scene.default_camera().unwrap();
    let (lo, hi) = scene.bounds().unwrap();
    let (_, grid, vox) = voxelized_64(&scene);
    let sampling = SamplingContext::new(&scene, &g, &vox).unwrap();
    let records =
        precompute(&sampling, &PrecomputeOptions { rays: 32, seed: 0 }, averages::fit).unwrap();
    let build = BuildOptions { depth: None, dense_log2: 4 };
    let tree = Octree::from_brick_map(grid, &records.records, AveragePayload::from_record, &build)
        .unwrap();
    let light = match scene.light() {
        voxlod_scene::Light::Directional { to_light, irradiance } => {
            Light::Directional { to_light, irradiance }
        }
        voxlod_scene::Light::Point { position, intensity } => Light::Point { position, intensity },
    };
    let radiance: Octree<RadiancePayload> = inject(&tree, &light, &Shadows::MARCH).unwrap();
    let gb = voxlod_cpu::render::ground_truth::gbuffer(&scene, &g, &bvh, &camera, width, height)
        .unwrap();
    let points = ShadingPoint::from_gbuffer(&gb, camera.eye, 0.5);
    let options = TraceOptions { ao_radius: 0.1 * (hi - lo).length(), ..TraceOptions::default() };
    let tracer = ConeTracer::new(&radiance, options).unwrap();
    let query = ConeQuery::ALL;
    let cpu = || points.par_iter().map(|p| reference(&tracer, p, query)).collect::<Vec<_>>();
    let kernel = ctx.as_ref().map(ConeKernel::new);
    let uploaded = kernel.as_ref().map(|k| k.upload(&radiance).unwrap());
    let gpu = || {
        let (k, up) = (kernel.as_ref().unwrap(), uploaded.as_ref().unwrap());
        k.trace(up, &options, query, &points, width).unwrap()
    };
    if std::env::var("VOXLOD_BENCH_ONCE").is_ok_and(|v| v == "1") {
        let t = std::time::Instant::now();
        let c = cpu();
        eprintln!("cone 1280x720 6+1 cones, one frame, cpu: {:.3} s", t.elapsed().as_secs_f64());
        if kernel.is_some() {
            // The first call compiles the kernel: time a second one.
            let t = std::time::Instant::now();
            black_box(gpu());
            eprintln!("  gpu path, first frame (compiles): {:.3} s", t.elapsed().as_secs_f64());
            let t = std::time::Instant::now();
            let gp = gpu();
            eprintln!("  gpu path, second frame: {:.3} s", t.elapsed().as_secs_f64());
            let worst = c
                .iter()
                .zip(&gp)
                .map(|(a, b)| (a.ao - b.ao).abs().max((a.diffuse - b.diffuse).abs().max_element()))
                .fold(0.0f32, f32::max);
            eprintln!("  worst |ΔAO|, |ΔE/π| between the two: {worst:.2e}");
        }
        return;
    }
    let mut group = c.benchmark_group("cone_1280x720_6diffuse_1specular");
    group.sample_size(10);
    group.throughput(Throughput::Elements(width as u64 * height as u64));
    group.bench_function("cornell64/cpu", |b| b.iter(|| black_box(cpu())));
    if kernel.is_some() {
        group.bench_function("cornell64/gpu-path", |b| b.iter(|| black_box(gpu())));
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

criterion_group!(
    benches,
    voxelize,
    raycast,
    ground_truth,
    filtered,
    octree,
    precompute,
    cone,
    volume
);
criterion_main!(benches);
