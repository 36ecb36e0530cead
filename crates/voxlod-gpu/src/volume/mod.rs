//! Sparse procedural volumes with metavoxels on the GPU: the four stages of
//! [`voxlod_cpu::volume`] (McNabb 2015, "Sparse Procedural Volume Rendering", GPU Pro 6) as
//! wgpu compute kernels, each checked against its CPU reference by the equivalence suite.
//!
//! | stage | kernel (workgroup) | one invocation per | agreement with the CPU |
//! |---|---|---|---|
//! | [`VolumeKernels::bin`] (Listing 5.1) | `binning.wgsl` (64) | (particle, candidate metavoxel) | exact |
//! | [`VolumeKernels::fill`] (§5.5.2) | `fill.wgsl` (64) | voxel of a kept metavoxel | bounds below |
//! | [`VolumeKernels::propagate`] (Listing 5.2) | `propagate.wgsl` (64) | voxel column | bounds below |
//! | [`VolumeKernels::render`] (Listing 5.3) | `march.wgsl` (8×8) | pixel | bounds below |
//! | [`VolumeKernels::render`], exact model | `march_exact.wgsl` (8×8) | pixel | bounds below |
//!
//! [`VolumeKernels::build`] runs binning, culling, fill and propagation (the CPU's
//! [`voxlod_cpu::volume::build`]) and [`VolumeKernels::frame`] the whole frame (build, then the
//! march). The particles are uploaded as [`DisplacedSphere`], the `#[repr(C)]` type of
//! voxlod-scene, whose WGSL mirror (`Sphere` in `common.wgsl`) a layout test checks.
//!
//! # Binning: exact
//! The host converts the particles to voxel coordinates with the CPU's own
//! [`binning::prepare`] and lists each particle's candidate metavoxels with the CPU's per-axis
//! range arithmetic (the same Rust, so the same bits). The kernel evaluates the reference's
//! predicate (squared distance from the centre to the metavoxel's box against the squared
//! outer radius) per candidate. A real GPU may contract `a·b + c` into a fused multiply-add,
//! which can flip a comparison that is within rounding of a tie, so the kernel reports those
//! (`|d² − r²| ≤ 2⁻¹⁶ · max(d², r²)`, far more than the few ulps contraction changes) as
//! undecided and the host decides them with [`binning::sphere_overlaps_box`] itself: the bins
//! are **exactly** the CPU's on any device. The result is written per candidate (no atomics),
//! compacted on the host, sorted by (metavoxel key, particle) and grouped: each bin lists its
//! particles ascending, as the CPU's do. Culling ([`binning::cull`], a few thousand boxes
//! against 5 planes) stays on the host.
//!
//! # Fill: same summation order, coverage within rounding
//! Each voxel walks its bin in particle order with the CPU's per-voxel arithmetic (the same
//! operations in the same order, `r_lo`, `r_hi` and the accept/reject radii computed on the
//! host by the same Rust), so the density of a voxel is **the same sum in the same order**:
//! bit-identical wherever both backends find the same particles covering the voxel. What can
//! differ is coverage at the displaced surface: WGSL's division has 2.5 ulp accuracy (the
//! cube-map face coordinates) and a device may fuse multiply-adds (the offset and `d²`), so `n`
//! may differ in its last bits and a voxel whose centre lies within that of the surface may
//! flip in or out. The equivalence row therefore bounds per-voxel differences (`1e-5` relative
//! on density and colour, for the colour modes that read `n` or `√d²`) and the fraction of
//! voxels beyond that bound (the surface flips).
//!
//! # Propagation and march: transcendental rounding
//! Propagation is the CPU's loop per column; the march is the CPU's sample positions, voxel
//! reads and blend order per pixel. Differences come from `exp` (WGSL: 3 + 2|x| ulp; Rust:
//! libm, < 1 ulp), the ray direction's normalization and division, and fused multiply-adds, and
//! then from the fill's flipped voxels; the rows state a per-value (per-pixel) bound and the
//! fraction allowed beyond it.
//!
//! # What a real GPU should see
//! Binning: one invocation per candidate, so a large particle spreads over many invocations;
//! the binary search over the per-particle prefix sum is coherent within a workgroup. Fill: a
//! workgroup is 64 consecutive voxels of one metavoxel (x fastest), all walking the same
//! particle list (uniform loop, broadcast loads, coalesced stores); divergence only where
//! some voxels need the cube map and others do not. Propagation: 64 consecutive columns of one
//! metavoxel column, each step down reading and writing a contiguous row of voxels. March:
//! 8×8 pixel tiles walking the same metavoxel list; rays that miss a metavoxel skip it after
//! one slab test (every pixel tests every non-empty kept metavoxel, where the CPU first clips
//! each to its screen rectangle: with thousands of kept metavoxels a real GPU would want
//! per-tile lists). The covered-voxel box uses global atomics (six per covered voxel); a
//! workgroup reduction first would cut that traffic on a real GPU.
//!
//! # Limits and errors
//! Input is checked by the CPU's own checks ([`voxlod_cpu::volume::validate_build`]: particles and
//! light terms; [`voxlod_cpu::volume::check_budget`]: the `max_bytes` budget; the march's image
//! size, step, camera and depth buffer), so the errors are the very same. Buffers over the device's
//! limits are [`Error::BufferTooLarge`](crate::Error::BufferTooLarge) with the numbers; over `2³²`
//! voxels or candidates [`Error::TooLarge`](crate::Error::TooLarge). A volume lit with
//! [`Attenuation::Exact`](voxlod_cpu::volume::Attenuation::Exact) is marched by the reference march
//! (`march_exact.wgsl`: every voxel crossed with its exact length, the CPU's `render_exact`), as
//! the CPU's `render` does. Binning's compaction and sort run on the host (a GPU prefix-sum
//! compaction and segmented sort would replace them on a real GPU).
//!
//! # Layout of the module
//! `params` holds the `#[repr(C)]` mirrors of the kernels' WGSL structs; `binning`, `fill`,
//! `propagate` and `march` each prepare, dispatch and read back one stage (as voxlod-cpu's
//! `volume` module splits them); `gpu_volume` holds the device-side volume, its upload from a
//! CPU-built [`Volume`](voxlod_cpu::volume::Volume) and its readback.
//!
//! [`binning::prepare`]: voxlod_cpu::volume::binning::prepare
//! [`binning::sphere_overlaps_box`]: voxlod_cpu::volume::binning::sphere_overlaps_box
//! [`binning::cull`]: voxlod_cpu::volume::binning::cull

use std::time::{Duration, Instant};

use voxlod_cpu::volume::binning::cull;
use voxlod_cpu::volume::{
    BuildSettings, BuildStats, MarchOptions, StageTimes, VolumeSpec, check_budget, validate_build,
};
use voxlod_scene::camera::CameraFrame;
use voxlod_scene::particles::{DisplacedSphere, DisplacementMap};
use voxlod_scene::{Camera, Image};

use crate::raycast::GpuBvh;
use crate::{Context, Result};

mod binning;
mod fill;
mod gpu_volume;
mod march;
mod params;
mod propagate;

pub use gpu_volume::GpuVolume;
pub use march::sort_order;
pub use params::{
    GpuBinParams, GpuCandidate, GpuFillParams, GpuFrame, GpuMarchEntry, GpuMarchParams, GpuPrep,
    GpuPropagateParams, GpuSlot,
};

/// WGSL of the binning kernel.
pub const BINNING_WGSL: &str = include_str!("binning.wgsl");
/// WGSL shared by the fill kernel: the particle record, the frame, the cube-map look-up.
pub const COMMON_WGSL: &str = include_str!("common.wgsl");
/// WGSL of the fill kernel (after [`COMMON_WGSL`]).
pub const FILL_WGSL: &str = concat!(include_str!("common.wgsl"), include_str!("fill.wgsl"));
/// WGSL of the propagation kernel.
pub const PROPAGATE_WGSL: &str = include_str!("propagate.wgsl");
/// WGSL of the eye march kernel.
pub const MARCH_WGSL: &str = concat!(include_str!("march_common.wgsl"), include_str!("march.wgsl"));
/// WGSL of the exact-attenuation reference march kernel.
pub const MARCH_EXACT_WGSL: &str =
    concat!(include_str!("march_common.wgsl"), include_str!("march_exact.wgsl"));

/// Invocations per workgroup of the binning, fill and propagation kernels.
pub const WORKGROUP: u64 = 64;

/// The four volume kernels, compiled for one [`Context`].
pub struct VolumeKernels<'a> {
    ctx: &'a Context,
    binning: wgpu::ComputePipeline,
    fill: wgpu::ComputePipeline,
    propagate: wgpu::ComputePipeline,
    march: wgpu::ComputePipeline,
    march_exact: wgpu::ComputePipeline,
}

impl<'a> VolumeKernels<'a> {
    /// Compiles the kernels.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        Ok(Self {
            ctx,
            binning: ctx.pipeline("volume binning", BINNING_WGSL)?,
            fill: ctx.pipeline("volume fill", FILL_WGSL)?,
            propagate: ctx.pipeline("volume propagation", PROPAGATE_WGSL)?,
            march: ctx.pipeline("volume march", MARCH_WGSL)?,
            march_exact: ctx.pipeline("volume exact march", MARCH_EXACT_WGSL)?,
        })
    }

    /// The context.
    pub fn context(&self) -> &'a Context {
        self.ctx
    }

    /// Bins, culls, fills and lights `spheres` on the GPU: the CPU's
    /// [`voxlod_cpu::volume::build`] (same checks, same errors; `view` enables culling,
    /// `blocker` casts the mesh's shadow).
    pub fn build(
        &self,
        spheres: &[DisplacedSphere],
        map: &DisplacementMap,
        spec: &VolumeSpec,
        settings: &BuildSettings,
        view: Option<&CameraFrame>,
        blocker: Option<&GpuBvh>,
    ) -> Result<GpuVolume> {
        validate_build(spheres, settings)?;
        let mut times = StageTimes::default();
        let t = Instant::now();
        let binning = self.bin(spheres, spec)?;
        times.binning = t.elapsed();
        let t = Instant::now();
        let occupied = binning.bins.len();
        let bin_entries = binning.bins.iter().map(|b| b.particles.len()).sum();
        let bins = match view {
            Some(frame) => cull(binning.bins, spec, frame),
            None => binning.bins,
        };
        times.culling = t.elapsed();
        check_budget(bins.len(), spec, settings)?;
        let t = Instant::now();
        let mut volume = self.fill(spheres, &binning.prepared, map, spec, &bins)?;
        times.fill = t.elapsed();
        let t = Instant::now();
        self.propagate(&mut volume, settings, blocker)?;
        times.propagation = t.elapsed();
        volume.times = times;
        volume.stats =
            BuildStats { particles: spheres.len(), bin_entries, occupied, kept: bins.len() };
        Ok(volume)
    }

    /// The whole frame on the GPU: [`VolumeKernels::build`] with the camera's view for
    /// culling, then [`VolumeKernels::render`]. Returns the image, the volume and the march's
    /// wall-clock time.
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &self,
        spheres: &[DisplacedSphere],
        map: &DisplacementMap,
        spec: &VolumeSpec,
        settings: &BuildSettings,
        blocker: Option<&GpuBvh>,
        camera: &Camera,
        options: &MarchOptions,
        depth: Option<&[f32]>,
    ) -> Result<(Image, GpuVolume, Duration)> {
        let view = march::check_march(camera, options, depth)?;
        let volume = self.build(spheres, map, spec, settings, Some(&view), blocker)?;
        let t = Instant::now();
        let image = self.render(&volume, camera, options, depth)?;
        Ok((image, volume, t.elapsed()))
    }
}
