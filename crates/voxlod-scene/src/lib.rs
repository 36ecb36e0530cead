//! Scene inputs for voxlod: triangle [`Mesh`]es in world space, [`Material`]s with
//! [`Texture`]s, a pinhole [`Camera`], [`Light`]s, the background colour, and float/8-bit
//! [`image`]s; loaders for OBJ+MTL ([`obj`]) and glTF 2.0 ([`gltf`]); deterministic procedural
//! scenes ([`procedural`]); displaced-sphere particles for procedural volumes ([`particles`]).
//!
//! Conventions (the CPU↔GPU contract): right-handed, y up; colours are linear RGB unless a name
//! says sRGB; texture coordinates have their origin at the image's top-left corner, v pointing
//! down (glTF's convention — the OBJ loader flips v).

#![deny(missing_docs)]

pub mod animation;
pub mod camera;
mod error;
pub mod gltf;
pub mod image;
pub mod light;
pub mod material;
pub mod mesh;
pub mod obj;
pub mod particles;
pub mod procedural;
pub mod scene;
pub mod texture;

pub use animation::{Animation, Node, Pose, Skin, Transform};
pub use camera::Camera;
pub use error::{Error, Result};
pub use image::{Image, Srgb8Image};
pub use light::{Light, LightSample};
pub use material::{AlphaMode, Material, MaterialSample, TextureRef};
pub use mesh::Mesh;
pub use scene::{Geometry, Scene};
pub use texture::{Sampler, Texture, WrapMode};
