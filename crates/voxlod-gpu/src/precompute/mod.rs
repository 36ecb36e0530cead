//! The per-voxel appearance precompute on the GPU (the voxel sampling of Brito, Poulin and
//! Teichrieb 2023, §3.2 and §3.4), the mirror of voxlod-cpu's ray sampler
//! ([`voxlod_cpu::appearance::line_sampler`]), opacity subgrid
//! ([`voxlod_cpu::appearance::subgrid::build`]) and Averages fit
//! ([`voxlod_cpu::appearance::averages::fit`]), driven like
//! [`voxlod_cpu::appearance::precompute::precompute`].
//!
//! # What it computes
//! For every voxel of a voxelization with triangle lists: its `R` sampling lines (the CPU's
//! `sample_line`: voxel id `x + X·(y + Y·z)`, dimensions `8·seed + 0..5`, the same counter RNG
//! in WGSL, so every line is drawn from the same random numbers as on the CPU), the closest
//! hit of each whole line on the voxel's own triangles (ties to the lowest triangle id), the
//! cases of the sampler's rules (occluded; inside the closed voxel and front-facing, or any
//! side on double-sided materials, whose shading normal is then flipped), with the sampler's
//! alpha rules (a hit on an `Opaque` material always counts, on a `Mask` material where its
//! alpha at the hit's interpolated UV is > 0, on a `Blend` material on triangle `t` where
//! `rand_f32(v, i, blend_key(seed) ^ t) < alpha`; the closest *accepted* hit wins, rejected
//! hits do not occlude), the textured albedo, specular level and exponent of
//! `Material::sample` at the hit's UV ([`crate::material`]'s WGSL), and per voxel:
//! - the counts of occluded and case-(a) lines ([`VoxelStats`]);
//! - the sums the Averages fit reads (albedo, shading normal, `Σ n nᵀ`, specular level and
//!   level × exponent), reduced per workgroup in a fixed order; the host turns them into
//!   the [`AverageRecord`] exactly as [`averages::fit`](voxlod_cpu::appearance::averages::fit)
//!   does (mean, normalized sum or principal eigenvector, `occluded / R`, the same encoders),
//!   a few flops per voxel;
//! - the 27-byte opacity subgrid: every line books a ray, and an occlusion if occluded, on each
//!   sub-cell it crosses (integer workgroup atomics: exact and order-free), case-(a) hits mark
//!   their sub-cell (`atomicOr`), then the CPU's rule: unmarked or uncrossed cells 0, the
//!   others `unorm8(occluded / rays)`;
//! - optionally every line ([`Outputs::lines`]) as [`VoxelSamples`], so the CPU fits
//!   (\[VJK21\], virtual mesh) can run on GPU-sampled data.
//!
//! # Host preparation
//! The inputs are checked by voxlod-cpu's [`SamplingContext::new`] (same errors), options as
//! the CPU driver checks them (`rays = 0` is the CPU's error). Each voxel's triangles are set
//! up in voxel-local coordinates on the host **in `f64`, exactly as the CPU sampler does**
//! (plane, barycentric planes, flat axes; degenerate triangles dropped), then rounded to `f32`:
//! 80 bytes per (voxel, triangle) pair. So the kernel's `f32` numbers are the CPU's own, and
//! only the kernel's arithmetic can differ. A triangle whose material is not `Opaque` carries
//! a flag (bit 3 of its flat-axis word) so that the alpha test runs only on its hits. Every
//! material kind is served: the materials, texture descriptors and texels are
//! [`crate::material::gpu_materials`]' buffers; what cannot be served is a device limit (a
//! texture edge over [`crate::material::MAX_TEXTURE_EDGE`], texels or triangles over a storage
//! binding), an error with the numbers, never a fallback to the CPU.
//!
//! # Kernel (what a real GPU sees)
//! One workgroup of [`WORKGROUP`] = 64 invocations per voxel; the invocations stride over the
//! voxel's lines (150 by default: 3 strides, the last one 22/64 busy). Every invocation runs
//! the same loop over the voxel's triangles, reading the same 80-byte triangle at the same
//! time: a uniform (broadcast) load served from cache, so a voxel's triangles are fetched from
//! memory about once, with no workgroup memory and no barrier in the loop. The only
//! divergence is the booking of a hit (taken by the lines that hit), the sub-cell loop
//! (≤ 7 iterations) and, on alpha-filtered triangles only, the alpha test of a closer hit: the
//! UV interpolation and a material evaluation (on a textured material four texel loads and
//! ~100 integer operations of exact addressing, see [`crate::material`]), plus one PCG3D call
//! on `Blend`; booking a surface hit evaluates the material once more for its albedo. A line
//! costs its set-up (5 PCG3D calls, two degree-12 polynomials, a
//! square root, 3 divisions for the chord) and about 25 flops per triangle of its voxel. The
//! per-voxel reductions stay in the workgroup: integer counters with workgroup atomics, and
//! the float sums (16 per invocation, 4 KiB of workgroup memory) added by invocation 0 in
//! invocation order after the kernel's second and last barrier. One thread per
//! (voxel, line) instead would need global atomics or a second pass for the per-voxel
//! reductions; one thread per voxel would leave a GPU idle below ~10⁵ voxels and make
//! neighbouring lanes wait for the voxel with the most triangles. Voxels are split into
//! dispatches of at most [`VOXELS_PER_DISPATCH`] workgroups and [`LINES_PER_DISPATCH`] lines
//! (a bound on a dispatch's duration, which desktop drivers' watchdogs limit), each a 2D
//! dispatch within `max_compute_workgroups_per_dimension`.
//!
//! On a CPU implementation (lavapipe) every workgroup barrier is a costly switch between
//! invocations, hence one barrier for the float sums where a tree reduction would take six.
//!
//! # Agreement with the CPU (the equivalence suite's bounds)
//! The random numbers are equal bit for bit; the lines (direction, entry, chord) and the hit
//! tests use the CPU's `f32` expressions in the CPU's order, but WGSL's division and `sqrt`
//! are only accurate to a few ULP and a shader compiler may fuse multiply-adds (naga does not
//! mark operations `NoContraction`), so a line's numbers may differ in the last bits. A line
//! grazing a triangle edge (within a few ULP), a triangle's plane at a voxel face, or two
//! triangles at the same distance may then change case or triangle: the suite measures how
//! many lines do and bounds the fraction. The float sums are `f32`, each invocation's partial
//! sums added in invocation order, where the CPU sums in `f64` in line order (about 1e-7
//! relative), so a record byte may round the other way: ±1 in each byte where every line
//! agrees. The subgrid's counters are integers (exact). Textures and alpha add one inexact step,
//! the bilinear lerp (a multiply-add may be fused: a few ULP): an alpha within those ULP of a
//! mask cutoff or of a blend number can flip a line, an albedo move by ULP; the UV itself is
//! the CPU's expression in the CPU's order.
//!
//! # Layout of the module
//! `params` holds the `#[repr(C)]` mirrors of the kernel's WGSL structs, `prepare` the
//! host-side set-up of each voxel's triangles, `readback` the records, counts and lines built
//! from the kernel's outputs; this file compiles the kernel and runs the dispatches.
//!
//! [`VoxelSamples`]: voxlod_cpu::appearance::voxel_samples::VoxelSamples

use voxlod_cpu::appearance::AppearanceGrid;
use voxlod_cpu::appearance::line_sampler::{SamplingContext, blend_key, dimension_base};
use voxlod_cpu::appearance::precompute::PrecomputeOptions;
use voxlod_cpu::voxelize::Voxelization;
use voxlod_format::records::AverageRecord;
use voxlod_scene::{Geometry, Scene};

use crate::ground_truth::gpu_shade_tris;
use crate::material::gpu_materials;
use crate::{Context, Error, Result};

mod params;
mod prepare;
mod readback;

pub use params::{ALPHA_FLAG, GpuLineOut, GpuLocalTri, GpuPrecomputeParams, GpuVoxel, GpuVoxelOut};
pub use prepare::prepare;
pub use readback::{GpuPrecompute, LineCase, VoxelStats};

/// The WGSL source of the kernel: the RNG, materials and textures, then the sampler.
pub const WGSL: &str = concat!(
    include_str!("../random/random.wgsl"),
    include_str!("../material/material.wgsl"),
    include_str!("../subgrid.wgsl"),
    include_str!("precompute.wgsl")
);

/// Invocations per workgroup (one workgroup per voxel).
pub const WORKGROUP: u32 = 64;

/// Voxels (workgroups) per dispatch, at most.
pub const VOXELS_PER_DISPATCH: u32 = 1 << 14;

/// Lines per dispatch, at most (fewer voxels per dispatch when a voxel has many lines; at
/// least one voxel).
pub const LINES_PER_DISPATCH: u64 = 1 << 22;

/// What [`Precomputer::run`] returns besides the Averages grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// Also read back every line as [`VoxelSamples`](voxlod_cpu::appearance::voxel_samples::VoxelSamples)
    /// (80 bytes per line on the device).
    pub lines: bool,
}

/// The Averages grid of `vox`'s voxels sampled with `opts` on the GPU: what
/// `voxlod_cpu::appearance::precompute::precompute(ctx, opts, averages::fit)` returns (module
/// docs: agreement), with the same errors for bad input.
pub fn averages(
    ctx: &Context,
    scene: &Scene,
    geometry: &Geometry,
    vox: &Voxelization,
    opts: &PrecomputeOptions,
) -> Result<AppearanceGrid<AverageRecord>> {
    Ok(Precomputer::new(ctx)?.run(scene, geometry, vox, opts, Outputs::default())?.averages)
}

/// The precompute kernel, compiled for one [`Context`].
pub struct Precomputer<'a> {
    ctx: &'a Context,
    pipeline: wgpu::ComputePipeline,
    voxels_per_dispatch: u32,
    dispatch_width: u32,
}

impl<'a> Precomputer<'a> {
    /// Compiles the kernel.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        Ok(Self {
            ctx,
            pipeline: ctx.pipeline("precompute", WGSL)?,
            voxels_per_dispatch: VOXELS_PER_DISPATCH,
            dispatch_width: ctx.limits().max_compute_workgroups_per_dimension,
        })
    }

    /// Sets the most voxels per dispatch (at least 1). The results do not depend on it (each
    /// voxel is one workgroup), which the equivalence suite checks bit for bit.
    pub fn with_voxels_per_dispatch(mut self, voxels: u32) -> Self {
        self.voxels_per_dispatch = voxels.max(1);
        self
    }

    /// Sets the most workgroups along x of a dispatch (at least 1, at most the device's
    /// `max_compute_workgroups_per_dimension`): smaller forces the 2D dispatch, for tests.
    pub fn with_dispatch_width(mut self, width: u32) -> Self {
        let max = self.ctx.limits().max_compute_workgroups_per_dimension;
        self.dispatch_width = width.clamp(1, max);
        self
    }

    /// Samples every voxel of `vox` (with triangle lists, over `geometry` = `scene.geometry()`)
    /// with `opts` on the GPU (module docs).
    pub fn run(
        &self,
        scene: &Scene,
        geometry: &Geometry,
        vox: &Voxelization,
        opts: &PrecomputeOptions,
        outputs: Outputs,
    ) -> Result<GpuPrecompute> {
        let ctx = self.ctx;
        let sampling = SamplingContext::new(scene, geometry, vox)?;
        if opts.rays == 0 {
            // The CPU driver's error, word for word.
            return Err(voxlod_cpu::Error::InvalidParameter {
                name: "rays",
                value: "0".into(),
                reason: "at least one sampling line per voxel".into(),
            }
            .into());
        }
        if opts.rays > u32::MAX - WORKGROUP {
            // The kernel's stride over the lines must not wrap.
            return Err(Error::TooLarge {
                what: "lines per voxel",
                requested: opts.rays as u64,
                limit: (u32::MAX - WORKGROUP) as u64,
            });
        }
        let materials = gpu_materials(scene)?;
        let n = sampling.voxel_count();
        let rays = opts.rays;
        let (voxels, tris) = prepare(&sampling, scene, geometry)?;
        if n as u64 > u32::MAX as u64 || tris.len() as u64 > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "voxels or (voxel, triangle) pairs (32-bit indices)",
                requested: (n as u64).max(tris.len() as u64),
                limit: u32::MAX as u64,
            });
        }
        let line_count = n as u64 * rays as u64;
        if outputs.lines && line_count > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "lines read back (voxels × rays, 32-bit indices)",
                requested: line_count,
                limit: u32::MAX as u64,
            });
        }
        let mut out_raw = Vec::new();
        let mut line_raw = Vec::new();
        if n > 0 {
            let shade = gpu_shade_tris(geometry);
            let voxel_buf = ctx.storage_init("precompute voxels", bytemuck::cast_slice(&voxels))?;
            let tri_buf = ctx.storage_init("precompute triangles", bytemuck::cast_slice(&tris))?;
            let shade_buf = ctx.storage_init("shading triangles", bytemuck::cast_slice(&shade))?;
            let mat_bufs = materials.upload(ctx)?;
            let out_bytes = n as u64 * size_of::<GpuVoxelOut>() as u64;
            let out_buf = ctx.storage_zeroed("precompute results", out_bytes)?;
            let line_bytes =
                // Without lines, one element: a binding holds at least one.
                size_of::<GpuLineOut>() as u64 * if outputs.lines { line_count } else { 1 };
            let line_buf = ctx.storage_zeroed("precompute lines", line_bytes)?;
            let mut first = 0u32;
            while (first as usize) < n {
                let by_lines = (LINES_PER_DISPATCH / rays as u64).clamp(1, u32::MAX as u64) as u32;
                let count = (n as u32 - first).min(self.voxels_per_dispatch).min(by_lines);
                let x = count.min(self.dispatch_width);
                let y = count.div_ceil(x);
                let max = ctx.limits().max_compute_workgroups_per_dimension;
                if y > max {
                    return Err(Error::TooLarge {
                        what: "precompute workgroups per dispatch",
                        requested: count as u64,
                        limit: x as u64 * max as u64,
                    });
                }
                let params = GpuPrecomputeParams {
                    counts: [n as u32, rays, first, u32::from(outputs.lines)],
                    seed: [dimension_base(opts.seed), count, blend_key(opts.seed), 0],
                };
                let uniform = ctx.uniform("precompute params", bytemuck::bytes_of(&params))?;
                let buffers = [
                    &uniform,
                    &voxel_buf,
                    &tri_buf,
                    &shade_buf,
                    &mat_bufs.materials,
                    &out_buf,
                    &line_buf,
                    &mat_bufs.textures,
                    &mat_bufs.texels,
                ];
                ctx.dispatch("sampling voxels", &self.pipeline, &buffers, (x, y))?;
                first += count;
            }
            out_raw = ctx.read(&out_buf, out_bytes)?;
            if outputs.lines {
                line_raw = ctx.read(&line_buf, line_bytes)?;
            }
        }
        readback::results(
            &sampling,
            geometry,
            &materials.materials,
            rays,
            &out_raw,
            outputs.lines.then_some(&line_raw[..]),
        )
    }
}
