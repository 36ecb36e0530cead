//! The `.vxl` container: one [`GridSpec`], one sparse [`BrickMap`] of per-voxel records of a
//! [`VxlRecord`] type, and a few named metadata strings, in a versioned, checksummed,
//! little-endian file.
//!
//! Reading never trusts the file: a truncated or corrupted file, a wrong magic, a newer version,
//! a brick table that contradicts itself or the grid, or counts that would need more bytes than
//! the file has are each an [`Error`] ([`Error::Malformed`] with the byte offset,
//! [`Error::UnsupportedVersion`], [`Error::ChecksumMismatch`], [`Error::RecordMismatch`]), never
//! a panic, and no allocation is sized by a count before that count is checked against the
//! file's length. Every field is read from bytes with `from_le_bytes`, so reading depends on
//! neither the host's byte order nor the buffer's alignment.
//!
//! # Layout (version 1)
//!
//! All integers and floats little-endian; offsets from the start of the file.
//!
//! | offset | size | field | notes |
//! |---|---|---|---|
//! | 0 | 8 | magic | `89 56 58 4C 0D 0A 1A 0A` (`\x89VXL\r\n\x1a\n`, PNG-style: catches text-mode mangling) |
//! | 8 | 4 | version `u32` | [`VERSION`]; a reader refuses newer versions |
//! | 12 | 4 | flags `u32` | no flag is defined in version 1: must be 0 |
//! | 16 | 8 | body length `u64` | bytes after the 32-byte header; must match the file |
//! | 24 | 4 | CRC-32 `u32` | CRC-32/ISO-HDLC ([`crc32`]) of the body: every byte from offset 32 on |
//! | 28 | 4 | reserved `u32` | 0 |
//! | 32 | 24 | origin `f64`×3 | [`GridSpec::origin`] |
//! | 56 | 8 | voxel size `f64` | [`GridSpec::voxel_size`] |
//! | 64 | 12 | dims `u32`×3 | [`GridSpec::dims`]; the grid must pass [`GridSpec::validate`] |
//! | 76 | 4 | record tag | [`VxlRecord::TAG`] |
//! | 80 | 4 | record size `u32` | `size_of` the record; 0 for [`Occupancy`] |
//! | 84 | 4 | metadata count `u32` | M |
//! | 88 | 8 | brick count `u64` | B |
//! | 96 | 8 | voxel count `u64` | V: occupied voxels, the sum of the masks' bit counts |
//! | 104 | … | M metadata entries | each: key length `u32`, key (UTF-8, non-empty, unique), value length `u32`, value (UTF-8) |
//! | … | 76·B | brick table | per brick: Morton code `u64`, occupancy mask `u64`×8, first value index `u32` |
//! | … | size·V | payload | the records in global Morton order, every scalar field little-endian |
//!
//! The brick table is a [`BrickMap`]'s [`BrickHeader`](crate::brickmap::BrickHeader)s without
//! their padding: Morton codes strictly increasing and inside the grid, masks non-empty with
//! no voxel outside the grid, `first` equal to the number of voxels in the bricks before.
//! The file ends exactly after the payload.

mod crc32;
mod decode;
mod encode;
mod record;
#[cfg(test)]
mod tests;

use std::path::Path;

pub use crc32::crc32;
pub use record::{Occupancy, VxlRecord, tag_name};

use crate::{BrickMap, Error, GridSpec, Result};

/// The magic bytes that open every `.vxl` file.
pub const MAGIC: [u8; 8] = *b"\x89VXL\r\n\x1a\n";
/// The format version this library writes, and the newest it reads.
pub const VERSION: u32 = 1;
/// Length of the fixed header (magic, version, flags, body length, CRC, reserved), which the
/// CRC does not cover.
pub const HEADER_LEN: usize = 32;
/// Length of one brick-table entry: Morton code, 512-bit mask, first value index.
pub const BRICK_ENTRY_LEN: usize = 8 + 64 + 4;
/// Offset of the first metadata entry: the end of the fixed-size fields.
const FIXED_END: usize = 104;

/// A decoded `.vxl` file.
#[derive(Clone, Debug)]
pub struct VxlFile<T> {
    /// Format version of the file.
    pub version: u32,
    /// The grid.
    pub grid: GridSpec,
    /// The voxels and their records; `map.dims() == grid.dims`.
    pub map: BrickMap<T>,
    /// Named metadata, in file order (keys unique).
    pub meta: Vec<(String, String)>,
}

impl<T> VxlFile<T> {
    /// Value of metadata `key`, if present.
    pub fn meta_value(&self, key: &str) -> Option<&str> {
        meta_value(&self.meta, key)
    }
}

/// What a `.vxl` file holds, read without decoding its bricks or payload (for `voxlod info`).
#[derive(Clone, Debug, PartialEq)]
pub struct VxlInfo {
    /// Format version.
    pub version: u32,
    /// Flags word (0 in version 1).
    pub flags: u32,
    /// Total file length in bytes.
    pub file_len: u64,
    /// The grid.
    pub grid: GridSpec,
    /// Tag of the record type (see [`tag_name`]).
    pub record_tag: [u8; 4],
    /// Size of one record in bytes.
    pub record_size: u32,
    /// Number of allocated bricks.
    pub brick_count: u64,
    /// Number of occupied voxels.
    pub voxel_count: u64,
    /// Named metadata, in file order.
    pub meta: Vec<(String, String)>,
    /// The CRC-32 stored in the header.
    pub checksum: u32,
    /// Whether the stored CRC-32 matches the body.
    pub checksum_ok: bool,
}

impl VxlInfo {
    /// Value of metadata `key`, if present.
    pub fn meta_value(&self, key: &str) -> Option<&str> {
        meta_value(&self.meta, key)
    }

    /// Whether the file's records are of type `T` (same tag and size).
    pub fn holds<T: VxlRecord>(&self) -> bool {
        self.record_tag == T::TAG && self.record_size as usize == size_of::<T>()
    }
}

fn meta_value<'a>(meta: &'a [(String, String)], key: &str) -> Option<&'a str> {
    meta.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

/// Encodes a grid, its brick map and metadata as `.vxl` bytes (see the [module docs](self) for
/// the layout).
///
/// Errors: the grid fails [`GridSpec::validate`] or its dims differ from the map's
/// ([`Error::InvalidGrid`]); a metadata key is empty or repeated, or a string is longer than
/// `u32::MAX` bytes ([`Error::InvalidMetadata`]).
pub fn encode<T: VxlRecord>(
    grid: &GridSpec,
    map: &BrickMap<T>,
    meta: &[(String, String)],
) -> Result<Vec<u8>> {
    encode::encode(grid, map, meta)
}

/// Writes a `.vxl` file atomically (temporary file, then rename: a failure leaves no
/// half-written file and keeps the old one).
///
/// ```
/// use glam::{DVec3, UVec3};
/// use voxlod_format::{BrickMap, GridSpec, vxl};
/// let grid = GridSpec::new(DVec3::new(-1.0, 0.0, 2.0), 0.25, UVec3::new(16, 4, 9)).unwrap();
/// let map = BrickMap::from_voxels(grid.dims, [(UVec3::new(3, 1, 8), 0.5f32)]).unwrap();
/// let meta = [("scene".to_string(), "builtin:bunny".to_string())];
/// let path = std::env::temp_dir().join("voxlod-doc-vxl-write.vxl");
/// vxl::write(&path, &grid, &map, &meta).unwrap();
///
/// let file = vxl::read::<f32>(&path).unwrap();
/// assert_eq!(file.grid, grid);
/// assert_eq!(file.map.get(UVec3::new(3, 1, 8)), Some(&0.5));
/// assert_eq!(file.meta_value("scene"), Some("builtin:bunny"));
/// // The records are typed: reading them as another type is an error.
/// assert!(vxl::read::<u32>(&path).is_err());
/// ```
pub fn write<T: VxlRecord>(
    path: impl AsRef<Path>,
    grid: &GridSpec,
    map: &BrickMap<T>,
    meta: &[(String, String)],
) -> Result<()> {
    let bytes = encode(grid, map, meta)?;
    crate::io::write_bytes_atomic(path.as_ref(), &bytes)
}

/// Decodes `.vxl` bytes holding records of type `T`; `path` only names the source in errors.
///
/// ```
/// use std::path::Path;
/// use glam::{DVec3, UVec3};
/// use voxlod_format::{BrickMap, Error, GridSpec, vxl::{self, Occupancy}};
/// let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(8)).unwrap();
/// let map = BrickMap::from_voxels(grid.dims, [(UVec3::new(1, 2, 3), Occupancy)]).unwrap();
/// let bytes = vxl::encode(&grid, &map, &[]).unwrap();
/// let file = vxl::decode::<Occupancy>(&bytes, Path::new("<memory>")).unwrap();
/// assert!(file.map.contains(UVec3::new(1, 2, 3)));
/// // A truncated file is an error naming the offset, not a panic.
/// let err = vxl::decode::<Occupancy>(&bytes[..bytes.len() - 1], Path::new("<memory>"));
/// assert!(matches!(err, Err(Error::Malformed { .. })));
/// ```
pub fn decode<T: VxlRecord>(bytes: &[u8], path: &Path) -> Result<VxlFile<T>> {
    decode::decode(bytes, path)
}

/// Reads a `.vxl` file holding records of type `T` (see [`decode`]).
pub fn read<T: VxlRecord>(path: impl AsRef<Path>) -> Result<VxlFile<T>> {
    let path = path.as_ref();
    decode(&crate::io::read_bytes(path)?, path)
}

/// Describes `.vxl` bytes without decoding the bricks or payload. A checksum mismatch is
/// reported in [`VxlInfo::checksum_ok`] rather than as an error, unless the corruption makes
/// the fixed fields or metadata unreadable (then [`Error::ChecksumMismatch`]).
pub fn decode_info(bytes: &[u8], path: &Path) -> Result<VxlInfo> {
    decode::decode_info(bytes, path)
}

/// Describes a `.vxl` file (see [`decode_info`]).
///
/// ```
/// use glam::{DVec3, UVec3};
/// use voxlod_format::{BrickMap, GridSpec, vxl};
/// let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(20)).unwrap();
/// let voxels = [(UVec3::ZERO, 1u32), (UVec3::splat(19), 2)];
/// let map = BrickMap::from_voxels(grid.dims, voxels).unwrap();
/// let path = std::env::temp_dir().join("voxlod-doc-vxl-info.vxl");
/// vxl::write(&path, &grid, &map, &[("mode".into(), "solid".into())]).unwrap();
/// let info = vxl::read_info(&path).unwrap();
/// assert_eq!((info.brick_count, info.voxel_count), (2, 2));
/// assert!(info.checksum_ok && info.holds::<u32>());
/// assert_eq!(vxl::tag_name(info.record_tag), "u32");
/// assert_eq!(info.meta_value("mode"), Some("solid"));
/// ```
pub fn read_info(path: impl AsRef<Path>) -> Result<VxlInfo> {
    let path = path.as_ref();
    decode_info(&crate::io::read_bytes(path)?, path)
}

/// The [`Error::Malformed`] of this format.
fn malformed(path: &Path, offset: usize, reason: impl Into<String>) -> Error {
    Error::Malformed {
        path: path.to_owned(),
        format: "vxl",
        offset: offset as u64,
        reason: reason.into(),
    }
}
