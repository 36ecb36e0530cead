//! Per-voxel ray samples (HPG 2023 §3.2; design note §1): lines through the voxel from uniform
//! random directions, hit-tested against the voxel's own triangle list. Every representation is
//! fitted from these.

use glam::Vec3;

/// A surface point a sampling line met inside its voxel on a front face (case (a) of §3.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    /// Hit point in voxel-local coordinates, each in [0, 1].
    pub point: Vec3,
    /// Unit shading normal (flipped toward the incoming line on double-sided materials).
    pub normal: Vec3,
    /// Linear albedo (texture applied).
    pub albedo: Vec3,
    /// Specular level (mean of the material's specular colour), 0 for diffuse materials.
    pub specular: f32,
    /// Blinn-Phong exponent of the material.
    pub shininess: f32,
}

/// One sampling line through a voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaySample {
    /// Unit direction of travel.
    pub dir: Vec3,
    /// Where the line enters the voxel, voxel-local (each coordinate in [0, 1]).
    pub entry: Vec3,
    /// Length of the line inside the voxel, in voxel units (0 < chord ≤ √3).
    pub chord: f32,
    /// Whether the line's closest hit on the voxel's triangles exists at all: inside or outside
    /// the voxel, front- or back-facing (the line is occluded).
    pub occluded: bool,
    /// The closest hit, when it is front-facing and inside the voxel.
    pub surface: Option<SurfaceSample>,
}

/// The sampling lines of one voxel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VoxelSamples {
    /// The lines, in sample-index order.
    pub rays: Vec<RaySample>,
}

impl VoxelSamples {
    /// The surface samples (case (a) hits), in ray order.
    pub fn surfaces(&self) -> impl Iterator<Item = &SurfaceSample> + '_ {
        self.rays.iter().filter_map(|r| r.surface.as_ref())
    }

    /// Number of occluded lines (any closest hit: case (a), back-facing, or outside the voxel).
    pub fn occluded(&self) -> usize {
        self.rays.iter().filter(|r| r.occluded).count()
    }

    /// Occluded lines over all lines (the Averages opacity, design note §2); 0 without lines.
    pub fn opacity(&self) -> f32 {
        if self.rays.is_empty() { 0.0 } else { self.occluded() as f32 / self.rays.len() as f32 }
    }
}
