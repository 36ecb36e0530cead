//! Heitz and Neyret (2012): a surface stored in an octree as a macroscopic signed distance
//! (a plane per node) plus Gaussian statistics of what lies below a node's scale — heights,
//! normals and a colour correlated with height — pre-filtered bottom-up so that a coarse node
//! reads like the fine surface it covers, seen through a pixel.
//!
//! | module | owns |
//! |---|---|
//! | [`payload`] | [`MicrosurfacePayload`]: the node record, its pre-filter, and [`Microsurface`], the statistics a renderer reads from a sample |
//! | [`smith`] | Smith's Λ, masking, height CDF, Eq. 17's view- and light-dependent colour: stable over their whole domains, in `f64` and in the GPU kernel's `f32` |
//! | [`special`] | `erf`, `erfc`, `erfcx` (`f64` and `f32`) |
//!
//! # The record (§5.2) and the one change an octree forces on it
//! Per node: the macro-surface as an affine distance field (`h̄` at the node's centre and the
//! mean unit normal `n̄`, whose zero set is the node's plane), the height variance `σh²` about
//! that plane, the normals' second moments (the normal distribution, isotropic or not), the
//! mean colour `ā` and its correlation with height `aₛ` (§5.1, H5bis), and the material's own
//! specular level and roughness. Everything is stored **premultiplied by coverage** `c` (the
//! fraction of the node's leaves that hold surface), like every voxlod-octree payload, so that
//! the mean of eight children is the coverage-weighted mean of their statistics.
//!
//! The paper's bricks hold a distance at every voxel. A sparse octree does not: a missing node
//! reads as [`crate::Payload::empty`], the additive zero, and an unweighted mean would read
//! empty space as `h̄ = 0` — on the surface — and pull planes toward the nodes around occupied
//! ones. Weighting by coverage removes empty nodes from the mean, but a distance read at a
//! node's centre is still wrong at another point: halfway between a surface node and an empty
//! one, the weighted mean is the surface node's `h̄`, half a node too close. So the distance is
//! stored **relative to the node** (at its centre, in node units) and every corner of an
//! interpolation is moved to the sample point first, `h(p) = h̄·size + n̄·(p − centre)`
//! ([`crate::Payload::add_scaled_at`]): each node contributes its own plane, extended to the
//! point, with its coverage as weight. A sample's plane is then exact for a planar surface
//! however many of its corners are empty, no plane appears where every corner is empty, and
//! the pre-filter moves each child's plane to the parent's centre the same way (tested).
//!
//! # Pre-filtering (children → parent), all in the parent's units
//! - **Linear** (the plain mean of eight premultiplied children): coverage, the distance field
//!   (after the move to the parent's centre), `n̄`, the normals' second moments `E[n nᵀ]`, `ā`,
//!   the specular level and roughness. These also interpolate linearly: a mixture of two nodes
//!   has the mixture's moments (second moments, never standard deviations).
//! - **`σh²`** by the law of total variance about the parent's plane: each child's own variance
//!   (its heights tilted onto the parent's plane, plus the tilt of its plane across its extent,
//!   taken as a node-sized square) and the spread of the children's planes about the parent's.
//! - **`aₛ`**, the least-squares projection of `a − ā` on `s(h) = erf(h/(√2·σh))` with the
//!   parent's `σh` (§5.2), integrated over each child's Gaussian heights and colour profile by
//!   8-point Gauss–Hermite quadrature (the paper integrates over the finest level; children's
//!   Gaussian statistics stand in for it). A node without height spread has `aₛ = 0`.
//!
//! Interpolation between nodes mixes `σh²` and `aₛ` linearly, as the paper's hardware
//! interpolation does.
//!
//! # Model limits (Heitz and Neyret's hypotheses)
//! The surface is locally planar at a node's scale (H6) and bounds a solid (H7): thin
//! two-sided sheets and foliage, whose normals cancel, are outside the model. They still get a
//! plane (the principal axis of their normals, with a canonical sign) so that nothing is
//! undefined, and renderers shade them two-sided.

pub mod payload;
#[cfg(test)]
mod reference;
pub mod smith;
pub mod special;

pub use payload::{Microsurface, MicrosurfacePayload};
