//! The error type of voxlod-octree: bad input (too deep, out of range, duplicate, non-finite
//! payload) and broken invariants found by [`crate::Octree::validate`]. Every variant names what
//! and where.

use glam::UVec3;

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong when building or checking an octree.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The requested depth exceeds what 63-bit Morton codes address (21 levels below the root).
    #[error("octree depth {requested} is too deep: at most {max} levels below the root")]
    TooDeep {
        /// The requested depth.
        requested: u32,
        /// The deepest supported octree.
        max: u32,
    },
    /// The grid does not fit in the `2^depth` cube of the requested depth.
    #[error("grid of {dims} voxels does not fit in an octree of depth {depth} ({res}³ voxels)")]
    GridDoesNotFit {
        /// Grid dimensions.
        dims: UVec3,
        /// The requested depth.
        depth: u32,
        /// `2^depth`.
        res: u32,
    },
    /// The dense top levels asked for would not fit in memory.
    #[error(
        "dense top levels down to {requested_log2}: ({res}³ nodes) exceed the supported 2^{max_log2} per axis"
    )]
    DenseTooLarge {
        /// Requested `log2` of the finest dense level's resolution.
        requested_log2: u32,
        /// `2^requested_log2`.
        res: u64,
        /// Largest supported `log2`.
        max_log2: u32,
    },
    /// A voxel coordinate outside the grid.
    #[error("voxel {coord} lies outside the grid of {dims} voxels")]
    OutOfBounds {
        /// The offending coordinate.
        coord: UVec3,
        /// The grid's dimensions.
        dims: UVec3,
    },
    /// The same voxel was given twice.
    #[error("voxel {coord} was given more than once")]
    DuplicateVoxel {
        /// The repeated coordinate.
        coord: UVec3,
    },
    /// Voxels given to a sorted entry point are out of Morton order.
    #[error("voxel {coord} (Morton code {code}) is out of Morton order")]
    OutOfOrder {
        /// The voxel that breaks the order.
        coord: UVec3,
        /// Its Morton code.
        code: u64,
    },
    /// A voxel's payload cannot be used (NaN or infinite value, opacity outside \[0, 1\]).
    #[error("voxel {coord}: invalid payload: {reason}")]
    InvalidPayload {
        /// The voxel.
        coord: UVec3,
        /// What is wrong with its payload.
        reason: &'static str,
    },
    /// [`crate::Octree::from_topology`] was given a different number of payloads than the
    /// topology has voxels.
    #[error("{payloads} payloads given for a topology of {voxels} voxels")]
    PayloadCount {
        /// Voxels in the topology.
        voxels: u64,
        /// Payloads given.
        payloads: u64,
    },
    /// A level would hold more nodes than a `u32` node index addresses.
    #[error("level {level} would hold {nodes} nodes, more than 32-bit node indices address")]
    TooManyNodes {
        /// The level (0 = leaves).
        level: u32,
        /// Nodes it would hold.
        nodes: u64,
    },
    /// The grid specification is invalid.
    #[error(transparent)]
    Grid(#[from] voxlod_format::Error),
    /// A structural invariant does not hold (found by [`crate::Octree::validate`]).
    #[error("octree invariant broken at level {level}, node {node}: {reason}")]
    Invalid {
        /// The level (0 = leaves).
        level: u32,
        /// Index of the node in its level's arrays.
        node: u64,
        /// Which invariant and how it fails.
        reason: String,
    },
}
