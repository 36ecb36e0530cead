//! The voxel data formats of voxlod: the grid a scene is voxelized into ([`GridSpec`]), 63-bit
//! 3D Morton codes ([`morton`]), a sparse grid that stores only occupied 8³ bricks
//! ([`BrickMap`]), the frozen per-voxel appearance records of the filtered representations
//! ([`records`]), and files: voxlod's own `.vxl` container ([`vxl`]: versioned, checksummed,
//! typed records), and for the tools people already have binvox ([`binvox`]), MagicaVoxel
//! `.vox` ([`vox`]), Mitsuba 3's grid volumes ([`vol`]) and NanoVDB's sparse grids
//! ([`nvdb`]).
//!
//! This crate is the bottom of the voxlod stack: every other voxlod crate speaks its types, and
//! it depends on no other voxlod crate and on no GPU API. Every type a GPU reads
//! ([`brickmap::BrickHeader`], the records) is `#[repr(C)]` and [`bytemuck::Pod`].
//!
//! # Example
//! Fit a grid to a box, index voxels by Morton code, store a sparse map of one `f32` per
//! occupied voxel, and write and read it back as a `.vxl` file.
//! ```
//! use glam::{DVec3, UVec3};
//! use voxlod_format::{BrickMap, GridSpec, morton, vxl};
//!
//! # fn main() -> voxlod_format::Result<()> {
//! // A 2 × 1 × 1 box, 64 voxels along its longest axis: voxels of 1/32.
//! let grid = GridSpec::fit(DVec3::ZERO, DVec3::new(2.0, 1.0, 1.0), 64)?;
//! assert_eq!(grid.dims, UVec3::new(64, 32, 32));
//! assert_eq!(grid.voxel_of(DVec3::splat(0.3)), Some(UVec3::splat(9)));
//!
//! // Morton codes interleave the bits of x, y and z (x lowest) and round-trip.
//! assert_eq!(morton::encode(UVec3::new(1, 1, 0)), 0b011);
//! assert_eq!(morton::decode(morton::encode(UVec3::new(5, 9, 31))), UVec3::new(5, 9, 31));
//!
//! // The diagonal (i, i, i): 32 voxels in 4 bricks of 8³, out of 256 bricks in the box.
//! let map = BrickMap::from_voxels(grid.dims, (0..32).map(|i| (UVec3::splat(i), i as f32)))?;
//! assert_eq!((map.len(), map.bricks().len()), (32, 4));
//! assert_eq!(map.get(UVec3::splat(9)), Some(&9.0));
//! assert_eq!(map.get(UVec3::new(9, 9, 8)), None);
//!
//! // A .vxl file: written atomically, read back with its grid, records and metadata.
//! let path = std::env::temp_dir().join("voxlod-format-example.vxl");
//! vxl::write(&path, &grid, &map, &[("scene".into(), "diagonal".into())])?;
//! let file = vxl::read::<f32>(&path)?;
//! assert_eq!((file.grid, file.map.values()), (grid, map.values()));
//! assert_eq!(file.meta_value("scene"), Some("diagonal"));
//! assert!(vxl::read::<u32>(&path).is_err()); // records are typed
//! # Ok(())
//! # }
//! ```
//!
//! # Main types
//! | item | what it is |
//! |---|---|
//! | [`GridSpec`] | origin, voxel size (`f64`) and dimensions; voxel `(i, j, k)` covers `origin + [i, i+1)·voxel_size` per axis |
//! | [`morton`] | [`morton::encode`] / [`morton::decode`] of 63-bit codes (21 bits per axis); steps along one axis without decoding |
//! | [`BrickMap`] | occupied 8³ bricks (a 512-bit mask and a packed run of values each), sorted by Morton code; iteration in global Morton order |
//! | [`vxl`] | [`vxl::write`] / [`vxl::read`] / [`vxl::read_info`]; [`VxlRecord`], the trait a storable record implements; the zero-sized [`Occupancy`] |
//! | [`binvox`] | occupancy export (padded to a cube, world positions kept) and strict import of versions 1 and 2 |
//! | [`vox`] | MagicaVoxel export (occupancy, a 255-colour palette by median cut + k-means with its measured error, 256³ models placed by the scene graph) and import (rotations, translations and the default palette applied) |
//! | [`vol`] | Mitsuba 3 `.vol` grid volumes (dense `float32`, 1/3/6 channels): density (extinction) and albedo of an Averages grid; read and write |
//! | [`nvdb`] | NanoVDB `.nvdb` (NanoVDB 32.4's flat layout): sparse `float` and `Vec3f` grids with node statistics, index-to-world map (index = voxel centre) and full checksum; density (extinction) and colour of an Averages grid; read and write |
//! | [`import`] | `.vox` scenes and `.vol` density (+ albedo) grids as Averages records over a grid, for `.vxl` |
//! | [`records`] | the Averages, SGGX, virtual-mesh and specular records and the adaptive grid's reference, with their quantizers ([`records::quant`]) |
//! | [`origin`] | [`origin::recentring_origin`]: the `f64` offset that brings a box far from the world origin next to it (0 for a box that reaches near the origin), so its coordinates fit `f32` |
//! | [`io`] | [`io::write_atomic`]: a temporary file renamed over the target, so a failure never leaves half a file |
//!
//! Memory follows occupied content: a [`BrickMap`] holds 80 bytes per occupied brick, one value
//! per occupied voxel and a hash entry per brick, whatever the grid's bounding box.
//!
//! # Errors
//! Every fallible call returns [`Error`], each variant naming what and where: a grid that is
//! invalid, too large or cannot be fitted to its bounds ([`Error::InvalidGrid`],
//! [`Error::GridTooLarge`], [`Error::InvalidBounds`]); a voxel outside the grid or given twice
//! ([`Error::OutOfBounds`], [`Error::DuplicateVoxel`]); a failed read or write, with the path
//! ([`Error::Io`]); a truncated, corrupted or inconsistent file, with the byte offset
//! ([`Error::Malformed`]); a newer format version ([`Error::UnsupportedVersion`]); records of
//! another type than the one asked for ([`Error::RecordMismatch`]); a checksum that does not
//! match ([`Error::ChecksumMismatch`]); metadata that cannot be stored
//! ([`Error::InvalidMetadata`]); data a format cannot hold, refused before anything is written
//! ([`Error::Unrepresentable`]); a file using a feature this library does not read
//! ([`Error::Unsupported`]). Reading never trusts the file: no allocation is sized by a count
//! before the count is checked against the file's length, and malformed input is an error, never
//! a panic.
//!
//! # What this crate does not do
//! - It does not voxelize or load meshes (voxlod-cpu voxelizes, voxlod-scene loads OBJ and glTF).
//! - No compression beyond sparsity: payloads are stored as they are in memory, little-endian.
//! - Files are read whole into memory; there is no streaming or memory-mapped access.
//! - binvox carries occupancy only; records need `.vxl`. `.vox` keeps occupancy and quantized
//!   colours but not the grid's origin and voxel size; `.vol` is dense.
//! - No OpenVDB `.vdb`: [`nvdb`] writes NanoVDB, which OpenVDB's `nanovdb_convert` turns into
//!   `.vdb`; `.nvdb` files are uncompressed, and only `float` and `Vec3f` grids with every
//!   active value in a leaf are read.
//! - A [`BrickMap`] is built once from its voxels: values can change in place, but voxels cannot
//!   be added or removed without rebuilding it.
//!
//! # References
//! - Brito, Poulin, Teichrieb 2023, "Voxel-based Representations for Improved Filtered
//!   Appearance", High-Performance Graphics, §3.3–3.4 and §4: the Averages, SGGX and
//!   virtual-mesh records ([`records`]).
//! - Vicini, Jakob, Kaplanyan 2021, "A Non-Exponential Transmittance Model for Volumetric Scene
//!   Representations", SIGGRAPH (\[VJK21\]): the SGGX record's σ and γ.
//! - Heitz, Dupuy, Crassin, Dachsbacher 2015, "The SGGX Microflake Distribution", SIGGRAPH: the
//!   SGGX matrix.
//! - Min, binvox file format specification (`patrickmin.com/binvox`): [`binvox`].
//! - ephtracy, "MagicaVoxel .vox File Format" and its scene-graph extension
//!   (`github.com/ephtracy/voxel-model`); Heckbert 1982, "Color image quantization for frame
//!   buffer display", SIGGRAPH (median cut): [`vox`].
//! - Mitsuba 3 documentation, `gridvolume` plugin (the `.vol` layout): [`vol`].
//! - Museth 2021, "NanoVDB: A GPU-Friendly and Portable VDB Data Structure For Real-Time
//!   Rendering And Simulation", SIGGRAPH Talks, and OpenVDB 10.0's NanoVDB headers (the
//!   layout, file codec and checksum): [`nvdb`].

#![deny(missing_docs)]

pub mod binvox;
pub mod brickmap;
mod error;
pub mod grid;
pub mod import;
pub mod io;
pub mod morton;
pub mod nvdb;
pub mod origin;
pub mod records;
pub mod vol;
pub mod vox;
pub mod vxl;

pub use brickmap::{BRICK_EDGE, BRICK_VOXELS, BrickMap};
pub use error::{Error, Result};
pub use grid::GridSpec;
pub use vxl::{Occupancy, VxlRecord};

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;
