//! Device buffers of a build: the octree left on the device ([`GpuOctree`]) and its
//! readback as the CPU's flat layout, and the node and tile arrays that grow by copying as
//! the sparse levels are appended.

use voxlod_octree::{AveragePayload, FlatOctree, GpuLevel, GpuNode, GpuTile};

use crate::{Context, Error, Result};

/// An octree built on the GPU and still there: the host's level table and the device
/// buffers of the flat layout ([`FlatOctree`]'s arrays, global indices).
pub struct GpuOctree<'a> {
    pub(super) ctx: &'a Context,
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

/// A device buffer that grows (by copying) as levels are appended.
pub(super) struct Growing {
    what: &'static str,
    stride: u64,
    capacity: u64,
    pub(super) buffer: wgpu::Buffer,
}

impl Growing {
    /// Room for `needed` entries (an error with the numbers if that is over the limit), and
    /// up to `hint` if the limit allows.
    pub(super) fn new(
        ctx: &Context,
        what: &'static str,
        stride: u64,
        needed: u64,
        hint: u64,
    ) -> Result<Self> {
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
    pub(super) fn reserve(
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
