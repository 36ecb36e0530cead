//! The filtered-appearance comparison of one scene (Brito, Poulin and Teichrieb 2023, Tables 1
//! and 2, regenerated): at each voxel resolution, every representation is precomputed from the same
//! per-voxel ray samples, rendered from the same cameras as the ground truth at an image size
//! equal to the voxel resolution and at a higher one, and scored against the ground truth.
//!
//! Rows: Averages, \[VJK21\] (SGGX + non-exponential transmittance), the virtual mesh with the
//! opacity subgrid (line-sampled directional opacity, and the paper's normalized circles as a
//! second row), and Adaptive at each threshold of [`FilteredConfig::thresholds`].

use std::time::{Duration, Instant};

use voxlod_cpu::appearance::AuthorsChoices;
use voxlod_cpu::appearance::adaptive::contribution::ContributionOptions;
use voxlod_cpu::appearance::adaptive::{self, AdaptiveOptions, Selector};
use voxlod_cpu::appearance::averages::AveragesGrid;
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::precompute;
use voxlod_cpu::appearance::subgrid::DirectionalRule;
use voxlod_cpu::appearance::virtual_mesh::{VirtualMeshGrid, VirtualMeshParams};
use voxlod_cpu::appearance::{Appearance, averages, sggx, virtual_mesh};
use voxlod_cpu::render::filtered::{self, FrameCache, PixelPattern, VjkChord};
use voxlod_cpu::voxelize::{self, Mode};
use voxlod_eval::report::{Cell, Column, LabeledImage, NumberFormat, Plot, Series, Table};
use voxlod_eval::{compare, error_heatmap};
use voxlod_format::GridSpec;
use voxlod_gpu::filtered::{FilteredKernel, GpuRecords};
use voxlod_scene::{Camera, Geometry, Scene, Srgb8Image};

use crate::Error;
use crate::backend::SceneGpu;
use crate::ground_truths::GroundTruths;
use crate::spread::{Spread, ms};

/// Settings of the filtered-appearance comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct FilteredConfig {
    /// Voxels along each scene's longest axis; each resolution is rendered at an image side
    /// equal to it (as the paper does) and at [`FilteredConfig::higher_image`].
    pub resolutions: Vec<u32>,
    /// A second, higher image side rendered at every resolution (None: only the paper's).
    pub higher_image: Option<u32>,
    /// Sampling rays per voxel (the paper's 150).
    pub rays: u32,
    /// Held-out rays per voxel for the Adaptive selector's error estimate.
    pub heldout: u32,
    /// Adaptive thresholds of the held-out directional error, one report row each.
    pub thresholds: Vec<f32>,
    /// Adaptive thresholds of the image-error selector ([`adaptive::Selector::Image`]), one
    /// report row each (none by default).
    pub image_thresholds: Vec<f32>,
    /// Voxels whose measured image contribution ranks the two selectors' errors
    /// ([`adaptive::contribution`]) at every resolution, at the image side equal to it
    /// (0: no check).
    pub contribution_samples: usize,
    /// Directional-opacity rule and shading samples of Adaptive's virtual-mesh candidate.
    pub adaptive_vmesh: VirtualMeshParams,
    /// Where the pipeline follows the authors' code instead of ours, and the seeds of the
    /// sampling lines and pixel pattern (default: ours, seeds 0). A choice the GPU kernel has
    /// no code for renders its rows on the CPU, and the row's backend says so.
    pub choices: AuthorsChoices,
}

impl FilteredConfig {
    /// The default run's settings.
    pub fn quick() -> Self {
        Self {
            resolutions: vec![64],
            higher_image: Some(128),
            rays: 150,
            heldout: adaptive::DEFAULT_HELDOUT,
            thresholds: vec![0.1, 0.2, 0.3],
            image_thresholds: Vec::new(),
            contribution_samples: 0,
            adaptive_vmesh: VirtualMeshParams::default(),
            choices: AuthorsChoices::default(),
        }
    }

    /// The paper's scale: 128³ and 256³.
    pub fn full() -> Self {
        Self { resolutions: vec![128, 256], higher_image: Some(512), ..Self::quick() }
    }

    /// Checks every field (named in the error).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "filtered appearance", field, value, expected })
        };
        if self.resolutions.is_empty() {
            return bad("resolutions", "[]".into(), "at least one resolution");
        }
        for &r in &self.resolutions {
            if !(2..=2048).contains(&r) {
                return bad("resolutions", r.to_string(), "in 2..=2048");
            }
        }
        if let Some(h) = self.higher_image.filter(|h| !(1..=4096).contains(h)) {
            return bad("higher_image", h.to_string(), "an image side in 1..=4096");
        }
        if self.rays == 0 {
            return bad("rays", "0".into(), "at least 1 sampling ray per voxel");
        }
        if self.heldout == 0 {
            return bad("heldout", "0".into(), "at least 1 held-out ray per voxel");
        }
        for &t in &self.thresholds {
            if !(t.is_finite() && t >= 0.0) {
                return bad("thresholds", t.to_string(), "finite and >= 0");
            }
        }
        for &t in &self.image_thresholds {
            if !(t.is_finite() && t >= 0.0) {
                return bad("image_thresholds", t.to_string(), "finite and >= 0");
            }
        }
        Ok(())
    }
}

/// One representation at one resolution and image size.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MethodRow {
    /// Representation (and its parameter).
    pub method: String,
    /// Voxels along the longest axis.
    pub resolution: u32,
    /// Image side in pixels.
    pub image: u32,
    /// Voxels with a record.
    pub voxels: usize,
    /// Bytes of the records per voxel (record, specular side record, type tag).
    pub record_bytes: f64,
    /// Heap bytes of the whole grid (brick map, lookup, records) per voxel.
    pub bytes_per_voxel: f64,
    /// Heap bytes of the whole grid.
    pub memory_bytes: usize,
    /// Precompute time (sampling + fit), ms.
    pub precompute_ms: f64,
    /// Mean render time per frame over the views with a fresh per-voxel cache, ms.
    pub render_cold_ms: f64,
    /// Mean render time of the same frame again, cache warm, ms.
    pub render_warm_ms: f64,
    /// MSE against the ground truth, over views.
    pub mse: Spread,
    /// SSIM against the ground truth, over views.
    pub ssim: Spread,
    /// For Adaptive: the share of voxels of each kind (Averages, \[VJK21\], virtual mesh); in
    /// JSON an object `{"averages", "vjk21", "virtual_mesh"}`.
    #[serde(serialize_with = "ser_mix")]
    pub mix: Option<[f64; 3]>,
    /// What rendered the row: `cpu` or the GPU adapter's short name. None (and left out of
    /// the JSON) in an all-CPU run, whose output is unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub backend: Option<String>,
    /// What precomputed the row's records: the GPU adapter's short name for Averages (whose
    /// precompute has a GPU kernel for every scene, textured and alpha-tested materials
    /// included), else `cpu`. None (and left out of the JSON) in an all-CPU run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub precompute_backend: Option<String>,
}

/// What the comparison of one scene produced.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct FilteredResult {
    /// One row per method, resolution and image size.
    pub rows: Vec<MethodRow>,
    /// Resolutions skipped for the time budget.
    pub skipped: Vec<u32>,
    /// Per resolution, the Adaptive selectors' errors ranked against the measured per-voxel
    /// image contribution (with [`FilteredConfig::contribution_samples`] > 0).
    pub predictor: Vec<PredictorCheck>,
    /// Per resolution: view 0 at the image side equal to the resolution — the ground truth,
    /// then each method and its error heat map (the paper's Fig. 11).
    #[serde(skip)]
    pub images: Vec<(u32, Vec<LabeledImage>)>,
}

/// The Adaptive selectors' errors against the measured per-voxel image contribution at one
/// resolution ([`adaptive::contribution::measure`]: the virtual mesh everywhere, one voxel
/// switched to Averages).
#[derive(Clone, Debug, serde::Serialize)]
pub struct PredictorCheck {
    /// Voxels along the longest axis (and image side).
    pub resolution: u32,
    /// Voxels measured.
    pub samples: usize,
    /// How many of them changed the image when switched.
    pub changed: usize,
    /// Spearman rank correlation of the held-out error's prediction with the measured benefit.
    pub heldout_spearman: f64,
    /// The same for the image error.
    pub image_spearman: f64,
    /// Over the voxels that changed the image only: held-out.
    pub heldout_spearman_changed: f64,
    /// Over the voxels that changed the image only: image error.
    pub image_spearman_changed: f64,
}

/// A precomputed representation, ready to render.
struct Built {
    method: String,
    grid: Box<dyn Appearance>,
    /// The same records uploaded for the GPU kernel (every representation on the GPU
    /// backend): rendered there instead of from `grid`.
    gpu: Option<GpuRecords>,
    record_bytes: f64,
    memory_bytes: usize,
    precompute: Duration,
    /// The GPU adapter that precomputed the records (None: the CPU).
    precompute_gpu: Option<String>,
    mix: Option<[f64; 3]>,
    /// Why a GPU run renders this row on the CPU (a choice of [`AuthorsChoices`] the kernel
    /// has no code for).
    cpu_reason: Option<String>,
}

/// The records `upload` puts on the GPU, unless `refused` (a render option the kernel does not
/// follow) or the upload itself names a choice the kernel has no code for
/// ([`voxlod_gpu::Error::Unsupported`]): then none, and the reason the row renders on the CPU.
fn upload_or_cpu(
    gpu: Option<&SceneGpu<'_>>,
    refused: Option<&'static str>,
    upload: impl FnOnce(&FilteredKernel<'_>) -> Result<GpuRecords, voxlod_gpu::Error>,
) -> Result<(Option<GpuRecords>, Option<String>), Error> {
    let Some(k) = gpu else { return Ok((None, None)) };
    if let Some(what) = refused {
        return Ok((None, Some(what.to_string())));
    }
    match upload(&k.kernels.filtered) {
        Ok(records) => Ok((Some(records), None)),
        Err(voxlod_gpu::Error::Unsupported { what }) => Ok((None, Some(what.to_string()))),
        Err(e) => Err(e.into()),
    }
}

/// The render option of `choices` the GPU kernel does not follow for a row, if any:
/// `vjk` says whether the row has \[VJK21\] voxels (the chord matters only for them).
fn gpu_refusal(choices: &AuthorsChoices, vjk: bool) -> Option<&'static str> {
    if choices.pattern != PixelPattern::Fixed {
        Some("a jittered pixel pattern")
    } else if vjk && choices.vjk_chord != VjkChord::PerRay {
        Some("a cached [VJK21] chord")
    } else {
        None
    }
}

/// Everything a scene section shares.
pub(super) struct SceneInputs<'a> {
    pub scene: &'a Scene,
    pub geometry: &'a Geometry,
    pub views: &'a [Camera],
    pub ambient: glam::Vec3,
    pub label: &'a str,
}

/// Runs the comparison of one scene; `over_budget` says when to skip the remaining
/// resolutions.
pub(super) fn run(
    inputs: &SceneInputs<'_>,
    config: &FilteredConfig,
    gt: &mut GroundTruths<'_>,
    gpu: Option<&SceneGpu<'_>>,
    over_budget: &dyn Fn() -> bool,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<FilteredResult, Error> {
    let mut result = FilteredResult::default();
    let (lo, hi) = inputs.scene.bounds()?;
    let label = inputs.label;
    for &res in &config.resolutions {
        if over_budget() {
            result.skipped.push(res);
            continue;
        }
        progress(&format!("{label}: filtered {res}³: voxelizing"));
        let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res)?;
        let options = voxelize::Options { mode: Mode::Conservative, ..Default::default() };
        let vox = voxelize::voxelize(inputs.geometry, &grid, &options)?;
        let ctx = SamplingContext::new(inputs.scene, inputs.geometry, &vox)?;
        let (built, candidates) =
            build_all(&ctx, inputs, config, gpu, &|m| progress(&format!("{label}: {res}³: {m}")))?;
        drop(ctx);
        drop(vox);

        let mut sizes = vec![res];
        if let Some(h) = config.higher_image.filter(|&h| h != res) {
            sizes.push(h);
        }
        for &size in &sizes {
            let references = gt.get(size, progress)?.to_vec();
            let mut figure = vec![LabeledImage::new("ground truth", references[0].clone())];
            let mut heat_maps = vec![LabeledImage::new("reference", references[0].clone())];
            for b in &built {
                progress(&format!("{label}: {res}³ {}: rendering {size}²", b.method));
                let (row, first) =
                    render_row(inputs, &config.choices, b, gpu, res, size, &references)?;
                if size == res {
                    let heat = error_heatmap(&first, &references[0], 0.25)?;
                    figure.push(LabeledImage::new(b.method.clone(), first));
                    heat_maps.push(LabeledImage::new(format!("|error| {}", b.method), heat));
                }
                result.rows.push(row);
            }
            if size == res {
                figure.append(&mut heat_maps);
                result.images.push((res, figure));
            }
            if size == res && config.contribution_samples > 0 {
                progress(&format!("{label}: {res}³ Adaptive: measured voxel contributions"));
                let options = ContributionOptions {
                    samples: config.contribution_samples,
                    render: render_options(inputs, &config.choices, size),
                    ..Default::default()
                };
                let light = inputs.scene.light();
                let background = inputs.scene.background;
                let c = adaptive::contribution::measure(
                    &candidates,
                    inputs.views,
                    &light,
                    background,
                    &references,
                    &options,
                )?;
                result.predictor.push(PredictorCheck {
                    resolution: res,
                    samples: c.voxels.len(),
                    changed: c.changed,
                    heldout_spearman: c.heldout_spearman,
                    image_spearman: c.image_spearman,
                    heldout_spearman_changed: c.heldout_spearman_changed,
                    image_spearman_changed: c.image_spearman_changed,
                });
            }
        }
    }
    Ok(result)
}

/// Precomputes every representation from the same samples (each timed on its own: its
/// precompute time is sampling plus its fit); with `gpu`, precomputes Averages on the adapter
/// (`voxlod_gpu::precompute`, the same lines as the CPU's, every material kind: textured,
/// alpha-masked and alpha-blended included; the row names it) and uploads the records that
/// have a GPU kernel (untimed). There is no CPU path behind it: what the kernel cannot serve
/// (a device limit) is an error.
fn build_all(
    ctx: &SamplingContext<'_>,
    inputs: &SceneInputs<'_>,
    config: &FilteredConfig,
    gpu: Option<&SceneGpu<'_>>,
    progress: &dyn Fn(&str),
) -> Result<(Vec<Built>, adaptive::Candidates), Error> {
    let geometry = inputs.geometry;
    let choices = &config.choices;
    let opts = choices.precompute(config.rays);
    let mut built = Vec::new();

    progress("Averages");
    let t = Instant::now();
    let (g, precompute_gpu) = match gpu {
        Some(k) => {
            let run = k.kernels.precompute.run(
                ctx.scene(),
                geometry,
                ctx.voxelization(),
                &opts,
                voxlod_gpu::precompute::Outputs::default(),
            );
            (run?.averages, Some(k.kernels.name.clone()))
        }
        None => (precompute(ctx, &opts, averages::fit)?, None),
    };
    let precompute_time = t.elapsed();
    let g = AveragesGrid { grid: g, normal: choices.averages_normal };
    let (gpu_records, cpu_reason) =
        upload_or_cpu(gpu, gpu_refusal(choices, false), |k| k.upload_averages_grid(&g))?;
    built.push(Built {
        method: "Averages".into(),
        record_bytes: g.grid.record_bytes() as f64,
        memory_bytes: g.grid.memory_bytes(),
        precompute: precompute_time,
        precompute_gpu,
        gpu: gpu_records,
        grid: Box::new(g),
        mix: None,
        cpu_reason,
    });

    progress("[VJK21]");
    let t = Instant::now();
    let g = precompute(ctx, &opts, sggx::fit)?;
    let precompute_time = t.elapsed();
    let (gpu_records, cpu_reason) =
        upload_or_cpu(gpu, gpu_refusal(choices, true), |k| k.upload_vjk21(&g))?;
    built.push(Built {
        method: "[VJK21]".into(),
        record_bytes: g.record_bytes() as f64,
        memory_bytes: g.memory_bytes(),
        precompute: precompute_time,
        precompute_gpu: None,
        gpu: gpu_records,
        grid: Box::new(g),
        mix: None,
        cpu_reason,
    });

    progress("virtual mesh");
    let t = Instant::now();
    let g = precompute(ctx, &opts, virtual_mesh::fit)?;
    let precompute_vm = t.elapsed();
    let mut rows = vec![
        (DirectionalRule::Lines, false, "virtual mesh (lines)"),
        (DirectionalRule::Circles, false, "virtual mesh (circles)"),
        (DirectionalRule::Lines, true, "virtual mesh (lines × area)"),
    ];
    if choices.opacity_rule == DirectionalRule::Authors {
        rows.push((DirectionalRule::Authors, false, "virtual mesh (authors' opacity)"));
    }
    for (rule, projected_area, name) in rows {
        let base = VirtualMeshParams { rule, projected_area, ..Default::default() };
        let grid = VirtualMeshGrid::with_params(g.clone(), choices.virtual_mesh_shading(base));
        let (gpu_records, cpu_reason) =
            upload_or_cpu(gpu, gpu_refusal(choices, false), |k| k.upload_virtual_mesh(&grid))?;
        built.push(Built {
            method: name.into(),
            record_bytes: g.record_bytes() as f64,
            memory_bytes: g.memory_bytes(),
            precompute: precompute_vm,
            precompute_gpu: None,
            gpu: gpu_records,
            grid: Box::new(grid),
            mix: None,
            cpu_reason,
        });
    }

    progress("Adaptive: candidates and held-out errors");
    let t = Instant::now();
    let options = AdaptiveOptions {
        rays: config.rays,
        heldout: config.heldout,
        ambient: inputs.ambient,
        seed: choices.precompute_seed,
        vmesh: choices.virtual_mesh_shading(config.adaptive_vmesh),
        ..Default::default()
    };
    let candidates = adaptive::Candidates::build(ctx, &options)?;
    let candidates_time = t.elapsed();
    let selections = (config.thresholds.iter().map(|&t| (Selector::HeldOut, t)))
        .chain(config.image_thresholds.iter().map(|&t| (Selector::Image, t)));
    for (selector, threshold) in selections {
        let t = Instant::now();
        let g = candidates.select_with(selector, threshold)?;
        let (gpu_records, cpu_reason) =
            upload_or_cpu(gpu, gpu_refusal(choices, true), |k| k.upload_adaptive(&g))?;
        built.push(Built {
            method: match selector {
                Selector::HeldOut => format!("Adaptive τ={threshold}"),
                Selector::Image => format!("Adaptive (image) τ={threshold}"),
            },
            record_bytes: g.record_bytes(),
            memory_bytes: g.memory_bytes(),
            precompute: candidates_time + t.elapsed(),
            precompute_gpu: None,
            mix: Some(g.mix()),
            gpu: gpu_records,
            grid: Box::new(g),
            cpu_reason,
        });
    }
    Ok((built, candidates))
}

/// The filtered renderer's options for the study's frames at `size`², with the render
/// choices of `choices`.
fn render_options(
    inputs: &SceneInputs<'_>,
    choices: &AuthorsChoices,
    size: u32,
) -> filtered::Options {
    let plain = filtered::Options {
        width: size,
        height: size,
        ambient: inputs.ambient,
        shadows: true,
        ..Default::default()
    };
    choices.render(plain)
}

/// Renders one representation from every view at `size`², cold then warm, and scores it
/// (on the GPU when its records were uploaded: no cache there, the same frame twice).
/// Returns the row and the view-0 image.
fn render_row(
    inputs: &SceneInputs<'_>,
    choices: &AuthorsChoices,
    b: &Built,
    gpu: Option<&SceneGpu<'_>>,
    res: u32,
    size: u32,
    references: &[Srgb8Image],
) -> Result<(MethodRow, Srgb8Image), Error> {
    // The GPU kernel renders the plain options (a render choice it has no code for sent the
    // row to the CPU already).
    let plain = render_options(inputs, &AuthorsChoices::default(), size);
    let options = render_options(inputs, choices, size);
    let light = inputs.scene.light();
    let (mut cold, mut warm) = (Duration::ZERO, Duration::ZERO);
    let mut metrics = Vec::new();
    let mut first = None;
    let background = inputs.scene.background;
    for (camera, reference) in inputs.views.iter().zip(references) {
        let image = match (gpu, &b.gpu) {
            (Some(k), Some(records)) => {
                // Uploaded rows are those whose images do not depend on the render choices
                // (`gpu_refusal`): the kernel renders them with the defaults.
                let kernel = &k.kernels.filtered;
                let t = Instant::now();
                let image = kernel.render(records, camera, &light, background, &plain)?;
                cold += t.elapsed();
                let t = Instant::now();
                drop(kernel.render(records, camera, &light, background, &plain)?);
                warm += t.elapsed();
                image
            }
            _ => {
                // The cache's voxel look-up is built per grid, not per frame; "cold" is the
                // first frame with every per-voxel slot empty.
                let mut cache = FrameCache::new(b.grid.as_ref())?;
                let t = Instant::now();
                let image = filtered::render(&mut cache, camera, &light, background, &options)?;
                cold += t.elapsed();
                let t = Instant::now();
                let again = filtered::render(&mut cache, camera, &light, background, &options)?;
                warm += t.elapsed();
                drop(again);
                image
            }
        };
        let image = image.to_srgb8();
        metrics.push(compare(&image, reference)?);
        first.get_or_insert(image);
    }
    let n = inputs.views.len().max(1) as f64;
    let voxels = b.grid.len();
    let row = MethodRow {
        method: b.method.clone(),
        resolution: res,
        image: size,
        voxels,
        record_bytes: b.record_bytes,
        bytes_per_voxel: b.memory_bytes as f64 / voxels.max(1) as f64,
        memory_bytes: b.memory_bytes,
        precompute_ms: ms(b.precompute),
        render_cold_ms: ms(cold) / n,
        render_warm_ms: ms(warm) / n,
        mse: Spread::of(&metrics.iter().map(|m| m.mse).collect::<Vec<_>>()),
        ssim: Spread::of(&metrics.iter().map(|m| m.ssim).collect::<Vec<_>>()),
        mix: b.mix,
        backend: gpu.map(|k| match (&b.gpu, &b.cpu_reason) {
            (Some(_), _) => k.kernels.name.clone(),
            (None, Some(why)) => format!("cpu (no GPU kernel for {why})"),
            (None, None) => "cpu".into(),
        }),
        precompute_backend: gpu.map(|_| b.precompute_gpu.clone().unwrap_or_else(|| "cpu".into())),
    };
    Ok((row, first.expect("at least one view")))
}

impl FilteredResult {
    /// Plots of SSIM against memory and against render time (warm cache), one series per
    /// method over the resolutions, at the image side equal to the resolution.
    pub fn plots(&self, label: &str) -> Vec<(String, Plot)> {
        let mut methods: Vec<&str> = Vec::new();
        for r in &self.rows {
            if !methods.contains(&r.method.as_str()) {
                methods.push(&r.method);
            }
        }
        let series = |f: &dyn Fn(&MethodRow) -> (f64, f64)| -> Vec<Series> {
            methods
                .iter()
                .map(|m| {
                    let points = self
                        .rows
                        .iter()
                        .filter(|r| r.method == *m && r.image == r.resolution)
                        .map(f)
                        .collect();
                    Series::new(*m, points)
                })
                .collect()
        };
        vec![
            (
                format!("{label}-ssim-vs-memory"),
                Plot {
                    title: format!("{label}: SSIM against memory (image side = resolution)"),
                    x_label: "memory (bytes)".into(),
                    y_label: "SSIM (mean over views)".into(),
                    log_x: true,
                    series: series(&|r| (r.memory_bytes as f64, r.ssim.mean)),
                    ..Default::default()
                },
            ),
            (
                format!("{label}-ssim-vs-render-time"),
                Plot {
                    title: format!("{label}: SSIM against render time (warm cache)"),
                    x_label: "render time per frame (ms)".into(),
                    y_label: "SSIM (mean over views)".into(),
                    log_x: true,
                    series: series(&|r| (r.render_warm_ms, r.ssim.mean)),
                    ..Default::default()
                },
            ),
        ]
    }

    /// One table per resolution: every method at every image size.
    pub fn tables(&self, label: &str) -> Result<Vec<Table>, Error> {
        let mut resolutions: Vec<u32> = self.rows.iter().map(|r| r.resolution).collect();
        resolutions.dedup();
        let mut tables = Vec::new();
        // A `backend` column only when a GPU was asked for: the CPU report is unchanged.
        let with_backend = self.rows.iter().any(|r| r.backend.is_some());
        for res in resolutions {
            let mut columns = vec![
                Column::text("method"),
                Column::number("image", NumberFormat::Integer),
                Column::number("voxels", NumberFormat::Integer),
                Column::number("record B/voxel", NumberFormat::Fixed(2)),
                Column::number("total B/voxel", NumberFormat::Fixed(2)),
                Column::number("memory (MiB)", NumberFormat::Fixed(3)),
                Column::number("precompute (ms)", NumberFormat::Fixed(0)),
                Column::number("render cold (ms)", NumberFormat::Fixed(1)),
                Column::number("render warm (ms)", NumberFormat::Fixed(1)),
                Column::text("MSE mean (min–max)"),
                Column::text("SSIM mean (min–max)"),
                Column::text("mix avg/vjk/vmesh"),
            ];
            if with_backend {
                columns.push(Column::text("backend"));
                columns.push(Column::text("precompute on"));
            }
            let mut table = Table::new(format!("{label} filtered appearance {res}^3"), columns);
            for r in self.rows.iter().filter(|r| r.resolution == res) {
                let mut cells = vec![
                    r.method.clone().into(),
                    Cell::Number(r.image as f64),
                    Cell::Number(r.voxels as f64),
                    Cell::Number(r.record_bytes),
                    Cell::Number(r.bytes_per_voxel),
                    Cell::Number(r.memory_bytes as f64 / (1 << 20) as f64),
                    Cell::Number(r.precompute_ms),
                    Cell::Number(r.render_cold_ms),
                    Cell::Number(r.render_warm_ms),
                    Cell::Text(format!("{:.2e}", r.mse.mean)),
                    Cell::Text(r.ssim.display(4)),
                    r.mix.map_or(Cell::Empty, |m| {
                        Cell::Text(format!(
                            "{:.0}/{:.0}/{:.0}%",
                            m[0] * 100.0,
                            m[1] * 100.0,
                            m[2] * 100.0
                        ))
                    }),
                ];
                if with_backend {
                    cells.push(Cell::Text(r.backend.clone().unwrap_or_else(|| "cpu".into())));
                    let on = r.precompute_backend.clone().unwrap_or_else(|| "cpu".into());
                    cells.push(Cell::Text(on));
                }
                table.push_row(cells)?;
            }
            tables.push(table);
        }
        if !self.predictor.is_empty() {
            let mut table = Table::new(
                format!("{label} Adaptive selector errors against measured voxel contributions"),
                vec![
                    Column::number("resolution", NumberFormat::Integer),
                    Column::number("voxels measured", NumberFormat::Integer),
                    Column::number("changed the image", NumberFormat::Integer),
                    Column::number("Spearman held-out", NumberFormat::Fixed(3)),
                    Column::number("Spearman image", NumberFormat::Fixed(3)),
                    Column::number("held-out (changed)", NumberFormat::Fixed(3)),
                    Column::number("image (changed)", NumberFormat::Fixed(3)),
                ],
            );
            for p in &self.predictor {
                table.push_row(vec![
                    Cell::Number(p.resolution as f64),
                    Cell::Number(p.samples as f64),
                    Cell::Number(p.changed as f64),
                    Cell::Number(p.heldout_spearman),
                    Cell::Number(p.image_spearman),
                    Cell::Number(p.heldout_spearman_changed),
                    Cell::Number(p.image_spearman_changed),
                ])?;
            }
            tables.push(table);
        }
        Ok(tables)
    }
}

fn ser_mix<S: serde::Serializer>(mix: &Option<[f64; 3]>, s: S) -> Result<S::Ok, S::Error> {
    #[derive(serde::Serialize)]
    struct Mix {
        averages: f64,
        vjk21: f64,
        virtual_mesh: f64,
    }
    let mix = mix.map(|[averages, vjk21, virtual_mesh]| Mix { averages, vjk21, virtual_mesh });
    serde::Serialize::serialize(&mix, s)
}
