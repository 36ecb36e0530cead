//! The paper's other measurements, under its conditions: rays per voxel against quality (where
//! more rays stop helping), the 2×2-downsample experiment of §5 (\[VJK21\] at twice the
//! resolution, its image averaged down, against the virtual mesh), and the single-threaded
//! precompute time and memory of the virtual mesh beside the paper's Table 2.

use std::time::Instant;

use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::virtual_mesh::{VirtualMeshGrid, VirtualMeshParams};
use voxlod_cpu::appearance::{Appearance, sggx, virtual_mesh};
use voxlod_cpu::voxelize::{self, Mode, Voxelization};
use voxlod_eval::report::{Cell, Column, NumberFormat, Report, Table};
use voxlod_format::GridSpec;
use voxlod_scene::Image;

use super::setup::{Loaded, Setup, render_linear};
use super::{PairedDiff, PaperConfig, TruthCache, Variant};
use crate::Error;

/// Brito, Poulin and Teichrieb (2023), Table 2, for their representations: `(scene,
/// triangles, memory MB at 128³, at 256³, precompute s at 128³, at 256³)` (single thread,
/// Intel i7-8700K).
pub const PAPER_TABLE_2: &[(&str, u32, f64, f64, f64, f64)] = &[
    ("Bunny", 144_000, 10.6, 52.4, 15.0, 66.0),
    ("Trees", 540_000, 18.7, 106.2, 33.0, 150.0),
    ("Island", 307_000, 4.7, 22.4, 8.0, 34.0),
    ("Bistro", 3_420_000, 19.9, 135.5, 29.0, 156.0),
    ("City", 635_000, 8.9, 48.0, 28.0, 102.0),
];

/// Which extra measurements to run.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtrasConfig {
    /// Rays per voxel of the sweep (empty: no sweep); paired against [`PaperConfig::rays`].
    pub rays: Vec<u32>,
    /// The 2×2-downsample experiment.
    pub downsample: bool,
    /// The single-threaded precompute beside Table 2.
    pub precompute: bool,
}

impl Default for ExtrasConfig {
    fn default() -> Self {
        Self { rays: vec![50, 150, 500], downsample: true, precompute: true }
    }
}

/// Scores of one method in one extra measurement, sample by sample (seed-major, then view).
#[derive(Clone, Debug, serde::Serialize)]
pub struct ExtraRow {
    /// Scene label.
    pub scene: String,
    /// Voxel resolution of the paper setup (= the scored image side).
    pub resolution: u32,
    /// What was measured (method and its setting).
    pub what: String,
    /// Rays per voxel.
    pub rays: u32,
    /// MSE per sample.
    pub mse: Vec<f64>,
    /// SSIM per sample.
    pub ssim: Vec<f64>,
}

/// Single-threaded precompute of the virtual mesh (sampling + fit) and its memory.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PrecomputeRow {
    /// Scene label.
    pub scene: String,
    /// The paper scene it stands for.
    pub paper: Option<String>,
    /// Triangles.
    pub triangles: usize,
    /// Voxel resolution.
    pub resolution: u32,
    /// Occupied voxels.
    pub voxels: usize,
    /// Voxelization time, one thread, s.
    pub voxelize_s: f64,
    /// Sampling + fit of the virtual mesh, one thread, s.
    pub precompute_s: f64,
    /// The virtual-mesh grid's heap bytes, MB (10⁶).
    pub memory_mb: f64,
    /// The paper's Table 2 `(memory MB, precompute s)` at this resolution.
    pub paper_table_2: Option<(f64, f64)>,
}

/// What the extras measured.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ExtrasResult {
    /// Rays per voxel sweep: every method at each ray count.
    pub rays: Vec<ExtraRow>,
    /// The downsample experiment: \[VJK21\] at the resolution, at twice it averaged 2×2 down,
    /// and the virtual mesh at the resolution.
    pub downsample: Vec<ExtraRow>,
    /// Single-threaded precompute.
    pub precompute: Vec<PrecomputeRow>,
}

/// Runs the extras on every scene and resolution of `config`, under the paper setup.
pub fn run(
    config: &PaperConfig,
    extras: &ExtrasConfig,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<ExtrasResult, Error> {
    config.validate()?;
    let cache = TruthCache::new(config.cache.clone());
    let mut result = ExtrasResult::default();
    for &rays in &extras.rays {
        let c = PaperConfig {
            rays,
            thresholds: Vec::new(),
            image_thresholds: Vec::new(),
            ..config.clone()
        };
        let run = super::run(&c, &|m| progress(&format!("{rays} rays/voxel: {m}")))?;
        for case in run.cases {
            for m in case.methods {
                result.rays.push(ExtraRow {
                    scene: case.scene.clone(),
                    resolution: case.resolution,
                    what: m.method,
                    rays,
                    mse: m.mse,
                    ssim: m.ssim,
                });
            }
        }
    }
    for scene in &config.scenes {
        let loaded = Loaded::new(&scene.spec, config.views)?;
        for &res in &config.resolutions {
            let say = |m: &str| progress(&format!("{} {res}³: {m}", scene.label));
            if extras.downsample {
                let setup = loaded.truths(&Variant::paper(), res, config, &cache, &say)?;
                result.downsample.extend(downsample(
                    &loaded,
                    &setup,
                    &scene.label,
                    res,
                    config,
                    &say,
                )?);
            }
            if extras.precompute {
                say("single-threaded precompute");
                let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| {
                    Error::NothingToMeasure { scene: scene.spec.clone(), why: e.to_string() }
                })?;
                let row = pool.install(|| -> Result<PrecomputeRow, Error> {
                    let t = Instant::now();
                    let vox = voxelize_at(&loaded, res)?;
                    let voxelize_s = t.elapsed().as_secs_f64();
                    let ctx = SamplingContext::new(&loaded.scene, &loaded.geometry, &vox)?;
                    let t = Instant::now();
                    let opts = PrecomputeOptions { rays: config.rays, seed: 0 };
                    let g = precompute(&ctx, &opts, virtual_mesh::fit)?;
                    let precompute_s = t.elapsed().as_secs_f64();
                    let paper_table_2 = scene.paper.as_deref().and_then(|p| {
                        PAPER_TABLE_2.iter().find(|r| r.0 == p).and_then(|r| match res {
                            128 => Some((r.2, r.4)),
                            256 => Some((r.3, r.5)),
                            _ => None,
                        })
                    });
                    Ok(PrecomputeRow {
                        scene: scene.label.clone(),
                        paper: scene.paper.clone(),
                        triangles: loaded.scene.triangle_count(),
                        resolution: res,
                        voxels: vox.voxels.len(),
                        voxelize_s,
                        precompute_s,
                        memory_mb: g.memory_bytes() as f64 / 1e6,
                        paper_table_2,
                    })
                })?;
                result.precompute.push(row);
            }
        }
    }
    Ok(result)
}

fn voxelize_at(loaded: &Loaded, res: u32) -> Result<Voxelization, Error> {
    let (lo, hi) = loaded.scene.bounds()?;
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res)?;
    let options = voxelize::Options { mode: Mode::Conservative, ..Default::default() };
    Ok(voxelize::voxelize(&loaded.geometry, &grid, &options)?)
}

/// Averages 2×2 blocks of linear pixels (the image side must be even).
fn downsample_2x2(image: &Image) -> Image {
    let (w, h) = (image.width / 2, image.height / 2);
    let mut out = Image::new(w, h, glam::Vec4::ZERO);
    for y in 0..h {
        for x in 0..w {
            let s = image.get(2 * x, 2 * y)
                + image.get(2 * x + 1, 2 * y)
                + image.get(2 * x, 2 * y + 1)
                + image.get(2 * x + 1, 2 * y + 1);
            out.set(x, y, s * 0.25);
        }
    }
    out
}

/// The §5 experiment at `res`: \[VJK21\] at `res`³ and at `2·res`³ rendered at `(2·res)²` and
/// averaged 2×2 down, and the virtual mesh at `res`³, all scored against the `res`² truth.
fn downsample(
    loaded: &Loaded,
    setup: &Setup,
    label: &str,
    res: u32,
    config: &PaperConfig,
    progress: &dyn Fn(&str),
) -> Result<Vec<ExtraRow>, Error> {
    let fine = voxelize_at(loaded, 2 * res)?;
    let coarse = voxelize_at(loaded, res)?;
    let names = [
        format!("[VJK21] {res}³"),
        format!("[VJK21] {}³ at {}², 2×2 → {res}²", 2 * res, 2 * res),
        format!("virtual mesh {res}³"),
    ];
    let mut rows: Vec<ExtraRow> = names
        .iter()
        .map(|n| ExtraRow {
            scene: label.into(),
            resolution: res,
            what: n.clone(),
            rays: config.rays,
            mse: Vec::new(),
            ssim: Vec::new(),
        })
        .collect();
    for seed in 0..config.seeds {
        let opts = PrecomputeOptions { rays: config.rays, seed };
        let choices = Variant::paper().choices_for_seed(seed);
        progress(&format!("downsample experiment, seed {seed}: precompute"));
        let c_ctx = SamplingContext::new(&loaded.scene, &loaded.geometry, &coarse)?;
        let vjk = precompute(&c_ctx, &opts, sggx::fit)?;
        let vm = VirtualMeshGrid::with_params(
            precompute(&c_ctx, &opts, virtual_mesh::fit)?,
            choices.virtual_mesh(VirtualMeshParams::default()),
        );
        drop(c_ctx);
        let f_ctx = SamplingContext::new(&loaded.scene, &loaded.geometry, &fine)?;
        let vjk_fine = precompute(&f_ctx, &opts, sggx::fit)?;
        drop(f_ctx);
        let grids: [(&dyn Appearance, u32); 3] = [(&vjk, res), (&vjk_fine, 2 * res), (&vm, res)];
        for (row, (grid, size)) in rows.iter_mut().zip(grids) {
            progress(&format!("downsample experiment, seed {seed}: {}", row.what));
            for (camera, reference) in loaded.views.iter().zip(&setup.references) {
                let bg = setup.scene.background;
                let (lights, ambient) = (&setup.lights, config.ambient);
                let image = render_linear(grid, camera, lights, bg, ambient, &choices, size)?;
                let image = if size == res { image } else { downsample_2x2(&image) };
                let m = voxlod_eval::compare(&image.to_srgb8(), reference)?;
                row.mse.push(m.mse);
                row.ssim.push(m.ssim);
            }
        }
    }
    Ok(rows)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

impl ExtrasResult {
    /// The tables: the rays sweep (paired against `base_rays`), the downsample experiment
    /// (paired against the virtual mesh), and the precompute beside Table 2.
    pub fn tables(&self, base_rays: u32) -> Result<Vec<Table>, Error> {
        let mut tables = Vec::new();
        if !self.rays.is_empty() {
            let mut t = Table::new(
                format!(
                    "rays per voxel: each method's scores and their paired change from {base_rays} rays (95 % bootstrap interval)"
                ),
                vec![
                    Column::text("scene"),
                    Column::number("res", NumberFormat::Integer),
                    Column::text("method"),
                    Column::number("rays", NumberFormat::Integer),
                    Column::text("MSE"),
                    Column::text("ΔMSE [95 %]"),
                    Column::text("SSIM"),
                    Column::text("ΔSSIM [95 %]"),
                ],
            );
            for r in &self.rays {
                let base = self.rays.iter().find(|b| {
                    b.rays == base_rays
                        && b.scene == r.scene
                        && b.resolution == r.resolution
                        && b.what == r.what
                });
                let (dm, ds) = match base.filter(|_| r.rays != base_rays) {
                    Some(b) => (
                        PairedDiff::of(&r.mse, &b.mse).display_sci(2),
                        PairedDiff::of(&r.ssim, &b.ssim).display_fixed(4),
                    ),
                    None => (String::new(), String::new()),
                };
                t.push_row(vec![
                    Cell::Text(r.scene.clone()),
                    Cell::Number(r.resolution as f64),
                    Cell::Text(r.what.clone()),
                    Cell::Number(r.rays as f64),
                    Cell::Text(format!("{:.3e}", mean(&r.mse))),
                    Cell::Text(dm),
                    Cell::Text(format!("{:.4}", mean(&r.ssim))),
                    Cell::Text(ds),
                ])?;
            }
            tables.push(t);
        }
        if !self.downsample.is_empty() {
            let mut t = Table::new(
                "the 2×2-downsample experiment: differences paired against the virtual mesh at the same resolution (95 % bootstrap interval)",
                vec![
                    Column::text("scene"),
                    Column::text("method"),
                    Column::text("MSE"),
                    Column::text("SSIM"),
                    Column::text("ΔMSE vs virtual mesh [95 %]"),
                    Column::text("ΔSSIM vs virtual mesh [95 %]"),
                ],
            );
            for chunk in self.downsample.chunks(3) {
                let vm = &chunk[2];
                for r in chunk {
                    let vs = |f: fn(&ExtraRow) -> &Vec<f64>, sci: bool| {
                        if std::ptr::eq(r, vm) {
                            return String::new();
                        }
                        let d = PairedDiff::of(f(r), f(vm));
                        if sci { d.display_sci(2) } else { d.display_fixed(4) }
                    };
                    t.push_row(vec![
                        Cell::Text(format!("{} {}³", r.scene, r.resolution)),
                        Cell::Text(r.what.clone()),
                        Cell::Text(format!("{:.3e}", mean(&r.mse))),
                        Cell::Text(format!("{:.4}", mean(&r.ssim))),
                        Cell::Text(vs(|r| &r.mse, true)),
                        Cell::Text(vs(|r| &r.ssim, false)),
                    ])?;
                }
            }
            tables.push(t);
        }
        if !self.precompute.is_empty() {
            let mut t = Table::new(
                "virtual mesh precompute on one thread, beside the paper's Table 2 (its scenes at their own triangle counts, an Intel i7-8700K)",
                vec![
                    Column::text("scene"),
                    Column::number("triangles", NumberFormat::Integer),
                    Column::number("res", NumberFormat::Integer),
                    Column::number("voxels", NumberFormat::Integer),
                    Column::number("voxelize (s)", NumberFormat::Fixed(2)),
                    Column::number("sampling + fit (s)", NumberFormat::Fixed(1)),
                    Column::number("memory (MB)", NumberFormat::Fixed(1)),
                    Column::text("paper memory (MB)"),
                    Column::text("paper precompute (s)"),
                ],
            );
            for r in &self.precompute {
                t.push_row(vec![
                    Cell::Text(r.scene.clone()),
                    Cell::Number(r.triangles as f64),
                    Cell::Number(r.resolution as f64),
                    Cell::Number(r.voxels as f64),
                    Cell::Number(r.voxelize_s),
                    Cell::Number(r.precompute_s),
                    Cell::Number(r.memory_mb),
                    r.paper_table_2.map_or(Cell::Empty, |p| Cell::Text(format!("{:.1}", p.0))),
                    r.paper_table_2.map_or(Cell::Empty, |p| Cell::Text(format!("{:.0}", p.1))),
                ])?;
            }
            tables.push(t);
        }
        Ok(tables)
    }

    /// The extras' report section.
    pub fn add_to_report(&self, report: &mut Report, config: &PaperConfig) -> Result<(), Error> {
        report.heading(2, "Rays per voxel, the downsample experiment and the precompute");
        report.text(
            "Under the paper setup. The downsample experiment follows Brito, Poulin and Teichrieb \
             (2023, §5): \\[VJK21\\] voxelized at twice the resolution and rendered at twice the \
             image side, its linear image averaged over 2×2 pixels, scored against the same \
             ground truth as the virtual mesh at the resolution. The precompute is sampling and \
             fit of the virtual mesh on one thread (the paper's is single-threaded software).",
        );
        for t in self.tables(config.rays)? {
            report.table(t);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downsampling_averages_each_2x2_block() {
        let mut image = Image::new(4, 2, glam::Vec4::ZERO);
        for (x, v) in [(0, 1.0), (1, 3.0), (2, 0.5), (3, 0.5)] {
            image.set(x, 0, glam::Vec4::splat(v));
            image.set(x, 1, glam::Vec4::splat(v * 2.0));
        }
        let d = downsample_2x2(&image);
        assert_eq!((d.width, d.height), (2, 1));
        assert_eq!(d.get(0, 0), glam::Vec4::splat(3.0));
        assert_eq!(d.get(1, 0), glam::Vec4::splat(0.75));
    }
}
