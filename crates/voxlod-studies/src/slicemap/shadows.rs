//! Transmittance shadow maps (Eisemann and Décoret 2006, §3.1) against ray-traced
//! transmittance through the same geometry.
//!
//! The scene's semi-transparent triangles (material names containing
//! [`ShadowConfig::transmissive`], the forest's leaves by default; every triangle when none
//! matches) go into a locally sliced slicemap from the light, the others into an opaque depth
//! map ([`TransmittanceShadowMap`]). At every pixel-centre hit of the scene's camera the map's
//! transmittance `(1 − σ)^n` is compared with the exact one ([`RayTracedTransmittance`]:
//! every semi-transparent triangle the segment to the light crosses), and the ground-truth
//! renderer shades the scene with each (its own shadow rays off, the transmittance as its light
//! filter), so the images differ only in the shadows. The "opaque leaves" row is what a standard
//! shadow map gives: the exact visibility with semi-transparent triangles opaque.

use glam::Vec3;
use serde::Serialize;
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth::{self, GBuffer, LightFilter};
use voxlod_cpu::voxelize::slicemap::Slicing;
use voxlod_cpu::voxelize::slicemap::shadow::{
    RayTracedTransmittance, ShadowOptions, TransmittanceShadowMap,
};
use voxlod_eval::heatmap::error_heatmap;
use voxlod_eval::metrics::{ImageMetrics, compare};
use voxlod_gpu::slicemap::SlicemapRenderer;
use voxlod_scene::{Geometry, Scene, Srgb8Image};

use super::{Timing, time};
use crate::Error;

/// What the shadow part measures.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowConfig {
    /// Scene spec.
    pub scene: String,
    /// Substring of the names of semi-transparent materials.
    pub transmissive: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Rays per pixel of the rendered images.
    pub spp: u32,
    /// Maps measured: (columns per side, slices of the semi-transparent map).
    pub maps: Vec<(u32, u32)>,
    /// Attenuation of one semi-transparent layer.
    pub sigma: f32,
    /// Lookup bias in pixels of the light's map.
    pub bias_pixels: f64,
    /// Ambient irradiance of the renders (so that shadowed parts stay visible).
    pub ambient: f32,
    /// Timed runs per figure.
    pub repeats: u32,
}

/// One method's transmittance against the ray-traced one.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShadowRow {
    /// Method.
    pub method: String,
    /// Columns per side (slicemap rows).
    pub map_size: Option<u32>,
    /// Slices (slicemap rows).
    pub slices: Option<u32>,
    /// Hit points whose opaque occlusion differs from the reference's, fraction (slicemap rows).
    pub opaque_mismatch: Option<f64>,
    /// Hit points unoccluded in both whose layer count differs, fraction (slicemap rows).
    pub count_mismatch: Option<f64>,
    /// Mean absolute transmittance error over the camera's hit points.
    pub mean_abs_error: f64,
    /// Root mean square error.
    pub rmse: f64,
    /// Largest absolute error.
    pub max_abs_error: f64,
    /// The shaded image against the ray-traced one.
    pub image: ImageMetrics,
    /// Time to build the maps, ms (CPU reference).
    pub build_ms: Option<Timing>,
    /// The same on the GPU path.
    pub gpu_build_ms: Option<Timing>,
    /// Time to look up every hit point, ms.
    pub lookup_ms: Timing,
    /// Bytes of the maps.
    pub memory_bytes: u64,
}

/// The shadow part's results.
#[derive(Clone, Debug)]
pub struct ShadowResult {
    /// Scene spec.
    pub scene: String,
    /// Semi-transparent triangles / all triangles.
    pub transmissive: (usize, usize),
    /// Hit points compared.
    pub points: usize,
    /// Rows: ray traced (the reference), opaque leaves, then one per slice count.
    pub rows: Vec<ShadowRow>,
    /// Images: label and picture (reference, methods, error heat map).
    pub images: Vec<(String, Srgb8Image)>,
}

fn errors(test: &[f32], reference: &[f32]) -> (f64, f64, f64) {
    let n = reference.len().max(1) as f64;
    let (mut sum, mut sq, mut max) = (0.0, 0.0, 0.0f64);
    for (a, b) in test.iter().zip(reference) {
        let e = (*a as f64 - *b as f64).abs();
        sum += e;
        sq += e * e;
        max = max.max(e);
    }
    (sum / n, (sq / n).sqrt(), max)
}

/// A camera from the scene camera's direction framing the semi-transparent triangles and, for
/// a directional light, their shadow on the plane of the scene's lowest point.
fn shadow_camera(
    scene: &Scene,
    g: &Geometry,
    flags: &[bool],
    light: &voxlod_scene::Light,
) -> Result<voxlod_scene::Camera, Error> {
    let base = scene.default_camera()?;
    let (scene_lo, _) = scene.bounds()?;
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for (t, idx) in g.indices.iter().enumerate() {
        if flags[t] {
            for &i in idx {
                let p = g.positions[i as usize];
                lo = lo.min(p);
                hi = hi.max(p);
                if let voxlod_scene::Light::Directional { to_light, .. } = *light
                    && to_light.y > 0.05
                {
                    let q = p - to_light * ((p.y - scene_lo.y) / to_light.y);
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
        }
    }
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    Ok(voxlod_scene::Camera::framing(base.eye - base.target, centre, radius, 40.0))
}

/// Runs the shadow part (module docs).
pub fn run(
    config: &ShadowConfig,
    gpu: Option<&SlicemapRenderer>,
    progress: &dyn Fn(&str),
) -> Result<ShadowResult, Error> {
    let c = config;
    if !(0.0..=1.0).contains(&c.sigma) {
        return Err(Error::InvalidConfig {
            study: "slicemap",
            field: "shadows.sigma",
            value: c.sigma.to_string(),
            expected: "an attenuation per layer in [0, 1]",
        });
    }
    progress(&format!("slicemap shadows: {}", c.scene));
    let scene: Scene = crate::scenes::load(&c.scene)?;
    let g: Geometry = scene.geometry();
    let names: Vec<bool> =
        scene.materials.iter().map(|m| m.name.contains(c.transmissive.as_str())).collect();
    let mut flags: Vec<bool> = g.materials.iter().map(|&m| names[m as usize]).collect();
    if !flags.iter().any(|&f| f) {
        flags.iter_mut().for_each(|f| *f = true);
    }
    let transmissive = |t: usize| flags[t];
    let light = scene.light();
    let bvh = Bvh::new(&g)?;
    let camera = shadow_camera(&scene, &g, &flags, &light)?;
    let gbuffer: GBuffer = ground_truth::gbuffer(&scene, &g, &bvh, &camera, c.width, c.height)?;
    let points: Vec<Vec3> =
        gbuffer.texels.iter().filter(|t| t.triangle != u32::MAX).map(|t| t.position).collect();
    let (lo, hi) = scene.bounds()?;
    let extent = (hi - lo).length();
    let repeats = c.repeats.max(1);
    let render = |filter: &dyn LightFilter| {
        let o = ground_truth::Options {
            width: c.width,
            height: c.height,
            spp: c.spp,
            ambient: Vec3::splat(c.ambient),
            shadows: false,
            light_filter: Some(filter),
            ..Default::default()
        };
        Ok::<_, Error>(ground_truth::render(&scene, &g, &bvh, &camera, &o)?.image.to_srgb8())
    };
    let reference =
        RayTracedTransmittance::new(&g, &bvh, transmissive, &light, c.sigma, extent * 1e-5)?;
    let (exact, exact_ms) = time(repeats, || {
        Ok(points.iter().map(|&p| reference.transmittance(p)).collect::<Vec<f32>>())
    })?;
    progress("slicemap shadows: reference render");
    let reference_image = render(&reference)?;
    let mut rows = Vec::new();
    let mut images = vec![("ray traced".to_string(), reference_image.clone())];
    let same = compare(&reference_image, &reference_image)?;
    let crossings: Vec<(bool, u32)> = points.iter().map(|&p| reference.crossings(p)).collect();
    let mismatch = |other: &[(bool, u32)]| {
        let n = points.len().max(1) as f64;
        let opaque = crossings.iter().zip(other).filter(|(a, b)| a.0 != b.0).count();
        let count = crossings.iter().zip(other).filter(|(a, b)| !a.0 && !b.0 && a.1 != b.1).count();
        (opaque as f64 / n, count as f64 / n)
    };
    rows.push(ShadowRow {
        method: "ray traced (reference)".into(),
        map_size: None,
        slices: None,
        opaque_mismatch: None,
        count_mismatch: None,
        mean_abs_error: 0.0,
        rmse: 0.0,
        max_abs_error: 0.0,
        image: same,
        build_ms: None,
        gpu_build_ms: None,
        lookup_ms: exact_ms,
        memory_bytes: 0,
    });
    // A standard shadow map's answer: semi-transparent triangles opaque.
    let opaque = RayTracedTransmittance::new(&g, &bvh, transmissive, &light, 1.0, extent * 1e-5)?;
    let (binary, binary_ms) = time(repeats, || {
        Ok(points.iter().map(|&p| opaque.transmittance(p)).collect::<Vec<f32>>())
    })?;
    let binary_image = render(&opaque)?;
    let (mae, rmse, max) = errors(&binary, &exact);
    rows.push(ShadowRow {
        method: "opaque leaves (standard shadow map, exact)".into(),
        map_size: None,
        slices: None,
        opaque_mismatch: None,
        count_mismatch: None,
        mean_abs_error: mae,
        rmse,
        max_abs_error: max,
        image: compare(&binary_image, &reference_image)?,
        build_ms: None,
        gpu_build_ms: None,
        lookup_ms: binary_ms,
        memory_bytes: 0,
    });
    images.push(("opaque leaves".into(), binary_image));
    for (k, &(size, slices)) in c.maps.iter().enumerate() {
        progress(&format!("slicemap shadows: {size}² × {slices} slices"));
        // Bias: a few pixels of the light's map, in world units.
        let pixel = extent as f64 / size as f64;
        let options = ShadowOptions {
            size,
            slices,
            slicing: Slicing::Local,
            sigma: c.sigma,
            bias: c.bias_pixels * pixel,
            ..ShadowOptions::default()
        };
        let (map, build_ms) = time(repeats, || {
            Ok(TransmittanceShadowMap::build(&g, transmissive, &light, &options)?)
        })?;
        let gpu_build_ms = match gpu {
            Some(r) => Some(
                time(repeats, || {
                    Ok(TransmittanceShadowMap::build_with(
                        &g,
                        transmissive,
                        &light,
                        &options,
                        |g, cam, o| r.build(g, cam, o),
                    )?)
                })?
                .1,
            ),
            None => None,
        };
        let (approx, lookup_ms) = time(repeats, || {
            Ok(points.iter().map(|&p| map.transmittance(p)).collect::<Vec<f32>>())
        })?;
        let (mae, rmse, max) = errors(&approx, &exact);
        let looked: Vec<(bool, u32)> =
            points.iter().map(|&p| map.lookup(p.as_dvec3()).unwrap_or((false, 0))).collect();
        let (opaque_mismatch, count_mismatch) = mismatch(&looked);
        let image = render(&map)?;
        rows.push(ShadowRow {
            method: format!("slicemap {size}², {slices} slices, local"),
            map_size: Some(size),
            slices: Some(slices),
            opaque_mismatch: Some(opaque_mismatch),
            count_mismatch: Some(count_mismatch),
            mean_abs_error: mae,
            rmse,
            max_abs_error: max,
            image: compare(&image, &reference_image)?,
            build_ms: Some(build_ms),
            gpu_build_ms,
            lookup_ms,
            memory_bytes: map.memory_bytes(),
        });
        if k == 0 || k + 1 == c.maps.len() {
            images.push((format!("{size}, {slices} sl."), image.clone()));
            images.push((
                format!("err x10, {size}, {slices}"),
                error_heatmap(&image, &reference_image, 0.1)?,
            ));
        }
    }
    Ok(ShadowResult {
        scene: c.scene.clone(),
        transmissive: (flags.iter().filter(|&&f| f).count(), flags.len()),
        points: points.len(),
        rows,
        images,
    })
}
