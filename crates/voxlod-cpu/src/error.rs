//! The error type of voxlod-cpu.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in the CPU references.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The scene is invalid (non-finite vertex, dangling index, …).
    #[error(transparent)]
    Scene(#[from] voxlod_scene::Error),
    /// A grid or format problem.
    #[error(transparent)]
    Format(#[from] voxlod_format::Error),
    /// An octree or voxel-cache problem (voxlod-octree).
    #[error(transparent)]
    Octree(#[from] voxlod_octree::Error),
    /// A scene's moving object cannot be cached or posed.
    #[error("dynamic object '{object}': {reason}")]
    Dynamic {
        /// The object.
        object: String,
        /// What is wrong.
        reason: String,
    },
    /// A grid whose voxelization would not fit in memory, with the estimate.
    #[error(
        "a {dims:?} grid needs about {estimated_bytes} bytes for this voxelization, over the limit of {limit_bytes} bytes"
    )]
    OutOfMemory {
        /// Grid dimensions.
        dims: [u32; 3],
        /// Estimated bytes.
        estimated_bytes: u64,
        /// The limit in force.
        limit_bytes: u64,
    },
    /// A parameter out of its valid range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: String,
        /// The valid range.
        reason: String,
    },
}
