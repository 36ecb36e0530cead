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
mod report;
pub mod scaling;
mod setup;
pub mod stability;

use serde::Serialize;
use voxlod_cpu::dynamic::{CacheOptions, ObjectKind, RecordSource};
use voxlod_cpu::voxelize::Mode;
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
