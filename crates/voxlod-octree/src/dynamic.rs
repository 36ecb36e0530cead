//! Moving objects by **voxel transformation** (Yalçıner and Sahillioğlu 2020, §3 and §4.2):
//! each object is voxelized once in its own space into a [`VoxelCache`]; every frame its voxels
//! are moved into the world grid by a rigid matrix or by linear blend skinning
//! ([`transform`][mod@transform]), split over world voxels by one of the paper's two filters
//! and blended in fixed point ([`blend`][mod@blend]), merged with the static voxels, and the
//! octree is rebuilt from the result ([`DynamicWorld`]). Building caches from meshes
//! (voxelization, Averages records, skin weights) is voxlod-cpu's `dynamic` module; the wgpu
//! kernels are voxlod-gpu's `dynamic` module, which mirrors the arithmetic written here.
//!
//! # Caches ([`cache`])
//! - A cached voxel's position is its integer index in the object's own grid, whose origin is
//!   the corner of the object's bounds in object space, packed 10 bits per axis into a `u32`
//!   (`x | y << 10 | z << 20`, the paper's 30-bit positions): at most [`MAX_CACHE_DIM`] = 1024
//!   voxels per axis, [`Error::CacheTooLarge`] past it.
//! - Its record is an Averages record in object space; a skinned object's voxel also has a
//!   `VoxelSkin` (four joints, unorm8 weights summing to 255).
//! - A cache knows the object-to-world scale it was built for: a cached voxel spans
//!   `voxel_size · scale` world units, which must equal the world grid's voxel
//!   ([`Error::CacheResolution`]).
//!
//! # Placement ([`place`][mod@place], on the host in `f64`)
//! A rigid object has one object-to-world matrix per frame, a skinned one a matrix per joint
//! (bind space to world: the joint's world matrix times its inverse bind matrix). Each must be
//! finite and **rigid at the cache's scale**: its three linear columns of length `scale` and
//! pairwise orthogonal, within a relative tolerance ([`FrameOptions::rigidity_tolerance`]),
//! else [`Error::NotRigid`] — voxels have a fixed size, so scaling (uniform too) and shearing
//! cached voxels is refused rather than approximated (the paper's §6). Each matrix is composed
//! with the cache's index-to-object map and the world-to-grid map into an affine map from a
//! cached voxel's integer position to world-grid coordinates (voxel units), then split into an
//! integer **anchor** (`i32`, the grid cell of the object's reference point) and `f32` maps
//! relative to it: `f32` then carries only the object's own extent, not its distance from the
//! grid origin, so a huge translation costs no precision. An anchor beyond ±2³⁰ voxels puts
//! the whole object outside the grid: its voxels are counted as clipped and not transformed.
//!
//! # Transform ([`transform`][mod@transform], per voxel in `f32`, the GPU kernel's arithmetic)
//! - Rigid: `r = M·i + t`. Skinned: the blended matrix `Σ (w_k/255)·M_k` (in slot order, from
//!   zero), then `r = M·i + t` — linear blend skinning; the weights were interpolated and
//!   renormalized when the cache was built.
//! - The record's normal is mapped by the (blended) linear part, normalized and quantized to
//!   snorm12 (`⌊2047·n + ½⌋`).
//! - **Nearest**: the world voxel containing the moved voxel's centre, `anchor + ⌊r⌋`.
//! - **8-neighbour**: with `q = r − ½`, the lower corner `anchor + ⌊q⌋` of the eight world
//!   voxels whose centres surround the moved centre, and the fraction `q − ⌊q⌋` in sixty-fourths
//!   per axis, rounded to nearest (0 ..= 64).
//! - A non-finite `r`, or one beyond ±2²³ voxels (where `f32` stops holding integers), is
//!   outside.
//!
//! # Blend ([`blend`][mod@blend], exact integers: the result does not depend on the order)
//! A moved voxel contributes to each world voxel it covers the volume it covers there, in units
//! of 2⁻¹⁸ voxel: the trilinear weight `w = wx·wy·wz` (`wx = 64 − fx` for the lower, `fx` for
//! the upper neighbour) — exactly the overlap of the moved voxel's axis-aligned box with each
//! world voxel — or all of `2¹⁸` for nearest. Per world voxel the blend sums, in 64-bit
//! integers: coverage `W = Σ w`, `A = Σ w·α` (α the record's unorm8 opacity),
//! `C = Σ w·α·c` (c the linear colour in 12 bits, from the record's sRGB8 by a table) and
//! `N = Σ w·α·n` (the quantized moved normal, signed). Static voxels contribute `2¹⁸` at their
//! own voxel; overlapping static and moving voxels blend like any others. Contributions outside
//! the grid are clipped and counted (never written). Each contribution is below 2³⁸ in
//! magnitude, so a frame of at most [`MAX_CONTRIBUTIONS`] = 2²⁴ contributions (2²¹ voxels under
//! the 8-neighbour filter) sums exactly ([`Error::FrameTooLarge`] past it).
//!
//! # Resolve ([`WorldSums::resolve`])
//! A world voxel is **occupied when the moved voxels cover at least `τ` of its volume**
//! (`W ≥ τ·2¹⁸`, [`FrameOptions::occupancy_threshold`], default [`DEFAULT_OCCUPANCY`]) and some
//! of them are not transparent (`A > 0`). Its payload: opacity `min(1, A / (255·2¹⁸))` — the
//! covered volume adjusts the opacity, as the paper's §3.3 says — colour `C / (4095·A)`, normal
//! `N/|N|`. With the nearest filter every touched voxel is occupied.
//!
//! [`Error::CacheTooLarge`]: crate::Error::CacheTooLarge
//! [`Error::CacheResolution`]: crate::Error::CacheResolution
//! [`Error::NotRigid`]: crate::Error::NotRigid
//! [`Error::FrameTooLarge`]: crate::Error::FrameTooLarge

pub mod blend;
pub mod cache;
pub mod place;
#[cfg(test)]
mod tests;
pub mod transform;
mod world;

pub use blend::{
    BlendInput, BlendStats, CellSums, FULL_WEIGHT, MAX_CONTRIBUTIONS, WorldSums, blend,
    linear12_table,
};
pub use cache::{CacheSkin, MAX_CACHE_DIM, VoxelCache, pack_position, unpack_position};
pub use place::{Affine, ObjectFrame, Placement, place};
pub use transform::{Filter, Placed, quantize_normal, transform, transform_voxel, voxel_matrix};
pub use world::{DEFAULT_OCCUPANCY, DynamicWorld, FrameOptions, FrameStats};
