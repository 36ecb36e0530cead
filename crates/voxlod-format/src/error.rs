//! The error type of voxlod-format.

use std::path::PathBuf;

use glam::UVec3;

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in voxlod-format. Each variant names what and where.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A grid's dimensions exceed what a format or algorithm supports.
    #[error("grid {requested:?} is too large: at most {max} voxels per axis are supported")]
    GridTooLarge {
        /// The requested dimensions.
        requested: [u64; 3],
        /// The largest supported extent per axis.
        max: u64,
    },
    /// More voxels than a brick map can address (brick offsets are `u32`).
    #[error("{voxels} voxels: a brick map addresses at most {max} (u32 offsets)")]
    TooManyVoxels {
        /// The voxels given (at least).
        voxels: u64,
        /// The most a brick map holds.
        max: u64,
    },
    /// A grid parameter is not usable (zero dimension, non-finite origin, non-positive size).
    #[error("invalid grid: {reason}")]
    InvalidGrid {
        /// What is wrong with it.
        reason: String,
    },
    /// Scene bounds that cannot be fitted with a grid (empty, non-finite, or a single point).
    #[error("cannot fit a grid to bounds min {min:?} max {max:?}: {reason}")]
    InvalidBounds {
        /// Lower corner of the bounds.
        min: [f64; 3],
        /// Upper corner of the bounds.
        max: [f64; 3],
        /// What is wrong with them.
        reason: &'static str,
    },
    /// A voxel coordinate outside the grid.
    #[error("voxel {coord} lies outside a grid of {dims} voxels")]
    OutOfBounds {
        /// The offending coordinate.
        coord: UVec3,
        /// The grid's dimensions.
        dims: UVec3,
    },
    /// The same voxel was given twice when building a brick map.
    #[error("voxel {coord} was given more than once")]
    DuplicateVoxel {
        /// The repeated coordinate.
        coord: UVec3,
    },
    /// Reading or writing a file failed.
    #[error("{op} {path}: {source}")]
    Io {
        /// What was being done ("reading", "writing", ...).
        op: &'static str,
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A file's content is malformed: truncated, corrupted or of an unknown kind.
    #[error("{path}: {format} file is malformed at byte {offset}: {reason}")]
    Malformed {
        /// The file (or `<memory>` for byte slices).
        path: PathBuf,
        /// Which format ("vxl", "binvox").
        format: &'static str,
        /// Byte offset where the problem was found.
        offset: u64,
        /// What is wrong.
        reason: String,
    },
    /// A file written by a newer version of this library.
    #[error(
        "{path}: {format} version {found} is newer than the newest this library reads ({supported})"
    )]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// Which format.
        format: &'static str,
        /// Version found in the file.
        found: u32,
        /// Newest version supported.
        supported: u32,
    },
    /// A `.vxl` file holds records of another type than the one asked for.
    #[error(
        "{path}: holds {found} records of {found_size} bytes, not the requested {expected} records of {expected_size} bytes"
    )]
    RecordMismatch {
        /// The file.
        path: PathBuf,
        /// Tag of the requested record type (see `vxl::tag_name`).
        expected: String,
        /// Size in bytes of the requested record type.
        expected_size: u32,
        /// Tag found in the file.
        found: String,
        /// Record size found in the file.
        found_size: u32,
    },
    /// Metadata that cannot be stored in a `.vxl` file (empty or repeated key, too long).
    #[error("metadata key {key:?}: {reason}")]
    InvalidMetadata {
        /// The offending key.
        key: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// Data that a file format cannot hold: a dimension, count or value beyond what the format
    /// stores. Nothing is written.
    #[error("{format} cannot hold {what}: {reason}")]
    Unrepresentable {
        /// Which format ("vol", "vox", ...).
        format: &'static str,
        /// What was refused (with where it is, e.g. the voxel).
        what: String,
        /// The format's limit.
        reason: String,
    },
    /// A well-formed file that uses a feature of its format this library does not read.
    #[error("{path}: {format} file at byte {offset} uses an unsupported feature: {feature}")]
    Unsupported {
        /// The file (or `<memory>` for byte slices).
        path: PathBuf,
        /// Which format.
        format: &'static str,
        /// Byte offset of the feature.
        offset: u64,
        /// What it is.
        feature: String,
    },
    /// The stored checksum does not match the content.
    #[error(
        "{path}: checksum mismatch (stored {stored:#010x}, computed {computed:#010x}): the file is corrupted"
    )]
    ChecksumMismatch {
        /// The file.
        path: PathBuf,
        /// Checksum stored in the file.
        stored: u32,
        /// Checksum computed over the content.
        computed: u32,
    },
}
