//! Adaptive representation (beyond the HPG 2023 paper, which suggests it in its conclusion):
//! per voxel, the cheapest of Averages (8 B), \[VJK21\] (12 B) and the virtual mesh with its
//! opacity subgrid (136 B) whose **directional error** is at most a threshold τ; a voxel whose
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

/// Default number of held-out rays per voxel.
pub const DEFAULT_HELDOUT: u32 = 512;

/// Fewest case-(a) hits a direction bin needs before its shading error counts.
pub const MIN_SURFACE_HITS: u32 = 4;

const S: f32 = 0.577_350_3; // 1/√3

/// The direction bins of the error: the 6 axes and the 8 diagonals.
pub const BINS: [Vec3; 14] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
    Vec3::new(S, S, S),
    Vec3::new(-S, S, S),
    Vec3::new(S, -S, S),
    Vec3::new(-S, -S, S),
    Vec3::new(S, S, -S),
    Vec3::new(-S, S, -S),
    Vec3::new(S, -S, -S),
    Vec3::new(-S, -S, -S),
];

/// The light directions of the shading error: the corners of a tetrahedron.
pub const LIGHTS: [Vec3; 4] =
    [Vec3::new(S, S, S), Vec3::new(S, -S, -S), Vec3::new(-S, S, -S), Vec3::new(-S, -S, S)];

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
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        let p = precompute::PrecomputeOptions::default();
        Self {
            rays: p.rays,
            heldout: DEFAULT_HELDOUT,
            seed: p.seed,
            vmesh: VirtualMeshParams::default(),
        }
    }
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Per-bin statistics of held-out lines: counts, occlusions, Lambert sums.
struct HeldOut<'a> {
    samples: &'a VoxelSamples,
    /// Bin of each ray.
    bin: Vec<u8>,
    rays: [u32; 14],
    occluded: [u32; 14],
    hits: [u32; 14],
    lambert: [[f32; 4]; 14],
}

impl<'a> HeldOut<'a> {
    fn new(samples: &'a VoxelSamples) -> Self {
        let mut h = HeldOut {
            samples,
            bin: Vec::with_capacity(samples.rays.len()),
            rays: [0; 14],
            occluded: [0; 14],
            hits: [0; 14],
            lambert: [[0.0; 4]; 14],
        };
        for r in &samples.rays {
            let b = nearest_bin(r.dir);
            h.bin.push(b as u8);
            h.rays[b] += 1;
            h.occluded[b] += u32::from(r.occluded);
            if let Some(s) = &r.surface {
                h.hits[b] += 1;
                let a = luminance(s.albedo);
                for (j, l) in LIGHTS.iter().enumerate() {
                    h.lambert[b][j] += a * s.normal.dot(*l).max(0.0);
                }
            }
        }
        h
    }

    /// The directional error of `record` (module docs).
    fn error<R: RecordAppearance>(
        &self,
        record: &R,
        params: R::Params,
        specular: Option<&SpecularRecord>,
    ) -> f32 {
        let mut opacity_sum = 0.0;
        let mut opacity_bins = 0u32;
        let mut shading_sum = 0.0;
        let mut shading_terms = 0u32;
        let mut predicted = [0.0f32; 14];
        let mut ops = [Opacity::Alpha(0.0); 14];
        for b in 0..14 {
            if self.rays[b] > 0 {
                ops[b] = record.opacity(params, BINS[b]);
            }
        }
        for (r, &b) in self.samples.rays.iter().zip(&self.bin) {
            predicted[b as usize] += 1.0 - ops[b as usize].apply(1.0, r.chord);
        }
        for b in 0..14 {
            if self.rays[b] == 0 {
                continue;
            }
            let n = self.rays[b] as f32;
            opacity_sum += (predicted[b] / n - self.occluded[b] as f32 / n).abs();
            opacity_bins += 1;
            if self.hits[b] < MIN_SURFACE_HITS {
                continue;
            }
            let to_viewer = -BINS[b];
            for (j, l) in LIGHTS.iter().enumerate() {
                let light = LightSample {
                    to_light: *l,
                    distance: f32::INFINITY,
                    irradiance: Vec3::splat(std::f32::consts::PI),
                };
                let c = record.radiance(params, specular, to_viewer, &light, 1.0, Vec3::ZERO);
                shading_sum += (luminance(c) - self.lambert[b][j] / self.hits[b] as f32).abs();
                shading_terms += 1;
            }
        }
        let o = if opacity_bins > 0 { opacity_sum / opacity_bins as f32 } else { 0.0 };
        let s = if shading_terms > 0 { shading_sum / shading_terms as f32 } else { 0.0 };
        o + s
    }
}

fn nearest_bin(d: Vec3) -> usize {
    let mut best = 0;
    let mut best_dot = f32::NEG_INFINITY;
    for (i, b) in BINS.iter().enumerate() {
        let dot = b.dot(d);
        if dot > best_dot {
            best_dot = dot;
            best = i;
        }
    }
    best
}

/// The directional error of `record` on held-out samples of its voxel (module docs), exposed
/// for tests and reports.
pub fn directional_error<R: RecordAppearance>(
    record: &R,
    params: R::Params,
    specular: Option<&SpecularRecord>,
    heldout: &VoxelSamples,
) -> f32 {
    HeldOut::new(heldout).error(record, params, specular)
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
}

/// All three candidates of every voxel with their held-out errors: built once, then
/// [`Candidates::select`]ed at any number of thresholds.
#[derive(Clone, Debug)]
pub struct Candidates {
    grid: GridSpec,
    rule: VirtualMeshParams,
    voxels: Vec<Candidate>,
    specular: bool,
}

impl Candidates {
    /// Fits the three candidates of every voxel (from the same `rays` samples) and scores each
    /// on `heldout` further rays. Parallel over voxels; deterministic.
    pub fn build(ctx: &SamplingContext<'_>, options: &AdaptiveOptions) -> Result<Self> {
        if options.rays == 0 || options.heldout == 0 {
            return Err(Error::InvalidParameter {
                name: "rays/heldout",
                value: format!("{}/{}", options.rays, options.heldout),
                reason: "the fit and the error estimate each need at least one ray".into(),
            });
        }
        let specular = ctx.has_specular();
        let rule = options.vmesh;
        let voxels: Vec<Candidate> = (0..ctx.voxel_count())
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
                    let errors = [
                        h.error(&average, (), spec.as_ref()),
                        h.error(&sggx, (), spec.as_ref()),
                        h.error(&vmesh, rule, spec.as_ref()),
                    ];
                    Some(Candidate {
                        code: morton::encode(ctx.coord(i)),
                        average,
                        sggx,
                        vmesh,
                        specular: spec,
                        errors,
                    })
                },
            )
            .flatten()
            .collect();
        Ok(Self { grid: *ctx.grid(), rule, voxels, specular })
    }

    /// Voxels with candidates.
    pub fn len(&self) -> usize {
        self.voxels.len()
    }

    /// Whether no voxel has candidates.
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty()
    }

    /// Per voxel (brick-map Morton order), the held-out error of Averages, \[VJK21\] and the
    /// virtual mesh.
    pub fn errors(&self) -> impl Iterator<Item = [f32; 3]> + '_ {
        self.voxels.iter().map(|v| v.errors)
    }

    /// The kind chosen for a voxel with `errors` at `threshold`: the cheapest at most
    /// `threshold`, else the one with the least error (the cheaper on ties).
    pub fn choose(errors: [f32; 3], threshold: f32) -> Kind {
        const KINDS: [Kind; 3] = [Kind::Average, Kind::Sggx, Kind::VirtualMesh];
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

    /// The mixed grid at `threshold`.
    pub fn select(&self, threshold: f32) -> Result<AdaptiveGrid> {
        if !(threshold.is_finite() && threshold >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "threshold",
                value: threshold.to_string(),
                reason: "must be finite and non-negative".into(),
            });
        }
        let mut g = AdaptiveGrid {
            grid: self.grid,
            rule: self.rule,
            refs: BrickMap::new(self.grid.dims),
            averages: Vec::new(),
            sggx: Vec::new(),
            vmesh: Vec::new(),
            specular: self.specular.then(Vec::new),
        };
        let mut refs = Vec::with_capacity(self.voxels.len());
        for v in &self.voxels {
            let kind = Self::choose(v.errors, threshold);
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

    /// Heap bytes: the tag brick map (headers, lookup, tags), the record arrays and the
    /// specular records.
    pub fn memory_bytes(&self) -> usize {
        self.refs.memory_bytes()
            + self.averages.capacity() * size_of::<AverageRecord>()
            + self.sggx.capacity() * size_of::<SggxRecord>()
            + self.vmesh.capacity() * size_of::<VirtualMeshRecord>()
            + self.specular.as_ref().map_or(0, |s| s.capacity() * size_of::<SpecularRecord>())
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
mod tests {
    use super::*;
    use crate::appearance::voxel_samples::{RaySample, SurfaceSample};

    #[test]
    fn the_cheapest_kind_under_the_threshold_wins_else_the_least_error() {
        assert_eq!(Candidates::choose([0.05, 0.01, 0.0], 0.1), Kind::Average);
        assert_eq!(Candidates::choose([0.2, 0.05, 0.0], 0.1), Kind::Sggx);
        assert_eq!(Candidates::choose([0.2, 0.15, 0.1], 0.1), Kind::VirtualMesh);
        assert_eq!(Candidates::choose([0.3, 0.2, 0.25], 0.1), Kind::Sggx);
        // Ties without any kind under the threshold go to the cheaper kind.
        assert_eq!(Candidates::choose([0.3, 0.3, 0.3], 0.1), Kind::Average);
    }

    /// Held-out lines in every bin not parallel to the plane z = ½, all hitting its white
    /// two-sided surface (normal ±z toward the line).
    fn opaque_plane(count: usize) -> VoxelSamples {
        let bins: Vec<Vec3> = BINS.iter().copied().filter(|b| b.z != 0.0).collect();
        let rays = (0..count)
            .map(|i| {
                let dir = bins[i % bins.len()];
                let normal = if dir.z < 0.0 { Vec3::Z } else { -Vec3::Z };
                RaySample {
                    dir,
                    entry: Vec3::splat(0.5),
                    chord: 1.0,
                    occluded: true,
                    surface: Some(SurfaceSample {
                        point: Vec3::splat(0.5),
                        normal,
                        albedo: Vec3::ONE,
                        specular: 0.0,
                        shininess: 1.0,
                    }),
                }
            })
            .collect();
        VoxelSamples { rays }
    }

    #[test]
    fn a_matching_record_scores_lower_than_a_wrong_one() {
        let held = opaque_plane(10 * 8);
        let good = AverageRecord::new(Vec3::ONE, Vec3::Z, 1.0);
        let transparent = AverageRecord::new(Vec3::ONE, Vec3::Z, 0.0);
        let dark = AverageRecord::new(Vec3::splat(0.2), Vec3::Z, 1.0);
        let e_good = directional_error(&good, (), None, &held);
        let e_transparent = directional_error(&transparent, (), None, &held);
        let e_dark = directional_error(&dark, (), None, &held);
        // The opacity term vanishes for the opaque record; the Averages normal is flipped
        // toward each viewer like the samples', so shading matches up to quantization.
        assert!(e_good < 0.02, "{e_good}");
        assert!((e_transparent - e_good - 1.0).abs() < 0.02, "{e_transparent} vs {e_good}");
        assert!(e_dark > e_good + 0.1, "{e_dark} vs {e_good}");
        for e in [e_good, e_transparent, e_dark] {
            assert!(e.is_finite() && e >= 0.0);
        }
    }

    #[test]
    fn every_held_out_line_falls_in_its_nearest_bin() {
        for (i, b) in BINS.iter().enumerate() {
            assert_eq!(nearest_bin(*b), i);
            assert_eq!(nearest_bin(*b * 3.0 + Vec3::splat(1e-3)), i);
        }
        for l in LIGHTS {
            assert!((l.length() - 1.0).abs() < 1e-6);
        }
    }
}
