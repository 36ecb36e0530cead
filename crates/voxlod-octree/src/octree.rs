//! The [`Octree`] type, its [`BuildOptions`] and read access to its levels ([`LevelView`]).
//!
//! # Layout (levels are numbered from the leaves: level 0 holds voxels, level `depth` the root)
//! - **Dense levels** `first_dense..=depth` (resolution `≤ 2^dense_log2` per axis, the paper's
//!   64³ by default) store every node: an array of `r³` payloads indexed by the node's Morton
//!   code. No pointers, no neighbour links: a neighbour is an index computation. Only the finest
//!   dense level also stores child pointers and masks, the entry points into the sparse levels.
//! - **Sparse levels** `0..first_dense` store 2×2×2 **node tiles** (GigaVoxels; the paper's
//!   `atomicAdd(allocator, 8)`): a parent's `child` pointer is the index of its tile's first node,
//!   the child in octant `x + 2y + 4z` is at `child + octant`. Tiles are laid out in Morton order
//!   of their parents, so each level's nodes are in Morton order.
//! - Per sparse node: payload, `child: u32` (or [`NONE`]) and `mask: u8` (bit `k`: child `k`'s
//!   subtree holds an input voxel) above level 0.
//! - Per sparse **tile**: three forward neighbour links `[u32; 3]`: for +x, +y, +z, the index of
//!   the first node of the tile one step along that axis at the same level, or [`NONE`]. A
//!   node's +a neighbour follows ([`LevelView::neighbour`]): node `8t + k` whose `k` has the
//!   a-bit clear has it in its own tile (`k | bit`); otherwise it is child `k & !bit` of the
//!   neighbour tile. Three `u32` per tile carry what three per node would, at an eighth of the
//!   bytes.
//!
//! # Which nodes exist (the paper's §4.4, made precise)
//! Let `O_l` be the occupied nodes of level `l` (leaves given as input, and every ancestor of
//! one). Sampling rounds a position down to the node `b` whose centre is the lower corner of the
//! interpolation cell and reaches the other seven corners `b + e`, `e ∈ {0,1}³`, by forward
//! links. So every sparse level holds the **backward closure** `N_l = { o − d : o ∈ O_l,
//! d ∈ {0,1}³, o − d ≥ 0 }` (the paper's "all 8 backward neighbours", created with empty payload),
//! then completes every tile. Consequences, all checked by [`Octree::validate`]:
//! 1. if any corner of an interpolation cell is occupied, its lower corner `b` exists, and so does
//!    every node on a monotone path from `b` to that corner (they are backward neighbours of it),
//!    so the x-then-y-then-z hops of the sampler find it; a missing node is empty space;
//! 2. the parent of a node of `N_l` lies in `N_{l+1}` (a backward neighbour of the occupied
//!    parent), so every node is reachable from the root;
//! 3. nodes that are not occupied have the empty payload.
//!
//! The closure is taken towards lower coordinates, so it never leaves the `2^depth` cube.

use glam::UVec3;
use voxlod_format::GridSpec;

use crate::payload::Payload;

/// "No node": an absent child tile or neighbour.
pub const NONE: u32 = u32::MAX;

/// Deepest supported octree: 21 levels below the root, what a 63-bit Morton code addresses.
pub const MAX_DEPTH: u32 = voxlod_format::morton::BITS_PER_AXIS;

/// Largest `log2` resolution of the finest dense level: 256³ nodes.
pub const MAX_DENSE_LOG2: u32 = 8;

/// How to build an octree. `Default` is the paper's choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// Levels below the root. `None`: the smallest depth whose `2^depth` cube holds the grid.
    /// A larger depth is allowed (the virtual resolution then exceeds the grid); at most
    /// [`MAX_DEPTH`].
    pub depth: Option<u32>,
    /// Levels whose resolution is at most `2^dense_log2` per axis are stored densely (default 6:
    /// 64³, the paper's trade-off). Dense levels cost `(8/7)·8^dense_log2` payloads whatever the
    /// scene holds, and save the pointer descent for coarse samples; at most [`MAX_DENSE_LOG2`].
    /// 0 stores only the root densely.
    pub dense_log2: u32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self { depth: None, dense_log2: 6 }
    }
}

/// One level's storage (struct of arrays).
#[derive(Clone, Debug)]
pub(crate) struct Level<P> {
    /// `log2` of the resolution per axis.
    pub res_log2: u32,
    /// Stored densely (every node, indexed by Morton code).
    pub dense: bool,
    /// One payload per node.
    pub payload: Vec<P>,
    /// Child tile per node; empty for level 0 and for dense levels above the finest one.
    pub child: Vec<u32>,
    /// Occupied-children mask per node, alongside `child`.
    pub mask: Vec<u8>,
    /// +x, +y, +z neighbour tile (index of its first node, or [`NONE`]) per tile of 8 nodes;
    /// sparse levels only.
    pub tile_links: Vec<[u32; 3]>,
}

/// A sparse voxel octree with dense top levels and forward neighbour links (module docs),
/// generic over its node [`Payload`].
#[derive(Clone, Debug)]
pub struct Octree<P> {
    pub(crate) grid: GridSpec,
    pub(crate) depth: u32,
    pub(crate) first_dense: u32,
    pub(crate) voxels: u64,
    /// Indexed by level, 0 = leaves.
    pub(crate) levels: Vec<Level<P>>,
}

/// Read access to one level's arrays.
#[derive(Clone, Copy, Debug)]
pub struct LevelView<'a, P> {
    /// The level (0 = leaves).
    pub level: u32,
    /// Nodes per axis at this level: `2^(depth − level)`.
    pub resolution: u32,
    /// Whether every node is stored (indexed by Morton code) rather than sparse tiles.
    pub dense: bool,
    /// Payload per node.
    pub payload: &'a [P],
    /// Child tile index per node ([`NONE`] if none); empty where children are implicit (dense
    /// levels above the finest dense one) or absent (level 0).
    pub child: &'a [u32],
    /// Occupied-children mask per node, alongside `child`.
    pub mask: &'a [u8],
    /// Per 2×2×2 tile (nodes `8t..8t + 8`) of a sparse level: the first node of the +x, +y, +z
    /// neighbour tile ([`NONE`] if none); empty for dense levels. Read a node's neighbour with
    /// [`LevelView::neighbour`].
    pub tile_links: &'a [[u32; 3]],
}

impl<P> LevelView<'_, P> {
    /// Index of the node one step along `axis` (0: +x, 1: +y, 2: +z) from node `node` of this
    /// level, or `None` if that node does not exist (outside the cube, or not stored in a sparse
    /// level), `node` is not a node of this level, or `axis > 2`. Sparse levels answer from the
    /// tile links (module docs), dense levels by a Morton-code step.
    pub fn neighbour(&self, node: u32, axis: usize) -> Option<u32> {
        if axis > 2 || node as usize >= self.payload.len() {
            return None;
        }
        let n = if self.dense {
            let res_log2 = self.resolution.trailing_zeros();
            voxlod_format::morton::step_up(node as u64, axis, res_log2).map_or(NONE, |c| c as u32)
        } else {
            sparse_neighbour(self.tile_links, node, axis)
        };
        (n != NONE).then_some(n)
    }
}

/// The +`axis` neighbour of `node` in a sparse level with these tile links ([`NONE`] if none).
/// `node` must be a node of the level and `axis < 3`.
#[inline]
pub(crate) fn sparse_neighbour(tile_links: &[[u32; 3]], node: u32, axis: usize) -> u32 {
    let bit = 1u32 << axis;
    if node & bit == 0 {
        return node | bit;
    }
    let t = tile_links[(node >> 3) as usize][axis];
    if t == NONE { NONE } else { t | (node & 7 & !bit) }
}

impl<P: Payload> Octree<P> {
    /// The grid the octree was built over (world placement of level-0 voxels).
    pub fn grid(&self) -> &GridSpec {
        &self.grid
    }
    /// Levels below the root; the leaves' virtual resolution is `2^depth` per axis.
    pub fn depth(&self) -> u32 {
        self.depth
    }
    /// The finest densely stored level: levels `first_dense()..=depth()` are dense.
    pub fn first_dense(&self) -> u32 {
        self.first_dense
    }
    /// Number of input (occupied) voxels.
    pub fn voxel_count(&self) -> u64 {
        self.voxels
    }
    /// Whether no voxel is occupied.
    pub fn is_empty(&self) -> bool {
        self.voxels == 0
    }
    /// The arrays of `level` (0 = leaves). Panics if `level > depth()`.
    pub fn level(&self, level: u32) -> LevelView<'_, P> {
        let l = &self.levels[level as usize];
        LevelView {
            level,
            resolution: 1 << l.res_log2,
            dense: l.dense,
            payload: &l.payload,
            child: &l.child,
            mask: &l.mask,
            tile_links: &l.tile_links,
        }
    }

    /// Morton codes (at their level's resolution) of the nodes of `level`, in storage order,
    /// derived from the child pointers top-down (the octree stores no coordinates). Strictly
    /// increasing for a valid octree. Panics if `level > depth()`.
    pub fn node_codes(&self, level: u32) -> Vec<u64> {
        let count = |l: u32| self.levels[l as usize].payload.len();
        if level >= self.first_dense {
            return (0..count(level) as u64).collect();
        }
        let mut codes: Vec<u64> = (0..count(self.first_dense) as u64).collect();
        for l in (level..self.first_dense).rev() {
            let parent = &self.levels[l as usize + 1];
            let mut next = vec![0u64; count(l)];
            for (p, &c) in parent.child.iter().enumerate() {
                if c != NONE {
                    for k in 0..8u64 {
                        if let Some(slot) = next.get_mut(c as usize + k as usize) {
                            *slot = codes[p] << 3 | k;
                        }
                    }
                }
            }
            codes = next;
        }
        codes
    }

    /// Node coordinates of `level` in storage order (see [`Octree::node_codes`]).
    pub fn node_coords(&self, level: u32) -> Vec<UVec3> {
        self.node_codes(level).into_iter().map(voxlod_format::morton::decode).collect()
    }
}
