//! Primary visibility with level of detail by distance: a scene whose far part covers many
//! voxels per pixel rendered by [`PrimaryRenderer`] (one pixel-wide cone per pixel, level of
//! detail by distance) at each LOD bias, against (a) the same renderer with bias 0 (always the
//! finest level) and (b) the ground-truth mesh render: image error (MSE, SSIM on 8-bit sRGB),
//! octree samples per pixel and time.
//!
//! Pipeline: conservative voxelization at [`LodConfig::resolution`] → Averages records (32 rays
//! per voxel) → octree → [`PrimaryRenderer::render`] with voxlod-cpu's `shade()` (the scene's
//! light, ambient 0.1 as the ground truth here, no specular: Averages carry none) → compared
//! with `ground_truth::render` ([`LodConfig::spp`] rays per pixel; a second seed estimates its
//! own error as half the MSE between the two).

use std::time::Instant;

use glam::{Vec3, Vec4};
use serde::Serialize;
use voxlod_cone::{
    PinholeCamera, PrimaryImage, PrimaryOptions, PrimaryRenderer, ShadeInput, SurfaceMedium,
};
use voxlod_cpu::appearance::averages;
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_cpu::shading::shade;
use voxlod_cpu::voxelize;
use voxlod_eval::report::{Cell, Column, ImageGrid, LabeledImage, NumberFormat, Table};
use voxlod_format::GridSpec;
use voxlod_octree::{AveragePayload, BuildOptions, Directional, Octree};
use voxlod_scene::{Image, MaterialSample, Srgb8Image};

use crate::Error;
use crate::ground_truths::{SeededTruth, seeded_truth};

/// What the LOD measurement renders.
#[derive(Clone, Debug, PartialEq)]
pub struct LodConfig {
    /// The scene spec.
    pub scene: String,
    /// Voxels along the longest axis of the scene's octree (a power of two in 4..=1024).
    pub resolution: u32,
    /// Image side, pixels (1..=2048).
    pub image_size: u32,
    /// LOD biases (footprint multipliers in [0, 64]; 0 = always the finest level, the reference
    /// march).
    pub biases: Vec<f32>,
    /// Step of the march as a fraction of the footprint diameter, in [0.05, 4].
    pub step: f32,
    /// Moves the scene's default camera away from its target by this factor (finite, > 0).
    pub zoom_out: f32,
    /// Rays per pixel of the ground-truth mesh render (≥ 1).
    pub spp: u32,
}

impl LodConfig {
    /// The forest at 256³, 128² pixels, biases 0, 0.5, 1, 2, 4, step 0.5, the default camera,
    /// ground truth at 64 rays per pixel.
    pub fn quick() -> Self {
        Self {
            scene: "builtin:forest".into(),
            resolution: 256,
            image_size: 128,
            biases: vec![0.0, 0.5, 1.0, 2.0, 4.0],
            step: 0.5,
            zoom_out: 1.0,
            spp: 64,
        }
    }

    /// Checks every field (named in the error).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "cone LOD", field, value, expected })
        };
        if !(self.resolution.is_power_of_two() && (4..=1024).contains(&self.resolution)) {
            return bad("resolution", self.resolution.to_string(), "a power of two in 4..=1024");
        }
        if !(1..=2048).contains(&self.image_size) {
            return bad("image_size", self.image_size.to_string(), "in 1..=2048");
        }
        if self.biases.is_empty() {
            return bad("biases", "[]".into(), "at least one value");
        }
        for &b in &self.biases {
            if !(b.is_finite() && (0.0..=64.0).contains(&b)) {
                return bad("biases", b.to_string(), "in [0, 64]");
            }
        }
        if !(0.05..=4.0).contains(&self.step) {
            return bad("step", self.step.to_string(), "a fraction of the footprint in [0.05, 4]");
        }
        if !(self.zoom_out.is_finite() && self.zoom_out > 0.0) {
            return bad("zoom_out", self.zoom_out.to_string(), "finite and > 0");
        }
        if self.spp == 0 {
            return bad("spp", "0".into(), "at least 1");
        }
        Ok(())
    }
}

/// Ambient term of both the voxel shading and the ground truth (as the experiments use).
const AMBIENT: f32 = 0.1;

/// One LOD bias measured.
#[derive(Clone, Debug, Serialize)]
pub struct LodRow {
    /// Opacity pre-filter: "isotropic" (coverage) or "directional" (six opacities of crossing).
    pub opacity: String,
    /// Footprint multiplier (0: always the finest level).
    pub bias: f32,
    /// MSE / SSIM against the ground-truth mesh render.
    pub mse_truth: f64,
    /// SSIM against the ground truth.
    pub ssim_truth: f64,
    /// MSE / SSIM against the finest-level march (bias 0).
    pub mse_finest: f64,
    /// SSIM against the finest-level march.
    pub ssim_finest: f64,
    /// Primary-cone octree samples per pixel.
    pub samples_per_pixel: f64,
    /// Shadow-cone octree samples per pixel.
    pub shadow_samples_per_pixel: f64,
    /// Render time, ms (CPU, rayon).
    pub ms: f64,
}

/// The pixel footprint at bias 1, in voxels, at the nearest and the farthest corner of the
/// scene's bounds.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FootprintRange {
    /// At the nearest corner.
    pub nearest_voxels: f32,
    /// At the farthest corner.
    pub farthest_voxels: f32,
}

/// Octree build times of the LOD scene (voxelization and records excluded).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct BuildTimes {
    /// The isotropic octree, ms.
    pub isotropic_ms: f64,
    /// The directional octree, ms.
    pub directional_ms: f64,
}

/// Everything the primary-visibility measurement measured.
#[derive(Clone, Debug, Serialize)]
pub struct LodResult {
    /// Scene spec.
    pub scene: String,
    /// Voxels along the longest axis.
    pub resolution: u32,
    /// Octree depth.
    pub depth: u32,
    /// Occupied voxels.
    pub voxels: u64,
    /// Image side, pixels.
    pub image_size: u32,
    /// Step as a fraction of the footprint.
    pub step: f32,
    /// Pixel footprint (bias 1) at the nearest and farthest corner of the scene's bounds.
    pub footprint: FootprintRange,
    /// Rays per pixel of the ground truth.
    pub truth_spp: u32,
    /// Ground-truth render time, ms.
    pub truth_ms: f64,
    /// MSE between two independent seeds (0 and 1) of the ground truth.
    pub truth_seed_mse: f64,
    /// The ground truth's own error, estimated as half of `truth_seed_mse`.
    pub truth_error_mse: f64,
    /// Octree build times.
    pub build: BuildTimes,
    /// One row per opacity pre-filter and bias.
    pub rows: Vec<LodRow>,
    /// The ground truth and each bias's image (for the report), labelled.
    #[serde(skip)]
    pub images: Vec<(String, Srgb8Image)>,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn to_srgb(img: &PrimaryImage) -> Srgb8Image {
    let mut out = Image::new(img.width, img.height, Vec4::ZERO);
    out.pixels.copy_from_slice(&img.pixels);
    out.to_srgb8()
}

/// Runs the measurement; `say` receives a short message at each stage.
pub fn run(config: &LodConfig, say: &dyn Fn(&str)) -> Result<LodResult, Error> {
    config.validate()?;
    let scene = crate::scenes::load(&config.scene)?;
    let geometry = scene.geometry();
    say(&format!("{}: BVH and ground truth", config.scene));
    let bvh = Bvh::new(&geometry)?;
    let mut camera = scene.default_camera()?;
    camera.eye = camera.target + (camera.eye - camera.target) * config.zoom_out;
    let size = config.image_size;
    let gt_options = ground_truth::Options {
        width: size,
        height: size,
        spp: config.spp,
        seed: 0,
        ambient: Vec3::splat(AMBIENT),
        shadows: true,
        light_filter: None,
    };
    let SeededTruth { srgb8: truth_img, ms: truth_ms, seed_mse: truth_seed_mse, .. } =
        seeded_truth(&scene, &geometry, &bvh, &camera, &gt_options)?;

    say(&format!("{}: voxelizing and building the octree at {}³", config.scene, config.resolution));
    let (lo, hi) = scene.bounds()?;
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), config.resolution)?;
    let vox = voxelize::voxelize(&geometry, &grid, &voxelize::Options::default())?;
    let ctx = SamplingContext::new(&scene, &geometry, &vox)?;
    let records = precompute(&ctx, &PrecomputeOptions { rays: 32, seed: 0 }, averages::fit)?;
    let t = Instant::now();
    let tree = Octree::from_brick_map(
        grid,
        &records.records,
        AveragePayload::from_record,
        &BuildOptions::default(),
    )?;
    let build_iso = ms(t);
    let t = Instant::now();
    let directional: Octree<Directional<AveragePayload>> = Octree::from_brick_map(
        grid,
        &records.records,
        |r| Directional::isotropic(AveragePayload::from_record(r)),
        &BuildOptions::default(),
    )?;
    let build = BuildTimes { isotropic_ms: build_iso, directional_ms: ms(t) };

    let pinhole = PinholeCamera {
        eye: camera.eye,
        target: camera.target,
        up: camera.up,
        fov_y_deg: camera.fov_y_deg,
        width: size,
        height: size,
    };
    let light = scene.light();
    let cone_light = crate::scenes::cone_light(light);
    let ambient = Vec3::splat(AMBIENT);
    let shader = |s: &ShadeInput| {
        let m =
            MaterialSample { albedo: s.albedo, alpha: 1.0, specular: Vec3::ZERO, shininess: 0.0 };
        shade(&m, s.normal, s.to_viewer, &light.sample(s.position), s.visibility, ambient)
    };
    let options = |bias: f32| PrimaryOptions {
        lod_bias: bias,
        step_factor: config.step,
        background: scene.background,
        ..PrimaryOptions::default()
    };
    let frame = Frame { camera: pinhole, light: cone_light, options: &options, shader: &shader };
    let px = (size as f64).powi(2);
    let mut rows = Vec::new();
    let mut images = vec![(format!("mesh, {} spp", config.spp), truth_img.clone())];
    for opacity in ["isotropic", "directional"] {
        say(&format!("{}: {opacity} LOD marches", config.scene));
        let measured = if opacity == "isotropic" {
            measure(&tree, &frame, &config.biases, &truth_img)?
        } else {
            measure(&directional, &frame, &config.biases, &truth_img)?
        };
        for (row, img) in measured {
            images.push((format!("{} {}", &opacity[..3], row.bias), img));
            rows.push(LodRow {
                opacity: opacity.into(),
                samples_per_pixel: row.samples_per_pixel / px,
                shadow_samples_per_pixel: row.shadow_samples_per_pixel / px,
                ..row
            });
        }
    }
    // The pixel footprint (bias 1) at the bounds' nearest and farthest corners.
    let unit = PrimaryRenderer::new(&tree, pinhole, cone_light, PrimaryOptions::default())?;
    let voxel = grid.voxel_size as f32;
    let corners = (0..8).map(|i| {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        unit.footprint_voxels(c.distance(camera.eye) / voxel)
    });
    let [nearest_voxels, farthest_voxels] =
        corners.fold([f32::INFINITY, 0.0f32], |[a, b], f| [a.min(f), b.max(f)]);
    Ok(LodResult {
        scene: config.scene.clone(),
        resolution: config.resolution,
        depth: tree.depth(),
        voxels: tree.voxel_count(),
        image_size: size,
        step: config.step,
        footprint: FootprintRange { nearest_voxels, farthest_voxels },
        truth_spp: config.spp,
        truth_ms,
        truth_seed_mse,
        truth_error_mse: truth_seed_mse / 2.0,
        build,
        rows,
        images,
    })
}

/// What every render of one measurement shares.
struct Frame<'a> {
    camera: PinholeCamera,
    light: voxlod_cone::Light,
    options: &'a dyn Fn(f32) -> PrimaryOptions,
    shader: &'a (dyn Fn(&ShadeInput) -> Vec3 + Sync),
}

/// Renders `tree` at bias 0 and at each bias, scored against the truth and the bias-0 image;
/// the rows' sample counts are totals (the caller divides by the pixels).
fn measure<M: SurfaceMedium>(
    tree: &Octree<M>,
    frame: &Frame,
    biases: &[f32],
    truth: &Srgb8Image,
) -> Result<Vec<(LodRow, Srgb8Image)>, Error> {
    let render = |bias: f32| -> Result<(PrimaryImage, f64), Error> {
        let r = PrimaryRenderer::new(tree, frame.camera, frame.light, (frame.options)(bias))?;
        let t = Instant::now();
        let img = r.render(frame.shader);
        Ok((img, ms(t)))
    };
    let (finest, finest_ms) = render(0.0)?;
    let finest_img = to_srgb(&finest);
    let mut out = Vec::new();
    for &bias in biases {
        let (img, t) = if bias == 0.0 { (finest.clone(), finest_ms) } else { render(bias)? };
        let srgb = to_srgb(&img);
        let a = voxlod_eval::compare(&srgb, truth)?;
        let b = voxlod_eval::compare(&srgb, &finest_img)?;
        let row = LodRow {
            opacity: String::new(),
            bias,
            mse_truth: a.mse,
            ssim_truth: a.ssim,
            mse_finest: b.mse,
            ssim_finest: b.ssim,
            samples_per_pixel: img.samples as f64,
            shadow_samples_per_pixel: img.shadow_samples as f64,
            ms: t,
        };
        out.push((row, srgb));
    }
    Ok(out)
}

impl LodResult {
    /// The table of the measurement.
    pub fn table(&self) -> Result<Table, Error> {
        let o = self;
        let num = |n: &str, f| Column::number(n, f);
        let mut t = Table::new(
            format!(
                "primary visibility with LOD by distance: {} at {}³, {}² pixels, step {}",
                o.scene, o.resolution, o.image_size, o.step
            ),
            vec![
                Column::text("opacity"),
                num("LOD bias", NumberFormat::Fixed(2)),
                num("MSE vs mesh", NumberFormat::Significant(3)),
                num("SSIM vs mesh", NumberFormat::Fixed(3)),
                num("MSE vs finest", NumberFormat::Significant(3)),
                num("SSIM vs finest", NumberFormat::Fixed(3)),
                num("samples/px", NumberFormat::Significant(3)),
                num("shadow samples/px", NumberFormat::Significant(3)),
                num("ms", NumberFormat::Significant(3)),
            ],
        );
        for r in &o.rows {
            let mut cells = vec![Cell::Text(r.opacity.clone())];
            cells.extend(
                [
                    r.bias as f64,
                    r.mse_truth,
                    r.ssim_truth,
                    r.mse_finest,
                    r.ssim_finest,
                    r.samples_per_pixel,
                    r.shadow_samples_per_pixel,
                    r.ms,
                ]
                .into_iter()
                .map(Cell::Number),
            );
            t.push_row(cells)?;
        }
        Ok(t)
    }

    /// The sentence that goes with the table.
    pub fn summary(&self) -> String {
        let o = self;
        format!(
            "{} voxelized at {}³ (depth {}, {} occupied voxels; octree build {:.0} ms isotropic, {:.0} ms directional), seen from its \
         default camera: the pixel footprint (bias 1) spans {:.2}–{:.2} voxels from the nearest \
         to the farthest corner of the scene's bounds. Bias 0 reads level 0 everywhere (the \
         finest-level march); bias b reads level log2(max(b·footprint, 1)). Ground truth: the \
         mesh at {} rays per pixel ({:.0} ms; its own error, half the MSE between two seeds: \
         {:.1e}). \
         Times are CPU times on a shared machine.",
            o.scene,
            o.resolution,
            o.depth,
            o.voxels,
            o.build.isotropic_ms,
            o.build.directional_ms,
            o.footprint.nearest_voxels,
            o.footprint.farthest_voxels,
            o.truth_spp,
            o.truth_ms,
            o.truth_error_mse
        )
    }

    /// The images side by side: the ground truth, then one per bias.
    pub fn image_grid(&self) -> ImageGrid {
        let o = self;
        let labelled = o
            .images
            .iter()
            .map(|(label, img)| LabeledImage::new(label.clone(), img.clone()))
            .collect();
        ImageGrid::new(o.images.len().min(6) as u32, labelled)
    }
}
