//! NanoVDB (`.nvdb`): sparse VDB grids in NanoVDB's flat, pointer-free layout, the format of
//! OpenVDB's NanoVDB library version 32.4 (as shipped with OpenVDB 10.0), which Blender, Houdini
//! and OpenVDB's own tools read directly or convert to OpenVDB `.vdb` (`nanovdb_convert`).
//!
//! Written: `float` grids (a density) and `Vec3f` grids (a colour), several per file, each
//! with per-node statistics, the world and index bounding boxes, an affine index-to-world map
//! and NanoVDB's two-part CRC-32 checksum; the file codec is uncompressed. Read: files of this
//! layout holding `float` or `Vec3f` grids whose active values all sit in leaf nodes (what this
//! module writes), back to their active voxels and values.
//!
//! # Index space and the half-voxel offset
//! A VDB grid indexes voxel *centres*: index `(i, j, k)` maps to the world point
//! `M · (i, j, k) + t`. voxlod's [`GridSpec`] puts voxel `(i, j, k)`'s centre at
//! `origin + (i + ½) · voxel_size`, so a grid written from a `GridSpec` keeps voxel `(i, j, k)`
//! at index `(i, j, k)` with `M = voxel_size · I` and `t = origin + ½ · voxel_size`
//! ([`IndexToWorld::from_grid_spec`]). Any map with orthogonal columns of one length (a
//! rotation and uniform scale, as NanoVDB requires) can be written ([`IndexToWorld`]).
//!
//! # Layout of a grid (NanoVDB 32.4, little-endian, every block 32-byte aligned)
//! | block | bytes (`float` / `Vec3f`) | content |
//! |---|---|---|
//! | GridData | 672 | magic `NanoVDB0`, checksum, version 32.4.2, flags (bbox, min/max, average, standard deviation, breadth-first), grid index 0 of 1, byte size, name (≤ 255 bytes + NUL), map (3×3 matrix, inverse, translation, taper, in `f32` then `f64`), world bbox, voxel size, [`GridClass`], [`GridType`] |
//! | TreeData | 64 | byte offsets from the tree to the first leaf, lower, upper node and the root; node counts per level; active tile counts (0: every active value is a voxel); active voxel count |
//! | RootData | 64 / 96 | index bbox of the active voxels, tile count, background, min, max, average, standard deviation |
//! | root tiles | 32 each | key `(x>>12)<<42 \| (y>>12)<<21 \| (z>>12)` (the upper node's origin), byte offset from the root to the upper node |
//! | upper nodes (32³) | 270 400 / 532 544 | active bbox, flags, value mask, child mask (4096 bytes each), min, max, average, standard deviation, 32 768 entries: byte offset to a lower node or a (background) value |
//! | lower nodes (16³) | 33 856 / 66 624 | the same with 16³ = 4096 entries, children the leaves |
//! | leaves (8³) | 2 144 / 6 272 | active bbox minimum and extent, flags, value mask (64 bytes), min, max, average, standard deviation, 512 values |
//!
//! Node entries are indexed `n = x·D² + y·D + z` (local coordinates, `D` the node's width in
//! children); masks are bit `n % 64` of word `n / 64`. Nodes follow each other breadth first,
//! each level in the order of a depth-first walk, as NanoVDB's `NodeManager` expects. The
//! statistics follow NanoVDB's `GridStats`: for `float`, min/max/average/standard deviation of
//! the active values; for `Vec3f`, min and max are the vectors of least and greatest squared
//! length and the average and deviation are those of the squared lengths. The world bbox is
//! the map of the index box `[min, max + 1]`, as `GridStats` computes it.
//!
//! # Checksum
//! NanoVDB's `GridChecksum` (full mode): the low 32 bits are the CRC-32 (IEEE, as zlib) of the
//! grid's bytes from offset 16 to the end of the root's tiles; the high 32 bits are the CRC-32
//! of the list of each node's CRC-32 (upper nodes, then lower, then leaves), each stored as a
//! 64-bit little-endian word — the width of `std::uint_fast32_t` on 64-bit Linux, where
//! NanoVDB's tools compute it. [`decode`] verifies both halves; a file whose tail half is
//! `0xffffffff` (NanoVDB's partial mode) is checked on its head only, and a checksum of all ones
//! (`0xffffffffffffffff`, NanoVDB's "disabled") is not checked.
//!
//! # File
//! One segment: a 16-byte header (magic, version, grid count `u16`, codec `u16` = 0, none), one
//! 176-byte metadata record per grid (sizes, name hash, voxel count, type, class, world and index
//! bbox, voxel size, name length, node and tile counts, codec, version) each followed by the
//! grid's NUL-terminated name, then the grids' bytes in the same order.
//!
//! # Density and colour
//! [`density_and_color`] turns an Averages grid into two grids: `density`, a `float`
//! [`GridClass::FogVolume`] holding the extinction σ = −ln(1 − α)/voxel size per world unit
//! ([`extinction_from_opacity`]; \[VJK21\]'s non-exponential transmittance, which the Averages
//! opacity does not model either, has no VDB counterpart), and `color`, a `Vec3f` grid of the
//! linear-RGB colour; both have the Averages voxels as their active set and zero background.
//!
//! # Refused
//! An empty grid, a non-finite value (naming the voxel), a voxel given twice, an index
//! coordinate beyond ±[`MAX_INDEX`], a grid over [`MAX_GRID_BYTES`], a name over 255 bytes or
//! holding a NUL, a map that is not finite or not a rotation times a uniform positive scale
//! ([`Error::Unrepresentable`]). Reading refuses a wrong magic or an unsupported version, a
//! compressed codec, value types other than `float` and `Vec3f`, active tiles above the leaves
//! ([`Error::Unsupported`]), truncation, offsets out of bounds or misaligned, inconsistent
//! metadata ([`Error::Malformed`]) and checksum mismatches ([`Error::ChecksumMismatch`]).

use std::path::Path;

use glam::{DMat3, DVec3, IVec3, Vec3};

use crate::records::{AverageRecord, extinction_from_opacity};
use crate::{BrickMap, Error, GridSpec, Result};

mod layout;
mod read;

pub use read::{decode, read};

/// `"NanoVDB0"`, the magic number opening every grid and every file segment (little-endian).
pub const MAGIC: u64 = 0x304244566f6e614e;
/// The NanoVDB version written: 32.4.2, packed as `major << 21 | minor << 10 | patch`.
pub const VERSION: u32 = (32 << 21) | (4 << 10) | 2;
/// The major version read (the ABI and file layout).
pub const MAJOR_VERSION: u32 = 32;
/// Largest index coordinate magnitude written: 2³⁰ − 1, so that every node origin and NanoVDB's
/// own `max + 1` bounding-box arithmetic stay inside `i32`.
pub const MAX_INDEX: i32 = (1 << 30) - 1;
/// Largest grid written or read, in bytes (4 GiB): a limit of this library, checked before
/// anything is allocated, so a mistaken resolution does not fill memory or a disk.
pub const MAX_GRID_BYTES: u64 = 1 << 32;
/// Longest grid name, in bytes (NanoVDB keeps 256 bytes with the terminating NUL).
pub const MAX_NAME_BYTES: usize = 255;

/// NanoVDB's grid classes (what the values mean), by their numbers in the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum GridClass {
    /// No particular meaning (`0`), used for the colour grid.
    Unknown,
    /// A fog volume, e.g. a density (`2`): `float` values, zero outside.
    FogVolume,
}

impl GridClass {
    /// The number stored in the file.
    pub fn code(self) -> u32 {
        match self {
            GridClass::Unknown => 0,
            GridClass::FogVolume => 2,
        }
    }

    fn from_code(code: u32) -> Option<Self> {
        match code {
            0 => Some(GridClass::Unknown),
            2 => Some(GridClass::FogVolume),
            _ => None,
        }
    }
}

/// NanoVDB's value types that this module writes, by their numbers in the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum GridType {
    /// 32-bit float (`1`).
    Float,
    /// Three 32-bit floats (`6`).
    Vec3f,
}

impl GridType {
    /// The number stored in the file.
    pub fn code(self) -> u32 {
        match self {
            GridType::Float => 1,
            GridType::Vec3f => 6,
        }
    }
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for glam::Vec3 {}
}

/// A value type a NanoVDB grid holds here: `f32` ([`GridType::Float`]) or [`Vec3`]
/// ([`GridType::Vec3f`]).
pub trait NvdbValue: Copy + PartialEq + std::fmt::Debug + sealed::Sealed {
    /// The grid type.
    const GRID_TYPE: GridType;
    /// Bytes of one value.
    const SIZE: usize;
    /// The zero value.
    const ZERO: Self;
    /// Writes the value, little-endian, into `out[..SIZE]`.
    fn put(&self, out: &mut [u8]);
    /// Reads a value from `bytes[..SIZE]`.
    fn get(bytes: &[u8]) -> Self;
    /// Whether every component is finite.
    fn is_finite(&self) -> bool;
    /// The scalar NanoVDB's statistics order and average: the value itself, or a vector's
    /// squared length (computed in `f32`, as NanoVDB does).
    fn stat(&self) -> f32;
}

impl NvdbValue for f32 {
    const GRID_TYPE: GridType = GridType::Float;
    const SIZE: usize = 4;
    const ZERO: Self = 0.0;
    fn put(&self, out: &mut [u8]) {
        out[..4].copy_from_slice(&self.to_le_bytes());
    }
    fn get(bytes: &[u8]) -> Self {
        f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])
    }
    fn is_finite(&self) -> bool {
        f32::is_finite(*self)
    }
    fn stat(&self) -> f32 {
        *self
    }
}

impl NvdbValue for Vec3 {
    const GRID_TYPE: GridType = GridType::Vec3f;
    const SIZE: usize = 12;
    const ZERO: Self = Vec3::ZERO;
    fn put(&self, out: &mut [u8]) {
        for (i, x) in self.to_array().into_iter().enumerate() {
            out[4 * i..4 * i + 4].copy_from_slice(&x.to_le_bytes());
        }
    }
    fn get(bytes: &[u8]) -> Self {
        Vec3::new(f32::get(bytes), f32::get(&bytes[4..]), f32::get(&bytes[8..]))
    }
    fn is_finite(&self) -> bool {
        Vec3::is_finite(*self)
    }
    fn stat(&self) -> f32 {
        self.x * self.x + self.y * self.y + self.z * self.z
    }
}

/// The affine map from index space (integer coordinates at voxel centres) to world space:
/// `world = matrix · ijk + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndexToWorld {
    /// The linear part: a rotation times the voxel size (columns: the world vectors of one
    /// index step along i, j and k).
    pub matrix: DMat3,
    /// The world position of index `(0, 0, 0)`, the centre of that voxel.
    pub translation: DVec3,
}

impl IndexToWorld {
    /// The map of a voxlod grid: voxel `(i, j, k)` at index `(i, j, k)`, its centre
    /// `origin + (i + ½) · voxel_size` (see the [module docs](self)).
    pub fn from_grid_spec(grid: &GridSpec) -> Self {
        Self {
            matrix: DMat3::from_diagonal(DVec3::splat(grid.voxel_size)),
            translation: grid.origin + DVec3::splat(0.5 * grid.voxel_size),
        }
    }

    /// The world position of index-space point `ijk`.
    pub fn apply(&self, ijk: DVec3) -> DVec3 {
        self.matrix * ijk + self.translation
    }

    /// The voxel size per axis (the lengths of the matrix columns).
    pub fn voxel_size(&self) -> DVec3 {
        DVec3::new(
            self.matrix.x_axis.length(),
            self.matrix.y_axis.length(),
            self.matrix.z_axis.length(),
        )
    }

    /// Checks that NanoVDB can hold this map: finite, with orthogonal columns of one positive
    /// length (a rotation or reflection times a uniform scale).
    pub fn validate(&self) -> Result<()> {
        let refuse = |reason: &str| {
            Err(unrepresentable(
                format!("the index-to-world map {:?} + {}", self.matrix, self.translation),
                reason.into(),
            ))
        };
        if !(self.matrix.is_finite() && self.translation.is_finite()) {
            return refuse("the map must be finite");
        }
        let s = self.voxel_size();
        let scale = s.x;
        if !(scale > 0.0 && scale.is_finite())
            || (s - DVec3::splat(scale)).abs().max_element() > 1e-9 * scale
        {
            return refuse("NanoVDB maps need columns of one positive length (uniform scale)");
        }
        let m = self.matrix;
        let dots = [m.x_axis.dot(m.y_axis), m.y_axis.dot(m.z_axis), m.z_axis.dot(m.x_axis)];
        if dots.iter().any(|d| d.abs() > 1e-9 * scale * scale) {
            return refuse("NanoVDB maps need orthogonal columns (a rotation times a scale)");
        }
        Ok(())
    }
}

/// One sparse NanoVDB grid: its name, class, map, background and active voxels.
#[derive(Clone, Debug, PartialEq)]
pub struct NvdbGrid<T> {
    /// The grid's name (≤ [`MAX_NAME_BYTES`] bytes, no NUL).
    pub name: String,
    /// What the values mean.
    pub class: GridClass,
    /// Index to world.
    pub map: IndexToWorld,
    /// The value of every inactive voxel.
    pub background: T,
    /// The active voxels: index coordinate and value, each coordinate once. [`read`] returns
    /// them in the file's order (root tiles, then each node's children by offset).
    pub voxels: Vec<(IVec3, T)>,
}

impl<T: NvdbValue> NvdbGrid<T> {
    /// The grid of `map`'s voxels on `grid` (see [`IndexToWorld::from_grid_spec`]): every voxel
    /// of the map active, with `value(record)`, background zero.
    ///
    /// Errors: `grid` invalid or of other dims than `map` ([`Error::InvalidGrid`]).
    pub fn from_brick_map<R>(
        name: &str,
        class: GridClass,
        grid: &GridSpec,
        map: &BrickMap<R>,
        value: impl Fn(&R) -> T,
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
        Ok(Self {
            name: name.into(),
            class,
            map: IndexToWorld::from_grid_spec(grid),
            background: T::ZERO,
            voxels: map.iter().map(|(c, r)| (c.as_ivec3(), value(r))).collect(),
        })
    }
}

/// A grid of either value type, as a file holds several.
#[derive(Clone, Debug, PartialEq)]
pub enum AnyGrid {
    /// A `float` grid.
    Float(NvdbGrid<f32>),
    /// A `Vec3f` grid.
    Vec3f(NvdbGrid<Vec3>),
}

impl AnyGrid {
    /// The grid's name.
    pub fn name(&self) -> &str {
        match self {
            AnyGrid::Float(g) => &g.name,
            AnyGrid::Vec3f(g) => &g.name,
        }
    }

    /// Its active voxel count.
    pub fn voxel_count(&self) -> usize {
        match self {
            AnyGrid::Float(g) => g.voxels.len(),
            AnyGrid::Vec3f(g) => g.voxels.len(),
        }
    }
}

impl From<NvdbGrid<f32>> for AnyGrid {
    fn from(g: NvdbGrid<f32>) -> Self {
        AnyGrid::Float(g)
    }
}

impl From<NvdbGrid<Vec3>> for AnyGrid {
    fn from(g: NvdbGrid<Vec3>) -> Self {
        AnyGrid::Vec3f(g)
    }
}

/// The `density` (`float`, [`GridClass::FogVolume`], extinction per world unit from
/// [`AverageRecord::extinction`]) and `color` (`Vec3f`, linear RGB from
/// [`AverageRecord::color`]) grids of an Averages grid.
pub fn density_and_color(
    grid: &GridSpec,
    map: &BrickMap<AverageRecord>,
) -> Result<(NvdbGrid<f32>, NvdbGrid<Vec3>)> {
    let size = grid.voxel_size;
    let density = NvdbGrid::from_brick_map("density", GridClass::FogVolume, grid, map, |r| {
        r.extinction(size)
    })?;
    let color = NvdbGrid::from_brick_map("color", GridClass::Unknown, grid, map, |r| r.color())?;
    Ok((density, color))
}

/// The `density` grid of an occupancy map: every occupied voxel fully opaque (opacity 1, so
/// `σ = `[`MAX_VOXEL_OPTICAL_DEPTH`](crate::records::MAX_VOXEL_OPTICAL_DEPTH)` / voxel size`).
pub fn occupancy_density<R>(grid: &GridSpec, map: &BrickMap<R>) -> Result<NvdbGrid<f32>> {
    let sigma = extinction_from_opacity(1.0, grid.voxel_size);
    NvdbGrid::from_brick_map("density", GridClass::FogVolume, grid, map, |_| sigma)
}

/// What [`encode`] wrote for one grid.
#[derive(Clone, Debug, PartialEq)]
pub struct GridSummary {
    /// The grid's name.
    pub name: String,
    /// Its value type.
    pub grid_type: GridType,
    /// Active voxels.
    pub voxels: u64,
    /// Nodes per level: leaves, lower, upper, and the root's tiles.
    pub nodes: [u32; 4],
    /// Bytes of the grid in the file.
    pub bytes: u64,
    /// The stored checksum (head CRC in the low 32 bits, tail CRC in the high 32 bits).
    pub checksum: u64,
}

/// The bytes of an `.nvdb` file holding `grids` (at least one), with a summary per grid.
/// Errors: anything the format cannot hold ([`Error::Unrepresentable`], see the
/// [module docs](self)); nothing is written.
pub fn encode(grids: &[AnyGrid]) -> Result<(Vec<u8>, Vec<GridSummary>)> {
    if grids.is_empty() {
        return Err(unrepresentable(
            "a file of no grids".into(),
            "an .nvdb file holds one grid or more".into(),
        ));
    }
    if grids.len() > u16::MAX as usize {
        return Err(unrepresentable(
            format!("{} grids", grids.len()),
            "a file segment counts its grids in 16 bits".into(),
        ));
    }
    let built = grids
        .iter()
        .map(|g| match g {
            AnyGrid::Float(g) => layout::build(g),
            AnyGrid::Vec3f(g) => layout::build(g),
        })
        .collect::<Result<Vec<_>>>()?;
    let mut out = Vec::new();
    layout::write_file(&mut out, &built);
    let summaries = built.iter().map(|b| b.summary.clone()).collect();
    Ok((out, summaries))
}

/// Writes `grids` as an `.nvdb` file, atomically (see [`encode`]).
///
/// ```
/// use glam::{DMat3, DVec3, IVec3};
/// use voxlod_format::nvdb::{self, AnyGrid, GridClass, IndexToWorld, NvdbGrid};
/// let grid = NvdbGrid {
///     name: "density".into(),
///     class: GridClass::FogVolume,
///     map: IndexToWorld { matrix: DMat3::from_diagonal(DVec3::splat(0.5)), translation: DVec3::ZERO },
///     background: 0.0f32,
///     voxels: vec![(IVec3::new(1, 2, 3), 0.25), (IVec3::new(5000, 0, 0), 2.0)],
/// };
/// let path = std::env::temp_dir().join("voxlod-doc.nvdb");
/// let summary = nvdb::write(&path, &[AnyGrid::Float(grid.clone())]).unwrap();
/// assert_eq!(summary[0].nodes, [2, 2, 2, 2]); // two root tiles: the voxels are 4096 apart
/// let back = nvdb::read(&path).unwrap();
/// assert_eq!(back, [AnyGrid::Float(grid)]);
/// ```
pub fn write(path: impl AsRef<Path>, grids: &[AnyGrid]) -> Result<Vec<GridSummary>> {
    let (bytes, summaries) = encode(grids)?;
    crate::io::write_bytes_atomic(path.as_ref(), &bytes)?;
    Ok(summaries)
}

/// NanoVDB's string hash of grid names (`nanovdb::io::stringHash`), stored in the file's
/// metadata records.
pub fn name_hash(name: &str) -> u64 {
    name.bytes().fold(0u64, |hash, b| {
        let overflow = hash >> 56;
        hash.wrapping_mul(67).wrapping_add(b as u64).wrapping_add(overflow)
    })
}

fn unrepresentable(what: String, reason: String) -> Error {
    Error::Unrepresentable { format: "nvdb", what, reason }
}

#[cfg(test)]
mod tests;
