//! voxlod's GPU backend on wgpu: a [`Context`] that picks an adapter and guards every
//! allocation and dispatch, and WGSL kernels (compute, and one render pipeline) that mirror the
//! CPU references of
//! [`voxlod_cpu`], [`voxlod_octree`] and [`voxlod_cone`]. Each kernel is checked against its
//! reference by the crate's equivalence suite (`tests/equivalence`, run on every adapter found)
//! with a stated tolerance.
//!
//! # Example
//! Open the adapter [`Context::new`] picks and voxelize one triangle on it; the occupancy is
//! exactly the CPU reference's. Without an adapter the example says so and stops.
//! ```
//! use glam::{DVec3, UVec3, Vec3};
//! use voxlod_format::GridSpec;
//! use voxlod_gpu::voxelize::{VoxelizeOptions, Voxelizer};
//! use voxlod_gpu::{Context, Error};
//! use voxlod_scene::Geometry;
//!
//! # fn main() -> voxlod_gpu::Result<()> {
//! let ctx = match Context::new() {
//!     Ok(ctx) => ctx,
//!     Err(Error::NoAdapter) => {
//!         println!("no GPU adapter: nothing to run");
//!         return Ok(());
//!     }
//!     Err(e) => return Err(e),
//! };
//! println!("on {}", ctx.summary());
//!
//! // One triangle lying exactly on the boundary between voxel layers z = 1 and z = 2.
//! let geometry = Geometry {
//!     positions: vec![Vec3::new(0.0, 0.0, 2.0), Vec3::new(4.0, 0.0, 2.0), Vec3::new(0.0, 4.0, 2.0)],
//!     indices: vec![[0, 1, 2]],
//!     ..Default::default()
//! };
//! let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(4)).expect("a valid grid");
//! let gpu = Voxelizer::new(&ctx)?.voxelize(&geometry, &grid, &VoxelizeOptions::default())?;
//!
//! let cpu = voxlod_cpu::voxelize::voxelize(&geometry, &grid, &Default::default())?;
//! assert_eq!(gpu.len(), cpu.voxels.len()); // closed voxels: both layers, 13 columns each
//! assert_eq!(gpu.len(), 26);
//! # Ok(())
//! # }
//! ```
//!
//! # Kernels
//! Each kernel type compiles its WGSL once for a [`Context`] (`Voxelizer::new(&ctx)`, …);
//! host-side inputs are checked before anything is allocated.
//!
//! | module | what it runs | CPU reference | agreement |
//! |---|---|---|---|
//! | [`voxelize`] | conservative / thin surface voxelization | [`voxlod_cpu::voxelize`] | exact |
//! | [`raycast`] | closest hits through a BVH | [`voxlod_cpu::raycast::Bvh`] | `t` within 1e-4 relative; other triangle only at near ties |
//! | [`random`] | the PCG3D counter RNG | [`voxlod_cpu::random`] | exact |
//! | [`material`] | materials and textures | [`voxlod_scene::Material::sample`] | texture samples within 2⁻²¹ |
//! | [`ground_truth`] | the ground-truth renderer | [`voxlod_cpu::render::ground_truth`] | 1 sRGB step, 98 % of pixels |
//! | [`filtered`] | Averages, \[VJK21\], baseline voxels | [`voxlod_cpu::render::filtered`] | 1 sRGB step, 99 % of pixels |
//! | [`filtered::voxels`] | virtual-mesh and Adaptive grids | [`voxlod_cpu::render::filtered`] | 2 sRGB steps, 99 % of pixels |
//! | [`precompute`] | per-voxel ray sampling, Averages sums, opacity subgrid | [`voxlod_cpu::appearance::precompute`] | ≤ 10⁻³ of lines change case; ±1 per record byte |
//! | [`octree`] | sparse voxel octree build, Averages pre-filter | [`voxlod_octree`] | exact topology; payloads within `8·depth·2⁻²⁴` |
//! | [`cone`] | cone tracing (AO, diffuse, specular) | [`voxlod_cone::ConeTracer`] | within 1e-3 for 99 % of points |
//! | [`dynamic`] | a dynamic scene's frame: voxel transformation, fixed-point blend, octree rebuild, light injection | [`voxlod_octree::dynamic`], [`voxlod_cone::inject()`] | cells exact but within 10⁻⁵ voxel of a boundary (≤ 0.1 %); sums and topology exact; radiance within 1e-3 for 99 % |
//! | [`differential`] | Heitz–Neyret differential cone tracing with coverage masks; its `f32` Smith functions | [`voxlod_cone::DifferentialRenderer`] with [`differential::shade_element`]; `f64` Λ and erfc | 2 sRGB steps, 98 % of pixels, same element counts; Λ within 1e-4 relative |
//! | [`volume`] | metavoxel binning, fill, propagation, march | [`voxlod_cpu::volume`] | binning exact; values 1e-5 / 1e-4 relative; image 1 sRGB step |
//! | [`slicemap`] | slicemaps by rasterization (a render pipeline: vertex + fragment stages, fragment-stage `atomicOr`), their occluder and inner-voxel queries | [`voxlod_cpu::voxelize::slicemap`] | columns exact; slice bits but at fragments within 1e-5 of a slice boundary; queries exact |
//!
//! Each module's documentation states why its bound is what it is (which WGSL operations are
//! less accurate than Rust's, where a fused multiply-add can move a tie) and what a real GPU
//! sees of the kernel (work decomposition, coherence, divergence).
//!
//! # Host-side preparation reused from the CPU crates
//! The GPU path runs the CPU crates' own host-side code before its kernels, for two reasons:
//! bad input gets the very error the CPU path gives (the same checks, in the same order), and
//! every decision the CPU makes in integer or `f64` arithmetic (which WGSL does not have) is
//! made once, by one definition, so the two backends can differ only by the kernels' own float
//! arithmetic. The steps reused are small next to the kernels (linear in the triangles, bins or
//! nodes), sequential or branchy:
//! - from voxlod-cpu: the voxelizer's fixed-point lattice (vertex snapping, culling of
//!   triangles that cannot reach the grid, input checks); the BVH build (obvhs's CWBVH, with
//!   its checks), uploaded node for node for ray casting, the ground truth and the volume's
//!   mesh shadow; the precompute's sampling context and its `f64` set-up of each voxel's
//!   triangles, and the Averages fit's arithmetic on the read-back sums; the filtered and
//!   ground-truth renderers' frame and option checks and random-stream keys; the volume's
//!   input checks, particle preparation, culling and memory budget; the slicemap's view
//!   transform, clipping and sub-pixel snapping of the triangles;
//! - from voxlod-octree: the build plan (depth, dense levels), the payload checks and the
//!   flat layout ([`voxlod_octree::FlatOctree`], [`voxlod_octree::GpuNode`] and friends) the
//!   octree kernels build and the cone kernel reads;
//! - from voxlod-cone: the options' validation, the diffuse cone directions and the aperture
//!   constants (computed by its code, uploaded as the kernel's uniform); the radiance octree
//!   itself is built on the CPU;
//! - from voxlod-format: the record decoders and tables (sRGB, semi-axis scale), so decoded
//!   inputs are bit-identical to the CPU's.
//!
//! # Errors
//! Every fallible call returns [`Error`]: bad input as the CPU crates report it
//! ([`Error::Cpu`], [`Error::Octree`], [`Error::Cone`]); no adapter or a selector that matches
//! none; a buffer or dispatch over the device's limits, with the numbers
//! ([`Error::BufferTooLarge`], [`Error::TooLarge`]); a request with no kernel
//! ([`Error::Unsupported`]); and what the device reports — out of memory, validation errors,
//! device loss, a wait over the timeout — caught by error scopes, never a panic or a hang.
//!
//! # What this crate does not do
//! - It does not fall back to the CPU: a GPU entry point without an adapter, over the device's
//!   limits or without a kernel for the request returns an error.
//! - It computes and reads back; it does not present to a window or surface, and keeps no
//!   state between frames beyond what the caller uploads.
//! - Not every CPU path has a kernel: solid voxelization, the ground truth's host-side light
//!   filter, the \[VJK21\] and virtual-mesh fits (the precompute can return every sampled line
//!   for them to run on the CPU), octree payloads other than Averages, and the radiance
//!   octree's light injection stay on the CPU.
//! - Agreement is exact only where stated (voxelization, random numbers, binning, octree
//!   topology); elsewhere results agree with the CPU within the bounds above.
//! - It does not measure GPU speed on a CPU adapter: on Mesa's lavapipe ([`Context::is_cpu`])
//!   the kernels run on the CPU, so their timings are CPU timings of the GPU path.
//!
//! # References
//! - Brito, Poulin, Teichrieb 2023, "Voxel-based Representations for Improved Filtered
//!   Appearance", High-Performance Graphics: [`precompute`], [`filtered`].
//! - Vicini, Jakob, Kaplanyan 2021, "A Non-Exponential Transmittance Model for Volumetric
//!   Scene Representations", SIGGRAPH (\[VJK21\]): [`filtered`].
//! - McNabb 2015, "Sparse Procedural Volume Rendering", GPU Pro 6: [`volume`].
//! - Yalçıner, Sahillioğlu 2020, "Voxel transformation: scalable scene geometry discretization
//!   for global illumination", Journal of Real-Time Image Processing 17(5): [`octree`],
//!   [`cone`].
//! - Eisemann, Décoret 2006, "Fast Scene Voxelization and Applications", I3D: [`slicemap`].
//! - Heitz, Neyret 2012, "Representing Appearance and Pre-filtering Subpixel Data in Sparse
//!   Voxel Octrees", High-Performance Graphics: [`differential`].

#![deny(missing_docs)]

pub mod cone;
pub mod context;
pub mod differential;
pub mod dynamic;
mod error;
pub mod filtered;
pub mod ground_truth;
pub mod layout;
pub mod material;
pub mod octree;
pub mod precompute;
pub mod random;
pub mod raycast;
pub mod slicemap;
pub mod volume;
pub mod voxelize;

pub use context::{AdapterSummary, Context, adapters};
pub use error::{Error, Result};

/// Morton codes in WGSL (as `voxlod_format::morton`), prepended to the octree-build, dynamic,
/// cone, differential and light-injection kernels.
pub const MORTON_WGSL: &str = include_str!("morton.wgsl");
/// WGSL shared by the cone, differential and light-injection kernels (after [`MORTON_WGSL`]):
/// a node's +axis neighbour on a sparse level, the descent to a node (`Octree::find`) and the
/// eight nodes around a sample (`Octree::corners`).
pub const OCTREE_WALK_WGSL: &str = include_str!("octree_walk.wgsl");

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;

/// A light as the kernels' `Params` carry it: whether it is a point light, then `light_a`
/// (direction toward a directional light, or a point light's position) and `light_b`
/// (irradiance, or intensity).
pub(crate) fn light_words(light: &voxlod_scene::Light) -> (bool, glam::Vec3, glam::Vec3) {
    match *light {
        voxlod_scene::Light::Directional { to_light, irradiance } => (false, to_light, irradiance),
        voxlod_scene::Light::Point { position, intensity } => (true, position, intensity),
    }
}
