//! Node hierarchy, skins and animations, read from glTF and kept with the scene (`voxlod info`
//! lists them). Nothing in voxlod animates a scene yet: renders use the world-space meshes of
//! [`crate::Scene`], flattened at the rest pose, and ignore these.

use glam::Mat4;

/// A node of the scene graph.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Node {
    /// Name (or `nodes[i]`).
    pub name: String,
    /// Parent node, `None` for roots.
    pub parent: Option<usize>,
    /// Local transform relative to the parent.
    pub local: Mat4,
    /// World transform at load time (rest pose).
    pub world: Mat4,
}

/// A skin: joints (node indices) and their inverse bind matrices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skin {
    /// Name.
    pub name: String,
    /// Joint nodes, indices into [`crate::Scene::nodes`].
    pub joints: Vec<usize>,
    /// One inverse bind matrix per joint.
    pub inverse_bind_matrices: Vec<Mat4>,
}

/// What an animation channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimatedProperty {
    /// Translation (3 floats per key).
    Translation,
    /// Rotation quaternion xyzw (4 floats per key).
    Rotation,
    /// Scale (3 floats per key).
    Scale,
    /// Morph target weights (n floats per key).
    MorphWeights,
}

/// Keyframe interpolation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Linear (slerp for rotations).
    Linear,
    /// Step.
    Step,
    /// Cubic spline with in/out tangents (3 values per key).
    CubicSpline,
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Target node.
    pub node: usize,
    /// Target property.
    pub property: AnimatedProperty,
    /// Interpolation.
    pub interpolation: Interpolation,
    /// Key times in seconds.
    pub times: Vec<f32>,
    /// Key values, flattened.
    pub values: Vec<f32>,
}

/// A named animation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Animation {
    /// Name.
    pub name: String,
    /// Its channels.
    pub channels: Vec<Channel>,
}
