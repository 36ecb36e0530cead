//! The build itself: the dense levels' table, then per sparse level mark, scan, allocate and
//! link (one readback of the level's tile count each), then leaves, scatter and the
//! bottom-up pre-filter, recorded in the order the module docs give.

use voxlod_octree::{GpuLevel, NONE};

use super::buffers::{GpuOctree, Growing};
use super::input::{Input, first_duplicate};
use super::*;

impl<'a> OctreeBuilder<'a> {
    /// Records the in-place exclusive prefix sum of the `n` values of `data`; returns the
    /// buffer whose first word will be their total.
    pub(crate) fn scan(
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

    /// The build (module docs: kernels).
    pub(super) fn run(&self, input: Input<'_>) -> Result<GpuOctree<'a>> {
        let ctx = self.ctx;
        let Input { depth, first_dense: fd, coords, voxels, payload, device } = input;
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
        let host_coords;
        let coords_buf = match device {
            Some((c, _)) => c,
            None => {
                host_coords =
                    ctx.storage_init("octree voxel coordinates", bytemuck::cast_slice(&coords))?;
                &host_coords
            }
        };
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
                &[(1, &level_buf), (2, &nodes.buffer), (3, coords_buf), (4, &flags), (5, &masks)],
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
            &[(1, &level_buf), (2, &nodes.buffer), (3, coords_buf), (4, &hits), (5, &duplicate)],
            &mut keep,
        )?;
        let host_payload;
        let payload_in = match (device, payload) {
            (Some((_, p)), _) => Some(p),
            (None, Some(payload)) => {
                host_payload =
                    ctx.storage_init("octree voxel payloads", bytemuck::cast_slice(payload))?;
                Some(&host_payload)
            }
            (None, None) => None,
        };
        let payload_buf = match payload_in {
            None => None,
            Some(input) => {
                let stride = size_of::<AveragePayload>() as u64;
                let out = ctx.storage_zeroed("octree payloads", next * stride)?;
                self.dispatch(
                    &mut encoder,
                    SCATTER,
                    n.div_ceil(WORKGROUP),
                    params,
                    &[(1, &level_buf), (2, &nodes.buffer), (3, coords_buf), (4, input), (5, &out)],
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
            if device.is_some() {
                return Err(Error::Device {
                    adapter: ctx.info().name.clone(),
                    during: "building an octree",
                    message: "the device-resident input holds a voxel twice".into(),
                });
            }
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
