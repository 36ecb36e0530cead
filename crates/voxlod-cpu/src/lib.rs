//! CPU references of voxlod, parallel with rayon: the shading function every renderer shares
//! ([`shading`]), counter-based random numbers ([`random`]), exact fixed-point voxelizers
//! ([`voxelize`]), BVH ray casting ([`raycast`]), the ground-truth mesh renderer and the voxel
//! renderers ([`render`]), sparse procedural volumes with metavoxels ([`volume`]).
//!
//! Each GPU kernel of voxlod-gpu is checked against the function here that it mirrors.

#![deny(missing_docs)]

pub mod appearance;
pub mod dynamic;
mod error;
pub mod random;
pub mod raycast;
pub mod render;
pub mod shading;
pub mod volume;
pub mod voxelize;

pub use error::{Error, Result};
