//! voxlod's studies: each representation voxlod builds, measured against a ground-truth render
//! of the mesh it came from — image error (MSE, SSIM on 8-bit sRGB), memory, precompute and
//! render time — as report sections (markdown tables, image grids, SVG plots) and JSON.
//!
//! Every study has the same shape: a configuration struct with `quick()` (minutes on two
//! cores) and `full()` (the papers' settings) presets, a `run` function that returns a result
//! holding every measured number, and methods that turn the result into tables and report
//! sections. The `voxlod` command line only parses arguments into a configuration, calls `run`
//! and writes what it returns.
//!
//! | module | study |
//! |---|---|
//! | [`report`] | the default report (`cargo run --release`): every study below on the embedded scenes |
//! | [`baseline`] | ground truth and its noise, voxelization, the voxel baseline (opaque cubes of average colour) per resolution |
//! | [`filtered`] | the filtered-appearance representations of Brito, Poulin and Teichrieb (2023): Averages, \[VJK21\], virtual mesh + opacity subgrid, Adaptive |
//! | [`volume`] | procedural participating media with metavoxels (McNabb, GPU Pro): attenuation models, metavoxel sizes, memory |
//! | [`cone`] | voxel cone tracing on the sparse voxel octree: AO and indirect light against ray-traced references, light leaking, and ([`cone::lod`]) primary visibility with level of detail by distance |
//! | [`heitz_neyret`] | Heitz and Neyret's (2012) pre-filtered surface statistics with coverage masks against alpha blending over distance: error, silhouettes, colour at grazing angles, cost, bytes per node |
//!
//! Shared pieces: [`scenes`] (scene specs, with the embedded models), [`views`] (orbiting
//! cameras), [`spread`] (mean and range over views), [`alloc`] (peak heap memory per stage),
//! [`backend`] (where a study's GPU-capable images are rendered), [`machine`] (the machine a
//! report names).
//!
//! ```
//! // The smallest baseline study: the embedded bunny at 16³, one 16² view.
//! use voxlod_studies::report::{self, Config};
//! use voxlod_studies::backend::Backend;
//!
//! let config = Config {
//!     scenes: vec![report::SceneCase::new("builtin:bunny", "bunny")],
//!     resolutions: vec![16],
//!     image_size: 16,
//!     gt_spp: 4,
//!     views: 1,
//!     filtered: None,
//!     volume: None,
//!     cone: None,
//!     ..Config::quick()
//! };
//! let outcome = report::run(&config, Backend::Cpu, &|_| {})?;
//! let row = &outcome.scenes[0].rows[0];
//! assert_eq!(row.resolution, 16);
//! assert!(row.ssim.mean > 0.0 && row.ssim.mean <= 1.0);
//! # Ok::<(), voxlod_studies::Error>(())
//! ```

#![deny(missing_docs)]

pub mod alloc;
pub mod backend;
pub mod baseline;
pub mod cone;
mod error;
pub mod filtered;
mod ground_truths;
pub mod heitz_neyret;
pub mod machine;
pub mod report;
pub mod scenes;
pub mod spread;
pub mod views;
pub mod volume;

pub use error::Error;
pub use spread::Spread;
