//! Kernel 4 (first part): the filtered voxel renderer for **Averages** and **\[VJK21\]**
//! (SGGX) records on the GPU, the mirror of [`voxlod_cpu::render::filtered::render`] over an
//! [`AppearanceGrid`] of [`AverageRecord`] or [`SggxRecord`]: 4 camera rays per pixel through
//! [`PATTERN_4`](voxlod_cpu::render::sampling::PATTERN_4), each walking the grid with the DDA
//! of [`voxlod_cpu::render::dda`] (ported line by line: the same plane expression, tie rule and
//! clipping), compositing the voxels with a record front to back until `T < 0.001` with
//! `Opacity::apply` (alpha for Averages; for \[VJK21\] the non-exponential update of
//! [`voxlod_cpu::appearance::transmittance::compose`] with the ray's exact chord in voxel
//! units, `f⁻¹` by the same 8 Newton steps), each voxel shaded for the voxel-centre-to-camera
//! direction with `shading.wgsl` (the port of [`voxlod_cpu::shading::shade`]) — Averages with
//! its normal turned toward the viewer, SGGX as the mean over the 16 fixed VNDF samples of
//! [`voxlod_cpu::appearance::sggx::shade_record`] — and, with shadows on, the visibility of
//! one shadow ray from the voxel centre that ignores the voxels within 1.5 voxel sizes and
//! composes every other voxel's opacity with its chord. An Averages voxel whose normal faces
//! away from the light traces no shadow ray
//! ([`Appearance::needs_visibility`](voxlod_cpu::appearance::Appearance::needs_visibility));
//! SGGX voxels always do (the CPU's default).
//!
//! The baseline renderer (opaque cubes of one colour, [`voxlod_cpu::render::baseline`]) runs
//! in the same kernel as record kind 2 ([`FilteredKernel::upload_baseline`],
//! [`FilteredKernel::render_baseline`]): the DDA reports the entry face's normal as the CPU's
//! does (`normal_for`: the largest `|dir|` among the axes crossed), the first voxel stops the
//! ray and is shaded at its entry point, and its shadow ray is the filtered one over records of
//! opacity 1 (the transmittance drops to 0 at the first counted voxel: the CPU's "blocked").
//! Virtual-mesh and Adaptive grids (record kinds 3 and 4, [`FilteredKernel::upload_virtual_mesh`],
//! [`FilteredKernel::upload_adaptive`], rendered by the same [`FilteredKernel::render`]) run as
//! per-voxel passes: see [`voxels`].
//!
//! # Use
//! ```no_run
//! # fn demo(app: &voxlod_cpu::appearance::AppearanceGrid<voxlod_format::records::AverageRecord>,
//! #         camera: &voxlod_scene::Camera, light: &voxlod_scene::Light) -> voxlod_gpu::Result<()> {
//! use voxlod_cpu::render::filtered::Options;
//! let ctx = voxlod_gpu::Context::new()?;
//! let kernel = voxlod_gpu::filtered::FilteredKernel::new(&ctx)?;
//! let gpu = kernel.upload_averages(app)?; // or upload_vjk21 for an SggxRecord grid
//! let options = Options { width: 256, height: 256, ..Options::default() };
//! let image = kernel.render(&gpu, camera, light, glam::Vec3::ZERO, &options)?;
//! # Ok(()) }
//! ```
//! `voxlod compare --backend gpu` calls it in place of [`voxlod_cpu::render::filtered::render`]
//! and [`voxlod_cpu::render::baseline::render`] (same inputs, same image up to the stated
//! bound) for every row: baseline, Averages, \[VJK21\], virtual mesh and Adaptive; every row
//! says which backend rendered it. `voxlod render` renders
//! the ground truth only, not voxel representations.
//!
//! # No per-frame cache: why evaluating per hit gives the CPU's cached values
//! The CPU caches per voxel a radiance, an opacity and a visibility. Each is a function of the
//! voxel alone (its record, its centre, the eye, the light, the ambient term): the direction is
//! from the voxel *centre* to the eye, not the ray's, and the shadow ray starts at the voxel
//! centre. So every ray that meets the voxel computes the same values, and the CPU's own
//! `render_uncached` (evaluating per ray) is tested equal to the cached render. The kernel
//! evaluates per hit: no atomics, no cache memory, at the cost of repeating a voxel's shadow
//! ray for each of the (up to 4 × pixels) camera rays that reach it.
//!
//! # Data on the GPU
//! The brick map as in voxlod-cpu's `render/filtered/lookup.rs`: a dense table of brick
//! ordinals over the grid's brick dimensions ([`DenseBricks::MAX_ENTRIES`] at most), per brick
//! a 512-bit occupancy mask in linear order (`x + 8y + 64z`) with the rank of each word's first
//! voxel ([`GpuBrick`]), and the record index of each rank; the records, decoded on the host by
//! voxlod-format's own decoders ([`GpuRecord`], 64 bytes instead of the record's 8 or 12: inputs
//! bit-identical to the CPU's; a production kernel would decode the packed bytes in the shader).
//! Light bounds and screen tiles are not ported: on the CPU they only shorten `t_max` and never
//! change the image (tested there); the GPU walks to the grid's exit.
//!
//! # Kernel (what a real GPU sees)
//! One invocation per pixel in 8×8 workgroups; every loop is bounded (a DDA visits at most
//! `dims.x + dims.y + dims.z` voxels). Expected on a real GPU: neighbouring camera rays cross
//! the same bricks, so brick-table and mask loads are shared in cache; divergence comes from
//! rays of one warp stopping at different depths (silhouettes) and from shadow rays, which are
//! all parallel (directional light) but start at different voxels and lengths, so a warp waits
//! for its longest shadow ray. Repeating shadow rays per hit costs up to ~4 × (voxels visible
//! per pixel) shadow walks; a two-pass version (visible voxels first, then one shadow ray per
//! voxel) is the next step where shadows dominate.
//!
//! Empty space is skipped as on the CPU (`walk_next` in `filtered.wgsl`, the port of
//! [`Dda::next_occupied_voxel`](voxlod_cpu::render::dda::Dda::next_occupied_voxel)): an
//! unallocated 8³ brick is crossed in one step (its exit planes, then the cell entered, by
//! the plane expression and tie rules of the voxel stepping), and inside an allocated brick an
//! empty 2³ block is left in one jump (two mask words tested per block). Every walk of every
//! kind (camera rays, shadow rays, the per-voxel passes of [`voxels`]) uses it, so a ray in
//! empty space costs one iteration per brick instead of one per voxel: about 8× fewer
//! iterations where bricks are empty, and fewer divergent lanes in a warp whose rays cross
//! different amounts of empty space. Same voxels, `t`s and entry normals as stepping (the CPU
//! proptests the skipping walk against plain stepping; the equivalence suite's images are
//! unchanged: 0 sRGB steps on every scene row).
//!
//! Measured (`cargo bench -p voxlod-gpu --bench kernels -- filtered`, bunny 64³, 128×128,
//! shadows, 2 cores shared with other jobs, load ~10): on lavapipe — **CPU timings of the GPU
//! path**, not GPU speed — 1.29 s (Averages) and 0.96 s (\[VJK21\]) per frame, against
//! 87 ms and 93 ms for voxlod-cpu's cold-cache frame. Indicative only: lavapipe's timings
//! swing by two orders of magnitude with the machine's load (the equivalence suite's
//! ground-truth proptest took 422 s loaded and 1.4 s on a quiet machine), and the GPU path
//! also repeats every shadow ray per hit, which the CPU path's cache avoids (these figures were
//! taken before the GPU walks skipped empty bricks and blocks).
//!
//! # Agreement with the CPU
//! Same arithmetic except float rounding: voxel centres are computed in `f32` here (`f64`
//! then rounded on the CPU), WGSL's division and `normalize` are within a few ULP, a compiler
//! may fuse multiply-adds. A DDA plane crossing that differs by an ULP can flip which voxel a
//! ray grazing an edge or corner visits, which changes a pixel by a fraction of the local
//! contrast; everywhere else pixels agree to ~1e-6 relative. The equivalence suite states the
//! bound.

use glam::{UVec3, Vec3, Vec4};
use voxlod_cpu::appearance::{AppearanceGrid, RecordAppearance, record_material};
use voxlod_cpu::render::baseline::{self, BaselineVoxel};
use voxlod_cpu::render::bricks::DenseBricks;
use voxlod_cpu::render::filtered::{FrameCache, Options, check_frame};
use voxlod_format::records::{AverageRecord, SggxRecord};
use voxlod_format::{BRICK_EDGE, BrickMap, GridSpec};
use voxlod_scene::MaterialSample;
use voxlod_scene::{Camera, Image, Light};

pub mod voxels;

use crate::raycast::entry;
use crate::{Context, Error, Result, light_words};

/// The WGSL source of the kernel: shading, then the renderer.
pub const WGSL: &str = concat!(include_str!("../shading.wgsl"), include_str!("filtered.wgsl"));

/// The kernel's parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuFilteredParams {
    /// Camera eye (world).
    pub eye: [f32; 4],
    /// Eye in grid coordinates, computed as the CPU's DDA does (`f64`, then `f32`); `w` =
    /// voxels per world unit.
    pub eye_grid: [f32; 4],
    /// Unit view direction.
    pub forward: [f32; 4],
    /// Right vector scaled by tan(fov/2)·aspect.
    pub right: [f32; 4],
    /// Up vector scaled by tan(fov/2).
    pub up: [f32; 4],
    /// Background colour (linear RGB).
    pub background: [f32; 4],
    /// Ambient term of the shading function.
    pub ambient: [f32; 4],
    /// Directional light: unit direction toward it; point light: its position.
    pub light_a: [f32; 4],
    /// Directional light: irradiance; point light: intensity.
    pub light_b: [f32; 4],
    /// Grid origin (`f32`); `w` = voxel size.
    pub grid: [f32; 4],
    /// Grid dimensions; `w` = flags (1: shadows, 2: point light).
    pub dims: [u32; 4],
    /// Width, height, the DDA step bound, 0.
    pub size: [u32; 4],
    /// Bricks per axis, 0.
    pub brick_dims: [u32; 4],
    /// Virtual-mesh and Adaptive grids ([`voxels`]): directional-opacity rule (0 Lines,
    /// 1 Circles), shading samples per distribution face, projected-area scaling (0/1), and
    /// the number of voxels with a record. Zero for the other kinds.
    pub vmesh: [u32; 4],
}

/// One allocated brick (mirrors WGSL `Brick`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuBrick {
    /// Occupancy, bit `x + 8y + 64z` of the brick's 512 (word = bit / 32).
    pub mask: [u32; 16],
    /// Rank (index into the slot array) of the first occupied voxel of each word.
    pub before: [u32; 16],
}

/// A record decoded for the kernel (mirrors WGSL `Record`). Averages: `a` = (albedo,
/// opacity), `b` = (mean normal, 0); \[VJK21\]: `a` = (albedo, σ), `b.w` = γ, and the SGGX
/// matrix's columns in `b`, `c`, `d` (`xyz`). Both: `c.w` = specular level, `d.w` = shininess
/// (as `record_material` gives them).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuRecord {
    /// Albedo, opacity or σ.
    pub a: [f32; 4],
    /// Normal or first matrix column; γ.
    pub b: [f32; 4],
    /// Second matrix column; specular level.
    pub c: [f32; 4],
    /// Third matrix column; shininess.
    pub d: [f32; 4],
}

/// Which records a [`GpuRecords`] holds (the kernel's `size.w`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecordKind {
    /// [`AverageRecord`]: alpha compositing, one normal.
    Averages = 0,
    /// [`SggxRecord`]: \[VJK21\] transmittance, SGGX shading.
    Vjk21 = 1,
    /// [`BaselineVoxel`]: opaque cubes of one colour, the baseline renderer
    /// ([`voxlod_cpu::render::baseline`]).
    Baseline = 2,
    /// [`VirtualMeshGrid`](voxlod_cpu::appearance::vmesh::VirtualMeshGrid): virtual mesh +
    /// opacity subgrid, rendered by the per-voxel passes of [`voxels`].
    VirtualMesh = 3,
    /// [`AdaptiveGrid`](voxlod_cpu::appearance::adaptive::AdaptiveGrid): each voxel one of
    /// the three, rendered by the per-voxel passes of [`voxels`].
    Adaptive = 4,
}

/// The look-up arrays of a brick map: the dense brick table (`u32::MAX` = empty), the bricks'
/// linear masks and ranks, and the value index of each rank. Errors when the dense table
/// would exceed [`DenseBricks::MAX_ENTRIES`].
pub fn brick_lookup<T>(map: &BrickMap<T>) -> Result<(Vec<u32>, Vec<GpuBrick>, Vec<u32>)> {
    let bd = map.brick_dims();
    let entries = bd.as_u64vec3().element_product();
    if entries > DenseBricks::MAX_ENTRIES {
        return Err(Error::TooLarge {
            what: "dense brick table of the filtered renderer (brick positions)",
            requested: entries,
            limit: DenseBricks::MAX_ENTRIES,
        });
    }
    let mut table = vec![u32::MAX; entries as usize];
    let mut per_brick: Vec<Vec<(u32, u32)>> = vec![Vec::new(); map.bricks().len()];
    for (i, (c, _)) in map.iter().enumerate() {
        let b = c / BRICK_EDGE;
        let ordinal = map.brick_index(b).expect("an occupied voxel's brick is allocated");
        table[(b.x + bd.x * (b.y + bd.y * b.z)) as usize] = ordinal as u32;
        let l = c % BRICK_EDGE;
        per_brick[ordinal].push((l.x | l.y << 3 | l.z << 6, i as u32));
    }
    let mut bricks = Vec::with_capacity(per_brick.len());
    let mut slots = Vec::with_capacity(map.len());
    for mut voxels in per_brick {
        voxels.sort_unstable();
        let mut b = GpuBrick::default();
        for &(l, value) in &voxels {
            b.mask[(l >> 5) as usize] |= 1 << (l & 31);
            slots.push(value);
        }
        let mut rank = (slots.len() - voxels.len()) as u32;
        for w in 0..16 {
            b.before[w] = rank;
            rank += b.mask[w].count_ones();
        }
        bricks.push(b);
    }
    Ok((table, bricks, slots))
}

/// A record grid uploaded to one device.
pub struct GpuRecords {
    kind: RecordKind,
    grid: GridSpec,
    table: wgpu::Buffer,
    bricks: wgpu::Buffer,
    slots: wgpu::Buffer,
    records: wgpu::Buffer,
    /// Virtual-mesh and Adaptive grids: the buffers of the per-voxel passes.
    voxels: Option<voxels::VoxelBuffers>,
}

impl GpuRecords {
    /// Which records these are.
    pub fn kind(&self) -> RecordKind {
        self.kind
    }
}

/// The filtered renderer kernel for Averages and \[VJK21\] records, compiled for one
/// [`Context`].
pub struct FilteredKernel<'a> {
    ctx: &'a Context,
    pipeline: wgpu::ComputePipeline,
    /// The per-voxel passes, compiled on first use (virtual-mesh and Adaptive grids).
    passes: std::sync::OnceLock<voxels::Passes>,
}

/// Records with a linear albedo (both record kinds of the kernel).
pub trait HasColor {
    /// Linear albedo.
    fn color(&self) -> Vec3;
}

impl HasColor for AverageRecord {
    fn color(&self) -> Vec3 {
        AverageRecord::color(self)
    }
}

impl HasColor for SggxRecord {
    fn color(&self) -> Vec3 {
        SggxRecord::color(self)
    }
}

/// A non-empty byte slice for a storage buffer (a zero-sized binding is invalid).
fn non_empty<T: bytemuck::Pod + Default>(v: &mut Vec<T>) -> &[u8] {
    if v.is_empty() {
        v.push(T::default());
    }
    bytemuck::cast_slice(v)
}

impl<'a> FilteredKernel<'a> {
    /// Compiles the kernel.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        Ok(Self {
            ctx,
            pipeline: ctx.pipeline("filtered averages", WGSL)?,
            passes: std::sync::OnceLock::new(),
        })
    }

    /// Uploads `app` after the CPU renderer's checks on it (a [`FrameCache`] is built over its
    /// own records and dropped: invalid grid, inconsistent records or side records give the
    /// CPU's errors).
    pub fn upload_averages(&self, app: &AppearanceGrid<AverageRecord>) -> Result<GpuRecords> {
        self.upload(app, RecordKind::Averages, |r, m| GpuRecord {
            a: m.albedo.extend(r.opacity()).to_array(),
            b: r.normal().extend(0.0).to_array(),
            c: [0.0, 0.0, 0.0, m.specular.x],
            d: [0.0, 0.0, 0.0, m.shininess],
        })
    }

    /// Uploads a \[VJK21\] (SGGX) grid, with the checks of [`FilteredKernel::upload_averages`].
    pub fn upload_vjk21(&self, app: &AppearanceGrid<SggxRecord>) -> Result<GpuRecords> {
        self.upload(app, RecordKind::Vjk21, |r, m| {
            let s = r.matrix();
            GpuRecord {
                a: m.albedo.extend(r.sigma_t()).to_array(),
                b: s.x_axis.extend(r.gamma()).to_array(),
                c: s.y_axis.extend(m.specular.x).to_array(),
                d: s.z_axis.extend(m.shininess).to_array(),
            }
        })
    }

    fn upload<R>(
        &self,
        app: &AppearanceGrid<R>,
        kind: RecordKind,
        decode: impl Fn(&R, &MaterialSample) -> GpuRecord,
    ) -> Result<GpuRecords>
    where
        R: RecordAppearance<Params = ()> + HasColor,
    {
        drop(FrameCache::with_layout(app, &app.records)?);
        if let Some(s) = app.specular.as_ref().filter(|s| s.len() != app.records.len()) {
            return Err(Error::Cpu(voxlod_cpu::Error::InvalidParameter {
                name: "specular records",
                value: s.len().to_string(),
                reason: format!("one per record: {}", app.records.len()),
            }));
        }
        let records: Vec<GpuRecord> = app
            .records
            .values()
            .iter()
            .enumerate()
            .map(|(i, r)| {
                decode(r, &record_material(r.color(), app.specular.as_ref().map(|s| &s[i])))
            })
            .collect();
        self.buffers(kind, app.grid, &app.records, records)
    }

    /// Uploads the baseline renderer's voxels (opaque cubes of one colour) over `grid`, with
    /// the checks [`voxlod_cpu::render::baseline::render`] makes on them (a valid grid, a brick
    /// map of the grid's size). Render with [`FilteredKernel::render_baseline`].
    pub fn upload_baseline(
        &self,
        grid: &GridSpec,
        voxels: &BrickMap<BaselineVoxel>,
    ) -> Result<GpuRecords> {
        grid.validate().map_err(voxlod_cpu::Error::from)?;
        if voxels.dims() != grid.dims {
            return Err(Error::Cpu(voxlod_cpu::Error::InvalidParameter {
                name: "voxels",
                value: format!("brick map of {} voxels", voxels.dims()),
                reason: format!("the grid has {} voxels", grid.dims),
            }));
        }
        let records = voxels
            .values()
            .iter()
            .map(|v| GpuRecord { a: v.albedo().extend(1.0).to_array(), ..Default::default() })
            .collect();
        self.buffers(RecordKind::Baseline, *grid, voxels, records)
    }

    /// The buffers of `records` laid out as `map`'s values.
    fn buffers<T>(
        &self,
        kind: RecordKind,
        grid: GridSpec,
        map: &BrickMap<T>,
        mut records: Vec<GpuRecord>,
    ) -> Result<GpuRecords> {
        let (mut table, mut bricks, mut slots) = brick_lookup(map)?;
        let ctx = self.ctx;
        Ok(GpuRecords {
            kind,
            grid,
            table: ctx.storage_init("brick table", non_empty(&mut table))?,
            bricks: ctx.storage_init("brick masks", non_empty(&mut bricks))?,
            slots: ctx.storage_init("record slots", non_empty(&mut slots))?,
            records: ctx.storage_init("filtered records", non_empty(&mut records))?,
            voxels: None,
        })
    }

    /// Renders uploaded baseline voxels from `camera`: what
    /// [`voxlod_cpu::render::baseline::render`] returns for them, with the same errors.
    pub fn render_baseline(
        &self,
        voxels: &GpuRecords,
        camera: &Camera,
        light: &Light,
        background: Vec3,
        options: &baseline::Options,
    ) -> Result<Image> {
        let baseline::Options { width, height, ambient, shadows } = *options;
        let options = Options { width, height, ambient, shadows };
        self.render(voxels, camera, light, background, &options)
    }

    /// Renders the uploaded grid from `camera`: what
    /// [`voxlod_cpu::render::filtered::render`] returns for it (linear RGB with the background
    /// composited, alpha = coverage), with the same errors for bad options, camera, light,
    /// ambient term or background.
    pub fn render(
        &self,
        app: &GpuRecords,
        camera: &Camera,
        light: &Light,
        background: Vec3,
        options: &Options,
    ) -> Result<Image> {
        let ctx = self.ctx;
        let light = check_frame(camera, light, background, options)?;
        let Options { width, height, .. } = *options;
        let (lx, ly) =
            ctx.image_dispatch("filtered image edge (workgroups of 8 pixels)", width, height)?;
        let params = Self::params(app, camera, &light, background, options);
        if let Some(v) = &app.voxels {
            return self.render_voxels(app, v, &params, (lx, ly));
        }
        let bytes = width as u64 * height as u64 * 16;
        let out = ctx.storage_zeroed("filtered image", bytes)?;
        let uniform = ctx.uniform("filtered params", bytemuck::bytes_of(&params))?;
        let layout = self.pipeline.get_bind_group_layout(0);
        let bind = ctx.guarded("binding filtered-renderer buffers", || {
            ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("filtered averages"),
                layout: &layout,
                entries: &[
                    entry(0, &uniform),
                    entry(1, &app.table),
                    entry(2, &app.bricks),
                    entry(3, &app.slots),
                    entry(4, &app.records),
                    entry(5, &out),
                ],
            })
        })?;
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(lx, ly, 1);
        }
        ctx.submit("rendering filtered records", encoder)?;
        read_image(ctx, &out, width, height)
    }

    /// The kernel's parameters for a frame (inputs already checked by `check_frame`).
    fn params(
        app: &GpuRecords,
        camera: &Camera,
        light: &Light,
        background: Vec3,
        options: &Options,
    ) -> GpuFilteredParams {
        let Options { width, height, ambient, shadows } = *options;
        let frame = camera.frame(width, height);
        let grid = app.grid;
        let eye_grid = ((camera.eye.as_dvec3() - grid.origin) / grid.voxel_size).as_vec3();
        let (point, la, lb) = light_words(light);
        let dims: UVec3 = grid.dims;
        let brick_dims = (dims + BRICK_EDGE - 1) / BRICK_EDGE;
        let steps = dims.x.saturating_add(dims.y).saturating_add(dims.z).saturating_add(3);
        GpuFilteredParams {
            eye: camera.eye.extend(0.0).to_array(),
            eye_grid: eye_grid.extend((1.0 / grid.voxel_size) as f32).to_array(),
            forward: frame.forward.extend(0.0).to_array(),
            right: frame.right.extend(0.0).to_array(),
            up: frame.up.extend(0.0).to_array(),
            background: background.extend(0.0).to_array(),
            ambient: ambient.extend(0.0).to_array(),
            light_a: la.extend(0.0).to_array(),
            light_b: lb.extend(0.0).to_array(),
            grid: grid.origin.as_vec3().extend(grid.voxel_size as f32).to_array(),
            dims: dims.extend(u32::from(shadows) | if point { 2 } else { 0 }).to_array(),
            size: [width, height, steps, app.kind as u32],
            brick_dims: brick_dims.extend(0).to_array(),
            vmesh: app.voxels.as_ref().map_or([0; 4], |v| v.params),
        }
    }
}

/// Reads a `width × height` image of `vec4<f32>` pixels back.
fn read_image(ctx: &Context, out: &wgpu::Buffer, width: u32, height: u32) -> Result<Image> {
    let raw = ctx.read(out, width as u64 * height as u64 * 16)?;
    let pixels: Vec<Vec4> =
        bytemuck::cast_slice::<u8, [f32; 4]>(&raw).iter().map(|p| Vec4::from_array(*p)).collect();
    Ok(Image { width, height, pixels })
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use glam::UVec3;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn filtered_types_mirror_their_wgsl() {
        type P = GpuFilteredParams;
        assert_mirrors(
            WGSL,
            "Params",
            size_of::<P>(),
            &[
                ("eye", offset_of!(P, eye)),
                ("eye_grid", offset_of!(P, eye_grid)),
                ("forward", offset_of!(P, forward)),
                ("right", offset_of!(P, right)),
                ("up", offset_of!(P, up)),
                ("background", offset_of!(P, background)),
                ("ambient", offset_of!(P, ambient)),
                ("light_a", offset_of!(P, light_a)),
                ("light_b", offset_of!(P, light_b)),
                ("grid", offset_of!(P, grid)),
                ("dims", offset_of!(P, dims)),
                ("size", offset_of!(P, size)),
                ("brick_dims", offset_of!(P, brick_dims)),
                ("vmesh", offset_of!(P, vmesh)),
            ],
        );
        assert_mirrors(
            WGSL,
            "Brick",
            size_of::<GpuBrick>(),
            &[("mask", offset_of!(GpuBrick, mask)), ("before", offset_of!(GpuBrick, before))],
        );
        assert_mirrors(
            WGSL,
            "Record",
            size_of::<GpuRecord>(),
            &[
                ("a", offset_of!(GpuRecord, a)),
                ("b", offset_of!(GpuRecord, b)),
                ("c", offset_of!(GpuRecord, c)),
                ("d", offset_of!(GpuRecord, d)),
            ],
        );
    }

    /// The look-up arrays find every voxel's value index, as the brick map does, and the 2³
    /// block test finds every block holding a voxel (the WGSL `walk_next`'s rank look-up and
    /// block bits, written here in Rust over the same arrays).
    #[test]
    fn brick_lookup_finds_every_voxel() {
        let dims = UVec3::new(21, 9, 17);
        let voxels = (0..400u32).map(|i| {
            let r = |k| voxlod_cpu::random::rand_u32(i, 5, k);
            (UVec3::new(r(0) % dims.x, r(1) % dims.y, r(2) % dims.z), i)
        });
        let voxels: std::collections::HashMap<UVec3, u32> = voxels.collect();
        let map = BrickMap::from_voxels(dims, voxels).unwrap();
        let (table, bricks, slots) = brick_lookup(&map).unwrap();
        let bd = map.brick_dims();
        for x in 0..dims.x {
            for y in 0..dims.y {
                for z in 0..dims.z {
                    let c = UVec3::new(x, y, z);
                    let b = c / 8;
                    let bi = table[(b.x + bd.x * (b.y + bd.y * b.z)) as usize];
                    let got = (bi != u32::MAX)
                        .then(|| {
                            let l = c % 8;
                            let lin = l.x | l.y << 3 | l.z << 6;
                            let (w, bit) = ((lin >> 5) as usize, lin & 31);
                            let word = bricks[bi as usize].mask[w];
                            (word >> bit & 1 == 1).then(|| {
                                let below = (word & ((1u32 << bit) - 1)).count_ones();
                                slots[(bricks[bi as usize].before[w] + below) as usize] as usize
                            })
                        })
                        .flatten();
                    assert_eq!(got, map.index_of(c), "{c}");
                    if bi == u32::MAX {
                        continue;
                    }
                    // walk_next's block test: 0x303 << ((x & 6) + 16·((y >> 1) & 1)) in the
                    // words of the block's two z layers.
                    let l = c % 8;
                    let bw = ((l.y >> 2) + 4 * (l.z >> 1)) as usize;
                    let mask = &bricks[bi as usize].mask;
                    let block = (mask[bw] | mask[bw + 2]) >> ((l.x & 6) + 16 * ((l.y >> 1) & 1));
                    let lo = c / 2 * 2;
                    let occupied = (0..8).any(|k| {
                        let v = lo + UVec3::new(k & 1, k >> 1 & 1, k >> 2);
                        v.cmplt(dims).all() && map.index_of(v).is_some()
                    });
                    assert_eq!(block & 0x303 != 0, occupied, "block of {c}");
                }
            }
        }
    }
}
