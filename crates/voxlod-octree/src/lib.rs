//! Sparse voxel octrees for voxel cone tracing (Yalçıner and Sahillioğlu 2020, §4.3–4.4, after Crassin et al. 2011): built bottom-up from
//! Morton-sorted voxels, top levels stored densely (the paper's 64³ by default), sparse levels
//! as 2×2×2 node tiles with child pointers, forward neighbour links on +x, +y, +z and the extra
//! nodes that make every trilinear interpolation find its data, pre-filtered payloads, and
//! quadrilinear sampling (trilinear within a level, linear between two).
//!
//! | module | owns |
//! |---|---|
//! | [`payload`] | the [`Payload`] trait (how eight children combine) and its Averages, SGGX and six-directional-opacity implementations |
//! | [`microsurface`] | [`MicrosurfacePayload`]: Heitz and Neyret's (2012) distance, normal-distribution and height-correlated colour statistics, and Smith's model written stably for their renderer |
//! | [`octree`] | the [`Octree`] layout, [`BuildOptions`], which nodes exist and why |
//! | [`topology`] | [`Topology`]: the occupied levels and their child structure alone, the first step of the build |
//! | `build` | the CPU reference build ([`Octree::build`], [`Octree::from_brick_map`], [`Octree::from_topology`]) |
//! | `sample` | [`Octree::sample`] (position + footprint diameter), [`Octree::sample_level`] |
//! | `validate` | [`Octree::validate`]: every structural invariant |
//! | [`stats`] | [`MemoryStats`]: nodes per level, bytes by role, bytes per voxel |
//! | [`gpu_layout`] | [`FlatOctree`]: the `#[repr(C)]` GPU layout, and a CPU emulation of the lock-free level-by-level GPU build |
//!
//! This crate depends on `voxlod-format` only (no GPU API, no scene crate), so another project
//! can use it alone. Out of scope: merging virtual-mesh records across levels (open research,
//! Brito et al. 2023, §6), light injection and cone tracing (`voxlod-cone`), the wgpu kernel of the build
//! (voxlod-gpu's `octree` module; its algorithm is emulated and checked in [`gpu_layout`]).
//!
//! ```
//! use glam::{DVec3, UVec3, Vec3};
//! use voxlod_format::GridSpec;
//! use voxlod_octree::{AveragePayload, BuildOptions, Octree, Payload};
//!
//! // A 2×1×1 red wall in a 16³ grid.
//! let grid = GridSpec::new(DVec3::ZERO, 0.5, UVec3::splat(16))?;
//! let red = AveragePayload::new(Vec3::new(1.0, 0.0, 0.0), Vec3::Z, 1.0);
//! let voxels = [(UVec3::new(4, 4, 4), red), (UVec3::new(5, 4, 4), red)];
//! let tree = Octree::build(grid, voxels, &BuildOptions { depth: None, dense_log2: 2 })?;
//! assert_eq!(tree.depth(), 4);
//!
//! // At a voxel centre with a one-voxel footprint: that voxel's payload.
//! let p = tree.sample(Vec3::new(4.5, 4.5, 4.5), 1.0);
//! assert!((p.opacity - 1.0).abs() < 1e-6 && (p.color() - Vec3::X).length() < 1e-6);
//! // Halfway between the two voxels' centres and empty space below: trilinear.
//! assert!((tree.sample_level(Vec3::new(5.0, 4.0, 4.5), 0).opacity - 0.5).abs() < 1e-6);
//! // A 2-voxel footprint reads level 1, whose node (2,2,2) averages the 8 voxels it covers.
//! assert!((tree.sample(Vec3::splat(5.0), 2.0).opacity - 0.25).abs() < 1e-6);
//! let stats = tree.memory_stats();
//! assert_eq!(stats.occupied_voxels, 2);
//! tree.validate()?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

mod build;
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

#[cfg(test)]
mod tests;
