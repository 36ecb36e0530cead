//! Turntables: a camera orbiting the scene, each frame the ground truth beside the voxel
//! representations rendered from the same camera (labelled panels), as an animated PNG — so a
//! reader sees where each representation departs from the mesh as the view turns — with each
//! panel's error against the ground truth over the orbit.
//!
//! Panels: the ground truth (BVH ray casting, `gt_spp` rays per pixel), the voxel baseline (one
//! colour per voxel from its triangles, `voxlod_cpu::render::baseline`) and Averages (Brito,
//! Poulin and Teichrieb 2023: one mean colour, normal and opacity per voxel from `rays`
//! sampling lines; `voxlod_cpu::render::filtered`), both at `resolution` voxels along the
//! scene's longest axis. Frame `k` looks from the scene's camera orbited by `k/frames` of a turn
//! about the vertical axis ([`crate::views::orbit_views`]).
//!
//! With [`Backend::Gpu`] every panel is rendered by voxlod-gpu's kernels (ground truth,
//! baseline, Averages on the adapter); the records are built on the CPU either way.

use std::time::{Duration, Instant};

use glam::Vec3;
use voxlod_cpu::appearance::averages;
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::filtered::{self, FrameCache};
use voxlod_cpu::render::{baseline, ground_truth};
use voxlod_cpu::voxelize::{self, Mode};
use voxlod_eval::animation::{Animation, MAX_FRAMES};
use voxlod_eval::compare;
use voxlod_eval::report::{Column, ImageGrid, LabeledImage, NumberFormat, Report, Table};
use voxlod_format::GridSpec;
use voxlod_scene::{Camera, Geometry, Image, Scene};

use crate::Error;
use crate::backend::{Backend, Kernels};
use crate::spread::{Spread, ms};
use crate::views::orbit_views;

/// Smallest panel side: SSIM's 11×11 window and a readable label need some room.
pub const MIN_PANEL: u32 = 16;

/// Settings of a turntable.
#[derive(Clone, Debug, PartialEq)]
pub struct TurntableConfig {
    /// Frames per turn (1 to [`MAX_FRAMES`]).
    pub frames: usize,
    /// Panel width and height in pixels (each at least [`MIN_PANEL`]).
    pub panel: (u32, u32),
    /// Rays per pixel of the ground truth.
    pub gt_spp: u32,
    /// Seed of the ground truth's pixel sampling pattern.
    pub seed: u32,
    /// Voxels along the scene's longest axis for the voxel panels.
    pub resolution: u32,
    /// Sampling lines per voxel for the Averages records.
    pub rays: u32,
    /// How long each frame shows, in milliseconds.
    pub frame_ms: u16,
    /// Ambient term of the shading, the same for every panel.
    pub ambient: Vec3,
}

impl TurntableConfig {
    /// 24 frames of 128² panels, 32 rays per pixel, 64³ voxels, 64 lines per voxel, 100 ms per
    /// frame (a 2.4 s turn).
    pub fn quick() -> Self {
        Self {
            frames: 24,
            panel: (128, 128),
            gt_spp: 32,
            seed: 0,
            resolution: 64,
            rays: 64,
            frame_ms: 100,
            ambient: Vec3::splat(0.1),
        }
    }

    /// 72 frames (5° apart) of 256² panels, 128 rays per pixel, 128³ voxels, 256 lines per
    /// voxel, 50 ms per frame.
    pub fn full() -> Self {
        Self {
            frames: 72,
            panel: (256, 256),
            gt_spp: 128,
            resolution: 128,
            rays: 256,
            frame_ms: 50,
            ..Self::quick()
        }
    }

    /// Checks every field's range ([`Error::InvalidConfig`]).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field, value: String, expected| {
            Err(Error::InvalidConfig { study: "turntable", field, value, expected })
        };
        if !(1..=MAX_FRAMES).contains(&self.frames) {
            return bad("frames", self.frames.to_string(), "1 to 3600 frames");
        }
        if self.panel.0 < MIN_PANEL || self.panel.1 < MIN_PANEL {
            let value = format!("{}×{}", self.panel.0, self.panel.1);
            return bad("panel", value, "at least 16×16 pixels");
        }
        if self.gt_spp == 0 {
            return bad("gt_spp", "0".into(), "at least one ray per pixel");
        }
        if self.resolution == 0 {
            return bad("resolution", "0".into(), "at least one voxel");
        }
        if self.rays == 0 {
            return bad("rays", "0".into(), "at least one sampling line per voxel");
        }
        if self.frame_ms == 0 {
            return bad("frame_ms", "0".into(), "at least 1 ms");
        }
        if !self.ambient.is_finite() || self.ambient.min_element() < 0.0 {
            return bad("ambient", format!("{}", self.ambient), "finite and non-negative");
        }
        Ok(())
    }
}

/// The scene a turntable turns around.
#[derive(Clone, Copy)]
pub struct TurntableInputs<'a> {
    /// The scene (its light and background are used).
    pub scene: &'a Scene,
    /// Its flattened triangles.
    pub geometry: &'a Geometry,
    /// A BVH over `geometry`.
    pub bvh: &'a Bvh,
    /// The camera of frame 0; the others orbit it about the vertical axis.
    pub camera: Camera,
    /// Names the scene in progress messages and errors.
    pub label: &'a str,
}

/// One panel's cost and error over the turn.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PanelRow {
    /// The panel's label.
    pub panel: String,
    /// Voxels with a record (none for the ground truth).
    pub voxels: Option<usize>,
    /// Time to build the panel's records (voxelization included), in ms.
    pub build_ms: Option<f64>,
    /// Mean render time per frame, in ms.
    pub render_ms: f64,
    /// MSE against the ground truth over the frames (none for the ground truth).
    pub mse: Option<Spread>,
    /// SSIM against the ground truth over the frames.
    pub ssim: Option<Spread>,
}

/// A rendered turntable.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TurntableResult {
    /// The scene's label.
    pub label: String,
    /// Frames per turn.
    pub frames: usize,
    /// How long each frame shows, in milliseconds.
    pub frame_ms: u16,
    /// Panel width and height in pixels.
    pub panel: [u32; 2],
    /// Voxels along the longest axis of the voxel panels.
    pub resolution: u32,
    /// Grid dimensions of the voxel panels.
    pub dims: [u32; 3],
    /// What rendered the panels.
    pub backend: String,
    /// One row per panel, the ground truth first.
    pub panels: Vec<PanelRow>,
    /// Wall time of the whole turntable, in seconds.
    pub elapsed_s: f64,
    /// The composed frames.
    #[serde(skip)]
    pub animation: Animation,
}

impl TurntableResult {
    /// The panels' cost and error as a table.
    pub fn table(&self) -> Result<Table, Error> {
        let columns = vec![
            Column::text("panel"),
            Column::number("voxels", NumberFormat::Integer),
            Column::number("build (ms)", NumberFormat::Fixed(1)),
            Column::number("render/frame (ms)", NumberFormat::Fixed(1)),
            Column::text("MSE mean (min–max)"),
            Column::text("SSIM mean (min–max)"),
        ];
        let mut table = Table::new(format!("turntable-{}", self.label), columns);
        for r in &self.panels {
            let sci = |s: &Option<Spread>| {
                s.map_or("—".into(), |s| format!("{:.2e} ({:.2e}–{:.2e})", s.mean, s.min, s.max))
            };
            table.push_row(vec![
                r.panel.clone().into(),
                r.voxels.map_or(voxlod_eval::report::Cell::Empty, |v| (v as f64).into()),
                r.build_ms.map_or(voxlod_eval::report::Cell::Empty, Into::into),
                r.render_ms.into(),
                sci(&r.mse).into(),
                r.ssim.map_or("—".into(), |s| s.display(4)).into(),
            ])?;
        }
        Ok(table)
    }

    /// Adds the animation (asset `name`) and the table to `report`.
    pub fn add_to_report(&self, report: &mut Report, name: &str) -> Result<(), Error> {
        let [w, h] = self.panel;
        let caption = format!(
            "{}: a turn in {} frames, {w}×{h} panels ({}), voxel panels at {}×{}×{}",
            self.label, self.frames, self.backend, self.dims[0], self.dims[1], self.dims[2]
        );
        report.animation(name, caption, self.animation.clone());
        report.text(
            "Error of each panel against the ground truth of the same frame, over the turn \
             (8-bit sRGB; SSIM after Wang et al. 2004).",
        );
        report.table(self.table()?);
        Ok(())
    }
}

/// Renders a turntable of `inputs` (see the [module docs](self)).
pub fn run(
    config: &TurntableConfig,
    inputs: &TurntableInputs<'_>,
    backend: Backend<'_>,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<TurntableResult, Error> {
    config.validate()?;
    let start = Instant::now();
    let TurntableInputs { scene, geometry, bvh, camera, label } = *inputs;
    camera.validate()?;
    let (lo, hi) = scene.bounds()?;
    let views = orbit_views(camera, (lo + hi) * 0.5, config.frames);
    let light = scene.light();
    let background = scene.background;
    let (width, height) = config.panel;
    let res = config.resolution;

    progress(&format!("{label}: turntable: voxelizing at {res}³"));
    let t = Instant::now();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res)?;
    let options = voxelize::Options { mode: Mode::Conservative, ..Default::default() };
    let vox = voxelize::voxelize(geometry, &grid, &options)?;
    let voxelize_time = t.elapsed();
    let t = Instant::now();
    let base = baseline::build(scene, geometry, &vox)?;
    let base_time = voxelize_time + t.elapsed();
    progress(&format!("{label}: turntable: Averages records ({} lines per voxel)", config.rays));
    let t = Instant::now();
    let ctx = SamplingContext::new(scene, geometry, &vox)?;
    let opts = PrecomputeOptions { rays: config.rays, seed: 0 };
    let avg = precompute(&ctx, &opts, averages::fit)?;
    let avg_time = voxelize_time + t.elapsed();
    drop(ctx);
    drop(vox);

    let gt_options = ground_truth::Options {
        width,
        height,
        spp: config.gt_spp,
        seed: config.seed,
        ambient: config.ambient,
        shadows: true,
        light_filter: None,
    };
    let base_options = baseline::Options { width, height, ambient: config.ambient, shadows: true };
    let avg_options = filtered::Options {
        width,
        height,
        ambient: config.ambient,
        shadows: true,
        ..Default::default()
    };

    // One renderer per panel, on the backend asked for.
    type Render<'r> = Box<dyn FnMut(&Camera) -> Result<Image, Error> + 'r>;
    let kernels = match backend {
        Backend::Cpu => None,
        Backend::Gpu(ctx) => Some(Kernels::new(ctx)?),
    };
    let mut renderers: Vec<Render<'_>> = Vec::with_capacity(3);
    let backend_name;
    match &kernels {
        None => {
            backend_name = "cpu".to_string();
            renderers.push(Box::new(|c: &Camera| {
                Ok(ground_truth::render(scene, geometry, bvh, c, &gt_options)?.image)
            }));
            renderers.push(Box::new(|c: &Camera| {
                Ok(baseline::render(&grid, &base, c, &light, background, &base_options)?)
            }));
            let mut cache = FrameCache::new(&avg)?;
            renderers.push(Box::new(move |c: &Camera| {
                Ok(filtered::render(&mut cache, c, &light, background, &avg_options)?)
            }));
        }
        Some(k) => {
            backend_name = k.name.clone();
            progress(&format!("{label}: turntable: uploading to {}", k.name));
            let gpu = k.upload_scene(scene, geometry, bvh, label)?;
            renderers.push(Box::new(move |c: &Camera| Ok(gpu.ground_truth(c, &gt_options)?.image)));
            let up = k.filtered.upload_baseline(&grid, &base)?;
            renderers.push(Box::new(move |c: &Camera| {
                Ok(k.filtered.render_baseline(&up, c, &light, background, &base_options)?)
            }));
            let up = k.filtered.upload_averages(&avg)?;
            renderers.push(Box::new(move |c: &Camera| {
                Ok(k.filtered.render(&up, c, &light, background, &avg_options)?)
            }));
        }
    }
    // Panel labels in the report font's ASCII (no superscripts).
    let names =
        ["ground truth".to_string(), format!("voxels {res}^3"), format!("Averages {res}^3")];

    let mut times = [Duration::ZERO; 3];
    let mut mse: [Vec<f64>; 2] = Default::default();
    let mut ssim: [Vec<f64>; 2] = Default::default();
    let mut frames = Vec::with_capacity(views.len());
    for (i, camera) in views.iter().enumerate() {
        progress(&format!("{label}: turntable frame {}/{}", i + 1, views.len()));
        let mut panels = Vec::with_capacity(3);
        for (p, render) in renderers.iter_mut().enumerate() {
            let t = Instant::now();
            let image = render(camera)?.to_srgb8();
            times[p] += t.elapsed();
            if p > 0 {
                let m = compare(&image, &panels[0])?;
                mse[p - 1].push(m.mse);
                ssim[p - 1].push(m.ssim);
            }
            panels.push(image);
        }
        let labelled = names.iter().zip(panels).map(|(n, img)| LabeledImage::new(n.clone(), img));
        frames.push(ImageGrid::new(3, labelled.collect()).compose()?);
    }
    drop(renderers);
    let n = views.len() as f64;
    let mut rows = vec![PanelRow {
        panel: names[0].clone(),
        voxels: None,
        build_ms: None,
        render_ms: ms(times[0]) / n,
        mse: None,
        ssim: None,
    }];
    for (p, (voxels, build)) in
        [(base.len(), base_time), (avg.records.len(), avg_time)].into_iter().enumerate()
    {
        rows.push(PanelRow {
            panel: names[p + 1].clone(),
            voxels: Some(voxels),
            build_ms: Some(ms(build)),
            render_ms: ms(times[p + 1]) / n,
            mse: Some(Spread::of(&mse[p])),
            ssim: Some(Spread::of(&ssim[p])),
        });
    }
    Ok(TurntableResult {
        label: label.to_string(),
        frames: views.len(),
        frame_ms: config.frame_ms,
        panel: [width, height],
        resolution: res,
        dims: grid.dims.to_array(),
        backend: backend_name,
        panels: rows,
        elapsed_s: start.elapsed().as_secs_f64(),
        animation: Animation::new(frames, config.frame_ms)?,
    })
}

#[cfg(test)]
mod tests;
