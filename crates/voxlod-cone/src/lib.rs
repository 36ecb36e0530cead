//! Voxel cone tracing on voxlod's sparse voxel octree (Yalçıner and Sahillioğlu 2020, §4.5, after
//! Crassin et al. 2011): direct light injected into the leaves and pre-filtered upward, then
//! cones marched front to back from shading points for ambient occlusion, diffuse indirect light
//! and a specular cone; and primary visibility with level of detail by distance.
//!
//! # Example
//! Inject a light into an octree of a floor and a ceiling and trace ambient occlusion and
//! diffuse light from the floor.
//! ```
//! use glam::{DVec3, UVec3, Vec3};
//! use voxlod_cone::{ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
//! use voxlod_format::GridSpec;
//! use voxlod_octree::{AveragePayload, BuildOptions, Octree};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // A 16×16 white floor at y = 0 and a 16×16 white ceiling at y = 8, in a 16³ grid of 1 m
//! // voxels, as an octree of Averages.
//! let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(16))?;
//! let mut voxels = Vec::new();
//! for x in 0..16 {
//!     for z in 0..16 {
//!         voxels.push((UVec3::new(x, 0, z), AveragePayload::new(Vec3::ONE, Vec3::Y, 1.0)));
//!         voxels.push((UVec3::new(x, 8, z), AveragePayload::new(Vec3::ONE, Vec3::NEG_Y, 1.0)));
//!     }
//! }
//! let geometry = Octree::build(grid, voxels, &BuildOptions::default())?;
//! // Light from above: the ceiling's top is lit, its underside (facing the floor) is not.
//! let light = Light::Directional { to_light: Vec3::Y, irradiance: Vec3::splat(3.0) };
//! let radiance: Octree<RadiancePayload> = inject(&geometry, &light, &Shadows::MARCH)?;
//! let options = TraceOptions { ao_radius: 4.0, ..TraceOptions::default() };
//! let tracer = ConeTracer::new(&radiance, options)?;
//! // On the floor, 7 voxels below the ceiling: the AO radius of 4 does not reach it.
//! let ao = tracer.ambient_occlusion(Vec3::new(8.0, 1.0, 8.0), Vec3::Y);
//! assert!(ao > 0.95, "{ao}");
//! // With a radius of 16 the ceiling occludes part of the hemisphere.
//! let wide = ConeTracer::new(&radiance, TraceOptions { ao_radius: 16.0, ..options })?;
//! assert!(wide.ambient_occlusion(Vec3::new(8.0, 1.0, 8.0), Vec3::Y) < ao - 0.02);
//! // The floor is in the ceiling's shadow: the cones bring back no light from above it.
//! assert!(tracer.diffuse(Vec3::new(8.0, 1.0, 8.0), Vec3::Y).max_element() < 1e-3);
//! // Bad options are errors that name the field.
//! let bad = TraceOptions { diffuse_aperture_deg: 180.0, ..options };
//! let err = ConeTracer::new(&radiance, bad).unwrap_err();
//! assert!(err.to_string().contains("diffuse_aperture_deg"));
//! # Ok(())
//! # }
//! ```
//!
//! # Modules
//! | module | owns |
//! |---|---|
//! | [`medium`] | [`RadiancePayload`] (opacity-weighted radiance) and the [`ConeMedium`] trait (opacity along a direction, radiance) |
//! | [`inject`](mod@inject) | [`inject()`]: light with shadows into the leaves; [`InjectionCache`]: no re-injection when nothing changed |
//! | [`cone`] | one cone's march: **aperture (full angle)**, footprint level, step, opacity correction, AO falloff — defined there once |
//! | [`tracer`] | [`ConeTracer`]: AO, diffuse and specular cones from a shading point; self-occlusion offsets |
//! | [`primary`] | [`PrimaryRenderer`]: primary visibility, one pixel-wide cone per pixel, level of detail by distance, shaded samples |
//! | [`dynamic`] | [`FramePipeline`]: a dynamic scene's frame — transform the cached voxels, rebuild the octree, re-inject the light (skipped when nothing moved) |
//! | [`differential`] | [`DifferentialRenderer`]: Heitz and Neyret's (2012) differential cone tracing of a `MicrosurfacePayload` octree with coverage masks, view- and light-dependent colour, depth of field |
//!
//! Shadows at injection are either marched through the geometry octree itself or given per leaf
//! by the caller ([`Shadows`]). The ray-traced references these estimates are measured against
//! are voxlod-cpu's `render::indirect` (same falloff, same cosine-weighted estimator).
//!
//! # Known behaviour, pinned by tests
//! - Thin walls leak at coarse levels through isotropic opacity (a node's opacity is the mean of
//!   its children's, so a one-voxel wall read at level `l` has opacity `2^−l`): a 30° cone
//!   meeting a one-voxel wall 20 voxels away accumulates less than 0.2 of opacity, against more
//!   than 0.5 through `Directional<RadiancePayload>`; 30° AO cones under a one-voxel ceiling
//!   under-estimate its occlusion, which 4° cones recover within 0.05 of the analytic value.
//! - Furnace: from inside a closed one-voxel shell of radiance 1 (exact `E/π = 1`), 30° cones
//!   through `Directional<RadiancePayload>` return 0.7–1, at least 0.2 more than through the
//!   isotropic octree; the cone blends the six directional opacities by `dir²`, so an oblique
//!   cone still sees a wall node as partly open.
//! - Shadow marches end one voxel short of a point light, so a light hanging just below a
//!   ceiling lights the floor under it.
//!
//! # Errors
//! Every fallible call returns [`Error`]: an option or light outside its range, naming the field
//! ([`Error::InvalidParameter`]); a per-leaf visibility list of the wrong length or with a value
//! outside \[0, 1\] ([`Error::VisibilityLength`], [`Error::InvalidVisibility`]); a failed build
//! of the radiance octree ([`Error::Octree`]). Per-pixel shading inputs are not errors: a
//! non-finite position or normal gives the unoccluded answer, and glossiness is clamped.
//!
//! # What this crate does not do
//! - Only direct light is injected: one bounce of indirect light, no multiple bounces.
//! - Injected radiance is Lambertian; one directional or point light, no emissive surfaces or
//!   environment light.
//! - No GPU: voxlod-gpu's `cone` module traces the AO, diffuse and specular cones and is checked
//!   against [`ConeTracer`] by its equivalence suite, and its `differential` module runs
//!   [`DifferentialRenderer`]'s march; injection and [`PrimaryRenderer`] run here.
//!
//! It depends on voxlod-octree and voxlod-format only (no BVH, no scene crate, no GPU API).
//!
//! # References
//! - Yalçıner, Sahillioğlu 2020, "Voxel transformation: scalable scene geometry discretization
//!   for global illumination", Journal of Real-Time Image Processing 17(5), §4.5: [`tracer`].
//! - Crassin, Neyret, Sainz, Green, Eisemann 2011, "Interactive Indirect Illumination Using
//!   Voxel Cone Tracing", Pacific Graphics: [`inject()`], [`cone`], [`tracer`], directional
//!   opacities.
//! - Heitz, Neyret 2012, "Representing Appearance and Pre-filtering Subpixel Data in Sparse
//!   Voxel Octrees", High Performance Graphics: [`differential`].

#![deny(missing_docs)]

pub mod cone;
pub mod differential;
pub mod dynamic;
mod error;
pub mod inject;
pub mod medium;
pub mod primary;
pub mod tracer;

pub use cone::{Cone, ConeResult, March, SampleInfo, falloff, trace, trace_shaded};
pub use differential::{
    Compositing, DepthOfField, DifferentialImage, DifferentialOptions, DifferentialPixel,
    DifferentialRenderer, FrameConstants, SurfaceShadeInput,
};
pub use dynamic::{FramePipeline, FrameReport};
pub use error::{Error, Result};
pub use inject::{InjectionCache, Light, Shadows, inject, occupied_leaves};
pub use medium::{ConeMedium, RadianceLeaf, RadiancePayload};
pub use primary::{
    PinholeCamera, PrimaryImage, PrimaryOptions, PrimaryPixel, PrimaryRenderer, ShadeInput,
    SurfaceMedium,
};
pub use tracer::{ConeTracer, TraceOptions, specular_aperture};

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;

#[cfg(test)]
mod tests;
