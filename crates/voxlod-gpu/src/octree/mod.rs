//! The sparse voxel octree build on the GPU: the lock-free level-by-level build of
//! [`voxlod_octree::gpu_layout`] (the per-frame build of Yalçıner and Sahillioğlu 2020, §4.3–4.4, with an
//! exclusive prefix sum where the paper takes a spin lock) as wgpu kernels, producing the flat
//! layout [`FlatOctree`] (nodes of all levels root first, 2×2×2 tiles with +x/+y/+z links on the
//! sparse levels) and the bottom-up Averages pre-filter.
//!
//! # Contract
//! The topology — the level table, every node's child pointer and mask, every tile's links,
//! hence every node's neighbour — **equals exactly** what the CPU builds give
//! ([`FlatOctree::from_octree`] of [`voxlod_octree::Octree::build`], and
//! [`FlatOctree::build_level_by_level`]), in the same (Morton) order: the allocation is an
//! exclusive prefix sum over the parent level, not an atomic counter, so the result is
//! deterministic. Averages payloads are the CPU's arithmetic in the CPU's order (sum the eight
//! children in octant order from zero, then scale by 1/8; additions and multiplications are
//! correctly rounded in Vulkan), so they agree to the last bit unless a driver reorders float
//! additions or flushes subnormals; the equivalence suite's bound (`8·depth·2⁻²⁴` on
//! components of magnitude ≤ 1) covers a reordering of every level's eight-term sum.
//!
//! Input checks are the CPU's, on the host, in the CPU's order (grid, depth and dense levels
//! by [`voxlod_octree::plan`], then coordinates and payloads voxel by voxel), so bad input gets
//! the very [`voxlod_octree::Error`] the CPU build returns ([`Error::Octree`]); a voxel given
//! twice is detected on the GPU (two voxels reaching one leaf) and then named by the host as
//! the CPU names it.
//!
//! # Kernels (workgroup size 64 unless said; one pass each, in dependency order)
//! For each sparse level `l`, from the finest dense level down:
//! 1. `mark`: one invocation per (voxel, backward shift `d ∈ {0,1}³`), eight adjacent
//!    invocations per voxel: descend from the finest dense level through the child pointers
//!    built so far to the parent of node `(v >> l) − d` and set its flag (`atomicStore`,
//!    relaxed: every writer writes 1); `d = 0` also ORs the voxel's octant into its parent's
//!    mask (`atomicOr`).
//! 2. `scan_block` (workgroup 256, 512 values per workgroup, Hillis–Steele in workgroup
//!    memory) and `scan_add`: an exclusive prefix sum over the parent level's flags, recursive
//!    over the block totals (one more level per factor 512: three levels cover 2²⁷ parents).
//!    The total (tiles of level `l`) is read back: it sizes the level (one round trip per
//!    sparse level, at most 21).
//! 3. `fill` (the new level's nodes: no child, empty mask), `allocate` (one invocation per
//!    parent: flagged parent of rank `r` gets tile `r`, i.e. nodes `8r..8r+8`, and tile `r`
//!    records its parent), `link` (one invocation per tile: its +a neighbour tile is the child
//!    tile of its parent's +a neighbour, by Morton increment on a dense parent level, within
//!    the parent's tile or through the parent tile's link on a sparse one).
//!
//! Then `leaves` (one invocation per voxel: descend to its leaf, count it; a leaf counted
//! twice is a duplicate voxel) and, for Averages, `scatter` (each voxel's payload to its leaf)
//! and `prefilter` per level bottom-up (one invocation per node over its child tile).
//!
//! # On a real GPU
//! Expected, not measured on one: the mark pass should dominate (per level, 8 descents per voxel of
//! `first_dense − l` dependent reads each). The eight invocations of one voxel sit in one warp and
//! walk the same path (the same cache lines; their flag writes hit at most 8 parents, usually 1–4),
//! voxels in input order are spatially coherent if the input is (a Morton-sorted input makes whole
//! warps walk shared paths), and divergence is limited to the `o ≥ d` test at the grid's lower
//! faces. Flags are plain relaxed stores (no contention beyond the cache line). The scan is
//! bandwidth-bound (two reads and one write per parent) and the allocate, link and prefilter passes
//! read and write consecutive nodes and tiles in consecutive invocations (coalesced; link reads the
//! parent level's child pointers at Morton-near addresses). The per-level read back of the tile
//! count is a synchronization point per sparse level (≤ 21); allocating every level at its worst
//! case instead would remove it at a large memory cost.
//!
//! # Limits
//! Every buffer is checked against the device's binding limit before it is allocated
//! ([`Error::BufferTooLarge`] with the numbers: nodes take 8 bytes, tiles 12, payloads 28 each);
//! a dispatch over `2^31` invocations (the mark pass: `8·voxels`) is [`Error::TooLarge`], and
//! over the device's workgroup-count limit it is split in 2D ([`Context::dispatch_size`]).
//! A tree of `2^32 − 1` nodes or more is voxlod-octree's `TooManyNodes`, as on the CPU.
//!
//! # Layout of the module
//! `params` holds the kernels' uniform (the flat-layout types are voxlod-octree's own),
//! `input` the host-side checks, `build` the sequence of dispatches, `buffers` the growing
//! node and tile arrays and the octree left on the device with its readback; this file
//! compiles the kernels and records one dispatch.

use glam::UVec3;
use voxlod_format::GridSpec;
use voxlod_octree::{AveragePayload, BuildOptions, FlatOctree};

use crate::context::record_pass;
use crate::{Context, Error, Result};

mod buffers;
mod build;
mod input;
mod params;

pub use buffers::GpuOctree;
pub use params::GpuOctreeParams;

use input::{Input, check_input};

/// The WGSL shared by every kernel: the mirrors of [`GpuNode`](voxlod_octree::GpuNode),
/// [`GpuTile`](voxlod_octree::GpuTile), [`GpuLevel`](voxlod_octree::GpuLevel),
/// [`AveragePayload`] (`Average`) and [`GpuOctreeParams`] (after [`crate::MORTON_WGSL`]).
pub const COMMON_WGSL: &str = include_str!("common.wgsl");

macro_rules! kernel {
    ($($file:literal),*) => { concat!(include_str!("../morton.wgsl"), include_str!("common.wgsl"), $(include_str!($file)),*) };
}

/// The kernels' sources, `(name, WGSL)`, in the order of [`OctreeBuilder`]'s pipelines.
pub const KERNELS: [(&str, &str); 9] = [
    ("octree fill", kernel!("fill.wgsl")),
    ("octree mark", kernel!("descend.wgsl", "mark.wgsl")),
    ("octree scan block", kernel!("scan_block.wgsl")),
    ("octree scan add", kernel!("scan_add.wgsl")),
    ("octree allocate", kernel!("allocate.wgsl")),
    ("octree link", kernel!("link.wgsl")),
    ("octree leaves", kernel!("descend.wgsl", "leaves.wgsl")),
    ("octree scatter", kernel!("descend.wgsl", "scatter.wgsl")),
    ("octree prefilter", kernel!("prefilter.wgsl")),
];

const FILL: usize = 0;
const MARK: usize = 1;
const SCAN_BLOCK: usize = 2;
const SCAN_ADD: usize = 3;
const ALLOCATE: usize = 4;
const LINK: usize = 5;
const LEAVES: usize = 6;
const SCATTER: usize = 7;
const PREFILTER: usize = 8;

/// Invocations per workgroup of every kernel but `scan_block` (WGSL `WG`).
pub const WORKGROUP: u64 = 64;
/// Values one `scan_block` workgroup scans (256 invocations, two values each).
pub const SCAN_BLOCK_VALUES: u64 = 512;
/// Most invocations of one dispatch: the kernels' flat 32-bit index stays exact for any 2D
/// split of up to this many.
pub const MAX_INVOCATIONS: u64 = 1 << 31;

/// The octree-build kernels, compiled for one [`Context`].
pub struct OctreeBuilder<'a> {
    ctx: &'a Context,
    pipelines: Vec<wgpu::ComputePipeline>,
}

impl<'a> OctreeBuilder<'a> {
    /// Compiles the kernels.
    pub fn new(ctx: &'a Context) -> Result<Self> {
        let pipelines =
            KERNELS.iter().map(|(name, src)| ctx.pipeline(name, src)).collect::<Result<_>>()?;
        Ok(Self { ctx, pipelines })
    }

    /// Builds the octree of `voxels` (any order) with Averages payloads and reads it back:
    /// equal to [`FlatOctree::build_level_by_level`] (module docs: contract).
    pub fn build(
        &self,
        grid: &GridSpec,
        voxels: &[(UVec3, AveragePayload)],
        options: &BuildOptions,
    ) -> Result<FlatOctree<AveragePayload>> {
        self.build_buffers(grid, voxels, options)?.read_back()
    }

    /// Builds the octree of `voxels` with Averages payloads, left on the device.
    pub fn build_buffers(
        &self,
        grid: &GridSpec,
        voxels: &[(UVec3, AveragePayload)],
        options: &BuildOptions,
    ) -> Result<GpuOctree<'a>> {
        let payload: Vec<AveragePayload> = voxels.iter().map(|v| v.1).collect();
        let input = check_input(grid, voxels.iter().map(|v| v.0), Some(&payload), options)?;
        self.run(input)
    }

    /// Builds the topology alone (no payloads) of the occupied voxels `coords` (any order),
    /// left on the device ([`GpuOctree::read_topology`]).
    pub fn build_topology(
        &self,
        grid: &GridSpec,
        coords: &[UVec3],
        options: &BuildOptions,
    ) -> Result<GpuOctree<'a>> {
        let input = check_input(grid, coords.iter().copied(), None, options)?;
        self.run(input)
    }

    /// Builds the octree of `voxels` voxels whose coordinates (`u32` × 3 each) and Averages
    /// payloads are already on the device — the output of another kernel (the
    /// [`crate::dynamic`] blend) — left on the device. The input is trusted to be inside
    /// `grid`, without duplicates and with valid payloads (the producing kernel guarantees it;
    /// a duplicate is still detected and reported as a device error); the grid and `options`
    /// are checked as [`OctreeBuilder::build`] checks them.
    pub fn build_device(
        &self,
        grid: &GridSpec,
        coords: &wgpu::Buffer,
        payload: &wgpu::Buffer,
        voxels: usize,
        options: &BuildOptions,
    ) -> Result<GpuOctree<'a>> {
        grid.validate().map_err(voxlod_octree::Error::from)?;
        let (depth, first_dense) = voxlod_octree::plan(grid.dims, options)?;
        let input = Input {
            depth,
            first_dense,
            coords: Vec::new(),
            voxels,
            payload: None,
            device: Some((coords, payload)),
        };
        self.run(input)
    }

    /// Fills `tree` (built from the same voxels, in the same order as `coords`) with new leaf
    /// payloads `payload` (Averages layout, one per voxel) pre-filtered up every level: the
    /// octree of the same voxels with other payloads (for example injected radiance) without
    /// building its topology again. Returns the new payload buffer (one per node).
    pub fn refill(
        &self,
        tree: &GpuOctree<'a>,
        coords: &wgpu::Buffer,
        payload: &wgpu::Buffer,
        voxels: usize,
    ) -> Result<wgpu::Buffer> {
        let ctx = self.ctx;
        let mut keep = Vec::new();
        let level_buf = ctx.storage_init("octree levels", bytemuck::cast_slice(&tree.levels))?;
        let stride = size_of::<AveragePayload>() as u64;
        let out = ctx.storage_zeroed("octree payloads", tree.node_count * stride)?;
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let n = voxels as u64;
        let fd = tree.first_dense;
        let params = GpuOctreeParams { n: n as u32, level: 0, first_dense: fd, extra: 0 };
        self.dispatch(
            &mut encoder,
            SCATTER,
            n.div_ceil(WORKGROUP),
            params,
            &[(1, &level_buf), (2, &tree.nodes), (3, coords), (4, payload), (5, &out)],
            &mut keep,
        )?;
        for l in 1..=tree.depth {
            let count = tree.levels[l as usize].count as u64;
            let p = GpuOctreeParams { n: count as u32, level: l, first_dense: fd, extra: 0 };
            self.dispatch(
                &mut encoder,
                PREFILTER,
                count.div_ceil(WORKGROUP),
                p,
                &[(1, &level_buf), (2, &tree.nodes), (3, &out)],
                &mut keep,
            )?;
        }
        ctx.submit("refilling an octree's payloads", encoder)?;
        Ok(out)
    }

    /// Records one dispatch of `kernel` over `threads` invocations (`scan_block`: blocks) with
    /// `params` and the buffers `entries`, keeping what it allocates in `keep`.
    fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        kernel: usize,
        workgroups: u64,
        params: GpuOctreeParams,
        entries: &[(u32, &wgpu::Buffer)],
        keep: &mut Vec<wgpu::Buffer>,
    ) -> Result<()> {
        if workgroups == 0 {
            return Ok(());
        }
        let ctx = self.ctx;
        let (name, _) = KERNELS[kernel];
        let invocations = workgroups * if kernel == SCAN_BLOCK { 256 } else { WORKGROUP };
        if invocations > MAX_INVOCATIONS {
            return Err(Error::TooLarge {
                what: "invocations of one octree-build dispatch",
                requested: invocations,
                limit: MAX_INVOCATIONS,
            });
        }
        let (x, y) = ctx.dispatch_size(name, workgroups)?;
        let uniform = ctx.uniform(name, bytemuck::bytes_of(&params))?;
        let pipeline = &self.pipelines[kernel];
        let mut all = vec![(0, &uniform)];
        all.extend_from_slice(entries);
        let layout = pipeline.get_bind_group_layout(0);
        let bind = ctx.bind_group_at("binding octree-build buffers", &layout, &all)?;
        record_pass(encoder, name, pipeline, &bind, (x, y));
        keep.push(uniform);
        Ok(())
    }

    /// The kernels' exclusive prefix sum of `values` (the allocation step's scan, exposed so
    /// that its multi-pass recursion can be checked on large inputs): the exclusive sums and
    /// the total. The values' sum must fit in `u32` (flags do: at most one per node).
    pub fn prefix_sum(&self, values: &[u32]) -> Result<(Vec<u32>, u32)> {
        let ctx = self.ctx;
        let n = values.len() as u64;
        if n > u32::MAX as u64 {
            return Err(Error::TooLarge {
                what: "values of one prefix sum",
                requested: n,
                limit: u32::MAX as u64,
            });
        }
        let data = ctx.storage_init("prefix sum values", bytemuck::cast_slice(values))?;
        let mut keep = Vec::new();
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let total = self.scan(&mut encoder, &data, n, &mut keep)?;
        ctx.submit("a prefix sum", encoder)?;
        let sums = bytemuck::pod_collect_to_vec(&ctx.read(&data, n * 4)?);
        let total = bytemuck::pod_read_unaligned::<u32>(&ctx.read(&total, 4)?);
        Ok((sums, total))
    }
}
