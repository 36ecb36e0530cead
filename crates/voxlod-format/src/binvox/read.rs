//! Reading binvox: the header and the run-length data, each checked as it is read.

use std::path::Path;

use glam::{DVec3, UVec3};

use super::{BinvoxHeader, MAX_VERSION, malformed};
use crate::{Error, GridSpec, Result};

/// The header must end (with its `data` line) within this many bytes.
const MAX_HEADER_LEN: usize = 4096;

/// Parses the header; returns it, its grid, and the offset of the first run.
pub(super) fn parse_header(bytes: &[u8], path: &Path) -> Result<(BinvoxHeader, GridSpec, usize)> {
    let mut pos = 0;
    let mut next_line = |what: &str| -> Result<(usize, &str)> {
        let start = pos;
        let window = &bytes[start..bytes.len().min(MAX_HEADER_LEN)];
        let Some(len) = window.iter().position(|&b| b == b'\n') else {
            let reason = if bytes.len() <= MAX_HEADER_LEN {
                format!("truncated header: no end of line where {what} should be")
            } else {
                format!(
                    "the header does not end within {MAX_HEADER_LEN} bytes (looking for {what})"
                )
            };
            return Err(malformed(path, start, reason));
        };
        pos = start + len + 1;
        let line = &window[..len];
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        let text = std::str::from_utf8(line)
            .map_err(|_| malformed(path, start, format!("{what} is not ASCII text")))?;
        Ok((start, text))
    };

    let (_, first) = next_line("the `#binvox` line")?;
    let mut tokens = first.split_ascii_whitespace();
    if tokens.next() != Some("#binvox") {
        return Err(malformed(path, 0, "not a binvox file: it does not start with `#binvox`"));
    }
    let version = match (tokens.next().map(str::parse::<u32>), tokens.next()) {
        (Some(Ok(v)), None) if v >= 1 => v,
        _ => return Err(malformed(path, 0, format!("bad version line {first:?}"))),
    };
    if version > MAX_VERSION {
        return Err(Error::UnsupportedVersion {
            path: path.to_owned(),
            format: "binvox",
            found: version,
            supported: MAX_VERSION,
        });
    }

    let (mut dim, mut translate, mut scale) = (None, None, None);
    loop {
        let (at, line) = next_line("the `data` line")?;
        let mut tokens = line.split_ascii_whitespace();
        let keyword = tokens.next().unwrap_or("");
        let args: Vec<&str> = tokens.collect();
        let bad = |reason: String| malformed(path, at, reason);
        let floats = |n: usize| -> Result<Vec<f64>> {
            let v: Vec<f64> = args.iter().filter_map(|a| a.parse().ok()).collect();
            if args.len() != n || v.len() != n || !v.iter().all(|x| x.is_finite()) {
                return Err(bad(format!("`{keyword}` needs {n} finite numbers: {line:?}")));
            }
            Ok(v)
        };
        let repeated = match keyword {
            "data" if args.is_empty() => break,
            "dim" => {
                let v: Vec<u32> = args.iter().filter_map(|a| a.parse().ok()).collect();
                if args.len() != 3 || v.len() != 3 || v[0] == 0 {
                    return Err(bad(format!("`dim` needs 3 positive integers: {line:?}")));
                }
                if v[0] != v[1] || v[0] != v[2] {
                    return Err(bad(format!(
                        "non-cubic dim {line:?}: binvox readers disagree on its axis order"
                    )));
                }
                if v[0] > GridSpec::MAX_DIM {
                    return Err(bad(format!("dim {} exceeds {}", v[0], GridSpec::MAX_DIM)));
                }
                dim.replace(v[0]).is_some()
            }
            "translate" => {
                let v = floats(3)?;
                translate.replace(DVec3::new(v[0], v[1], v[2])).is_some()
            }
            "scale" => {
                let v = floats(1)?;
                if v[0] <= 0.0 {
                    return Err(bad(format!("scale must be positive: {line:?}")));
                }
                scale.replace(v[0]).is_some()
            }
            _ => return Err(bad(format!("unknown header line {line:?}"))),
        };
        if repeated {
            return Err(malformed(path, at, format!("`{keyword}` given twice")));
        }
    }
    let data = pos;
    let Some(dim) = dim else {
        return Err(malformed(path, data, "the header has no `dim` line"));
    };
    let header = BinvoxHeader {
        version,
        dim,
        translate: translate.unwrap_or(DVec3::ZERO),
        scale: scale.unwrap_or(1.0),
    };
    let grid = GridSpec::new(header.translate, header.scale / dim as f64, UVec3::splat(dim))
        .map_err(|e| malformed(path, data, format!("the header gives no usable grid: {e}")))?;
    Ok((header, grid, data))
}

/// Walks the runs from offset `data`, checking each, and calls `set(start, count)` for every
/// run of set voxels (binvox indices).
pub(super) fn scan_runs(
    bytes: &[u8],
    data: usize,
    header: &BinvoxHeader,
    path: &Path,
    mut set: impl FnMut(u64, u64),
) -> Result<()> {
    let total = (header.dim as u64).pow(3);
    let mut index = 0u64;
    let mut p = data;
    while index < total {
        let Some(&[value, count]) = bytes.get(p..p + 2) else {
            return Err(malformed(
                path,
                p,
                format!("truncated: the runs end after {index} of {total} voxels"),
            ));
        };
        if count == 0 {
            return Err(malformed(path, p + 1, "run of length 0"));
        }
        if header.version == 1 && value > 1 {
            return Err(malformed(path, p, format!("value {value} in a binvox 1 file (0 or 1)")));
        }
        let count = count as u64;
        if index + count > total {
            return Err(malformed(
                path,
                p + 1,
                format!(
                    "a run of {count} overruns the {total} voxels by {}",
                    index + count - total
                ),
            ));
        }
        if value != 0 {
            set(index, count);
        }
        index += count;
        p += 2;
    }
    if p != bytes.len() {
        return Err(malformed(path, p, format!("{} bytes after the last run", bytes.len() - p)));
    }
    Ok(())
}
