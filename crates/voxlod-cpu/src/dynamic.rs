//! The scene side of dynamic scenes by voxel transformation (Yalçıner and Sahillioğlu 2020,
//! §3): which meshes of an animated scene move and how ([`DynamicScene`]), each moving object's
//! geometry in its own space and its voxel cache built once ([`build_cache`]), its placement in
//! every pose, and the re-voxelization of the posed meshes that voxel transformation replaces
//! ([`revoxelize`], the per-frame baseline and the reference the transform is measured
//! against). The transform, the filters and the blend are voxlod-octree's `dynamic` module.
//!
//! # Objects and their spaces
//! A skinned mesh belongs to its skin's object, whose space is the skin's bind space; a mesh
//! whose node (or an ancestor of it) the animation drives belongs to its node's object, whose
//! space is the node's local space (the rest mesh mapped back by the node's rest world
//! matrix). Everything else is static and voxelized once into the world grid. An object's
//! **scale** is the uniform scale of its rest transform (node world matrix, or every used
//! joint's matrix — they must agree); the cache's voxel is the world voxel divided by it, so a
//! cached voxel is one world voxel. Rest transforms that scale non-uniformly or shear are
//! refused (voxels cannot follow them).
//!
//! # Caches
//! The object's triangles are voxelized in the object grid (origin at the corner of its
//! bounds; conservative by default, thin on request) with triangle lists; each voxel gets an
//! Averages record ([`RecordSource`]: the ray-sampled Averages fit, default 32 lines, or the
//! fragment average of its pieces). A skinned object's voxel gets its joints and weights
//! **interpolated at the centroids of the voxel's triangle pieces** (each triangle clipped to
//! the voxel's box, [`pieces`]): the barycentric blend of the triangle's vertex weights at the
//! piece's area centroid, weighted by the piece's area and summed over the voxel's pieces; the
//! four largest joints are kept and renormalized to unorm8 weights summing to 255. A voxel
//! whose pieces all have zero area (only degenerate triangles) weighs its triangles equally. A
//! voxel whose weights sum to zero is an error naming it (vertex weights are checked when a
//! mesh is validated, so this takes a mesh built by hand).

mod cache;
pub mod pieces;
mod revoxelize;
mod scene;
#[cfg(test)]
mod tests;

pub use cache::{
    CacheOptions, RecordSource, build_cache, fragment_records, static_voxels, voxel_records,
    voxel_skins,
};
pub use revoxelize::{Revoxelized, geometry_of, revoxelize};
pub use scene::{DynamicObject, DynamicScene, ObjectKind, uniform_scale};
