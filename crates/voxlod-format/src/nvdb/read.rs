//! Reading `.nvdb` files of the layout [`super`] writes: every segment, every `float` or
//! `Vec3f` grid, walked root → upper → lower → leaf to its active voxels.

use std::path::Path;

use glam::{DMat3, DVec3, IVec3, Vec3};

use super::layout::{GRID_BYTES, HEADER_BYTES, META_BYTES, Sizes, TILE_BYTES, TOTAL, checksum};
use super::{
    AnyGrid, GridClass, IndexToWorld, MAGIC, MAJOR_VERSION, MAX_GRID_BYTES, NvdbGrid, NvdbValue,
};
use crate::{Error, Result};

/// A checksum of all ones: NanoVDB's "no checksum".
const NO_CHECKSUM: u64 = u64::MAX;

/// Decodes `.nvdb` bytes into their grids, in file order; `path` only names the source in
/// errors. Verifies each grid's checksum (see the [module docs](super)).
pub fn decode(bytes: &[u8], path: &Path) -> Result<Vec<AnyGrid>> {
    let bad = |offset: usize, reason: String| Error::Malformed {
        path: path.to_owned(),
        format: "nvdb",
        offset: offset as u64,
        reason,
    };
    let unsupported = |offset: usize, feature: String| Error::Unsupported {
        path: path.to_owned(),
        format: "nvdb",
        offset: offset as u64,
        feature,
    };
    let mut grids = Vec::new();
    let mut at = 0usize;
    while at < bytes.len() {
        let header = bytes.get(at..at + HEADER_BYTES).ok_or_else(|| {
            bad(at, format!("truncated segment header: {} bytes", bytes.len() - at))
        })?;
        if u64_at(header, 0) != MAGIC {
            return Err(bad(
                at,
                "not a NanoVDB file: the segment does not start with `NanoVDB0`".into(),
            ));
        }
        let version = u32_at(header, 8);
        if version >> 21 != MAJOR_VERSION {
            return Err(Error::UnsupportedVersion {
                path: path.to_owned(),
                format: "nvdb",
                found: version >> 21,
                supported: MAJOR_VERSION,
            });
        }
        let count = u16::from_le_bytes([header[12], header[13]]) as usize;
        let codec = u16::from_le_bytes([header[14], header[15]]);
        if codec != 0 {
            let name = ["none", "zip", "blosc"].get(codec as usize).copied().unwrap_or("unknown");
            return Err(unsupported(
                at + 14,
                format!("codec {codec} ({name}); only uncompressed files are read"),
            ));
        }
        if count == 0 {
            return Err(bad(at + 12, "a segment of no grids".into()));
        }
        at += HEADER_BYTES;
        let mut sizes = Vec::with_capacity(count);
        for _ in 0..count {
            let meta = bytes
                .get(at..at + META_BYTES)
                .ok_or_else(|| bad(at, "truncated grid metadata record".into()))?;
            let (grid_size, file_size) = (u64_at(meta, 0), u64_at(meta, 8));
            if grid_size != file_size {
                return Err(bad(
                    at + 8,
                    format!(
                        "{file_size} bytes on disk for a grid of {grid_size}: not uncompressed"
                    ),
                ));
            }
            let name_size = u32_at(meta, 136) as usize;
            let name =
                bytes.get(at + META_BYTES..at + META_BYTES + name_size).ok_or_else(|| {
                    bad(at + META_BYTES, format!("truncated grid name of {name_size} bytes"))
                })?;
            sizes.push((at, grid_size, name.split(|&c| c == 0).next().unwrap_or(&[]).to_vec()));
            at += META_BYTES + name_size;
        }
        for (meta_at, size, name) in sizes {
            if size > MAX_GRID_BYTES || size as usize > bytes.len() - at {
                return Err(bad(
                    meta_at,
                    format!("a grid of {size} bytes, but {} remain in the file", bytes.len() - at),
                ));
            }
            let g = &bytes[at..at + size as usize];
            let grid = decode_grid(g, at, path)?;
            if grid.name().as_bytes() != name {
                return Err(bad(
                    meta_at + META_BYTES,
                    format!(
                        "metadata names the grid {:?}, the grid says {:?}",
                        String::from_utf8_lossy(&name),
                        grid.name()
                    ),
                ));
            }
            grids.push(grid);
            at += size as usize;
        }
    }
    if grids.is_empty() {
        return Err(bad(0, "an empty file".into()));
    }
    Ok(grids)
}

/// Reads an `.nvdb` file (see [`decode`]).
pub fn read(path: impl AsRef<Path>) -> Result<Vec<AnyGrid>> {
    let path = path.as_ref();
    decode(&crate::io::read_bytes(path)?, path)
}

/// One grid's bytes `g`, at `base` in the file.
fn decode_grid(g: &[u8], base: usize, path: &Path) -> Result<AnyGrid> {
    let bad = |offset: usize, reason: String| Error::Malformed {
        path: path.to_owned(),
        format: "nvdb",
        offset: (base + offset) as u64,
        reason,
    };
    if g.len() < GRID_BYTES + 64 {
        return Err(bad(0, format!("a grid of {} bytes, shorter than its header", g.len())));
    }
    if u64_at(g, 0) != MAGIC {
        return Err(bad(0, "the grid does not start with `NanoVDB0`".into()));
    }
    if u32_at(g, 16) >> 21 != MAJOR_VERSION {
        return Err(Error::UnsupportedVersion {
            path: path.to_owned(),
            format: "nvdb",
            found: u32_at(g, 16) >> 21,
            supported: MAJOR_VERSION,
        });
    }
    if u64_at(g, 32) != g.len() as u64 {
        return Err(bad(
            32,
            format!("the grid says it has {} bytes, the file gives it {}", u64_at(g, 32), g.len()),
        ));
    }
    match u32_at(g, 636) {
        1 => Ok(AnyGrid::Float(decode_typed::<f32>(g, base, path)?)),
        6 => Ok(AnyGrid::Vec3f(decode_typed::<Vec3>(g, base, path)?)),
        t => Err(Error::Unsupported {
            path: path.to_owned(),
            format: "nvdb",
            offset: (base + 636) as u64,
            feature: format!("grid type {t} (only 1, float, and 6, Vec3f, are read)"),
        }),
    }
}

fn decode_typed<T: NvdbValue>(g: &[u8], base: usize, path: &Path) -> Result<NvdbGrid<T>> {
    let bad = |offset: usize, reason: String| Error::Malformed {
        path: path.to_owned(),
        format: "nvdb",
        offset: (base + offset) as u64,
        reason,
    };
    let unsupported = |offset: usize, feature: String| Error::Unsupported {
        path: path.to_owned(),
        format: "nvdb",
        offset: (base + offset) as u64,
        feature,
    };
    let sz = Sizes::of(T::SIZE);
    let name_bytes = &g[40..40 + 256];
    let name_len = name_bytes
        .iter()
        .position(|&c| c == 0)
        .ok_or_else(|| bad(40, "the grid name has no terminating NUL".into()))?;
    let name = std::str::from_utf8(&name_bytes[..name_len])
        .map_err(|e| bad(40, format!("the grid name is not UTF-8: {e}")))?
        .to_string();
    let class = GridClass::from_code(u32_at(g, 632)).ok_or_else(|| {
        unsupported(632, format!("grid class {} (0 and 2 are read)", u32_at(g, 632)))
    })?;
    let mut matrix = [[0.0f64; 3]; 3];
    let mut translation = [0.0f64; 3];
    for r in 0..3 {
        for (c, col) in matrix.iter_mut().enumerate() {
            col[r] = f64_at(g, 384 + 8 * (3 * r + c));
        }
        translation[r] = f64_at(g, 528 + 8 * r);
    }
    let map = IndexToWorld {
        matrix: DMat3::from_cols_array_2d(&matrix),
        translation: DVec3::from_array(translation),
    };

    // Tree and root.
    let tree = GRID_BYTES;
    let root_at = (tree as u64).saturating_add(u64_at(g, tree + 24));
    let node_at = |level: usize| (tree as u64).saturating_add(u64_at(g, tree + 16 - 8 * level));
    let counts = [
        u32_at(g, tree + 40) as usize,
        u32_at(g, tree + 36) as usize,
        u32_at(g, tree + 32) as usize,
    ];
    if !root_at.is_multiple_of(32) || root_at.saturating_add(sz.root as u64) > g.len() as u64 {
        return Err(bad(tree + 24, format!("root offset {root_at} out of the grid or misaligned")));
    }
    let root_at = root_at as usize;
    let tiles = u32_at(g, root_at + 24) as usize;
    let root_end = root_at + sz.root + TILE_BYTES * tiles;
    if root_end > g.len() {
        return Err(bad(root_at + 24, format!("{tiles} root tiles run past the grid's end")));
    }
    // Node levels: (first offset, size, count) of the upper, lower and leaf nodes.
    let sizes = [sz.upper, sz.lower, sz.leaf];
    let mut levels = [(0usize, 0usize, 0usize); 3];
    for level in 0..3 {
        let (at, n) = (node_at(level), counts[level]);
        let end = at.checked_add(n as u64 * sizes[level] as u64);
        if n > 0
            && (!at.is_multiple_of(32)
                || end.is_none_or(|e| e > g.len() as u64)
                || at < root_end as u64)
        {
            return Err(bad(
                tree + 16 - 8 * level,
                format!("{n} nodes of level {level} at {at} do not fit the grid"),
            ));
        }
        levels[level] = (at as usize, sizes[level], n);
    }

    let stored = u64_at(g, 8);
    if stored != NO_CHECKSUM {
        let computed = checksum(g, root_end, &levels);
        let head_only = stored >> 32 == 0xffff_ffff;
        // The head first; the tail unless the file holds a partial (head-only) checksum.
        let (s, c) = if head_only || stored as u32 != computed as u32 {
            (stored as u32, computed as u32)
        } else {
            ((stored >> 32) as u32, (computed >> 32) as u32)
        };
        if s != c {
            return Err(Error::ChecksumMismatch { path: path.to_owned(), stored: s, computed: c });
        }
    }

    // The walk. Children must lie after their parent, inside their level's block, each reached
    // once: no cycles, no reads out of bounds, at most 512 voxels per leaf of the file.
    let background = T::get(&g[root_at + 28..]);
    let mut voxels = Vec::new();
    let mut reached = levels.map(|(_, _, n)| vec![false; n]);
    let mut child_of = |parent: usize, offset: i64, level: usize| -> Result<usize> {
        let (first, size, n) = levels[level];
        let at = (parent as i64).checked_add(offset).filter(|&at| {
            offset > 0
                && at >= first as i64
                && at < (first + size * n) as i64
                && (at as usize - first).is_multiple_of(size)
        });
        let Some(at) = at else {
            return Err(bad(
                parent,
                format!("child offset {offset} does not point at a node of level {level}"),
            ));
        };
        let index = (at as usize - first) / size;
        if std::mem::replace(&mut reached[level][index], true) {
            return Err(bad(parent, format!("node {index} of level {level} has two parents")));
        }
        Ok(at as usize)
    };
    for t in 0..tiles {
        let tile = root_at + sz.root + TILE_BYTES * t;
        let child = i64_at(g, tile + 8);
        if child == 0 {
            if u32_at(g, tile + 16) != 0 {
                return Err(unsupported(
                    tile,
                    "an active root tile (a constant 4096³ region)".into(),
                ));
            }
            continue;
        }
        let upper = child_of(root_at, child, 0)?;
        for (lower, _) in internal_children(g, upper, 5, sz.upper_table, sz.entry, &unsupported)? {
            let lower = child_of(upper, lower, 1)?;
            for (leaf, _) in internal_children(g, lower, 4, sz.lower_table, sz.entry, &unsupported)?
            {
                let leaf = child_of(lower, leaf, 2)?;
                let origin = ivec3_at(g, leaf) & IVec3::splat(!((1 << TOTAL[2]) - 1));
                let values = leaf + sz.leaf_values;
                for w in 0..8 {
                    let mut word = u64_at(g, leaf + 16 + 8 * w);
                    while word != 0 {
                        let e = 64 * w + word.trailing_zeros() as usize;
                        word &= word - 1;
                        let c = origin
                            + IVec3::new((e >> 6) as i32, ((e >> 3) & 7) as i32, (e & 7) as i32);
                        voxels.push((c, T::get(&g[values + e * T::SIZE..])));
                    }
                }
            }
        }
    }
    Ok(NvdbGrid { name, class, map, background, voxels })
}

/// The child offsets of the internal node at `at` (`log2` 5 or 4), by entry; an active tile
/// (a value mask bit off the child mask) is unsupported.
fn internal_children(
    g: &[u8],
    at: usize,
    log2: u32,
    table: usize,
    entry: usize,
    unsupported: &dyn Fn(usize, String) -> Error,
) -> Result<Vec<(i64, usize)>> {
    let n = 1usize << (3 * log2);
    let (value_mask, child_mask) = (at + 32, at + 32 + n / 8);
    let mut children = Vec::new();
    for w in 0..n / 64 {
        let (values, childs) = (u64_at(g, value_mask + 8 * w), u64_at(g, child_mask + 8 * w));
        if values & !childs != 0 {
            return Err(unsupported(
                value_mask + 8 * w,
                format!("active tiles in an internal node of {}³ children", 1 << log2),
            ));
        }
        let mut word = childs;
        while word != 0 {
            let e = 64 * w + word.trailing_zeros() as usize;
            word &= word - 1;
            children.push((i64_at(g, at + table + e * entry), e));
        }
    }
    Ok(children)
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}
fn i64_at(b: &[u8], at: usize) -> i64 {
    u64_at(b, at) as i64
}
fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_bits(u64_at(b, at))
}
fn ivec3_at(b: &[u8], at: usize) -> IVec3 {
    let i = |k: usize| u32_at(b, at + 4 * k) as i32;
    IVec3::new(i(0), i(1), i(2))
}
