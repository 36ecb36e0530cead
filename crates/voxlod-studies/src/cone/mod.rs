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

mod images;
mod leak;
pub mod lod;
mod report;

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;
use voxlod_cone::{ConeMedium, ConeTracer, RadiancePayload, Shadows, TraceOptions, inject};
use voxlod_cpu::appearance::averages;
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth::{self, GBuffer};
use voxlod_cpu::render::indirect;
use voxlod_cpu::voxelize;
use voxlod_eval::npy::FloatArray;
use voxlod_eval::report::LabeledImage;
use voxlod_format::GridSpec;
use voxlod_gpu::cone::{ConeKernel, ConeQuery, GpuConeOctree, GpuMedium, ShadingPoint};
use voxlod_octree::{AveragePayload, BuildOptions, Directional, Octree};
use voxlod_scene::Srgb8Image;

use crate::Error;
use crate::backend::Backend;
use images::{Best, Traced, colour, gray, reference_outputs};
pub use leak::LeakRow;
use leak::leak_experiment;
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
