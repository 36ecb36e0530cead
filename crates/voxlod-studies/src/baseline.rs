//! One scene section of the default report: ground truth, its own error, and the voxel baseline
//! at each resolution.

use std::time::{Duration, Instant};

use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::{baseline, ground_truth};
use voxlod_cpu::voxelize::{self, Mode};
use voxlod_eval::report::{Cell, Column, ImageGrid, LabeledImage, NumberFormat, Report, Table};
use voxlod_eval::{ImageMetrics, compare, error_heatmap};
use voxlod_format::GridSpec;
use voxlod_scene::Srgb8Image;

use crate::backend::Kernels;
use crate::filtered::{self, FilteredResult, SceneInputs};
use crate::ground_truths::GroundTruths;
use crate::report::{Config, SceneCase};
use crate::spread::{Spread, ms};
use crate::views::orbit_views;
use crate::{Error, alloc};

/// One row of a scene's table: the baseline at one resolution.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BaselineRow {
    /// Voxels along the longest axis.
    pub resolution: u32,
    /// Grid dimensions.
    pub dims: [u32; 3],
    /// Occupied voxels.
    pub voxels: usize,
    /// Bytes of the brick map holding the records (headers, records, lookup).
    pub memory_bytes: usize,
    /// `memory_bytes / voxels`.
    pub bytes_per_voxel: f64,
    /// Voxelization time (conservative, with triangle lists), ms.
    pub voxelize_ms: f64,
    /// Heap bytes voxelization held at its peak beyond what was live before (None without the
    /// tracking allocator).
    pub voxelize_peak_bytes: Option<usize>,
    /// Record build time (average colour per voxel), ms.
    pub build_ms: f64,
    /// Mean render time per frame over the views, ms.
    pub render_ms: f64,
    /// MSE against the ground truth, over views.
    pub mse: Spread,
    /// SSIM against the ground truth, over views.
    pub ssim: Spread,
    /// What rendered the row: `cpu` or the GPU adapter's short name. None (and left out of
    /// the JSON) in an all-CPU run, whose output is unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub backend: Option<String>,
}

/// Everything one scene section measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SceneResult {
    /// Label.
    pub label: String,
    /// Spec it was loaded from.
    pub spec: String,
    /// Triangles.
    pub triangles: usize,
    /// Scene load/generation time, ms.
    pub load_ms: f64,
    /// BVH build time, ms.
    pub bvh_ms: f64,
    /// Mean ground-truth render time per view, ms.
    pub gt_ms: f64,
    /// Heap bytes one ground-truth render held at its peak beyond what was live before (None
    /// on the GPU backend: device memory is not counted).
    pub gt_peak_bytes: Option<usize>,
    /// What rendered the ground truth: the GPU adapter's short name; None (and left out of the
    /// JSON) on the CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gt_backend: Option<String>,
    /// Whether that GPU adapter is a CPU implementation (lavapipe): its times are CPU timings
    /// of the GPU path.
    #[serde(skip)]
    pub(crate) gpu_is_cpu: bool,
    /// The ground truth's own error: seed 1 against seed 0, over views.
    pub gt_noise: Vec<ImageMetrics>,
    /// One row per resolution that fit in the budget.
    pub rows: Vec<BaselineRow>,
    /// Resolutions skipped because the section ran over its budget.
    pub skipped: Vec<u32>,
    /// The filtered-appearance comparison, when configured.
    pub filtered: Option<FilteredResult>,
    /// Wall time of the section (`elapsed_s` in JSON, seconds).
    #[serde(rename = "elapsed_s", serialize_with = "ser_secs")]
    pub elapsed: Duration,
    /// Images for the report: ground truth, then baseline per resolution (view 0), then the
    /// error heat map of the finest resolution.
    #[serde(skip)]
    pub images: Vec<LabeledImage>,
}

fn ser_secs<S: serde::Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(d.as_secs_f64())
}

/// Runs one scene section; with `kernels`, every image with a GPU kernel is rendered on the
/// GPU.
pub(super) fn run_scene(
    case: &SceneCase,
    config: &Config,
    kernels: Option<&Kernels<'_>>,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<SceneResult, Error> {
    let start = Instant::now();
    let label = &case.label;
    progress(&format!("{label}: loading"));
    let t = Instant::now();
    let scene = crate::scenes::load(&case.spec)?;
    let load_ms = ms(t.elapsed());
    let geometry = scene.geometry();
    let t = Instant::now();
    let bvh = Bvh::new(&geometry)?;
    let bvh_ms = ms(t.elapsed());
    let (lo, hi) = scene.bounds()?;
    let views = orbit_views(scene.default_camera()?, (lo + hi) * 0.5, config.views);
    let light = scene.light();
    let size = config.image_size;
    // Upload outside the timed renders (like the BVH build); a refused scene names itself.
    let gpu = match kernels {
        Some(k) => {
            progress(&format!("{label}: uploading the scene to the GPU"));
            Some(k.upload_scene(&scene, &geometry, &bvh, &case.spec)?)
        }
        None => None,
    };
    let row_backend = kernels.map(|k| k.name.clone());

    let gt_options = |seed| ground_truth::Options {
        width: size,
        height: size,
        spp: config.gt_spp,
        seed,
        ambient: config.ambient,
        shadows: true,
        light_filter: None,
    };
    let mut gt = Vec::new();
    let mut gt_noise = Vec::new();
    let mut gt_time = Duration::ZERO;
    let mut gt_peak_bytes = None;
    for (i, camera) in views.iter().enumerate() {
        progress(&format!("{label}: ground truth, view {}/{}", i + 1, views.len()));
        let t = Instant::now();
        let reference = match &gpu {
            Some(g) => g.ground_truth(camera, &gt_options(0)),
            None => {
                let (reference, peak) = alloc::measure_peak(|| {
                    ground_truth::render(&scene, &geometry, &bvh, camera, &gt_options(0))
                });
                gt_peak_bytes = gt_peak_bytes.max(peak);
                reference.map_err(Error::from)
            }
        };
        gt_time += t.elapsed();
        let reference = reference?.image.to_srgb8();
        let second = match &gpu {
            Some(g) => g.ground_truth(camera, &gt_options(1))?,
            None => ground_truth::render(&scene, &geometry, &bvh, camera, &gt_options(1))?,
        };
        gt_noise.push(compare(&second.image.to_srgb8(), &reference)?);
        gt.push(reference);
    }
    let mut images = vec![LabeledImage::new("ground truth", gt[0].clone())];

    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let mut finest: Option<Srgb8Image> = None;
    for &res in &config.resolutions {
        if start.elapsed() > config.section_budget {
            skipped.push(res);
            continue;
        }
        progress(&format!("{label}: voxelizing at {res}³"));
        let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res)?;
        let options = voxelize::Options { mode: Mode::Conservative, ..Default::default() };
        let t = Instant::now();
        let (vox, voxelize_peak_bytes) =
            alloc::measure_peak(|| voxelize::voxelize(&geometry, &grid, &options));
        let vox = vox?;
        let voxelize_ms = ms(t.elapsed());
        let t = Instant::now();
        let records = baseline::build(&scene, &geometry, &vox)?;
        let build_ms = ms(t.elapsed());
        drop(vox);
        let uploaded = match kernels {
            Some(k) => Some(k.filtered.upload_baseline(&grid, &records)?),
            None => None,
        };

        let options =
            baseline::Options { width: size, height: size, ambient: config.ambient, shadows: true };
        let mut render_time = Duration::ZERO;
        let mut metrics = Vec::new();
        for (i, camera) in views.iter().enumerate() {
            progress(&format!("{label}: baseline at {res}³, view {}/{}", i + 1, views.len()));
            let t = Instant::now();
            let image = match (kernels, &uploaded) {
                (Some(k), Some(u)) => {
                    k.filtered.render_baseline(u, camera, &light, scene.background, &options)?
                }
                _ => baseline::render(&grid, &records, camera, &light, scene.background, &options)?,
            };
            render_time += t.elapsed();
            let image = image.to_srgb8();
            metrics.push(compare(&image, &gt[i])?);
            if i == 0 {
                images.push(LabeledImage::new(format!("baseline {res}^3"), image.clone()));
                finest = Some(image);
            }
        }
        let memory_bytes = records.memory_bytes();
        rows.push(BaselineRow {
            resolution: res,
            dims: grid.dims.to_array(),
            voxels: records.len(),
            memory_bytes,
            bytes_per_voxel: memory_bytes as f64 / records.len().max(1) as f64,
            voxelize_ms,
            voxelize_peak_bytes,
            build_ms,
            render_ms: ms(render_time) / views.len() as f64,
            mse: Spread::of(&metrics.iter().map(|m| m.mse).collect::<Vec<_>>()),
            ssim: Spread::of(&metrics.iter().map(|m| m.ssim).collect::<Vec<_>>()),
            backend: row_backend.clone(),
        });
    }
    if let (Some(image), Some(row)) = (finest, rows.last()) {
        let heat = error_heatmap(&image, &gt[0], 0.25)?;
        images.push(LabeledImage::new(format!("|error| {}^3", row.resolution), heat));
    }
    let filtered = match &config.filtered {
        None => None,
        Some(fc) => {
            let mut truths =
                GroundTruths::new(&scene, &geometry, &bvh, &views, config, label, gpu.as_ref());
            truths.insert(size, gt);
            let inputs = SceneInputs {
                scene: &scene,
                geometry: &geometry,
                views: &views,
                ambient: config.ambient,
                label,
            };
            let over_budget = || start.elapsed() > config.section_budget;
            let gpu = gpu.as_ref();
            Some(filtered::run(&inputs, fc, &mut truths, gpu, &over_budget, progress)?)
        }
    };
    Ok(SceneResult {
        label: label.clone(),
        spec: case.spec.clone(),
        triangles: geometry.triangle_count(),
        load_ms,
        bvh_ms,
        gt_ms: ms(gt_time) / views.len() as f64,
        gt_peak_bytes,
        gt_backend: row_backend,
        gpu_is_cpu: kernels.is_some_and(|k| k.is_cpu),
        gt_noise,
        rows,
        skipped,
        filtered,
        elapsed: start.elapsed(),
        images,
    })
}

fn mib(bytes: Option<usize>) -> Cell {
    bytes.map_or(Cell::Empty, |b| Cell::Number(b as f64 / (1 << 20) as f64))
}

/// `mean (min–max)` in scientific notation: noise levels span many decades.
fn sci(s: Spread) -> String {
    format!("{:.2e} ({:.2e}–{:.2e})", s.mean, s.min, s.max)
}

impl SceneResult {
    /// What a reader must know about GPU times from a CPU adapter ("" otherwise).
    fn cpu_adapter_note(&self) -> &'static str {
        if self.gpu_is_cpu {
            "; this adapter is a CPU implementation: CPU timings of the GPU path, not GPU speed"
        } else {
            ""
        }
    }

    /// The scene's results as a table (one row per resolution).
    pub fn table(&self) -> Result<Table, Error> {
        // A `backend` column only when a GPU was asked for: the CPU report is unchanged.
        let with_backend = self.rows.iter().any(|r| r.backend.is_some());
        let mut columns = vec![
            Column::text("method"),
            Column::number("res", NumberFormat::Integer),
            Column::number("voxels", NumberFormat::Integer),
            Column::number("bytes/voxel", NumberFormat::Fixed(2)),
            Column::number("memory (MiB)", NumberFormat::Fixed(3)),
            Column::number("voxelize (ms)", NumberFormat::Fixed(1)),
            Column::number("voxelize peak (MiB)", NumberFormat::Fixed(1)),
            Column::number("build (ms)", NumberFormat::Fixed(1)),
            Column::number("render/frame (ms)", NumberFormat::Fixed(1)),
            Column::text("MSE mean (min–max)"),
            Column::text("SSIM mean (min–max)"),
        ];
        if with_backend {
            columns.push(Column::text("backend"));
        }
        let mut table = Table::new(format!("{} baseline", self.label), columns);
        for r in &self.rows {
            let mut cells = vec![
                "baseline (opaque cubes)".into(),
                Cell::Number(r.resolution as f64),
                Cell::Number(r.voxels as f64),
                Cell::Number(r.bytes_per_voxel),
                Cell::Number(r.memory_bytes as f64 / (1 << 20) as f64),
                Cell::Number(r.voxelize_ms),
                mib(r.voxelize_peak_bytes),
                Cell::Number(r.build_ms),
                Cell::Number(r.render_ms),
                Cell::Text(r.mse.display(5)),
                Cell::Text(r.ssim.display(4)),
            ];
            if with_backend {
                cells.push(Cell::Text(r.backend.clone().unwrap_or_else(|| "cpu".into())));
            }
            table.push_row(cells)?;
        }
        Ok(table)
    }

    /// Appends this scene's section to `report`.
    pub fn write_section(&self, report: &mut Report, config: &Config) -> Result<(), Error> {
        report.heading(2, format!("{} ({})", self.label, self.spec));
        let noise_mse = Spread::of(&self.gt_noise.iter().map(|m| m.mse).collect::<Vec<_>>());
        let noise_ssim = Spread::of(&self.gt_noise.iter().map(|m| m.ssim).collect::<Vec<_>>());
        report.text(format!(
            "{} triangles; load {:.0} ms, BVH build {:.0} ms. Ground truth: {:.0} ms per view at \
             {} rays/pixel (peak {} beyond the scene and BVH). **The ground truth's own error**, \
             estimated as half the MSE between two independent seeds: MSE {} (seed 1 against \
             seed 0: MSE {}, 1 − SSIM {}); errors against the ground truth below it are not \
             resolved. Section time {:.1} s (budget {} s).{}",
            self.triangles,
            self.load_ms,
            self.bvh_ms,
            self.gt_ms,
            config.gt_spp,
            self.gt_peak_bytes
                .map_or("n/a".into(), |b| format!("{:.1} MiB", b as f64 / (1 << 20) as f64)),
            sci(noise_mse.map(|v| v / 2.0)),
            sci(noise_mse),
            sci(noise_ssim.map(|v| 1.0 - v)),
            self.elapsed.as_secs_f64(),
            config.section_budget.as_secs(),
            self.gt_backend.as_ref().map_or(String::new(), |b| format!(
                " Ground truth and baseline rendered on the GPU ({b}): times are those of the \
                 GPU path, upload excluded{}.",
                self.cpu_adapter_note()
            )),
        ));
        report.table(self.table()?);
        if !self.skipped.is_empty() {
            report.text(format!(
                "Skipped (section over its time budget): {}.",
                self.skipped.iter().map(|r| format!("{r}³")).collect::<Vec<_>>().join(", ")
            ));
        }
        report.images(
            format!("{}-images", self.label),
            "View 0: ground truth, the baseline at each resolution, and its per-pixel error.",
            ImageGrid::new(self.images.len().min(6) as u32, self.images.clone()),
        );
        if let Some(f) = &self.filtered {
            report.heading(3, format!("{}: filtered appearance", self.label));
            report.text(
                "Every representation fitted from the same per-voxel sampling lines; render times \
                 are per frame with the per-voxel cache cold (first frame of a view) and warm \
                 (the same view again); bytes are per voxel with a record, the total including \
                 the sparse brick map.",
            );
            if let Some(b) = &self.gt_backend {
                report.text(format!(
                    "Rows with backend `{b}` were rendered on the GPU, which keeps no per-voxel \
                     cache: cold and warm are the same work timed twice (upload and pipeline \
                     compilation excluded){}. Rows with backend `cpu` have no GPU kernel yet.",
                    self.cpu_adapter_note()
                ));
            }
            for table in f.tables(&self.label)? {
                report.text(format!("**{}**", table.name()));
                report.table(table);
            }
            if !f.skipped.is_empty() {
                report.text(format!(
                    "Filtered appearance skipped (section over its time budget): {}.",
                    f.skipped.iter().map(|r| format!("{r}³")).collect::<Vec<_>>().join(", ")
                ));
            }
            for (res, figure) in &f.images {
                report.images(
                    format!("{}-filtered-{res}", self.label),
                    format!(
                        "{res}³ at {res}², view 0: ground truth, then each representation and its \
                         per-pixel error (full scale 0.25)."
                    ),
                    ImageGrid::new(figure.len().div_ceil(2) as u32, figure.clone()),
                );
            }
            for (name, plot) in f.plots(&self.label) {
                report.plot(name, plot);
            }
        }
        Ok(())
    }
}
