//! Voxel formats for voxlod: the grid a scene is voxelized into ([`GridSpec`]), 63-bit 3D Morton
//! codes ([`morton`]), a sparse brick map that allocates only occupied 8³ bricks ([`BrickMap`]),
//! and the on-disk containers: `.vxl` ([`vxl`]) and binvox ([`binvox`]).
//!
//! This crate is the bottom of the voxlod stack: it depends on no other voxlod crate and never on
//! a GPU API. Every type the GPU reads is `#[repr(C)]` and [`bytemuck::Pod`].

#![deny(missing_docs)]

pub mod binvox;
pub mod brickmap;
mod error;
pub mod grid;
pub mod io;
pub mod morton;
pub mod records;
pub mod vxl;

pub use brickmap::{BRICK_EDGE, BRICK_VOXELS, BrickMap};
pub use error::{Error, Result};
pub use grid::GridSpec;
pub use vxl::{Occupancy, VxlRecord};
