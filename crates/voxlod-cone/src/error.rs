//! The error type of voxlod-cone: invalid cone, light or injection parameters, and octree
//! errors passed through. Every variant names what and where.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong when injecting light or tracing cones.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter outside its documented range (NaN, infinite, negative, …).
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's name (e.g. `aperture_deg`).
        name: &'static str,
        /// Its value, formatted.
        value: String,
        /// What the valid range is.
        reason: &'static str,
    },
    /// A per-leaf visibility list whose length does not match the octree's occupied leaves.
    #[error("visibility list has {given} entries but the octree has {expected} occupied leaves")]
    VisibilityLength {
        /// Entries given.
        given: usize,
        /// Occupied leaves of the octree.
        expected: usize,
    },
    /// A per-leaf visibility outside \[0, 1\] or NaN.
    #[error("visibility of leaf {index} (voxel {voxel:?}) is {value}, not in [0, 1]")]
    InvalidVisibility {
        /// Index in the list.
        index: usize,
        /// The leaf's voxel coordinate.
        voxel: [u32; 3],
        /// The offending value.
        value: f32,
    },
    /// A dynamic frame's transform, blend or octree build failed.
    #[error("dynamic frame: {0}")]
    Frame(voxlod_octree::Error),
    /// Building the radiance octree failed.
    #[error("building the radiance octree: {0}")]
    Octree(#[from] voxlod_octree::Error),
}

/// An [`Error::InvalidParameter`] unless `ok`.
pub(crate) fn check(ok: bool, name: &'static str, value: f32, reason: &'static str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::InvalidParameter { name, value: value.to_string(), reason })
    }
}
