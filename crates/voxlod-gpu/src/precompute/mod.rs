//! Kernel 6: the per-voxel appearance precompute on the GPU, the mirror of voxlod-cpu's ray
//! sampler ([`voxlod_cpu::appearance::sampler`]), opacity subgrid
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
//!   level × exponent), reduced per workgroup in a fixed tree order; the host turns them into
//!   the [`AverageRecord`] exactly as [`averages::fit`](voxlod_cpu::appearance::averages::fit)
//!   does (mean, normalized sum or principal eigenvector, `occluded / R`, the same encoders),
//!   a few flops per voxel;
//! - the 27-byte opacity subgrid: every line books a ray, and an occlusion if occluded, on each
//!   sub-cell it crosses (integer workgroup atomics: exact and order-free), case-(a) hits mark
//!   their sub-cell (`atomicOr`), then the CPU's rule: unmarked or uncrossed cells 0, the
//!   others `unorm8(occluded / rays)`;
//! - optionally every line ([`Outputs::lines`]) as [`VoxelSamples`], so the CPU fits (VJK21,
//!   virtual mesh) can run on GPU-sampled data.
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
//! On lavapipe (a CPU implementation) a workgroup is expensive in itself: the bunny at 32³
//! (3253 voxels) took 0.7–0.9 s with 1 line per voxel and 1.7–2.2 s with 150, and the bench
//! (`precompute_averages_bunny64_150`, 2 cores shared with other builds) measured 6.8 s for
//! the bunny at 64³ against 0.40 s for the CPU reference (rayon, AVX2): CPU timings of the
//! GPU path, not GPU speed. A first version staged the triangles through workgroup memory
//! (two barriers per tile) and reduced the sums in a tree (six more): 1.4 s and 3.4 s at 32³,
//! 10.7 s at 64³ (against 0.64 s for the CPU in that run).

//! # Agreement with the CPU (the equivalence suite's bounds)
//! The random numbers are equal bit for bit; the lines (direction, entry, chord) and the hit
//! tests use the CPU's `f32` expressions in the CPU's order, but WGSL's division and `sqrt`
//! are only accurate to a few ULP and a shader compiler may fuse multiply-adds (naga does not
//! mark operations `NoContraction`), so a line's numbers may differ in the last bits. A line
//! grazing a triangle edge (within a few ULP), a triangle's plane at a voxel face, or two
//! triangles at the same distance may then change case or triangle: the suite measures how
//! many lines do (none on its scenes on llvmpipe) and bounds the fraction. The float sums are
//! `f32` in a tree order where the CPU sums in `f64` in line order (about 1e-7 relative), so a
//! record byte may round the other way: ±1 in each byte where every line agrees. Measured
//! on llvmpipe (the suite's scenes and 16 random soups: 1.1 M lines, 7.7 k voxels): every
//! line's direction, entry and chord equal the CPU's bit for bit, no line changes case, and
//! every record and subgrid byte equals the CPU's. Textures and alpha add one inexact step,
//! the bilinear lerp (a multiply-add may be fused: a few ULP): an alpha within those ULP of a
//! mask cutoff or of a blend number can flip a line, an albedo move by ULP; the UV itself is
//! the CPU's expression in the CPU's order.

use glam::{DVec3, Vec3};
use voxlod_cpu::appearance::AppearanceGrid;
use voxlod_cpu::appearance::eigen::symmetric_eigen;
use voxlod_cpu::appearance::precompute::PrecomputeOptions;
use voxlod_cpu::appearance::sampler::{SamplingContext, blend_key, dimension_base};
use voxlod_cpu::appearance::samples::{RaySample, SurfaceSample, VoxelSamples};
use voxlod_cpu::voxelize::Voxelization;
use voxlod_format::records::{AverageRecord, SpecularRecord};
use voxlod_format::{BrickMap, morton};
use voxlod_scene::{AlphaMode, Geometry, Scene};

use crate::ground_truth::gpu_shade_tris;
use crate::material::{GpuMaterial, gpu_materials};
use crate::raycast::entry;
use crate::{Context, Error, Result};

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

/// The kernel's parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPrecomputeParams {
    /// Voxels, lines per voxel, first voxel of the dispatch, flags (1: write the lines).
    pub counts: [u32; 4],
    /// First random dimension (`8·seed`), voxels in the dispatch, blend key
    /// (`blend_key(seed)`), 0.
    pub seed: [u32; 4],
}

/// One voxel (mirrors WGSL `Voxel`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuVoxel {
    /// First entry in the triangle buffer.
    pub first: u32,
    /// Entries (non-degenerate triangles of the voxel's list, in list order).
    pub count: u32,
    /// Random id `x + X·(y + Y·z)`.
    pub id: u32,
    /// Zero.
    pub pad: u32,
}

/// A triangle of one voxel in voxel-local coordinates (mirrors WGSL `Tri`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuLocalTri {
    /// Vertex 0; `w` = bits of the flat-axis mask (bits 0..3) and [`ALPHA_FLAG`].
    pub a: [f32; 4],
    /// Unit plane normal; `w` = offset.
    pub n: [f32; 4],
    /// Barycentric plane of vertex 1; `w` = its constant.
    pub bu: [f32; 4],
    /// Barycentric plane of vertex 2; `w` = its constant.
    pub bv: [f32; 4],
    /// World geometric normal `(b−a)×(c−a)`; `w` = bits of the triangle id.
    pub ng: [f32; 4],
}

/// Set in [`GpuLocalTri::a`]'s `w` bits when the triangle's material is not `Opaque` (its hits
/// pass the alpha test).
pub const ALPHA_FLAG: u32 = 8;

/// One voxel's results (mirrors WGSL `VoxelOut`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuVoxelOut {
    /// Occluded lines, case-(a) lines, marked sub-cells (bit mask), lines.
    pub counts: [u32; 4],
    /// Σ albedo; `w` = Σ specular level.
    pub albedo: [f32; 4],
    /// Σ shading normal; `w` = Σ level × exponent.
    pub normal: [f32; 4],
    /// Σ n nᵀ: xx, xy, xz, yy.
    pub scatter0: [f32; 4],
    /// Σ n nᵀ: yz, zz, 0, 0.
    pub scatter1: [f32; 4],
    /// The 27 subgrid bytes (index `x + 3y + 9z`), then zeros.
    pub subgrid: [u32; 8],
}

/// One line (mirrors WGSL `LineOut`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuLineOut {
    /// Direction; `w` = chord.
    pub dir: [f32; 4],
    /// Entry point; `w` = bits of the case (0 miss, 1 occluded without surface, 2 surface).
    pub entry: [f32; 4],
    /// Hit point; `w` = bits of the triangle id (`u32::MAX`: none).
    pub point: [f32; 4],
    /// Shading normal of a surface hit.
    pub normal: [f32; 4],
    /// Albedo of a surface hit (`Material::sample` at its UV).
    pub albedo: [f32; 4],
}

/// The case of one sampling line (the sampler's rules).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LineCase {
    /// No closest hit.
    Miss,
    /// A closest hit outside the voxel or back-facing: occludes, no surface sample.
    Occluded,
    /// An inside, front-facing closest hit: a surface sample (case (a)).
    Surface,
}

impl LineCase {
    /// The case of a CPU [`RaySample`].
    pub fn of(r: &RaySample) -> Self {
        match (r.occluded, r.surface.is_some()) {
            (_, true) => LineCase::Surface,
            (true, false) => LineCase::Occluded,
            (false, false) => LineCase::Miss,
        }
    }
}

/// Per-voxel counts and subgrid, in the voxelization's (Morton) voxel order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxelStats {
    /// Occluded lines (any closest hit).
    pub occluded: u32,
    /// Case-(a) lines (inside, front-facing).
    pub front: u32,
    /// The opacity subgrid, as [`voxlod_cpu::appearance::subgrid::build`] returns it.
    pub subgrid: [u8; 27],
}

/// What [`Precomputer::run`] returns besides the Averages grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// Also read back every line as [`VoxelSamples`] (80 bytes per line on the device).
    pub lines: bool,
}

/// The GPU precompute's results.
#[derive(Clone, Debug)]
pub struct GpuPrecompute {
    /// The Averages grid, what `precompute(ctx, opts, averages::fit)` returns on the CPU.
    pub averages: AppearanceGrid<AverageRecord>,
    /// Counts and subgrid of every voxel of the voxelization.
    pub voxels: Vec<VoxelStats>,
    /// Every voxel's lines, if [`Outputs::lines`] was asked for.
    pub samples: Option<Vec<VoxelSamples>>,
    /// The line cases behind `samples` with the hit triangle (`u32::MAX`: none), if asked for.
    pub cases: Option<Vec<Vec<(LineCase, u32)>>>,
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
            let layout = self.pipeline.get_bind_group_layout(0);
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
                let bind = ctx.guarded("binding precompute buffers", || {
                    ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("precompute"),
                        layout: &layout,
                        entries: &[
                            entry(0, &uniform),
                            entry(1, &voxel_buf),
                            entry(2, &tri_buf),
                            entry(3, &shade_buf),
                            entry(4, &mat_bufs.materials),
                            entry(5, &out_buf),
                            entry(6, &line_buf),
                            entry(7, &mat_bufs.textures),
                            entry(8, &mat_bufs.texels),
                        ],
                    })
                })?;
                let mut encoder = ctx.device().create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_pipeline(&self.pipeline);
                    pass.set_bind_group(0, &bind, &[]);
                    pass.dispatch_workgroups(x, y, 1);
                }
                ctx.submit("sampling voxels", encoder)?;
                first += count;
            }
            out_raw = ctx.read(&out_buf, out_bytes)?;
            if outputs.lines {
                line_raw = ctx.read(&line_buf, line_bytes)?;
            }
        }
        let outs: Vec<GpuVoxelOut> = bytemuck::pod_collect_to_vec(&out_raw);
        let specular = sampling.has_specular();
        let mut entries = Vec::new();
        let mut side = Vec::new();
        let mut stats = Vec::with_capacity(n);
        for (i, o) in outs.iter().enumerate() {
            let bytes: &[u8] = bytemuck::cast_slice(&o.subgrid);
            stats.push(VoxelStats {
                occluded: o.counts[0],
                front: o.counts[1],
                subgrid: bytes[..27].try_into().expect("27 bytes"),
            });
            if let Some(record) = average_record(o) {
                entries.push((morton::encode(sampling.coord(i)), record));
                if specular {
                    side.push(specular_record(o));
                }
            }
        }
        let grid = *sampling.grid();
        let records = BrickMap::from_morton_sorted(grid.dims, entries)
            .map_err(|e| Error::Cpu(voxlod_cpu::Error::Format(e)))?;
        let averages = AppearanceGrid { grid, records, specular: specular.then_some(side) };
        let (samples, cases) = if outputs.lines {
            let lines: Vec<GpuLineOut> = bytemuck::pod_collect_to_vec(&line_raw);
            let (s, c) = to_samples(&lines, rays as usize, &materials.materials, geometry);
            (Some(s), Some(c))
        } else {
            (None, None)
        };
        Ok(GpuPrecompute { averages, voxels: stats, samples, cases })
    }
}

/// The kernel's voxels and their local triangles, set up as the CPU sampler's
/// `load_triangles` does (in `f64` from the grid's origin and voxel size, then rounded), with
/// [`ALPHA_FLAG`] on triangles of `scene`'s non-`Opaque` materials.
pub fn prepare(
    sampling: &SamplingContext,
    scene: &Scene,
    geometry: &Geometry,
) -> Result<(Vec<GpuVoxel>, Vec<GpuLocalTri>)> {
    let alpha: Vec<bool> =
        scene.materials.iter().map(|m| m.alpha_mode != AlphaMode::Opaque).collect();
    let vox = sampling.voxelization();
    let grid = sampling.grid();
    let inv = 1.0 / grid.voxel_size;
    let mut voxels = Vec::with_capacity(sampling.voxel_count());
    let mut tris = Vec::new();
    for i in 0..sampling.voxel_count() {
        let min = grid.voxel_min(sampling.coord(i));
        let local = |p: Vec3| (p.as_dvec3() - min) * inv;
        let first = tris.len();
        for &t in vox.triangles_of(i) {
            let [a, b, c] = geometry.triangle(t as usize);
            let (la, lb, lc) = (local(a), local(b), local(c));
            let (e1, e2) = (lb - la, lc - la);
            let big_n = e1.cross(e2);
            let area2 = big_n.length_squared();
            if area2.is_nan() || area2 <= 0.0 {
                continue; // degenerate: never hit
            }
            let bu = e2.cross(big_n) / area2;
            let bv = big_n.cross(e1) / area2;
            let n = big_n / area2.sqrt();
            let (fa, fb, fc) = (la.as_vec3(), lb.as_vec3(), lc.as_vec3());
            let mut flat =
                (0..3).filter(|&j| fa[j] == fb[j] && fa[j] == fc[j]).fold(0u32, |m, j| m | 1 << j);
            // Indices checked by SamplingContext::new.
            if alpha[geometry.materials[t as usize] as usize] {
                flat |= ALPHA_FLAG;
            }
            let w = |v: DVec3, w: f32| v.as_vec3().extend(w).to_array();
            tris.push(GpuLocalTri {
                a: fa.extend(f32::from_bits(flat)).to_array(),
                n: w(n, n.dot(la) as f32),
                bu: w(bu, -bu.dot(la) as f32),
                bv: w(bv, -bv.dot(la) as f32),
                ng: (b - a).cross(c - a).extend(f32::from_bits(t)).to_array(),
            });
        }
        let count = tris.len() - first;
        if first > u32::MAX as usize || count > u32::MAX as usize {
            return Err(Error::TooLarge {
                what: "(voxel, triangle) pairs (32-bit indices)",
                requested: tris.len() as u64,
                limit: u32::MAX as u64,
            });
        }
        voxels.push(GpuVoxel {
            first: first as u32,
            count: count as u32,
            id: sampling.voxel_id(i),
            pad: 0,
        });
    }
    Ok((voxels, tris))
}

/// The Averages record of one voxel's sums, as `averages::fit` computes it from the lines.
fn average_record(o: &GpuVoxelOut) -> Option<AverageRecord> {
    let [occluded, count, _, rays] = o.counts;
    if count == 0 || rays == 0 {
        return None;
    }
    let v = |a: &[f32; 4]| Vec3::new(a[0], a[1], a[2]).as_dvec3();
    let (albedo, normal) = (v(&o.albedo), v(&o.normal));
    let [xx, xy, xz, yy] = o.scatter0.map(f64::from);
    let [yz, zz, _, _] = o.scatter1.map(f64::from);
    let n = if normal.length() >= 1e-3 * count as f64 {
        normal.normalize()
    } else {
        symmetric_eigen([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]).1[0]
    };
    let opacity = occluded as f32 / rays as f32;
    Some(AverageRecord::new((albedo / count as f64).as_vec3(), n.as_vec3(), opacity))
}

/// The specular side record of one voxel's sums, as the CPU driver's `specular_record`.
fn specular_record(o: &GpuVoxelOut) -> SpecularRecord {
    let (count, level, weighted) = (o.counts[1], o.albedo[3] as f64, o.normal[3] as f64);
    if count == 0 || level <= 0.0 {
        return SpecularRecord::new(0.0, 0.0);
    }
    SpecularRecord::new((level / count as f64) as f32, (weighted / level) as f32)
}

/// The GPU's lines as [`VoxelSamples`] (the kernel's textured albedo; level and exponent from
/// the hit triangle's material, which `Material::sample` does not vary with the UV) and their
/// cases.
#[allow(clippy::type_complexity)]
fn to_samples(
    lines: &[GpuLineOut],
    rays: usize,
    materials: &[GpuMaterial],
    geometry: &Geometry,
) -> (Vec<VoxelSamples>, Vec<Vec<(LineCase, u32)>>) {
    let v3 = |a: &[f32; 4]| Vec3::new(a[0], a[1], a[2]);
    lines
        .chunks(rays.max(1))
        .map(|chunk| {
            let mut samples = VoxelSamples { rays: Vec::with_capacity(chunk.len()) };
            let mut cases = Vec::with_capacity(chunk.len());
            for l in chunk {
                let case = match l.entry[3].to_bits() {
                    0 => LineCase::Miss,
                    1 => LineCase::Occluded,
                    _ => LineCase::Surface,
                };
                let triangle = l.point[3].to_bits();
                let surface = (case == LineCase::Surface).then(|| {
                    let m = &materials[geometry.materials[triangle as usize] as usize];
                    SurfaceSample {
                        point: v3(&l.point),
                        normal: v3(&l.normal),
                        albedo: v3(&l.albedo),
                        specular: (m.specular[0] + m.specular[1] + m.specular[2]) * (1.0 / 3.0),
                        shininess: m.specular[3],
                    }
                });
                samples.rays.push(RaySample {
                    dir: v3(&l.dir),
                    entry: v3(&l.entry),
                    chord: l.dir[3],
                    occluded: case != LineCase::Miss,
                    surface,
                });
                cases.push((case, triangle));
            }
            (samples, cases)
        })
        .unzip()
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn precompute_types_mirror_their_wgsl() {
        type P = GpuPrecomputeParams;
        assert_mirrors(
            WGSL,
            "Params",
            size_of::<P>(),
            &[("counts", offset_of!(P, counts)), ("seed", offset_of!(P, seed))],
        );
        assert_mirrors(
            WGSL,
            "Voxel",
            size_of::<GpuVoxel>(),
            &[
                ("first", offset_of!(GpuVoxel, first)),
                ("count", offset_of!(GpuVoxel, count)),
                ("id", offset_of!(GpuVoxel, id)),
                ("pad", offset_of!(GpuVoxel, pad)),
            ],
        );
        type T = GpuLocalTri;
        assert_mirrors(
            WGSL,
            "Tri",
            size_of::<T>(),
            &[
                ("a", offset_of!(T, a)),
                ("n", offset_of!(T, n)),
                ("bu", offset_of!(T, bu)),
                ("bv", offset_of!(T, bv)),
                ("ng", offset_of!(T, ng)),
            ],
        );
        type O = GpuVoxelOut;
        assert_mirrors(
            WGSL,
            "VoxelOut",
            size_of::<O>(),
            &[
                ("counts", offset_of!(O, counts)),
                ("albedo", offset_of!(O, albedo)),
                ("normal", offset_of!(O, normal)),
                ("scatter0", offset_of!(O, scatter0)),
                ("scatter1", offset_of!(O, scatter1)),
                ("subgrid", offset_of!(O, subgrid)),
            ],
        );
        type L = GpuLineOut;
        assert_mirrors(
            WGSL,
            "LineOut",
            size_of::<L>(),
            &[
                ("dir", offset_of!(L, dir)),
                ("entry", offset_of!(L, entry)),
                ("point", offset_of!(L, point)),
                ("normal", offset_of!(L, normal)),
                ("albedo", offset_of!(L, albedo)),
            ],
        );
        use crate::ground_truth::GpuShadeTri;
        assert_mirrors(
            WGSL,
            "ShadeTri",
            size_of::<GpuShadeTri>(),
            &[
                ("p0", offset_of!(GpuShadeTri, p0)),
                ("p1", offset_of!(GpuShadeTri, p1)),
                ("p2", offset_of!(GpuShadeTri, p2)),
                ("n0", offset_of!(GpuShadeTri, n0)),
                ("n1", offset_of!(GpuShadeTri, n1)),
                ("n2", offset_of!(GpuShadeTri, n2)),
                ("uv01", offset_of!(GpuShadeTri, uv01)),
                ("uv2", offset_of!(GpuShadeTri, uv2)),
            ],
        );
    }

    /// `prepare` flags the triangles of non-`Opaque` materials (their hits pass the alpha
    /// test in the kernel) next to the flat-axis bits, and no others.
    #[test]
    fn prepare_flags_the_triangles_whose_alpha_filters_hits() {
        use voxlod_cpu::voxelize::{Options, voxelize};
        use voxlod_format::GridSpec;
        use voxlod_scene::{Material, Mesh};
        let tri = |z: f32, material| Mesh {
            name: "t".into(),
            positions: vec![Vec3::new(0.1, 0.1, z), Vec3::new(0.9, 0.1, z), Vec3::new(0.1, 0.9, z)],
            normals: vec![Vec3::Z; 3],
            uvs: vec![glam::Vec2::ZERO; 3],
            indices: vec![[0, 1, 2]],
            material,
            ..Default::default()
        };
        let blend = Material { alpha_mode: AlphaMode::Blend, ..Default::default() };
        let scene = Scene {
            meshes: vec![tri(0.3, 0), tri(0.6, 1)],
            materials: vec![Material::default(), blend],
            ..Default::default()
        };
        let geometry = scene.geometry();
        let grid = GridSpec::new(DVec3::ZERO, 1.0, glam::UVec3::ONE).unwrap();
        let vox = voxelize(&geometry, &grid, &Options::default()).unwrap();
        let sampling = SamplingContext::new(&scene, &geometry, &vox).unwrap();
        let (_, tris) = prepare(&sampling, &scene, &geometry).unwrap();
        let flags: Vec<u32> = tris.iter().map(|t| t.a[3].to_bits()).collect();
        // Both lie in a z plane (flat-axis bit 2); only the blended one is alpha-filtered.
        assert_eq!(flags, [4, 4 | ALPHA_FLAG]);
    }

    /// The host fit from sums is the CPU's fit from lines: mean albedo, normalized sum, the
    /// principal axis when the normals cancel, `occluded / rays`.
    #[test]
    fn records_from_sums_follow_the_averages_rules() {
        let mut o = GpuVoxelOut { counts: [3, 2, 1, 4], ..Default::default() };
        o.albedo = [0.4, 0.6, 0.8, 0.0];
        o.normal = [0.0, 0.0, 2.0, 0.0];
        o.scatter1 = [0.0, 2.0, 0.0, 0.0];
        let r = average_record(&o).unwrap();
        assert_eq!(r, AverageRecord::new(Vec3::new(0.2, 0.3, 0.4), Vec3::Z, 0.75));
        // n and −n: the sum cancels, the principal axis of Σ n nᵀ (canonical sign) remains.
        o.normal = [0.0, 0.0, 0.0, 0.0];
        o.scatter0 = [0.0, 0.0, 0.0, 2.0];
        o.scatter1 = [0.0, 0.0, 0.0, 0.0];
        assert_eq!(average_record(&o).unwrap().normal(), Vec3::Y);
        o.counts[1] = 0;
        assert_eq!(average_record(&o), None);
    }
}
