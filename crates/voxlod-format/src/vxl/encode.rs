//! Writing the `.vxl` layout (see the module docs of [`crate::vxl`]).

use std::collections::HashSet;

use super::record::{convert_le, layout_ok};
use super::{BRICK_ENTRY_LEN, FIXED_END, HEADER_LEN, MAGIC, VERSION, VxlRecord, crc32};
use crate::{BrickMap, Error, GridSpec, Result};

pub(super) fn encode<T: VxlRecord>(
    grid: &GridSpec,
    map: &BrickMap<T>,
    meta: &[(String, String)],
) -> Result<Vec<u8>> {
    const { assert!(layout_ok::<T>(), "VxlRecord::FIELD_WIDTHS does not describe the record") };
    grid.validate()?;
    if map.dims() != grid.dims {
        return Err(Error::InvalidGrid {
            reason: format!("brick map dims {} differ from grid dims {}", map.dims(), grid.dims),
        });
    }
    check_meta(meta)?;

    let record_size = size_of::<T>();
    let meta_len: usize = meta.iter().map(|(k, v)| 8 + k.len() + v.len()).sum();
    let total =
        FIXED_END + meta_len + map.bricks().len() * BRICK_ENTRY_LEN + map.len() * record_size;
    let mut out = Vec::with_capacity(total);

    // Header; the CRC is filled in last.
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes()); // flags
    out.extend_from_slice(&((total - HEADER_LEN) as u64).to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes()); // CRC placeholder
    out.extend_from_slice(&0u32.to_le_bytes()); // reserved

    for v in grid.origin.to_array() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&grid.voxel_size.to_le_bytes());
    for d in grid.dims.to_array() {
        out.extend_from_slice(&d.to_le_bytes());
    }
    out.extend_from_slice(&T::TAG);
    out.extend_from_slice(&(record_size as u32).to_le_bytes());
    out.extend_from_slice(&(meta.len() as u32).to_le_bytes());
    out.extend_from_slice(&(map.bricks().len() as u64).to_le_bytes());
    out.extend_from_slice(&(map.len() as u64).to_le_bytes());
    debug_assert_eq!(out.len(), FIXED_END);

    for (k, v) in meta {
        for s in [k, v] {
            out.extend_from_slice(&(s.len() as u32).to_le_bytes());
            out.extend_from_slice(s.as_bytes());
        }
    }
    for b in map.bricks() {
        out.extend_from_slice(&b.morton.to_le_bytes());
        for w in b.mask {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.extend_from_slice(&b.first.to_le_bytes());
    }
    let payload = out.len();
    out.extend_from_slice(bytemuck::cast_slice(map.values()));
    convert_le(&mut out[payload..], T::FIELD_WIDTHS);
    debug_assert_eq!(out.len(), total);

    let crc = crc32(&out[HEADER_LEN..]);
    out[24..28].copy_from_slice(&crc.to_le_bytes());
    Ok(out)
}

/// Keys non-empty and unique; every string's length fits the `u32` length field.
fn check_meta(meta: &[(String, String)]) -> Result<()> {
    let mut seen = HashSet::new();
    for (k, v) in meta {
        let bad = |reason| Err(Error::InvalidMetadata { key: k.clone(), reason });
        if k.is_empty() {
            return bad("keys must not be empty");
        }
        if !seen.insert(k.as_str()) {
            return bad("the key is given more than once");
        }
        if k.len() > u32::MAX as usize || v.len() > u32::MAX as usize {
            return bad("keys and values must be shorter than 4 GiB");
        }
    }
    Ok(())
}
