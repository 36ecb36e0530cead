//! The ground-truth renderer: the mesh ray cast with many stratified rays per pixel, box
//! filtered, and its G-buffer.
//!
//! Per pixel, `spp` camera rays through [`stratified`] sub-pixel positions (default 1024, a
//! 32×32 jittered grid) are averaged with equal weights: a box filter over the pixel. Each ray
//! that hits is shaded alike (`surface.rs`): interpolated shading normal and UV, bilinear texture
//! sample, double-sided materials facing the viewer, alpha masks and stochastic alpha blending,
//! one shadow ray toward the scene's light (visibility 0 or 1), times the optional
//! [`LightFilter`] of [`Options::light_filter`] (e.g. a participating medium's shadow:
//! [`crate::volume::Volume`]), [`crate::shading::shade`] with the optional ambient term. A miss
//! returns the scene's background colour.
//!
//! Output: a linear float [`Image`] whose RGB is the box-filtered radiance with the background
//! composited in and whose alpha is the coverage (the fraction of rays that hit), and a
//! [`GBuffer`].
//!
//! Determinism: a pixel's rays are a pure function of (pixel index, sample index, seed) through
//! [`Streams`], summed in sample order, and pixels are independent, so the same seed gives a
//! bit-identical image with any number of threads.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;
use voxlod_scene::camera::CameraFrame;
use voxlod_scene::{Camera, Geometry, Image, Scene};

use super::pixel_samples::{Streams, stratified};
pub use super::surface::LightFilter;
use super::surface::{Lighting, MeshTracer, SurfacePoint};
use super::{check_colour, check_image_size};
use crate::raycast::Bvh;
use crate::{Error, Result};

/// Options of [`render`]. Cost is linear in `width · height · spp`, about doubled by shadows.
#[derive(Clone, Copy)]
pub struct Options<'a> {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Camera rays per pixel, ≥ 1 (1024 as in the HPG 2023 paper's reference images).
    pub spp: u32,
    /// Seed of the sub-pixel jitter and the stochastic alpha; another seed gives an
    /// independent estimate of the same image (its difference measures the noise).
    pub seed: u32,
    /// Ambient irradiance term of [`crate::shading::shade`] (`albedo · ambient`), zero for none.
    pub ambient: Vec3,
    /// Whether to trace shadow rays (off: every point sees the light).
    pub shadows: bool,
    /// Extra light transmittance per shading point (`None`, the default: none, and the image
    /// is bit for bit the one without this option). Where the light is above the shading
    /// normal's horizon and the shadow ray (if traced) is not blocked, the direct light
    /// (diffuse and specular, not the ambient term) is multiplied by
    /// `filter.transmittance(position)` at the hit position, clamped into [0, 1] (NaN: 0).
    /// Evaluated once per such camera-ray hit: its cost adds to each lit sample. The G-buffer
    /// does not depend on it. The CPU renderer only: voxlod-gpu's kernel refuses it.
    pub light_filter: Option<&'a dyn LightFilter>,
}

impl Default for Options<'_> {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            spp: 1024,
            seed: 0,
            ambient: Vec3::ZERO,
            shadows: true,
            light_filter: None,
        }
    }
}

impl std::fmt::Debug for Options<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Options")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("spp", &self.spp)
            .field("seed", &self.seed)
            .field("ambient", &self.ambient)
            .field("shadows", &self.shadows)
            .field("light_filter", &self.light_filter.map(|_| "<LightFilter>"))
            .finish()
    }
}

/// Equal when every field is, the light filters being the same object (or both `None`).
impl PartialEq for Options<'_> {
    fn eq(&self, o: &Self) -> bool {
        let filters = match (self.light_filter, o.light_filter) {
            (None, None) => true,
            (Some(a), Some(b)) => std::ptr::addr_eq(a as *const dyn LightFilter, b),
            _ => false,
        };
        filters
            && (self.width, self.height, self.spp, self.seed, self.ambient, self.shadows)
                == (o.width, o.height, o.spp, o.seed, o.ambient, o.shadows)
    }
}

/// What the camera sees at one pixel: the hit of the ray through the pixel centre (one shading
/// point per pixel, what cone tracing and compositing need), plus the coverage of the pixel.
///
/// Layout: `#[repr(C)]`, 48 bytes, `Pod`, ready for a GPU buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct GTexel {
    /// World position of the centre ray's hit (zero on a miss).
    pub position: Vec3,
    /// Distance from the eye to that hit along the unit centre ray (not view-space z: multiply
    /// by `dir · forward` for that); `f32::INFINITY` on a miss.
    pub depth: f32,
    /// Unit shading normal at the hit, flipped toward the viewer on double-sided materials
    /// (zero on a miss).
    pub normal: Vec3,
    /// Fraction of the pixel's rays that hit geometry: the stratified rays of [`render`], or 0/1
    /// from the centre ray alone for [`gbuffer`].
    pub coverage: f32,
    /// Linear albedo of the material at the hit, texture applied (zero on a miss).
    pub albedo: Vec3,
    /// Triangle id of the hit, `u32::MAX` on a miss.
    pub triangle: u32,
}

/// A per-pixel G-buffer, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct GBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` texels.
    pub texels: Vec<GTexel>,
    /// The camera's eye: every texel's point was seen from here (secondary rays from a texel
    /// leave toward this side of the surfaces through it, [`crate::raycast::offset_origin`]).
    pub eye: Vec3,
}

impl GBuffer {
    /// Texel of pixel `(x, y)`.
    pub fn get(&self, x: u32, y: u32) -> &GTexel {
        &self.texels[y as usize * self.width as usize + x as usize]
    }
}

/// The output of [`render`].
#[derive(Clone, Debug, PartialEq)]
pub struct GroundTruth {
    /// Linear radiance (RGB, background composited) and coverage (A).
    pub image: Image,
    /// The pixel-centre G-buffer, with the coverage of the stratified rays.
    pub gbuffer: GBuffer,
}

/// Renders `scene` (whose flattened triangles are `geometry`, with `bvh` built over them) from
/// `camera`. Errors on a zero or oversized image, `spp = 0`, a non-finite or negative ambient
/// term, an invalid camera or light, or a BVH/geometry mismatch.
pub fn render(
    scene: &Scene,
    geometry: &Geometry,
    bvh: &Bvh,
    camera: &Camera,
    options: &Options,
) -> Result<GroundTruth> {
    let Options { width, height, spp, seed, ambient, shadows, light_filter } = *options;
    check_options(options)?;
    camera.validate()?;
    let tracer = MeshTracer::new(scene, geometry, bvh)?;
    let frame = camera.frame(width, height);
    let streams = Streams::new(seed);
    let background = scene.background;
    let lighting = Lighting { shadows, ambient, filter: light_filter };
    let mut image = Image::new(width, height, Vec4::ZERO);
    let mut texels = vec![GTexel::default(); image.pixels.len()];
    let w = width as usize;
    image.pixels.par_chunks_mut(w).zip(texels.par_chunks_mut(w)).enumerate().for_each(
        |(y, (row, grow))| {
            for (x, (px, gt)) in row.iter_mut().zip(grow.iter_mut()).enumerate() {
                let pixel = (y * w + x) as u32;
                let corner = Vec2::new(x as f32, y as f32);
                let dir =
                    |s: u32| frame.ray_dir(corner + stratified(s, spp, streams.jitter(pixel, s)));
                let mut sum = Vec3::ZERO;
                let mut hits = 0u32;
                let mut add = |s: u32, dir: Vec3, surface: Option<SurfacePoint>| {
                    sum += match surface {
                        Some(surface) => {
                            hits += 1;
                            tracer.radiance(&surface, dir, pixel, s, &streams, lighting)
                        }
                        None => background,
                    };
                };
                // Camera rays in packets of 4 consecutive samples (same answers as one by
                // one), the remainder one by one; radiance summed in sample order.
                let packets = spp / 4 * 4;
                for s in (0..packets).step_by(4) {
                    let dirs = [dir(s), dir(s + 1), dir(s + 2), dir(s + 3)];
                    let surfaces = tracer.trace4(frame.eye, &dirs, pixel, s, &streams);
                    for (l, (&d, surface)) in dirs.iter().zip(surfaces).enumerate() {
                        add(s + l as u32, d, surface);
                    }
                }
                for s in packets..spp {
                    let d = dir(s);
                    add(s, d, tracer.trace(frame.eye, d, pixel, s, &streams));
                }
                *px = (sum / spp as f32).extend(hits as f32 / spp as f32);
                *gt = centre_texel(&tracer, &frame, corner, pixel, &streams);
                gt.coverage = hits as f32 / spp as f32;
            }
        },
    );
    Ok(GroundTruth { image, gbuffer: GBuffer { width, height, texels, eye: frame.eye } })
}

/// Checks what [`render`] checks before it renders — the options, the camera, and that
/// `scene`, `geometry` and `bvh` belong together with a valid light — so that another backend
/// (voxlod-gpu's ground-truth kernel) refuses bad input with the same errors.
pub fn validate(
    scene: &Scene,
    geometry: &Geometry,
    bvh: &Bvh,
    camera: &Camera,
    options: &Options,
) -> Result<()> {
    check_options(options)?;
    camera.validate()?;
    MeshTracer::new(scene, geometry, bvh)?;
    Ok(())
}

/// The image size, `spp` and ambient checks of [`render`] (an error naming the parameter).
pub fn check_options(options: &Options) -> Result<()> {
    let Options { width, height, spp, ambient, .. } = *options;
    check_image_size(width, height)?;
    if spp == 0 {
        return Err(Error::InvalidParameter {
            name: "spp",
            value: "0".into(),
            reason: "at least one ray per pixel".into(),
        });
    }
    check_colour("ambient", ambient)
}

/// The G-buffer alone, from one ray through each pixel centre (coverage 0 or 1): the cheap
/// shading points for cone tracing. It equals the G-buffer of [`render`] except for coverage.
pub fn gbuffer(
    scene: &Scene,
    geometry: &Geometry,
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Result<GBuffer> {
    check_image_size(width, height)?;
    camera.validate()?;
    let tracer = MeshTracer::new(scene, geometry, bvh)?;
    let frame = camera.frame(width, height);
    // The centre ray's stochastic alpha uses seed 0, as in `render`'s default.
    let streams = Streams::new(0);
    let mut texels = vec![GTexel::default(); width as usize * height as usize];
    let w = width as usize;
    texels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, gt) in row.iter_mut().enumerate() {
            let pixel = (y * w + x) as u32;
            *gt = centre_texel(&tracer, &frame, Vec2::new(x as f32, y as f32), pixel, &streams);
        }
    });
    Ok(GBuffer { width, height, texels, eye: frame.eye })
}

/// Sample index of the pixel-centre ray in the random streams (never a stratified sample).
const CENTRE_SAMPLE: u32 = u32::MAX;

fn centre_texel(
    tracer: &MeshTracer,
    frame: &CameraFrame,
    corner: Vec2,
    pixel: u32,
    streams: &Streams,
) -> GTexel {
    let dir = frame.ray_dir(corner + 0.5);
    match tracer.trace(frame.eye, dir, pixel, CENTRE_SAMPLE, streams) {
        Some(SurfacePoint { hit, position, normal, material }) => GTexel {
            position,
            depth: hit.t,
            normal,
            coverage: 1.0,
            albedo: material.albedo,
            triangle: hit.triangle,
        },
        None => GTexel { depth: f32::INFINITY, triangle: u32::MAX, ..GTexel::default() },
    }
}

#[cfg(test)]
mod tests;
