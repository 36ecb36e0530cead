//! voxlod's studies: each representation voxlod builds, measured against a ground-truth render
//! of the mesh it came from — image error (MSE, SSIM on 8-bit sRGB), memory, precompute and
//! render time — as report sections (markdown tables, image grids, SVG plots) and JSON.
//!
//! Every study has the same shape: a configuration struct with a `quick()` preset (minutes on two
//! cores; `full()`, where there is one, uses the papers' settings), a `run` function that returns
//! a result holding every measured number, and methods that turn the result into tables and
//! report sections. The `voxlod` command line only parses arguments into a configuration, calls
//! `run` and writes what it returns.
//!
//! # Example
//! Run the smallest baseline study on the CPU and write its report.
//! ```
//! use voxlod_studies::backend::Backend;
//! use voxlod_studies::report::{self, Config, SceneCase};
//!
//! # fn main() -> Result<(), voxlod_studies::Error> {
//! // The smallest baseline study: the embedded bunny voxelized at 16³, one 16² view, its ground
//! // truth at 4 rays per pixel; no filtered-appearance, volume or cone sections.
//! let config = Config {
//!     scenes: vec![SceneCase::new("builtin:bunny", "bunny")],
//!     resolutions: vec![16],
//!     image_size: 16,
//!     gt_spp: 4,
//!     views: 1,
//!     filtered: None,
//!     volume: None,
//!     cone: None,
//!     ..Config::quick()
//! };
//! let outcome = report::run(&config, Backend::Cpu, &|stage| eprintln!("{stage}"))?;
//!
//! // Every number it measured is in the result; the report holds the same as tables and images.
//! let row = &outcome.scenes[0].rows[0];
//! assert_eq!(row.resolution, 16);
//! assert!(row.ssim.mean > 0.0 && row.ssim.mean < 1.0 && row.mse.mean > 0.0);
//! let written = outcome.report.write(&std::env::temp_dir().join("voxlod-studies-example"))?;
//! assert!(std::fs::read_to_string(&written.markdown).expect("written").contains("bunny"));
//! # Ok(())
//! # }
//! ```
//!
//! # Studies
//! | module | study |
//! |---|---|
//! | [`report`] | the default report (`cargo run --release`): every study below on the embedded scenes |
//! | [`baseline`] | ground truth and its noise, voxelization, the voxel baseline (opaque cubes of average colour) per resolution |
//! | [`filtered`] | the filtered-appearance representations of Brito, Poulin and Teichrieb (2023): Averages, \[VJK21\], virtual mesh + opacity subgrid, Adaptive |
//! | [`volume`] | procedural participating media with metavoxels (McNabb 2015, GPU Pro 6): attenuation models, metavoxel sizes, memory |
//! | [`dynamic`] | dynamic scenes by voxel transformation (Yalçıner and Sahillioğlu 2020): transformed object-space caches against re-voxelization — agreement, exact rotations, temporal stability, time per frame against object count, a frame sequence on either backend |
//! | [`slicemap`] | slicemaps (Eisemann and Décoret 2006): holes against the exact voxelizers, transmittance shadow maps against ray-traced transmittance, the traversed volume for refraction against ray-cast intervals |
//! | [`cone`] | voxel cone tracing on the sparse voxel octree: AO and indirect light against ray-traced references, light leaking, and ([`cone::lod`]) primary visibility with level of detail by distance |
//! | [`heitz_neyret`] | Heitz and Neyret's (2012) pre-filtered surface statistics with coverage masks against alpha blending over distance: error, silhouettes, colour at grazing angles, cost, bytes per node |
//! | [`turntable`] | a camera orbiting the scene, each frame the ground truth beside the voxel baseline and Averages (labelled panels) as an animated PNG, with each panel's error over the turn |
//!
//! Shared pieces: [`scenes`] (scene specs, with the embedded models), [`views`] (orbiting
//! cameras), [`spread`] (mean and range over views), [`alloc`] (peak heap memory per stage),
//! [`backend`] (where a study's GPU-capable images are rendered), [`machine`] (the machine a
//! report names).
//!
//! Every image is scored against a ground truth rendered from the same camera, and the ground
//! truth's own noise (a second seed) is reported beside the differences it bounds; every row
//! names the backend that rendered it. Times are wall-clock on the machine the report names (on
//! lavapipe a GPU row's time is a CPU time); quality figures are deterministic for a given
//! configuration.
//!
//! # Errors
//! Every fallible call returns [`Error`]: an error of a layered crate, with its cause chain
//! ([`Error::Scene`], [`Error::Format`], [`Error::Cpu`], [`Error::Eval`], [`Error::Octree`],
//! [`Error::Cone`], [`Error::Gpu`]); a scene the GPU backend cannot render ([`Error::GpuScene`]);
//! a configuration field out of its range, naming the study, field, value and what it accepts
//! ([`Error::InvalidConfig`]); a scene that leaves a study nothing to measure
//! ([`Error::NothingToMeasure`]).
//!
//! # What this crate does not do
//! - No command line (the root `voxlod` crate) and no stored results: numbers exist once a study
//!   runs.
//! - The GPU backend covers the work that has a kernel; the rest runs on the CPU, and nothing
//!   falls back from the GPU to the CPU.
//!
//! It depends on every voxlod library crate, voxlod-gpu and its wgpu stack included.
//!
//! # References
//! - Brito, Poulin, Teichrieb 2023, "Voxel-based Representations for Improved Filtered
//!   Appearance", High-Performance Graphics, Tables 1 and 2: [`filtered`].
//! - Vicini, Jakob, Kaplanyan 2021, "A Non-Exponential Transmittance Model for Volumetric Scene
//!   Representations", SIGGRAPH (\[VJK21\]): [`filtered`].
//! - McNabb 2015, "Sparse Procedural Volume Rendering", GPU Pro 6: [`volume`].
//! - Yalçıner, Sahillioğlu 2020, "Voxel transformation: scalable scene geometry discretization
//!   for global illumination", Journal of Real-Time Image Processing 17(5), §4.5, and Crassin,
//!   Neyret, Sainz, Green, Eisemann 2011, "Interactive Indirect Illumination Using Voxel Cone
//!   Tracing", Pacific Graphics: [`cone`].
//! - Eisemann, Décoret 2006, "Fast Scene Voxelization and Applications", ACM Symposium on
//!   Interactive 3D Graphics and Games (I3D), §2, §3.1 and §3.3: [`slicemap`].
//! - Wang, Bovik, Sheikh, Simoncelli 2004, "Image Quality Assessment: From Error Visibility to
//!   Structural Similarity", IEEE Transactions on Image Processing 13(4): the SSIM every study
//!   reports.

#![deny(missing_docs)]

pub mod alloc;
pub mod backend;
pub mod baseline;
pub mod cone;
pub mod dynamic;
mod error;
pub mod filtered;
mod ground_truths;
pub mod heitz_neyret;
pub mod machine;
pub mod paper;
pub mod report;
pub mod scenes;
pub mod slicemap;
pub mod spread;
pub mod turntable;
pub mod views;
pub mod volume;

pub use error::Error;
pub use spread::Spread;

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;
