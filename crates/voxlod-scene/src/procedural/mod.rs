//! Deterministic procedural scenes: embedded test scenes that need no download, each built to
//! show where pre-filtered voxels matter, plus small analytic shapes for tests.
//!
//! | builtin | what it is | what it stresses |
//! |---|---|---|
//! | [`forest`](mod@forest) | ground + trees: trunks, thin branches, many tiny leaf quads (alpha-masked, double-sided) | geometry below a voxel and a pixel; partial coverage at every orientation; scales past 1 M triangles |
//! | [`island`](mod@island) | heightfield island, specular sea, rocks, thin grass blades | direction-dependent opacity of oriented sub-voxel blades; two surfaces in one voxel at the shore; specular highlights |
//! | [`blinds`](mod@blinds) | tilted two-coloured slats spaced below a voxel, before a striped wall | directional opacity and colour with a closed-form answer |
//! | [`crowd`](mod@crowd) | skinned walkers (17 joints, a walk cycle) among rotating tori and cubes on a static floor, animated | dynamic scenes: voxel transformation of rigid and skinned objects against re-voxelization |
//! | [`bumpy`](mod@bumpy) (`bumpy-sphere`, `bumpy-specular`) | a closed sphere with fine fractal displacement, colour correlated with height or one glossy grey | view- and light-dependent colour and roughness from sub-pixel relief (Heitz and Neyret 2012) |
//! | [`city`](mod@city) | city blocks: buildings with recessed windows as geometry, streets with markings, sidewalks, lamp posts, benches, parked cars | large occluders with sub-voxel relief (two surfaces and jambs in a voxel), many distinct colours, small closed props |
//! | `cornell`, `cube`, `sphere` | [`primitives`] | analytic checks |
//!
//! Triangle counts at default parameters: `forest` 294 776, `island` about 142 000, `city`
//! 164 184, `blinds` 1 554, `bumpy-sphere` and `bumpy-specular` 81 920, `crowd` 60 898 (16 walkers, 16 objects),
//! `cornell` 34, `cube` 12, `sphere` 1 280. Build one by name with
//! [`builtin`]`("forest", &[("trees", "20")])` or [`from_spec`]`("forest?trees=20&seed=3")`
//! (the syntax is in [`registry`]), or directly from a parameter struct ([`ForestParams`],
//! [`IslandParams`], [`CityParams`], [`BlindsParams`]), whose fields document their ranges and cost.
//!
//! ```
//! use voxlod_scene::procedural::{ForestParams, forest, from_spec};
//!
//! let a = from_spec("forest?trees=2&leaves=100&seed=3")?;
//! let p = ForestParams { trees: 2, leaves_per_tree: 100, seed: 3, ..Default::default() };
//! assert_eq!(a, forest(&p)?);
//! assert_eq!(a.triangle_count() as u64, p.triangle_count());
//! # Ok::<(), voxlod_scene::Error>(())
//! ```
//!
//! **Determinism.** A scene is a pure function of its parameters and seed, identical on every
//! platform: randomness comes from [`Rng`] (SplitMix64) with one stream per object,
//! trigonometry from [`rng::sin_cos_turns`] (no libm, camera placement included), noise from a
//! lattice hash; no hash-map iteration order or thread scheduling is involved. The tests hash
//! every bit of the generated geometry.
//!
//! Units are arbitrary but consistent (think metres); y is up, the ground or sea is the plane
//! y = 0 centred at the origin.

pub mod blinds;
mod builder;
pub mod bumpy;
pub mod city;
pub mod crowd;
pub mod forest;
pub mod island;
pub(crate) mod noise;
mod param;
pub mod primitives;
pub mod registry;
pub mod rng;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod testutil;
mod tree;

use glam::Vec3;

pub use blinds::{BlindsParams, SlatGeometry, blinds};
pub use bumpy::{BumpyParams, bumpy};
pub use city::{CityParams, city};
pub use crowd::{CrowdParams, crowd};
pub use forest::{ForestParams, forest};
pub use island::{IslandParams, island};
pub use param::MAX_TRIANGLES;
pub use registry::{ParamInfo, builtin, builtin_names, builtin_params, from_spec, parse_spec};
pub use rng::Rng;

use crate::{Camera, Light};

/// Linear sky colour of the outdoor scenes' background.
const SKY: Vec3 = Vec3::new(0.42, 0.60, 0.85);

/// A warm sun in direction `to_light` (normalized here).
fn sun(to_light: Vec3) -> Light {
    Light::Directional { to_light: to_light.normalize(), irradiance: Vec3::new(3.2, 3.0, 2.7) }
}

/// [`Camera::framing`] with the deterministic sine of [`rng::sin_cos_deg`]: a camera looking at
/// the sphere `(center, radius)` from `direction`, far enough to see it whole in `fov_y_deg`.
fn framing(direction: Vec3, center: Vec3, radius: f32, fov_y_deg: f32) -> Camera {
    let (half, _) = rng::sin_cos_deg(0.5 * fov_y_deg);
    let dir = direction.normalize();
    let eye = center + dir * (radius / half * 1.05);
    Camera::look_at(eye, center, Vec3::Y, fov_y_deg)
}
