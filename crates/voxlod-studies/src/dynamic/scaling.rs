//! Time per frame against object count: `builtin:crowd` with `n` walkers and `n` rigid objects,
//! the transform alone against voxelizing the moved triangles alone (conservative and thin,
//! occupancy only, as the paper compares its transform with a voxelizer), and whole frames —
//! transform, blend, rebuild, inject, trace against pose, voxelize, fragment records, rebuild,
//! inject, trace — with their peak memory.

use std::time::Instant;

use serde::Serialize;
use voxlod_cone::{FramePipeline, RadiancePayload, Shadows, TraceOptions};
use voxlod_cpu::dynamic::{CacheOptions, RecordSource, fragment_records, geometry_of};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_cpu::voxelize::{self, Mode};
use voxlod_gpu::cone::{ConeQuery, ShadingPoint};
use voxlod_gpu::dynamic::DynamicKernels;
use voxlod_octree::dynamic::{FrameOptions, Placement, VoxelCache, WorldSums};
use voxlod_octree::{AveragePayload, Octree};

use super::setup::{cone_light, inject_and_trace, ms, prepare, trace_gbuffer};
use crate::backend::Backend;
use crate::{Error, Spread, alloc};

/// One object count.
#[derive(Clone, Debug, Serialize)]
pub struct ScalingRow {
    /// Walkers (skinned, 17 joints each).
    pub walkers: u32,
    /// Moving objects (walkers and rigid objects).
    pub objects: u32,
    /// Triangles of the moving objects.
    pub moving_triangles: u64,
    /// Cached voxels of all objects.
    pub cached_voxels: u64,
    /// World grid, voxels per axis.
    pub grid: [u32; 3],
    /// Placing and transforming every cached voxel (8-neighbour), ms.
    pub transform_ms: Spread,
    /// Blending them with the static voxels and resolving the leaves, ms.
    pub blend_ms: Spread,
    /// Skinning and moving the meshes' vertices (what re-voxelizing needs first), ms.
    pub pose_ms: Spread,
    /// Voxelizing the moved triangles, conservative, occupancy only, ms.
    pub voxelize_conservative_ms: Spread,
    /// The same, thin (6-separating), ms.
    pub voxelize_thin_ms: Spread,
    /// A whole frame by transformation: transform, blend, octree, injection, trace, ms.
    pub frame_transform_ms: Spread,
    /// A whole frame by re-voxelization: pose, voxelize (conservative, with triangle lists),
    /// fragment records, blend with the static voxels, octree, injection, trace, ms.
    pub frame_voxelize_ms: Spread,
    /// A whole frame by transformation on the GPU backend (device frame, then the cone kernel),
    /// ms; on a CPU adapter (lavapipe) CPU times of the GPU path.
    pub frame_gpu_ms: Option<Spread>,
    /// Peak heap bytes of a transformed frame (None without the tracking allocator).
    pub frame_transform_peak_bytes: Option<u64>,
    /// Peak heap bytes of a re-voxelized frame.
    pub frame_voxelize_peak_bytes: Option<u64>,
    /// The transformed frame's transient arrays (moved voxels, sums, leaves), bytes.
    pub transient_bytes: u64,
    /// Bytes of all caches.
    pub cache_bytes: u64,
}

/// Settings of the scaling part.
pub struct ScalingSettings<'a> {
    /// Walker counts (1..=256); each with as many rigid objects.
    pub walkers: &'a [u32],
    /// World voxel edge (world units).
    pub voxel_size: f64,
    /// Repetitions per measurement (the spread is over them).
    pub repeats: u32,
    /// The traced image's width (height ¾ of it).
    pub image_width: u32,
    /// Animation time of the measured frame.
    pub time: f32,
}

fn spread(values: &[f64]) -> Spread {
    Spread::of(values)
}

/// Runs the sweep (see the module docs) on `backend` for the GPU column.
pub fn run(
    s: &ScalingSettings,
    backend: Backend<'_>,
    say: &dyn Fn(&str),
) -> Result<Vec<ScalingRow>, Error> {
    let kernels = match backend {
        Backend::Gpu(ctx) => Some(DynamicKernels::new(ctx)?),
        Backend::Cpu => None,
    };
    let mut rows = Vec::new();
    for &n in s.walkers {
        say(&format!("scaling: {n} walkers, {n} rigid objects: caches"));
        let scene = voxlod_scene::procedural::from_spec(&format!("crowd?walkers={n}&rigid={n}"))?;
        let options = CacheOptions { records: RecordSource::Pieces, ..Default::default() };
        let p = prepare(scene, s.voxel_size, &options)?;
        let pose = p.ds.pose(s.time)?;
        let placements = p.ds.placements(&pose)?;
        let objects: Vec<(&VoxelCache, &Placement)> = p.caches.iter().zip(&placements).collect();
        let moving: Vec<usize> =
            p.ds.objects.iter().flat_map(|o| o.meshes.iter().copied()).collect();
        let posed = p.ds.posed_scene(&pose)?;
        let g = posed.geometry();
        let bvh = Bvh::new(&g)?;
        let camera = posed.default_camera()?;
        let (w, h) = (s.image_width, (s.image_width * 3 / 4).max(1));
        let gb = ground_truth::gbuffer(&posed, &g, &bvh, &camera, w, h)?;
        let light = cone_light(posed.light());
        let trace = TraceOptions::default();
        let frame_options = FrameOptions::default();
        let (mut t_tr, mut t_bl, mut t_po, mut t_vc, mut t_vt, mut t_ft, mut t_fv, mut t_gpu) =
            (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
        let mut transient = 0;
        let (mut peak_t, mut peak_v) = (None, None);
        say(&format!("scaling: {n} walkers: timing"));
        for r in 0..s.repeats {
            let t = Instant::now();
            let (placed, _) = p.world.transform_all(&objects, &frame_options)?;
            t_tr.push(ms(t));
            let t = Instant::now();
            let (sums, _) = p.world.sums(&objects, &placed, &frame_options)?;
            let (leaves, _) = sums.resolve(frame_options.occupancy_threshold)?;
            t_bl.push(ms(t));
            drop((placed, sums, leaves));
            let t = Instant::now();
            let posed_now = p.ds.posed_scene(&pose)?;
            t_po.push(ms(t));
            let moving_geometry = geometry_of(&posed_now, &moving);
            for (mode, out) in [(Mode::Conservative, &mut t_vc), (Mode::Thin, &mut t_vt)] {
                let o = voxelize::Options { mode, triangle_lists: false, ..Default::default() };
                let t = Instant::now();
                let v = voxelize::voxelize(&moving_geometry, &p.grid, &o)?;
                out.push(ms(t));
                drop(v);
            }
            // Whole frame by transformation (a fresh pipeline: nothing cached from the last run).
            let (frame, peak) = alloc::measure_peak(|| -> Result<(f64, u64), Error> {
                let t = Instant::now();
                let mut pipeline: FramePipeline<RadiancePayload> =
                    FramePipeline::new(&p.world, &p.caches, frame_options, light, Shadows::MARCH);
                let (_, radiance, report) = pipeline.frame(&placements)?;
                trace_gbuffer(radiance, &gb, trace)?;
                Ok((ms(t), report.stats.transient_bytes))
            });
            let (elapsed, bytes) = frame?;
            t_ft.push(elapsed);
            transient = bytes;
            if r == 0 {
                peak_t = peak.map(|b| b as u64);
            }
            // Whole frame by re-voxelization.
            let (frame, peak) = alloc::measure_peak(|| -> Result<f64, Error> {
                let t = Instant::now();
                let posed_now = p.ds.posed_scene(&pose)?;
                let geometry = geometry_of(&posed_now, &moving);
                let o = voxelize::Options {
                    mode: Mode::Conservative,
                    triangle_lists: true,
                    ..Default::default()
                };
                let vox = voxelize::voxelize(&geometry, &p.grid, &o)?;
                let records = fragment_records(&posed_now, &geometry, &vox)?;
                let moving_sums =
                    WorldSums::from_static(&p.grid, records.iter().map(|(c, r)| (c, *r)))?;
                let (leaves, _) = moving_sums.merge(&p.world.statics).resolve(0.5)?;
                let tree: Octree<AveragePayload> =
                    Octree::from_morton_sorted(p.grid, leaves, &frame_options.build)?;
                inject_and_trace(&tree, &light, &gb, trace)?;
                Ok(ms(t))
            });
            t_fv.push(frame?);
            if r == 0 {
                peak_v = peak.map(|b| b as u64);
            }
            if let (Some(k), Backend::Gpu(_)) = (&kernels, backend) {
                let up = k.upload(&p.world, &p.caches)?;
                let points = ShadingPoint::from_gbuffer(&gb, camera.eye, 0.5);
                let query = ConeQuery { ambient_occlusion: true, diffuse: true, specular: false };
                if r == 0 {
                    // Warm-up: pipelines compile on first use.
                    let f = k.frame(
                        &up,
                        &p.caches,
                        &placements,
                        &frame_options,
                        &light,
                        &Shadows::MARCH,
                    )?;
                    k.trace(&f, &trace, query, &points, w)?;
                }
                let t = Instant::now();
                let f =
                    k.frame(&up, &p.caches, &placements, &frame_options, &light, &Shadows::MARCH)?;
                k.trace(&f, &trace, query, &points, w)?;
                t_gpu.push(ms(t));
            }
        }
        rows.push(ScalingRow {
            walkers: n,
            objects: p.ds.objects.len() as u32,
            moving_triangles: moving
                .iter()
                .map(|&m| p.ds.scene.meshes[m].triangle_count() as u64)
                .sum(),
            cached_voxels: p.caches.iter().map(|c| c.len() as u64).sum(),
            grid: p.grid.dims.to_array(),
            transform_ms: spread(&t_tr),
            blend_ms: spread(&t_bl),
            pose_ms: spread(&t_po),
            voxelize_conservative_ms: spread(&t_vc),
            voxelize_thin_ms: spread(&t_vt),
            frame_transform_ms: spread(&t_ft),
            frame_voxelize_ms: spread(&t_fv),
            frame_gpu_ms: (!t_gpu.is_empty()).then(|| spread(&t_gpu)),
            frame_transform_peak_bytes: peak_t,
            frame_voxelize_peak_bytes: peak_v,
            transient_bytes: transient,
            cache_bytes: p.caches.iter().map(|c| c.memory_bytes() as u64).sum(),
        });
    }
    Ok(rows)
}
