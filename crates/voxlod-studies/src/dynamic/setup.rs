//! A dynamic scene made ready for the study: split into static meshes and moving objects, the
//! world grid over everything the animation reaches, every object's cache built once, the
//! static voxels; and the cone-tracing helpers every part shares (octree → injected light →
//! AO and `E/π` at G-buffer points, as images).

use std::time::Instant;

use glam::{DVec3, Vec3, Vec4};
use rayon::prelude::*;
use voxlod_cone::{ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
use voxlod_cpu::dynamic::{CacheOptions, DynamicScene, build_cache, static_voxels};
use voxlod_cpu::render::ground_truth::GBuffer;
use voxlod_format::GridSpec;
use voxlod_octree::dynamic::{DynamicWorld, VoxelCache};
use voxlod_octree::{AveragePayload, Octree};
use voxlod_scene::{Image, Scene, Srgb8Image};

use crate::Error;

/// Animation times sampled to bound the moving objects (per animation, including its ends).
const BOUND_SAMPLES: u32 = 16;

/// A dynamic scene ready to measure.
pub struct Prepared {
    /// The split scene.
    pub ds: DynamicScene,
    /// The world grid: the scene's bounds over the sampled poses, plus a voxel of margin.
    pub grid: GridSpec,
    /// One cache per moving object (same order as `ds.objects`).
    pub caches: Vec<VoxelCache>,
    /// Milliseconds to build each cache.
    pub cache_ms: Vec<f64>,
    /// The world with its static voxels.
    pub world: DynamicWorld,
    /// The world without static voxels (occupancy of the moving objects alone).
    pub moving_only: DynamicWorld,
}

/// The bounds of `ds` over `BOUND_SAMPLES` poses of its animation.
pub fn swept_bounds(ds: &DynamicScene) -> Result<(DVec3, DVec3), Error> {
    let d = ds.animation.duration();
    let (mut lo, mut hi) = ds.scene.bounds()?;
    for k in 0..=BOUND_SAMPLES {
        let pose = ds.pose(d * k as f32 / BOUND_SAMPLES as f32)?;
        let (l, h) = ds.posed_scene(&pose)?.bounds()?;
        lo = lo.min(l);
        hi = hi.max(h);
    }
    Ok((lo.as_dvec3(), hi.as_dvec3()))
}

/// Splits `scene` by its first animation, fits a grid of `voxel_size` over everything it
/// reaches and builds the caches and static voxels with `options`.
pub fn prepare(scene: Scene, voxel_size: f64, options: &CacheOptions) -> Result<Prepared, Error> {
    let spec = scene.name.clone();
    if scene.animations.is_empty() {
        return Err(Error::NothingToMeasure {
            scene: spec,
            why: "the scene has no animation".into(),
        });
    }
    let ds = DynamicScene::new(scene, 0)?;
    if ds.objects.is_empty() {
        return Err(Error::NothingToMeasure {
            scene: spec,
            why: "its animation moves no mesh".into(),
        });
    }
    let (lo, hi) = swept_bounds(&ds)?;
    let margin = DVec3::splat(voxel_size);
    let (lo, hi) = (lo - margin, hi + margin);
    let dims = ((hi - lo) / voxel_size).ceil().max(DVec3::ONE).as_uvec3();
    let grid = GridSpec::new(lo, voxel_size, dims)?;
    let mut caches = Vec::with_capacity(ds.objects.len());
    let mut cache_ms = Vec::with_capacity(ds.objects.len());
    for o in 0..ds.objects.len() {
        let t = Instant::now();
        caches.push(build_cache(&ds, o, voxel_size, options)?);
        cache_ms.push(ms(t));
    }
    let world = DynamicWorld::new(grid, static_voxels(&ds, &grid, options)?)?;
    let moving_only = DynamicWorld::new(grid, [])?;
    Ok(Prepared { ds, grid, caches, cache_ms, world, moving_only })
}

/// Milliseconds since `t`.
pub fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The scene's light in voxlod-cone's terms.
pub fn cone_light(l: voxlod_scene::Light) -> Light {
    match l {
        voxlod_scene::Light::Directional { to_light, irradiance } => {
            Light::Directional { to_light, irradiance }
        }
        voxlod_scene::Light::Point { position, intensity } => Light::Point { position, intensity },
    }
}

/// AO per pixel and `E/π` per pixel, cone traced through `radiance` at the G-buffer's points
/// (misses: AO 1, no light).
pub fn trace_gbuffer(
    radiance: &Octree<RadiancePayload>,
    gb: &GBuffer,
    options: TraceOptions,
) -> Result<(Vec<f32>, Vec<Vec3>), Error> {
    let tracer = ConeTracer::new(radiance, options)?;
    Ok(gb
        .texels
        .par_iter()
        .map(|t| {
            if t.triangle == u32::MAX {
                return (1.0, Vec3::ZERO);
            }
            let (ao, e, _) = tracer.ao_and_diffuse(t.position, t.normal, true, true);
            (ao, e)
        })
        .unzip())
}

/// Light injected into `geometry` (shadows marched) and traced at `gb`'s points.
pub fn inject_and_trace(
    geometry: &Octree<AveragePayload>,
    light: &Light,
    gb: &GBuffer,
    options: TraceOptions,
) -> Result<(Vec<f32>, Vec<Vec3>), Error> {
    let radiance: Octree<RadiancePayload> = inject(geometry, light, &Shadows::MARCH)?;
    trace_gbuffer(&radiance, gb, options)
}

/// AO values as a grey 8-bit sRGB image.
pub fn gray(gb: &GBuffer, v: &[f32]) -> Srgb8Image {
    let mut img = Image::new(gb.width, gb.height, Vec4::ZERO);
    for (p, &a) in img.pixels.iter_mut().zip(v) {
        *p = Vec3::splat(a).extend(1.0);
    }
    img.to_srgb8()
}

/// Indirect light `albedo · E/π` as an 8-bit sRGB image.
pub fn colour(gb: &GBuffer, e: &[Vec3]) -> Srgb8Image {
    let mut img = Image::new(gb.width, gb.height, Vec4::ZERO);
    for ((p, &e), t) in img.pixels.iter_mut().zip(e).zip(&gb.texels) {
        *p = (t.albedo * e).extend(1.0);
    }
    img.to_srgb8()
}
