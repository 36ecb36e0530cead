//! The sparse voxel octree build on the GPU: the lock-free level-by-level build of
//! [`voxlod_octree::flat`] (seed 002 §4.3–4.4 without the paper's spin lock) as wgpu kernels,
//! producing the flat layout [`FlatOctree`] (nodes of all levels root first, 2×2×2 tiles with
//! +x/+y/+z links on the sparse levels) and the bottom-up Averages pre-filter.
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
//! Expected, not measured on one: the mark pass should dominate (per level, 8 descents per
//! voxel of `first_dense − l` dependent reads each). The eight invocations of one voxel sit in one warp and walk the same path
//! (the same cache lines; their flag writes hit at most 8 parents, usually 1–4), voxels in
//! input order are spatially coherent if the input is (a Morton-sorted input makes whole warps
//! walk shared paths), and divergence is limited to the `o ≥ d` test at the grid's lower
//! faces. Flags are plain relaxed stores (no contention beyond the cache line). The scan is
//! bandwidth-bound (two reads and one write per parent) and the allocate, link and prefilter
//! passes read and write consecutive nodes and tiles in consecutive invocations (coalesced;
//! link reads the parent level's child pointers at Morton-near addresses). The per-level read
//! back of the tile count is a synchronization point per sparse level (≤ 21); allocating
//! every level at its worst case instead would remove it at a large memory cost. On lavapipe
//! the 200 k-voxel shell of the `kernels` bench took 1.3–2.1 s under load, against 0.4 s for
//! the CPU reference on the same loaded cores: CPU timings of the GPU path, not GPU speed.
//!
//! # Limits
//! Every buffer is checked against the device's binding limit before it is allocated
//! ([`Error::BufferTooLarge`] with the numbers: nodes take 8 bytes, tiles 12, payloads 28 each);
//! a dispatch over `2^31` invocations (the mark pass: `8·voxels`) is [`Error::TooLarge`], and
//! over the device's workgroup-count limit it is split in 2D ([`Context::dispatch_size`]).
//! A tree of `2^32 − 1` nodes or more is voxlod-octree's `TooManyNodes`, as on the CPU.

use glam::UVec3;
use voxlod_format::{GridSpec, morton};
use voxlod_octree::{
    AveragePayload, BuildOptions, FlatOctree, GpuLevel, GpuNode, GpuTile, NONE, Payload,
};

use crate::context::record_pass;
use crate::{Context, Error, Result};

/// The WGSL shared by every kernel: the mirrors of [`GpuNode`], [`GpuTile`], [`GpuLevel`],
/// [`AveragePayload`] (`Average`) and [`GpuOctreeParams`], and Morton codes.
pub const COMMON_WGSL: &str = include_str!("common.wgsl");

macro_rules! kernel {
    ($($file:literal),*) => { concat!(include_str!("common.wgsl"), $(include_str!($file)),*) };
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

/// The kernels' uniform parameters (mirrors WGSL `Params`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuOctreeParams {
    /// Invocations (or items) of the dispatch.
    pub n: u32,
    /// The level built (mark, allocate, link) or filtered (prefilter).
    pub level: u32,
    /// The finest dense level.
    pub first_dense: u32,
    /// Kernel-specific: fill's first node, allocate's flagged-parent count.
    pub extra: u32,
}

/// An octree built on the GPU and still there: the host's level table and the device
/// buffers of the flat layout ([`FlatOctree`]'s arrays, global indices).
pub struct GpuOctree<'a> {
    ctx: &'a Context,
    /// Levels below the root.
    pub depth: u32,
    /// The finest dense level.
    pub first_dense: u32,
    /// Indexed by level, 0 = leaves (as [`FlatOctree::levels`]).
    pub levels: Vec<GpuLevel>,
    /// Nodes in all levels.
    pub node_count: u64,
    /// Tiles in all sparse levels.
    pub tile_count: u64,
    /// `array<GpuNode>` of at least `node_count` entries.
    pub nodes: wgpu::Buffer,
    /// `array<GpuTile>` of at least `tile_count` entries.
    pub tiles: wgpu::Buffer,
    /// `array<Average>` of `node_count` entries, if built with payloads.
    pub payload: Option<wgpu::Buffer>,
}

impl GpuOctree<'_> {
    /// The topology read back, with unit payloads.
    pub fn read_topology(&self) -> Result<FlatOctree<()>> {
        let nodes: Vec<GpuNode> =
            bytemuck::pod_collect_to_vec(&self.ctx.read(&self.nodes, self.node_count * 8)?);
        let tiles: Vec<GpuTile> =
            bytemuck::pod_collect_to_vec(&self.ctx.read(&self.tiles, self.tile_count * 12)?);
        Ok(FlatOctree {
            depth: self.depth,
            levels: self.levels.clone(),
            payload: vec![(); nodes.len()],
            nodes,
            tiles,
        })
    }

    /// The whole octree read back; [`Error::Unsupported`] if it was built without payloads.
    pub fn read_back(&self) -> Result<FlatOctree<AveragePayload>> {
        let Some(buffer) = &self.payload else {
            return Err(Error::Unsupported {
                what: "reading payloads of an octree built without them (read_topology)",
            });
        };
        let topology = self.read_topology()?;
        let payload: Vec<AveragePayload> = bytemuck::pod_collect_to_vec(
            &self.ctx.read(buffer, self.node_count * size_of::<AveragePayload>() as u64)?,
        );
        Ok(FlatOctree {
            depth: topology.depth,
            levels: topology.levels,
            nodes: topology.nodes,
            payload,
            tiles: topology.tiles,
        })
    }
}

/// The octree-build kernels, compiled for one [`Context`].
pub struct OctreeBuilder<'a> {
    ctx: &'a Context,
    pipelines: Vec<wgpu::ComputePipeline>,
}

/// A device buffer that grows (by copying) as levels are appended.
struct Growing {
    what: &'static str,
    stride: u64,
    capacity: u64,
    buffer: wgpu::Buffer,
}

impl Growing {
    /// Room for `needed` entries (an error with the numbers if that is over the limit), and
    /// up to `hint` if the limit allows.
    fn new(ctx: &Context, what: &'static str, stride: u64, needed: u64, hint: u64) -> Result<Self> {
        ctx.check_storage(what, needed * stride)?;
        let capacity = hint.min(Self::limit(ctx, stride)).max(needed).max(1);
        let buffer = ctx.storage_zeroed(what, capacity * stride)?;
        Ok(Self { what, stride, capacity, buffer })
    }

    /// Most entries one binding holds.
    fn limit(ctx: &Context, stride: u64) -> u64 {
        ctx.limits().max_storage_buffer_binding_size.min(ctx.limits().max_buffer_size) / stride
    }

    /// Makes room for `needed` entries (keeping the first `used`), doubling, within the limit.
    fn reserve(
        &mut self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        used: u64,
        needed: u64,
    ) -> Result<()> {
        if needed <= self.capacity {
            return Ok(());
        }
        ctx.check_storage(self.what, needed * self.stride)?;
        let capacity = (2 * self.capacity).min(Self::limit(ctx, self.stride)).max(needed);
        let buffer = ctx.storage_zeroed(self.what, capacity * self.stride)?;
        if used > 0 {
            encoder.copy_buffer_to_buffer(&self.buffer, 0, &buffer, 0, used * self.stride);
        }
        self.buffer = buffer;
        self.capacity = capacity;
        Ok(())
    }
}

/// The host's plan and input, checked.
struct Input<'v> {
    depth: u32,
    first_dense: u32,
    coords: Vec<u32>,
    voxels: usize,
    payload: Option<&'v [AveragePayload]>,
}

/// The CPU builds' input checks, in their order (grid, plan, then per voxel: inside the grid,
/// then an acceptable payload). Duplicates are found on the GPU.
fn check_input<'v>(
    grid: &GridSpec,
    coords: impl ExactSizeIterator<Item = UVec3>,
    payload: Option<&'v [AveragePayload]>,
    options: &BuildOptions,
) -> Result<Input<'v>> {
    grid.validate().map_err(voxlod_octree::Error::from)?;
    let (depth, first_dense) = voxlod_octree::plan(grid.dims, options)?;
    let voxels = coords.len();
    let mut flat = Vec::with_capacity(3 * voxels);
    for (i, c) in coords.enumerate() {
        if !c.cmplt(grid.dims).all() {
            return Err(voxlod_octree::Error::OutOfBounds { coord: c, dims: grid.dims }.into());
        }
        if let Some(reason) = payload.and_then(|p| p[i].check()) {
            return Err(voxlod_octree::Error::InvalidPayload { coord: c, reason }.into());
        }
        flat.extend_from_slice(&c.to_array());
    }
    Ok(Input { depth, first_dense, coords: flat, voxels, payload })
}

/// The first duplicate in Morton order, as the CPU build names it (error path only).
fn first_duplicate(coords: &[u32]) -> Error {
    let mut codes: Vec<u64> =
        coords.chunks_exact(3).map(|c| morton::encode(UVec3::new(c[0], c[1], c[2]))).collect();
    codes.sort_unstable();
    match codes.windows(2).find(|w| w[0] == w[1]) {
        Some(w) => voxlod_octree::Error::DuplicateVoxel { coord: morton::decode(w[0]) }.into(),
        None => Error::Device {
            adapter: String::new(),
            during: "building an octree",
            message: "the leaves kernel reported a duplicate voxel, but there is none".into(),
        },
    }
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

    /// Records the in-place exclusive prefix sum of the `n` values of `data`; returns the
    /// buffer whose first word will be their total.
    fn scan(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        data: &wgpu::Buffer,
        n: u64,
        keep: &mut Vec<wgpu::Buffer>,
    ) -> Result<wgpu::Buffer> {
        let blocks = n.div_ceil(SCAN_BLOCK_VALUES).max(1);
        let sums = self.ctx.storage_zeroed("octree scan block sums", blocks * 4)?;
        let params = GpuOctreeParams { n: n as u32, ..Default::default() };
        self.dispatch(encoder, SCAN_BLOCK, blocks, params, &[(3, data), (4, &sums)], keep)?;
        if blocks == 1 {
            return Ok(sums);
        }
        let total = self.scan(encoder, &sums, blocks, keep)?;
        self.dispatch(
            encoder,
            SCAN_ADD,
            n.div_ceil(WORKGROUP),
            params,
            &[(3, data), (4, &sums)],
            keep,
        )?;
        keep.push(sums);
        Ok(total)
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

    /// The build (module docs: kernels).
    fn run(&self, input: Input<'_>) -> Result<GpuOctree<'a>> {
        let ctx = self.ctx;
        let Input { depth, first_dense: fd, coords, voxels, payload } = input;
        let n = voxels as u64;
        let mark_threads = 8 * n;
        if mark_threads > MAX_INVOCATIONS {
            return Err(Error::TooLarge {
                what: "octree voxels (8 mark invocations each)",
                requested: n,
                limit: MAX_INVOCATIONS / 8,
            });
        }
        let too_many = |level: u32, nodes: u64| -> Result<()> {
            if nodes >= NONE as u64 {
                return Err(voxlod_octree::Error::TooManyNodes { level, nodes }.into());
            }
            Ok(())
        };
        // The dense levels, root first.
        let mut levels = vec![GpuLevel::default(); depth as usize + 1];
        let mut next = 0u64;
        for l in (fd..=depth).rev() {
            let count = 1u64 << (3 * (depth - l));
            too_many(l, next + count)?;
            levels[l as usize] = GpuLevel {
                first: next as u32,
                count: count as u32,
                res_log2: depth - l,
                dense: 1,
                first_tile: 0,
            };
            next += count;
        }
        let dense_nodes = next;
        let mut tile_total = 0u64;
        let mut keep = Vec::new();
        let coords_buf =
            ctx.storage_init("octree voxel coordinates", bytemuck::cast_slice(&coords))?;
        let mut nodes = Growing::new(ctx, "octree nodes", 8, dense_nodes, dense_nodes + 16 * n)?;
        let mut tiles = Growing::new(ctx, "octree tiles", 12, 0, 2 * n)?;
        let table =
            |levels: &[GpuLevel]| ctx.storage_init("octree levels", bytemuck::cast_slice(levels));

        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let fill = GpuOctreeParams { n: dense_nodes as u32, extra: 0, ..Default::default() };
        self.dispatch(
            &mut encoder,
            FILL,
            dense_nodes.div_ceil(WORKGROUP),
            fill,
            &[(2, &nodes.buffer)],
            &mut keep,
        )?;
        for l in (0..fd).rev() {
            let parents = levels[l as usize + 1].count as u64;
            let flags = ctx.storage_zeroed("octree tile flags", parents * 4)?;
            let masks = ctx.storage_zeroed("octree child masks", parents * 4)?;
            let level_buf = table(&levels)?;
            let params =
                GpuOctreeParams { n: mark_threads as u32, level: l, first_dense: fd, extra: 0 };
            self.dispatch(
                &mut encoder,
                MARK,
                mark_threads.div_ceil(WORKGROUP),
                params,
                &[(1, &level_buf), (2, &nodes.buffer), (3, &coords_buf), (4, &flags), (5, &masks)],
                &mut keep,
            )?;
            let total = self.scan(&mut encoder, &flags, parents, &mut keep)?;
            ctx.submit("building an octree level", encoder)?;
            let flagged = bytemuck::pod_read_unaligned::<u32>(&ctx.read(&total, 4)?) as u64;
            keep.clear();
            let count = 8 * flagged;
            too_many(l, next + count)?;
            levels[l as usize] = GpuLevel {
                first: next as u32,
                count: count as u32,
                res_log2: depth - l,
                dense: 0,
                first_tile: tile_total as u32,
            };
            encoder = ctx.device().create_command_encoder(&Default::default());
            nodes.reserve(ctx, &mut encoder, next, next + count)?;
            tiles.reserve(ctx, &mut encoder, tile_total, tile_total + flagged)?;
            let level_buf = table(&levels)?;
            let tile_parent = ctx.storage_zeroed("octree tile parents", flagged * 4)?;
            let fill =
                GpuOctreeParams { n: count as u32, extra: next as u32, ..Default::default() };
            self.dispatch(
                &mut encoder,
                FILL,
                count.div_ceil(WORKGROUP),
                fill,
                &[(2, &nodes.buffer)],
                &mut keep,
            )?;
            let alloc = GpuOctreeParams {
                n: parents as u32,
                level: l,
                first_dense: fd,
                extra: flagged as u32,
            };
            self.dispatch(
                &mut encoder,
                ALLOCATE,
                parents.div_ceil(WORKGROUP),
                alloc,
                &[(1, &level_buf), (2, &nodes.buffer), (3, &flags), (4, &masks), (5, &tile_parent)],
                &mut keep,
            )?;
            let link = GpuOctreeParams { n: flagged as u32, level: l, first_dense: fd, extra: 0 };
            self.dispatch(
                &mut encoder,
                LINK,
                flagged.div_ceil(WORKGROUP),
                link,
                &[(1, &level_buf), (2, &nodes.buffer), (3, &tile_parent), (4, &tiles.buffer)],
                &mut keep,
            )?;
            keep.extend([flags, masks, level_buf, tile_parent]);
            next += count;
            tile_total += flagged;
        }

        // Leaves: duplicates, then payloads bottom-up.
        let level_buf = table(&levels)?;
        let leaves = levels[0].count as u64;
        let hits = ctx.storage_zeroed("octree leaf hits", leaves * 4)?;
        let duplicate = ctx.storage_zeroed("octree duplicate flag", 8)?;
        let params = GpuOctreeParams { n: n as u32, level: 0, first_dense: fd, extra: 0 };
        self.dispatch(
            &mut encoder,
            LEAVES,
            n.div_ceil(WORKGROUP),
            params,
            &[(1, &level_buf), (2, &nodes.buffer), (3, &coords_buf), (4, &hits), (5, &duplicate)],
            &mut keep,
        )?;
        let payload_buf = match payload {
            None => None,
            Some(payload) => {
                let stride = size_of::<AveragePayload>() as u64;
                let out = ctx.storage_zeroed("octree payloads", next * stride)?;
                let input =
                    ctx.storage_init("octree voxel payloads", bytemuck::cast_slice(payload))?;
                self.dispatch(
                    &mut encoder,
                    SCATTER,
                    n.div_ceil(WORKGROUP),
                    params,
                    &[
                        (1, &level_buf),
                        (2, &nodes.buffer),
                        (3, &coords_buf),
                        (4, &input),
                        (5, &out),
                    ],
                    &mut keep,
                )?;
                for l in 1..=depth {
                    let count = levels[l as usize].count as u64;
                    let p =
                        GpuOctreeParams { n: count as u32, level: l, first_dense: fd, extra: 0 };
                    self.dispatch(
                        &mut encoder,
                        PREFILTER,
                        count.div_ceil(WORKGROUP),
                        p,
                        &[(1, &level_buf), (2, &nodes.buffer), (3, &out)],
                        &mut keep,
                    )?;
                }
                keep.push(input);
                Some(out)
            }
        };
        ctx.submit("building an octree's leaves and payloads", encoder)?;
        let flags: Vec<u32> = bytemuck::pod_collect_to_vec(&ctx.read(&duplicate, 8)?);
        if flags[1] != 0 {
            return Err(Error::Device {
                adapter: ctx.info().name.clone(),
                during: "building an octree",
                message: "a voxel's leaf is missing (a child pointer on its path is NONE)".into(),
            });
        }
        if flags[0] != 0 {
            return Err(first_duplicate(&coords));
        }
        drop(keep);
        Ok(GpuOctree {
            ctx,
            depth,
            first_dense: fd,
            levels,
            node_count: next,
            tile_count: tile_total,
            nodes: nodes.buffer,
            tiles: tiles.buffer,
            payload: payload_buf,
        })
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use super::*;
    use crate::layout::assert_mirrors;

    #[test]
    fn octree_types_mirror_their_wgsl() {
        for (_, src) in KERNELS {
            assert_mirrors(
                src,
                "GpuNode",
                size_of::<GpuNode>(),
                &[("child", offset_of!(GpuNode, child)), ("mask", offset_of!(GpuNode, mask))],
            );
            assert_mirrors(
                src,
                "GpuTile",
                size_of::<GpuTile>(),
                &[("links", offset_of!(GpuTile, links))],
            );
            assert_mirrors(
                src,
                "GpuLevel",
                size_of::<GpuLevel>(),
                &[
                    ("first", offset_of!(GpuLevel, first)),
                    ("count", offset_of!(GpuLevel, count)),
                    ("res_log2", offset_of!(GpuLevel, res_log2)),
                    ("dense", offset_of!(GpuLevel, dense)),
                    ("first_tile", offset_of!(GpuLevel, first_tile)),
                ],
            );
            assert_mirrors(
                src,
                "Average",
                size_of::<AveragePayload>(),
                &[
                    ("color_alpha", offset_of!(AveragePayload, color_alpha)),
                    ("normal_alpha", offset_of!(AveragePayload, normal_alpha)),
                    ("opacity", offset_of!(AveragePayload, opacity)),
                ],
            );
            assert_mirrors(
                src,
                "Params",
                size_of::<GpuOctreeParams>(),
                &[
                    ("n", offset_of!(GpuOctreeParams, n)),
                    ("level", offset_of!(GpuOctreeParams, level)),
                    ("first_dense", offset_of!(GpuOctreeParams, first_dense)),
                    ("extra", offset_of!(GpuOctreeParams, extra)),
                ],
            );
        }
    }

    #[test]
    fn bad_input_gets_the_cpu_error_before_any_gpu_work() {
        use glam::{DVec3, Vec3};
        let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(4)).unwrap();
        let ok = AveragePayload::new(Vec3::ONE, Vec3::Z, 0.5);
        let nan = AveragePayload::new(Vec3::ONE, Vec3::Z, f32::NAN);
        let opts = BuildOptions::default();
        let cases: [(Vec<(UVec3, AveragePayload)>, BuildOptions); 4] = [
            (vec![(UVec3::ZERO, ok), (UVec3::new(0, 4, 0), ok)], opts),
            (vec![(UVec3::ZERO, ok), (UVec3::new(1, 2, 3), nan), (UVec3::splat(9), ok)], opts),
            (vec![(UVec3::ZERO, ok)], BuildOptions { depth: Some(1), dense_log2: 1 }),
            (vec![(UVec3::ZERO, ok)], BuildOptions { depth: None, dense_log2: 30 }),
        ];
        for (voxels, opts) in cases {
            let coords = voxels.iter().map(|v| v.0);
            let payload: Vec<_> = voxels.iter().map(|v| v.1).collect();
            let gpu = check_input(&grid, coords, Some(&payload), &opts).err().unwrap().to_string();
            let cpu =
                FlatOctree::build_level_by_level(grid, &voxels, &opts).unwrap_err().to_string();
            assert_eq!(gpu, cpu);
        }
        // Duplicates: named as the CPU names them (the smallest repeated Morton code).
        let coords = [3, 1, 0, 1, 1, 1, 3, 1, 0, 1, 1, 1];
        let voxels: Vec<_> = coords.chunks(3).map(|c| (UVec3::from_slice(c), ok)).collect();
        let cpu = FlatOctree::build_level_by_level(grid, &voxels, &opts).unwrap_err().to_string();
        assert_eq!(first_duplicate(&coords).to_string(), cpu);
    }
}
