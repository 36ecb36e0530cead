//! Heitz and Neyret (2012): pre-filtered surface statistics in the octree and differential cone
//! tracing with coverage masks, against the alpha-blending primary renderer on Averages and a
//! supersampled ground truth, over distance (level of detail) — the trade of that
//! representation, measured.
//!
//! # What is rendered, per scene and zoom
//! Pipeline: conservative voxelization at [`HeitzNeyretConfig::resolution`] → per-voxel ray
//! samples ([`HeitzNeyretConfig::rays`] lines per voxel) → Heitz–Neyret leaf records
//! (`voxlod_cpu::appearance::microsurface::fit`) and Averages records from the same lines →
//! octrees → renders from the scene's default camera moved away from its target by each zoom
//! factor (same image size: the pixel footprint grows with the zoom, the octree is read at
//! coarser levels). Each render is compared with the ground truth of the mesh at that zoom
//! (`ground_truth::render`, [`HeitzNeyretConfig::spp`] stratified rays per pixel, its own noise
//! measured with a second seed). The methods ([`Method`]):
//! - **masks**: [`DifferentialRenderer`](voxlod_cone::DifferentialRenderer) with coverage
//!   masks and Eq. 17's colour, shaded by `voxlod_gpu::differential::shade_element`
//!   (voxlod-cpu's `shade`);
//! - **masks, mean colour**: the same without the colour's height correlation (`aₛ` ignored,
//!   the colour filtered separately: what the paper calls MIP-mapping the colour);
//! - **blending**: the same records and elements composited as if uncorrelated (Eq. 12), to
//!   isolate what the masks change;
//! - **Averages**, **Averages directional**:
//!   [`PrimaryRenderer`](voxlod_cone::PrimaryRenderer) on Averages octrees (isotropic opacity,
//!   and six directional opacities), the existing alpha-blending baseline, shaded by `shade`
//!   with the mean colour and normal and, for a scene of one material, that material's own
//!   specular lobe (the unfiltered BRDF on the mean normal, as the paper's naive method).
//!
//! # Measures
//! - MSE and SSIM against the ground truth (8-bit sRGB), and the ground truth's own error (half
//!   the MSE between two seeds).
//! - **Silhouette thickness**: `(Σα − Σα_truth) / n_edge` pixels, `α` the coverage, `n_edge`
//!   the pixels the truth covers partly (`0.05 ≤ α ≤ 0.95`): by how many pixels the silhouette
//!   grows (> 0) or shrinks; and the coverage excess `(Σα − Σα_truth)/Σα_truth`.
//! - **Colour at grazing angles** (the paper's Fig. 9) on scenes whose macro-surface is a sphere
//!   about the scene's centre (`radial` cases): pixels the truth covers fully, binned by
//!   `μ = |v·n|` with `n` the radial direction at the pixel's hit; per bin the mean linear
//!   colour of the truth and of each method where it covers the pixel (the background it
//!   composited taken out, so that coverage does not count twice), compared by chromaticity
//!   (`(r, g) = (R, G)/(R + G + B)`: the hue shift the height-correlated colour causes, apart
//!   from the brightness the lighting changes).
//! - **Cost**: elements (octree samples) per pixel of the primary and shadow cones, render time
//!   (CPU, rayon; min and max over [`HeitzNeyretConfig::repeats`] runs); on
//!   [`Backend::Gpu`] also the differential kernel's time (on lavapipe, CPU time of the GPU
//!   path) and its largest difference from the CPU image.
//! - **Memory and precompute**: bytes per node of each payload (the paper's 15–20 B per voxel
//!   with 8–16-bit channels), bytes per occupied voxel of each octree, record fit and octree
//!   build times.
//! - **Depth of field** (the paper's Fig. 4): the first in-domain scene through a thin lens
//!   focused in front of it: the total coverage relative to the pinhole's, masks against
//!   blending (a blur moves coverage; it should not add any).
//!
//! Scenes outside the model (thin sheets, foliage: its hypothesis H7) are run too and marked
//! `in_domain = false`.

mod measure;
mod tables;

use serde::Serialize;

use crate::Error;
#[cfg(doc)]
use crate::backend::Backend;
pub use measure::run;

/// A scene of the study.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneCase {
    /// The scene spec ([`crate::scenes::load`]).
    pub spec: String,
    /// Short label for tables.
    pub label: String,
    /// Inside the model's domain (a solid with a locally planar macro-surface).
    pub in_domain: bool,
    /// The macro-surface is a sphere about the centre of the scene's bounds: the grazing-colour
    /// bins are measured.
    pub radial: bool,
}

impl SceneCase {
    fn new(spec: &str, label: &str, in_domain: bool, radial: bool) -> Self {
        Self { spec: spec.into(), label: label.into(), in_domain, radial }
    }
}

/// What the study measures.
#[derive(Clone, Debug, PartialEq)]
pub struct HeitzNeyretConfig {
    /// The scenes.
    pub scenes: Vec<SceneCase>,
    /// Voxels along the longest axis (a power of two in 8..=1024).
    pub resolution: u32,
    /// Image side, pixels (8..=2048).
    pub image_size: u32,
    /// Camera distance factors from the default framing (finite, ≥ 0.5; 1 = the default).
    pub zooms: Vec<f32>,
    /// Rays per pixel of the ground truth (≥ 1).
    pub spp: u32,
    /// Sampling lines per voxel for the records (1..=4096).
    pub rays: u32,
    /// Timed renders per method and zoom (1..=16): the times are the min and max.
    pub repeats: u32,
    /// Measure depth of field on the first in-domain scene.
    pub depth_of_field: bool,
}

impl HeitzNeyretConfig {
    /// About a minute on two cores: the bumpy sphere and the glossy bumpy sphere, the bunny and
    /// a small forest at 128³, 128² pixels, zooms 1, 2, 4, 8 (a pixel covers about 1 to 14
    /// voxels), 64 rays per pixel, 64 lines per voxel, three timed renders.
    pub fn quick() -> Self {
        Self {
            scenes: vec![
                SceneCase::new("builtin:bumpy-sphere", "bumpy sphere", true, true),
                SceneCase::new("builtin:bumpy-specular", "bumpy specular", true, true),
                SceneCase::new("builtin:bunny", "bunny", true, false),
                SceneCase::new("builtin:forest?trees=2&leaves=2000", "forest", false, false),
            ],
            resolution: 128,
            image_size: 128,
            zooms: vec![1.0, 2.0, 4.0, 8.0],
            spp: 64,
            rays: 64,
            repeats: 3,
            depth_of_field: true,
        }
    }

    /// The report's settings: the same scenes with the default forest at 256³,
    /// 256² pixels, zooms 1, 2, 4, 8, 16, 256 rays per pixel, the paper's 150 lines per voxel,
    /// three timed renders.
    pub fn full() -> Self {
        Self {
            scenes: vec![
                SceneCase::new("builtin:bumpy-sphere", "bumpy sphere", true, true),
                SceneCase::new("builtin:bumpy-specular", "bumpy specular", true, true),
                SceneCase::new("builtin:bunny", "bunny", true, false),
                SceneCase::new("builtin:forest", "forest", false, false),
            ],
            resolution: 256,
            image_size: 256,
            zooms: vec![1.0, 2.0, 4.0, 8.0, 16.0],
            spp: 256,
            rays: 150,
            repeats: 3,
            depth_of_field: true,
        }
    }

    /// Checks every field (named in the error).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "heitz-neyret", field, value, expected })
        };
        if self.scenes.is_empty() {
            return bad("scenes", "[]".into(), "at least one scene");
        }
        if !(self.resolution.is_power_of_two() && (8..=1024).contains(&self.resolution)) {
            return bad("resolution", self.resolution.to_string(), "a power of two in 8..=1024");
        }
        if !(8..=2048).contains(&self.image_size) {
            return bad("image_size", self.image_size.to_string(), "in 8..=2048");
        }
        if self.zooms.is_empty() {
            return bad("zooms", "[]".into(), "at least one zoom factor");
        }
        if let Some(z) = self.zooms.iter().find(|z| !(z.is_finite() && **z >= 0.5)) {
            return bad("zooms", z.to_string(), "finite and >= 0.5");
        }
        if self.spp == 0 {
            return bad("spp", "0".into(), "at least 1");
        }
        if !(1..=4096).contains(&self.rays) {
            return bad("rays", self.rays.to_string(), "in 1..=4096");
        }
        if !(1..=16).contains(&self.repeats) {
            return bad("repeats", self.repeats.to_string(), "in 1..=16");
        }
        Ok(())
    }
}

/// A rendering method of the study (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Differential cone tracing with coverage masks, Eq. 17's colour.
    Masks,
    /// The same with the colour filtered separately (`aₛ` ignored).
    MasksMeanColour,
    /// The same records and elements, alpha-blended as if uncorrelated.
    Blending,
    /// The primary renderer on Averages, isotropic opacity.
    Averages,
    /// The primary renderer on Averages with six directional opacities.
    AveragesDirectional,
}

impl Method {
    /// Every method, in table order.
    pub const ALL: [Method; 5] = [
        Method::Masks,
        Method::MasksMeanColour,
        Method::Blending,
        Method::Averages,
        Method::AveragesDirectional,
    ];

    /// The label in tables.
    pub fn label(self) -> &'static str {
        match self {
            Method::Masks => "masks",
            Method::MasksMeanColour => "masks, mean colour",
            Method::Blending => "blending",
            Method::Averages => "Averages",
            Method::AveragesDirectional => "Averages directional",
        }
    }
}

/// Minimum and maximum of repeated timings, milliseconds.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TimeRange {
    /// Fastest run.
    pub min_ms: f64,
    /// Slowest run.
    pub max_ms: f64,
}

/// One method at one zoom.
#[derive(Clone, Debug, Serialize)]
pub struct MethodRow {
    /// The method.
    pub method: Method,
    /// MSE against the ground truth (8-bit sRGB, [0, 1] scale as voxlod-eval computes it).
    pub mse: f64,
    /// SSIM against the ground truth.
    pub ssim: f64,
    /// `(Σα − Σα_truth) / n_edge`, pixels (module docs).
    pub silhouette_thickness_px: f64,
    /// `(Σα − Σα_truth) / Σα_truth`.
    pub coverage_excess: f64,
    /// Octree samples of the primary cones per pixel.
    pub elements_per_pixel: f64,
    /// Octree samples of the shadow cones per pixel.
    pub shadow_elements_per_pixel: f64,
    /// CPU render time (rayon, all threads), min and max over the repeats.
    pub cpu: TimeRange,
    /// CPU render time per pixel the truth covers (`Σα_truth`), microseconds (the minimum):
    /// the paper's cost per covered pixel.
    pub cpu_us_per_covered_pixel: f64,
    /// On the GPU backend (masks only): the kernel's time, min and max over the repeats.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu: Option<TimeRange>,
    /// On the GPU backend: the kernel's time per covered pixel, microseconds (the minimum).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_us_per_covered_pixel: Option<f64>,
    /// On the GPU backend: largest difference from the CPU image, 8-bit sRGB steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_worst_step: Option<u8>,
}

/// Mean linear colours of one grazing-angle bin.
#[derive(Clone, Debug, Serialize)]
pub struct GrazingBin {
    /// Lower bound of `μ = |v·n|`.
    pub mu_min: f32,
    /// Upper bound of `μ`.
    pub mu_max: f32,
    /// Pixels in the bin.
    pub pixels: usize,
    /// Mean linear RGB of the ground truth.
    pub truth_rgb: [f32; 3],
    /// Per method (in [`Method::ALL`] order): mean linear RGB.
    pub method_rgb: Vec<[f32; 3]>,
}

/// One zoom of one scene.
#[derive(Clone, Debug, Serialize)]
pub struct ZoomResult {
    /// Camera distance factor.
    pub zoom: f32,
    /// Pixel footprint at the centre of the scene's bounds, voxels.
    pub footprint_voxels: f32,
    /// Pixels the truth covers partly (the silhouette's length in pixels, about).
    pub edge_pixels: usize,
    /// Pixels the truth covers (`Σα_truth`).
    pub covered_pixels: f64,
    /// Ground-truth render time, ms (CPU).
    pub truth_ms: f64,
    /// MSE between two ground truths of different seeds.
    pub truth_seed_mse: f64,
    /// The ground truth's own error against the converged image, estimated as half
    /// [`Self::truth_seed_mse`]: MSE differences below it are not resolved.
    pub truth_error_mse: f64,
    /// One row per method.
    pub rows: Vec<MethodRow>,
    /// Grazing-colour bins (radial scenes only).
    pub grazing: Vec<GrazingBin>,
}

/// Memory and precompute of one representation.
#[derive(Clone, Debug, Serialize)]
pub struct Representation {
    /// "Heitz–Neyret" or "Averages".
    pub name: String,
    /// Bytes of one node's payload.
    pub payload_bytes_per_node: usize,
    /// Payload bytes of the sparse levels per occupied voxel.
    pub payload_bytes_per_voxel: f64,
    /// All bytes of the octree per occupied voxel.
    pub total_bytes_per_voxel: f64,
    /// Record fit (sampling included), ms.
    pub fit_ms: f64,
    /// Octree build, ms.
    pub build_ms: f64,
}

/// Depth of field on one scene (module docs).
#[derive(Clone, Debug, Serialize)]
pub struct DepthOfFieldResult {
    /// The scene's label.
    pub scene: String,
    /// Lens radius, world units.
    pub lens_radius: f32,
    /// Focus distance, world units.
    pub focus_distance: f32,
    /// Σα with the lens over Σα with the pinhole, masks.
    pub masks_coverage_ratio: f64,
    /// The same for blending.
    pub blending_coverage_ratio: f64,
}

/// Everything measured on one scene.
#[derive(Clone, Debug, Serialize)]
pub struct SceneResult {
    /// The scene.
    pub case: SceneCase,
    /// Triangles.
    pub triangles: usize,
    /// Voxels along the longest axis.
    pub resolution: u32,
    /// Occupied voxels.
    pub voxels: u64,
    /// Octree depth.
    pub depth: u32,
    /// Both representations' memory and precompute.
    pub representations: Vec<Representation>,
    /// One entry per zoom.
    pub zooms: Vec<ZoomResult>,
    /// The images (truth and each method) per zoom, for the report.
    #[serde(skip)]
    pub images: Vec<(String, voxlod_scene::Srgb8Image)>,
}

/// Everything the study measured.
#[derive(Clone, Debug, Serialize)]
pub struct HeitzNeyretResult {
    /// Where the renders ran ([`Backend::describe`]).
    pub backend: String,
    /// The machine.
    pub machine: String,
    /// Image side, pixels.
    pub image_size: u32,
    /// Ground-truth rays per pixel.
    pub spp: u32,
    /// Sampling lines per voxel.
    pub rays: u32,
    /// Per scene.
    pub scenes: Vec<SceneResult>,
    /// Depth of field, if measured.
    pub depth_of_field: Option<DepthOfFieldResult>,
}

#[cfg(test)]
mod tests;
