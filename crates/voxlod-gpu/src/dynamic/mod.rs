//! A dynamic scene's frame on the GPU (Yalçıner and Sahillioğlu 2020, §4.1–4.2): the cached
//! voxels of every moving object transformed into the world grid, blended in fixed point with
//! the static voxels, the octree rebuilt from the result with [`crate::octree`]'s kernels,
//! the light injected (a new kernel) and the radiance octree pre-filtered, ready for
//! [`crate::cone`]'s tracer — the whole frame on the device; the host only places the objects
//! (their matrices, a few bytes each) and reads back three counts. The CPU reference is
//! voxlod-octree's `dynamic` module and voxlod-cone's `inject`.
//!
//! # Kernels (workgroups of 64, one pass each, in order)
//! 1. `transform`: one invocation per cached voxel (every object's cache concatenated and
//!    uploaded once): the voxel's matrix (its object's, or the blend of its joints'), its
//!    moved centre, the nearest or 8-neighbour cell and fractions, its moved normal — the
//!    arithmetic of `voxlod_octree::dynamic::transform_voxel` in its order.
//! 2. `mark`: one invocation per (moved voxel, corner) and per static voxel: the flag of the
//!    2×2×2 **brick** its world voxel lies in, in a dense table indexed by the brick's Morton
//!    code (8^(depth−1) words: 8 MiB for a 256³ grid, 64 MiB for 512³; a larger table than the
//!    device binds is [`crate::Error::BufferTooLarge`]).
//! 3. An exclusive prefix sum over the flags ([`crate::octree`]'s scan kernels): each flagged
//!    brick's slot, in Morton order; `bricks` records each slot's brick. The brick count is
//!    read back and sizes the sums (8 world voxels × 16 words per brick).
//! 4. `accumulate`: one invocation per (moved voxel, corner) and per static voxel adds its
//!    contribution — weight, weight × alpha, colour and normal sums — as **64-bit integers on
//!    `u32` atomics**: `atomicAdd` on the low word, the carry (the low word wrapped) and the
//!    high part added to the high word. WGSL has no float atomics and no 64-bit ones; this sum
//!    is exact modulo 2⁶⁴ in any order, and the blend's bound keeps it below 2⁶³. Products
//!    above 32 bits are formed exactly from 16-bit halves.
//! 5. `compact`: occupancy per world voxel (covered volume ≥ the threshold, alpha ≠ 0), a
//!    prefix sum over it (its total read back), then each occupied voxel written as a leaf —
//!    coordinates, Averages payload, raw sums — in Morton order.
//! 6. The octree build ([`OctreeBuilder::build_device`]) from the leaves on the device.
//! 7. `convert` the geometry octree's payloads to opacity, then `inject`: one invocation per
//!    leaf, its Lambert radiance with a shadow march through the geometry octree (the cone
//!    kernel's sampler and march, `cone.wgsl`'s functions). [`OctreeBuilder::refill`]
//!    pre-filters the radiance up the same topology, `convert` gives the cone kernel's
//!    payloads, and [`GpuFrame::radiance`] is ready for [`ConeKernel::trace`].
//!
//! # Agreement with the CPU (the equivalence suite's rows)
//! Transformed cells are equal except for voxels within rounding of a cell boundary (fused
//! multiply-adds, WGSL's division); blended sums are exact for equal moved voxels; the rebuilt
//! topology is exact for equal leaves; payloads and injected radiance are floats within a
//! stated bound.
//!
//! # On a real GPU
//! Not measured on one. Expected: the transform reads 16–20 bytes per voxel and writes 32,
//! coalesced (voxels of one object are consecutive); the accumulation is atomic-bound where
//! many voxels land in one world voxel (collapsed joints, dense crowds), otherwise scattered
//! adds to Morton-near addresses; the two read-backs (brick and leaf counts) and the octree's
//! per-level counts are synchronization points.

use std::cell::OnceCell;

use glam::UVec3;
use voxlod_cone::{Light, Shadows, TraceOptions};
use voxlod_format::{GridSpec, morton};
use voxlod_octree::dynamic::{
    CellSums, DynamicWorld, Filter, FrameOptions, MAX_CONTRIBUTIONS, ObjectFrame, Placed,
    Placement, VoxelCache, linear12_table, place,
};
use voxlod_octree::{AveragePayload, GpuLevel};

use crate::cone::{ConeKernel, ConeQuery, ConeShade, GpuConeOctree, ShadingPoint};
use crate::octree::{GpuOctree, OctreeBuilder};
use crate::{Context, Error, Result};

mod inject;
mod params;

pub use inject::inject_source;
pub use params::{GpuDynamicParams, GpuInjectParams, GpuObject};

/// The WGSL shared by the dynamic kernels (mirrors of [`Placed`] and [`GpuDynamicParams`],
/// corners, 64-bit helpers; after [`crate::MORTON_WGSL`]).
pub const COMMON_WGSL: &str = include_str!("common.wgsl");

macro_rules! kernel {
    ($file:literal) => {
        concat!(include_str!("../morton.wgsl"), include_str!("common.wgsl"), include_str!($file))
    };
}

/// The kernels' sources, `(name, WGSL)`, in the order of [`DynamicKernels`]' pipelines (the
/// injection kernel is [`inject_source`]).
pub const KERNELS: [(&str, &str); 6] = [
    ("dynamic transform", kernel!("transform.wgsl")),
    ("dynamic mark", kernel!("mark.wgsl")),
    ("dynamic bricks", kernel!("bricks.wgsl")),
    ("dynamic accumulate", kernel!("accumulate.wgsl")),
    ("dynamic compact", kernel!("compact.wgsl")),
    ("dynamic convert", kernel!("convert.wgsl")),
];

const TRANSFORM: usize = 0;
const MARK: usize = 1;
const BRICKS: usize = 2;
const ACCUMULATE: usize = 3;
const COMPACT: usize = 4;
const CONVERT: usize = 5;

/// Invocations per workgroup of every dynamic kernel.
pub const WORKGROUP: u64 = 64;

/// A moving object's place in the concatenated caches.
#[derive(Clone, Copy, Debug)]
struct ObjectMeta {
    skinned: bool,
}

/// The caches and static voxels of a world on the device, uploaded once
/// ([`DynamicKernels::upload`]).
pub struct GpuDynamicScene {
    /// The world grid.
    pub grid: GridSpec,
    /// Cached voxels of all objects.
    pub voxels: u64,
    objects: Vec<ObjectMeta>,
    positions: wgpu::Buffer,
    records: wgpu::Buffer,
    skins: wgpu::Buffer,
    object_of: wgpu::Buffer,
    static_cells: wgpu::Buffer,
    static_sums: wgpu::Buffer,
    static_count: u64,
    linear12: wgpu::Buffer,
    brick_log2: u32,
}

impl GpuDynamicScene {
    /// Static voxels held.
    pub fn static_count(&self) -> u64 {
        self.static_count
    }
}

/// A frame's occupied world voxels on the device, in Morton order.
pub struct GpuLeaves {
    /// Coordinates, `u32` × 3 per leaf.
    pub coords: wgpu::Buffer,
    /// Averages payload per leaf.
    pub payload: wgpu::Buffer,
    /// The raw sums ([`CellSums`]: 16 words) per leaf.
    pub sums: wgpu::Buffer,
    /// Leaves.
    pub count: u64,
    /// World voxels touched (occupied or not).
    pub touched: u64,
}

/// A frame on the device: its leaves, geometry octree and radiance octree.
pub struct GpuFrame<'a> {
    /// The occupied world voxels.
    pub leaves: GpuLeaves,
    /// The geometry octree (Averages payloads).
    pub geometry: GpuOctree<'a>,
    /// Injected radiance per leaf (Averages layout: radiance × opacity in the colour words).
    pub injected: wgpu::Buffer,
    /// The radiance octree, ready for [`ConeKernel::trace`].
    pub radiance: GpuConeOctree,
}

/// The dynamic kernels, compiled for one [`Context`], with the octree and cone kernels they
/// use.
pub struct DynamicKernels<'a> {
    ctx: &'a Context,
    pipelines: Vec<wgpu::ComputePipeline>,
    inject: OnceCell<wgpu::ComputePipeline>,
    octree: OctreeBuilder<'a>,
    cone: ConeKernel<'a>,
}

fn entry(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }
}

impl<'a> DynamicKernels<'a> {
    /// Compiles the kernels (the injection kernel when first used).
    pub fn new(ctx: &'a Context) -> Result<Self> {
        let pipelines =
            KERNELS.iter().map(|(name, src)| ctx.pipeline(name, src)).collect::<Result<_>>()?;
        Ok(Self {
            ctx,
            pipelines,
            inject: OnceCell::new(),
            octree: OctreeBuilder::new(ctx)?,
            cone: ConeKernel::new(ctx),
        })
    }

    /// The cone kernel frames are traced with.
    pub fn cone(&self) -> &ConeKernel<'a> {
        &self.cone
    }

    /// Records one dispatch of `pipeline` over `invocations` with the parameters `params` at
    /// binding 0 and `entries`.
    fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (pipeline, name): (&wgpu::ComputePipeline, &'static str),
        invocations: u64,
        params: &[u8],
        entries: &[(u32, &wgpu::Buffer)],
        keep: &mut Vec<wgpu::Buffer>,
    ) -> Result<()> {
        if invocations == 0 {
            return Ok(());
        }
        let ctx = self.ctx;
        if invocations > crate::octree::MAX_INVOCATIONS {
            return Err(Error::TooLarge {
                what: "invocations of one dynamic-scene dispatch",
                requested: invocations,
                limit: crate::octree::MAX_INVOCATIONS,
            });
        }
        let (x, y) = ctx.dispatch_size(name, invocations.div_ceil(WORKGROUP))?;
        let uniform = ctx.uniform(name, params)?;
        let layout = pipeline.get_bind_group_layout(0);
        let mut all = vec![entry(0, &uniform)];
        all.extend(entries.iter().map(|&(b, buf)| entry(b, buf)));
        let bind = ctx.guarded("binding dynamic-scene buffers", || {
            ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(name),
                layout: &layout,
                entries: &all,
            })
        })?;
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(name),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        keep.push(uniform);
        Ok(())
    }

    fn run(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        kernel: usize,
        invocations: u64,
        params: GpuDynamicParams,
        entries: &[(u32, &wgpu::Buffer)],
        keep: &mut Vec<wgpu::Buffer>,
    ) -> Result<()> {
        let pipeline = &self.pipelines[kernel];
        let name = KERNELS[kernel].0;
        self.dispatch(
            encoder,
            (pipeline, name),
            invocations,
            bytemuck::bytes_of(&params),
            entries,
            keep,
        )
    }

    /// Uploads `caches` (every moving object's, in the order placements will come) and the
    /// static voxels of `world`. Errors: a world grid beyond the brick table's reach (2¹⁰
    /// bricks per axis) and the device's limits.
    pub fn upload(&self, world: &DynamicWorld, caches: &[VoxelCache]) -> Result<GpuDynamicScene> {
        let ctx = self.ctx;
        let grid = world.grid;
        let (depth, _) = voxlod_octree::plan(grid.dims, &voxlod_octree::BuildOptions::default())?;
        let brick_log2 = depth.saturating_sub(1);
        if brick_log2 > 10 {
            return Err(Error::TooLarge {
                what: "world grid voxels per axis (bricks are indexed by 30-bit Morton codes)",
                requested: grid.dims.max_element() as u64,
                limit: 2048,
            });
        }
        let mut positions = Vec::new();
        let mut records: Vec<u32> = Vec::new();
        let mut skins: Vec<u32> = Vec::new();
        let mut object_of = Vec::new();
        let mut objects = Vec::with_capacity(caches.len());
        for (o, c) in caches.iter().enumerate() {
            positions.extend_from_slice(&c.positions);
            records.extend_from_slice(bytemuck::cast_slice(&c.records));
            match &c.skin {
                Some(s) => skins.extend_from_slice(bytemuck::cast_slice(&s.voxels)),
                None => skins.extend(std::iter::repeat_n(0u32, 2 * c.len())),
            }
            object_of.extend(std::iter::repeat_n(o as u32, c.len()));
            objects.push(ObjectMeta { skinned: c.skin.is_some() });
        }
        let statics = &world.statics;
        let cells: Vec<u32> =
            statics.codes.iter().flat_map(|&c| morton::decode(c).to_array()).collect();
        Ok(GpuDynamicScene {
            grid,
            voxels: positions.len() as u64,
            objects,
            positions: ctx
                .storage_init("cached voxel positions", bytemuck::cast_slice(&positions))?,
            records: ctx.storage_init("cached voxel records", bytemuck::cast_slice(&records))?,
            skins: ctx.storage_init("cached voxel skins", bytemuck::cast_slice(&skins))?,
            object_of: ctx
                .storage_init("cached voxel objects", bytemuck::cast_slice(&object_of))?,
            static_cells: ctx.storage_init("static voxels", bytemuck::cast_slice(&cells))?,
            static_sums: ctx.storage_init("static sums", bytemuck::cast_slice(&statics.sums))?,
            static_count: statics.len() as u64,
            linear12: ctx
                .storage_init("linear colour table", bytemuck::cast_slice(linear12_table()))?,
            brick_log2,
        })
    }

    fn params(&self, scene: &GpuDynamicScene, filter: Filter) -> GpuDynamicParams {
        GpuDynamicParams {
            n: 0,
            filter_mode: u32::from(filter == Filter::EightNeighbour),
            brick_log2: scene.brick_log2,
            extra: 0,
            dims: scene.grid.dims.to_array(),
            min_weight: 1,
        }
    }

    /// Moves every cached voxel by `frames` (one per object, from
    /// [`voxlod_octree::dynamic::place()`]), left on the device: one [`Placed`] per voxel.
    pub fn transform(
        &self,
        scene: &GpuDynamicScene,
        frames: &[ObjectFrame],
        filter: Filter,
    ) -> Result<wgpu::Buffer> {
        let ctx = self.ctx;
        if frames.len() != scene.objects.len() {
            return Err(Error::Octree(voxlod_octree::Error::InvalidParameter {
                name: "object frames",
                value: frames.len().to_string(),
                reason: "one frame per uploaded cache",
            }));
        }
        let mut gpu_objects = Vec::with_capacity(frames.len());
        let mut matrices: Vec<voxlod_octree::dynamic::Affine> = Vec::new();
        for (f, meta) in frames.iter().zip(&scene.objects) {
            gpu_objects.push(GpuObject {
                anchor: f.anchor,
                first_matrix: matrices.len() as u32,
                skinned: u32::from(meta.skinned),
                outside: u32::from(f.outside),
                pad: [0; 2],
            });
            matrices.extend_from_slice(&f.matrices);
        }
        let objects = ctx.storage_init("object frames", bytemuck::cast_slice(&gpu_objects))?;
        let mats = ctx.storage_init("object matrices", bytemuck::cast_slice(&matrices))?;
        let placed =
            ctx.storage_zeroed("placed voxels", scene.voxels * size_of::<Placed>() as u64)?;
        let mut keep = Vec::new();
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let params = GpuDynamicParams { n: scene.voxels as u32, ..self.params(scene, filter) };
        self.run(
            &mut encoder,
            TRANSFORM,
            scene.voxels,
            params,
            &[
                (1, &scene.positions),
                (2, &scene.records),
                (3, &scene.skins),
                (4, &scene.object_of),
                (5, &objects),
                (6, &mats),
                (7, &placed),
            ],
            &mut keep,
        )?;
        ctx.submit("transforming cached voxels", encoder)?;
        Ok(placed)
    }

    /// Reads moved voxels back.
    pub fn read_placed(&self, placed: &wgpu::Buffer, voxels: u64) -> Result<Vec<Placed>> {
        Ok(bytemuck::pod_collect_to_vec(
            &self.ctx.read(placed, voxels * size_of::<Placed>() as u64)?,
        ))
    }

    /// Uploads moved voxels (for instance the CPU's, to check the blend alone).
    pub fn upload_placed(&self, placed: &[Placed]) -> Result<wgpu::Buffer> {
        self.ctx.storage_init("placed voxels", bytemuck::cast_slice(placed))
    }

    /// Blends the moved voxels `placed` (one per cached voxel of `scene`) and the static voxels
    /// into world voxels and compacts the occupied ones (module docs: kernels 2–5). Errors:
    /// more contributions than the blend sums exactly, a threshold outside \[0, 8\], the
    /// device's limits.
    pub fn blend(
        &self,
        scene: &GpuDynamicScene,
        placed: &wgpu::Buffer,
        filter: Filter,
        threshold: f32,
    ) -> Result<GpuLeaves> {
        let ctx = self.ctx;
        if !(threshold.is_finite() && (0.0..=8.0).contains(&threshold)) {
            return Err(voxlod_octree::Error::InvalidParameter {
                name: "occupancy_threshold",
                value: threshold.to_string(),
                reason: "a covered volume in [0, 8] voxels",
            }
            .into());
        }
        let corners = filter.corners() as u64;
        let contributions = scene.voxels * corners + scene.static_count;
        if contributions > MAX_CONTRIBUTIONS {
            return Err(voxlod_octree::Error::FrameTooLarge {
                contributions,
                max: MAX_CONTRIBUTIONS,
            }
            .into());
        }
        let bricks = 1u64 << (3 * scene.brick_log2);
        let flags = ctx.storage_zeroed("brick flags", bricks * 4)?;
        let slots = ctx.storage_zeroed("brick slots", bricks * 4)?;
        let base = self.params(scene, filter);
        let min_weight = ((threshold as f64 * 262_144.0).ceil() as u32).max(1);
        let mut keep = Vec::new();
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let moving = scene.voxels * corners;
        let mark = GpuDynamicParams { n: moving as u32, ..base };
        let entries = [(1, placed), (2, &scene.static_cells), (3, &flags)];
        self.run(&mut encoder, MARK, moving, mark, &entries, &mut keep)?;
        let marks = GpuDynamicParams { n: scene.static_count as u32, extra: 1, ..base };
        self.run(&mut encoder, MARK, scene.static_count, marks, &entries, &mut keep)?;
        encoder.copy_buffer_to_buffer(&flags, 0, &slots, 0, bricks * 4);
        let total = self.octree.scan(&mut encoder, &slots, bricks, &mut keep)?;
        ctx.submit("marking world bricks", encoder)?;
        let used = bytemuck::pod_read_unaligned::<u32>(&ctx.read(&total, 4)?) as u64;
        keep.clear();
        let cells = 8 * used;
        let slot_code = ctx.storage_zeroed("brick codes", used.max(1) * 4)?;
        let sums = ctx.storage_zeroed("world voxel sums", cells.max(1) * 64)?;
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let p = GpuDynamicParams { n: bricks as u32, ..base };
        self.run(
            &mut encoder,
            BRICKS,
            bricks,
            p,
            &[(1, &flags), (2, &slots), (3, &slot_code)],
            &mut keep,
        )?;
        let acc = [
            (1, placed),
            (2, &scene.records),
            (3, &slots),
            (4, &sums),
            (5, &scene.linear12),
            (6, &scene.static_cells),
            (7, &scene.static_sums),
        ];
        self.run(
            &mut encoder,
            ACCUMULATE,
            moving,
            GpuDynamicParams { n: moving as u32, ..base },
            &acc,
            &mut keep,
        )?;
        let s = GpuDynamicParams { n: scene.static_count as u32, extra: 1, ..base };
        self.run(&mut encoder, ACCUMULATE, scene.static_count, s, &acc, &mut keep)?;
        let occupied = ctx.storage_zeroed("occupancy", cells.max(1) * 4)?;
        let dummy = ctx.storage_zeroed("unused", 64)?;
        let occ = GpuDynamicParams { n: cells as u32, min_weight, ..base };
        self.run(
            &mut encoder,
            COMPACT,
            cells,
            occ,
            &[(1, &sums), (2, &slot_code), (3, &occupied), (4, &dummy), (5, &dummy), (6, &dummy)],
            &mut keep,
        )?;
        let total = self.octree.scan(&mut encoder, &occupied, cells.max(1), &mut keep)?;
        ctx.submit("blending moved voxels", encoder)?;
        let count = bytemuck::pod_read_unaligned::<u32>(&ctx.read(&total, 4)?) as u64;
        keep.clear();
        let coords = ctx.storage_zeroed("leaf coordinates", count.max(1) * 12)?;
        let payload =
            ctx.storage_zeroed("leaf payloads", count.max(1) * size_of::<AveragePayload>() as u64)?;
        let leaf_sums = ctx.storage_zeroed("leaf sums", count.max(1) * 64)?;
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let compact = GpuDynamicParams { extra: 1, ..occ };
        self.run(
            &mut encoder,
            COMPACT,
            cells,
            compact,
            &[
                (1, &sums),
                (2, &slot_code),
                (3, &occupied),
                (4, &coords),
                (5, &payload),
                (6, &leaf_sums),
            ],
            &mut keep,
        )?;
        ctx.submit("compacting occupied world voxels", encoder)?;
        // Touched world voxels: slots whose weight is not zero (read back only for statistics).
        let raw: Vec<u32> = bytemuck::pod_collect_to_vec(&ctx.read(&sums, cells * 64)?);
        let touched = raw.chunks_exact(16).filter(|s| s[0] != 0 || s[1] != 0).count() as u64;
        Ok(GpuLeaves { coords, payload, sums: leaf_sums, count, touched })
    }

    /// Reads leaves back: coordinates, payloads and raw sums, in Morton order.
    pub fn read_leaves(
        &self,
        leaves: &GpuLeaves,
    ) -> Result<(Vec<UVec3>, Vec<AveragePayload>, Vec<CellSums>)> {
        let n = leaves.count;
        let coords: Vec<u32> =
            bytemuck::pod_collect_to_vec(&self.ctx.read(&leaves.coords, n * 12)?);
        let payload = bytemuck::pod_collect_to_vec(
            &self.ctx.read(&leaves.payload, n * size_of::<AveragePayload>() as u64)?,
        );
        let sums = bytemuck::pod_collect_to_vec(&self.ctx.read(&leaves.sums, n * 64)?);
        Ok((coords.chunks_exact(3).map(UVec3::from_slice).collect(), payload, sums))
    }

    /// One whole frame on the device (module docs): places the objects on the host (the CPU's
    /// checks and errors), then transform, blend, octree, injection and the radiance octree.
    pub fn frame(
        &self,
        scene: &GpuDynamicScene,
        caches: &[VoxelCache],
        placements: &[Placement],
        options: &FrameOptions,
        light: &Light,
        shadows: &Shadows,
    ) -> Result<GpuFrame<'a>> {
        if placements.len() != caches.len() {
            return Err(voxlod_cone::Error::InvalidParameter {
                name: "placements",
                value: placements.len().to_string(),
                reason: "one placement per cached object",
            }
            .into());
        }
        let frames = caches
            .iter()
            .zip(placements)
            .map(|(c, p)| place(c, p, &scene.grid, options.rigidity_tolerance))
            .collect::<voxlod_octree::Result<Vec<_>>>()?;
        let placed = self.transform(scene, &frames, options.filter)?;
        let leaves = self.blend(scene, &placed, options.filter, options.occupancy_threshold)?;
        drop(placed);
        let geometry = self.octree.build_device(
            &scene.grid,
            &leaves.coords,
            &leaves.payload,
            leaves.count as usize,
            &options.build,
        )?;
        let injected = self.inject(&scene.grid, &geometry, &leaves, light, shadows)?;
        let filled =
            self.octree.refill(&geometry, &leaves.coords, &injected, leaves.count as usize)?;
        let payload = self.convert(&filled, geometry.node_count, true)?;
        let radiance = GpuConeOctree::from_device(
            self.ctx,
            &geometry.levels,
            geometry.nodes.clone(),
            geometry.tiles.clone(),
            geometry.tile_count,
            payload,
            scene.grid,
            geometry.depth,
            geometry.first_dense,
        )?;
        Ok(GpuFrame { leaves, geometry, injected, radiance })
    }

    /// Cone traces `points` (an image `width` wide) through a frame's radiance octree.
    pub fn trace(
        &self,
        frame: &GpuFrame,
        options: &TraceOptions,
        query: ConeQuery,
        points: &[ShadingPoint],
        width: u32,
    ) -> Result<Vec<ConeShade>> {
        self.cone.trace(&frame.radiance, options, query, points, width)
    }
}

/// The level table a frame's geometry octree was built with (for tests and statistics).
pub fn levels_of<'t>(tree: &'t GpuOctree) -> &'t [GpuLevel] {
    &tree.levels
}

#[cfg(test)]
mod tests;
