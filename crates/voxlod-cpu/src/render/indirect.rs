//! Ray-traced references for voxel cone tracing, on the mesh itself: ambient occlusion and
//! one-bounce diffuse indirect light, per pixel of a [`GBuffer`].
//!
//! # Definitions (shared with voxlod-cone, which defines them in its `cone` and `tracer` modules)
//! - **Directions**: `spp` cosine-distributed directions about the G-buffer's shading normal,
//!   from the counter-based RNG ([`crate::random`]): `rand_f32(pixel, sample, key)` with two keys
//!   derived from the seed. Rays leave from [`offset_origin`], seen from the G-buffer's eye (a
//!   point on an edge or corner gets the limit from the visible side).
//! - **AO** `= 1 − mean f(t_hit)`, `f(t) = max(0, 1 − t/R)` ([`falloff`], the same function as
//!   `voxlod_cone::falloff`), `t_hit` the distance of the closest hit (alpha masks and blending
//!   honoured), a miss or a hit beyond `R` counting 0. 1: unoccluded.
//! - **One-bounce diffuse indirect light**: the incoming radiance `E/π = mean L(ω)` over the
//!   cosine-distributed directions, where `L(ω)` is the radiance leaving the first surface hit
//!   along `ω` toward the shading point: direct light only, with a shadow ray, through
//!   [`crate::shading::shade`] (no ambient term) — one bounce. Misses bring nothing (the
//!   background is not a light). The outgoing indirect radiance of a diffuse pixel is
//!   `albedo · E/π`. Per-pixel noise falls as `1/√spp`; two seeds measure it.

use glam::Vec3;
use rayon::prelude::*;
use voxlod_scene::{Geometry, Scene};

use super::ground_truth::GBuffer;
use super::pixel_samples::Streams;
use super::surface::{Lighting, MeshTracer};
use crate::random::{rand_f32, rand_u32};
use crate::raycast::{Bvh, offset_origin};
use crate::{Error, Result};

/// The AO falloff `f(t) = max(0, 1 − t/R)` for radius `R > 0` (module docs).
#[inline]
pub fn falloff(t: f32, radius: f32) -> f32 {
    (1.0 - t / radius).clamp(0.0, 1.0)
}

/// Options of [`ambient_occlusion`] and [`indirect_diffuse`]. Cost is linear in `spp` (times
/// about two for the indirect light's shadow rays).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Rays per pixel, ≥ 1.
    pub spp: u32,
    /// Seed of the directions; another seed gives an independent estimate.
    pub seed: u32,
    /// AO radius `R` in world units, finite and > 0 (ignored by [`indirect_diffuse`]).
    pub ao_radius: f32,
}

impl Default for Options {
    fn default() -> Self {
        Self { spp: 256, seed: 0, ao_radius: 1.0 }
    }
}

impl Options {
    fn validate(&self) -> Result<()> {
        if self.spp == 0 {
            return Err(Error::InvalidParameter {
                name: "spp",
                value: "0".into(),
                reason: "at least one ray per pixel".into(),
            });
        }
        if !(self.ao_radius.is_finite() && self.ao_radius > 0.0) {
            return Err(Error::InvalidParameter {
                name: "ao_radius",
                value: self.ao_radius.to_string(),
                reason: "must be finite and > 0".into(),
            });
        }
        Ok(())
    }
}

/// Unit direction `(u1, u2)` cosine-distributed about unit `n`.
#[inline]
pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt());
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    (t * local.x + bt * local.y + n * local.z).normalize_or(n)
}

fn per_pixel<T: Send + Default + Clone>(
    gbuffer: &GBuffer,
    f: impl Fn(u32, &super::ground_truth::GTexel) -> T + Sync,
) -> Vec<T> {
    gbuffer
        .texels
        .par_iter()
        .enumerate()
        .map(|(i, t)| if t.triangle == u32::MAX { T::default() } else { f(i as u32, t) })
        .collect()
}

/// Ray-traced AO per pixel of `gbuffer` (row-major; 1 where the G-buffer missed). Errors on
/// invalid options or a scene/geometry/BVH mismatch.
pub fn ambient_occlusion(
    scene: &Scene,
    geometry: &Geometry,
    bvh: &Bvh,
    gbuffer: &GBuffer,
    options: &Options,
) -> Result<Vec<f32>> {
    options.validate()?;
    let tracer = MeshTracer::new(scene, geometry, bvh)?;
    let streams = Streams::new(options.seed);
    let (k1, k2) = keys(options.seed);
    let r = options.ao_radius;
    let ao = per_pixel(gbuffer, |pixel, t| {
        let mut occ = 0.0;
        for s in 0..options.spp {
            let dir = cosine_direction(t.normal, rand_f32(pixel, s, k1), rand_f32(pixel, s, k2));
            let origin =
                offset_origin(geometry, t.triangle, t.position, dir, gbuffer.eye - t.position);
            if let Some(hit) = tracer.trace(origin, dir, pixel, s, &streams) {
                occ += falloff(hit.hit.t, r);
            }
        }
        1.0 - occ / options.spp as f32
    });
    // Misses: unoccluded.
    Ok(ao
        .into_iter()
        .zip(&gbuffer.texels)
        .map(|(a, t)| if t.triangle == u32::MAX { 1.0 } else { a })
        .collect())
}

/// One-bounce diffuse incoming radiance `E/π` per pixel of `gbuffer` (module docs; zero where
/// the G-buffer missed). Multiply by the albedo for the outgoing indirect light.
pub fn indirect_diffuse(
    scene: &Scene,
    geometry: &Geometry,
    bvh: &Bvh,
    gbuffer: &GBuffer,
    options: &Options,
) -> Result<Vec<Vec3>> {
    options.validate()?;
    let tracer = MeshTracer::new(scene, geometry, bvh)?;
    let streams = Streams::new(options.seed);
    let (k1, k2) = keys(options.seed);
    let lighting = Lighting { shadows: true, ambient: Vec3::ZERO, filter: None };
    Ok(per_pixel(gbuffer, |pixel, t| {
        let mut sum = Vec3::ZERO;
        for s in 0..options.spp {
            let dir = cosine_direction(t.normal, rand_f32(pixel, s, k1), rand_f32(pixel, s, k2));
            let origin =
                offset_origin(geometry, t.triangle, t.position, dir, gbuffer.eye - t.position);
            if let Some(surface) = tracer.trace(origin, dir, pixel, s, &streams) {
                sum += tracer.radiance(&surface, dir, pixel, s, &streams, lighting);
            }
        }
        sum / options.spp as f32
    }))
}

/// The two direction keys of `seed` (distinct from [`Streams`]' purposes 0–3).
fn keys(seed: u32) -> (u32, u32) {
    (rand_u32(seed, 16, 0x5EED), rand_u32(seed, 17, 0x5EED))
}

#[cfg(test)]
mod tests;
