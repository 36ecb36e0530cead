//! The CPU references of voxlod, parallel with rayon: exact voxelizers ([`voxelize`]), BVH ray
//! casting ([`raycast`]), the shading function every renderer shares ([`shading`]),
//! counter-based random numbers ([`random`]), the ground-truth mesh renderer every
//! approximation is scored against and the voxel renderers ([`render`]), the per-voxel
//! appearance precompute and its representations ([`appearance`]), and sparse procedural
//! volumes with metavoxels ([`volume`]).
//!
//! It is the reference of the project: every GPU kernel of voxlod-gpu is checked against the
//! function here that it mirrors. Results are deterministic: the same image, grid or record with
//! any number of threads.
//!
//! # Example
//! Voxelize a sphere, render its ground truth, pre-filter each voxel's appearance as Averages and
//! render that: the voxels cover the sphere and reproduce its colours.
//! ```
//! use glam::Vec4;
//! use voxlod_cpu::appearance::averages;
//! use voxlod_cpu::appearance::line_sampler::SamplingContext;
//! use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
//! use voxlod_cpu::raycast::Bvh;
//! use voxlod_cpu::render::filtered::{self, FrameCache};
//! use voxlod_cpu::render::ground_truth;
//! use voxlod_cpu::voxelize::{Options, voxelize};
//! use voxlod_format::GridSpec;
//! use voxlod_scene::{Image, procedural};
//!
//! # fn main() -> voxlod_cpu::Result<()> {
//! // A sphere of 1 280 triangles, voxelized at 32³ with each voxel's triangle list.
//! let scene = procedural::from_spec("sphere")?;
//! let geometry = scene.geometry();
//! let (lo, hi) = scene.bounds()?;
//! let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 32)?;
//! let voxels = voxelize(&geometry, &grid, &Options::default())?;
//!
//! // The ground truth: the mesh ray cast through a BVH, 16 rays per pixel.
//! let camera = scene.default_camera()?;
//! let bvh = Bvh::new(&geometry)?;
//! let options = ground_truth::Options { width: 32, height: 32, spp: 16, ..Default::default() };
//! let truth = ground_truth::render(&scene, &geometry, &bvh, &camera, &options)?.image;
//!
//! // Averages: 150 lines sampled per voxel, one 8-byte record each, then the filtered renderer.
//! let ctx = SamplingContext::new(&scene, &geometry, &voxels)?;
//! let averages = precompute(&ctx, &PrecomputeOptions::default(), averages::fit)?;
//! assert_eq!(averages.record_bytes(), 8);
//! let options = filtered::Options { width: 32, height: 32, ..Default::default() };
//! let (light, background) = (scene.light(), scene.background);
//! let mut cache = FrameCache::new(&averages)?;
//! let image = filtered::render(&mut cache, &camera, &light, background, &options)?;
//!
//! // The voxels cover the sphere's silhouette, and their colours are those of the mesh to
//! // within a few hundredths per pixel (linear RGB, the largest channel).
//! let coverage = |i: &Image| i.pixels.iter().map(|p| p.w).sum::<f32>() / 1024.0;
//! assert!((coverage(&truth) - coverage(&image)).abs() < 0.05);
//! let error = |(a, b): (&Vec4, &Vec4)| (a.truncate() - b.truncate()).abs().max_element();
//! assert!(truth.pixels.iter().zip(&image.pixels).map(error).sum::<f32>() / 1024.0 < 0.03);
//! # Ok(())
//! # }
//! ```
//!
//! # Main types
//! | module | what it holds |
//! |---|---|
//! | [`voxelize`] | [`voxelize::voxelize`]: conservative, 6-separating thin or solid, decided in integer arithmetic on a fixed-point lattice (exact, scale-independent); a [`voxelize::Voxelization`] is a brick map of occupied voxels with their triangle lists |
//! | [`raycast`] | [`raycast::Bvh`] (obvhs's compressed wide BVH8): closest-hit, 2×2-packet and any-hit queries with alpha filters; watertight triangle tests; results independent of the tree |
//! | [`shading`] | [`shading::shade`]: Lambert, normalized Blinn-Phong and ambient, the one shading function, so an error measures a representation and not a shading difference |
//! | [`random`] | PCG3D counter-based random numbers, a pure function of (id, sample, dimension) that WGSL reproduces bit for bit |
//! | [`render`] | [`render::ground_truth`], [`render::baseline`] (opaque cubes of average colour), [`render::filtered`] (any [`appearance::Appearance`], cached per-voxel shading, voxel shadow rays), [`render::indirect`] (ray-traced AO and one-bounce diffuse light), the brick-skipping [`render::dda`] |
//! | [`appearance`] | [`appearance::line_sampler`], [`appearance::precompute`], and the representations: [`appearance::averages`], [`appearance::sggx`] + [`appearance::nonexp`] (\[VJK21\]), [`appearance::virtual_mesh`] + [`appearance::subgrid`], [`appearance::adaptive`] |
//! | [`volume`] | displaced-sphere particles binned into light-oriented metavoxels, filled, lit down the columns and ray marched, with three attenuation models (one exact) |
//!
//! Memory follows occupied content: voxelizations, appearance grids and volumes allocate per
//! occupied brick or kept metavoxel, never per voxel of the bounding box; a voxelization or
//! volume whose estimated memory exceeds its limit is refused before anything large is
//! allocated.
//!
//! # Errors
//! Every fallible call returns [`Error`]: an invalid scene, geometry, camera or light as
//! voxlod-scene reports it ([`Error::Scene`]); a grid or brick-map problem as voxlod-format
//! reports it ([`Error::Format`]); a result whose estimated memory exceeds the limit in force,
//! with the estimate ([`Error::OutOfMemory`]); an option out of its range, with its name, value
//! and valid range ([`Error::InvalidParameter`]).
//!
//! # What this crate does not do
//! - No GPU: voxlod-gpu runs the same algorithms in wgpu and is checked against this crate.
//! - No sparse voxel octree or cone tracing (voxlod-octree, voxlod-cone) and no image metrics
//!   (voxlod-eval).
//! - The renderers compute direct light from one light with one shadow ray per shading point,
//!   plus an optional constant ambient term; the only indirect light is
//!   [`render::indirect`]'s one-bounce diffuse reference. No window, no real-time loop.
//! - Appearance records are fitted from samples of the triangles inside each voxel only.
//! - Metallic-roughness materials are not modelled: surfaces are Lambert with an optional
//!   normalized Blinn-Phong lobe.
//!
//! It depends on voxlod-format and voxlod-scene, and on no GPU API.
//!
//! # References
//! - Brito, Poulin, Teichrieb 2023, "Voxel-based Representations for Improved Filtered
//!   Appearance", High-Performance Graphics: line sampling (§3.2), virtual mesh (§3.3),
//!   opacity subgrid (§3.4), the voxel renderer and its shadow rays (§4), Averages (§5).
//! - Vicini, Jakob, Kaplanyan 2021, "A Non-Exponential Transmittance Model for Volumetric Scene
//!   Representations", SIGGRAPH (\[VJK21\]): [`appearance::nonexp`],
//!   [`appearance::transmittance`].
//! - Heitz, Dupuy, Crassin, Dachsbacher 2015, "The SGGX Microflake Distribution", SIGGRAPH:
//!   [`appearance::sggx`].
//! - McNabb 2015, "Sparse Procedural Volume Rendering", GPU Pro 6, §5.3–5.5: [`volume`].
//! - Schwarz, Seidel 2010, "Fast Parallel Surface and Solid Voxelization on GPUs", SIGGRAPH
//!   Asia: the thin voxelization.
//! - Woop, Benthin, Wald 2013, "Watertight Ray/Triangle Intersection", JCGT: [`raycast`].
//! - Ylitie, Karras, Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed
//!   Wide BVHs", High-Performance Graphics: the BVH layout.
//! - Jarzynski, Olano 2020, "Hash Functions for GPU Rendering", JCGT: [`random`].
//! - Amanatides, Woo 1987, "A Fast Voxel Traversal Algorithm for Ray Tracing", Eurographics:
//!   [`render::dda`].

#![deny(missing_docs)]

pub mod appearance;
mod error;
pub mod random;
pub mod raycast;
pub mod render;
pub mod shading;
pub mod volume;
pub mod voxelize;

pub use error::{Error, Result};

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;
