//! voxlod: voxel representations of triangle scenes. This facade re-exports the layered crates:
//!
//! - [`format`](mod@format): grids, Morton codes, sparse brick maps, `.vxl` and binvox;
//! - [`scene`]: meshes, materials, cameras, lights, OBJ/glTF loaders, procedural scenes;
//! - [`cpu`]: the CPU references (voxelizers, ray casting, renderers, shading);
//! - [`eval`]: metrics (MSE, PSNR, SSIM) and reports;
//! - [`gpu`]: the wgpu backend (kernels checked against the CPU references; only used when
//!   asked for, e.g. `--backend gpu`: without a GPU everything else still runs);
//!
//! and adds scene specs with embedded models ([`scenes`]), the default experiment
//! ([`experiment`]) and peak-memory measurement ([`alloc`]).

#![warn(missing_docs)]

pub mod alloc;
mod error;
pub mod experiment;
pub mod scenes;

pub use error::Error;
pub use voxlod_cpu as cpu;
pub use voxlod_eval as eval;
pub use voxlod_format as format;
pub use voxlod_gpu as gpu;
pub use voxlod_scene as scene;
