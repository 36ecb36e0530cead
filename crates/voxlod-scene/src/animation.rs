//! Node hierarchy, skins and animations (read from glTF, or built by the procedural crowd), and
//! their evaluation at a time: [`Animation::pose`] gives every node's local and world matrix,
//! [`Skin::joint_matrices`] the joint matrices of linear blend skinning. Static renders use the
//! world-space meshes of [`crate::Scene`] (the rest pose) and ignore these; the dynamic-scene
//! pipeline moves meshes with them.
//!
//! # Sampling (glTF 2.0 §3.11, Appendix C)
//! - A channel drives one of translation, rotation or scale of one node; the other components
//!   keep the node's rest values ([`Node::trs`]). Nodes no channel drives keep their rest local
//!   matrix.
//! - Before the first key time a channel holds its first value, after the last its last value
//!   (no extrapolation, no looping: wrap the time yourself, [`Animation::duration`]).
//! - **Step**: the value of the last key at or before the time. **Linear**: componentwise
//!   linear interpolation of translation and scale; rotation by spherical linear interpolation
//!   along the shorter arc (the second quaternion negated when their dot product is negative),
//!   normalized. **Cubic spline**: the glTF cubic Hermite spline on keys stored as (in-tangent,
//!   value, out-tangent), tangents scaled by the key interval; a rotation is normalized after.
//! - Two keys at the same time: the later one holds from that time on (a jump).
//! - An animation with a **morph-target weights** channel is refused
//!   ([`Error::Animation`]): morph targets deform the mesh, which voxel transformation cannot
//!   follow, and a silent static pose would be wrong.
//! - A channel on a node given by a `matrix` (glTF forbids animating those) or on a node that
//!   does not exist, a non-finite time, a key count that does not match the values, and a
//!   rotation that interpolates to a zero quaternion are [`Error::Animation`]s naming the
//!   animation, channel and node.

mod sample;
#[cfg(test)]
mod tests;

use glam::{Mat4, Quat, Vec3};

pub use sample::Pose;

/// A node's local transform as translation, rotation and scale (applied scale first): the
/// matrix `T·R·S`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Translation.
    pub translation: Vec3,
    /// Unit rotation quaternion.
    pub rotation: Quat,
    /// Scale per axis.
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self { translation: Vec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE }
    }
}

impl Transform {
    /// The matrix `T·R·S`.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

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
    /// The local transform as translation, rotation and scale, when the node was given that
    /// way (`None` for a node given by a matrix, which cannot be animated).
    pub trs: Option<Transform>,
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

impl Skin {
    /// The joint matrices of linear blend skinning in `pose`: joint `k`'s world matrix times
    /// its inverse bind matrix, mapping the skinned mesh's bind space to world space. A joint
    /// node outside the pose is an [`Error::DanglingReference`].
    pub fn joint_matrices(&self, pose: &Pose) -> Result<Vec<Mat4>> {
        self.joints
            .iter()
            .zip(&self.inverse_bind_matrices)
            .map(|(&j, ibm)| {
                pose.world.get(j).map(|w| *w * *ibm).ok_or_else(|| Error::DanglingReference {
                    what: "node",
                    index: j,
                    count: pose.world.len(),
                    by: format!("skin '{}'", self.name),
                })
            })
            .collect()
    }
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

impl Animation {
    /// The last key time of any channel (0 for an animation without keys): sample
    /// `time % duration()` to loop.
    pub fn duration(&self) -> f32 {
        self.channels.iter().filter_map(|c| c.times.last().copied()).fold(0.0, f32::max)
    }
}

use crate::{Error, Result};
