//! The primary-visibility part of `voxlod cone`: a scene whose far part covers many voxels per
//! pixel rendered by [`PrimaryRenderer`] (one pixel-wide cone per pixel, level of detail by
//! distance) at each `--lod-bias`, against (a) the same renderer with bias 0 (always the finest
//! level) and (b) the ground-truth mesh render: image error (MSE, SSIM on 8-bit sRGB), octree
//! samples per pixel and time.
//!
//! Pipeline: conservative voxelization at `--lod-res` → Averages records (32 rays per voxel) →
//! octree → [`PrimaryRenderer::render`] with voxlod-cpu's `shade()` (the scene's light, ambient
//! 0.1 as the ground truth here, no specular: Averages carry none) → compared with
//! `ground_truth::render` (`--lod-spp` rays per pixel; a second seed gives its own noise).

use std::time::Instant;

use anyhow::{Context, Result, ensure};
use glam::{Vec3, Vec4};
use serde::Serialize;
use voxlod::cpu::appearance::averages;
use voxlod::cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod::cpu::appearance::sampler::SamplingContext;
use voxlod::cpu::raycast::Bvh;
use voxlod::cpu::render::ground_truth;
use voxlod::cpu::shading::shade;
use voxlod::cpu::voxelize;
use voxlod::eval::report::{Cell, Column, ImageGrid, LabeledImage, NumberFormat, Table};
use voxlod::format::GridSpec;
use voxlod::scene::{Image, MaterialSample, Srgb8Image};
use voxlod_cone::{
    PinholeCamera, PrimaryImage, PrimaryOptions, PrimaryRenderer, ShadeInput, SurfaceMedium,
};
use voxlod_octree::{AveragePayload, BuildOptions, Directional, Octree};

use super::load_scene;
use crate::cli::ConeArgs;

/// Ambient term of both the voxel shading and the ground truth (as the experiments use).
const AMBIENT: f32 = 0.1;

/// One LOD bias measured.
#[derive(Clone, Debug, Serialize)]
pub struct PrimaryRow {
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

/// The outcome of the primary-visibility measurement.
#[derive(Clone, Debug, Serialize)]
pub struct PrimaryOutcome {
    /// Scene spec.
    pub scene: String,
    /// Voxels along the longest axis, octree depth, occupied voxels.
    pub res: u32,
    /// Octree depth.
    pub depth: u32,
    /// Occupied voxels.
    pub voxels: u64,
    /// Image side, pixels.
    pub size: u32,
    /// Step as a fraction of the footprint.
    pub step: f32,
    /// Pixel footprint (bias 1) at the nearest and farthest corner of the scene's bounds, voxels.
    pub footprint_range: [f32; 2],
    /// Ground truth: rays per pixel, render ms, and its own noise (MSE between seeds 0 and 1).
    pub truth_spp: u32,
    /// Ground-truth render time, ms.
    pub truth_ms: f64,
    /// Ground truth's own noise.
    pub truth_noise_mse: f64,
    /// Octree build ms, isotropic and directional (voxelization and records excluded).
    pub build_ms: [f64; 2],
    /// One row per bias.
    pub rows: Vec<PrimaryRow>,
    /// The ground truth and each bias's image (for the report), labelled.
    #[serde(skip)]
    pub images: Vec<(String, Srgb8Image)>,
}

/// Checks the `--lod-*` options (named in the errors).
pub fn check_args(args: &ConeArgs) -> Result<()> {
    ensure!(
        args.lod_res.is_power_of_two() && (4..=1024).contains(&args.lod_res),
        "--lod-res {}: a power of two in 4..=1024",
        args.lod_res
    );
    ensure!(
        (1..=2048).contains(&args.lod_size),
        "--lod-size {} is out of range 1..=2048",
        args.lod_size
    );
    ensure!(!args.lod_bias.is_empty(), "--lod-bias needs at least one value");
    for &b in &args.lod_bias {
        ensure!(b.is_finite() && (0.0..=64.0).contains(&b), "--lod-bias {b}: in [0, 64]");
    }
    ensure!(
        (0.05..=4.0).contains(&args.lod_step),
        "--lod-step {}: a fraction of the footprint in [0.05, 4]",
        args.lod_step
    );
    ensure!(
        args.lod_zoom_out.is_finite() && args.lod_zoom_out > 0.0,
        "--lod-zoom-out {}: finite and > 0",
        args.lod_zoom_out
    );
    ensure!(args.lod_spp > 0, "--lod-spp must be at least 1");
    Ok(())
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn to_srgb(img: &PrimaryImage) -> Srgb8Image {
    let mut out = Image::new(img.width, img.height, Vec4::ZERO);
    out.pixels.copy_from_slice(&img.pixels);
    out.to_srgb8()
}

/// Runs the measurement (`args.lod_scene` must not be "none").
pub fn run(args: &ConeArgs, say: &dyn Fn(&str)) -> Result<PrimaryOutcome> {
    check_args(args)?;
    let scene = load_scene(&args.lod_scene)?;
    let geometry = scene.geometry();
    say(&format!("{}: BVH and ground truth", args.lod_scene));
    let bvh = Bvh::new(&geometry)?;
    let mut camera = scene.default_camera()?;
    camera.eye = camera.target + (camera.eye - camera.target) * args.lod_zoom_out;
    let size = args.lod_size;
    let gt_options = |seed| ground_truth::Options {
        width: size,
        height: size,
        spp: args.lod_spp,
        seed,
        ambient: Vec3::splat(AMBIENT),
        shadows: true,
        light_filter: None,
    };
    let t = Instant::now();
    let truth = ground_truth::render(&scene, &geometry, &bvh, &camera, &gt_options(0))?;
    let truth_ms = ms(t);
    let truth_img = truth.image.to_srgb8();
    let noise = ground_truth::render(&scene, &geometry, &bvh, &camera, &gt_options(1))?;
    let truth_noise_mse = voxlod::eval::mse(&noise.image.to_srgb8(), &truth_img)?;

    say(&format!("{}: voxelizing and building the octree at {}³", args.lod_scene, args.lod_res));
    let (lo, hi) = scene.bounds()?;
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), args.lod_res)?;
    let vox = voxelize::voxelize(&geometry, &grid, &voxelize::Options::default())?;
    let ctx = SamplingContext::new(&scene, &geometry, &vox)?;
    let records = precompute(&ctx, &PrecomputeOptions { rays: 32, seed: 0 }, averages::fit)?;
    let t = Instant::now();
    let tree = Octree::from_brick_map(
        grid,
        &records.records,
        AveragePayload::from_record,
        &BuildOptions::default(),
    )
    .context("building the LOD scene's octree")?;
    let build_iso = ms(t);
    let t = Instant::now();
    let directional: Octree<Directional<AveragePayload>> = Octree::from_brick_map(
        grid,
        &records.records,
        |r| Directional::isotropic(AveragePayload::from_record(r)),
        &BuildOptions::default(),
    )
    .context("building the LOD scene's directional octree")?;
    let build_ms = [build_iso, ms(t)];

    let pinhole = PinholeCamera {
        eye: camera.eye,
        target: camera.target,
        up: camera.up,
        fov_y_deg: camera.fov_y_deg,
        width: size,
        height: size,
    };
    let light = scene.light();
    let cone_light = super::cone::cone_light(light);
    let ambient = Vec3::splat(AMBIENT);
    let shader = |s: &ShadeInput| {
        let m =
            MaterialSample { albedo: s.albedo, alpha: 1.0, specular: Vec3::ZERO, shininess: 0.0 };
        shade(&m, s.normal, s.to_viewer, &light.sample(s.position), s.visibility, ambient)
    };
    let options = |bias: f32| PrimaryOptions {
        lod_bias: bias,
        step_factor: args.lod_step,
        background: scene.background,
        ..PrimaryOptions::default()
    };
    let frame = Frame { camera: pinhole, light: cone_light, options: &options, shader: &shader };
    let px = (size as f64).powi(2);
    let mut rows = Vec::new();
    let mut images = vec![(format!("mesh, {} spp", args.lod_spp), truth_img.clone())];
    for opacity in ["isotropic", "directional"] {
        say(&format!("{}: {opacity} LOD marches", args.lod_scene));
        let measured = if opacity == "isotropic" {
            measure(&tree, &frame, &args.lod_bias, &truth_img)?
        } else {
            measure(&directional, &frame, &args.lod_bias, &truth_img)?
        };
        for (row, img) in measured {
            images.push((format!("{} {}", &opacity[..3], row.bias), img));
            rows.push(PrimaryRow {
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
    let footprint_range = corners.fold([f32::INFINITY, 0.0f32], |[a, b], f| [a.min(f), b.max(f)]);
    Ok(PrimaryOutcome {
        scene: args.lod_scene.clone(),
        res: args.lod_res,
        depth: tree.depth(),
        voxels: tree.voxel_count(),
        size,
        step: args.lod_step,
        footprint_range,
        truth_spp: args.lod_spp,
        truth_ms,
        truth_noise_mse,
        build_ms,
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
) -> Result<Vec<(PrimaryRow, Srgb8Image)>> {
    let render = |bias: f32| -> Result<(PrimaryImage, f64)> {
        let r = PrimaryRenderer::new(tree, frame.camera, frame.light, (frame.options)(bias))
            .with_context(|| format!("LOD bias {bias}"))?;
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
        let a = voxlod::eval::compare(&srgb, truth)?;
        let b = voxlod::eval::compare(&srgb, &finest_img)?;
        let row = PrimaryRow {
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

/// The table of the measurement.
pub fn table(o: &PrimaryOutcome) -> Result<Table> {
    let num = |n: &str, f| Column::number(n, f);
    let mut t = Table::new(
        format!(
            "primary visibility with LOD by distance: {} at {}³, {}² pixels, step {}",
            o.scene, o.res, o.size, o.step
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
pub fn summary(o: &PrimaryOutcome) -> String {
    format!(
        "{} voxelized at {}³ (depth {}, {} occupied voxels; octree build {:.0} ms isotropic, {:.0} ms directional), seen from its \
         default camera: the pixel footprint (bias 1) spans {:.2}–{:.2} voxels from the nearest \
         to the farthest corner of the scene's bounds. Bias 0 reads level 0 everywhere (the \
         finest-level march); bias b reads level log2(max(b·footprint, 1)). Ground truth: the \
         mesh at {} rays per pixel ({:.0} ms; its own noise, MSE between two seeds: {:.1e}). \
         Times are CPU times on a shared machine.",
        o.scene,
        o.res,
        o.depth,
        o.voxels,
        o.build_ms[0],
        o.build_ms[1],
        o.footprint_range[0],
        o.footprint_range[1],
        o.truth_spp,
        o.truth_ms,
        o.truth_noise_mse
    )
}

/// The images side by side: the ground truth, then one per bias.
pub fn image_grid(o: &PrimaryOutcome) -> ImageGrid {
    let labelled =
        o.images.iter().map(|(label, img)| LabeledImage::new(label.clone(), img.clone())).collect();
    ImageGrid::new(o.images.len().min(6) as u32, labelled)
}
