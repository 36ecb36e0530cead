//! Adaptive representation (beyond the HPG 2023 paper, which suggests it in its conclusion):
//! per voxel, the cheapest of Averages (8 B), \[VJK21\] (12 B) and the virtual mesh with its
//! opacity subgrid (136 B) whose error — the held-out **directional error** (the default) or
//! the predicted **image error** ([`Selector`]) — is at most a threshold τ; a voxel whose
//! candidates all exceed τ keeps the one with the smallest error. One parameter dials memory
//! against quality, and every voxel pays a 4-byte [`AdaptiveRef`] type tag.
//!
//! # The directional error
//!
//! Measured on **held-out rays**: `heldout` lines per voxel drawn by the same sampler as the
//! fit but with sample indices `rays..rays + heldout`, so they are independent of the rays the
//! records were fitted to (fitting and scoring on the same 150 rays would reward over-fitting).
//! Each held-out line goes to the nearest of [`BINS`] fixed directions (the 6 axes and the 8
//! diagonals); with the default 512 held-out lines a bin holds about 37, so a bin's empirical
//! opacity has a standard error of at most 0.08 and the mean over 14 bins about 0.02 — which
//! is why thresholds below about 0.02 separate nothing but noise. The error of a record is
//!
//! `E = mean_b |α̂_b − α_b| + mean_{b,j} |L̂_bj − L_bj|`
//!
//! - `α_b`: the fraction of the bin's held-out lines that hit a triangle of the voxel (booked as
//!   for the fit, design note §1); `α̂_b`: the record's opacity, `1 − T` after one crossing with
//!   each held-out line's own chord (so \[VJK21\]'s chord dependence is scored), averaged over
//!   the bin's lines, with the record's opacity for the bin direction.
//! - `L_bj`: for each of [`LIGHTS`] fixed unit light directions `l_j`, the mean over the bin's
//!   front-facing in-voxel hits (case (a)) of the Lambert response `lum(albedo)·max(n·l_j, 0)`;
//!   `L̂_bj`: the luminance of the record's own radiance toward the viewer `−d_b` under a unit
//!   directional light `l_j` (irradiance π, so [`crate::shading::shade`]'s Lambert term is
//!   `albedo·max(n·l, 0)`), no shadow, no ambient. Only bins with at least [`MIN_SURFACE_HITS`]
//!   such hits count.
//!
//! Both terms are on a [0, 1] scale per unit albedo, so τ reads as "mean absolute error in
//! opacity plus in Lambert shading".
//!
//! # The image error ([`Selector::Image`])
//!
//! The directional error weighs every direction and every voxel alike, but the renderer does
//! not: an opacity error shows only where what lies behind the voxel differs from the voxel's
//! own colour, a shading error only where the voxel is seen, and a hidden voxel shows nothing.
//! The image error is the first-order change of one pixel when only this voxel's record
//! replaces the truth, everything else along the pixel's ray staying true. Per bin `b`
//! (travel direction `d_b`, viewer at `−d_b`) with held-out lines:
//!
//! - every voxel's truth is its held-out opacity `α_b` and the mean radiance `L_b` of the bin's
//!   surface hits toward their viewers under the scene's light at the voxel centre, with the
//!   renderer's ambient term and the voxel's light visibility `V`: the transmittance of a walk
//!   from its centre toward the light through the other voxels' true opacities (skipping those
//!   within 1.5 voxel sizes, as the renderer's shadow rays do). Bins with fewer than
//!   [`MIN_SURFACE_HITS`] hits take the Averages record's radiance as their truth;
//! - a walk from the voxel toward the viewer composites the voxels in front, back to front,
//!   into the colour `F` they add and their transmittance `T_f`; a walk along `d_b`
//!   composites those behind and then the scene's background into `B`;
//! - the pixel is `F + T_f·(α_b L_b + (1 − α_b)·B)` in truth and
//!   `F + T_f·(α̂_b L̂_b + (1 − α̂_b)·B)` with the record (`α̂_b` as above, `L̂_b` the record's
//!   radiance toward `−d_b` with visibility `V`); its error is the difference of their sRGB
//!   encodings (each channel clamped to [0, 1]), the scale the MSE and SSIM are computed on.
//!
//! `E_img` is the root mean square of that difference over the bins with lines and the
//! colour channels, so τ reads as "RMS sRGB error of the pixels this voxel covers". Walks stop
//! when the transmittance falls below 0.001 (a voxel hidden that well has error 0). What it
//! leaves out: the other voxels' own errors (they are taken as true), the views (every bin
//! weighs the same), and a record's effect on the shadows of others.
//!
//! # Mixed grids along a ray
//!
//! Each voxel applies its own update to the running transmittance `T` (design note §4(e)):
//! Averages and virtual-mesh voxels `T ← T(1 − α)`; \[VJK21\] voxels
//! `T ← min(T, f(f⁻¹(T, γ) + σℓ, γ))`, whose `f⁻¹` reinterprets whatever `T` arrived as its own
//! equivalent optical depth. Both updates are monotone and keep `T` in [0, 1], so any order of
//! kinds composes; this is [`Opacity::apply`], the same code path as the single-kind grids.

use glam::{UVec3, Vec3};
use rayon::prelude::*;
use voxlod_format::records::{
    AdaptiveRef, AverageRecord, Kind, SggxRecord, SpecularRecord, VirtualMeshRecord,
};
use voxlod_format::{BrickMap, GridSpec, morton};
use voxlod_scene::LightSample;

use super::line_sampler::SamplingContext;
use super::virtual_mesh::VirtualMeshParams;
use super::voxel_samples::VoxelSamples;
use super::{
    Appearance, Opacity, RecordAppearance, averages, nonexp, precompute, sggx, subgrid,
    virtual_mesh,
};
use crate::{Error, Result};
use heldout::HeldOut;
use image::VoxelBins;

pub mod contribution;
mod heldout;
mod image;

pub use heldout::{BINS, DEFAULT_HELDOUT, LIGHTS, MIN_SURFACE_HITS, directional_error};

/// Which per-voxel error the selector compares with the threshold τ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Selector {
    /// The held-out directional error (module docs, "The directional error").
    #[default]
    HeldOut,
    /// The predicted image error (module docs, "The image error").
    Image,
}

impl Selector {
    /// Its name in reports and on the command line: `heldout` or `image`.
    pub fn name(self) -> &'static str {
        match self {
            Selector::HeldOut => "heldout",
            Selector::Image => "image",
        }
    }
}

impl std::str::FromStr for Selector {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "heldout" => Ok(Selector::HeldOut),
            "image" => Ok(Selector::Image),
            _ => Err(Error::InvalidParameter {
                name: "selector",
                value: s.into(),
                reason: "expected `heldout` or `image`".into(),
            }),
        }
    }
}

/// Settings of the Adaptive precompute.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveOptions {
    /// Rays each candidate is fitted to (the paper's 150).
    pub rays: u32,
    /// Held-out rays per voxel for the error estimate.
    pub heldout: u32,
    /// Seed of the sampler.
    pub seed: u32,
    /// Directional-opacity rule and shading samples of the virtual-mesh candidate.
    pub vmesh: VirtualMeshParams,
    /// The error [`Candidates::select`] compares with τ (both are always computed;
    /// [`Candidates::select_with`] picks either).
    pub selector: Selector,
    /// Ambient term the image error shades with (the renderer's
    /// [`crate::render::filtered::Options::ambient`]).
    pub ambient: Vec3,
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        let p = precompute::PrecomputeOptions::default();
        Self {
            rays: p.rays,
            heldout: DEFAULT_HELDOUT,
            seed: p.seed,
            vmesh: VirtualMeshParams::default(),
            selector: Selector::default(),
            ambient: Vec3::ZERO,
        }
    }
}

/// One voxel's three candidate records and their errors.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    code: u64,
    average: AverageRecord,
    sggx: SggxRecord,
    vmesh: VirtualMeshRecord,
    specular: Option<SpecularRecord>,
    errors: [f32; 3],
    image_errors: [f32; 3],
}

impl Candidate {
    /// Radiance of candidate `k` (Averages, \[VJK21\], virtual mesh) toward `to_viewer`.
    fn radiance(
        &self,
        k: usize,
        rule: VirtualMeshParams,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        let s = self.specular.as_ref();
        match k {
            0 => self.average.radiance((), s, to_viewer, light, visibility, ambient),
            1 => self.sggx.radiance((), s, to_viewer, light, visibility, ambient),
            _ => self.vmesh.radiance(rule, s, to_viewer, light, visibility, ambient),
        }
    }
}

/// All three candidates of every voxel with their held-out and image errors: built once, then
/// [`Candidates::select`]ed at any number of thresholds.
#[derive(Clone, Debug)]
pub struct Candidates {
    grid: GridSpec,
    rule: VirtualMeshParams,
    selector: Selector,
    voxels: Vec<Candidate>,
    specular: bool,
}

const KINDS: [Kind; 3] = [Kind::Average, Kind::Sggx, Kind::VirtualMesh];

impl Candidates {
    /// Fits the three candidates of every voxel (from the same `rays` samples), scores each on
    /// `heldout` further rays, then predicts each one's image error (module docs). Parallel
    /// over voxels; deterministic.
    pub fn build(ctx: &SamplingContext<'_>, options: &AdaptiveOptions) -> Result<Self> {
        if options.rays == 0 || options.heldout == 0 {
            return Err(Error::InvalidParameter {
                name: "rays/heldout",
                value: format!("{}/{}", options.rays, options.heldout),
                reason: "the fit and the error estimate each need at least one ray".into(),
            });
        }
        crate::render::check_colour("ambient", options.ambient)?;
        let specular = ctx.has_specular();
        let rule = options.vmesh;
        let grid = *ctx.grid();
        let light = ctx.scene().light().validated()?;
        let fitted: Vec<(Candidate, UVec3, VoxelBins)> = (0..ctx.voxel_count())
            .into_par_iter()
            .map_init(
                || (VoxelSamples::default(), VoxelSamples::default()),
                |(fit, held), i| {
                    ctx.sample_voxel_seeded(i, options.seed, 0, options.rays, fit);
                    let average = averages::fit(fit)?;
                    // One SGGX estimate for both records (what `sggx::fit` and `virtual_mesh::fit`
                    // would each compute).
                    let estimate = sggx::estimate_samples(fit)?;
                    let sggx = sggx::record(fit, &estimate, nonexp::fit(&fit.rays));
                    let vmesh = virtual_mesh::fit_with(fit, &estimate, subgrid::build(fit));
                    let spec = specular.then(|| precompute::specular_record(fit));
                    ctx.sample_voxel_seeded(i, options.seed, options.rays, options.heldout, held);
                    let h = HeldOut::new(held);
                    let alpha_hat = [
                        h.predicted_opacity(&average, ()),
                        h.predicted_opacity(&sggx, ()),
                        h.predicted_opacity(&vmesh, rule),
                    ];
                    let errors = [
                        h.error(&average, (), spec.as_ref(), &alpha_hat[0]),
                        h.error(&sggx, (), spec.as_ref(), &alpha_hat[1]),
                        h.error(&vmesh, rule, spec.as_ref(), &alpha_hat[2]),
                    ];
                    let c = ctx.coord(i);
                    let l = image::light_at(&light, &grid, c);
                    let bins = VoxelBins::new(&h, &l, options.ambient, alpha_hat);
                    let candidate = Candidate {
                        code: morton::encode(c),
                        average,
                        sggx,
                        vmesh,
                        specular: spec,
                        errors,
                        image_errors: [0.0; 3],
                    };
                    Some((candidate, c, bins))
                },
            )
            .flatten()
            .collect();
        let mut voxels = Vec::with_capacity(fitted.len());
        let mut coords = Vec::with_capacity(fitted.len());
        let mut bins = Vec::with_capacity(fitted.len());
        for (v, c, b) in fitted {
            voxels.push(v);
            coords.push(c);
            bins.push(b);
        }
        image_errors(&mut voxels, &coords, &bins, &grid, &light, ctx.scene().background, options)?;
        Ok(Self { grid, rule, selector: options.selector, voxels, specular })
    }

    /// Voxels with candidates.
    pub fn len(&self) -> usize {
        self.voxels.len()
    }

    /// Whether no voxel has candidates.
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty()
    }

    /// The grid.
    pub fn grid(&self) -> &GridSpec {
        &self.grid
    }

    /// The selector [`Candidates::select`] uses.
    pub fn selector(&self) -> Selector {
        self.selector
    }

    /// Per voxel (brick-map Morton order), the held-out error of Averages, \[VJK21\] and the
    /// virtual mesh.
    pub fn errors(&self) -> impl Iterator<Item = [f32; 3]> + '_ {
        self.voxels.iter().map(|v| v.errors)
    }

    /// Per voxel (brick-map Morton order), the predicted image error of Averages, \[VJK21\]
    /// and the virtual mesh.
    pub fn image_errors(&self) -> impl Iterator<Item = [f32; 3]> + '_ {
        self.voxels.iter().map(|v| v.image_errors)
    }

    /// The kind chosen for a voxel with `errors` at `threshold`: the cheapest at most
    /// `threshold`, else the one with the least error (the cheaper on ties).
    pub fn choose(errors: [f32; 3], threshold: f32) -> Kind {
        if let Some(k) = (0..3).find(|&k| errors[k] <= threshold) {
            return KINDS[k];
        }
        let mut best = 0;
        for k in 1..3 {
            if errors[k] < errors[best] {
                best = k;
            }
        }
        KINDS[best]
    }

    /// The mixed grid at `threshold`, by the selector of the build options.
    pub fn select(&self, threshold: f32) -> Result<AdaptiveGrid> {
        self.select_with(self.selector, threshold)
    }

    /// The mixed grid at `threshold` by `selector`'s error.
    pub fn select_with(&self, selector: Selector, threshold: f32) -> Result<AdaptiveGrid> {
        if !(threshold.is_finite() && threshold >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "threshold",
                value: threshold.to_string(),
                reason: "must be finite and non-negative".into(),
            });
        }
        self.select_kinds_by(|v| {
            let errors = match selector {
                Selector::HeldOut => v.errors,
                Selector::Image => v.image_errors,
            };
            Self::choose(errors, threshold)
        })
    }

    /// The grid whose voxel `i` (brick-map Morton order) uses `kinds[i]`. Errors when the
    /// count differs from [`Candidates::len`].
    pub fn select_kinds(&self, kinds: &[Kind]) -> Result<AdaptiveGrid> {
        if kinds.len() != self.voxels.len() {
            return Err(Error::InvalidParameter {
                name: "kinds",
                value: kinds.len().to_string(),
                reason: format!("one kind per voxel: {}", self.voxels.len()),
            });
        }
        let mut i = 0;
        self.select_kinds_by(|_| {
            i += 1;
            kinds[i - 1]
        })
    }

    /// The grid whose every voxel uses the kind `choose` returns for it, every array built at
    /// its exact size.
    fn select_kinds_by(&self, mut choose: impl FnMut(&Candidate) -> Kind) -> Result<AdaptiveGrid> {
        let kinds: Vec<Kind> = self.voxels.iter().map(&mut choose).collect();
        let count = |k: Kind| kinds.iter().filter(|&&x| x == k).count();
        let mut g = AdaptiveGrid {
            grid: self.grid,
            rule: self.rule,
            refs: BrickMap::new(self.grid.dims),
            averages: Vec::with_capacity(count(Kind::Average)),
            sggx: Vec::with_capacity(count(Kind::Sggx)),
            vmesh: Vec::with_capacity(count(Kind::VirtualMesh)),
            specular: self.specular.then(|| Vec::with_capacity(self.voxels.len())),
        };
        let mut refs = Vec::with_capacity(self.voxels.len());
        for (v, &kind) in self.voxels.iter().zip(&kinds) {
            let index = match kind {
                Kind::Average => push(&mut g.averages, v.average),
                Kind::Sggx => push(&mut g.sggx, v.sggx),
                Kind::VirtualMesh => push(&mut g.vmesh, v.vmesh),
            };
            let r =
                AdaptiveRef::new(kind, index as u32).ok_or_else(|| Error::InvalidParameter {
                    name: "voxels",
                    value: index.to_string(),
                    reason: format!(
                        "an adaptive grid holds at most {} records per kind",
                        AdaptiveRef::MAX_INDEX
                    ),
                })?;
            refs.push((v.code, r));
            if let (Some(s), Some(rec)) = (g.specular.as_mut(), v.specular) {
                s.push(rec);
            }
        }
        g.refs = BrickMap::from_morton_sorted(self.grid.dims, refs)?;
        Ok(g)
    }
}

/// Fills every candidate's image error: light visibilities, the true radiance of every voxel
/// per bin, then the composited error per voxel (module docs, "The image error").
fn image_errors(
    voxels: &mut [Candidate],
    coords: &[UVec3],
    bins: &[VoxelBins],
    grid: &GridSpec,
    light: &voxlod_scene::Light,
    background: Vec3,
    options: &AdaptiveOptions,
) -> Result<()> {
    crate::render::check_colour("background", background)?;
    let index = BrickMap::from_morton_sorted(grid.dims, voxels.iter().map(|v| (v.code, ())))?;
    let vis = image::visibilities(&index, grid, coords, bins, light);
    let rule = options.vmesh;
    // Per voxel and bin: the record radiance of each candidate, and the truth (the mean of
    // the bin's hits where it has enough, else the Averages record's).
    let radiance: Vec<[[Vec3; 14]; 3]> = (0..voxels.len())
        .into_par_iter()
        .map(|i| {
            let l = image::light_at(light, grid, coords[i]);
            let mut r = [[Vec3::ZERO; 14]; 3];
            for (k, rk) in r.iter_mut().enumerate() {
                for (b, d) in BINS.iter().enumerate() {
                    rk[b] = voxels[i].radiance(k, rule, -*d, &l, vis[i], options.ambient);
                }
            }
            r
        })
        .collect();
    let truth: Vec<[Vec3; 14]> = (0..voxels.len())
        .into_par_iter()
        .map(|i| {
            let v = &bins[i];
            std::array::from_fn(|b| {
                if v.shaded & (1 << b) != 0 {
                    v.radiance[0][b] + vis[i] * (v.radiance[1][b] - v.radiance[0][b])
                } else {
                    radiance[i][0][b]
                }
            })
        })
        .collect();
    let scene = image::Compositor { index: &index, grid, coords, bins, truth: &truth, background };
    let errors: Vec<[f32; 3]> =
        (0..voxels.len()).into_par_iter().map(|i| scene.errors(i, &radiance[i])).collect();
    for (v, e) in voxels.iter_mut().zip(errors) {
        v.image_errors = e;
    }
    Ok(())
}

fn push<T>(v: &mut Vec<T>, x: T) -> usize {
    v.push(x);
    v.len() - 1
}

/// A grid whose voxels each use one of the three representations: a brick map of
/// [`AdaptiveRef`] tags and one flat record array per kind.
#[derive(Clone, Debug)]
pub struct AdaptiveGrid {
    grid: GridSpec,
    rule: VirtualMeshParams,
    refs: BrickMap<AdaptiveRef>,
    averages: Vec<AverageRecord>,
    sggx: Vec<SggxRecord>,
    vmesh: Vec<VirtualMeshRecord>,
    specular: Option<Vec<SpecularRecord>>,
}

impl AdaptiveGrid {
    /// Share of voxels of each kind (Averages, \[VJK21\], virtual mesh).
    pub fn mix(&self) -> [f64; 3] {
        let n = self.refs.len().max(1) as f64;
        [self.averages.len() as f64 / n, self.sggx.len() as f64 / n, self.vmesh.len() as f64 / n]
    }

    /// Mean bytes of records per voxel: the type tag, the chosen record, the specular side
    /// record.
    pub fn record_bytes(&self) -> f64 {
        let n = self.refs.len().max(1) as f64;
        let records = self.averages.len() * size_of::<AverageRecord>()
            + self.sggx.len() * size_of::<SggxRecord>()
            + self.vmesh.len() * size_of::<VirtualMeshRecord>();
        let specular = self.specular.as_ref().map_or(0, |_| size_of::<SpecularRecord>());
        (size_of::<AdaptiveRef>() + specular) as f64 + records as f64 / n
    }

    /// Packed bytes, what a renderer holds: the tag brick map (headers, packed look-up, tags;
    /// [`BrickMap::memory_bytes`]), the record arrays and the specular records, counted from
    /// lengths. The arrays are built at their exact size, so this is also their heap size.
    pub fn memory_bytes(&self) -> usize {
        self.refs.memory_bytes()
            + self.averages.len() * size_of::<AverageRecord>()
            + self.sggx.len() * size_of::<SggxRecord>()
            + self.vmesh.len() * size_of::<VirtualMeshRecord>()
            + self.specular.as_ref().map_or(0, |s| s.len() * size_of::<SpecularRecord>())
    }

    /// The tag of voxel `index`.
    pub fn tag(&self, index: usize) -> AdaptiveRef {
        self.refs.values()[index]
    }

    /// The voxels' tags: voxel `i` of the brick map (its value order) uses record
    /// `tag.index()` of its kind's array. Other backends (voxlod-gpu) upload these.
    pub fn refs(&self) -> &BrickMap<AdaptiveRef> {
        &self.refs
    }

    /// The Averages records.
    pub fn average_records(&self) -> &[AverageRecord] {
        &self.averages
    }

    /// The \[VJK21\] records.
    pub fn sggx_records(&self) -> &[SggxRecord] {
        &self.sggx
    }

    /// The virtual-mesh records.
    pub fn vmesh_records(&self) -> &[VirtualMeshRecord] {
        &self.vmesh
    }

    /// The specular side records, one per voxel in the tags' order, if the scene has them.
    pub fn specular_records(&self) -> Option<&[SpecularRecord]> {
        self.specular.as_deref()
    }

    /// The parameters the virtual-mesh records are read with.
    pub fn vmesh_params(&self) -> VirtualMeshParams {
        self.rule
    }

    fn specular(&self, index: usize) -> Option<&SpecularRecord> {
        self.specular.as_ref().map(|s| &s[index])
    }
}

impl Appearance for AdaptiveGrid {
    fn grid(&self) -> &GridSpec {
        &self.grid
    }

    fn len(&self) -> usize {
        self.refs.len()
    }

    fn index_of(&self, c: UVec3) -> Option<usize> {
        self.refs.index_of(c)
    }

    fn opacity(&self, index: usize, dir: Vec3) -> Opacity {
        let r = self.tag(index);
        let i = r.index() as usize;
        match r.kind() {
            Kind::Average => RecordAppearance::opacity(&self.averages[i], (), dir),
            Kind::Sggx => RecordAppearance::opacity(&self.sggx[i], (), dir),
            Kind::VirtualMesh => RecordAppearance::opacity(&self.vmesh[i], self.rule, dir),
        }
    }

    fn radiance(
        &self,
        index: usize,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        let r = self.tag(index);
        let i = r.index() as usize;
        let s = self.specular(index);
        match r.kind() {
            Kind::Average => {
                self.averages[i].radiance((), s, to_viewer, light, visibility, ambient)
            }
            Kind::Sggx => self.sggx[i].radiance((), s, to_viewer, light, visibility, ambient),
            Kind::VirtualMesh => {
                self.vmesh[i].radiance(self.rule, s, to_viewer, light, visibility, ambient)
            }
        }
    }

    fn needs_visibility(&self, index: usize, to_viewer: Vec3, light: &LightSample) -> bool {
        let r = self.tag(index);
        let i = r.index() as usize;
        match r.kind() {
            Kind::Average => self.averages[i].needs_visibility((), to_viewer, light),
            Kind::Sggx => self.sggx[i].needs_visibility((), to_viewer, light),
            Kind::VirtualMesh => self.vmesh[i].needs_visibility(self.rule, to_viewer, light),
        }
    }
}

#[cfg(test)]
mod tests;
