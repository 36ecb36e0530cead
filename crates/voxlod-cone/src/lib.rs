//! Voxel cone tracing on voxlod's sparse voxel octree (Yalçıner and Sahillioğlu 2020, §4.5, after Crassin et al.
//! 2011): direct light injected into the leaves and pre-filtered upward, then cones marched
//! front to back from shading points for ambient occlusion, diffuse indirect light and a
//! specular cone.
//!
//! | module | owns |
//! |---|---|
//! | [`medium`] | [`RadiancePayload`] (opacity-weighted radiance) and the [`ConeMedium`] trait (opacity along a direction, radiance) |
//! | [`inject`](mod@inject) | [`inject()`]: light with shadows into the leaves; [`InjectionCache`]: no re-injection when nothing changed |
//! | [`cone`] | one cone's march: **aperture (full angle)**, footprint level, step, opacity correction, AO falloff — defined there once |
//! | [`tracer`] | [`ConeTracer`]: AO, diffuse and specular cones from a shading point; self-occlusion offsets |
//! | [`primary`] | [`PrimaryRenderer`]: primary visibility, one pixel-wide cone per pixel, level of detail by distance, shaded samples |
//! | [`differential`] | [`DifferentialRenderer`]: Heitz and Neyret's (2012) differential cone tracing of a `MicrosurfacePayload` octree with coverage masks, view- and light-dependent colour, depth of field |
//!
//! Layering: depends on `voxlod-octree` and `voxlod-format` only (no BVH, no GPU API). Shadows
//! at injection are either marched through the geometry octree itself or given per leaf by the
//! caller ([`Shadows`]). The wgpu kernel of the AO / diffuse / specular cones is voxlod-gpu's
//! `cone` module (checked against [`ConeTracer`] by its equivalence suite).
//!
//! ```
//! use glam::{DVec3, UVec3, Vec3};
//! use voxlod_format::GridSpec;
//! use voxlod_octree::{AveragePayload, BuildOptions, Octree};
//! use voxlod_cone::{ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
//!
//! // A 16×16 white floor at y = 0 and a 16×16 white ceiling at y = 8, in a 16³ grid of 1 m voxels.
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
//! // Bad options are errors that name the field.
//! let bad = TraceOptions { diffuse_aperture_deg: 180.0, ..options };
//! assert!(ConeTracer::new(&radiance, bad).unwrap_err().to_string().contains("diffuse_aperture_deg"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

pub mod cone;
pub mod differential;
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
pub use error::{Error, Result};
pub use inject::{InjectionCache, Light, Shadows, inject, occupied_leaves};
pub use medium::{ConeMedium, RadianceLeaf, RadiancePayload};
pub use primary::{
    PinholeCamera, PrimaryImage, PrimaryOptions, PrimaryPixel, PrimaryRenderer, ShadeInput,
    SurfaceMedium,
};
pub use tracer::{ConeTracer, TraceOptions, specular_aperture};

#[cfg(test)]
mod tests;
