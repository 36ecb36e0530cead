//! Memory statistics: nodes per level and bytes by role, per occupied voxel.
//!
//! # What the neighbour links cost, against ESVO's anchor
//! ESVO (Laine & Karras 2010) spends about 1 byte of topology per voxel: one 32-bit child
//! descriptor per parent, children stored only where occupied. This layout spends, per node of a
//! sparse level, 5 bytes of topology above level 0 (`child: u32`, `mask: u8`), and **12 bytes
//! of forward links per 2×2×2 tile of every sparse level, leaves included** (`[u32; 3]`, 1.5
//! bytes per node), on the occupied nodes *and* on the nodes the backward closure and the tiles
//! add (`octree` module docs), which on surfaces are several times the occupied ones.
//! [`MemoryStats`] measures each part; `cargo bench -p voxlod-octree --bench build` prints them
//! for a sphere shell. [`crate::Topology::memory_bytes`] gives the occupied levels alone.

use crate::octree::Octree;
use crate::payload::Payload;

/// Nodes of one level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelStats {
    /// The level (0 = leaves).
    pub level: u32,
    /// Nodes per axis.
    pub resolution: u32,
    /// Stored densely.
    pub dense: bool,
    /// Stored nodes (dense: `resolution³`).
    pub nodes: u64,
    /// Nodes whose subtree holds an input voxel (from the masks; on dense levels above the
    /// finest dense one, which store no masks: nodes with a non-empty payload).
    pub occupied: u64,
}

/// Bytes of an octree by role (array lengths × element sizes; the arrays are shrunk to fit
/// after the build, so this is the heap the octree holds, up to allocator overhead).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryStats {
    /// Per level, leaves first.
    pub levels: Vec<LevelStats>,
    /// Input (occupied) voxels.
    pub occupied_voxels: u64,
    /// Child pointers and masks of the sparse levels.
    pub topology_bytes: u64,
    /// Forward neighbour links (+x, +y, +z) of the sparse levels.
    pub link_bytes: u64,
    /// Payloads of the sparse levels.
    pub payload_bytes: u64,
    /// Dense top levels: their payloads, and the finest one's child pointers and masks.
    pub dense_bytes: u64,
}

impl MemoryStats {
    /// All bytes.
    pub fn total_bytes(&self) -> u64 {
        self.topology_bytes + self.link_bytes + self.payload_bytes + self.dense_bytes
    }
    /// Bytes that grow with the content: everything but the dense top levels.
    pub fn sparse_bytes(&self) -> u64 {
        self.topology_bytes + self.link_bytes + self.payload_bytes
    }
    /// `bytes / occupied voxels` (0 for an empty octree).
    pub fn per_voxel(&self, bytes: u64) -> f64 {
        if self.occupied_voxels == 0 { 0.0 } else { bytes as f64 / self.occupied_voxels as f64 }
    }
    /// Nodes stored in the sparse levels.
    pub fn sparse_nodes(&self) -> u64 {
        self.levels.iter().filter(|l| !l.dense).map(|l| l.nodes).sum()
    }
}

impl<P: Payload> Octree<P> {
    /// Nodes per level and bytes by role ([`MemoryStats`]).
    pub fn memory_stats(&self) -> MemoryStats {
        let mut s = MemoryStats {
            levels: Vec::with_capacity(self.levels.len()),
            occupied_voxels: self.voxels,
            topology_bytes: 0,
            link_bytes: 0,
            payload_bytes: 0,
            dense_bytes: 0,
        };
        for (l, lv) in self.levels.iter().enumerate() {
            let payload = (lv.payload.len() * size_of::<P>()) as u64;
            let topology = (lv.child.len() * size_of::<u32>() + lv.mask.len()) as u64;
            if lv.dense {
                s.dense_bytes += payload + topology;
            } else {
                s.payload_bytes += payload;
                s.topology_bytes += topology;
                s.link_bytes += (lv.tile_links.len() * size_of::<[u32; 3]>()) as u64;
            }
            let occupied = if l == 0 {
                self.voxels
            } else if lv.mask.is_empty() {
                let empty = P::empty();
                lv.payload.iter().filter(|p| p.max_abs_diff(&empty) != 0.0).count() as u64
            } else {
                lv.mask.iter().filter(|&&m| m != 0).count() as u64
            };
            s.levels.push(LevelStats {
                level: l as u32,
                resolution: 1 << lv.res_log2,
                dense: lv.dense,
                nodes: lv.payload.len() as u64,
                occupied,
            });
        }
        s
    }
}
