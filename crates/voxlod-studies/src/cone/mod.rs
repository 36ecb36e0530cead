//! Voxel cone tracing on the sparse voxel octree (Yalçıner and Sahillioğlu 2020, §4.5, after
//! Crassin et al. 2011), measured against ray-traced references on the
//! mesh: AO and one-bounce diffuse indirect light over cone count × aperture × octree depth ×
//! step, both opacity pre-filters; the light-leaking experiment (a wall of known thickness
//! between a lit floor and a receiver); and ([`lod`]) primary visibility with level of detail
//! by distance.
//!
//! Pipeline per resolution: conservative voxelization → Averages records (32 lines per voxel) →
//! octree ([`Octree::from_brick_map`], depth = log2 of the resolution) → light injection
//! (shadows marched in the octree) into an isotropic and a directional radiance octree → per
//! option set and octree, AO and `albedo · E/π` from the pixel-centre G-buffer → MSE and SSIM
//! against the references (`voxlod_cpu::render::indirect`, [`ConeConfig::spp`] rays, seed 0;
//! a second seed estimates the references' own error: half the MSE between the two seeds).
//!
//! On [`Backend::Gpu`] the sweep's cones are traced by voxlod-gpu's cone kernel (the same AO
//! and `E/π` per pixel as the CPU's `ConeTracer::ao_and_diffuse`, checked by the equivalence
//! suite); its trace times are the kernel's (upload of the shading points, dispatches,
//! readback), on lavapipe CPU times of the GPU path. The G-buffer, the references, the octrees,
//! the leak experiment and the LOD part stay on the CPU.

pub mod lod;

use std::time::Instant;

use glam::{UVec3, Vec3, Vec4};
use rayon::prelude::*;
use serde::Serialize;
use voxlod_cone::{ConeMedium, ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
use voxlod_cpu::appearance::averages;
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth::{self, GBuffer};
use voxlod_cpu::render::indirect;
use voxlod_cpu::voxelize;
use voxlod_eval::error_heatmap;
use voxlod_eval::npy::FloatArray;
use voxlod_eval::report::{
    Cell, Column, ImageGrid, LabeledImage, NumberFormat, Plot, Report, Series, Table,
};
use voxlod_format::GridSpec;
use voxlod_gpu::cone::{ConeKernel, ConeQuery, GpuConeOctree, GpuMedium, ShadingPoint};
use voxlod_octree::{AveragePayload, BuildOptions, Directional, Octree};
use voxlod_scene::{Image, Srgb8Image};

use crate::Error;
use crate::backend::Backend;
pub use lod::{LodConfig, LodResult, LodRow};

/// What the cone study measures. [`ConeConfig::quick`] is `voxlod cone builtin:cornell` with its
/// defaults; [`ConeConfig::full`] raises the references to 1024 rays per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct ConeConfig {
    /// The scene spec ([`crate::scenes::load`]); it must occlude itself (a convex scene is
    /// refused: no cone meets anything there).
    pub scene: String,
    /// Voxels along the longest axis (powers of two in 4..=1024; octree depth = log2).
    pub resolutions: Vec<u32>,
    /// Diffuse cone counts (1..=1024).
    pub cones: Vec<u32>,
    /// Full cone apertures, degrees, in [0, 180).
    pub apertures_deg: Vec<f32>,
    /// Step lengths as fractions of the cone diameter, in [0.05, 4].
    pub steps: Vec<f32>,
    /// Image side, pixels (1..=2048).
    pub image_size: u32,
    /// Rays per pixel of the ray-traced references (≥ 1).
    pub spp: u32,
    /// AO radius as a fraction of the scene's bounding-box diagonal (finite, > 0).
    pub ao_radius: f32,
    /// Primary visibility with level of detail by distance (None: not measured).
    pub lod: Option<LodConfig>,
}

impl ConeConfig {
    /// `voxlod cone builtin:cornell` with its defaults: 32³ and 64³, 1/6/16 cones of 15/30/60°,
    /// steps 0.5 and 1, 64² pixels, references at 256 rays per pixel, AO radius 0.1, and the LOD
    /// part on the forest ([`LodConfig::quick`]).
    pub fn quick() -> Self {
        Self {
            scene: "builtin:cornell".into(),
            resolutions: vec![32, 64],
            cones: vec![1, 6, 16],
            apertures_deg: vec![15.0, 30.0, 60.0],
            steps: vec![0.5, 1.0],
            image_size: 64,
            spp: 256,
            ao_radius: 0.1,
            lod: Some(LodConfig::quick()),
        }
    }

    /// [`ConeConfig::quick`] with references at 1024 rays per pixel.
    pub fn full() -> Self {
        Self { spp: 1024, ..Self::quick() }
    }

    /// Checks every field (named in the error).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "cone", field, value, expected })
        };
        if self.resolutions.is_empty() {
            return bad("resolutions", "[]".into(), "at least one resolution");
        }
        for &r in &self.resolutions {
            if !(r.is_power_of_two() && (4..=1024).contains(&r)) {
                return bad("resolutions", r.to_string(), "a power of two in 4..=1024");
            }
        }
        if !(1..=2048).contains(&self.image_size) {
            return bad("image_size", self.image_size.to_string(), "in 1..=2048");
        }
        if self.spp == 0 {
            return bad("spp", "0".into(), "at least 1");
        }
        if !(self.ao_radius.is_finite() && self.ao_radius > 0.0) {
            return bad("ao_radius", self.ao_radius.to_string(), "finite and > 0");
        }
        if self.cones.is_empty() || self.apertures_deg.is_empty() || self.steps.is_empty() {
            return bad("cones/apertures_deg/steps", "[]".into(), "at least one value each");
        }
        for &a in &self.apertures_deg {
            if !(0.0..180.0).contains(&a) {
                return bad("apertures_deg", a.to_string(), "a full angle in [0, 180) degrees");
            }
        }
        for &s in &self.steps {
            if !(0.05..=4.0).contains(&s) {
                return bad("steps", s.to_string(), "a fraction of the diameter in [0.05, 4]");
            }
        }
        for &c in &self.cones {
            if !(1..=1024).contains(&c) {
                return bad("cones", c.to_string(), "in 1..=1024");
            }
        }
        match &self.lod {
            Some(lod) => lod.validate(),
            None => Ok(()),
        }
    }
}

/// One measured option set.
#[derive(Clone, Debug, Serialize)]
pub struct ConeRow {
    /// Voxels along the longest axis.
    pub resolution: u32,
    /// Opacity pre-filter: "isotropic" (mean of the children) or "directional" (six
    /// opacities composited along the axes).
    pub opacity: String,
    /// Octree depth.
    pub depth: u32,
    /// Diffuse cones.
    pub cones: u32,
    /// Full aperture, degrees.
    pub aperture_deg: f32,
    /// Step as a fraction of the diameter.
    pub step: f32,
    /// AO: MSE and SSIM against the ray-traced AO (8-bit sRGB).
    pub ao_mse: f64,
    /// AO SSIM.
    pub ao_ssim: f64,
    /// Indirect light: MSE against the one-bounce path tracer.
    pub indirect_mse: f64,
    /// Indirect SSIM.
    pub indirect_ssim: f64,
    /// Cone tracing time for AO + indirect of the whole image, ms (CPU).
    pub trace_ms: f64,
    /// Octree samples per pixel.
    pub steps_per_pixel: f64,
}

/// One light-leaking measurement.
#[derive(Clone, Debug, Serialize)]
pub struct LeakRow {
    /// Octree depth (grid of 2^depth voxels over the unit cube).
    pub depth: u32,
    /// Wall thickness in voxels (1/32 of the scene).
    pub wall_voxels: u32,
    /// "isotropic" or "directional".
    pub option: String,
    /// Step fraction.
    pub step: f32,
    /// Receiver's `E/π` with the wall divided by without it (truth: 0).
    pub leak: f64,
}

/// One octree of the sweep (per resolution).
#[derive(Clone, Debug, Serialize)]
pub struct OctreeRow {
    /// Voxels along the longest axis.
    pub resolution: u32,
    /// Occupied voxels (leaves).
    pub voxels: u64,
    /// Bytes of the isotropic radiance octree per occupied voxel (nodes, links, payloads).
    pub bytes_per_voxel: f64,
    /// Build time of the geometry octree from the brick map, ms.
    pub build_ms: f64,
    /// Light injection time (isotropic radiance octree, shadows marched), ms.
    pub inject_ms: f64,
}

/// A pair of figures for the two references: ambient occlusion and indirect light.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct AoIndirect {
    /// For the AO reference.
    pub ao: f64,
    /// For the indirect-light reference.
    pub indirect: f64,
}

/// Everything the cone study measured.
#[derive(Debug, Serialize)]
pub struct ConeResult {
    /// Scene spec.
    pub scene: String,
    /// Where the sweep's cones were traced: `cpu (rayon)` or `gpu: <adapter>`.
    pub backend: String,
    /// MSE between two independent seeds (0 and 1) of each reference (8-bit sRGB).
    pub reference_seed_mse: AoIndirect,
    /// Each reference's own error against the converged truth, estimated as half of
    /// [`ConeResult::reference_seed_mse`] (independent seeds: the MSE between two estimates is
    /// the sum of their variances). Errors below it are not resolved.
    pub reference_error_mse: AoIndirect,
    /// Reference render times, ms (CPU).
    pub reference_ms: AoIndirect,
    /// One octree per resolution.
    pub octrees: Vec<OctreeRow>,
    /// Measured option sets.
    pub rows: Vec<ConeRow>,
    /// Light leaking.
    pub leaks: Vec<LeakRow>,
    /// Primary visibility with level of detail by distance (None when not configured).
    pub lod: Option<LodResult>,
    /// The sweep's rows with the lowest AO and indirect MSE (resolution, opacity, cones ×
    /// aperture, step), whose images the report shows.
    pub best_rows: BestRows,
    /// The references and the best rows' images, for the report (not serialized).
    #[serde(skip)]
    pub images: Vec<LabeledImage>,
    /// The same in linear float (AO, and `albedo · E/π` as RGB), written as `.npy` by the
    /// report (not serialized).
    #[serde(skip)]
    pub arrays: Vec<FloatArray>,
}

/// Which rows of the sweep scored best, by label.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BestRows {
    /// Lowest AO MSE.
    pub ao: Option<String>,
    /// Lowest indirect MSE.
    pub indirect: Option<String>,
}

/// One cone-traced image of the sweep, per pixel: AO, and `E/π` (before the albedo).
struct Traced {
    ao: Vec<f32>,
    irradiance: Vec<Vec3>,
}

/// The best row of the sweep for one target so far: its MSE, label and image.
struct Best {
    mse: f64,
    label: String,
    traced: Traced,
}

impl Best {
    fn keep(best: &mut Option<Best>, mse: f64, label: impl Fn() -> String, traced: &Traced) {
        if best.as_ref().is_none_or(|b| mse < b.mse) {
            let traced = Traced { ao: traced.ao.clone(), irradiance: traced.irradiance.clone() };
            *best = Some(Best { mse, label: label(), traced });
        }
    }
}

fn gray(gb: &GBuffer, v: &[f32]) -> Srgb8Image {
    let mut img = Image::new(gb.width, gb.height, Vec4::ZERO);
    for (p, &a) in img.pixels.iter_mut().zip(v) {
        *p = Vec3::splat(a).extend(1.0);
    }
    img.to_srgb8()
}

fn colour(gb: &GBuffer, e: &[Vec3]) -> Srgb8Image {
    let mut img = Image::new(gb.width, gb.height, Vec4::ZERO);
    for ((p, &e), t) in img.pixels.iter_mut().zip(e).zip(&gb.texels) {
        *p = (t.albedo * e).extend(1.0);
    }
    img.to_srgb8()
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Runs the study: the sweep (its cones traced on `backend`), the leak experiment and the LOD
/// part. `say` receives a short message at each stage.
pub fn run(
    config: &ConeConfig,
    backend: Backend<'_>,
    say: &dyn Fn(&str),
) -> Result<ConeResult, Error> {
    config.validate()?;
    let kernel = match backend {
        Backend::Cpu => None,
        Backend::Gpu(ctx) => Some(ConeKernel::new(ctx)),
    };
    let backend_name = backend.describe();
    let args = config;
    let scene = crate::scenes::load(&args.scene)?;
    let geometry = scene.geometry();
    let bvh = Bvh::new(&geometry)?;
    let camera = scene.default_camera()?;
    let (lo, hi) = scene.bounds()?;
    let radius = args.ao_radius * (hi - lo).length();
    let size = args.image_size;
    let gb = ground_truth::gbuffer(&scene, &geometry, &bvh, &camera, size, size)?;
    let hits = gb.texels.iter().filter(|t| t.triangle != u32::MAX).count();
    say("ray-traced references");
    let opts = |seed| indirect::Options { spp: args.spp, seed, ao_radius: radius };
    let t = Instant::now();
    let ao_ref = indirect::ambient_occlusion(&scene, &geometry, &bvh, &gb, &opts(0))?;
    let ao_ms = ms(t);
    let t = Instant::now();
    let ind_ref = indirect::indirect_diffuse(&scene, &geometry, &bvh, &gb, &opts(0))?;
    let ind_ms = ms(t);
    let (ao_ref_img, ind_ref_img) = (gray(&gb, &ao_ref), colour(&gb, &ind_ref));
    let ao_1 = indirect::ambient_occlusion(&scene, &geometry, &bvh, &gb, &opts(1))?;
    let ind_1 = indirect::indirect_diffuse(&scene, &geometry, &bvh, &gb, &opts(1))?;
    let noise = AoIndirect {
        ao: voxlod_eval::mse(&gray(&gb, &ao_1), &ao_ref_img)?,
        indirect: voxlod_eval::mse(&colour(&gb, &ind_1), &ind_ref_img)?,
    };
    let light = crate::scenes::cone_light(scene.light());
    let mut rows = Vec::new();
    let mut octrees = Vec::new();
    let (mut best_ao, mut best_indirect) = (None, None);
    for &res in &args.resolutions {
        say(&format!("voxelizing and building the octree at {res}³"));
        let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res)?;
        let vox = voxelize::voxelize(&geometry, &grid, &voxelize::Options::default())?;
        let ctx = SamplingContext::new(&scene, &geometry, &vox)?;
        let records = precompute(&ctx, &PrecomputeOptions { rays: 32, seed: 0 }, averages::fit)?;
        let t = Instant::now();
        let options = BuildOptions { depth: None, dense_log2: 4 };
        let tree =
            Octree::from_brick_map(grid, &records.records, AveragePayload::from_record, &options)?;
        let build_ms = ms(t);
        let t = Instant::now();
        let radiance: Octree<RadiancePayload> = inject(&tree, &light, &Shadows::MARCH)?;
        let inject_ms = ms(t);
        let directional: Octree<Directional<RadiancePayload>> =
            inject(&tree, &light, &Shadows::MARCH)?;
        let stats = radiance.memory_stats();
        octrees.push(OctreeRow {
            resolution: res,
            voxels: tree.voxel_count(),
            bytes_per_voxel: stats.per_voxel(stats.total_bytes()),
            build_ms,
            inject_ms,
        });
        let refs = References { gb: &gb, hits, ao: &ao_ref_img, indirect: &ind_ref_img };
        let uploaded = match &kernel {
            Some(k) => Some((k, k.upload(&radiance)?, k.upload(&directional)?)),
            None => None,
        };
        for &cones in &args.cones {
            for &aperture in &args.apertures_deg {
                for &step in &args.steps {
                    say(&format!("{res}³: {cones} cones, {aperture}°, step {step}"));
                    let o = TraceOptions {
                        diffuse_cones: cones,
                        diffuse_aperture_deg: aperture,
                        step_factor: step,
                        ao_radius: radius,
                        ..TraceOptions::default()
                    };
                    for opacity in OPACITIES {
                        let on = |directional| {
                            uploaded
                                .as_ref()
                                .map(|(k, iso, dir)| (*k, if directional { dir } else { iso }))
                        };
                        let (row, traced) = if opacity == "isotropic" {
                            measure(&args.scene, &radiance, on(false), o, &refs)?
                        } else {
                            measure(&args.scene, &directional, on(true), o, &refs)?
                        };
                        let label =
                            || format!("{res}³ {opacity}, {cones} × {aperture}°, step {step}");
                        Best::keep(&mut best_ao, row.ao_mse, label, &traced);
                        Best::keep(&mut best_indirect, row.indirect_mse, label, &traced);
                        rows.push(ConeRow { resolution: res, opacity: opacity.into(), ..row });
                    }
                }
            }
        }
    }
    say("light leaking");
    let leaks = leak_experiment(&[5, 6, 7], &args.steps)?;
    let lod = args.lod.as_ref().map(|l| lod::run(l, say)).transpose()?;
    let best_rows = BestRows {
        ao: best_ao.as_ref().map(|b: &Best| b.label.clone()),
        indirect: best_indirect.as_ref().map(|b: &Best| b.label.clone()),
    };
    let (images, arrays) = reference_outputs(&gb, &ao_ref, &ind_ref, best_ao, best_indirect)?;
    Ok(ConeResult {
        scene: args.scene.clone(),
        backend: backend_name,
        reference_seed_mse: noise,
        reference_error_mse: AoIndirect { ao: noise.ao / 2.0, indirect: noise.indirect / 2.0 },
        reference_ms: AoIndirect { ao: ao_ms, indirect: ind_ms },
        octrees,
        rows,
        leaks,
        lod,
        best_rows,
        images,
        arrays,
    })
}

/// The references, the best AO row's and the best indirect row's images with their per-pixel
/// error heat maps (8-bit sRGB), and the same in linear float: AO as `[height, width]`,
/// `albedo · E/π` as `[height, width, 3]`.
fn reference_outputs(
    gb: &GBuffer,
    ao_ref: &[f32],
    ind_ref: &[Vec3],
    best_ao: Option<Best>,
    best_indirect: Option<Best>,
) -> Result<(Vec<LabeledImage>, Vec<FloatArray>), Error> {
    let (w, h) = (gb.width as usize, gb.height as usize);
    let outgoing = |e: &[Vec3]| -> Vec<f32> {
        e.iter().zip(&gb.texels).flat_map(|(e, t)| (t.albedo * *e).to_array()).collect()
    };
    let gray_array = |name: &str, v: &[f32]| FloatArray {
        name: name.into(),
        shape: vec![h, w],
        data: v.to_vec(),
    };
    let rgb_array = |name: &str, e: &[Vec3]| FloatArray {
        name: name.into(),
        shape: vec![h, w, 3],
        data: outgoing(e),
    };
    let (ao_img, ind_img) = (gray(gb, ao_ref), colour(gb, ind_ref));
    // Labels stay short (they are drawn inside images as small as 16 px); the caption names
    // the rows.
    let mut images = vec![LabeledImage::new("AO ref", ao_img.clone())];
    let mut arrays = vec![gray_array("ao_reference", ao_ref)];
    if let Some(b) = best_ao {
        let img = gray(gb, &b.traced.ao);
        images.push(LabeledImage::new("AO best", img.clone()));
        images.push(LabeledImage::new("AO err", error_heatmap(&img, &ao_img, 0.25)?));
        arrays.push(gray_array("ao_best", &b.traced.ao));
    }
    images.push(LabeledImage::new("ind ref", ind_img.clone()));
    arrays.push(rgb_array("indirect_reference", ind_ref));
    if let Some(b) = best_indirect {
        let img = colour(gb, &b.traced.irradiance);
        images.push(LabeledImage::new("ind best", img.clone()));
        images.push(LabeledImage::new("ind err", error_heatmap(&img, &ind_img, 0.25)?));
        arrays.push(rgb_array("indirect_best", &b.traced.irradiance));
    }
    Ok((images, arrays))
}

/// The two opacity pre-filters measured: the mean of the eight children (one opacity) and six
/// directional opacities composited front to back along each axis.
const OPACITIES: [&str; 2] = ["isotropic", "directional"];

/// The references one option set is scored against.
struct References<'a> {
    gb: &'a GBuffer,
    hits: usize,
    ao: &'a Srgb8Image,
    indirect: &'a Srgb8Image,
}

/// AO and `albedo · E/π` by cone tracing `radiance` with `o` from every pixel of the
/// G-buffer — on the CPU, or with the GPU kernel on `gpu`'s upload of the same octree —
/// scored against the references (the row's resolution and opacity are the caller's).
fn measure<M: ConeMedium + GpuMedium + Sync>(
    scene: &str,
    radiance: &Octree<M>,
    gpu: Option<(&ConeKernel, &GpuConeOctree)>,
    o: TraceOptions,
    refs: &References,
) -> Result<(ConeRow, Traced), Error> {
    let (cones, aperture, step) = (o.diffuse_cones, o.diffuse_aperture_deg, o.step_factor);
    let gb = refs.gb;
    let tracer = ConeTracer::new(radiance, o)?;
    let t = Instant::now();
    let out: Vec<(f32, Vec3, u32)> = match gpu {
        None => gb
            .texels
            .par_iter()
            .map(|x| {
                if x.triangle == u32::MAX {
                    (1.0, Vec3::ZERO, 0)
                } else {
                    tracer.ao_and_diffuse(x.position, x.normal, true, true)
                }
            })
            .collect(),
        Some((kernel, tree)) => {
            // Misses get no cones (AO 1, no light), as above; no specular cone is traced.
            let points = ShadingPoint::from_gbuffer(gb, Vec3::ZERO, 0.0);
            let query = ConeQuery { ambient_occlusion: true, diffuse: true, specular: false };
            kernel
                .trace(tree, &o, query, &points, gb.width)?
                .iter()
                .map(|s| (s.ao, s.diffuse, s.diffuse_steps))
                .collect()
        }
    };
    let trace_ms = ms(t);
    let ao: Vec<f32> = out.iter().map(|o| o.0).collect();
    let e: Vec<Vec3> = out.iter().map(|o| o.1).collect();
    let steps: u64 = out.iter().map(|o| o.2 as u64).sum();
    // Geometry in view but not one octree sample: every cone left the octree's cube at its
    // apex. That happens when no surface sees another (a convex scene such as builtin:cube,
    // whose visible faces lie on the grid's boundary): the references are then exactly AO 1
    // and no indirect light, the cones agree with them trivially, and a row of MSE 0 / SSIM 1
    // would report a measurement that was never made.
    if refs.hits > 0 && steps == 0 {
        return Err(Error::NothingToMeasure {
            scene: scene.into(),
            why: format!(
                "no cone took an octree sample ({cones} cones, {aperture}°, step {step}) \
                 although {} pixels see geometry: no surface in view sees another (a convex \
                 scene: AO 1 and no indirect light everywhere); use a scene with occlusion, \
                 e.g. builtin:cornell",
                refs.hits
            ),
        });
    }
    let ma = voxlod_eval::compare(&gray(gb, &ao), refs.ao)?;
    let mi = voxlod_eval::compare(&colour(gb, &e), refs.indirect)?;
    let row = ConeRow {
        resolution: 0,
        opacity: String::new(),
        depth: radiance.depth(),
        cones,
        aperture_deg: aperture,
        step,
        ao_mse: ma.mse,
        ao_ssim: ma.ssim,
        indirect_mse: mi.mse,
        indirect_ssim: mi.ssim,
        trace_ms,
        steps_per_pixel: steps as f64 / gb.texels.len() as f64,
    };
    Ok((row, Traced { ao, irradiance: e }))
}

/// The wall scene over the unit cube at `2^depth` voxels: a floor (y = 0 layer) on `x < ½`,
/// lit from straight above, and a wall `x ∈ [½, ½ + 1/32)` across the whole cube (if `wall`);
/// its faces are vertical, so unlit. The receiver at `(¾, ¼, ½)` faces −x: it sees only the
/// wall's unlit face (truth 0), or the lit floor without the wall.
fn wall_scene(depth: u32, wall: bool) -> Result<Octree<AveragePayload>, Error> {
    let n = 1u32 << depth;
    let grid = GridSpec::new(glam::DVec3::ZERO, 1.0 / n as f64, UVec3::splat(n))?;
    let thick = (n / 32).max(1);
    let mut v = Vec::new();
    for x in 0..n / 2 {
        for z in 0..n {
            v.push((UVec3::new(x, 0, z), AveragePayload::new(Vec3::ONE, Vec3::Y, 1.0)));
        }
    }
    if wall {
        for x in n / 2..n / 2 + thick {
            let normal = if x == n / 2 { Vec3::NEG_X } else { Vec3::X };
            for y in 0..n {
                for z in 0..n {
                    v.push((UVec3::new(x, y, z), AveragePayload::new(Vec3::ONE, normal, 1.0)));
                }
            }
        }
    }
    Ok(Octree::build(grid, v, &BuildOptions { depth: Some(depth), dense_log2: 4.min(depth) })?)
}

fn leak_experiment(depths: &[u32], steps: &[f32]) -> Result<Vec<LeakRow>, Error> {
    let light =
        Light::Directional { to_light: Vec3::Y, irradiance: Vec3::splat(std::f32::consts::PI) };
    let p = Vec3::new(0.75, 0.25, 0.5);
    let mut rows = Vec::new();
    for &depth in depths {
        let with = wall_scene(depth, true)?;
        let without = wall_scene(depth, false)?;
        for &step in steps {
            let o = TraceOptions { step_factor: step, ..TraceOptions::default() };
            let e = |t: &Octree<AveragePayload>, directional: bool| -> Result<f64, Error> {
                Ok(if directional {
                    let r: Octree<Directional<RadiancePayload>> =
                        inject(t, &light, &Shadows::None)?;
                    ConeTracer::new(&r, o)?.diffuse(p, Vec3::NEG_X).x as f64
                } else {
                    let r: Octree<RadiancePayload> = inject(t, &light, &Shadows::None)?;
                    ConeTracer::new(&r, o)?.diffuse(p, Vec3::NEG_X).x as f64
                })
            };
            for (name, directional) in [("isotropic", false), ("directional", true)] {
                let open = e(&without, directional)?;
                let leak = if open > 0.0 { e(&with, directional)? / open } else { f64::NAN };
                rows.push(LeakRow {
                    depth,
                    wall_voxels: ((1u32 << depth) / 32).max(1),
                    option: name.into(),
                    step,
                    leak,
                });
            }
        }
    }
    Ok(rows)
}

impl ConeResult {
    /// The sweep's table, the leak table and (with the LOD part) its table.
    pub fn tables(&self) -> Result<Vec<Table>, Error> {
        let o = self;
        let num = |n: &str, f| Column::number(n, f);
        let mut t = Table::new(
            "cone tracing vs ray-traced references",
            vec![
                num("res", NumberFormat::Integer),
                num("depth", NumberFormat::Integer),
                Column::text("opacity"),
                num("cones", NumberFormat::Integer),
                num("aperture°", NumberFormat::Fixed(0)),
                num("step", NumberFormat::Fixed(2)),
                num("AO MSE", NumberFormat::Significant(3)),
                num("AO SSIM", NumberFormat::Fixed(3)),
                num("indirect MSE", NumberFormat::Significant(3)),
                num("indirect SSIM", NumberFormat::Fixed(3)),
                num("trace ms", NumberFormat::Significant(3)),
                num("samples/px", NumberFormat::Significant(3)),
            ],
        );
        for r in &o.rows {
            let mut cells: Vec<Cell> =
                [r.resolution as f64, r.depth as f64].into_iter().map(Cell::Number).collect();
            cells.push(Cell::Text(r.opacity.clone()));
            cells.extend(
                [
                    r.cones as f64,
                    r.aperture_deg as f64,
                    r.step as f64,
                    r.ao_mse,
                    r.ao_ssim,
                    r.indirect_mse,
                    r.indirect_ssim,
                    r.trace_ms,
                    r.steps_per_pixel,
                ]
                .into_iter()
                .map(Cell::Number),
            );
            t.push_row(cells)?;
        }
        let mut l = Table::new(
            "light leaking through a wall 1/32 of the scene thick (truth 0)",
            vec![
                num("depth", NumberFormat::Integer),
                num("wall voxels", NumberFormat::Integer),
                Column::text("opacity"),
                num("step", NumberFormat::Fixed(2)),
                num("leaked fraction", NumberFormat::Significant(3)),
            ],
        );
        for r in &o.leaks {
            l.push_row(vec![
                Cell::Number(r.depth as f64),
                Cell::Number(r.wall_voxels as f64),
                Cell::Text(r.option.clone()),
                Cell::Number(r.step as f64),
                Cell::Number(r.leak),
            ])?;
        }
        let mut out = vec![t, l];
        if let Some(p) = &o.lod {
            out.push(p.table()?);
        }
        Ok(out)
    }

    /// Appends the cone-tracing section (heading, references, tables, error-vs-time plots).
    pub fn add_to_report(&self, r: &mut Report) -> Result<(), Error> {
        let o = self;
        r.heading(2, format!("Voxel cone tracing: {}", o.scene));
        r.text(format!(
        "References: ray-traced AO and one-bounce path-traced diffuse indirect light on the mesh \
         ({:.0} ms and {:.0} ms, CPU). Their own error against the converged truth, estimated \
         as half the MSE between two independent seeds: AO {:.2e}, indirect {:.2e}; errors \
         below these are not resolved. Octrees (res, voxels, bytes/voxel, \
         build ms, injection ms): {}. Cones traced on {}. Times are wall-clock times on a \
         shared machine (on a CPU adapter such as lavapipe, CPU times of the GPU path).",
        o.reference_ms.ao,
        o.reference_ms.indirect,
        o.reference_error_mse.ao,
        o.reference_error_mse.indirect,
        o.octrees
            .iter()
            .map(|t| format!(
                "{}³: {} voxels, {:.1} B, {:.0} ms, {:.0} ms",
                t.resolution, t.voxels, t.bytes_per_voxel, t.build_ms, t.inject_ms
            ))
            .collect::<Vec<_>>()
            .join("; "),
        o.backend
    ));
        for t in o.tables()? {
            r.table(t);
        }
        if !o.images.is_empty() {
            r.images(
                "cone_references",
                format!(
                    "the ray-traced references, the sweep's best AO row ({}) and best indirect \
                     row ({}), and their per-pixel errors (heat maps: full scale 0.25)",
                    o.best_rows.ao.as_deref().unwrap_or("none"),
                    o.best_rows.indirect.as_deref().unwrap_or("none")
                ),
                ImageGrid::new(3, o.images.clone()),
            );
            r.data(
                "cone_reference_data",
                "the same images in linear float: AO [height, width]; albedo · E/π [height, \
                 width, 3]",
                o.arrays.clone(),
            );
        }
        if let Some(p) = &o.lod {
            r.text(p.summary());
            r.images(
                "cone_lod_images",
                format!("{}: the mesh and the LOD march at each bias", p.scene),
                p.image_grid(),
            );
        }
        let mut keys: Vec<(u32, u32, &str)> = o
            .rows
            .iter()
            .map(|x| (x.resolution, x.aperture_deg as u32, x.opacity.as_str()))
            .collect();
        keys.sort();
        keys.dedup();
        let series = |metric: fn(&ConeRow) -> f64| -> Vec<Series> {
            keys.iter()
                .map(|&(res, ap, opacity)| {
                    let pts = o
                        .rows
                        .iter()
                        .filter(|x| {
                            x.resolution == res
                                && x.aperture_deg as u32 == ap
                                && x.opacity == opacity
                        })
                        .map(|x| (x.trace_ms, metric(x)))
                        .collect();
                    Series::new(format!("{res}³, {ap}°, {opacity}"), pts)
                })
                .collect()
        };
        for (name, title, y_label, metric) in [
            (
                "cone_ao_error_vs_time",
                "AO error vs cone tracing time",
                "AO MSE (8-bit sRGB)",
                (|x: &ConeRow| x.ao_mse) as fn(&ConeRow) -> f64,
            ),
            (
                "cone_indirect_error_vs_time",
                "indirect light error vs cone tracing time",
                "indirect MSE (8-bit sRGB)",
                |x: &ConeRow| x.indirect_mse,
            ),
        ] {
            r.plot(
                name,
                Plot {
                    title: title.into(),
                    x_label: "trace time (ms, CPU)".into(),
                    y_label: y_label.into(),
                    log_x: true,
                    log_y: true,
                    series: series(metric),
                    ..Plot::default()
                },
            );
        }
        Ok(())
    }
}
