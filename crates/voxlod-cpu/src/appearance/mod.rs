//! Filtered voxel appearance (Brito, Poulin and Teichrieb, HPG 2023; design and every open choice in
//! `docs/design/filtered-appearance.md`): per-voxel ray sampling from outside the voxel
//! ([`voxel_samples`], drawn by [`line_sampler`]), the records each representation fits to those samples, and how each record
//! answers the two questions a voxel renderer asks — how much light does this voxel stop along
//! a direction ([`Opacity`]), and what radiance does it send toward the viewer
//! ([`Appearance::radiance`]).
//!
//! All representations are fitted from the same [`voxel_samples::VoxelSamples`] of a voxel, so their
//! differences measure the representation, not the sampling.

pub mod adaptive;
pub mod averages;
pub mod eigen;
pub mod line_sampler;
pub mod microsurface;
pub mod nonexp;
pub mod precompute;
pub mod sggx;
pub mod subgrid;
pub mod transmittance;
pub mod virtual_mesh;
pub mod voxel_samples;

use glam::Vec3;
use voxlod_format::records::SpecularRecord;

use crate::render::filtered::{self, PixelPattern, VjkChord};
use averages::AveragesNormal;
use precompute::PrecomputeOptions;
use subgrid::DirectionalRule;
use virtual_mesh::{FaceSampling, ShadingFallback, VirtualMeshParams};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::LightSample;

/// Where this implementation chose differently from the authors' public code of Brito, Poulin
/// and Teichrieb 2023 (`cjsb/voxel-filtered-appearance`), one field per choice, each an enum
/// whose default is ours and whose other variant is theirs; plus the seeds of the two random
/// sources a paired comparison varies (the precompute's sampling lines, the render's pixel
/// pattern). The default is exactly today's pipeline.
///
/// It reaches the three places it acts on through [`AuthorsChoices::virtual_mesh`] (the
/// virtual mesh's directional opacity, face samples and fallback),
/// [`AuthorsChoices::precompute`] (the lines' seed), [`AuthorsChoices::render`] (the \[VJK21\]
/// chord and the pixel pattern of [`crate::render::filtered`]) and
/// [`averages::AveragesGrid`] (the Averages normal).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct AuthorsChoices {
    /// Directional opacity of the virtual mesh's subgrid (§3.4): ours
    /// [`DirectionalRule::Lines`], the authors' [`DirectionalRule::Authors`] (their window,
    /// circle radii, 3×3 kernel and max rule, not normalized).
    pub opacity_rule: DirectionalRule,
    /// Shading samples per visible distribution face of the virtual mesh (§3.3, §4).
    pub face_samples: FaceSamples,
    /// What a virtual-mesh voxel shades with when no normal faces the viewer.
    pub fallback: ShadingFallback,
    /// The chord \[VJK21\] voxels are evaluated with when rendering (§4 caches every method's
    /// opacity per voxel).
    pub vjk_chord: VjkChord,
    /// Whether an Averages voxel's mean normal is flipped toward the viewer (§5).
    pub averages_normal: AveragesNormal,
    /// Seed of the precompute's sampling lines ([`PrecomputeOptions::seed`]; 0 by default).
    pub precompute_seed: u32,
    /// Where the 4 camera rays of a pixel go ([`PixelPattern::Fixed`] by default; a seeded
    /// jittered pattern otherwise).
    pub pattern: PixelPattern,
}

/// Shading samples per visible distribution face of the virtual mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FaceSamples {
    /// Ours: [`virtual_mesh::DEFAULT_SAMPLES_PER_FACE`] (16) fixed stratified points
    /// ([`FaceSampling::Stratified`]).
    #[default]
    Fixed,
    /// The paper's "as many as 40 samples per visible face" (§4), drawn as the authors' code
    /// does: [`virtual_mesh::AUTHORS_SAMPLES_PER_FACE`] random samples of
    /// [`virtual_mesh::AUTHORS_ATTEMPTS`] attempts each ([`FaceSampling::Random`]).
    Random {
        /// Seed of the samples.
        seed: u32,
    },
}

impl AuthorsChoices {
    /// Every choice the authors' way (seeds 0, the fixed pixel pattern): their directional
    /// opacity, 40 random face samples, the unshaded fallback, a cached \[VJK21\] chord
    /// ([`VjkChord::CachedChord`]) and the Averages normal as stored.
    pub fn authors() -> Self {
        Self {
            opacity_rule: DirectionalRule::Authors,
            face_samples: FaceSamples::Random { seed: 0 },
            fallback: ShadingFallback::Unshaded,
            vjk_chord: VjkChord::CachedChord,
            averages_normal: AveragesNormal::AsStored,
            ..Self::default()
        }
    }

    /// The virtual-mesh parameters of these choices, on top of `base` (whose projected-area
    /// switch is kept): the opacity rule, the face samples and the fallback.
    pub fn virtual_mesh(&self, base: VirtualMeshParams) -> VirtualMeshParams {
        let (samples_per_face, sampling) = match self.face_samples {
            FaceSamples::Fixed => (base.samples_per_face, FaceSampling::Stratified),
            FaceSamples::Random { seed } => {
                (virtual_mesh::AUTHORS_SAMPLES_PER_FACE, FaceSampling::authors(seed))
            }
        };
        VirtualMeshParams {
            rule: self.opacity_rule,
            samples_per_face,
            sampling,
            fallback: self.fallback,
            ..base
        }
    }

    /// The face samples and fallback of these choices on top of `base`, keeping its rule (for
    /// the study's rows that compare rules).
    pub fn virtual_mesh_shading(&self, base: VirtualMeshParams) -> VirtualMeshParams {
        VirtualMeshParams { rule: base.rule, ..self.virtual_mesh(base) }
    }

    /// The precompute options with `rays` lines per voxel and these choices' seed.
    pub fn precompute(&self, rays: u32) -> PrecomputeOptions {
        PrecomputeOptions { rays, seed: self.precompute_seed }
    }

    /// `base` with these choices' \[VJK21\] chord and pixel pattern.
    pub fn render(&self, base: filtered::Options) -> filtered::Options {
        filtered::Options { vjk_chord: self.vjk_chord, pattern: self.pattern, ..base }
    }
}

/// How a voxel attenuates light along one direction: what a renderer caches per voxel and
/// direction, and applies per ray with that ray's chord through the voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Opacity {
    /// Classic alpha: the transmittance is multiplied by `1 − α`, whatever the chord
    /// (Averages, virtual mesh + opacity subgrid).
    Alpha(f32),
    /// \[VJK21\] non-exponential transmittance: extinction `sigma` per voxel size and blend
    /// `gamma`; a ray with chord `ℓ` (voxel units) updates `T ← min(T, f(f⁻¹(T, γ) + σℓ, γ))`.
    NonExponential {
        /// Extinction per voxel size.
        sigma: f32,
        /// Blend: 1 exponential, 0 linear.
        gamma: f32,
    },
}

impl Opacity {
    /// The transmittance after a ray with transmittance `t` crosses the voxel over `chord`
    /// voxel units.
    #[inline]
    pub fn apply(self, t: f32, chord: f32) -> f32 {
        match self {
            Opacity::Alpha(a) => t * (1.0 - a.clamp(0.0, 1.0)),
            Opacity::NonExponential { sigma, gamma } => {
                transmittance::compose(t, sigma, gamma, chord)
            }
        }
    }
}

/// A grid of per-voxel appearance records of type `R`, in the brick map's Morton order, with
/// optional specular side records (present only for scenes with specular materials).
#[derive(Clone, Debug)]
pub struct AppearanceGrid<R> {
    /// The grid.
    pub grid: GridSpec,
    /// One record per voxel that has appearance.
    pub records: BrickMap<R>,
    /// One specular record per voxel (same order), if the scene is specular anywhere.
    pub specular: Option<Vec<SpecularRecord>>,
}

impl<R> AppearanceGrid<R> {
    /// Bytes per voxel of the records themselves (record + specular side record), the
    /// representation's cost without the sparse structure.
    pub fn record_bytes(&self) -> usize {
        size_of::<R>() + self.specular.as_ref().map_or(0, |_| size_of::<SpecularRecord>())
    }

    /// Packed bytes of the whole grid, what a renderer holds: the brick map (headers, packed
    /// look-up, records; [`BrickMap::memory_bytes`]) and the specular records, counted from
    /// lengths (no growth slack).
    pub fn memory_bytes(&self) -> usize {
        self.records.memory_bytes()
            + self.specular.as_ref().map_or(0, |s| s.len() * size_of::<SpecularRecord>())
    }
}

/// What a voxel renderer needs of a representation. Implemented by each record grid; the
/// renderer caches both answers per voxel and frame for the direction from the voxel centre to
/// the camera (and the light, for shadows).
pub trait Appearance: Sync {
    /// The grid the voxels live in.
    fn grid(&self) -> &GridSpec;

    /// Number of voxels with a record (indices `0..len()`, brick-map Morton order).
    fn len(&self) -> usize;

    /// Whether no voxel has a record.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of the record of voxel `c`, if it has one.
    fn index_of(&self, c: glam::UVec3) -> Option<usize>;

    /// How voxel `index` attenuates light travelling along unit direction `dir`.
    fn opacity(&self, index: usize, dir: Vec3) -> Opacity;

    /// Radiance voxel `index` sends toward the viewer: `to_viewer` is the unit direction from
    /// the voxel toward the eye, `light` the light seen from the voxel centre, `visibility` its
    /// shadow visibility in [0, 1], `ambient` the ambient term of [`crate::shading::shade`].
    /// Every implementation shades with [`crate::shading::shade`].
    fn radiance(
        &self,
        index: usize,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3;

    /// Whether [`Appearance::radiance`] of voxel `index` for this viewer and light can depend
    /// on `visibility`. `false` promises that the direct term is exactly zero (every normal
    /// the voxel shades with faces away from the light), so the result is the same, bit for
    /// bit, for every visibility, and a renderer may skip the shadow ray. The default, `true`,
    /// is always correct.
    fn needs_visibility(&self, index: usize, to_viewer: Vec3, light: &LightSample) -> bool {
        let _ = (index, to_viewer, light);
        true
    }
}

/// The per-voxel half of [`Appearance`]: what one record answers on its own, given the
/// parameters its grid shares (for example the directional-opacity rule of the virtual mesh).
/// Mixed grids ([`adaptive`]) and the Adaptive selector's error estimate evaluate records
/// through it; every grid of one record type implements [`Appearance`] on top of it.
pub trait RecordAppearance: Copy + Send + Sync {
    /// Parameters shared by all records of a grid.
    type Params: Copy + Send + Sync + Default + std::fmt::Debug;

    /// How this voxel attenuates light travelling along unit direction `dir`.
    fn opacity(&self, params: Self::Params, dir: Vec3) -> Opacity;

    /// Radiance toward the viewer, as [`Appearance::radiance`]; `specular` is the voxel's
    /// specular side record, if the grid has them.
    fn radiance(
        &self,
        params: Self::Params,
        specular: Option<&SpecularRecord>,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3;

    /// As [`Appearance::needs_visibility`]: `false` only when [`RecordAppearance::radiance`]
    /// does not depend on the visibility. The default, `true`, is always correct.
    fn needs_visibility(&self, params: Self::Params, to_viewer: Vec3, light: &LightSample) -> bool {
        let _ = (params, to_viewer, light);
        true
    }
}

/// The material a record shades with: its albedo, and the specular side record if any.
pub fn record_material(
    albedo: Vec3,
    specular: Option<&SpecularRecord>,
) -> voxlod_scene::MaterialSample {
    voxlod_scene::MaterialSample {
        albedo,
        alpha: 1.0,
        specular: Vec3::splat(specular.map_or(0.0, |s| s.level())),
        shininess: specular.map_or(1.0, |s| s.exponent()),
    }
}

/// Every grid of records without parameters (Averages, \[VJK21\]) answers through its
/// records' [`RecordAppearance`].
impl<R: RecordAppearance<Params = ()>> Appearance for AppearanceGrid<R> {
    fn grid(&self) -> &GridSpec {
        &self.grid
    }

    fn len(&self) -> usize {
        self.records.len()
    }

    fn index_of(&self, c: glam::UVec3) -> Option<usize> {
        self.records.index_of(c)
    }

    fn opacity(&self, index: usize, dir: Vec3) -> Opacity {
        self.records.values()[index].opacity((), dir)
    }

    fn radiance(
        &self,
        index: usize,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        let specular = self.specular.as_ref().map(|s| &s[index]);
        self.records.values()[index].radiance((), specular, to_viewer, light, visibility, ambient)
    }

    fn needs_visibility(&self, index: usize, to_viewer: Vec3, light: &LightSample) -> bool {
        self.records.values()[index].needs_visibility((), to_viewer, light)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default choices are today's pipeline; each of the authors' choices moves exactly
    /// its own parameter.
    #[test]
    fn default_choices_are_ours_and_each_authors_choice_moves_its_parameter() {
        let ours = AuthorsChoices::default();
        assert_eq!(ours.virtual_mesh(VirtualMeshParams::default()), VirtualMeshParams::default());
        assert_eq!(ours.precompute(150), PrecomputeOptions::default());
        let plain = filtered::Options { width: 7, ..Default::default() };
        assert_eq!(ours.render(plain), plain);

        let theirs = AuthorsChoices::authors();
        let p =
            theirs.virtual_mesh(VirtualMeshParams { projected_area: true, ..Default::default() });
        assert_eq!(p.rule, DirectionalRule::Authors);
        assert_eq!(p.samples_per_face, virtual_mesh::AUTHORS_SAMPLES_PER_FACE);
        assert_eq!(
            p.sampling,
            FaceSampling::Random { attempts: virtual_mesh::AUTHORS_ATTEMPTS, seed: 0 }
        );
        assert_eq!(p.fallback, ShadingFallback::Unshaded);
        assert!(p.projected_area, "the base's projected-area switch is kept");
        let shading = theirs.virtual_mesh_shading(VirtualMeshParams {
            rule: DirectionalRule::Circles,
            ..Default::default()
        });
        assert_eq!(shading.rule, DirectionalRule::Circles);
        assert_eq!(shading.fallback, ShadingFallback::Unshaded);
        assert_eq!(theirs.render(plain).vjk_chord, VjkChord::CachedChord);
        assert_eq!(theirs.averages_normal, AveragesNormal::AsStored);

        let seeded = AuthorsChoices {
            precompute_seed: 3,
            pattern: PixelPattern::Jittered { seed: 5 },
            ..ours
        };
        assert_eq!(seeded.precompute(64), PrecomputeOptions { rays: 64, seed: 3 });
        assert_eq!(seeded.render(plain).pattern, PixelPattern::Jittered { seed: 5 });
    }
}
