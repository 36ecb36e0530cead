//! Reading the `.vxl` layout (see the module docs of [`crate::vxl`]). Every count is checked
//! against the bytes present before anything is allocated from it.

use std::collections::HashSet;
use std::path::Path;

use glam::{DVec3, UVec3};

use super::record::{convert_le, layout_ok, tag_name};
use super::{
    BRICK_ENTRY_LEN, FIXED_END, HEADER_LEN, MAGIC, VERSION, VxlFile, VxlInfo, VxlRecord, crc32,
    malformed,
};
use crate::brickmap::{BRICK_EDGE, BRICK_VOXELS, BrickHeader, check_bricks};
use crate::{BrickMap, Error, GridSpec, Result};

/// Offsets of the count fields, for error messages.
const BRICK_COUNT_AT: usize = 88;
const VOXEL_COUNT_AT: usize = 96;

/// A bounds-checked little-endian reader over the whole file.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    path: &'a Path,
}

impl<'a> Cursor<'a> {
    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        let rest = self.remaining();
        if n > rest {
            return Err(malformed(
                self.path,
                self.pos,
                format!("{what} needs {n} bytes but only {rest} remain"),
            ));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N]> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N, what)?);
        Ok(a)
    }

    fn u32(&mut self, what: &str) -> Result<u32> {
        self.array(what).map(u32::from_le_bytes)
    }

    fn u64(&mut self, what: &str) -> Result<u64> {
        self.array(what).map(u64::from_le_bytes)
    }

    fn f64(&mut self, what: &str) -> Result<f64> {
        self.array(what).map(f64::from_le_bytes)
    }

    /// A `u32` length, then that many bytes of UTF-8.
    fn string(&mut self, what: &str) -> Result<String> {
        let len = self.u32(what)? as usize;
        let at = self.pos;
        let bytes = self.take(len, what)?;
        String::from_utf8(bytes.to_vec()).map_err(|e| {
            malformed(self.path, at + e.utf8_error().valid_up_to(), format!("{what} is not UTF-8"))
        })
    }
}

/// The 32-byte header, checked: magic, version, flags, body length, reserved word.
struct Header {
    version: u32,
    flags: u32,
    checksum: u32,
}

fn parse_header(bytes: &[u8], path: &Path) -> Result<Header> {
    let n = bytes.len().min(MAGIC.len());
    if let Some(i) = (0..n).find(|&i| bytes[i] != MAGIC[i]) {
        return Err(malformed(path, i, "not a .vxl file: wrong magic bytes"));
    }
    if n < MAGIC.len() {
        return Err(malformed(path, n, "truncated inside the magic bytes"));
    }
    let mut c = Cursor { bytes, pos: MAGIC.len(), path };
    let version = c.u32("the version")?;
    if version > VERSION {
        return Err(Error::UnsupportedVersion {
            path: path.to_owned(),
            format: "vxl",
            found: version,
            supported: VERSION,
        });
    }
    if version == 0 {
        return Err(malformed(path, 8, "version 0 does not exist"));
    }
    let flags = c.u32("the flags")?;
    if flags != 0 {
        return Err(malformed(path, 12, format!("unknown flags {flags:#x}")));
    }
    let body_len = c.u64("the body length")?;
    let checksum = c.u32("the checksum")?;
    if c.u32("the reserved word")? != 0 {
        return Err(malformed(path, 28, "the reserved header word is not zero"));
    }
    let actual = (bytes.len() - HEADER_LEN) as u64;
    if body_len > actual {
        return Err(malformed(
            path,
            bytes.len(),
            format!(
                "truncated: the header announces {body_len} bytes after it, the file has {actual}"
            ),
        ));
    }
    if body_len < actual {
        return Err(malformed(
            path,
            HEADER_LEN + body_len as usize,
            format!("{} unexpected bytes after the end of the file", actual - body_len),
        ));
    }
    Ok(Header { version, flags, checksum })
}

/// The fixed-size fields and the metadata.
struct Front {
    grid: GridSpec,
    tag: [u8; 4],
    record_size: u32,
    brick_count: u64,
    value_count: u64,
    meta: Vec<(String, String)>,
    /// Offset of the brick table.
    end: usize,
}

fn parse_front(bytes: &[u8], path: &Path) -> Result<Front> {
    let mut c = Cursor { bytes, pos: HEADER_LEN, path };
    let origin = DVec3::new(c.f64("the origin")?, c.f64("the origin")?, c.f64("the origin")?);
    let voxel_size = c.f64("the voxel size")?;
    let dims = UVec3::new(c.u32("the dims")?, c.u32("the dims")?, c.u32("the dims")?);
    let grid = GridSpec::new(origin, voxel_size, dims)
        .map_err(|e| malformed(path, HEADER_LEN, format!("bad grid: {e}")))?;
    let tag = c.array("the record tag")?;
    let record_size = c.u32("the record size")?;
    let meta_count = c.u32("the metadata count")? as usize;
    let brick_count = c.u64("the brick count")?;
    let value_count = c.u64("the voxel count")?;
    debug_assert_eq!(c.pos, FIXED_END);

    // Each entry takes at least its two length fields.
    if meta_count > c.remaining() / 8 {
        return Err(malformed(
            path,
            84,
            format!("{meta_count} metadata entries cannot fit in the {} bytes left", c.remaining()),
        ));
    }
    let mut meta = Vec::with_capacity(meta_count);
    let mut seen = HashSet::new();
    for _ in 0..meta_count {
        let at = c.pos;
        let key = c.string("a metadata key")?;
        let value = c.string("a metadata value")?;
        if key.is_empty() {
            return Err(malformed(path, at, "empty metadata key"));
        }
        if !seen.insert(key.clone()) {
            return Err(malformed(path, at, format!("metadata key {key:?} repeated")));
        }
        meta.push((key, value));
    }
    Ok(Front { grid, tag, record_size, brick_count, value_count, meta, end: c.pos })
}

/// The brick table and payload sizes that the counts imply must fill the rest of the file
/// exactly, and the counts must be possible for the grid.
fn check_sizes(front: &Front, bytes: &[u8], path: &Path) -> Result<()> {
    let rest = (bytes.len() - front.end) as u64;
    let size = front.record_size as u64;
    let need = front
        .brick_count
        .checked_mul(BRICK_ENTRY_LEN as u64)
        .and_then(|b| front.value_count.checked_mul(size).and_then(|p| b.checked_add(p)));
    if need != Some(rest) {
        return Err(malformed(
            path,
            BRICK_COUNT_AT,
            format!(
                "{} bricks and {} records of {size} bytes do not fill the {rest} bytes after the \
                 metadata",
                front.brick_count, front.value_count
            ),
        ));
    }
    let grid_bricks = ((front.grid.dims + (BRICK_EDGE - 1)) / BRICK_EDGE).as_u64vec3();
    if front.brick_count > grid_bricks.element_product() {
        return Err(malformed(
            path,
            BRICK_COUNT_AT,
            format!("{} bricks cannot fit a grid of {grid_bricks} bricks", front.brick_count),
        ));
    }
    // Bounded: brick_count * 76 <= file length.
    if front.value_count > front.brick_count * BRICK_VOXELS as u64 {
        return Err(malformed(
            path,
            VOXEL_COUNT_AT,
            format!("{} voxels cannot fit in {} bricks", front.value_count, front.brick_count),
        ));
    }
    Ok(())
}

pub(super) fn decode<T: VxlRecord>(bytes: &[u8], path: &Path) -> Result<VxlFile<T>> {
    const { assert!(layout_ok::<T>(), "VxlRecord::FIELD_WIDTHS does not describe the record") };
    let header = parse_header(bytes, path)?;
    let computed = crc32(&bytes[HEADER_LEN..]);
    if computed != header.checksum {
        return Err(Error::ChecksumMismatch {
            path: path.to_owned(),
            stored: header.checksum,
            computed,
        });
    }
    let front = parse_front(bytes, path)?;
    if front.tag != T::TAG || front.record_size as usize != size_of::<T>() {
        return Err(Error::RecordMismatch {
            path: path.to_owned(),
            expected: tag_name(T::TAG),
            expected_size: size_of::<T>() as u32,
            found: tag_name(front.tag),
            found_size: front.record_size,
        });
    }
    check_sizes(&front, bytes, path)?;

    let mut c = Cursor { bytes, pos: front.end, path };
    let mut bricks = Vec::with_capacity(front.brick_count as usize);
    for _ in 0..front.brick_count {
        let morton = c.u64("a brick")?;
        let mut mask = [0u64; 8];
        for w in &mut mask {
            *w = c.u64("a brick")?;
        }
        let first = c.u32("a brick")?;
        bricks.push(BrickHeader { morton, mask, first, _pad: 0 });
    }
    let dims = front.grid.dims;
    let count = check_bricks(dims, &bricks).map_err(|(i, e)| {
        malformed(path, front.end + i * BRICK_ENTRY_LEN, format!("brick table: {e}"))
    })?;
    if count as u64 != front.value_count {
        return Err(malformed(
            path,
            VOXEL_COUNT_AT,
            format!(
                "voxel count {} differs from the {count} voxels of the brick masks",
                front.value_count
            ),
        ));
    }

    let payload = c.take(count * size_of::<T>(), "the payload")?;
    let mut values = vec![T::zeroed(); count];
    let dst: &mut [u8] = bytemuck::cast_slice_mut(&mut values);
    dst.copy_from_slice(payload);
    convert_le(dst, T::FIELD_WIDTHS);
    Ok(VxlFile {
        version: header.version,
        grid: front.grid,
        map: BrickMap::from_checked_parts(dims, bricks, values),
        meta: front.meta,
    })
}

pub(super) fn decode_info(bytes: &[u8], path: &Path) -> Result<VxlInfo> {
    let header = parse_header(bytes, path)?;
    let computed = crc32(&bytes[HEADER_LEN..]);
    let checksum_ok = computed == header.checksum;
    let front = parse_front(bytes, path).and_then(|f| check_sizes(&f, bytes, path).map(|()| f));
    let front = match front {
        Ok(f) => f,
        // Corruption explains the inconsistency better than the field it happened to hit.
        Err(_) if !checksum_ok => {
            return Err(Error::ChecksumMismatch {
                path: path.to_owned(),
                stored: header.checksum,
                computed,
            });
        }
        Err(e) => return Err(e),
    };
    Ok(VxlInfo {
        version: header.version,
        flags: header.flags,
        file_len: bytes.len() as u64,
        grid: front.grid,
        record_tag: front.tag,
        record_size: front.record_size,
        brick_count: front.brick_count,
        voxel_count: front.value_count,
        meta: front.meta,
        checksum: header.checksum,
        checksum_ok,
    })
}
