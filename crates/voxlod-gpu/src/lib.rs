//! voxlod's GPU backend on wgpu: a [`Context`] that picks an adapter and guards every
//! allocation and dispatch, and WGSL kernels that mirror the CPU references of
//! [`voxlod_cpu`], each checked against its reference by the equivalence suite
//! (`tests/equivalence`, run by `cargo xtask test` on every adapter found).
//!
//! | kernel | CPU reference | agreement |
//! |---|---|---|
//! | [`voxelize`]: conservative / thin surface voxelization | [`voxlod_cpu::voxelize`] | exact (occupancy and triangles per voxel) |
//! | [`raycast`]: closest hit of rays through a BVH | [`voxlod_cpu::raycast::Bvh::intersect`] | see [`raycast`] |
//! | [`random`]: the PCG3D counter RNG | [`voxlod_cpu::random`] | exact (bit for bit) |
//! | [`material`]: materials and textures (bilinear, wrap modes, sRGB decode, alpha modes) | [`voxlod_scene::Material::sample`] | texture samples within 2^-21, see [`material`] |
//! | [`ground_truth`]: the ground-truth renderer (every material: textured, alpha-masked, alpha-blended) | [`voxlod_cpu::render::ground_truth::render`] | per-pixel bound on 8-bit sRGB, see [`ground_truth`] |
//! | [`filtered`]: the filtered voxel renderer, Averages and \[VJK21\] records and the baseline's opaque voxels (shadows, point and directional lights) | [`voxlod_cpu::render::filtered::render`] | per-pixel bound on 8-bit sRGB, see [`filtered`] |
//! | [`volume`]: the metavoxel volumes (seed 001): binning, fill, light propagation, eye march (all three attenuation models) | [`voxlod_cpu::volume`] | binning exact; fill, propagation and march per-value / per-pixel bounds, see [`volume`] |
//! | [`filtered::voxels`]: the same renderer on virtual mesh + opacity subgrid grids (both directional-opacity rules, projected area) and Adaptive grids | [`voxlod_cpu::render::filtered::render`] | per-pixel bound on 8-bit sRGB, see [`filtered::voxels`] |
//! | [`octree`]: the sparse voxel octree build, lock-free level by level (mark, prefix-sum allocation, links), Averages pre-filter | [`voxlod_octree::FlatOctree::build_level_by_level`], [`voxlod_octree::Octree::build`] | exact topology (levels, nodes, tiles, neighbours); payloads within `8·depth·2⁻²⁴`, see [`octree`] |
//! | [`precompute`]: the per-voxel ray sampler, Averages sums and opacity subgrid (opaque untextured materials) | [`voxlod_cpu::appearance::precompute::precompute`] with [`voxlod_cpu::appearance::averages::fit`], [`voxlod_cpu::appearance::subgrid::build`] | line cases exact but near-ties, record and subgrid bytes ±1, see [`precompute`] |
//! | [`cone`]: cone tracing from shading points (AO, diffuse, specular) through a flat radiance octree, isotropic or directional opacities | [`voxlod_cone::ConeTracer`] | per-point bound on AO and radiance, see [`cone`] |
//!
//! Host-side preparation (snapping to the lattice, culling, BVH build) uses voxlod-cpu's code,
//! so bad input gets the CPU path's errors; a GPU entry point never falls back to the CPU.
//!
//! Timings on a CPU adapter (Mesa's lavapipe, [`Context::is_cpu`]) are CPU timings of the GPU
//! path, never GPU speed.

#![warn(missing_docs)]

pub mod cone;
pub mod context;
mod error;
pub mod filtered;
pub mod ground_truth;
pub mod layout;
pub mod material;
pub mod octree;
pub mod precompute;
pub mod random;
pub mod raycast;
pub mod volume;
pub mod voxelize;

pub use context::{AdapterSummary, Context, adapters};
pub use error::{Error, Result};

/// A light as the kernels' `Params` carry it: whether it is a point light, then `light_a`
/// (direction toward a directional light, or a point light's position) and `light_b`
/// (irradiance, or intensity).
pub(crate) fn light_words(light: &voxlod_scene::Light) -> (bool, glam::Vec3, glam::Vec3) {
    match *light {
        voxlod_scene::Light::Directional { to_light, irradiance } => (false, to_light, irradiance),
        voxlod_scene::Light::Point { position, intensity } => (true, position, intensity),
    }
}
