//! binvox occupancy export and import, so that our grids open in the tools people already have
//! (binvox's viewvox, trimesh, many voxel pipelines).
//!
//! The format (Patrick Min's binvox specification, read at `patrickmin.com/binvox/binvox.html`;
//! trimesh's `exchange/binvox.py` read as a second opinion): an ASCII header
//!
//! ```text
//! #binvox 1
//! dim D D D
//! translate tx ty tz
//! scale s
//! data
//! ```
//!
//! then `(value, count)` byte pairs, each a run of `count` (1–255) voxels, over the `D³` voxels
//! in binvox order: **x slowest, then z, then y fastest**, i.e. voxel `(x, y, z)` has index
//! `x·D² + z·D + y`. Voxel `(i, j, k)` covers the normalized cube `[i, i+1)/D` (and so on) scaled
//! by `s` and then translated by `t`, so in world space its minimum corner is
//! `t + (i, j, k)·s/D`: `translate` is our grid's origin and `s/D` its voxel size.
//!
//! Export: binvox tools expect a cube, so a grid of dims `(X, Y, Z)` is written as a cube of
//! `D = max(X, Y, Z)` voxels padded with empty voxels on the high side of the shorter axes, with
//! `translate = origin` and `scale = voxel_size·D`; world positions are preserved. Floats are
//! written in Rust's shortest round-trip notation, so the origin reads back exactly and the
//! voxel size within one ulp (exactly whenever some `f64` scale divides back to it).
//!
//! Import accepts versions 1 and 2 (binvox_merge's extension: any non-zero value marks a set
//! voxel) and is strict where tools disagree or data would be silently lost: a non-cubic `dim`
//! (whose axis order binvox's and trimesh's readers interpret differently), an unknown header
//! keyword, a zero-length run, a value other than 0/1 in version 1, runs that stop short of or
//! overrun `D³` voxels, and bytes after the last run are each an [`Error::Malformed`] naming the
//! byte offset. Import costs time in proportion to the file's bytes and occupied voxels and
//! memory in proportion to occupied bricks, never to `D³`.

mod read;

use std::collections::HashMap;
use std::hash::BuildHasherDefault;
use std::io::Write;
use std::path::Path;

use glam::{DVec3, UVec3};

use crate::brickmap::{BrickHeader, MortonHasher};
use crate::{BrickMap, Error, GridSpec, Occupancy, Result, morton};

/// Largest cube edge [`encode`] writes: a 4096³ cube holds 2³⁶ voxels, and even empty it takes
/// 0.5 GB of runs; binvox itself stops at 1024 without `-e`.
pub const MAX_EXPORT_DIM: u32 = 4096;
/// Newest binvox version read.
pub const MAX_VERSION: u32 = 2;

/// A parsed binvox header.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinvoxHeader {
    /// Format version (1, or 2 for files with per-voxel values).
    pub version: u32,
    /// Cube edge in voxels.
    pub dim: u32,
    /// World position of the cube's minimum corner (`0` when the header has no `translate`).
    pub translate: DVec3,
    /// World edge length of the whole cube (`1` when the header has no `scale`).
    pub scale: f64,
}

/// What a binvox file holds (for `voxlod info`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinvoxInfo {
    /// The header.
    pub header: BinvoxHeader,
    /// The grid the header describes.
    pub grid: GridSpec,
    /// Number of set voxels.
    pub occupied: u64,
}

/// binvox bytes of `map`'s occupancy (see the [module docs](self) for the padding to a cube).
///
/// Errors: the grid fails [`GridSpec::validate`] or differs in dims from the map
/// ([`Error::InvalidGrid`]); its longest axis exceeds [`MAX_EXPORT_DIM`]
/// ([`Error::GridTooLarge`]); the cube's scale overflows `f64`.
pub fn encode<T>(grid: &GridSpec, map: &BrickMap<T>) -> Result<Vec<u8>> {
    let header = header_for(grid, map)?;
    let mut out = Vec::new();
    write_to(&mut out, &header, map).map_err(|source| Error::Io {
        op: "encoding",
        path: "<memory>".into(),
        source,
    })?;
    Ok(out)
}

/// Writes `map`'s occupancy as a binvox file, atomically (see [`encode`]).
///
/// ```
/// use glam::{DVec3, UVec3};
/// use voxlod_format::{BrickMap, GridSpec, binvox};
/// let grid = GridSpec::new(DVec3::new(-1.0, 0.0, 0.5), 0.25, UVec3::new(8, 3, 5)).unwrap();
/// let map = BrickMap::from_voxels(grid.dims, [(UVec3::new(7, 2, 4), ())]).unwrap();
/// let path = std::env::temp_dir().join("voxlod-doc-binvox.binvox");
/// binvox::write(&path, &grid, &map).unwrap();
///
/// // It reads back as the 8³ cube it was padded to, with the same origin and voxel size.
/// let (cube, occupancy) = binvox::read(&path).unwrap();
/// assert_eq!(cube.dims, UVec3::splat(8));
/// assert_eq!((cube.origin, cube.voxel_size), (grid.origin, grid.voxel_size));
/// assert_eq!(occupancy.coords().collect::<Vec<_>>(), [UVec3::new(7, 2, 4)]);
/// ```
pub fn write<T>(path: impl AsRef<Path>, grid: &GridSpec, map: &BrickMap<T>) -> Result<()> {
    // Check the arguments before creating anything, then stream the runs.
    let header = header_for(grid, map)?;
    crate::io::write_atomic(path.as_ref(), |w| write_to(w, &header, map))
}

/// Decodes binvox bytes into the cubic grid and its occupancy; `path` only names the source in
/// errors.
///
/// ```
/// use std::path::Path;
/// use glam::UVec3;
/// use voxlod_format::binvox;
/// // One voxel at (x=1, y=0, z=0) of a 2³ cube: binvox index x·4 + z·2 + y = 4.
/// let bytes = b"#binvox 1\ndim 2 2 2\ntranslate 0 0 0\nscale 1\ndata\n\x00\x04\x01\x01\x00\x03";
/// let (grid, map) = binvox::decode(bytes, Path::new("<memory>")).unwrap();
/// assert_eq!(grid.voxel_size, 0.5);
/// assert_eq!(map.coords().collect::<Vec<_>>(), [UVec3::new(1, 0, 0)]);
/// ```
pub fn decode(bytes: &[u8], path: &Path) -> Result<(GridSpec, BrickMap<Occupancy>)> {
    let (header, grid, data) = read::parse_header(bytes, path)?;
    let d = header.dim;
    let mut masks: HashMap<u64, [u64; 8], BuildHasherDefault<MortonHasher>> = HashMap::default();
    let mut occupied = 0u64;
    read::scan_runs(bytes, data, &header, path, |start, count| {
        occupied += count;
        let d = d as u64;
        let (mut x, mut z, mut y) = (start / (d * d), start / d % d, start % d);
        for _ in 0..count {
            let code = morton::encode(UVec3::new(x as u32, y as u32, z as u32));
            let local = code & 511;
            masks.entry(code >> 9).or_default()[(local >> 6) as usize] |= 1 << (local & 63);
            y += 1;
            if y == d {
                y = 0;
                z += 1;
                if z == d {
                    z = 0;
                    x += 1;
                }
            }
        }
    })?;
    if occupied > u32::MAX as u64 {
        return Err(Error::InvalidGrid {
            reason: format!("{occupied} occupied voxels exceed a brick map's {} values", u32::MAX),
        });
    }
    let mut sorted: Vec<(u64, [u64; 8])> = masks.into_iter().collect();
    sorted.sort_unstable_by_key(|b| b.0);
    let mut bricks = Vec::with_capacity(sorted.len());
    let mut first = 0u32;
    for (code, mask) in sorted {
        bricks.push(BrickHeader { morton: code, mask, first, _pad: 0 });
        first += mask.iter().map(|w| w.count_ones()).sum::<u32>();
    }
    let map = BrickMap::from_parts(grid.dims, bricks, vec![Occupancy; occupied as usize])?;
    Ok((grid, map))
}

/// Reads a binvox file (see [`decode`]).
pub fn read(path: impl AsRef<Path>) -> Result<(GridSpec, BrickMap<Occupancy>)> {
    let path = path.as_ref();
    decode(&crate::io::read_bytes(path)?, path)
}

/// Describes binvox bytes: header, grid and number of set voxels; every run is checked as in
/// [`decode`], but no map is built.
pub fn decode_info(bytes: &[u8], path: &Path) -> Result<BinvoxInfo> {
    let (header, grid, data) = read::parse_header(bytes, path)?;
    let mut occupied = 0;
    read::scan_runs(bytes, data, &header, path, |_, count| occupied += count)?;
    Ok(BinvoxInfo { header, grid, occupied })
}

/// Describes a binvox file (see [`decode_info`]).
pub fn read_info(path: impl AsRef<Path>) -> Result<BinvoxInfo> {
    let path = path.as_ref();
    decode_info(&crate::io::read_bytes(path)?, path)
}

fn malformed(path: &Path, offset: usize, reason: impl Into<String>) -> Error {
    Error::Malformed {
        path: path.to_owned(),
        format: "binvox",
        offset: offset as u64,
        reason: reason.into(),
    }
}

/// A checked export: the cube edge and the header text.
struct Header {
    dim: u32,
    text: String,
}

/// The header text for `grid`, after checking the arguments.
fn header_for<T>(grid: &GridSpec, map: &BrickMap<T>) -> Result<Header> {
    grid.validate()?;
    if map.dims() != grid.dims {
        return Err(Error::InvalidGrid {
            reason: format!("brick map dims {} differ from grid dims {}", map.dims(), grid.dims),
        });
    }
    let d = grid.dims.max_element();
    if d > MAX_EXPORT_DIM {
        return Err(Error::GridTooLarge {
            requested: grid.dims.as_u64vec3().to_array(),
            max: MAX_EXPORT_DIM as u64,
        });
    }
    let scale = cube_scale(grid.voxel_size, d);
    if !scale.is_finite() {
        return Err(Error::InvalidGrid {
            reason: format!(
                "a binvox cube of {d} voxels of size {} has no finite scale",
                grid.voxel_size
            ),
        });
    }
    let t = grid.origin;
    let text = format!(
        "#binvox 1\ndim {d} {d} {d}\ntranslate {:?} {:?} {:?}\nscale {scale:?}\ndata\n",
        t.x, t.y, t.z
    );
    Ok(Header { dim: d, text })
}

/// The cube scale `voxel_size·d`, nudged by an ulp when that makes `scale / d` give back
/// `voxel_size` exactly (the reader's division).
fn cube_scale(voxel_size: f64, d: u32) -> f64 {
    let d = d as f64;
    let s = voxel_size * d;
    [s, s.next_down(), s.next_up()]
        .into_iter()
        .find(|c| c.is_finite() && c / d == voxel_size)
        .unwrap_or(s)
}

/// Streams the header and the runs: time and memory follow the occupied voxels, plus two bytes
/// per 255 empty voxels of output.
fn write_to<T>(w: &mut dyn Write, header: &Header, map: &BrickMap<T>) -> std::io::Result<()> {
    let d = header.dim as u64;
    let mut indices: Vec<u64> =
        map.coords().map(|c| c.x as u64 * d * d + c.z as u64 * d + c.y as u64).collect();
    indices.sort_unstable();

    let mut out = std::io::BufWriter::new(w);
    out.write_all(header.text.as_bytes())?;
    let mut runs = |value: u8, mut n: u64| -> std::io::Result<()> {
        while n > 0 {
            let c = n.min(255);
            out.write_all(&[value, c as u8])?;
            n -= c;
        }
        Ok(())
    };
    let mut next = 0u64; // first index not yet written
    let mut i = 0;
    while i < indices.len() {
        let start = indices[i];
        let mut end = start + 1;
        i += 1;
        while i < indices.len() && indices[i] == end {
            end += 1;
            i += 1;
        }
        runs(0, start - next)?;
        runs(1, end - start)?;
        next = end;
    }
    runs(0, d * d * d - next)?;
    out.flush()
}

#[cfg(test)]
mod tests;
