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
    /// The grid specification is invalid, or a voxel cache file could not be read or written.
    #[error(transparent)]
    Grid(#[from] voxlod_format::Error),
    /// An object's voxel cache would need more voxels along an axis than its packed positions
    /// hold ([`crate::dynamic::MAX_CACHE_DIM`], 10 bits per axis).
    #[error(
        "object '{object}': its voxel cache needs {dims:?} voxels, more than {max} along an axis (positions pack 10 bits per axis): use a coarser world grid or split the object"
    )]
    CacheTooLarge {
        /// The object.
        object: String,
        /// Voxels the cache would need per axis.
        dims: [u64; 3],
        /// The most per axis.
        max: u32,
    },
    /// A voxel cache is inconsistent (a loaded file, or arrays of different lengths).
    #[error("voxel cache '{object}': {reason}")]
    InvalidCache {
        /// The object.
        object: String,
        /// What is wrong.
        reason: String,
    },
    /// A frame's object-to-world matrix is not a rotation and translation at the cache's scale:
    /// voxel transformation cannot scale or shear voxels (Yalçıner and Sahillioğlu 2020, §6).
    #[error(
        "object '{object}', matrix {matrix}: not rigid at the cache's scale {expected_scale}: column scales {scales:?}, largest column cosine {shear:.2e} (tolerance {tolerance:e}); scaling and shearing cached voxels is not supported"
    )]
    NotRigid {
        /// The object.
        object: String,
        /// Which matrix (0 for a rigid object, the joint for a skinned one).
        matrix: usize,
        /// Lengths of the matrix's three linear columns.
        scales: [f64; 3],
        /// Largest |cosine| between two columns (0 without shear).
        shear: f64,
        /// The scale the cache was built for.
        expected_scale: f64,
        /// Relative tolerance.
        tolerance: f64,
    },
    /// An object's cache was built for another world voxel size.
    #[error(
        "object '{object}': its cached voxels are {cache_voxel} world units, the world grid's are {world_voxel}: build the cache for this grid"
    )]
    CacheResolution {
        /// The object.
        object: String,
        /// A cached voxel's edge in world units.
        cache_voxel: f64,
        /// The world grid's voxel edge.
        world_voxel: f64,
    },
    /// A frame's matrix has a NaN or infinite entry, or a skinned object got the wrong number
    /// of joint matrices.
    #[error("object '{object}': {reason}")]
    InvalidPlacement {
        /// The object.
        object: String,
        /// What is wrong.
        reason: String,
    },
    /// A frame would sum more contributions than the fixed-point blend keeps exact.
    #[error(
        "a frame of {contributions} contributions exceeds the {max} the fixed-point blend sums exactly"
    )]
    FrameTooLarge {
        /// Contributions of the frame (voxels × 8 for the 8-neighbour filter).
        contributions: u64,
        /// The most.
        max: u64,
    },
    /// An option is out of its range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// The option.
        name: &'static str,
        /// Its value.
        value: String,
        /// The valid range.
        reason: &'static str,
    },
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
