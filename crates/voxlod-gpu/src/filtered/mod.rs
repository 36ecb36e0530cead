//! The filtered voxel renderer on the GPU (the voxel renderer of Brito, Poulin and Teichrieb
//! 2023, §3.1 and §4) for **Averages** and **\[VJK21\]** (SGGX; Vicini, Jakob and Kaplanyan
//! 2021) records, the mirror of [`voxlod_cpu::render::filtered::render`] over an
//! [`AppearanceGrid`] of [`AverageRecord`] or [`SggxRecord`]: 4 camera rays per pixel through
//! [`PATTERN_4`](voxlod_cpu::render::pixel_samples::PATTERN_4), each walking the grid with the DDA
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
//! Virtual-mesh and Adaptive grids (record kinds 3 and 4,
//! [`FilteredKernel::upload_virtual_mesh`], [`FilteredKernel::upload_adaptive`], rendered by
//! the same [`FilteredKernel::render`]) run as per-voxel passes: see [`voxels`].
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
//! says which backend rendered it. `voxlod render` renders the ground truth only, not voxel
//! representations.
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
//! per pixel) shadow walks; where shadows dominate, a two-pass version (visible voxels first,
//! then one shadow ray per voxel) would do less work.
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
//! property-tests the skipping walk against plain stepping).
//!
//! # Agreement with the CPU
//! Same arithmetic except float rounding: voxel centres are computed in `f32` here (`f64`
//! then rounded on the CPU), WGSL's division and `normalize` are within a few ULP, a compiler
//! may fuse multiply-adds. A DDA plane crossing that differs by an ULP can flip which voxel a
//! ray grazing an edge or corner visits, which changes a pixel by a fraction of the local
//! contrast; everywhere else pixels agree to ~1e-6 relative. The equivalence suite states the
//! bound.
//!
//! # Layout of the module
//! `params` holds the `#[repr(C)]` mirrors of the kernel's WGSL structs and a frame's
//! uniform, `lookup` the brick look-up arrays, `upload` the record grids' checks and uploads
//! ([`GpuRecords`]), [`voxels`] the virtual-mesh and Adaptive passes; this file compiles the
//! kernel and renders a frame.
//!
//! [`AppearanceGrid`]: voxlod_cpu::appearance::AppearanceGrid
//! [`AverageRecord`]: voxlod_format::records::AverageRecord
//! [`SggxRecord`]: voxlod_format::records::SggxRecord
//! [`DenseBricks::MAX_ENTRIES`]: voxlod_cpu::render::bricks::DenseBricks::MAX_ENTRIES

use glam::{Vec3, Vec4};
use voxlod_cpu::render::baseline;
use voxlod_cpu::render::filtered::{Options, PixelPattern, VjkChord, check_frame};
use voxlod_scene::{Camera, Image, Light};

use crate::{Context, Error, Result};

mod lookup;
mod params;
mod upload;
pub mod voxels;

pub use lookup::brick_lookup;
pub use params::{GpuBrick, GpuFilteredParams, GpuRecord, RecordKind};
pub use upload::{GpuRecords, HasColor};

/// The WGSL source of the kernel: shading, then the renderer.
pub const WGSL: &str = concat!(include_str!("../shading.wgsl"), include_str!("filtered.wgsl"));

/// The filtered renderer kernel for Averages and \[VJK21\] records, compiled for one
/// [`Context`].
pub struct FilteredKernel<'a> {
    ctx: &'a Context,
    pipeline: wgpu::ComputePipeline,
    /// The per-voxel passes, compiled on first use (virtual-mesh and Adaptive grids).
    passes: std::sync::OnceLock<voxels::Passes>,
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
        let options = Options { width, height, ambient, shadows, ..Options::default() };
        self.render(voxels, camera, light, background, &options)
    }

    /// Renders the uploaded grid from `camera`: what
    /// [`voxlod_cpu::render::filtered::render`] returns for it (linear RGB with the background
    /// composited, alpha = coverage), with the same errors for bad options, camera, light,
    /// ambient term or background. The kernel follows the default chord and pixel pattern only:
    /// [`Options::vjk_chord`] other than `PerRay` or [`Options::pattern`] other than `Fixed` is
    /// [`Error::Unsupported`], naming the option.
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
        check_gpu_options(options)?;
        let Options { width, height, .. } = *options;
        let (lx, ly) =
            ctx.image_dispatch("filtered image edge (workgroups of 8 pixels)", width, height)?;
        let params = params::frame_params(app, camera, &light, background, options);
        if let Some(v) = &app.voxels {
            return self.render_voxels(app, v, &params, (lx, ly));
        }
        let bytes = width as u64 * height as u64 * 16;
        let out = ctx.storage_zeroed("filtered image", bytes)?;
        let uniform = ctx.uniform("filtered params", bytemuck::bytes_of(&params))?;
        let buffers = [&uniform, &app.table, &app.bricks, &app.slots, &app.records, &out];
        ctx.dispatch("rendering filtered records", &self.pipeline, &buffers, (lx, ly))?;
        read_image(ctx, &out, width, height)
    }
}

/// The options the kernel does not follow: an [`Error::Unsupported`] naming the first.
pub fn check_gpu_options(options: &Options) -> Result<()> {
    if options.vjk_chord != VjkChord::PerRay {
        return Err(Error::Unsupported {
            what: "filtered::Options::vjk_chord other than VjkChord::PerRay (a [VJK21] chord \
                   cached per voxel) in the GPU filtered renderer",
        });
    }
    if options.pattern != PixelPattern::Fixed {
        return Err(Error::Unsupported {
            what: "filtered::Options::pattern other than PixelPattern::Fixed (jittered pixel \
                   patterns) in the GPU filtered renderer",
        });
    }
    Ok(())
}

/// Reads a `width × height` image of `vec4<f32>` pixels back.
fn read_image(ctx: &Context, out: &wgpu::Buffer, width: u32, height: u32) -> Result<Image> {
    let raw = ctx.read(out, width as u64 * height as u64 * 16)?;
    let pixels: Vec<Vec4> =
        bytemuck::cast_slice::<u8, [f32; 4]>(&raw).iter().map(|p| Vec4::from_array(*p)).collect();
    Ok(Image { width, height, pixels })
}
