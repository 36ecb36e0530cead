//! Sparse voxel octrees for voxel cone tracing (Yalçıner and Sahillioğlu 2020, §4.3–4.4, after
//! Crassin et al. 2011): built bottom-up from Morton-sorted voxels, top levels stored densely
//! (the paper's 64³ by default), sparse levels as 2×2×2 node tiles with child pointers, forward
//! neighbour links on +x, +y, +z and the extra nodes that make every trilinear interpolation
//! find its data, pre-filtered payloads, and quadrilinear sampling (trilinear within a level,
//! linear between two).
//!
//! # Example
//! Build an octree over a floor of voxels, sample it at two footprints and read its memory.
//! ```
//! use glam::{DVec3, UVec3, Vec3};
//! use voxlod_format::GridSpec;
//! use voxlod_octree::{AveragePayload, BuildOptions, Octree};
//!
//! # fn main() -> voxlod_octree::Result<()> {
//! // A 64 × 64 white floor at y = 0 in a 64³ grid of 0.25 m voxels, stored densely down to
//! // 8³ nodes (the default, the paper's 64³, suits larger scenes) and sparsely below.
//! let grid = GridSpec::new(DVec3::ZERO, 0.25, UVec3::splat(64))?;
//! let white = AveragePayload::new(Vec3::ONE, Vec3::Y, 1.0);
//! let floor = (0..64 * 64).map(|i| (UVec3::new(i % 64, 0, i / 64), white));
//! let tree = Octree::build(grid, floor, &BuildOptions { dense_log2: 3, ..Default::default() })?;
//! assert_eq!((tree.depth(), tree.voxel_count()), (6, 4096));
//!
//! // Positions are in grid units (voxel i spans [i, i+1)), footprints in voxels. A one-voxel
//! // footprint at a floor voxel's centre reads that leaf: opaque.
//! assert!((tree.sample(Vec3::new(10.5, 0.5, 10.5), 1.0).opacity - 1.0).abs() < 1e-6);
//! // A 4-voxel footprint reads level 2, whose node averages 4³ voxels, one layer of them floor.
//! let coarse = tree.sample(Vec3::new(10.0, 2.0, 10.0), 4.0);
//! assert!((coarse.opacity - 0.25).abs() < 1e-6 && (coarse.color() - Vec3::ONE).length() < 1e-5);
//! // The world-space version, and empty space.
//! assert_eq!(tree.sample_world(DVec3::new(8.0, 8.0, 8.0), 0.25).opacity, 0.0);
//!
//! // Memory by role. The leaf level stores the floor and the rest of its 2×2×2 node tiles,
//! // 8 192 of its 64³ nodes; validate() checks every structural invariant.
//! let stats = tree.memory_stats();
//! assert_eq!((stats.levels[0].nodes, stats.occupied_voxels), (8192, 4096));
//! println!("{:.0} bytes per voxel", stats.per_voxel(stats.total_bytes()));
//! tree.validate()?;
//! # Ok(())
//! # }
//! ```
//!
//! # Modules
//! | module | owns |
//! |---|---|
//! | [`payload`] | the [`Payload`] trait (how eight children combine) and its Averages, SGGX and six-directional-opacity implementations |
//! | [`microsurface`] | [`MicrosurfacePayload`]: Heitz and Neyret's (2012) distance, normal-distribution and height-correlated colour statistics, and Smith's model written stably for their renderer |
//! | [`octree`] | the [`Octree`] layout, [`BuildOptions`], which nodes exist and why |
//! | [`topology`] | [`Topology`]: the occupied levels and their child structure alone, the first step of the build |
//! | `build` | the CPU reference build ([`Octree::build`], [`Octree::from_brick_map`], [`Octree::from_topology`]) |
//! | `sample` | [`Octree::sample`] (position + footprint diameter), [`Octree::sample_level`], [`Octree::sample_world`] |
//! | `validate` | [`Octree::validate`]: every structural invariant, parents equal to the pre-filter of their children within [`PREFILTER_TOLERANCE`] |
//! | [`stats`] | [`MemoryStats`]: nodes per level, bytes by role, bytes per voxel |
//! | [`gpu_layout`] | [`FlatOctree`]: the `#[repr(C)]` GPU layout, and a CPU emulation of the lock-free level-by-level GPU build |
//! | [`dynamic`] | moving objects by voxel transformation: object-space voxel caches, per-frame rigid and skinned transforms, nearest and 8-neighbour filters, the fixed-point blend into the world voxels the octree is rebuilt from |
//!
//! # Errors
//! Every fallible call returns [`Error`]: a depth, grid or dense region the layout cannot hold
//! ([`Error::TooDeep`], [`Error::GridDoesNotFit`], [`Error::DenseTooLarge`],
//! [`Error::TooManyNodes`]); a voxel outside the grid, repeated or out of Morton order
//! ([`Error::OutOfBounds`], [`Error::DuplicateVoxel`], [`Error::OutOfOrder`]); a non-finite
//! payload or an opacity outside \[0, 1\] ([`Error::InvalidPayload`]); a payload count that does
//! not match a topology ([`Error::PayloadCount`]); an invalid grid ([`Error::Grid`]); a broken
//! invariant found by [`Octree::validate`], with its level and node ([`Error::Invalid`]).
//!
//! # What this crate does not do
//! - No light injection or cone tracing (voxlod-cone does both on this octree).
//! - No GPU build here: voxlod-gpu's `octree` kernel runs the algorithm
//!   [`FlatOctree::build_level_by_level`] emulates, and is checked against it.
//! - No updates: an octree is built once; changed voxels mean a new build.
//! - Virtual-mesh records are not supported as payloads: merging them across levels is open
//!   research (Brito et al. 2023, §6).
//! - Everything is in memory, payloads as `f32`: no streaming, no compression.
//!
//! This crate depends on voxlod-format only (no GPU API, no scene crate), so another project
//! can use it alone.
//!
//! # References
//! - Yalçıner, Sahillioğlu 2020, "Voxel transformation: scalable scene geometry discretization
//!   for global illumination", Journal of Real-Time Image Processing 17(5), §4.3–4.4: the SVO,
//!   its dense top levels, node tiles and neighbour pointers ([`octree`], [`gpu_layout`]).
//! - Crassin, Neyret, Sainz, Green, Eisemann 2011, "Interactive Indirect Illumination Using Voxel
//!   Cone Tracing", Pacific Graphics: the pre-filtered octree, directional opacities
//!   ([`payload`]).
//! - Crassin, Neyret, Lefebvre, Eisemann 2009, "GigaVoxels: Ray-Guided Streaming for Efficient
//!   and Detailed Voxel Rendering", I3D: node tiles.
//! - Laine, Karras 2010, "Efficient Sparse Voxel Octrees", I3D: [`Topology`]'s child
//!   descriptors, and the memory anchor of [`stats`].
//! - Heitz, Dupuy, Crassin, Dachsbacher 2015, "The SGGX Microflake Distribution", SIGGRAPH:
//!   [`SggxPayload`].

#![deny(missing_docs)]

mod build;
pub mod dynamic;
mod error;
pub mod gpu_layout;
mod input;
pub mod microsurface;
pub mod octree;
pub mod payload;
mod sample;
pub mod stats;
pub mod topology;
mod validate;

pub use error::{Error, Result};
pub use gpu_layout::{FlatOctree, GpuLevel, GpuNode, GpuTile};
pub use input::plan;
pub use microsurface::{Microsurface, MicrosurfacePayload};
pub use octree::{BuildOptions, LevelView, MAX_DENSE_LOG2, MAX_DEPTH, NONE, Octree};
pub use payload::{AveragePayload, DIRECTIONS, Directional, Payload, SggxPayload};
pub use stats::{LevelStats, MemoryStats};
pub use topology::Topology;
pub use validate::PREFILTER_TOLERANCE;

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;

#[cfg(test)]
mod tests;
