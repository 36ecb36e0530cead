//! The filtered-appearance comparison under the conditions of Brito, Poulin and Teichrieb (2023,
//! §5 and Table 1), and its ablation: one deviation from those conditions at a time, each
//! method's change measured on paired samples with a bootstrap interval.
//!
//! # The paper setup ([`Variant::paper`])
//! - **Scenes** of the paper's kinds at its triangle counts (10⁵–10⁶; [`PaperScene`]): a dense
//!   surface's triangles are small against a voxel, which is where the representations differ.
//! - **Lighting** ([`Lighting::SunAndPoint`]): the scene's sun and a point light, as in the
//!   authors' code; **background** white ([`Background::White`], red as the option of their
//!   Fig. 10).
//! - **Images** at a side equal to the voxel resolution (128³ → 128²), the ground truth at 1024
//!   rays per pixel box-filtered; scores on the whole image (the paper crops empty space for
//!   display but does not say whether its scores were cropped: [`Variant::crop`] measures it).
//! - **Methods**: Averages, \[VJK21\] (SGGX + non-exponential transmittance), the paper's
//!   virtual mesh with its opacity subgrid, and Adaptive at each threshold of
//!   [`PaperConfig::thresholds`] (held-out error) and [`PaperConfig::image_thresholds`] (image
//!   error).
//! - **The authors' choices** wherever their public code differs from voxlod's
//!   ([`Variant::choices`]: their directional opacity, 40 random face samples, the unshaded
//!   fallback, a cached \[VJK21\] chord, the Averages normal as stored) and a jittered pixel
//!   pattern (§4); each of voxlod's choices is a deviation of the ablation.
//!
//! # Samples and intervals
//! Every method is scored on `views × seeds` paired samples: the same cameras and, per seed,
//! the same random sources of the representations (precompute lines, face samples, pixel
//! jitter; the ground truth is seed 0, its own error is estimated from seed 1 and reported).
//! Differences between methods,
//! and between a variant and the paper setup, are paired per sample and carry the 95 %
//! bootstrap interval of [`stats::PairedDiff`]; a difference is called only when that interval
//! excludes zero.
//!
//! Ground truths are cached on disk by their inputs ([`cache::TruthCache`]): the variants that
//! keep the scene, lights and background score against the same images.

pub mod ablation;
pub mod cache;
pub mod extras;
pub mod lighting;
mod setup;
pub mod stats;
mod tables;

use std::path::PathBuf;
use std::time::Instant;

use glam::Vec3;
use voxlod_cpu::appearance::adaptive::{self, AdaptiveOptions, Selector};
use voxlod_cpu::appearance::averages::AveragesGrid;
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::virtual_mesh::{VirtualMeshGrid, VirtualMeshParams};
use voxlod_cpu::appearance::{
    Appearance, AuthorsChoices, FaceSamples, averages, sggx, virtual_mesh,
};
use voxlod_cpu::render::filtered::PixelPattern;
use voxlod_cpu::voxelize::{self, Mode};
use voxlod_eval::report::LabeledImage;
use voxlod_format::GridSpec;

pub use cache::TruthCache;
pub use lighting::{Background, Lighting};
pub use setup::Crop;
use setup::{Loaded, render};
pub use stats::PairedDiff;
pub use tables::{PAPER_TABLE_1, findings};

use crate::Error;
use crate::spread::ms;

/// A scene of the paper setup: its dense spec (the setup's) and a coarse one (the mesh-density
/// deviation), and the paper scene it stands for, if any.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PaperScene {
    /// Label in tables.
    pub label: String,
    /// The scene spec of the setup (dense triangles).
    pub spec: String,
    /// The same scene with coarse triangles (None: the mesh-density variant is not run).
    pub coarse: Option<String>,
    /// The scene of the paper's Table 1 it corresponds to.
    pub paper: Option<String>,
}

/// The embedded bunny split to the paper's order of triangles (midpoint subdivision, 3 674·4³ =
/// 235 136 triangles on the same surface; the paper's has 144 k), with the original as the
/// coarse variant: between the two only the triangles' size against a voxel changes.
pub fn dense_bunny() -> PaperScene {
    PaperScene {
        label: "bunny".into(),
        spec: "builtin:bunny?subdivide=3".into(),
        coarse: Some("builtin:bunny".into()),
        paper: Some("Bunny".into()),
    }
}

/// The scenes of the paper setup ([`crate::scenes::PAPER_SCENES`]), standing for the paper's
/// Bunny, Trees, Island and City (its Bistro, a downloaded 3.4 M-triangle model, is not built).
/// Only the bunny has a coarse variant: the others' detail is their content.
pub fn paper_scenes() -> Vec<PaperScene> {
    crate::scenes::PAPER_SCENES
        .iter()
        .map(|&(paper, spec)| {
            if paper == "Bunny" {
                return dense_bunny();
            }
            let label = match paper {
                "Trees" => "trees".to_string(),
                other => other.to_ascii_lowercase(),
            };
            PaperScene { label, spec: spec.into(), coarse: None, paper: Some(paper.into()) }
        })
        .collect()
}

/// The scenes a command names: `paper` (all of [`paper_scenes`]), one of their labels, or any
/// scene spec (with `coarse` as its coarse counterpart).
pub fn scenes_named(name: &str, coarse: Option<String>) -> Vec<PaperScene> {
    if name == "paper" {
        return paper_scenes();
    }
    if let Some(s) = paper_scenes().into_iter().find(|s| s.label == name) {
        return vec![PaperScene { coarse: coarse.or(s.coarse), ..s }];
    }
    let label = name.strip_prefix(crate::scenes::BUILTIN_PREFIX).unwrap_or(name);
    let label = label.split(['?', '/']).next_back().unwrap_or(label).to_string();
    vec![PaperScene { label, spec: name.into(), coarse, paper: None }]
}

/// How one run deviates from the paper setup (or not: [`Variant::paper`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Variant {
    /// Name in tables ("paper setup" or what was toggled).
    pub name: String,
    /// Whether the scene's coarse spec is used.
    pub coarse: bool,
    /// Background.
    pub background: Background,
    /// Lights.
    pub lighting: Lighting,
    /// Where the representations follow the authors' code or ours (opacity rule, face
    /// samples, fallback, \[VJK21\] chord, Averages normal, pixel pattern). Seeds inside it are
    /// replaced per sample seed: the precompute's lines, a random face sampling and a jittered
    /// pixel pattern all take the sample's seed.
    #[serde(serialize_with = "ser_debug")]
    pub choices: AuthorsChoices,
    /// Whether scores are computed on the images cropped to the ground truth's coverage
    /// (bounding box of pixels with any coverage, one pixel of margin, at least the SSIM window).
    pub crop: bool,
}

impl Variant {
    /// The paper's conditions: the authors' choices everywhere their code differs from ours
    /// ([`AuthorsChoices::authors`]) and a jittered pixel pattern (§4: "four rays per pixel,
    /// from a set of precomputed jittered patterns").
    pub fn paper() -> Self {
        Self {
            name: "paper setup".into(),
            coarse: false,
            background: Background::White,
            lighting: Lighting::SunAndPoint,
            choices: AuthorsChoices {
                pattern: PixelPattern::Jittered { seed: 0 },
                ..AuthorsChoices::authors()
            },
            crop: false,
        }
    }

    /// The choices for sample seed `seed`: every random source of the representations takes it.
    pub fn choices_for_seed(&self, seed: u32) -> AuthorsChoices {
        let mut c = self.choices;
        c.precompute_seed = seed;
        if let FaceSamples::Random { .. } = c.face_samples {
            c.face_samples = FaceSamples::Random { seed };
        }
        if let PixelPattern::Jittered { .. } = c.pattern {
            c.pattern = PixelPattern::Jittered { seed };
        }
        c
    }
}

/// Settings of a paper-setup run.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperConfig {
    /// Scenes.
    pub scenes: Vec<PaperScene>,
    /// Voxel resolutions; each is rendered at an image side equal to it.
    pub resolutions: Vec<u32>,
    /// Rays per pixel of the ground truth (the paper's 1024).
    pub gt_spp: u32,
    /// Views per scene (the scene's camera orbited about the vertical axis).
    pub views: usize,
    /// Seeds of the precompute's sampling lines.
    pub seeds: u32,
    /// Sampling rays per voxel (the paper's 150).
    pub rays: u32,
    /// Adaptive thresholds of the held-out error, one method each.
    pub thresholds: Vec<f32>,
    /// Adaptive thresholds of the image-error selector, one method each.
    pub image_thresholds: Vec<f32>,
    /// Ambient term of the shading.
    pub ambient: Vec3,
    /// Where ground truths are cached (None: rendered every time).
    pub cache: Option<PathBuf>,
    /// The command line that reproduces the run.
    pub command: String,
}

impl PaperConfig {
    /// The paper's scale: 128³ and 256³, 1024 rays per pixel, four views, two seeds.
    pub fn full() -> Self {
        Self {
            scenes: vec![dense_bunny()],
            resolutions: vec![128, 256],
            gt_spp: 1024,
            views: 4,
            seeds: 2,
            rays: 150,
            thresholds: vec![0.1],
            image_thresholds: vec![0.01, 0.02],
            ambient: Vec3::splat(0.1),
            cache: None,
            command: String::new(),
        }
    }

    /// A smoke version for tests: the coarse bunny at 32³, two views, 16 rays per pixel.
    pub fn smoke() -> Self {
        Self {
            scenes: vec![PaperScene {
                label: "bunny".into(),
                spec: "builtin:bunny".into(),
                coarse: Some("builtin:sphere?subdiv=2".into()),
                paper: Some("Bunny".into()),
            }],
            resolutions: vec![32],
            gt_spp: 16,
            views: 2,
            rays: 32,
            ..Self::full()
        }
    }

    /// Checks every field (named in the error).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, expected: &'static str| {
            Err(Error::InvalidConfig { study: "paper setup", field, value, expected })
        };
        if self.scenes.is_empty() {
            return bad("scenes", "[]".into(), "at least one scene");
        }
        if self.resolutions.is_empty() {
            return bad("resolutions", "[]".into(), "at least one resolution");
        }
        for &r in &self.resolutions {
            if !(voxlod_eval::ssim::SSIM_WINDOW..=1024).contains(&r) {
                return bad(
                    "resolutions",
                    r.to_string(),
                    "in 11..=1024 (the image side is the resolution, at least the SSIM window)",
                );
            }
        }
        if self.gt_spp == 0 {
            return bad("gt_spp", "0".into(), "at least 1 ray per pixel");
        }
        if self.views == 0 {
            return bad("views", "0".into(), "at least 1 view");
        }
        if self.seeds == 0 {
            return bad("seeds", "0".into(), "at least 1 seed");
        }
        if self.rays == 0 {
            return bad("rays", "0".into(), "at least 1 sampling ray per voxel");
        }
        for &t in self.thresholds.iter().chain(&self.image_thresholds) {
            if !(t.is_finite() && t >= 0.0) {
                return bad("thresholds", t.to_string(), "finite and >= 0");
            }
        }
        if !(self.ambient.is_finite() && self.ambient.min_element() >= 0.0) {
            return bad("ambient", format!("{}", self.ambient), "finite and >= 0 per channel");
        }
        Ok(())
    }
}

/// One method's scores in one case, sample by sample (`seed`-major, then view).
#[derive(Clone, Debug, serde::Serialize)]
pub struct MethodScores {
    /// The method.
    pub method: String,
    /// Packed bytes per voxel the renderer reads (records and index), seed 0.
    pub bytes_per_voxel: f64,
    /// Precompute time (sampling + fit) of seed 0, ms.
    pub precompute_ms: f64,
    /// Mean render time per frame (all lights), ms.
    pub render_ms: f64,
    /// MSE per sample.
    pub mse: Vec<f64>,
    /// SSIM per sample.
    pub ssim: Vec<f64>,
}

impl MethodScores {
    /// Mean MSE.
    pub fn mse_mean(&self) -> f64 {
        mean(&self.mse)
    }
    /// Mean SSIM.
    pub fn ssim_mean(&self) -> f64 {
        mean(&self.ssim)
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// Everything one scene, resolution and variant measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CaseResult {
    /// Scene label.
    pub scene: String,
    /// The spec that was run.
    pub spec: String,
    /// The paper scene it corresponds to.
    pub paper: Option<String>,
    /// Voxel resolution (= image side).
    pub resolution: u32,
    /// The variant.
    pub variant: Variant,
    /// Triangles of the scene.
    pub triangles: usize,
    /// Occupied voxels.
    pub voxels: usize,
    /// The ground truth's own error: half the MSE of its seed-1 render against seed 0, mean
    /// over views.
    pub truth_error_mse: f64,
    /// Samples per method (views × seeds).
    pub samples: usize,
    /// Every method's scores.
    pub methods: Vec<MethodScores>,
    /// Wall time of this case (its share of the shared precompute included), ms.
    pub wall_ms: f64,
    /// View 0 at seed 0: the ground truth, then each method.
    #[serde(skip)]
    pub figure: Vec<LabeledImage>,
}

impl CaseResult {
    /// The scores of `method`.
    pub fn method(&self, method: &str) -> Option<&MethodScores> {
        self.methods.iter().find(|m| m.method == method)
    }
}

/// What a paper-setup run produced.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PaperResult {
    /// One case per scene, resolution and variant.
    pub cases: Vec<CaseResult>,
    /// Ground truths loaded from the cache and rendered.
    pub truths_cached: usize,
    /// Ground truths rendered.
    pub truths_rendered: usize,
    /// Wall time, ms.
    pub wall_ms: f64,
}

/// Runs the paper setup (the variant [`Variant::paper`]) on every scene and resolution.
pub fn run(config: &PaperConfig, progress: &(dyn Fn(&str) + Sync)) -> Result<PaperResult, Error> {
    run_variants(config, &[Variant::paper()], progress)
}

/// Runs `variants` on every scene and resolution: the variants that share a mesh share its
/// voxelization and precompute (per seed), and the ones that share lights and background share
/// ground truths.
pub fn run_variants(
    config: &PaperConfig,
    variants: &[Variant],
    progress: &(dyn Fn(&str) + Sync),
) -> Result<PaperResult, Error> {
    config.validate()?;
    let start = Instant::now();
    let cache = TruthCache::new(config.cache.clone());
    let mut result = PaperResult::default();
    for scene in &config.scenes {
        for &res in &config.resolutions {
            for coarse in [false, true] {
                let group: Vec<&Variant> = variants.iter().filter(|v| v.coarse == coarse).collect();
                if group.is_empty() {
                    continue;
                }
                let spec = match (coarse, &scene.coarse) {
                    (false, _) => &scene.spec,
                    (true, Some(c)) => c,
                    (true, None) => continue,
                };
                let cases = run_group(config, scene, spec, res, &group, &cache, progress)?;
                result.cases.extend(cases);
            }
        }
    }
    // Report cases in the order the variants were given.
    result.cases.sort_by_key(|c| {
        let v = variants.iter().position(|v| *v == c.variant).unwrap_or(usize::MAX);
        let s = config.scenes.iter().position(|s| s.label == c.scene).unwrap_or(usize::MAX);
        (s, c.resolution, v)
    });
    (result.truths_cached, result.truths_rendered) = cache.counts();
    result.wall_ms = ms(start.elapsed());
    Ok(result)
}

/// A representation ready to render.
struct Built {
    method: String,
    repr: Repr,
    bytes_per_voxel: f64,
    precompute_ms: f64,
}

/// Averages and the virtual mesh are kept by type: each variant reads them with its own
/// choices (normal; rule, face samples, fallback).
enum Repr {
    Any(Box<dyn Appearance>),
    Averages(AveragesGrid),
    VirtualMesh(VirtualMeshGrid),
}

impl Repr {
    /// The representation read with `choices`.
    fn with(&mut self, choices: &AuthorsChoices) -> &dyn Appearance {
        match self {
            Repr::Any(g) => &**g,
            Repr::Averages(g) => {
                g.normal = choices.averages_normal;
                g
            }
            Repr::VirtualMesh(g) => {
                let p = choices.virtual_mesh(VirtualMeshParams::default());
                (g.rule, g.samples_per_face, g.sampling, g.fallback) =
                    (p.rule, p.samples_per_face, p.sampling, p.fallback);
                g
            }
        }
    }
}

/// Precomputes every method from the sampling lines of `seed` (each timed with its own share:
/// sampling plus fit).
fn build(
    ctx: &SamplingContext<'_>,
    config: &PaperConfig,
    seed: u32,
    progress: &dyn Fn(&str),
) -> Result<Vec<Built>, Error> {
    let opts = PrecomputeOptions { rays: config.rays, seed };
    let per_voxel = |bytes: usize, n: usize| bytes as f64 / n.max(1) as f64;
    let mut built = Vec::new();
    progress("Averages");
    let t = Instant::now();
    let g = precompute(ctx, &opts, averages::fit)?;
    built.push(Built {
        method: "Averages".into(),
        bytes_per_voxel: per_voxel(g.memory_bytes(), g.records.len()),
        precompute_ms: ms(t.elapsed()),
        repr: Repr::Averages(AveragesGrid { grid: g, normal: Default::default() }),
    });
    progress("[VJK21]");
    let t = Instant::now();
    let g = precompute(ctx, &opts, sggx::fit)?;
    built.push(Built {
        method: "[VJK21]".into(),
        bytes_per_voxel: per_voxel(g.memory_bytes(), g.records.len()),
        precompute_ms: ms(t.elapsed()),
        repr: Repr::Any(Box::new(g)),
    });
    progress("virtual mesh");
    let t = Instant::now();
    let g = precompute(ctx, &opts, virtual_mesh::fit)?;
    built.push(Built {
        method: "virtual mesh".into(),
        bytes_per_voxel: per_voxel(g.memory_bytes(), g.records.len()),
        precompute_ms: ms(t.elapsed()),
        repr: Repr::VirtualMesh(VirtualMeshGrid::new(g)),
    });
    if !config.thresholds.is_empty() || !config.image_thresholds.is_empty() {
        progress("Adaptive");
        let t = Instant::now();
        // Adaptive's candidates are built once per seed for every variant: its virtual mesh is
        // read with the paper setup's choices.
        let choices = Variant::paper().choices_for_seed(seed);
        let options = AdaptiveOptions {
            rays: config.rays,
            seed,
            ambient: config.ambient,
            vmesh: choices.virtual_mesh(VirtualMeshParams::default()),
            ..Default::default()
        };
        let candidates = adaptive::Candidates::build(ctx, &options)?;
        let candidates_ms = ms(t.elapsed());
        let selections = (config.thresholds.iter().map(|&t| (Selector::HeldOut, t)))
            .chain(config.image_thresholds.iter().map(|&t| (Selector::Image, t)));
        for (selector, threshold) in selections {
            let t = Instant::now();
            let g = candidates.select_with(selector, threshold)?;
            built.push(Built {
                method: match selector {
                    Selector::HeldOut => format!("Adaptive τ={threshold}"),
                    Selector::Image => format!("Adaptive (image) τ={threshold}"),
                },
                bytes_per_voxel: g.memory_bytes() as f64 / g.len().max(1) as f64,
                precompute_ms: candidates_ms + ms(t.elapsed()),
                repr: Repr::Any(Box::new(g)),
            });
        }
    }
    Ok(built)
}

/// One scene spec at one resolution, every variant of `group` (all on the same mesh).
fn run_group(
    config: &PaperConfig,
    case: &PaperScene,
    spec: &str,
    res: u32,
    group: &[&Variant],
    cache: &TruthCache,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<CaseResult>, Error> {
    let start = Instant::now();
    let label = &case.label;
    progress(&format!("{label} ({spec}): loading"));
    let loaded = Loaded::new(spec, config.views)?;
    let (base, geometry) = (&loaded.scene, &loaded.geometry);
    let (lo, hi) = base.bounds()?;
    let views = &loaded.views;
    let mut setups = Vec::new();
    for v in group {
        setups.push(loaded.truths(v, res, config, cache, &|m| progress(&format!("{label} {m}")))?);
    }

    progress(&format!("{label} {res}³: voxelizing"));
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res)?;
    let options = voxelize::Options { mode: Mode::Conservative, ..Default::default() };
    let vox = voxelize::voxelize(geometry, &grid, &options)?;
    let voxels = vox.voxels.len();
    let ctx = SamplingContext::new(base, geometry, &vox)?;

    let mut scores: Vec<Vec<MethodScores>> = vec![Vec::new(); group.len()];
    let mut figures: Vec<Vec<LabeledImage>> = setups
        .iter()
        .map(|s| vec![LabeledImage::new("ground truth", s.references[0].clone())])
        .collect();
    for seed in 0..config.seeds {
        let mut built = build(&ctx, config, seed, &|m| {
            progress(&format!("{label} {res}³ seed {seed}: precompute {m}"))
        })?;
        for (g, (v, setup)) in group.iter().zip(&setups).enumerate() {
            for b in &mut built {
                progress(&format!("{label} {res}² seed {seed} {}: rendering {}", v.name, b.method));
                let choices = v.choices_for_seed(seed);
                let grid = b.repr.with(&choices);
                let (mut mse, mut ssim, mut render_ms) = (Vec::new(), Vec::new(), 0.0);
                for ((camera, reference), crop) in
                    views.iter().zip(&setup.references).zip(&setup.crops)
                {
                    let t = Instant::now();
                    let background = setup.scene.background;
                    let ambient = config.ambient;
                    let image =
                        render(grid, camera, &setup.lights, background, ambient, &choices, res)?;
                    render_ms += ms(t.elapsed());
                    let m = voxlod_eval::compare(&crop.apply(&image), &crop.apply(reference))?;
                    if seed == 0 && mse.is_empty() {
                        // The label font is ASCII.
                        let label = b.method.replace('τ', "tau");
                        figures[g].push(LabeledImage::new(label, image));
                    }
                    mse.push(m.mse);
                    ssim.push(m.ssim);
                }
                let entry = match scores[g].iter_mut().find(|s| s.method == b.method) {
                    Some(e) => e,
                    None => {
                        scores[g].push(MethodScores {
                            method: b.method.clone(),
                            bytes_per_voxel: b.bytes_per_voxel,
                            precompute_ms: b.precompute_ms,
                            render_ms: render_ms / views.len() as f64,
                            mse: Vec::new(),
                            ssim: Vec::new(),
                        });
                        scores[g].last_mut().expect("just pushed")
                    }
                };
                entry.mse.extend(mse);
                entry.ssim.extend(ssim);
            }
        }
    }
    let wall_ms = ms(start.elapsed()) / group.len() as f64;
    Ok(group
        .iter()
        .zip(setups)
        .zip(scores.into_iter().zip(figures))
        .map(|((v, setup), (methods, figure))| CaseResult {
            scene: case.label.clone(),
            spec: spec.into(),
            paper: case.paper.clone(),
            resolution: res,
            variant: (*v).clone(),
            triangles: base.triangle_count(),
            voxels,
            truth_error_mse: setup.truth_error,
            samples: views.len() * config.seeds as usize,
            methods,
            wall_ms,
            figure,
        })
        .collect())
}

fn ser_debug<T: std::fmt::Debug, S: serde::Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&format!("{v:?}"))
}
