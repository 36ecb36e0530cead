//! Dynamic scenes by voxel transformation (Yalçıner and Sahillioğlu 2020, "Voxel transformation:
//! scalable scene geometry discretization for global illumination", J. Real-Time Image
//! Processing 17(5), §3 and §4.1–4.2): moving objects voxelized once into object-space caches
//! whose voxels are moved every frame — nearest or 8-neighbour, rigid or skinned — against
//! re-voxelizing the moved triangles every frame, on an animated scene (`builtin:crowd` by
//! default). What it measures:
//!
//! - **Caches**: voxels and bytes per object voxel, build time ([`CacheRow`]).
//! - **Agreement** ([`agreement`]): at each time, per class of objects (skinned walkers, rigid
//!   objects, all), per voxelizer (the caches' and the reference's: conservative or thin) and
//!   filter: occupancy IoU, missing and extra voxels, colour error against the
//!   re-voxelization of the posed meshes (records from the same source); and the cone-traced
//!   AO and indirect light of each method's octree (static voxels included) against ray-traced
//!   references of the posed mesh (MSE, SSIM on 8-bit sRGB).
//! - **Rotations**: one rigid object turned in place by exactly 45° about x, y and z (where
//!   nearest sampling leaves holes) and two other angles.
//! - **Temporal stability** ([`stability`]): frame-to-frame change of the AO a slowly moving
//!   object casts on the floor, per method, against the ray-traced truth.
//! - **Scaling** ([`scaling`]): time per frame against object count (1 … 256 walkers and as
//!   many rigid objects): the transform alone against voxelizing the moved triangles alone
//!   (conservative and thin), and whole frames of both; peak and transient memory.
//! - **Frames** ([`frames`]): a frame sequence through the whole pipeline on the chosen
//!   backend (on the GPU the whole frame runs on the device).
//!
//! Times are wall-clock on the machine the report names, shared with other work: each is the
//! mean of [`ScalingConfig::repeats`] runs with their range.

pub mod agreement;
pub mod frames;
pub mod scaling;
mod setup;
pub mod stability;

use serde::Serialize;
use voxlod_cpu::dynamic::{CacheOptions, ObjectKind, RecordSource};
use voxlod_cpu::voxelize::Mode;
use voxlod_eval::report::{
    Cell, Column, ImageGrid, LabeledImage, NumberFormat, Plot, Report, Series, Table,
};
use voxlod_octree::BuildOptions;

pub use agreement::{AgreementRow, ImageRow, RotationRow};
pub use frames::FrameRow;
pub use scaling::ScalingRow;
pub use setup::swept_bounds;
pub use stability::StabilityRow;

use crate::Error;
use crate::backend::Backend;

/// The scaling part's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalingConfig {
    /// Walker counts of `builtin:crowd` (each with as many rigid objects), in 1..=256.
    pub walkers: Vec<u32>,
    /// World voxel edge, metres (the walkers are 1.85 tall), in (0, 1].
    pub voxel_size: f32,
    /// Runs per measurement (≥ 1).
    pub repeats: u32,
}

/// The stability part's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StabilityConfig {
    /// Frames of the sequence (2..=256).
    pub frames: u32,
    /// Translation per frame, voxels, in [0, 4].
    pub voxels_per_frame: f32,
    /// Rotation per frame, degrees, in [0, 45].
    pub degrees_per_frame: f32,
}

/// What the dynamic study measures. [`DynamicConfig::quick`] is `voxlod dynamic` with its
/// defaults (a few minutes on two cores); [`DynamicConfig::full`] samples more times, both
/// thresholds, 256 walkers and references at 256 rays per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicConfig {
    /// An animated scene spec ([`crate::scenes::load`]): its first animation moves it.
    pub scene: String,
    /// World voxel edge (world units), > 0.
    pub voxel_size: f32,
    /// Voxelizers of the caches and of the re-voxelization they are compared with.
    pub voxelizers: Vec<Mode>,
    /// Where the caches' and the references' records come from.
    pub records: RecordSource,
    /// Animation times measured (seconds, finite).
    pub times: Vec<f32>,
    /// Occupancy thresholds measured (covered volume in [0, 8] voxels).
    pub thresholds: Vec<f32>,
    /// Image width, pixels (height ¾ of it), in 8..=1024.
    pub image_width: u32,
    /// Rays per pixel of the references (≥ 1).
    pub spp: u32,
    /// AO radius, world units, > 0.
    pub ao_radius: f32,
    /// Whether to measure the rotations.
    pub rotations: bool,
    /// The stability part (None: not measured).
    pub stability: Option<StabilityConfig>,
    /// The scaling part (None: not measured).
    pub scaling: Option<ScalingConfig>,
    /// Frames of the sequence rendered through the pipeline (0: none).
    pub frames: u32,
}

impl DynamicConfig {
    /// Four walkers and four rigid objects at 5 cm voxels, both voxelizers, Averages records
    /// of 32 lines, two times, threshold ½, 96-pixel images with 64-ray references, the
    /// rotations, 12 stability frames, scaling over 1, 4, 16 and 64 walkers at 10 cm voxels
    /// (3 runs each), 4 frames.
    pub fn quick() -> Self {
        Self {
            scene: "builtin:crowd?walkers=4&rigid=4".into(),
            voxel_size: 0.05,
            voxelizers: vec![Mode::Conservative, Mode::Thin],
            records: RecordSource::Rays { rays: 32, seed: 0 },
            times: vec![0.37, 1.12],
            thresholds: vec![0.5],
            image_width: 96,
            spp: 64,
            ao_radius: 0.5,
            rotations: true,
            stability: Some(StabilityConfig {
                frames: 12,
                voxels_per_frame: 0.1,
                degrees_per_frame: 0.5,
            }),
            scaling: Some(ScalingConfig {
                walkers: vec![1, 4, 16, 64],
                voxel_size: 0.1,
                repeats: 3,
            }),
            frames: 4,
        }
    }

    /// [`DynamicConfig::quick`] with six times, thresholds ¼ and ½, 160-pixel images with
    /// 256-ray references, 32 stability frames, scaling up to 256 walkers (5 runs), 8 frames.
    pub fn full() -> Self {
        Self {
            times: vec![0.12, 0.37, 0.62, 0.87, 1.12, 1.37],
            thresholds: vec![0.25, 0.5],
            image_width: 160,
            spp: 256,
            stability: Some(StabilityConfig {
                frames: 32,
                voxels_per_frame: 0.1,
                degrees_per_frame: 0.5,
            }),
            scaling: Some(ScalingConfig {
                walkers: vec![1, 4, 16, 64, 256],
                voxel_size: 0.1,
                repeats: 5,
            }),
            frames: 8,
            ..Self::quick()
        }
    }

    /// Checks every field (named in the error).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "dynamic", field, value, expected })
        };
        if !(self.voxel_size.is_finite() && self.voxel_size > 0.0) {
            return bad("voxel_size", self.voxel_size.to_string(), "finite and > 0");
        }
        if self.voxelizers.is_empty() || self.voxelizers.contains(&Mode::Solid) {
            return bad("voxelizers", format!("{:?}", self.voxelizers), "conservative and/or thin");
        }
        if let Some(t) = self.times.iter().find(|t| !t.is_finite()) {
            return bad("times", t.to_string(), "finite seconds");
        }
        if let Some(t) =
            self.thresholds.iter().find(|t| !(t.is_finite() && (0.0..=8.0).contains(*t)))
        {
            return bad("thresholds", t.to_string(), "a covered volume in [0, 8] voxels");
        }
        if self.thresholds.is_empty() && !self.times.is_empty() {
            return bad("thresholds", "[]".into(), "at least one threshold");
        }
        if !(8..=1024).contains(&self.image_width) {
            return bad("image_width", self.image_width.to_string(), "in 8..=1024");
        }
        if self.spp == 0 {
            return bad("spp", "0".into(), "at least 1");
        }
        if !(self.ao_radius.is_finite() && self.ao_radius > 0.0) {
            return bad("ao_radius", self.ao_radius.to_string(), "finite and > 0");
        }
        if let RecordSource::Rays { rays: 0, .. } = self.records {
            return bad("records", "0 rays".into(), "at least one line per voxel");
        }
        if let Some(s) = &self.stability {
            if !(2..=256).contains(&s.frames) {
                return bad("stability.frames", s.frames.to_string(), "in 2..=256");
            }
            if !(0.0..=4.0).contains(&s.voxels_per_frame) {
                return bad(
                    "stability.voxels_per_frame",
                    s.voxels_per_frame.to_string(),
                    "in [0, 4]",
                );
            }
            if !(0.0..=45.0).contains(&s.degrees_per_frame) {
                return bad(
                    "stability.degrees_per_frame",
                    s.degrees_per_frame.to_string(),
                    "in [0, 45]",
                );
            }
        }
        if let Some(s) = &self.scaling {
            if s.walkers.is_empty() || s.walkers.iter().any(|w| !(1..=256).contains(w)) {
                return bad("scaling.walkers", format!("{:?}", s.walkers), "counts in 1..=256");
            }
            if !(s.voxel_size.is_finite() && s.voxel_size > 0.0 && s.voxel_size <= 1.0) {
                return bad("scaling.voxel_size", s.voxel_size.to_string(), "in (0, 1] metres");
            }
            if s.repeats == 0 {
                return bad("scaling.repeats", "0".into(), "at least 1");
            }
        }
        if self.frames > 256 {
            return bad("frames", self.frames.to_string(), "at most 256");
        }
        Ok(())
    }
}

/// One object's cache.
#[derive(Clone, Debug, Serialize)]
pub struct CacheRow {
    /// The object.
    pub object: String,
    /// `rigid` or `skinned`.
    pub kind: String,
    /// The voxelizer it was built with.
    pub voxelizer: String,
    /// Cached voxels.
    pub voxels: u64,
    /// Object grid, voxels per axis.
    pub grid: [u32; 3],
    /// Bytes per cached voxel (position, record, skin).
    pub bytes_per_voxel: u64,
    /// Build time (voxelization, records, skin weights), ms.
    pub build_ms: f64,
}

/// Everything the dynamic study measured.
#[derive(Serialize)]
pub struct DynamicResult {
    /// The scene spec.
    pub scene: String,
    /// Where the frame sequence and the scaling part's GPU column ran.
    pub backend: String,
    /// The machine the times were measured on (CPU model, cores, OS).
    pub machine: String,
    /// The world grid of the agreement part, voxels per axis.
    pub grid: [u32; 3],
    /// Its voxel edge, world units.
    pub voxel_size: f64,
    /// The records' source.
    pub records: String,
    /// One row per object and voxelizer.
    pub caches: Vec<CacheRow>,
    /// Occupancy and colour agreement.
    pub agreement: Vec<AgreementRow>,
    /// Cone-traced images against the references.
    pub images: Vec<ImageRow>,
    /// Exact rotations.
    pub rotations: Vec<RotationRow>,
    /// Temporal stability.
    pub stability: Vec<StabilityRow>,
    /// Time per frame against object count.
    pub scaling: Vec<ScalingRow>,
    /// The frame sequence.
    pub frames: Vec<FrameRow>,
    #[serde(skip)]
    image_sets: Vec<agreement::ImageSet>,
    #[serde(skip)]
    frame_images: Vec<(String, voxlod_scene::Srgb8Image, voxlod_scene::Srgb8Image)>,
}

/// `conservative`/`thin`.
fn mode_label(m: Mode) -> String {
    agreement::mode_name(m).into()
}

/// Runs the study (module docs). The frame sequence and the scaling part's GPU column run on
/// `backend`; everything else on the CPU reference.
pub fn run(
    config: &DynamicConfig,
    backend: Backend<'_>,
    say: &dyn Fn(&str),
) -> Result<DynamicResult, Error> {
    config.validate()?;
    let mut prepared = Vec::new();
    for &mode in &config.voxelizers {
        say(&format!(
            "loading '{}' and building its {} caches",
            config.scene,
            agreement::mode_name(mode)
        ));
        let mut scene = crate::scenes::load(&config.scene)?;
        scene.name = config.scene.clone();
        let options = CacheOptions { mode, records: config.records };
        prepared.push((mode, setup::prepare(scene, config.voxel_size as f64, &options)?));
    }
    let first = &prepared[0].1;
    let mut caches = Vec::new();
    for (mode, p) in &prepared {
        for (o, c) in p.caches.iter().enumerate() {
            caches.push(CacheRow {
                object: c.name.clone(),
                kind: match p.ds.objects[o].kind {
                    ObjectKind::Rigid { .. } => "rigid".into(),
                    ObjectKind::Skinned { .. } => "skinned".into(),
                },
                voxelizer: mode_label(*mode),
                voxels: c.len() as u64,
                grid: c.grid.dims.to_array(),
                bytes_per_voxel: c.bytes_per_voxel() as u64,
                build_ms: p.cache_ms[o],
            });
        }
    }
    let settings = agreement::AgreementSettings {
        times: &config.times,
        thresholds: &config.thresholds,
        records: config.records,
        image_width: config.image_width,
        spp: config.spp,
        ao_radius: config.ao_radius,
        build: BuildOptions::default(),
    };
    let agreement::Agreement { rows: agreement_rows, images: image_rows, sets: image_sets } =
        agreement::run(&prepared, &settings, say)?;
    let rotations = if config.rotations {
        agreement::rotation_rows(
            &prepared,
            &CacheOptions { records: config.records, ..Default::default() },
            say,
        )?
    } else {
        Vec::new()
    };
    let stability = match &config.stability {
        Some(s) => stability::run(
            &prepared,
            &stability::StabilitySettings {
                frames: s.frames,
                voxels_per_frame: s.voxels_per_frame as f64,
                degrees_per_frame: s.degrees_per_frame as f64,
                image_width: config.image_width,
                spp: config.spp,
                ao_radius: config.ao_radius,
                records: config.records,
            },
            say,
        )?,
        None => Vec::new(),
    };
    let scaling = match &config.scaling {
        Some(s) => scaling::run(
            &scaling::ScalingSettings {
                walkers: &s.walkers,
                voxel_size: s.voxel_size as f64,
                repeats: s.repeats,
                image_width: 64,
                time: 0.37,
            },
            backend,
            say,
        )?,
        None => Vec::new(),
    };
    let sequence = if config.frames > 0 {
        Some(frames::run(first, config.frames, config.image_width, config.ao_radius, backend, say)?)
    } else {
        None
    };
    Ok(DynamicResult {
        scene: config.scene.clone(),
        backend: backend.describe(),
        machine: crate::machine::describe(),
        grid: first.grid.dims.to_array(),
        voxel_size: first.grid.voxel_size,
        records: match config.records {
            RecordSource::Rays { rays, seed } => {
                format!("Averages, {rays} lines per voxel (seed {seed})")
            }
            RecordSource::Pieces => "fragment averages of the triangle pieces".into(),
        },
        caches,
        agreement: agreement_rows,
        images: image_rows,
        rotations,
        stability,
        scaling,
        frames: sequence.as_ref().map(|s| s.rows.clone()).unwrap_or_default(),
        image_sets,
        frame_images: sequence.map(|s| s.images).unwrap_or_default(),
    })
}

fn num(name: &str, f: NumberFormat) -> Column {
    Column::number(name, f)
}

fn spread_cell(s: &crate::Spread) -> Cell {
    Cell::Text(s.display(if s.mean < 10.0 { 2 } else { 0 }))
}

impl DynamicResult {
    /// The study's tables: caches, agreement, images, rotations, stability, scaling, frames.
    pub fn tables(&self) -> Result<Vec<Table>, Error> {
        let mut out = Vec::new();
        let mut t = Table::new(
            "voxel caches (built once per object)",
            vec![
                Column::text("object"),
                Column::text("kind"),
                Column::text("voxelizer"),
                num("voxels", NumberFormat::Integer),
                Column::text("grid"),
                num("bytes/voxel", NumberFormat::Integer),
                num("build ms", NumberFormat::Significant(3)),
            ],
        );
        for r in &self.caches {
            t.push_row(vec![
                Cell::Text(r.object.clone()),
                Cell::Text(r.kind.clone()),
                Cell::Text(r.voxelizer.clone()),
                Cell::Number(r.voxels as f64),
                Cell::Text(format!("{}×{}×{}", r.grid[0], r.grid[1], r.grid[2])),
                Cell::Number(r.bytes_per_voxel as f64),
                Cell::Number(r.build_ms),
            ])?;
        }
        out.push(t);
        let mut t = Table::new(
            "occupancy and colour against re-voxelizing the posed meshes",
            vec![
                num("t (s)", NumberFormat::Fixed(2)),
                Column::text("objects"),
                Column::text("voxelizer"),
                Column::text("filter"),
                num("threshold", NumberFormat::Fixed(2)),
                num("ref voxels", NumberFormat::Integer),
                num("IoU", NumberFormat::Fixed(3)),
                num("missing", NumberFormat::Fixed(3)),
                num("extra", NumberFormat::Fixed(3)),
                num("colour err", NumberFormat::Significant(3)),
            ],
        );
        for r in &self.agreement {
            t.push_row(vec![
                Cell::Number(r.time_s as f64),
                Cell::Text(r.objects.clone()),
                Cell::Text(r.voxelizer.clone()),
                Cell::Text(r.filter.clone()),
                Cell::Number(r.threshold as f64),
                Cell::Number(r.reference_voxels as f64),
                Cell::Number(r.iou),
                Cell::Number(r.missing_fraction),
                Cell::Number(r.extra_fraction),
                Cell::Number(r.colour_error),
            ])?;
        }
        out.push(t);
        let mut t = Table::new(
            "cone-traced AO and indirect light against the ray-traced posed mesh and the re-voxelized octree",
            vec![
                num("t (s)", NumberFormat::Fixed(2)),
                Column::text("voxelizer"),
                Column::text("method"),
                num("AO MSE", NumberFormat::Significant(3)),
                num("AO SSIM", NumberFormat::Fixed(3)),
                num("indirect MSE", NumberFormat::Significant(3)),
                num("indirect SSIM", NumberFormat::Fixed(3)),
                num("AO MSE vs re-vox.", NumberFormat::Significant(3)),
                num("AO SSIM vs re-vox.", NumberFormat::Fixed(3)),
                num("indirect MSE vs re-vox.", NumberFormat::Significant(3)),
                num("indirect SSIM vs re-vox.", NumberFormat::Fixed(3)),
            ],
        );
        for r in &self.images {
            t.push_row(vec![
                Cell::Number(r.time_s as f64),
                Cell::Text(r.voxelizer.clone()),
                Cell::Text(r.method.clone()),
                Cell::Number(r.ao_mse),
                Cell::Number(r.ao_ssim),
                Cell::Number(r.indirect_mse),
                Cell::Number(r.indirect_ssim),
                Cell::Number(r.ao_mse_revoxelized),
                Cell::Number(r.ao_ssim_revoxelized),
                Cell::Number(r.indirect_mse_revoxelized),
                Cell::Number(r.indirect_ssim_revoxelized),
            ])?;
        }
        out.push(t);
        if !self.rotations.is_empty() {
            let mut t = Table::new(
                "a rigid object turned in place: occupancy against its re-voxelization",
                vec![
                    Column::text("rotation"),
                    Column::text("voxelizer"),
                    Column::text("filter"),
                    num("ref voxels", NumberFormat::Integer),
                    num("IoU", NumberFormat::Fixed(3)),
                    num("missing", NumberFormat::Fixed(3)),
                    num("extra", NumberFormat::Fixed(3)),
                ],
            );
            for r in &self.rotations {
                t.push_row(vec![
                    Cell::Text(r.rotation.clone()),
                    Cell::Text(r.voxelizer.clone()),
                    Cell::Text(r.filter.clone()),
                    Cell::Number(r.reference_voxels as f64),
                    Cell::Number(r.iou),
                    Cell::Number(r.missing_fraction),
                    Cell::Number(r.extra_fraction),
                ])?;
            }
            out.push(t);
        }
        if !self.stability.is_empty() {
            let mut t = Table::new(
                "temporal stability: AO change between consecutive frames of a slowly moving object",
                vec![
                    Column::text("voxelizer"),
                    Column::text("method"),
                    num("frames", NumberFormat::Integer),
                    num("mean change", NumberFormat::Significant(3)),
                    num("max change", NumberFormat::Significant(3)),
                ],
            );
            for r in &self.stability {
                t.push_row(vec![
                    Cell::Text(r.voxelizer.clone()),
                    Cell::Text(r.method.clone()),
                    Cell::Number(r.frames as f64),
                    Cell::Number(r.mean_change),
                    Cell::Number(r.max_change),
                ])?;
            }
            out.push(t);
        }
        if !self.scaling.is_empty() {
            let gpu = self.scaling.iter().any(|r| r.frame_gpu_ms.is_some());
            let mut cols = vec![
                num("walkers", NumberFormat::Integer),
                num("objects", NumberFormat::Integer),
                num("triangles", NumberFormat::Integer),
                num("cached voxels", NumberFormat::Integer),
                Column::text("transform ms"),
                Column::text("blend ms"),
                Column::text("pose ms"),
                Column::text("voxelize cons. ms"),
                Column::text("voxelize thin ms"),
                Column::text("frame (transform) ms"),
                Column::text("frame (voxelize) ms"),
            ];
            if gpu {
                cols.push(Column::text("frame on GPU ms"));
            }
            cols.extend([
                num("peak MB (transform)", NumberFormat::Fixed(1)),
                num("peak MB (voxelize)", NumberFormat::Fixed(1)),
                num("transient MB", NumberFormat::Fixed(1)),
                num("cache MB", NumberFormat::Fixed(2)),
            ]);
            let mut t = Table::new(
                "time per frame against object count (mean and range of the runs)",
                cols,
            );
            let mb =
                |b: Option<u64>| b.map_or(Cell::Text("-".into()), |b| Cell::Number(b as f64 / 1e6));
            for r in &self.scaling {
                let mut cells = vec![
                    Cell::Number(r.walkers as f64),
                    Cell::Number(r.objects as f64),
                    Cell::Number(r.moving_triangles as f64),
                    Cell::Number(r.cached_voxels as f64),
                    spread_cell(&r.transform_ms),
                    spread_cell(&r.blend_ms),
                    spread_cell(&r.pose_ms),
                    spread_cell(&r.voxelize_conservative_ms),
                    spread_cell(&r.voxelize_thin_ms),
                    spread_cell(&r.frame_transform_ms),
                    spread_cell(&r.frame_voxelize_ms),
                ];
                if gpu {
                    cells.push(r.frame_gpu_ms.as_ref().map_or(Cell::Text("-".into()), spread_cell));
                }
                cells.extend([
                    mb(r.frame_transform_peak_bytes),
                    mb(r.frame_voxelize_peak_bytes),
                    Cell::Number(r.transient_bytes as f64 / 1e6),
                    Cell::Number(r.cache_bytes as f64 / 1e6),
                ]);
                t.push_row(cells)?;
            }
            out.push(t);
        }
        if !self.frames.is_empty() {
            let mut t = Table::new(
                format!("frames through the pipeline ({})", self.backend),
                vec![
                    num("frame", NumberFormat::Integer),
                    num("t (s)", NumberFormat::Fixed(2)),
                    num("leaves", NumberFormat::Integer),
                    num("transform ms", NumberFormat::Significant(3)),
                    num("blend ms", NumberFormat::Significant(3)),
                    num("octree ms", NumberFormat::Significant(3)),
                    num("inject ms", NumberFormat::Significant(3)),
                    num("trace ms", NumberFormat::Significant(3)),
                    num("frame ms", NumberFormat::Significant(3)),
                ],
            );
            for r in &self.frames {
                t.push_row(
                    [
                        r.frame as f64,
                        r.time_s as f64,
                        r.leaves as f64,
                        r.transform_ms,
                        r.blend_ms,
                        r.build_ms,
                        r.inject_ms,
                        r.trace_ms,
                        r.frame_ms,
                    ]
                    .into_iter()
                    .map(Cell::Number)
                    .collect(),
                )?;
            }
            out.push(t);
        }
        Ok(out)
    }

    /// Appends the dynamic-scene section: what was measured, the tables, the time-per-frame
    /// plot and the images.
    pub fn add_to_report(&self, r: &mut Report) -> Result<(), Error> {
        r.heading(2, format!("Dynamic scenes by voxel transformation: {}", self.scene));
        r.text(format!(
            "Measured on {}. World grid {}×{}×{} of {} world units; records: {}. Moving objects are voxelized \
             once into object-space caches and moved every frame (nearest: the world voxel of the \
             moved centre; 8-neighbour: split over the eight around it by the volume each \
             covers, a world voxel occupied when half of it is covered), against re-voxelizing the \
             posed meshes with the same voxelizer. Frames ran on {}. Times are wall-clock \
             on a machine shared with other work (on a CPU adapter such as lavapipe, CPU times \
             of the GPU path).",
            self.machine,
            self.grid[0],
            self.grid[1],
            self.grid[2],
            self.voxel_size as f32,
            self.records,
            self.backend
        ));
        for t in self.tables()? {
            r.table(t);
        }
        if !self.scaling.is_empty() {
            let series = |name: &str, f: &dyn Fn(&ScalingRow) -> Option<f64>| {
                Series::new(
                    name,
                    self.scaling
                        .iter()
                        .filter_map(|x| f(x).map(|y| (x.objects as f64, y)))
                        .collect(),
                )
            };
            let mut all = vec![
                series("transform", &|x| Some(x.transform_ms.mean)),
                series("voxelize (conservative)", &|x| Some(x.voxelize_conservative_ms.mean)),
                series("voxelize (thin)", &|x| Some(x.voxelize_thin_ms.mean)),
                series("frame by transform", &|x| Some(x.frame_transform_ms.mean)),
                series("frame by re-voxelization", &|x| Some(x.frame_voxelize_ms.mean)),
            ];
            if self.scaling.iter().any(|x| x.frame_gpu_ms.is_some()) {
                all.push(series("frame on the GPU backend", &|x| {
                    x.frame_gpu_ms.as_ref().map(|s| s.mean)
                }));
            }
            r.plot(
                "dynamic_time_per_frame",
                Plot {
                    title: "time per frame against moving objects".into(),
                    x_label: "moving objects".into(),
                    y_label: "ms".into(),
                    log_x: true,
                    log_y: true,
                    series: all,
                    ..Plot::default()
                },
            );
        }
        for (i, set) in self.image_sets.iter().enumerate() {
            let images =
                set.images.iter().map(|(l, im)| LabeledImage::new(l.clone(), im.clone())).collect();
            r.images(
                format!("dynamic_ao_{i}"),
                "AO: the ray-traced mesh, then each method's cone-traced octree",
                ImageGrid::new(4, images),
            );
        }
        if !self.frame_images.is_empty() {
            let images = self
                .frame_images
                .iter()
                .flat_map(|(l, ao, e)| {
                    [
                        LabeledImage::new(format!("{l} AO"), ao.clone()),
                        LabeledImage::new(format!("{l} indirect"), e.clone()),
                    ]
                })
                .collect();
            r.images(
                "dynamic_frames",
                format!("frames through the pipeline ({})", self.backend),
                ImageGrid::new(4, images),
            );
        }
        Ok(())
    }
}
