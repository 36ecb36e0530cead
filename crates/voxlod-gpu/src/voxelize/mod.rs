//! Exact conservative (and 6-separating thin) surface voxelization on the GPU, the mirror of
//! [`voxlod_cpu::voxelize`] in its surface modes.
//!
//! # Contract
//! The occupied voxel set is **exactly** the CPU reference's, and so is each voxel's number of
//! overlapping triangles ([`GpuVoxelization::count`] equals the CPU's
//! [`TriangleRange::count`](voxlod_cpu::voxelize::TriangleRange)). The host does what the CPU
//! reference does first — [`Lattice::new`] snaps the vertices (in `f64`), and
//! [`Lattice::triangle`] culls triangles that cannot reach the grid and rejects bad input — so
//! bad input through this path gives the very error the CPU path gives. Every overlap decision
//! on the GPU is the integer test of [`voxlod_cpu::voxelize::overlap`] in WGSL, with the CPU's
//! `i64`/`i128` arithmetic emulated on 32-bit words (32×32→64 products from 16-bit halves, a
//! 128-bit accumulator for the plane test): no width restriction, the whole lattice range
//! (`|x| ≤ 2^29`, grids up to the device's buffer limits) is exact.
//!
//! # Work decomposition (what a real GPU sees)
//! One invocation per (triangle, column): the columns of a triangle are the voxels of its
//! clipped voxel range in the plane of the two axes other than its working axis `w` (the
//! largest component of the exact normal), so a large triangle spreads over many invocations
//! and a small one costs one or a few. The host computes per-triangle column counts and their
//! prefix sum; an invocation finds its triangle by binary search over that prefix sum (coherent
//! across a workgroup: neighbours read the same entries). Per column, the plane of the
//! triangle bounds the candidate voxels along `w` ("Candidates" below) to at most 4 for small
//! triangles, each decided by the exact test; hits set a bit of a dense bitset (`atomicOr`)
//! and optionally bump a per-voxel counter (`atomicAdd`). Work is split into batches of at most
//! [`ITEMS_PER_BATCH`] invocations, each a 2D dispatch within the workgroup-count limit.
//! Degenerate triangles (zero normal after snapping, i.e. segments and points) scan their
//! whole range along `w` — exact, and cheap for the short segments snapping produces.
//!
//! # Candidates
//! The plane test `|n·(c − a)| ≤ h‖n‖₁` of voxel centre `c` along a column is an interval
//! `|k − k_c| ≤ R` with `R = ‖n‖₁ / (2|n_w|) ≤ 3/2` and
//! `k_c = ⌊a_w / V⌋ + ((a_w mod V) − h − (n_u/n_w)·d_u − (n_v/n_w)·d_v) / V`, where
//! `d_u, d_v` are the column centre minus vertex `a` (exact `i32`). The kernel evaluates `k_c`
//! in `f32` from the ratios `n_u/n_w`, `n_v/n_w` (exact `i64` normal, divided in `f64` on the
//! host, rounded to `f32`): with `|n_u/n_w|, |n_v/n_w| ≤ 1` and `|d| ≤ (E + 1)·V` for a
//! triangle `E` voxels across, the rounding error is below `5·2^−24·(2E + 3)` voxels. The
//! kernel widens the interval by `m = 2^−18·(E + 2) + 2^−6` voxels (four times that bound)
//! and takes `⌊k_c − R − m⌋ ..= ⌈k_c + R + m⌉`: a superset of the voxels that pass, so the
//! exact test still decides every voxel. Thin mode tests a subset of the box (the diamond) and
//! uses the same candidates.
//!
//! # Limits
//! The bitset takes `voxels / 8` bytes and the counters `4 · voxels` bytes, each one storage
//! binding: a grid over the device's `max_storage_buffer_binding_size` is
//! [`Error::BufferTooLarge`] with the numbers (128 MiB on lavapipe: 1024³ voxels occupancy,
//! about 322³ with counts), and over `2^32 − 1` voxels [`Error::TooLarge`]. Solid mode has no
//! GPU kernel ([`Error::Unsupported`]).
//!
//! # Layout of the module
//! `prepare` holds the host-side preparation (snapping, culling, the triangles' records and
//! batches); this file the mirrors, the result type and the dispatches.
//!
//! [`Lattice::new`]: voxlod_cpu::voxelize::lattice::Lattice::new
//! [`Lattice::triangle`]: voxlod_cpu::voxelize::lattice::Lattice::triangle

use glam::UVec3;
use voxlod_cpu::voxelize::Mode;
use voxlod_cpu::voxelize::lattice;
use voxlod_format::{BrickMap, GridSpec, morton};
use voxlod_scene::Geometry;

use crate::context::record_pass;
use crate::{Context, Error, Result};

mod prepare;

pub use prepare::{Prepared, prepare, triangle_record};

/// The WGSL source of the kernel.
pub const WGSL: &str = include_str!("voxelize.wgsl");

/// Most invocations per batch (one dispatch each): bounds a dispatch's duration on real GPUs,
/// where a long dispatch can trip the driver's timeout detection.
pub const ITEMS_PER_BATCH: u64 = 1 << 22;

/// Invocations per workgroup (the WGSL `@workgroup_size`).
pub const WORKGROUP: u64 = 64;

/// One triangle as the kernel reads it (mirrors WGSL `Tri`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuTriangle {
    /// Snapped vertex 0; `w` = working axis (0, 1, 2).
    pub a: [i32; 4],
    /// Snapped vertex 1; `w` = 1 if degenerate (the whole range along the axis is scanned).
    pub b: [i32; 4],
    /// Snapped vertex 2; `w` = triangle id.
    pub c: [i32; 4],
    /// First voxel of the triangle's voxel range clipped to the grid; `w` = columns along the
    /// first in-plane axis.
    pub lo: [u32; 4],
    /// Last voxel of the clipped range; `w` = 0.
    pub hi: [u32; 4],
    /// `(n_u/n_w, n_v/n_w, R + m, 0)`: the candidate interval of the module docs.
    pub plane: [f32; 4],
}

/// The kernel's parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuVoxelizeParams {
    /// Grid dims; `w` = mode (0 conservative, 1 thin).
    pub dims: [u32; 4],
    /// `x` = triangles in the batch, `y` = invocations, `z` = 1 to count triangles per voxel.
    pub batch: [u32; 4],
}

/// Options of [`Voxelizer::voxelize`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxelizeOptions {
    /// [`Mode::Conservative`] or [`Mode::Thin`] ([`Mode::Solid`] has no GPU kernel).
    pub mode: Mode,
    /// Also count, per voxel, the triangles overlapping it (4 bytes per grid voxel on the
    /// device).
    pub counts: bool,
}

impl Default for VoxelizeOptions {
    fn default() -> Self {
        Self { mode: Mode::Conservative, counts: false }
    }
}

/// The GPU's answer: a dense bitset over the grid (x fastest, then y, then z; bit `i % 32` of
/// word `i / 32` for linear index `i`), and optionally per-voxel triangle counts.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuVoxelization {
    /// The grid voxelized into.
    pub grid: GridSpec,
    /// The mode used.
    pub mode: Mode,
    /// Occupancy bits.
    pub bits: Vec<u32>,
    /// Triangles per voxel, linear order, if requested.
    pub counts: Option<Vec<u32>>,
}

impl GpuVoxelization {
    fn linear(&self, c: UVec3) -> Option<usize> {
        let d = self.grid.dims;
        (c.x < d.x && c.y < d.y && c.z < d.z)
            .then(|| c.x as usize + d.x as usize * (c.y as usize + d.y as usize * c.z as usize))
    }

    /// Whether voxel `c` is occupied.
    pub fn contains(&self, c: UVec3) -> bool {
        self.linear(c).is_some_and(|i| self.bits[i / 32] >> (i % 32) & 1 == 1)
    }

    /// Triangles overlapping voxel `c`, if counts were requested.
    pub fn count(&self, c: UVec3) -> Option<u32> {
        let i = self.linear(c)?;
        self.counts.as_ref().map(|v| v[i])
    }

    /// Number of occupied voxels.
    pub fn len(&self) -> usize {
        self.bits.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Whether nothing is occupied.
    pub fn is_empty(&self) -> bool {
        self.bits.iter().all(|&w| w == 0)
    }

    /// Occupied voxels in linear order.
    pub fn coords(&self) -> impl Iterator<Item = UVec3> + '_ {
        let d = self.grid.dims;
        self.bits.iter().enumerate().flat_map(move |(w, &word)| {
            let mut bits = word;
            std::iter::from_fn(move || {
                (bits != 0).then(|| {
                    let i = w as u64 * 32 + bits.trailing_zeros() as u64;
                    bits &= bits - 1;
                    let (x, y) = (d.x as u64, d.y as u64);
                    UVec3::new((i % x) as u32, (i / x % y) as u32, (i / (x * y)) as u32)
                })
            })
        })
    }

    /// The sparse brick map of the occupied voxels (Morton order, as the CPU's), with the
    /// triangle count (0 without counts) as value.
    pub fn to_brick_map(&self) -> Result<BrickMap<u32>> {
        let mut voxels: Vec<(u64, u32)> =
            self.coords().map(|c| (morton::encode(c), self.count(c).unwrap_or(0))).collect();
        voxels.sort_unstable_by_key(|v| v.0);
        BrickMap::from_morton_sorted(self.grid.dims, voxels)
            .map_err(|e| Error::Cpu(voxlod_cpu::Error::Format(e)))
    }
}

/// The voxelization kernel, compiled for one [`Context`].
pub struct Voxelizer<'a> {
    ctx: &'a Context,
    pipeline: wgpu::ComputePipeline,
}

impl<'a> Voxelizer<'a> {
    /// Compiles the kernel.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        Ok(Self { ctx, pipeline: ctx.pipeline("voxelize", WGSL)? })
    }

    /// Voxelizes `geometry` into `grid` on the GPU (module docs: contract, limits, errors).
    pub fn voxelize(
        &self,
        geometry: &Geometry,
        grid: &GridSpec,
        options: &VoxelizeOptions,
    ) -> Result<GpuVoxelization> {
        let mode_id = match options.mode {
            Mode::Conservative => 0,
            Mode::Thin => 1,
            Mode::Solid => {
                return Err(Error::Unsupported {
                    what: "solid voxelization on the GPU (use voxlod_cpu::voxelize)",
                });
            }
        };
        lattice::check_grid(grid)?;
        let voxels = grid.voxel_count();
        if voxels > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "grid voxels (the kernel indexes voxels in 32 bits)",
                requested: voxels,
                limit: u32::MAX as u64,
            });
        }
        let ctx = self.ctx;
        let bit_bytes = voxels.div_ceil(32) * 4;
        let count_bytes = if options.counts { voxels * 4 } else { 4 };
        ctx.check_storage("the occupancy bitset", bit_bytes)?;
        ctx.check_storage("the per-voxel triangle counts", count_bytes)?;
        let binding = ctx.limits().max_storage_buffer_binding_size;
        let tris_per_batch = (binding / size_of::<GpuTriangle>() as u64).min(1 << 24) as usize;
        let prepared = prepare(geometry, grid, ITEMS_PER_BATCH, tris_per_batch)?;

        let bits = ctx.storage_zeroed("occupancy bits", bit_bytes)?;
        let counts = ctx.storage_zeroed("triangle counts", count_bytes)?;
        let layout = self.pipeline.get_bind_group_layout(0);
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        // Keep every batch's buffers alive until the submission completes.
        let mut keep = Vec::new();
        for &(first, count, items) in &prepared.batches {
            let params = GpuVoxelizeParams {
                dims: [grid.dims.x, grid.dims.y, grid.dims.z, mode_id],
                batch: [count as u32, items as u32, options.counts as u32, 0],
            };
            let uniform = ctx.uniform("voxelize params", bytemuck::bytes_of(&params))?;
            let tris = ctx.storage_init(
                "voxelize triangles",
                bytemuck::cast_slice(&prepared.triangles[first..first + count]),
            )?;
            let starts = ctx.storage_init(
                "voxelize starts",
                bytemuck::cast_slice(&prepared.starts[first..first + count]),
            )?;
            let (x, y) = ctx.dispatch_size("voxelize workgroups", items.div_ceil(WORKGROUP))?;
            let buffers = [&uniform, &tris, &starts, &bits, &counts];
            let bind = ctx.bind_group("binding voxelize buffers", &layout, &buffers)?;
            record_pass(&mut encoder, "voxelize", &self.pipeline, &bind, (x, y));
            keep.push((uniform, tris, starts, bind));
        }
        ctx.submit("voxelizing", encoder)?;
        let words: Vec<u32> = bytemuck::cast_slice(&ctx.read(&bits, bit_bytes)?).to_vec();
        let counts = if options.counts {
            Some(bytemuck::cast_slice(&ctx.read(&counts, count_bytes)?).to_vec())
        } else {
            None
        };
        drop(keep);
        Ok(GpuVoxelization { grid: *grid, mode: options.mode, bits: words, counts })
    }
}
