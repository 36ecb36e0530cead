//! voxlod: voxel representations of triangle scenes. This facade re-exports the layered crates:
//!
//! - [`format`](mod@format): grids, Morton codes, sparse brick maps, `.vxl` and binvox;
//! - [`scene`]: meshes, materials, cameras, lights, OBJ/glTF loaders, procedural scenes;
//! - [`cpu`]: the CPU references (voxelizers, ray casting, renderers, shading);
//! - [`eval`]: metrics (MSE, PSNR, SSIM) and reports.

#![warn(missing_docs)]

pub use voxlod_cpu as cpu;
pub use voxlod_eval as eval;
pub use voxlod_format as format;
pub use voxlod_scene as scene;
