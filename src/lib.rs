//! voxlod: voxel representations of triangle scenes — voxelize a mesh scene, pre-filter what
//! each voxel looks like from every direction, store it sparsely, render it, and measure what
//! each representation costs and buys against a ground-truth render of the mesh.
//!
//! This crate is the facade: it re-exports every voxlod library crate under a short name, and
//! holds the `voxlod` command-line tool. Depend on a layer crate directly when you want only
//! that layer (e.g. `voxlod-format` or `voxlod-octree`, which build without the GPU stack).
//!
//! | module | crate | what it owns |
//! |---|---|---|
//! | [`format`](mod@format) | `voxlod-format` | grids, Morton codes, sparse brick maps, `.vxl` and binvox, atomic writes |
//! | [`scene`] | `voxlod-scene` | meshes, materials, cameras, lights, OBJ/glTF loaders, procedural scenes, particles |
//! | [`cpu`] | `voxlod-cpu` | the CPU references: voxelizers, ray casting, renderers, shading, filtered appearance, volumes |
//! | [`octree`] | `voxlod-octree` | the sparse voxel octree, pre-filtered payloads, quadrilinear sampling |
//! | [`cone`] | `voxlod-cone` | light injection and voxel cone tracing on the octree |
//! | [`gpu`] | `voxlod-gpu` | the wgpu backend, each kernel checked against its CPU reference |
//! | [`eval`] | `voxlod-eval` | metrics (MSE, PSNR, SSIM), heat maps, report writer |
//! | [`studies`] | `voxlod-studies` | every study: the default report, filtered appearance, volumes, cone tracing |
//!
//! ```
//! // Voxelize the embedded bunny at 32³ and count the occupied voxels.
//! use voxlod::cpu::voxelize::{self, Options};
//! use voxlod::format::GridSpec;
//!
//! let scene = voxlod::studies::scenes::load("builtin:bunny")?;
//! let (lo, hi) = scene.bounds()?;
//! let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 32)?;
//! let voxels = voxelize::voxelize(&scene.geometry(), &grid, &Options::default())?;
//! assert!(voxels.voxels.len() > 1000);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

pub use voxlod_cone as cone;
pub use voxlod_cpu as cpu;
pub use voxlod_eval as eval;
pub use voxlod_format as format;
pub use voxlod_gpu as gpu;
pub use voxlod_octree as octree;
pub use voxlod_scene as scene;
pub use voxlod_studies as studies;

/// The README's Rust examples, compiled and run as doc tests (`cargo test --doc -p voxlod`).
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
