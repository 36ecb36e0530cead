//! Mitsuba 3's binary grid volume (`.vol`): dense `float32` grids of 1, 3 or 6 channels, which
//! Mitsuba's `gridvolume` plugin loads as a heterogeneous medium's density (`sigma_t`, one
//! channel) or albedo (three channels), so a voxelized or filtered grid can be rendered with a
//! path tracer.
//!
//! # Layout (version 3, as documented by Mitsuba 3's `gridvolume` plugin)
//!
//! All integers and floats little-endian; offsets from the start of the file.
//!
//! | offset | size | field | notes |
//! |---|---|---|---|
//! | 0 | 3 | magic | ASCII `VOL` |
//! | 3 | 1 | version `u8` | [`VERSION`] = 3 |
//! | 4 | 4 | encoding `i32` | [`ENCODING_F32`] = 1, dense `float32`: the only encoding Mitsuba 3 reads |
//! | 8 | 12 | cells along x, y, z `i32`×3 | each ≥ 1 |
//! | 20 | 4 | channels `i32` | 1, 3 or 6 |
//! | 24 | 24 | bounding box `f32`×6 | `xmin, ymin, zmin, xmax, ymax, zmax` |
//! | 48 | 4·x·y·z·channels | data `f32` | value `c` of cell `(x, y, z)` at index `((z·Y + y)·X + x)·channels + c` (x fastest) |
//!
//! The file ends exactly after the data.
//!
//! # Conventions
//! - Cells are voxlod's voxels, on voxlod's axes (right-handed, y up): cell `(i, j, k)` is voxel
//!   `(i, j, k)` of the [`GridSpec`], and the bounding box is the grid's world box, from its
//!   origin to its maximum corner, rounded to `f32`. Mitsuba 3 places a grid on the unit cube
//!   mapped by the volume's `to_world` unless its `use_grid_bbox` property is set, in which case
//!   it uses this box.
//! - Empty voxels get the background value given to [`VolGrid::from_brick_map`] (zero density,
//!   for instance): the format is dense, so files grow with the grid's box, not with its
//!   occupied voxels.
//! - [`density_and_albedo`] turns an Averages grid into the two grids a heterogeneous medium
//!   needs: extinction σ per world unit ([`extinction_from_opacity`]) and the linear albedo.
//!
//! # Refused
//! A dimension that is 0 or over `i32::MAX`, a channel count other than 1, 3 or 6, more than
//! [`MAX_VALUES`] values, a non-finite value, or a bounding box that is not finite and ordered in
//! `f32` ([`Error::Unrepresentable`]); reading refuses a wrong magic, version or encoding, a
//! truncated file or trailing bytes ([`Error::Malformed`], [`Error::UnsupportedVersion`]).

use std::io::Write;
use std::path::Path;

use glam::{UVec3, Vec3};

use crate::records::{AverageRecord, extinction_from_opacity};
use crate::{BrickMap, Error, GridSpec, Result};

/// The magic bytes that open every `.vol` file.
pub const MAGIC: [u8; 3] = *b"VOL";
/// The format version written and read.
pub const VERSION: u8 = 3;
/// The dense `float32` encoding, the only one Mitsuba 3 reads.
pub const ENCODING_F32: i32 = 1;
/// Length of the header: the data starts here.
pub const HEADER_LEN: usize = 48;
/// Most values (cells × channels) written or read: 2³⁰ (a 4 GiB file), a limit of this library
/// so that a mistaken resolution does not fill a disk; the format itself stops at `i32` cells
/// per axis.
pub const MAX_VALUES: u64 = 1 << 30;

/// A dense grid of `f32` values with its bounding box, as a `.vol` file holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct VolGrid {
    /// Cells along x, y and z.
    pub dims: UVec3,
    /// Values per cell: 1, 3 or 6.
    pub channels: u32,
    /// World-space minimum corner of the grid's box.
    pub bbox_min: Vec3,
    /// World-space maximum corner of the grid's box.
    pub bbox_max: Vec3,
    /// `dims` product × `channels` values, x fastest, then y, then z; channels innermost.
    pub data: Vec<f32>,
}

impl VolGrid {
    /// The grid of `map` over `grid`'s box: voxel `c` gets `value(record)`, empty voxels get
    /// `background`. `C` is the channel count (1, 3 or 6).
    ///
    /// Errors: `grid` invalid or of other dims than `map` ([`Error::InvalidGrid`]); anything
    /// the format cannot hold ([`Error::Unrepresentable`], see the [module docs](self)).
    ///
    /// ```
    /// use glam::{DVec3, UVec3};
    /// use voxlod_format::{BrickMap, GridSpec, vol::VolGrid};
    /// let grid = GridSpec::new(DVec3::ZERO, 0.5, UVec3::new(2, 1, 1)).unwrap();
    /// let map = BrickMap::from_voxels(grid.dims, [(UVec3::new(1, 0, 0), 3.0f32)]).unwrap();
    /// let v = VolGrid::from_brick_map(&grid, &map, [0.0], |&d| [d]).unwrap();
    /// assert_eq!(v.data, [0.0, 3.0]);
    /// assert_eq!(v.bbox_max.to_array(), [1.0, 0.5, 0.5]);
    /// ```
    pub fn from_brick_map<T, const C: usize>(
        grid: &GridSpec,
        map: &BrickMap<T>,
        background: [f32; C],
        value: impl Fn(&T) -> [f32; C],
    ) -> Result<Self> {
        grid.validate()?;
        if map.dims() != grid.dims {
            return Err(Error::InvalidGrid {
                reason: format!(
                    "brick map dims {} differ from grid dims {}",
                    map.dims(),
                    grid.dims
                ),
            });
        }
        check_shape(grid.dims, C as u32)?;
        let cells = grid.voxel_count() as usize;
        let mut data = Vec::with_capacity(cells * C);
        for _ in 0..cells {
            data.extend_from_slice(&background);
        }
        let (x, y) = (grid.dims.x as usize, grid.dims.y as usize);
        for (c, record) in map.iter() {
            let at = ((c.z as usize * y + c.y as usize) * x + c.x as usize) * C;
            data[at..at + C].copy_from_slice(&value(record));
        }
        let v = Self {
            dims: grid.dims,
            channels: C as u32,
            bbox_min: grid.origin.as_vec3(),
            bbox_max: grid.max_corner().as_vec3(),
            data,
        };
        v.validate()?;
        Ok(v)
    }

    /// Index in [`VolGrid::data`] of the first value of cell `c` (which must be in the grid).
    pub fn index(&self, c: UVec3) -> usize {
        let (x, y) = (self.dims.x as usize, self.dims.y as usize);
        ((c.z as usize * y + c.y as usize) * x + c.x as usize) * self.channels as usize
    }

    /// The values of cell `c`, or `None` outside the grid.
    pub fn get(&self, c: UVec3) -> Option<&[f32]> {
        c.cmplt(self.dims).all().then(|| {
            let at = self.index(c);
            &self.data[at..at + self.channels as usize]
        })
    }

    /// Checks that the format can hold this grid (see the [module docs](self)).
    pub fn validate(&self) -> Result<()> {
        check_shape(self.dims, self.channels)?;
        let expected = self.dims.as_u64vec3().element_product() * self.channels as u64;
        if self.data.len() as u64 != expected {
            return Err(Error::InvalidGrid {
                reason: format!(
                    "{} values for {} cells of {} channels (expected {expected})",
                    self.data.len(),
                    self.dims,
                    self.channels
                ),
            });
        }
        if !(self.bbox_min.is_finite() && self.bbox_max.is_finite())
            || self.bbox_min.cmpge(self.bbox_max).any()
        {
            return Err(unrepresentable(
                format!("the bounding box {} … {}", self.bbox_min, self.bbox_max),
                "the box must be finite in f32 with min < max on every axis".into(),
            ));
        }
        if let Some(i) = self.data.iter().position(|v| !v.is_finite()) {
            let ch = self.channels as usize;
            let cell = i / ch;
            let (x, y) = (self.dims.x as usize, self.dims.y as usize);
            let c = UVec3::new((cell % x) as u32, (cell / x % y) as u32, (cell / (x * y)) as u32);
            return Err(unrepresentable(
                format!("value {} at cell {c} channel {}", self.data[i], i % ch),
                "Mitsuba volumes hold finite floats".into(),
            ));
        }
        Ok(())
    }
}

/// The density (extinction σ per world unit, one channel) and albedo (linear RGB, three
/// channels) grids of an Averages grid, for a Mitsuba 3 heterogeneous medium: density from
/// [`AverageRecord::extinction`], albedo from [`AverageRecord::color`]; empty voxels have
/// density 0 and albedo 0.
pub fn density_and_albedo(
    grid: &GridSpec,
    map: &BrickMap<AverageRecord>,
) -> Result<(VolGrid, VolGrid)> {
    let size = grid.voxel_size;
    let density = VolGrid::from_brick_map(grid, map, [0.0], |r| [r.extinction(size)])?;
    let albedo = VolGrid::from_brick_map(grid, map, [0.0; 3], |r| r.color().to_array())?;
    Ok((density, albedo))
}

/// The density grid of an occupancy map: every occupied voxel fully opaque (opacity 1, so
/// `σ = `[`MAX_VOXEL_OPTICAL_DEPTH`](crate::records::MAX_VOXEL_OPTICAL_DEPTH)` / voxel size`).
pub fn occupancy_density<T>(grid: &GridSpec, map: &BrickMap<T>) -> Result<VolGrid> {
    let sigma = extinction_from_opacity(1.0, grid.voxel_size);
    VolGrid::from_brick_map(grid, map, [0.0], |_| [sigma])
}

/// The bytes of a `.vol` file holding `v` (checked with [`VolGrid::validate`]).
pub fn encode(v: &VolGrid) -> Result<Vec<u8>> {
    v.validate()?;
    let mut out = Vec::with_capacity(HEADER_LEN + 4 * v.data.len());
    write_to(&mut out, v).map_err(|source| Error::Io {
        op: "encoding",
        path: "<memory>".into(),
        source,
    })?;
    Ok(out)
}

/// Writes `v` as a `.vol` file, atomically (checked first with [`VolGrid::validate`]).
///
/// ```
/// use glam::{UVec3, Vec3};
/// use voxlod_format::vol::{self, VolGrid};
/// let v = VolGrid {
///     dims: UVec3::new(2, 1, 1),
///     channels: 1,
///     bbox_min: Vec3::ZERO,
///     bbox_max: Vec3::new(2.0, 1.0, 1.0),
///     data: vec![0.5, 1.5],
/// };
/// let path = std::env::temp_dir().join("voxlod-doc.vol");
/// vol::write(&path, &v).unwrap();
/// assert_eq!(vol::read(&path).unwrap(), v);
/// assert_eq!(std::fs::metadata(&path).unwrap().len(), 48 + 2 * 4);
/// ```
pub fn write(path: impl AsRef<Path>, v: &VolGrid) -> Result<()> {
    v.validate()?;
    crate::io::write_atomic(path.as_ref(), |w| write_to(w, v))
}

/// Decodes `.vol` bytes; `path` only names the source in errors.
pub fn decode(bytes: &[u8], path: &Path) -> Result<VolGrid> {
    let bad = |offset: usize, reason: String| Error::Malformed {
        path: path.to_owned(),
        format: "vol",
        offset: offset as u64,
        reason,
    };
    if bytes.len() < HEADER_LEN {
        return Err(bad(
            bytes.len(),
            format!("truncated: {} bytes, the header alone has {HEADER_LEN}", bytes.len()),
        ));
    }
    if bytes[0..3] != MAGIC {
        return Err(bad(0, "not a Mitsuba volume: it does not start with `VOL`".into()));
    }
    if bytes[3] != VERSION {
        if bytes[3] > VERSION {
            return Err(Error::UnsupportedVersion {
                path: path.to_owned(),
                format: "vol",
                found: bytes[3] as u32,
                supported: VERSION as u32,
            });
        }
        return Err(bad(3, format!("version {} (only version {VERSION} is read)", bytes[3])));
    }
    let i32_at = |o: usize| i32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    let f32_at = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    let encoding = i32_at(4);
    if encoding != ENCODING_F32 {
        return Err(Error::Unsupported {
            path: path.to_owned(),
            format: "vol",
            offset: 4,
            feature: format!("encoding {encoding} (only {ENCODING_F32}, dense float32, is read)"),
        });
    }
    let mut dims = [0u32; 3];
    for (axis, d) in dims.iter_mut().enumerate() {
        let n = i32_at(8 + 4 * axis);
        if n < 1 {
            return Err(bad(8 + 4 * axis, format!("{n} cells along axis {axis}")));
        }
        *d = n as u32;
    }
    let channels = i32_at(20);
    if !matches!(channels, 1 | 3 | 6) {
        return Err(bad(20, format!("{channels} channels (1, 3 or 6)")));
    }
    let dims = UVec3::from_array(dims);
    let values = dims.as_u64vec3().element_product() * channels as u64;
    if values > MAX_VALUES {
        return Err(bad(8, format!("{values} values exceed the {MAX_VALUES} this library reads")));
    }
    let expected = HEADER_LEN as u64 + 4 * values;
    if bytes.len() as u64 != expected {
        return Err(bad(
            bytes.len().min(expected as usize),
            format!(
                "{} bytes, but {dims} cells of {channels} channels need {expected}",
                bytes.len()
            ),
        ));
    }
    let bbox_min = Vec3::new(f32_at(24), f32_at(28), f32_at(32));
    let bbox_max = Vec3::new(f32_at(36), f32_at(40), f32_at(44));
    let data =
        bytes[HEADER_LEN..].chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    Ok(VolGrid { dims, channels: channels as u32, bbox_min, bbox_max, data: data.collect() })
}

/// Reads a `.vol` file (see [`decode`]).
pub fn read(path: impl AsRef<Path>) -> Result<VolGrid> {
    let path = path.as_ref();
    decode(&crate::io::read_bytes(path)?, path)
}

fn unrepresentable(what: String, reason: String) -> Error {
    Error::Unrepresentable { format: "vol", what, reason }
}

/// Dimensions and channels the format holds, within [`MAX_VALUES`].
fn check_shape(dims: UVec3, channels: u32) -> Result<()> {
    if !matches!(channels, 1 | 3 | 6) {
        return Err(unrepresentable(
            format!("{channels} channels"),
            "Mitsuba volumes have 1, 3 or 6".into(),
        ));
    }
    if dims.min_element() == 0 || dims.max_element() > i32::MAX as u32 {
        return Err(unrepresentable(
            format!("a grid of {dims} cells"),
            "each axis needs 1 to 2³¹ − 1 cells".into(),
        ));
    }
    let values = dims.as_u64vec3().element_product() * channels as u64;
    if values > MAX_VALUES {
        return Err(unrepresentable(
            format!("a grid of {dims} cells of {channels} channels ({values} values)"),
            format!("this library writes at most {MAX_VALUES} values (a dense 4 GiB file)"),
        ));
    }
    Ok(())
}

fn write_to(w: &mut dyn Write, v: &VolGrid) -> std::io::Result<()> {
    let mut header = Vec::with_capacity(HEADER_LEN);
    header.extend_from_slice(&MAGIC);
    header.push(VERSION);
    header.extend_from_slice(&ENCODING_F32.to_le_bytes());
    for d in v.dims.to_array() {
        header.extend_from_slice(&(d as i32).to_le_bytes());
    }
    header.extend_from_slice(&(v.channels as i32).to_le_bytes());
    for x in v.bbox_min.to_array().into_iter().chain(v.bbox_max.to_array()) {
        header.extend_from_slice(&x.to_le_bytes());
    }
    debug_assert_eq!(header.len(), HEADER_LEN);
    w.write_all(&header)?;
    let mut chunk = Vec::with_capacity(64 * 1024);
    for values in v.data.chunks(16 * 1024) {
        chunk.clear();
        for x in values {
            chunk.extend_from_slice(&x.to_le_bytes());
        }
        w.write_all(&chunk)?;
    }
    w.flush()
}

#[cfg(test)]
mod tests;
