//! The slicemap study (Eisemann and Décoret 2006): what bitmask voxelization by rasterization
//! buys and loses against voxlod's exact voxelizers, and its two uses.
//!
//! - [`holes`]: the voxels and cells slicemaps miss (triangles seen edge-on, steep parts),
//!   aligned with a grid (one map per axis) against the exact conservative and thin
//!   voxelizers, and in perspective
//!   (uniform and local slicing) against the exact cells of the same map; the emulated
//!   conservative rasterization and the three-axis merge, each with its time.
//! - [`shadows`]: transmittance shadow maps on semi-transparent leaves against ray-traced
//!   transmittance (per-point error, shaded images, build and lookup time).
//! - [`refraction`]: the traversed volume of a closed object from front and back maps against
//!   exact ray-cast interval lengths, per slice count, and the refraction, attenuation and
//!   frosted-glass effects it drives beside the same effects with the exact thickness.
//!
//! Times are the median and range of each part's `repeats`. Every measured cell, transmittance
//! and thickness comes from the CPU reference; with [`Backend::Gpu`] every map is also built by
//! voxlod-gpu's render pipeline on that adapter, for its time (the equivalence suite and the
//! `slicemap_agreement` example show the maps are the same bit for bit on lavapipe). On a CPU
//! adapter (lavapipe) GPU-path times are CPU times of the render pipeline.

pub mod holes;
pub mod refraction;
pub mod shadows;

use std::time::Instant;

use serde::Serialize;
use voxlod_cpu::voxelize::slicemap::SliceCamera;
use voxlod_eval::report::{
    Cell, Column, ImageGrid, LabeledImage, NumberFormat, Plot, Report, Series, Table,
};
use voxlod_gpu::Context;
use voxlod_gpu::slicemap::SlicemapRenderer;
use voxlod_gpu::slicemap::query::SlicemapQueries;
use voxlod_scene::Scene;

use crate::Error;
use crate::backend::Backend;
pub use holes::HolesConfig;
pub use refraction::RefractionConfig;
pub use shadows::ShadowConfig;

/// Version of [`SlicemapResult::to_json`]'s layout.
pub const SCHEMA_VERSION: u32 = 1;

/// A time measured several times: median and range, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Timing {
    /// Median, ms.
    pub median_ms: f64,
    /// Fastest, ms.
    pub min_ms: f64,
    /// Slowest, ms.
    pub max_ms: f64,
}

impl Timing {
    /// Median and range of `ms` (zeros for none).
    pub fn of(ms: &[f64]) -> Self {
        if ms.is_empty() {
            return Timing::default();
        }
        let mut v = ms.to_vec();
        v.sort_by(f64::total_cmp);
        Timing { median_ms: v[v.len() / 2], min_ms: v[0], max_ms: v[v.len() - 1] }
    }

    /// `median (min–max)`, or just the median for one run.
    pub fn display(&self) -> String {
        if self.min_ms == self.max_ms {
            format!("{:.1}", self.median_ms)
        } else {
            format!("{:.1} ({:.1}–{:.1})", self.median_ms, self.min_ms, self.max_ms)
        }
    }
}

/// Runs `f` `repeats` times; the last value and the timing.
pub fn time<T>(
    repeats: u32,
    mut f: impl FnMut() -> Result<T, Error>,
) -> Result<(T, Timing), Error> {
    let mut ms = Vec::new();
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        last = Some(f()?);
        ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok((last.expect("at least one run"), Timing::of(&ms)))
}

/// A perspective map through the scene's camera, `width × height` columns, its depth range the
/// scene's bounding sphere.
pub fn framing_camera(scene: &Scene, width: u32, height: u32) -> Result<SliceCamera, Error> {
    let camera = scene.default_camera()?;
    let (lo, hi) = scene.bounds()?;
    let c = ((lo + hi) * 0.5).as_dvec3();
    let r = ((hi - lo).length() * 0.5) as f64;
    let forward = (camera.target - camera.eye).as_dvec3().normalize_or_zero();
    let depth = (c - camera.eye.as_dvec3()).dot(forward);
    let far = (depth + r) * 1.001;
    let near = (depth - r).max(far * 1e-3);
    Ok(SliceCamera::from_camera(&camera, width, height, near, far))
}

/// The study's parts; `None` leaves a part out.
#[derive(Clone, Debug, PartialEq)]
pub struct SlicemapConfig {
    /// Holes against the exact voxelizers.
    pub holes: Option<HolesConfig>,
    /// Transmittance shadow maps.
    pub shadows: Option<ShadowConfig>,
    /// Traversed volume for refraction.
    pub refraction: Option<RefractionConfig>,
}

/// One tree with untextured 6 cm leaves in tufts of 4 (their shape is their geometry, which
/// both the slicemap and the ray tracer see; leaves larger than a map column, layered).
pub const QUICK_FOREST: &str =
    "builtin:forest?alpha=false&trees=1&leaves=12000&leaf_size=0.06&cluster=4";
/// Three such trees, denser.
pub const FULL_FOREST: &str =
    "builtin:forest?alpha=false&trees=3&leaves=40000&leaf_size=0.06&cluster=4";

impl SlicemapConfig {
    /// Minutes on two cores: the bunny and a small forest, small images, one run per time.
    pub fn quick() -> Self {
        SlicemapConfig {
            holes: Some(HolesConfig {
                scenes: vec!["builtin:bunny".into(), QUICK_FOREST.into()],
                resolution: 128,
                map_size: 256,
                slices: vec![32, 128, 512],
                repeats: 1,
            }),
            shadows: Some(ShadowConfig {
                scene: QUICK_FOREST.into(),
                transmissive: "leaves".into(),
                width: 256,
                height: 192,
                spp: 4,
                maps: vec![(512, 32), (512, 96), (512, 512), (1024, 96), (2048, 96)],
                sigma: 0.3,
                bias_pixels: 1.5,
                ambient: 0.15,
                repeats: 1,
            }),
            refraction: Some(RefractionConfig {
                scene: "builtin:bunny".into(),
                width: 256,
                height: 256,
                slices: vec![32, 64, 128, 256, 512],
                shown_slices: 32,
                views: 3,
                bend: 0.6,
                absorption: 1.5,
                blur: 0.4,
                checker: 16,
                repeats: 1,
            }),
        }
    }

    /// The paper's sizes (512² maps, up to 512 slices), the engine among the scenes, three runs
    /// per time.
    pub fn full() -> Self {
        let mut c = Self::quick();
        if let Some(h) = &mut c.holes {
            h.scenes = vec!["builtin:bunny".into(), "builtin:engine".into(), FULL_FOREST.into()];
            h.resolution = 256;
            h.map_size = 512;
            h.slices = vec![32, 96, 256, 512];
            h.repeats = 3;
        }
        if let Some(s) = &mut c.shadows {
            s.scene = FULL_FOREST.into();
            s.width = 512;
            s.height = 384;
            s.spp = 16;
            s.maps = vec![(512, 32), (512, 96), (512, 256), (512, 512), (1024, 96), (2048, 96)];
            s.repeats = 3;
        }
        if let Some(r) = &mut c.refraction {
            r.width = 512;
            r.height = 512;
            r.repeats = 3;
        }
        c
    }

    /// Checks every field of every part against its range (an [`Error::InvalidConfig`] naming
    /// it): scenes given, slices in 1..=512, sizes in 1..=4096, σ in [0, 1], rays per pixel
    /// and image sizes positive.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "slicemap", field, value, expected })
        };
        let slices_ok = |s: &[u32]| !s.is_empty() && s.iter().all(|&n| (1..=512).contains(&n));
        let side_ok = |n: u32| (1..=4096).contains(&n);
        if let Some(h) = &self.holes {
            if h.scenes.is_empty() {
                return bad("holes.scenes", "[]".into(), "at least one scene");
            }
            if !(1..=512).contains(&h.resolution) {
                return bad("holes.resolution", h.resolution.to_string(), "1..=512 voxels");
            }
            if !side_ok(h.map_size) {
                return bad("holes.map_size", h.map_size.to_string(), "1..=4096 columns");
            }
            if !slices_ok(&h.slices) {
                return bad("holes.slices", format!("{:?}", h.slices), "counts in 1..=512");
            }
        }
        if let Some(s) = &self.shadows {
            if s.maps.is_empty()
                || !s.maps.iter().all(|&(n, k)| side_ok(n) && (1..=512).contains(&k))
            {
                return bad(
                    "shadows.maps",
                    format!("{:?}", s.maps),
                    "(size in 1..=4096, slices in 1..=512) pairs",
                );
            }
            if !(0.0..=1.0).contains(&s.sigma) {
                return bad("shadows.sigma", s.sigma.to_string(), "an attenuation in [0, 1]");
            }
            if s.width == 0 || s.height == 0 || s.spp == 0 {
                return bad(
                    "shadows image",
                    format!("{}×{}, {} spp", s.width, s.height, s.spp),
                    "positive sizes and rays per pixel",
                );
            }
            if !(s.bias_pixels >= 0.0 && s.bias_pixels.is_finite()) {
                return bad("shadows.bias_pixels", s.bias_pixels.to_string(), "a finite bias ≥ 0");
            }
        }
        if let Some(r) = &self.refraction {
            if !slices_ok(&r.slices) {
                return bad("refraction.slices", format!("{:?}", r.slices), "counts in 1..=512");
            }
            if r.views == 0 {
                return bad("refraction.views", "0".into(), "at least one view");
            }
            if !side_ok(r.width) || !side_ok(r.height) {
                return bad(
                    "refraction image",
                    format!("{}×{}", r.width, r.height),
                    "sides in 1..=4096",
                );
            }
        }
        Ok(())
    }

    /// Every part on one scene (the command line's `voxlod slicemap SCENE`).
    pub fn for_scene(mut self, spec: &str) -> Self {
        if let Some(h) = &mut self.holes {
            h.scenes = vec![spec.into()];
        }
        if let Some(s) = &mut self.shadows {
            s.scene = spec.into();
        }
        if let Some(r) = &mut self.refraction {
            r.scene = spec.into();
        }
        self
    }
}

/// Everything the study measured.
#[derive(Clone, Debug)]
pub struct SlicemapResult {
    /// The GPU path's adapter, if one was used.
    pub adapter: Option<String>,
    /// Whether that adapter is a CPU implementation (its times are CPU times).
    pub adapter_is_cpu: bool,
    /// Holes.
    pub holes: Option<holes::HolesResult>,
    /// Shadows.
    pub shadows: Option<shadows::ShadowResult>,
    /// Refraction.
    pub refraction: Option<refraction::RefractionResult>,
}

/// Runs the configured parts, the slicemaps also on the adapter of a GPU `backend` (module
/// docs). Errors on an invalid configuration ([`SlicemapConfig::validate`]) or any error of the
/// scenes, maps and renders.
pub fn run(
    config: &SlicemapConfig,
    backend: Backend<'_>,
    progress: &dyn Fn(&str),
) -> Result<SlicemapResult, Error> {
    config.validate()?;
    let gpu = match backend {
        Backend::Cpu => None,
        Backend::Gpu(ctx) => Some(ctx),
    };
    let renderer = gpu.map(SlicemapRenderer::new).transpose()?;
    let queries = gpu.map(SlicemapQueries::new).transpose()?;
    let holes =
        config.holes.as_ref().map(|c| holes::run(c, renderer.as_ref(), progress)).transpose()?;
    let shadows = config
        .shadows
        .as_ref()
        .map(|c| shadows::run(c, renderer.as_ref(), progress))
        .transpose()?;
    let both = renderer.as_ref().zip(queries.as_ref());
    let refraction =
        config.refraction.as_ref().map(|c| refraction::run(c, both, progress)).transpose()?;
    Ok(SlicemapResult {
        adapter: gpu.map(Context::label),
        adapter_is_cpu: gpu.is_some_and(Context::is_cpu),
        holes,
        shadows,
        refraction,
    })
}

fn ms(t: &Option<Timing>) -> Cell {
    t.as_ref().map_or(Cell::Empty, |t| Cell::Text(t.display()))
}

fn percent(part: u64, whole: u64) -> Cell {
    if whole == 0 { Cell::Empty } else { Cell::Number(100.0 * part as f64 / whole as f64) }
}

fn grid(images: &[(String, voxlod_scene::Srgb8Image)], columns: u32) -> ImageGrid {
    ImageGrid::new(
        columns,
        images.iter().map(|(l, i)| LabeledImage::new(l.clone(), i.clone())).collect(),
    )
}

impl SlicemapResult {
    /// The study's tables: holes (aligned, perspective), shadows, thickness, effects.
    pub fn tables(&self) -> Result<Vec<Table>, Error> {
        use NumberFormat::{Fixed, Integer, Scientific};
        let mut out = Vec::new();
        if let Some(h) = &self.holes {
            let mut t = Table::new(
                "slicemap holes, aligned with the grid",
                vec![
                    Column::text("scene"),
                    Column::text("method"),
                    Column::number("voxels", Integer),
                    Column::number("missed conservative voxels", Integer),
                    Column::number("missed (%)", Fixed(2)),
                    Column::number("missed thin voxels", Integer),
                    Column::number("missed thin (%)", Fixed(2)),
                    Column::number("extra voxels", Integer),
                    Column::text("CPU ms"),
                    Column::text("GPU-path ms"),
                ],
            );
            let reference = |scene: &str, method: &str| {
                h.aligned
                    .iter()
                    .find(|r| r.scene == scene && r.method == method)
                    .map_or(0, |r| r.voxels)
            };
            for r in &h.aligned {
                let cons = reference(&r.scene, "exact conservative voxelizer");
                let thin = reference(&r.scene, "exact thin voxelizer");
                t.push_row(vec![
                    r.scene.as_str().into(),
                    r.method.as_str().into(),
                    Cell::Number(r.voxels as f64),
                    Cell::Number(r.missed_conservative as f64),
                    percent(r.missed_conservative, cons),
                    Cell::Number(r.missed_thin as f64),
                    percent(r.missed_thin, thin),
                    Cell::Number(r.extra as f64),
                    ms(&Some(r.cpu_ms)),
                    ms(&r.gpu_ms),
                ])?;
            }
            out.push(t);
            let mut t = Table::new(
                "slicemap holes in perspective, against the exact cells of the same map",
                vec![
                    Column::text("scene"),
                    Column::text("slicing"),
                    Column::number("slices", Integer),
                    Column::number("exact cells", Integer),
                    Column::number("set cells", Integer),
                    Column::number("missed", Integer),
                    Column::number("missed (%)", Fixed(2)),
                    Column::number("extra", Integer),
                    Column::number("columns", Integer),
                    Column::number("columns missed", Integer),
                    Column::text("CPU ms, standard"),
                    Column::text("CPU ms, exact"),
                    Column::text("GPU-path ms, standard"),
                    Column::text("GPU-path ms, conservative"),
                ],
            );
            for r in &h.cells {
                t.push_row(vec![
                    r.scene.as_str().into(),
                    r.slicing.as_str().into(),
                    Cell::Number(r.slices as f64),
                    Cell::Number(r.cells.exact as f64),
                    Cell::Number(r.cells.set as f64),
                    Cell::Number(r.cells.missed as f64),
                    percent(r.cells.missed, r.cells.exact),
                    Cell::Number(r.cells.extra as f64),
                    Cell::Number(r.cells.columns as f64),
                    Cell::Number(r.cells.columns_missed as f64),
                    ms(&Some(r.standard_ms)),
                    ms(&Some(r.exact_ms)),
                    ms(&r.gpu_standard_ms),
                    ms(&r.gpu_conservative_ms),
                ])?;
            }
            out.push(t);
        }
        if let Some(s) = &self.shadows {
            let mut t = Table::new(
                "transmittance shadow maps against ray-traced transmittance",
                vec![
                    Column::text("method"),
                    Column::number("opaque differs (%)", Fixed(2)),
                    Column::number("layers differ (%)", Fixed(2)),
                    Column::number("mean |ΔT|", Scientific(2)),
                    Column::number("RMSE T", Scientific(2)),
                    Column::number("max |ΔT|", Fixed(3)),
                    Column::number("image MSE", Scientific(2)),
                    Column::number("image SSIM", Fixed(4)),
                    Column::text("build CPU ms"),
                    Column::text("build GPU-path ms"),
                    Column::text("lookups ms"),
                    Column::number("maps (MiB)", Fixed(2)),
                ],
            );
            for r in &s.rows {
                t.push_row(vec![
                    r.method.as_str().into(),
                    r.opaque_mismatch.map_or(Cell::Empty, |f| Cell::Number(100.0 * f)),
                    r.count_mismatch.map_or(Cell::Empty, |f| Cell::Number(100.0 * f)),
                    Cell::Number(r.mean_abs_error),
                    Cell::Number(r.rmse),
                    Cell::Number(r.max_abs_error),
                    Cell::Number(r.image.mse),
                    Cell::Number(r.image.ssim),
                    ms(&r.build_ms),
                    ms(&r.gpu_build_ms),
                    ms(&Some(r.lookup_ms)),
                    Cell::Number(r.memory_bytes as f64 / (1 << 20) as f64),
                ])?;
            }
            out.push(t);
        }
        if let Some(r) = &self.refraction {
            let mut t = Table::new(
                "traversed volume against ray-cast in/out intervals",
                vec![
                    Column::text("method"),
                    Column::number("mean |ΔL|", Scientific(2)),
                    Column::number("mean |ΔL| / mean L (%)", Fixed(2)),
                    Column::number("p95 |ΔL|", Scientific(2)),
                    Column::number("max |ΔL|", Scientific(2)),
                    Column::number("pixels off by > 1 slice (%)", Fixed(2)),
                    Column::text("CPU ms"),
                    Column::text("GPU-path ms"),
                ],
            );
            for row in &r.thickness {
                t.push_row(vec![
                    row.method.as_str().into(),
                    Cell::Number(row.mean_abs_error),
                    Cell::Number(100.0 * row.relative_error),
                    Cell::Number(row.p95_abs_error),
                    Cell::Number(row.max_abs_error),
                    row.over_one_slice.map_or(Cell::Empty, |f| Cell::Number(100.0 * f)),
                    if row.slices.is_some() { ms(&Some(row.cpu_ms)) } else { Cell::Empty },
                    ms(&row.gpu_ms),
                ])?;
            }
            out.push(t);
            let mut t = Table::new(
                "refraction effects against the same effects with the exact thickness",
                vec![
                    Column::text("effect"),
                    Column::text("method"),
                    Column::number("MSE", Scientific(2)),
                    Column::number("PSNR (dB)", Fixed(1)),
                    Column::number("SSIM", Fixed(4)),
                ],
            );
            for e in &r.effects {
                t.push_row(vec![
                    e.effect.as_str().into(),
                    e.method.as_str().into(),
                    Cell::Number(e.image.mse),
                    Cell::Number(e.image.psnr),
                    Cell::Number(e.image.ssim),
                ])?;
            }
            out.push(t);
        }
        Ok(out)
    }

    /// Adds the study's sections (text, tables, images, plots) to `report`.
    pub fn add_to_report(&self, report: &mut Report) -> Result<(), Error> {
        report.heading(2, "Slicemaps (Eisemann and Décoret 2006)");
        let adapter = match (&self.adapter, self.adapter_is_cpu) {
            (Some(a), true) => format!(
                "GPU-path times on {a}, a CPU implementation of Vulkan: they are CPU times of the \
                 render pipeline, not GPU speed."
            ),
            (Some(a), false) => format!("GPU-path times on {a}."),
            (None, _) => "No GPU path was run.".into(),
        };
        report.text(format!(
            "Times are the median (and range) of the configured runs. {adapter} Standard \
             rasterization is the hardware's rule (pixel centres, top-left rule, 8 sub-pixel \
             bits, one depth per fragment); conservative is its emulation with the depth range \
             of the triangle over each pixel, which sets every cell a triangle meets."
        ));
        let mut tables = self.tables()?.into_iter();
        if let Some(h) = &self.holes {
            report.heading(3, "Holes");
            report.table(tables.next().expect("aligned table"));
            report.table(tables.next().expect("perspective table"));
            let mut images = Vec::new();
            for (label, cells, missed) in &h.images {
                images.push((format!("exact, {label}"), cells.clone()));
                images.push((format!("missed, {label}"), missed.clone()));
            }
            let scenes: Vec<&str> = {
                let mut s: Vec<&str> = h.cells.iter().map(|r| r.scene.as_str()).collect();
                s.dedup();
                s
            };
            report.images(
                "slicemap-holes",
                format!(
                    "Per scene ({}), the perspective uniform map: exact cells per column (grey) \
                     and the share of them the standard map misses (heat: blue none, red all).",
                    scenes.join(", ")
                ),
                grid(&images, 2),
            );
            let mut plot = Plot {
                title: "cells missed against slices".into(),
                x_label: "slices".into(),
                y_label: "missed cells (%)".into(),
                log_x: true,
                ..Plot::default()
            };
            let mut keys: Vec<(String, String)> =
                h.cells.iter().map(|r| (r.scene.clone(), r.slicing.clone())).collect();
            keys.dedup();
            for (scene, slicing) in keys {
                let points = h
                    .cells
                    .iter()
                    .filter(|r| r.scene == scene && r.slicing == slicing && r.cells.exact > 0)
                    .map(|r| {
                        (r.slices as f64, 100.0 * r.cells.missed as f64 / r.cells.exact as f64)
                    })
                    .collect();
                plot.series.push(Series::new(format!("{scene}, {slicing}"), points));
            }
            report.plot("slicemap-holes-plot", plot);
        }
        if let Some(s) = &self.shadows {
            report.heading(3, "Transmittance shadow maps");
            report.text(format!(
                "{}: {} of {} triangles semi-transparent; {} camera hit points compared.",
                s.scene, s.transmissive.0, s.transmissive.1, s.points
            ));
            report.table(tables.next().expect("shadow table"));
            report.images("slicemap-shadows", "Shaded with each transmittance (shadow rays off, the transmittance as the light filter).", grid(&s.images, 3));
        }
        if let Some(r) = &self.refraction {
            report.heading(3, "Traversed volume for refraction");
            let closed = if r.boundary_edges == 0 {
                "closed".to_string()
            } else {
                format!(
                    "NOT closed ({} boundary edges: the traversed volume is ill-defined)",
                    r.boundary_edges
                )
            };
            report.text(format!(
                "{} ({closed}): {} pixels over {} views see it, mean exact thickness {:.4}; \
             images of the first view, effect metrics averaged over the views.",
                r.scene, r.pixels, r.views, r.mean_thickness
            ));
            report.table(tables.next().expect("thickness table"));
            report.table(tables.next().expect("effects table"));
            let mut plot = Plot {
                title: "thickness error against slices".into(),
                x_label: "slices".into(),
                y_label: "mean |ΔL| / mean L (%)".into(),
                log_x: true,
                log_y: true,
                ..Plot::default()
            };
            let sliced: Vec<(f64, f64)> = r
                .thickness
                .iter()
                .filter_map(|t| t.slices.map(|n| (n as f64, 100.0 * t.relative_error)))
                .collect();
            if let Some(two) = r.thickness.iter().find(|t| t.slices.is_none()) {
                let ends = [sliced.first(), sliced.last()];
                let points =
                    ends.iter().flatten().map(|p| (p.0, 100.0 * two.relative_error)).collect();
                plot.series.push(Series::new("two depth maps", points));
            }
            plot.series.push(Series::new("slicemap (front/back, local)", sliced));
            report.plot("slicemap-thickness-plot", plot);
            report.images("slicemap-refraction", "Thickness (grey, same scale) and the three effects with the exact thickness, the slicemap's and two depth maps'.", grid(&r.images, 4));
        }
        Ok(())
    }

    /// Every row as JSON, with [`SCHEMA_VERSION`].
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "schema_version": SCHEMA_VERSION,
            "adapter": self.adapter,
            "adapter_is_cpu": self.adapter_is_cpu,
            "holes": self.holes.as_ref().map(|h| serde_json::json!({
                "aligned": h.aligned,
                "perspective": h.cells,
            })),
            "shadows": self.shadows.as_ref().map(|s| serde_json::json!({
                "scene": s.scene,
                "transmissive_triangles": s.transmissive.0,
                "triangles": s.transmissive.1,
                "points": s.points,
                "rows": s.rows,
            })),
            "refraction": self.refraction.as_ref().map(|r| serde_json::json!({
                "scene": r.scene,
                "boundary_edges": r.boundary_edges,
                "pixels": r.pixels,
                "views": r.views,
                "mean_thickness": r.mean_thickness,
                "thickness": r.thickness,
                "effects": r.effects,
            })),
        })
    }
}

#[cfg(test)]
mod tests;
