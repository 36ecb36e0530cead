//! The scene inputs of voxlod: triangle [`Mesh`]es in `f32` coordinates local to an `f64`
//! [`Scene::origin`] (far-from-origin models are re-centred on load), [`Material`]s with
//! [`Texture`]s, a pinhole [`Camera`], [`Light`]s and the background colour; loaders for OBJ + MTL
//! ([`obj`]) and glTF 2.0 ([`gltf`]) that turn every malformed file into an [`Error`] naming the
//! file and the element; deterministic procedural scenes that need no download ([`procedural`]);
//! float and 8-bit sRGB [`image`]s; and the displaced-sphere particles of procedural
//! participating media ([`particles`]).
//!
//! A [`Scene`] flattens into a [`Geometry`], the triangle arrays voxlod's voxelizers and ray
//! casters consume.
//!
//! # Example
//! Load an OBJ from memory, frame it with a camera, build a procedural scene and flatten it, and
//! see a malformed file refused. [`Scene::load`] loads an `.obj`, `.gltf` or `.glb` file from
//! disk and validates it.
//! ```
//! use std::path::Path;
//!
//! use glam::{Vec2, Vec3};
//! use voxlod_scene::{Error, obj, procedural};
//!
//! # fn main() -> voxlod_scene::Result<()> {
//! // OBJ text from memory (companion MTL and texture files come through the resolver).
//! let text = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nf 1 2 3 4\n";
//! let no_files = |_: &Path| Err(std::io::ErrorKind::NotFound.into());
//! let (quad, report) = obj::load_from_str(Path::new("quad.obj"), text, no_files)?;
//! assert_eq!((quad.triangle_count(), report.polygons_triangulated), (2, 1));
//! assert_eq!(quad.bounds()?, (Vec3::ZERO, Vec3::new(2.0, 1.0, 0.0)));
//!
//! // A camera framing it: the quad's centre projects to the image's centre.
//! let frame = quad.default_camera()?.frame(64, 64);
//! let (pixel, _depth) = frame.project(Vec3::new(1.0, 0.5, 0.0)).expect("in front of the eye");
//! assert!((pixel - Vec2::splat(32.0)).length() < 1e-3);
//!
//! // A procedural scene by name: deterministic, flattened into one triangle array.
//! let forest = procedural::from_spec("forest?trees=2&leaves=100&seed=3")?;
//! let geometry = forest.geometry();
//! assert_eq!(geometry.triangle_count(), forest.triangle_count());
//! assert_eq!(forest, procedural::from_spec("forest?trees=2&leaves=100&seed=3")?);
//!
//! // Bad input is an error naming the file and the line, not a panic.
//! let err = obj::load_from_str(Path::new("bad.obj"), "v 0 0 nan\n", no_files).unwrap_err();
//! assert!(matches!(err, Error::Obj { .. }) && err.to_string().starts_with("bad.obj: line 1"));
//! # Ok(())
//! # }
//! ```
//!
//! # Conventions
//! Coordinates: the loaders read in `f64` and re-centre each file on an origin chosen from its
//! bounds (zero unless the model sits far from the world origin relative to its size; see
//! [`voxlod_format::origin`]); a scene's meshes, camera and lights are local to it, world
//! positions given by a user go through [`Scene::to_local`], results leaving the library through
//! [`Scene::to_world`].
//!
//! The CPU↔GPU contract: right-handed, y up; colours are linear RGB unless a name says sRGB; a
//! white Lambertian surface facing a directional light of irradiance `E` has radiance `E/π`;
//! texture coordinates have their origin at the image's top-left corner, v pointing down
//! (glTF's convention — the OBJ loader flips v); pixel `(x, y)` has its centre at
//! `(x + 0.5, y + 0.5)` from the image's top-left corner ([`camera::CameraFrame::ray_dir`]).
//!
//! # Main types
//! | item | what it is |
//! |---|---|
//! | [`Scene`] | meshes, materials, textures, camera, lights, background, all local to [`Scene::origin`] (`world = local + origin`, `f64`); [`Scene::load`], [`Scene::geometry`], [`Scene::default_camera`], [`Scene::to_local`] / [`Scene::to_world`] |
//! | [`Mesh`], [`Geometry`] | one indexed triangle mesh in the scene's (local) coordinates; all of a scene's triangles in flat arrays with a material per triangle |
//! | [`Material`], [`Texture`], [`Sampler`] | base colour (factor × sRGB texture, bilinear in linear space), Blinn-Phong specular, [`AlphaMode`], sidedness |
//! | [`Camera`], [`camera::CameraFrame`] | a look-at pinhole camera and the one primary-ray convention |
//! | [`Light`] | one directional or point light, [`Light::sample`]d at a point |
//! | [`Image`], [`Srgb8Image`] | linear float RGBA as renderers produce it; 8-bit sRGB as PNGs hold it and metrics score it |
//! | [`obj`], [`gltf`] | the loaders, each with a `LoadReport` of what was skipped or repaired and a `load_from_bytes` that reads companion files through a resolver |
//! | [`animation`] | node hierarchies, skins and animations sampled at a time (step, linear, cubic spline): [`Pose`], joint matrices |
//! | [`procedural`] | `forest`, `island`, `blinds`, `crowd` (skinned walkers and rotating rigid objects, animated) and `cornell`, `cube`, `sphere`, by name ([`procedural::from_spec`]) or from parameter structs; pure functions of their parameters and seed |
//! | [`subdivide`] | midpoint (surface kept) and Loop 1987 (smoothed) subdivision of meshes and scenes; the `subdivide=N&subdivision=…` spec parameters |
//! | [`particles`] | displaced spheres, their animation, and deterministic smoke, explosion and cloud generators |
//!
//! # Errors
//! Every fallible call returns [`Error`]: a file that cannot be read ([`Error::Io`]); a
//! malformed OBJ/MTL file, with the line ([`Error::Obj`]), or glTF file, with the element
//! ([`Error::Gltf`]); an image that cannot be decoded ([`Error::Image`]); a mesh with a
//! non-finite attribute, an index out of range or attribute arrays of different lengths
//! ([`Error::NonFinite`], [`Error::IndexOutOfRange`], [`Error::AttributeLength`]); a material or
//! texture that does not exist ([`Error::DanglingReference`]); no triangles where some are needed
//! ([`Error::EmptyScene`]); a parameter or particle field out of its range, with the range
//! ([`Error::InvalidParameter`], [`Error::InvalidParticle`]); a file type it does not load
//! ([`Error::UnsupportedFormat`]).
//!
//! # What this crate does not do
//! - It does not render, voxelize or build acceleration structures (voxlod-cpu does).
//! - glTF materials are shaded as Lambert diffuse with their base colour: metallic-roughness
//!   parameters, normal maps, emission and `KHR_lights_punctual` are not read.
//! - Renders and voxelizers see the meshes flattened at the rest pose ([`Scene::geometry`]);
//!   node hierarchies, skins and animations ([`Scene::nodes`]) are sampled into poses and joint
//!   matrices ([`animation`]) but posing a mesh is voxlod-cpu's (`dynamic`). Morph targets are
//!   not animated (a morph-weight channel is an error).
//! - Formats: OBJ + MTL, glTF 2.0 (`.gltf`, `.glb`), textures in PNG and JPEG; files are read
//!   whole into memory.
//!
//! It depends on voxlod-format (sRGB conversions, atomic output) and on no GPU API.
//!
//! # References
//! - McNabb 2015, "Sparse Procedural Volume Rendering", GPU Pro 6, §5.5.2: [`particles`].
//! - Loop 1987, "Smooth Subdivision Surfaces Based on Triangles", M.S. thesis, University of
//!   Utah: [`subdivide`].
//! - Steele, Lea, Flood 2014, "Fast Splittable Pseudorandom Number Generators", OOPSLA
//!   (SplitMix64): [`procedural::Rng`].

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
pub mod subdivide;
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

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;
