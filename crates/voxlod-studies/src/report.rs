//! The default report behind `cargo run --release` (`voxlod report`): for each embedded scene,
//! render the ground truth from several viewpoints (and a second ground truth with another
//! seed, to estimate its own error), voxelize at a few resolutions, render each representation
//! from the same cameras, score it against the ground truth on 8-bit sRGB, and collect time and
//! peak memory per stage ([`crate::baseline`], [`crate::filtered`]); then the procedural-volume
//! study ([`crate::volume`]) and the cone-tracing study ([`crate::cone`]), all into one
//! [`Report`]. On request ([`Config::with_turntable`]), each scene section ends with a turntable
//! ([`crate::turntable`]): off by default, as it costs more than a tenth of the default run.
//!
//! Each scene is a section with its own time budget: when a section runs over, its remaining
//! resolutions are skipped and the report says so.

use std::time::{Duration, Instant};

use glam::Vec3;
use voxlod_eval::report::{Report, Series};

use crate::Error;
use crate::backend::{self, Backend};
use crate::baseline::{self, BaselineRow, SceneResult};
use crate::cone::{self, ConeConfig, ConeResult};
use crate::filtered::FilteredConfig;
use crate::turntable::{self, TurntableConfig, TurntableInputs, TurntableResult};
use crate::volume::{self, VolumeConfig, VolumeResult};

/// One scene of the experiment.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneCase {
    /// A scene spec for [`crate::scenes::load`].
    pub spec: String,
    /// Short label for tables.
    pub label: String,
}

impl SceneCase {
    /// A case from a spec and a label.
    pub fn new(spec: &str, label: &str) -> Self {
        Self { spec: spec.into(), label: label.into() }
    }
}

/// Settings of the experiment. [`Config::quick`] is the default run (about a minute on
/// 2 cores); [`Config::full`] uses the paper's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// Scenes, each a report section.
    pub scenes: Vec<SceneCase>,
    /// Voxels along each scene's longest axis.
    pub resolutions: Vec<u32>,
    /// Square image side in pixels.
    pub image_size: u32,
    /// Rays per pixel of the ground truth.
    pub gt_spp: u32,
    /// Viewpoints per scene (orbiting the scene's own camera about the vertical axis).
    pub views: usize,
    /// Time budget per scene section.
    pub section_budget: Duration,
    /// Ambient term of the shading, the same for the ground truth and every voxel renderer.
    pub ambient: Vec3,
    /// The filtered-appearance comparison (None: the baseline only).
    pub filtered: Option<FilteredConfig>,
    /// The procedural-volume section after the scenes (None: none).
    pub volume: Option<VolumeConfig>,
    /// The voxel cone tracing section after the volume (None: none).
    pub cone: Option<ConeConfig>,
    /// A turntable at the end of each scene section (None: none, the default).
    pub turntable: Option<TurntableConfig>,
    /// The command line that runs this configuration, named at the top of the report.
    pub command: String,
}

impl Config {
    /// The default run: three embedded scenes, the baseline at 32³ to 256³, the filtered
    /// representations at 64³ (64² and 128² images), 128 rays per pixel for the ground truth
    /// (its own error, estimated from a second seed, is reported and is far below the errors
    /// measured), three views.
    pub fn quick() -> Self {
        Self {
            scenes: default_scenes(),
            resolutions: vec![32, 64, 128, 256],
            image_size: 128,
            gt_spp: 128,
            views: 3,
            section_budget: Duration::from_secs(40),
            ambient: Vec3::splat(0.1),
            filtered: Some(FilteredConfig::quick()),
            // The smoke column at its default particle count, 128³ voxels, 256² pixels.
            volume: Some(VolumeConfig {
                particles: 0,
                resolution: 128,
                image: 256,
                mesh_spp: 16,
                ..VolumeConfig::quick("smoke")
            }),
            cone: Some(ConeConfig::quick()),
            turntable: None,
            command: "cargo run --release".into(),
        }
    }

    /// This configuration with a turntable of `frames` frames at the end of each scene section:
    /// panels of the report's image size, its ground truth's rays per pixel and ambient term;
    /// the voxel panels at the finest resolution of the filtered comparison (else 64³) with its
    /// sampling lines per voxel ([`TurntableConfig::quick`] otherwise).
    pub fn with_turntable(self, frames: usize) -> Self {
        let quick = TurntableConfig::quick();
        let (resolution, rays) = match &self.filtered {
            Some(f) => (f.resolutions.iter().copied().max().unwrap_or(64), f.rays),
            None => (quick.resolution, quick.rays),
        };
        let turntable = TurntableConfig {
            frames,
            panel: (self.image_size, self.image_size),
            gt_spp: self.gt_spp,
            resolution,
            rays,
            ambient: self.ambient,
            ..quick
        };
        Self { turntable: Some(turntable), ..self }
    }

    /// Paper-scale settings: the baseline at 64³ to 256³, the filtered representations at 128³
    /// and 256³ ([`FilteredConfig::full`]), 256² images, 1024 rays per pixel, four views.
    pub fn full() -> Self {
        Self {
            resolutions: vec![64, 128, 256],
            image_size: 256,
            gt_spp: 1024,
            views: 4,
            section_budget: Duration::from_secs(900),
            filtered: Some(FilteredConfig::full()),
            volume: Some(VolumeConfig {
                particles: 0,
                resolution: 256,
                image: 512,
                mesh_spp: 64,
                ..VolumeConfig::quick("smoke")
            }),
            cone: Some(ConeConfig::full()),
            command: "cargo run --release -- report --full".into(),
            ..Self::quick()
        }
    }

    /// Checks every field, and the filtered, volume and cone settings it carries (the first
    /// bad field is named in the error), before anything runs.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "report", field, value, expected })
        };
        if self.scenes.is_empty() {
            return bad("scenes", "[]".into(), "at least one scene");
        }
        if self.resolutions.is_empty() {
            return bad("resolutions", "[]".into(), "at least one resolution");
        }
        for &r in &self.resolutions {
            if !(1..=2048).contains(&r) {
                return bad("resolutions", r.to_string(), "in 1..=2048");
            }
        }
        if !(1..=4096).contains(&self.image_size) {
            return bad("image_size", self.image_size.to_string(), "an image side in 1..=4096");
        }
        if self.gt_spp == 0 {
            return bad("gt_spp", "0".into(), "at least 1 ray per pixel");
        }
        if self.views == 0 {
            return bad("views", "0".into(), "at least 1 view");
        }
        if !(self.ambient.is_finite() && self.ambient.min_element() >= 0.0) {
            return bad("ambient", format!("{}", self.ambient), "finite and >= 0 per channel");
        }
        if let Some(f) = &self.filtered {
            f.validate()?;
        }
        if let Some(v) = &self.volume {
            v.validate()?;
        }
        if let Some(c) = &self.cone {
            c.validate()?;
        }
        if let Some(t) = &self.turntable {
            t.validate()?;
        }
        Ok(())
    }
}

fn default_scenes() -> Vec<SceneCase> {
    vec![
        SceneCase::new("builtin:bunny", "bunny"),
        SceneCase::new("builtin:forest?trees=3&leaves=40000&leaf_size=0.04", "forest"),
        SceneCase::new("builtin:engine", "engine"),
    ]
}

/// What the experiment produced: per-scene results and the report to write.
#[derive(Debug)]
pub struct Outcome {
    /// Results per scene, in order.
    pub scenes: Vec<SceneResult>,
    /// The procedural-volume section's result, if the configuration asked for one.
    pub volume: Option<VolumeResult>,
    /// The cone-tracing section's result, if the configuration asked for one.
    pub cone: Option<ConeResult>,
    /// The turntable of each scene, if the configuration asked for them.
    pub turntables: Vec<TurntableResult>,
    /// The report (not yet written).
    pub report: Report,
    /// Wall time of the whole run.
    pub elapsed: Duration,
}

/// Runs the report with the images that have a GPU kernel rendered on `backend` (the ground
/// truth and the baseline and filtered rows; the volume and cone sections run on the CPU);
/// every row says which backend rendered it. `progress` receives a short message at each stage.
pub fn run(
    config: &Config,
    backend: Backend<'_>,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Outcome, Error> {
    config.validate()?;
    let start = Instant::now();
    let kernels = match backend {
        Backend::Cpu => None,
        Backend::Gpu(ctx) => {
            progress("compiling the GPU kernels");
            Some(backend::Kernels::new(ctx)?)
        }
    };
    let mut report = Report::new("voxlod report");
    let mut text = intro(config);
    if let Some(k) = &kernels {
        text.push_str(&gpu_intro(k));
    }
    report.text(text);
    let mut scenes = Vec::new();
    let mut turntables = Vec::new();
    for case in &config.scenes {
        let result = baseline::run_scene(case, config, kernels.as_ref(), progress)?;
        result.write_section(&mut report, config)?;
        scenes.push(result);
        if let Some(tc) = &config.turntable {
            let scene = crate::scenes::load(&case.spec)?;
            let geometry = scene.geometry();
            let bvh = voxlod_cpu::raycast::Bvh::new(&geometry)?;
            let inputs = TurntableInputs {
                scene: &scene,
                geometry: &geometry,
                bvh: &bvh,
                camera: scene.default_camera()?,
                label: &case.label,
            };
            let t = turntable::run(tc, &inputs, backend, progress)?;
            report.heading(3, format!("{}: turntable", case.label));
            t.add_to_report(&mut report, &format!("turntable-{}", case.label))?;
            turntables.push(t);
        }
    }
    summary_plots(&mut report, &scenes);
    let volume = match &config.volume {
        Some(v) => {
            let result = volume::run(v, Backend::Cpu, progress)?;
            result.add_to_report(&mut report)?;
            Some(result)
        }
        None => None,
    };
    // The cone study traces on the CPU in the report (its GPU kernel is checked by the
    // equivalence suite and used by `voxlod cone --backend gpu`).
    let cone = match &config.cone {
        Some(c) => {
            let result = cone::run(c, Backend::Cpu, progress)?;
            result.add_to_report(&mut report)?;
            Some(result)
        }
        None => None,
    };
    Ok(Outcome { scenes, volume, cone, turntables, report, elapsed: start.elapsed() })
}

fn intro(config: &Config) -> String {
    format!(
        "Generated by `{command}` on {machine}. Every number below was measured in this run on \
         this machine. Images are {size}×{size}; the ground truth casts {spp} stratified rays per \
         pixel through a BVH over the mesh and box-filters them; every representation is \
         rendered from the same {views} cameras and scored on 8-bit sRGB against it (MSE on \
         [0,1], SSIM as Wang et al. 2004). Spreads are min–max over the views. Peak memory is \
         the peak of live heap bytes during the stage beyond what was live before it, measured \
         by a counting allocator. Times are wall-clock times and vary from run to run; every \
         other figure is reproduced exactly by the same command.",
        command = config.command,
        machine = crate::machine::describe(),
        size = config.image_size,
        spp = config.gt_spp,
        views = config.views,
    )
}

fn gpu_intro(k: &backend::Kernels<'_>) -> String {
    format!(
        " **Backend:** the images with a GPU kernel — the ground truth, the baseline, Averages, \
         \\[VJK21\\], the virtual mesh and Adaptive — were rendered on the GPU adapter \
         {summary}. Every row's `backend` says which ({name} or cpu), and the times of GPU rows are times of the GPU path (upload and \
         pipeline compilation excluded){cpu_note}.",
        summary = k.summary,
        name = k.name,
        cpu_note = if k.is_cpu {
            ": this adapter is a CPU implementation, so they are CPU timings of the GPU path, \
             not GPU speed"
        } else {
            ""
        },
    )
}

fn summary_plots(report: &mut Report, scenes: &[SceneResult]) {
    let series = |f: fn(&BaselineRow) -> (f64, f64)| -> Vec<Series> {
        scenes
            .iter()
            .map(|s| Series::new(format!("{} baseline", s.label), s.rows.iter().map(f).collect()))
            .collect()
    };
    report.heading(2, "Error against cost");
    report.plot(
        "ssim-vs-memory",
        voxlod_eval::report::Plot {
            title: "SSIM against memory (baseline)".into(),
            x_label: "memory (bytes, voxels + brick map)".into(),
            y_label: "SSIM (mean over views)".into(),
            log_x: true,
            series: series(|r| (r.memory_bytes as f64, r.ssim.mean)),
            ..Default::default()
        },
    );
    report.plot(
        "mse-vs-render-time",
        voxlod_eval::report::Plot {
            title: "MSE against render time (baseline)".into(),
            x_label: "render time per frame (ms)".into(),
            y_label: "MSE (mean over views)".into(),
            log_x: true,
            log_y: true,
            series: series(|r| (r.render_ms, r.mse.mean)),
            ..Default::default()
        },
    );
}
