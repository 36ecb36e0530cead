//! Sparse procedural volumes with metavoxels on the GPU: the four stages of
//! [`voxlod_cpu::volume`] (seed 001, McNabb, "Sparse Procedural Volume Rendering") as wgpu
//! compute kernels, each checked against its CPU reference by the equivalence suite
//! (`tests/equivalence/volume.rs`).
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
//! Input is checked by the CPU's own checks ([`voxlod_cpu::volume::validate_build`]: particles
//! and light terms; [`voxlod_cpu::volume::check_budget`]: the `max_bytes` budget; the march's
//! image size, step, camera and depth buffer), so the errors are the very same. Buffers over the device's limits are
//! [`Error::BufferTooLarge`] with the numbers; over `2³²` voxels or candidates
//! [`Error::TooLarge`]. A volume lit with [`Attenuation::Exact`] is marched by the reference
//! march (`march_exact.wgsl`: every voxel crossed with its exact length, the CPU's
//! `render_exact`), as the CPU's `render` does. Binning's compaction and sort run on the host (a
//! GPU prefix-sum compaction and segmented sort would replace them on a real GPU).

use std::time::{Duration, Instant};

use glam::{Vec3, Vec4};
use voxlod_cpu::render::check_image_size;
use voxlod_cpu::volume::binning::{self, Bin, Binning, Prepared};
use voxlod_cpu::volume::{
    Attenuation, BuildSettings, BuildStats, LightSpace, MarchOptions, Metavoxel, StageTimes,
    Volume, VolumeSpec, check_budget, validate_build,
};
use voxlod_scene::camera::CameraFrame;
use voxlod_scene::particles::{DisplacedSphere, DisplacementMap, FLAG_EMISSIVE};
use voxlod_scene::{Camera, Image};

use crate::raycast::{GpuBvh, GpuRay, RayCaster};
use crate::{Context, Error, Result};

/// WGSL of the binning kernel.
pub const BINNING_WGSL: &str = include_str!("binning.wgsl");
/// WGSL shared by the fill kernel: the particle record, the frame, the cube-map look-up.
pub const COMMON_WGSL: &str = include_str!("common.wgsl");
/// WGSL of the fill kernel (after [`COMMON_WGSL`]).
pub const FILL_WGSL: &str = concat!(include_str!("common.wgsl"), include_str!("fill.wgsl"));
/// WGSL of the propagation kernel.
pub const PROPAGATE_WGSL: &str = include_str!("propagate.wgsl");
/// WGSL of the eye march kernel.
pub const MARCH_WGSL: &str = include_str!("march.wgsl");
/// WGSL of the exact-attenuation reference march kernel.
pub const MARCH_EXACT_WGSL: &str = include_str!("march_exact.wgsl");

/// Invocations per workgroup of the binning, fill and propagation kernels.
pub const WORKGROUP: u64 = 64;

/// The light-space frame as the kernels read it (mirrors WGSL `Frame`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuFrame {
    /// Origin; `w` the voxel size.
    pub origin: [f32; 4],
    /// First horizontal axis.
    pub u: [f32; 4],
    /// Second horizontal axis.
    pub v: [f32; 4],
    /// Direction of propagation.
    pub w: [f32; 4],
}

impl GpuFrame {
    /// The frame of `f`.
    pub fn new(f: &LightSpace) -> Self {
        Self {
            origin: f.origin.extend(f.voxel_size).to_array(),
            u: f.u.extend(0.0).to_array(),
            v: f.v.extend(0.0).to_array(),
            w: f.w.extend(0.0).to_array(),
        }
    }
}

/// One particle with candidates, as the binning kernel reads it (mirrors WGSL `Candidate`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuCandidate {
    /// Centre in voxel coordinates; `w` the outer radius in voxels.
    pub sphere: [f32; 4],
    /// First metavoxel of the range; `w` the first candidate's index.
    pub lo: [u32; 4],
    /// Last metavoxel of the range (inclusive); `w` unused.
    pub hi: [u32; 4],
}

/// Parameters of the binning kernel (mirrors WGSL `Params` of `binning.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuBinParams {
    /// Candidates, particles with candidates, `M`, unused.
    pub counts: [u32; 4],
}

/// Per particle, what the fill reads besides the sphere (mirrors WGSL `Prep`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPrep {
    /// Centre in voxel coordinates; `w` the inner radius in voxels.
    pub center: [f32; 4],
    /// Amplitude in voxels, accept², reject², unused.
    pub radii: [f32; 4],
}

/// One kept metavoxel for the fill (mirrors WGSL `Slot`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuSlot {
    /// Metavoxel coordinate; `w` its first entry in the particle lists.
    pub coord: [u32; 4],
    /// `x` its number of particles.
    pub range: [u32; 4],
}

/// Parameters of the fill kernel (mirrors WGSL `Params` of `fill.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuFillParams {
    /// `M`, kept metavoxels, cube-map face size, 1 if some particle is emissive.
    pub dims: [u32; 4],
    /// The frame.
    pub frame: GpuFrame,
}

/// Parameters of the propagation kernel (mirrors WGSL `Params` of `propagate.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuPropagateParams {
    /// `M`, columns, attenuation (0 chapter, 1 Beer–Lambert, 2 exact), emission live.
    pub dims: [u32; 4],
    /// `E/π`; `w` the voxel size.
    pub direct: [f32; 4],
    /// Ambient irradiance.
    pub ambient: [f32; 4],
}

/// Parameters of the march kernel (mirrors WGSL `Params` of `march.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuMarchParams {
    /// Camera eye.
    pub eye: [f32; 4],
    /// Camera forward.
    pub forward: [f32; 4],
    /// Camera right (scaled).
    pub right: [f32; 4],
    /// Camera up (scaled).
    pub up: [f32; 4],
    /// Light-space frame.
    pub frame: GpuFrame,
    /// Eye in voxel coordinates; `w` the step in world units.
    pub eye_voxel: [f32; 4],
    /// Width, height, entries, `M`.
    pub dims: [u32; 4],
    /// Attenuation (0 chapter, 1 Beer–Lambert), 1 if a depth buffer is bound.
    pub mode: [u32; 4],
}

/// One metavoxel of the march's order (mirrors WGSL `Entry`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuMarchEntry {
    /// Metavoxel box corner (voxel coordinates).
    pub base: [f32; 4],
    /// Marched box low corner.
    pub lo: [f32; 4],
    /// Marched box high corner.
    pub hi: [f32; 4],
    /// Slot, 1 for over blending.
    pub flags: [u32; 4],
}

/// A volume on the device: kept metavoxels (slots, in key order), their voxels (`M³` per
/// slot, RGB + extinction; albedo before propagation, lit radiance after), light at the top of
/// each voxel column and the occupied boxes.
pub struct GpuVolume {
    /// The shape.
    pub spec: VolumeSpec,
    /// The attenuation it was lit with (`None`: filled, not lit yet).
    pub attenuation: Option<Attenuation>,
    /// Metavoxel coordinate per slot.
    pub coords: Vec<[u32; 3]>,
    /// Particles binned into each slot.
    pub particles: Vec<usize>,
    /// Box of the voxels the fill wrote per slot (as [`Metavoxel::occupied`]).
    pub occupied: Vec<[[u32; 3]; 2]>,
    /// Whether an emission buffer is live (some kept bin holds an emissive particle).
    pub emissive: bool,
    /// Counts (as the CPU's).
    pub stats: BuildStats,
    /// Wall-clock per stage, host side (submission and readback included).
    pub times: StageTimes,
    voxels: wgpu::Buffer,
    emission: wgpu::Buffer,
    boxes: wgpu::Buffer,
    light_top: Option<wgpu::Buffer>,
}

impl GpuVolume {
    /// Device bytes of the volume: voxels, emission, light at the column tops, boxes.
    pub fn bytes(&self) -> u64 {
        self.voxels.size()
            + self.emission.size()
            + self.boxes.size()
            + self.light_top.as_ref().map_or(0, |b| b.size())
    }
}

impl std::fmt::Debug for GpuVolume {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuVolume")
            .field("spec", &self.spec)
            .field("attenuation", &self.attenuation)
            .field("kept", &self.coords.len())
            .field("stats", &self.stats)
            .finish()
    }
}

/// Metavoxel index range `[a, b]` on one axis covered by `[x − r, x + r]` (the CPU
/// reference's arithmetic, `binning::axis_range`), or `None` when it misses `[0, K)`.
fn axis_range(x: f32, r: f32, m: u32, k: u32) -> Option<(u32, u32)> {
    let lo = ((x - r) / m as f32).floor();
    let hi = ((x + r) / m as f32).floor();
    if !(hi >= 0.0 && lo < k as f32) {
        return None;
    }
    Some((lo.max(0.0) as u32, hi.min((k - 1) as f32) as u32))
}

/// The box of metavoxel `c` in voxel coordinates.
fn metavoxel_box(c: [u32; 3], m: u32) -> (Vec3, Vec3) {
    let lo = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * m as f32;
    (lo, lo + Vec3::splat(m as f32))
}

/// Sorted `(key, particle)` pairs into bins (the CPU's grouping).
fn group(spec: &VolumeSpec, pairs: &[(u32, u32)]) -> Vec<Bin> {
    let k = spec.metavoxels;
    pairs
        .chunk_by(|a, b| a.0 == b.0)
        .map(|run| {
            let key = run[0].0;
            Bin {
                coord: [key / (k * k), key / k % k, key % k],
                particles: run.iter().map(|p| p.1).collect(),
            }
        })
        .collect()
}

/// The march's metavoxel order for a camera at `eye` (the CPU's `march::sort_order` on the
/// slots' coordinates): slot indices and whether each is over-blended.
pub fn sort_order(spec: &VolumeSpec, coords: &[[u32; 3]], eye: Vec3) -> Vec<(usize, bool)> {
    let q = spec.frame.to_voxel(eye) / spec.metavoxel_edge as f32;
    let e = q.floor().clamp(Vec3::splat(-1e6), Vec3::splat(1e6)).as_ivec3().as_i64vec3();
    let dist = |c: [u32; 3]| {
        (c[0] as i64 - e.x).abs() + (c[1] as i64 - e.y).abs() + (c[2] as i64 - e.z).abs()
    };
    let mut over = Vec::new();
    let mut under = Vec::new();
    for (i, &c) in coords.iter().enumerate() {
        let d = dist(c);
        if c[2] as i64 <= e.z { over.push((d, i)) } else { under.push((d, i)) }
    }
    over.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    under.sort();
    over.into_iter()
        .map(|(_, i)| (i, true))
        .chain(under.into_iter().map(|(_, i)| (i, false)))
        .collect()
}

/// The march's checks of its input, with the CPU reference's errors.
fn check_march(
    camera: &Camera,
    options: &MarchOptions,
    depth: Option<&[f32]>,
) -> Result<CameraFrame> {
    check_image_size(options.width, options.height)?;
    if !(options.step.is_finite() && options.step > 0.0) {
        return Err(voxlod_cpu::Error::InvalidParameter {
            name: "march step",
            value: options.step.to_string(),
            reason: "must be finite and > 0 voxels".into(),
        }
        .into());
    }
    camera.validate().map_err(voxlod_cpu::Error::from)?;
    let pixels = options.width as usize * options.height as usize;
    if let Some(d) = depth
        && d.len() != pixels
    {
        return Err(voxlod_cpu::Error::InvalidParameter {
            name: "depth buffer",
            value: format!("{} entries", d.len()),
            reason: format!("must have one per pixel ({pixels})"),
        }
        .into());
    }
    Ok(camera.frame(options.width, options.height))
}

/// `v`, or one zeroed element when it is empty (a binding must hold one element of its
/// array; the kernels read none of it then).
fn at_least_one<T: bytemuck::Zeroable>(mut v: Vec<T>) -> Vec<T> {
    if v.is_empty() {
        v.push(T::zeroed());
    }
    v
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }
}

fn attenuation_id(a: Attenuation) -> u32 {
    match a {
        Attenuation::Chapter => 0,
        Attenuation::BeerLambert => 1,
        Attenuation::Exact => 2,
    }
}

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

    fn dispatch(
        &self,
        during: &'static str,
        pipeline: &wgpu::ComputePipeline,
        buffers: &[&wgpu::Buffer],
        (x, y): (u32, u32),
    ) -> Result<()> {
        let ctx = self.ctx;
        let layout = pipeline.get_bind_group_layout(0);
        let entries: Vec<_> = buffers.iter().enumerate().map(|(i, b)| entry(i as u32, b)).collect();
        let bind = ctx.guarded("binding volume buffers", || {
            ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(during),
                layout: &layout,
                entries: &entries,
            })
        })?;
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        ctx.submit(during, encoder)
    }

    /// Binning (Listing 5.1) on the GPU: the CPU's [`binning::bin`], exactly (module docs).
    pub fn bin(&self, spheres: &[DisplacedSphere], spec: &VolumeSpec) -> Result<Binning> {
        let ctx = self.ctx;
        if spheres.len() as u64 > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "particles (indexed in 32 bits)",
                requested: spheres.len() as u64,
                limit: u32::MAX as u64,
            });
        }
        let prepared = binning::prepare(spheres, spec);
        let (m, k) = (spec.metavoxel_edge, spec.metavoxels);
        let mut records = Vec::new();
        let mut owners = Vec::new();
        let mut total = 0u64;
        for (i, p) in prepared.iter().enumerate() {
            let ranges = (
                axis_range(p.center.x, p.outer, m, k),
                axis_range(p.center.y, p.outer, m, k),
                axis_range(p.center.z, p.outer, m, k),
            );
            let (Some(x), Some(y), Some(z)) = ranges else { continue };
            let count = (x.1 - x.0 + 1) as u64 * (y.1 - y.0 + 1) as u64 * (z.1 - z.0 + 1) as u64;
            if total + count > u32::MAX as u64 {
                return Err(Error::TooLarge {
                    what: "binning candidates (particle, metavoxel)",
                    requested: total + count,
                    limit: u32::MAX as u64,
                });
            }
            records.push(GpuCandidate {
                sphere: p.center.extend(p.outer).to_array(),
                lo: [x.0, y.0, z.0, total as u32],
                hi: [x.1, y.1, z.1, 0],
            });
            owners.push(i as u32);
            total += count;
        }
        if total == 0 {
            return Ok(Binning { prepared, bins: Vec::new() });
        }
        let result_bytes = total * 4;
        ctx.check_storage("binning results", result_bytes)?;
        let params = GpuBinParams { counts: [total as u32, records.len() as u32, m, 0] };
        let uniform = ctx.uniform("binning params", bytemuck::bytes_of(&params))?;
        let cands = ctx.storage_init("binning candidates", bytemuck::cast_slice(&records))?;
        let results = ctx.storage_zeroed("binning results", result_bytes)?;
        let wg = ctx.dispatch_size("binning workgroups", total.div_ceil(WORKGROUP))?;
        self.dispatch("binning", &self.binning, &[&uniform, &cands, &results], wg)?;
        let results: Vec<u32> = bytemuck::pod_collect_to_vec(&ctx.read(&results, result_bytes)?);
        // Compaction, in candidate order; the undecided ones by the reference predicate.
        let mut pairs = Vec::new();
        for (r, &owner) in records.iter().zip(&owners) {
            let n = [r.hi[0] - r.lo[0] + 1, r.hi[1] - r.lo[1] + 1, r.hi[2] - r.lo[2] + 1];
            let count = n[0] * n[1] * n[2];
            for local in 0..count {
                let c = [
                    r.lo[0] + local % n[0],
                    r.lo[1] + local / n[0] % n[1],
                    r.lo[2] + local / (n[0] * n[1]),
                ];
                let hit = match results[(r.lo[3] + local) as usize] {
                    1 => true,
                    2 => {
                        let p: &Prepared = &prepared[owner as usize];
                        let (lo, hi) = metavoxel_box(c, m);
                        binning::sphere_overlaps_box(p.center, p.outer, lo, hi)
                    }
                    _ => false,
                };
                if hit {
                    pairs.push((spec.key(c), owner));
                }
            }
        }
        pairs.sort_unstable();
        Ok(Binning { bins: group(spec, &pairs), prepared })
    }

    /// Fill (§5.5.2) of the metavoxels of `bins` on the GPU: density the sum, colour the max,
    /// emission kept apart (the CPU's [`voxlod_cpu::volume::fill::fill`] per bin). `prepared`
    /// is [`Binning::prepared`] of the same spheres and spec.
    pub fn fill(
        &self,
        spheres: &[DisplacedSphere],
        prepared: &[Prepared],
        map: &DisplacementMap,
        spec: &VolumeSpec,
        bins: &[Bin],
    ) -> Result<GpuVolume> {
        let ctx = self.ctx;
        if prepared.len() != spheres.len() {
            return Err(voxlod_cpu::Error::InvalidParameter {
                name: "prepared particles",
                value: format!("{} for {} spheres", prepared.len(), spheres.len()),
                reason: "must be binning::prepare of the same spheres".into(),
            }
            .into());
        }
        let m = spec.metavoxel_edge;
        let m3 = (m as u64).pow(3);
        let voxels = bins.len() as u64 * m3;
        if voxels > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "voxels of the kept metavoxels (indexed in 32 bits)",
                requested: voxels,
                limit: u32::MAX as u64,
            });
        }
        let [n_lo, n_hi] = map.bounds();
        let preps: Vec<GpuPrep> = prepared
            .iter()
            .map(|p| {
                // The CPU fill's radii, the same f32 operations.
                let (r_lo, r_hi) = (p.inner + p.amplitude * n_lo, p.inner + p.amplitude * n_hi);
                let accept = p.inner.max(r_lo);
                GpuPrep {
                    center: p.center.extend(p.inner).to_array(),
                    radii: [p.amplitude, accept * accept, r_hi * r_hi, 0.0],
                }
            })
            .collect();
        let mut lists = Vec::new();
        let mut slots = Vec::with_capacity(bins.len());
        let mut emissive = false;
        for b in bins {
            if let Some(&bad) = b.particles.iter().find(|&&p| p as usize >= spheres.len()) {
                return Err(voxlod_cpu::Error::InvalidParameter {
                    name: "bin",
                    value: format!("particle {bad} in metavoxel {:?}", b.coord),
                    reason: format!("only {} particles", spheres.len()),
                }
                .into());
            }
            emissive |= b.particles.iter().any(|&p| spheres[p as usize].flags & FLAG_EMISSIVE != 0);
            slots.push(GpuSlot {
                coord: [b.coord[0], b.coord[1], b.coord[2], lists.len() as u32],
                range: [b.particles.len() as u32, 0, 0, 0],
            });
            lists.extend_from_slice(&b.particles);
        }
        let voxel_bytes = voxels * 16;
        ctx.check_storage("volume voxels", voxel_bytes)?;
        let emission_bytes = if emissive { voxel_bytes } else { 16 };
        ctx.check_storage("volume emission", emission_bytes)?;
        let boxes_init: Vec<u32> =
            bins.iter().flat_map(|_| [u32::MAX, u32::MAX, u32::MAX, 0, 0, 0]).collect();
        // At least one element: a binding must hold one element of its array.
        let voxel_buf = ctx.storage_zeroed("volume voxels", voxel_bytes.max(16))?;
        let emission = ctx.storage_zeroed("volume emission", emission_bytes)?;
        let boxes = ctx.storage_init("volume boxes", bytemuck::cast_slice(&boxes_init))?;
        if !bins.is_empty() {
            let params = GpuFillParams {
                dims: [m, bins.len() as u32, map.face_size(), emissive as u32],
                frame: GpuFrame::new(&spec.frame),
            };
            let uniform = ctx.uniform("fill params", bytemuck::bytes_of(&params))?;
            let sphere_buf = ctx.storage_init("fill spheres", bytemuck::cast_slice(spheres))?;
            let prep_buf = ctx.storage_init("fill particles", bytemuck::cast_slice(&preps))?;
            let slot_buf = ctx.storage_init("fill slots", bytemuck::cast_slice(&slots))?;
            let list_buf = ctx.storage_init("fill bins", bytemuck::cast_slice(&lists))?;
            let texels = ctx.storage_init("cube map", bytemuck::cast_slice(map.texels()))?;
            let wg = ctx.dispatch_size("fill workgroups", voxels.div_ceil(WORKGROUP))?;
            self.dispatch(
                "filling metavoxels",
                &self.fill,
                &[
                    &uniform,
                    &sphere_buf,
                    &prep_buf,
                    &slot_buf,
                    &list_buf,
                    &texels,
                    &voxel_buf,
                    &emission,
                    &boxes,
                ],
                wg,
            )?;
        }
        let words: Vec<u32> =
            bytemuck::pod_collect_to_vec(&ctx.read(&boxes, boxes_init.len() as u64 * 4)?);
        let occupied = words
            .chunks_exact(6)
            .map(|b| {
                if b[0] == u32::MAX {
                    [[0; 3]; 2]
                } else {
                    [[b[0], b[1], b[2]], [b[3], b[4], b[5]]]
                }
            })
            .collect();
        Ok(GpuVolume {
            spec: *spec,
            attenuation: None,
            coords: bins.iter().map(|b| b.coord).collect(),
            particles: bins.iter().map(|b| b.particles.len()).collect(),
            occupied,
            emissive,
            stats: BuildStats {
                particles: spheres.len(),
                bin_entries: lists.len(),
                occupied: bins.len(),
                kept: bins.len(),
            },
            times: StageTimes::default(),
            voxels: voxel_buf,
            emission,
            boxes,
            light_top: None,
        })
    }

    /// Per voxel column of the kept metavoxel columns, the depth (voxels from the volume's
    /// top) of the first mesh hit: the CPU's `scene_shadow_depths`, its two rays per column
    /// cast by the GPU ray caster ([`RayCaster`]).
    fn shadow_depths(
        &self,
        spec: &VolumeSpec,
        columns: &[[u32; 2]],
        blocker: &GpuBvh,
    ) -> Result<Vec<f32>> {
        let m = spec.metavoxel_edge;
        let f = &spec.frame;
        let depth = spec.voxels_per_axis() as f32 * f.voxel_size;
        let mut up = Vec::with_capacity(columns.len() * (m * m) as usize);
        let mut down = Vec::with_capacity(up.capacity());
        for &[i, j] in columns {
            for idx in 0..m * m {
                let (a, b) = (idx % m, idx / m);
                let q = glam::Vec2::new((i * m + a) as f32 + 0.5, (j * m + b) as f32 + 0.5);
                let top = f.to_world(q.extend(0.0));
                up.push(GpuRay::new(top, -f.w, 0.0, f32::INFINITY));
                down.push(GpuRay::new(top, f.w, 0.0, depth));
            }
        }
        let caster = RayCaster::new(self.ctx)?;
        let up = caster.intersect(blocker, &up)?;
        let down = caster.intersect(blocker, &down)?;
        Ok(up
            .iter()
            .zip(&down)
            .map(|(u, d)| match (u.hit(), d.hit()) {
                (Some(_), _) => f32::NEG_INFINITY,
                (None, Some(h)) => h.t / f.voxel_size,
                (None, None) => f32::INFINITY,
            })
            .collect())
    }

    /// Light propagation (Listing 5.2) on the GPU: the CPU's
    /// [`voxlod_cpu::volume::propagate::propagate`] over the filled `volume`, in place.
    /// `blocker` (the mesh's BVH on this device) casts the scene's shadow on the volume.
    pub fn propagate(
        &self,
        volume: &mut GpuVolume,
        settings: &BuildSettings,
        blocker: Option<&GpuBvh>,
    ) -> Result<()> {
        let ctx = self.ctx;
        let spec = volume.spec;
        let m = spec.metavoxel_edge;
        let m2 = (m * m) as u64;
        let kept = volume.coords.len() as u64;
        let mut columns: Vec<[u32; 4]> = Vec::new();
        let mut heads: Vec<[u32; 2]> = Vec::new();
        for (s, c) in volume.coords.iter().enumerate() {
            match columns.last_mut() {
                Some(col) if heads.last() == Some(&[c[0], c[1]]) => col[1] += 1,
                _ => {
                    columns.push([s as u32, 1, 0, 0]);
                    heads.push([c[0], c[1]]);
                }
            }
        }
        let light_bytes = kept * m2 * 4;
        let light_top = ctx.storage_zeroed("volume light", light_bytes)?;
        if !columns.is_empty() {
            let items = columns.len() as u64 * m2;
            let shadow = match blocker {
                Some(bvh) => self.shadow_depths(&spec, &heads, bvh)?,
                None => vec![f32::INFINITY; items as usize],
            };
            let direct = settings.irradiance / std::f32::consts::PI;
            let params = GpuPropagateParams {
                dims: [
                    m,
                    columns.len() as u32,
                    attenuation_id(settings.attenuation),
                    volume.emissive as u32,
                ],
                direct: direct.extend(spec.frame.voxel_size).to_array(),
                ambient: settings.ambient.extend(0.0).to_array(),
            };
            let slots: Vec<[u32; 4]> =
                volume.coords.iter().map(|c| [c[0], c[1], c[2], 0]).collect();
            let uniform = ctx.uniform("propagation params", bytemuck::bytes_of(&params))?;
            let col_buf =
                ctx.storage_init("propagation columns", bytemuck::cast_slice(&columns))?;
            let slot_buf = ctx.storage_init("propagation slots", bytemuck::cast_slice(&slots))?;
            let shadow_buf =
                ctx.storage_init("propagation shadow", bytemuck::cast_slice(&shadow))?;
            let wg = ctx.dispatch_size("propagation workgroups", items.div_ceil(WORKGROUP))?;
            self.dispatch(
                "propagating light",
                &self.propagate,
                &[
                    &uniform,
                    &col_buf,
                    &slot_buf,
                    &volume.boxes,
                    &volume.emission,
                    &shadow_buf,
                    &volume.voxels,
                    &light_top,
                ],
                wg,
            )?;
        }
        volume.light_top = Some(light_top);
        volume.attenuation = Some(settings.attenuation);
        Ok(())
    }

    /// Uploads a CPU-built volume (for the march alone).
    pub fn upload(&self, volume: &Volume) -> Result<GpuVolume> {
        let ctx = self.ctx;
        let mvs = &volume.metavoxels;
        let voxels: Vec<Vec4> = mvs.iter().flat_map(|mv| mv.voxels.iter().copied()).collect();
        let light: Vec<f32> = mvs.iter().flat_map(|mv| mv.light_top.iter().copied()).collect();
        let boxes: Vec<u32> = mvs.iter().flat_map(|mv| mv.occupied.concat()).collect();
        Ok(GpuVolume {
            spec: volume.spec,
            attenuation: Some(volume.attenuation),
            coords: mvs.iter().map(|mv| mv.coord).collect(),
            particles: mvs.iter().map(|mv| mv.particles).collect(),
            occupied: mvs.iter().map(|mv| mv.occupied).collect(),
            emissive: false,
            stats: volume.stats,
            times: volume.times,
            voxels: ctx
                .storage_init("volume voxels", bytemuck::cast_slice(&at_least_one(voxels)))?,
            emission: ctx.storage_zeroed("volume emission", 16)?,
            boxes: ctx.storage_init("volume boxes", bytemuck::cast_slice(&boxes))?,
            light_top: Some(ctx.storage_init("volume light", bytemuck::cast_slice(&light))?),
        })
    }

    /// Reads the volume back: per slot its metavoxel (voxels, light at the column tops — all
    /// 1 before propagation, as the CPU fill leaves them — and occupied box) and, before
    /// propagation, its emission when the fill wrote any.
    pub fn read(&self, volume: &GpuVolume) -> Result<Vec<(Metavoxel, Option<Vec<Vec3>>)>> {
        let ctx = self.ctx;
        let m = volume.spec.metavoxel_edge as usize;
        let (m2, m3) = (m * m, m * m * m);
        let kept = volume.coords.len();
        if kept == 0 {
            return Ok(Vec::new());
        }
        let voxels: Vec<Vec4> =
            bytemuck::pod_collect_to_vec(&ctx.read(&volume.voxels, (kept * m3 * 16) as u64)?);
        let light: Vec<f32> = match &volume.light_top {
            Some(b) => bytemuck::pod_collect_to_vec(&ctx.read(b, (kept * m2 * 4) as u64)?),
            None => vec![1.0; kept * m2],
        };
        let emission: Option<Vec<Vec4>> = if volume.emissive && volume.attenuation.is_none() {
            Some(bytemuck::pod_collect_to_vec(
                &ctx.read(&volume.emission, (kept * m3 * 16) as u64)?,
            ))
        } else {
            None
        };
        Ok((0..kept)
            .map(|s| {
                let e = emission.as_ref().map(|e| {
                    e[s * m3..(s + 1) * m3].iter().map(|v| v.truncate()).collect::<Vec<Vec3>>()
                });
                let e = e.filter(|e| e.iter().any(|v| *v != Vec3::ZERO));
                (
                    Metavoxel {
                        coord: volume.coords[s],
                        particles: volume.particles[s],
                        voxels: voxels[s * m3..(s + 1) * m3].to_vec(),
                        light_top: light[s * m2..(s + 1) * m2].to_vec(),
                        occupied: volume.occupied[s],
                    },
                    e,
                )
            })
            .collect())
    }

    /// Reads a lit volume back as the CPU's [`Volume`] (for the volume's shadow on the mesh,
    /// [`Volume::transmittance_to_light`], and for comparisons). Errors before propagation.
    pub fn read_volume(&self, volume: &GpuVolume) -> Result<Volume> {
        let Some(attenuation) = volume.attenuation else {
            return Err(Error::Unsupported {
                what: "reading a volume that was not lit back as a Volume (propagate it first)",
            });
        };
        let metavoxels = self.read(volume)?.into_iter().map(|(mv, _)| mv).collect();
        Ok(Volume::from_parts(volume.spec, attenuation, metavoxels, volume.stats, volume.times)?)
    }

    /// The eye march (Listing 5.3) of a lit `volume` on the GPU: the CPU's
    /// [`voxlod_cpu::volume::march::render`] (premultiplied RGBA, rays stopping at `depth`).
    pub fn render(
        &self,
        volume: &GpuVolume,
        camera: &Camera,
        options: &MarchOptions,
        depth: Option<&[f32]>,
    ) -> Result<Image> {
        let ctx = self.ctx;
        let frame = check_march(camera, options, depth)?;
        let Some(attenuation) = volume.attenuation else {
            return Err(Error::Unsupported {
                what: "marching a volume that was not lit (propagate it first)",
            });
        };
        let spec = &volume.spec;
        let m = spec.metavoxel_edge;
        let mf = m as f32;
        let pixels = options.width as u64 * options.height as u64;
        let image_bytes = pixels * 16;
        ctx.check_storage("volume image", image_bytes)?;
        let wg = ctx.image_dispatch("volume march workgroups", options.width, options.height)?;
        let f = &spec.frame;
        let mut params = GpuMarchParams {
            eye: frame.eye.extend(0.0).to_array(),
            forward: frame.forward.extend(0.0).to_array(),
            right: frame.right.extend(0.0).to_array(),
            up: frame.up.extend(0.0).to_array(),
            frame: GpuFrame::new(f),
            eye_voxel: f.to_voxel(frame.eye).extend(options.step * f.voxel_size).to_array(),
            dims: [options.width, options.height, 0, m],
            mode: [attenuation_id(attenuation), depth.is_some() as u32, 0, 0],
        };
        let depth_buf =
            ctx.storage_init("march depth", bytemuck::cast_slice(depth.unwrap_or(&[])))?;
        let image = ctx.storage_zeroed("volume image", image_bytes)?;
        if attenuation == Attenuation::Exact {
            // The reference march: every voxel crossed, through the K³ slot index.
            let k = spec.metavoxels;
            let mut index = vec![u32::MAX; (k as usize).pow(3)];
            for (s, &c) in volume.coords.iter().enumerate() {
                index[spec.key(c) as usize] = s as u32;
            }
            params.dims[2] = k;
            params.eye_voxel[3] = 1e-4 * f.voxel_size;
            let uniform = ctx.uniform("exact march params", bytemuck::bytes_of(&params))?;
            let index_buf = ctx.storage_init("metavoxel index", bytemuck::cast_slice(&index))?;
            self.dispatch(
                "marching eye rays (exact)",
                &self.march_exact,
                &[&uniform, &index_buf, &volume.voxels, &depth_buf, &image],
                wg,
            )?;
        } else {
            let entries: Vec<GpuMarchEntry> = sort_order(spec, &volume.coords, frame.eye)
                .into_iter()
                .filter(|&(s, _)| volume.occupied[s][0][0] < volume.occupied[s][1][0])
                .map(|(s, over)| {
                    let c = volume.coords[s];
                    let base = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * mf;
                    let [lo, hi] = volume.occupied[s];
                    let lo =
                        (Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32) - 1.0).max(Vec3::ZERO);
                    let hi = (Vec3::new(hi[0] as f32, hi[1] as f32, hi[2] as f32) + 1.0)
                        .min(Vec3::splat(mf));
                    GpuMarchEntry {
                        base: base.extend(0.0).to_array(),
                        lo: (base + lo).extend(0.0).to_array(),
                        hi: (base + hi).extend(0.0).to_array(),
                        flags: [s as u32, over as u32, 0, 0],
                    }
                })
                .collect();
            params.dims[2] = entries.len() as u32;
            let uniform = ctx.uniform("march params", bytemuck::bytes_of(&params))?;
            let order =
                ctx.storage_init("march order", bytemuck::cast_slice(&at_least_one(entries)))?;
            self.dispatch(
                "marching eye rays",
                &self.march,
                &[&uniform, &order, &volume.voxels, &depth_buf, &image],
                wg,
            )?;
        }
        let pixels: Vec<Vec4> = bytemuck::pod_collect_to_vec(&ctx.read(&image, image_bytes)?);
        Ok(Image { width: options.width, height: options.height, pixels })
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
            Some(frame) => binning::cull(binning.bins, spec, frame),
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
        let view = check_march(camera, options, depth)?;
        let volume = self.build(spheres, map, spec, settings, Some(&view), blocker)?;
        let t = Instant::now();
        let image = self.render(&volume, camera, options, depth)?;
        Ok((image, volume, t.elapsed()))
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn sphere_mirrors_displaced_sphere() {
        type S = DisplacedSphere;
        assert_mirrors(
            FILL_WGSL,
            "Sphere",
            size_of::<S>(),
            &[
                ("center", offset_of!(S, center)),
                ("inner", offset_of!(S, inner)),
                ("color", offset_of!(S, color)),
                ("amplitude", offset_of!(S, amplitude)),
                ("color_outer", offset_of!(S, color_outer)),
                ("density", offset_of!(S, density)),
                ("rot_cos", offset_of!(S, rot_cos)),
                ("rot_sin", offset_of!(S, rot_sin)),
                ("color_mode", offset_of!(S, color_mode)),
                ("flags", offset_of!(S, flags)),
            ],
        );
    }

    #[test]
    fn kernel_records_mirror_their_wgsl() {
        assert_mirrors(
            BINNING_WGSL,
            "Candidate",
            size_of::<GpuCandidate>(),
            &[
                ("sphere", offset_of!(GpuCandidate, sphere)),
                ("lo", offset_of!(GpuCandidate, lo)),
                ("hi", offset_of!(GpuCandidate, hi)),
            ],
        );
        assert_mirrors(BINNING_WGSL, "Params", size_of::<GpuBinParams>(), &[("counts", 0)]);
        assert_mirrors(
            FILL_WGSL,
            "Frame",
            size_of::<GpuFrame>(),
            &[("origin", 0), ("u", 16), ("v", 32), ("w", 48)],
        );
        assert_mirrors(
            FILL_WGSL,
            "Params",
            size_of::<GpuFillParams>(),
            &[
                ("dims", offset_of!(GpuFillParams, dims)),
                ("frame", offset_of!(GpuFillParams, frame)),
            ],
        );
        assert_mirrors(
            FILL_WGSL,
            "Prep",
            size_of::<GpuPrep>(),
            &[("center", offset_of!(GpuPrep, center)), ("radii", offset_of!(GpuPrep, radii))],
        );
        assert_mirrors(
            FILL_WGSL,
            "Slot",
            size_of::<GpuSlot>(),
            &[("coord", offset_of!(GpuSlot, coord)), ("range", offset_of!(GpuSlot, range))],
        );
        assert_mirrors(
            PROPAGATE_WGSL,
            "Params",
            size_of::<GpuPropagateParams>(),
            &[
                ("dims", offset_of!(GpuPropagateParams, dims)),
                ("direct", offset_of!(GpuPropagateParams, direct)),
                ("ambient", offset_of!(GpuPropagateParams, ambient)),
            ],
        );
        type P = GpuMarchParams;
        let f = offset_of!(P, frame);
        // The approximate and the exact march read the same parameters.
        for wgsl in [MARCH_WGSL, MARCH_EXACT_WGSL] {
            assert_mirrors(
                wgsl,
                "Params",
                size_of::<P>(),
                &[
                    ("eye", offset_of!(P, eye)),
                    ("forward", offset_of!(P, forward)),
                    ("right", offset_of!(P, right)),
                    ("up", offset_of!(P, up)),
                    ("origin", f),
                    ("u", f + 16),
                    ("v", f + 32),
                    ("w", f + 48),
                    ("eye_voxel", offset_of!(P, eye_voxel)),
                    ("dims", offset_of!(P, dims)),
                    ("mode", offset_of!(P, mode)),
                ],
            );
        }
        assert_mirrors(
            MARCH_WGSL,
            "Entry",
            size_of::<GpuMarchEntry>(),
            &[
                ("base", offset_of!(GpuMarchEntry, base)),
                ("lo", offset_of!(GpuMarchEntry, lo)),
                ("hi", offset_of!(GpuMarchEntry, hi)),
                ("flags", offset_of!(GpuMarchEntry, flags)),
            ],
        );
    }

    #[test]
    fn axis_range_is_the_cpu_arithmetic() {
        // A sphere at x = 10 of radius 3 in metavoxels of 4 covers metavoxels 1..=3 of K = 8.
        assert_eq!(axis_range(10.0, 3.0, 4, 8), Some((1, 3)));
        assert_eq!(axis_range(-10.0, 3.0, 4, 8), None);
        assert_eq!(axis_range(40.0, 3.0, 4, 8), None);
        assert_eq!(axis_range(f32::NAN, 3.0, 4, 8), None);
        assert_eq!(axis_range(1.0, 100.0, 4, 8), Some((0, 7)));
    }
}
