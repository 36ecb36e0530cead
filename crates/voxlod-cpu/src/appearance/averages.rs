//! Averages (HPG 2023 §5; design note §2): one mean colour, one mean normal and one opacity per
//! voxel, the paper's 7 bytes ([`AverageRecord`]), fitted by [`fit`] and rendered through the
//! [`RecordAppearance`] implementation of [`AverageRecord`].
//!
//! # Rules (each has a unit test below)
//! - **Opacity** = occluded lines / all lines: every line whose closest hit exists counts,
//!   whether front- or back-facing, inside or outside the voxel (design note §1's booking).
//! - **Colour** = arithmetic mean of the case-(a) albedos (linear), stored as sRGB8.
//! - **Normal** = the normalized sum of the case-(a) shading normals. If the normals cancel,
//!   `|Σn| < 10⁻³·count` (a thin double-sided leaf seen from both sides), it is the principal
//!   eigenvector of `Σ n nᵀ` from [`symmetric_eigen`] instead, with its canonical sign.
//! - **No record** for a voxel without a case-(a) hit (or without lines): the subgrid would
//!   clear all 27 cells, so all representations agree on which voxels exist.
//! - **Shading** is [`shade`] with the record's colour and normal, the specular side record's
//!   level and exponent when the grid has them, and the normal **flipped toward the viewer**
//!   when `n·v < 0`: a voxel is shaded two-sided, as the ground truth shades double-sided
//!   leaves, since one mean normal cannot say which side a viewer sees. A record without a
//!   normal (all-zero bytes, never produced by [`fit`]) is shaded facing the viewer.
//!   [`AveragesNormal::AsStored`] shades with the stored normal as it is instead, as the
//!   authors' shading does with every normal it is given; [`AveragesGrid`] carries the choice.
//! - **Opacity along a direction** is the record's opacity, whatever the direction and chord
//!   ([`Opacity::Alpha`]).

use glam::{DVec3, Vec3};
use voxlod_format::records::AverageRecord;
use voxlod_scene::LightSample;

use glam::UVec3;
use voxlod_format::GridSpec;

use super::eigen::symmetric_eigen;
use super::voxel_samples::VoxelSamples;
use super::{Appearance, AppearanceGrid, Opacity};
use super::{RecordAppearance, record_material};
use crate::shading::shade;
use voxlod_format::records::SpecularRecord;

/// The Averages record of a voxel's samples (module docs), or `None` without a case-(a) hit.
pub fn fit(samples: &VoxelSamples) -> Option<AverageRecord> {
    let (mut count, mut albedo, mut normal) = (0u32, DVec3::ZERO, DVec3::ZERO);
    let mut scatter = [[0.0f64; 3]; 3];
    for s in samples.surfaces() {
        count += 1;
        albedo += s.albedo.as_dvec3();
        let n = s.normal.as_dvec3();
        normal += n;
        for (i, row) in scatter.iter_mut().enumerate() {
            for (j, m) in row.iter_mut().enumerate() {
                *m += n[i] * n[j];
            }
        }
    }
    if count == 0 {
        return None;
    }
    let n = if normal.length() >= 1e-3 * count as f64 {
        normal.normalize()
    } else {
        symmetric_eigen(scatter).1[0]
    };
    Some(AverageRecord::new((albedo / count as f64).as_vec3(), n.as_vec3(), samples.opacity()))
}

impl RecordAppearance for AverageRecord {
    type Params = ();

    fn opacity(&self, _: (), _dir: Vec3) -> Opacity {
        Opacity::Alpha(AverageRecord::opacity(self))
    }

    /// Shaded with the mean normal flipped toward the viewer (two-sided, as the ground truth
    /// shades double-sided leaves); a voxel whose normal decoded to zero faces the viewer.
    fn radiance(
        &self,
        _: (),
        specular: Option<&SpecularRecord>,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        radiance_with(
            self,
            AveragesNormal::TowardViewer,
            specular,
            to_viewer,
            light,
            visibility,
            ambient,
        )
    }

    /// The shading normal faces away from the light: [`shade`]'s direct and specular terms
    /// are `max(n·l, 0) = 0` times the visibility.
    fn needs_visibility(&self, _: (), to_viewer: Vec3, light: &LightSample) -> bool {
        shading_normal(self.normal(), to_viewer).dot(light.to_light) > 0.0
    }
}

/// The normal an Averages record shades with: its mean normal turned toward the viewer (two
/// sided), or the direction to the viewer where it has none.
#[inline]
fn shading_normal(n: Vec3, to_viewer: Vec3) -> Vec3 {
    shading_normal_with(n, to_viewer, AveragesNormal::TowardViewer)
}

/// [`shading_normal`] under `mode`: [`AveragesNormal::AsStored`] keeps the mean normal as it
/// is (the direction to the viewer still stands in for a missing one).
#[inline]
fn shading_normal_with(n: Vec3, to_viewer: Vec3, mode: AveragesNormal) -> Vec3 {
    if n == Vec3::ZERO {
        to_viewer
    } else if mode == AveragesNormal::TowardViewer && n.dot(to_viewer) < 0.0 {
        -n
    } else {
        n
    }
}

/// How an Averages voxel's mean normal meets the viewer when shading (Brito, Poulin and
/// Teichrieb 2023, §5: one average normal per voxel).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AveragesNormal {
    /// Ours: flipped toward the viewer where it faces away (two-sided, as the ground truth
    /// shades double-sided surfaces).
    #[default]
    TowardViewer,
    /// As stored, whichever side the viewer is on: the authors' shading (`phongShading` of
    /// their `representations.h`) uses every normal it is given as it is, so a voxel seen
    /// from behind its mean normal is lit as its front is.
    AsStored,
}

/// Radiance of one Averages record toward `to_viewer` with the normal rule `mode` (module
/// docs); [`RecordAppearance::radiance`] is this with [`AveragesNormal::TowardViewer`].
pub fn radiance_with(
    rec: &AverageRecord,
    mode: AveragesNormal,
    specular: Option<&SpecularRecord>,
    to_viewer: Vec3,
    light: &LightSample,
    visibility: f32,
    ambient: Vec3,
) -> Vec3 {
    let n = shading_normal_with(rec.normal(), to_viewer, mode);
    shade(&record_material(rec.color(), specular), n, to_viewer, light, visibility, ambient)
}

/// A grid of Averages records with the choice of [`AveragesNormal`] (the plain
/// [`AppearanceGrid`] of Averages records always flips toward the viewer).
#[derive(Clone, Debug)]
pub struct AveragesGrid {
    /// The records (and specular side records).
    pub grid: AppearanceGrid<AverageRecord>,
    /// How the mean normal meets the viewer.
    pub normal: AveragesNormal,
}

impl Appearance for AveragesGrid {
    fn grid(&self) -> &GridSpec {
        &self.grid.grid
    }

    fn len(&self) -> usize {
        self.grid.records.len()
    }

    fn index_of(&self, c: UVec3) -> Option<usize> {
        self.grid.records.index_of(c)
    }

    fn opacity(&self, index: usize, _dir: Vec3) -> Opacity {
        Opacity::Alpha(self.grid.records.values()[index].opacity())
    }

    fn radiance(
        &self,
        index: usize,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        let rec = &self.grid.records.values()[index];
        let specular = self.grid.specular.as_ref().map(|s| &s[index]);
        radiance_with(rec, self.normal, specular, to_viewer, light, visibility, ambient)
    }

    fn needs_visibility(&self, index: usize, to_viewer: Vec3, light: &LightSample) -> bool {
        let n = self.grid.records.values()[index].normal();
        shading_normal_with(n, to_viewer, self.normal).dot(light.to_light) > 0.0
    }
}

#[cfg(test)]
mod tests {
    use voxlod_format::BrickMap;
    use voxlod_scene::MaterialSample;

    use super::*;
    use crate::appearance::voxel_samples::{RaySample, SurfaceSample};

    fn line(occluded: bool, normal: Option<Vec3>, albedo: Vec3) -> RaySample {
        RaySample {
            dir: Vec3::NEG_Z,
            entry: Vec3::new(0.5, 0.5, 1.0),
            chord: 1.0,
            occluded,
            surface: normal.map(|normal| SurfaceSample {
                point: Vec3::splat(0.5),
                normal,
                albedo,
                specular: 0.0,
                shininess: 0.0,
            }),
        }
    }

    fn samples(rays: Vec<RaySample>) -> VoxelSamples {
        VoxelSamples { rays }
    }

    #[test]
    fn opacity_counts_every_occluded_line_over_all_lines() {
        let red = Vec3::new(0.8, 0.1, 0.1);
        // 1 front hit, 2 occluded without a normal (back-facing or outside), 1 miss.
        let s = samples(vec![
            line(true, Some(Vec3::Z), red),
            line(true, None, Vec3::ZERO),
            line(true, None, Vec3::ZERO),
            line(false, None, Vec3::ZERO),
        ]);
        let r = fit(&s).unwrap();
        assert_eq!(r.opacity, 191, "round(255·3/4)");
        assert!((r.color() - red).abs().max_element() < 0.01, "{}", r.color());
        assert_eq!(r.normal(), Vec3::Z);
        assert!((0.0..=1.0).contains(&r.opacity()));
    }

    #[test]
    fn colour_and_normal_are_means_of_front_hits_only() {
        let (a, b) = (Vec3::new(0.2, 0.4, 0.6), Vec3::new(0.6, 0.4, 0.2));
        let s = samples(vec![
            line(true, Some(Vec3::X), a),
            line(true, Some(Vec3::Y), b),
            line(true, None, Vec3::ONE),
        ]);
        let r = fit(&s).unwrap();
        assert!((r.color() - (a + b) / 2.0).abs().max_element() < 0.01);
        let n = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!((r.normal() - n).length() < 0.02, "{}", r.normal());
        assert_eq!(r.opacity, 255);
    }

    #[test]
    fn no_front_hit_gives_no_record() {
        assert_eq!(fit(&VoxelSamples::default()), None);
        let s = samples(vec![line(true, None, Vec3::ONE), line(false, None, Vec3::ONE)]);
        assert_eq!(fit(&s), None);
    }

    /// n and −n (a double-sided leaf seen from both sides) cancel: the normal is the principal
    /// axis ±n with the canonical sign, finite and unit.
    #[test]
    fn cancelling_normals_fall_back_to_the_principal_axis() {
        let n = Vec3::new(0.0, -0.6, 0.8);
        let s = samples(vec![
            line(true, Some(n), Vec3::ONE),
            line(true, Some(-n), Vec3::ONE),
            line(true, Some(n), Vec3::ONE),
            line(true, Some(-n), Vec3::ONE),
        ]);
        let r = fit(&s).unwrap();
        let m = r.normal();
        assert!(m.is_finite() && (m.length() - 1.0).abs() < 1e-5);
        assert!(m.dot(n).abs() > 0.999, "{m}");
        assert!(m.z > 0.0, "canonical sign: largest component positive, {m}");
    }

    #[test]
    fn quantization_round_trips_within_half_an_lsb() {
        for k in 0..=20 {
            let o = k as f32 / 20.0;
            let hits = (o * 1000.0).round() as usize;
            let mut rays = vec![line(true, Some(Vec3::Z), Vec3::splat(0.3)); hits.max(1)];
            rays.extend(vec![line(false, None, Vec3::ZERO); 1000 - hits.max(1)]);
            let r = fit(&samples(rays)).unwrap();
            let exact = hits.max(1) as f32 / 1000.0;
            assert!((r.opacity() - exact).abs() <= 0.5 / 255.0 + 1e-6, "{o}: {}", r.opacity());
        }
    }

    fn grid_of(
        record: AverageRecord,
        specular: Option<SpecularRecord>,
    ) -> AppearanceGrid<AverageRecord> {
        let grid = GridSpec::new(glam::DVec3::ZERO, 1.0, UVec3::splat(2)).unwrap();
        let records = BrickMap::from_voxels(grid.dims, [(UVec3::ONE, record)]).unwrap();
        AppearanceGrid { grid, records, specular: specular.map(|s| vec![s]) }
    }

    /// Two-sided shading: the normal is flipped toward the viewer, so a voxel seen from behind
    /// shades like its mirror seen from the front; opacity ignores the direction.
    #[test]
    fn a_voxel_facing_away_from_the_light_does_not_need_its_visibility() {
        use crate::random::rand_f32;
        let dir = |i: u32, k: u32| {
            Vec3::new(rand_f32(i, k, 0), rand_f32(i, k, 1), rand_f32(i, k, 2)) * 2.0 - 1.0
        };
        let (mut skipped, mut needed) = (0, 0);
        for i in 0..2000u32 {
            let record = AverageRecord::new(Vec3::new(0.2, 0.5, 0.9), dir(i, 0), 0.7);
            let g = grid_of(record, None);
            let to_viewer = dir(i, 1).normalize();
            let light = LightSample {
                to_light: dir(i, 2).normalize(),
                distance: f32::INFINITY,
                irradiance: Vec3::splat(2.0),
            };
            let shaded = |v: f32| g.radiance(0, to_viewer, &light, v, Vec3::splat(0.1));
            if g.needs_visibility(0, to_viewer, &light) {
                needed += 1;
                assert_ne!(shaded(0.0), shaded(1.0), "voxel {i}: lit, so visibility matters");
            } else {
                skipped += 1;
                for v in [0.0, 0.3, 1.0] {
                    assert_eq!(shaded(v).to_array(), shaded(1.0).to_array(), "voxel {i}");
                }
            }
        }
        // Random normals, viewers and lights: about half face away from the light.
        assert!(skipped > 600 && needed > 600, "{skipped} skipped, {needed} needed");
    }

    #[test]
    fn radiance_is_two_sided_and_uses_shade() {
        let g = grid_of(AverageRecord::new(Vec3::splat(0.5), Vec3::Z, 0.6), None);
        assert_eq!(g.len(), 1);
        assert_eq!(g.index_of(UVec3::ONE), Some(0));
        assert_eq!(g.index_of(UVec3::ZERO), None);
        let light = LightSample {
            to_light: Vec3::Z,
            distance: f32::INFINITY,
            irradiance: Vec3::splat(3.0),
        };
        let front = g.radiance(0, Vec3::new(0.0, 0.6, 0.8), &light, 1.0, Vec3::splat(0.1));
        let m = MaterialSample {
            albedo: g.records.values()[0].color(),
            alpha: 1.0,
            ..Default::default()
        };
        let expected = shade(&m, Vec3::Z, Vec3::new(0.0, 0.6, 0.8), &light, 1.0, Vec3::splat(0.1));
        assert_eq!(front, expected);
        let mirrored = LightSample { to_light: Vec3::NEG_Z, ..light };
        let back = g.radiance(0, Vec3::new(0.0, 0.6, -0.8), &mirrored, 1.0, Vec3::splat(0.1));
        assert!((back - front).abs().max_element() < 1e-6, "{back} vs {front}");
        for d in [Vec3::X, Vec3::NEG_Z, Vec3::new(1.0, 2.0, 3.0).normalize()] {
            assert_eq!(g.opacity(0, d), Opacity::Alpha(g.records.values()[0].opacity()));
        }
        // A normal-less record is shaded facing the viewer (finite, lit from the front).
        let none = grid_of(AverageRecord { normal: [0; 3], ..g.records.values()[0] }, None);
        let r = none.radiance(0, Vec3::Z, &light, 1.0, Vec3::ZERO);
        assert!(r.is_finite() && r.x > 0.0);
    }

    #[test]
    fn specular_side_records_add_a_highlight() {
        let rec = AverageRecord::new(Vec3::splat(0.5), Vec3::Z, 1.0);
        let diffuse = grid_of(rec, None);
        let shiny = grid_of(rec, Some(SpecularRecord::new(0.5, 64.0)));
        assert_eq!(shiny.record_bytes(), 10);
        let light =
            LightSample { to_light: Vec3::Z, distance: f32::INFINITY, irradiance: Vec3::ONE };
        let d = diffuse.radiance(0, Vec3::Z, &light, 1.0, Vec3::ZERO);
        let s = shiny.radiance(0, Vec3::Z, &light, 1.0, Vec3::ZERO);
        assert!(s.x > d.x * 2.0, "{s} vs {d}");
    }

    /// Seen from behind its mean normal, ours shades the mirrored normal, the authors' choice
    /// the normal as stored: lit from the front, the back view is dark with ours (the flipped
    /// normal faces away from the light) and lit as stored; from the front both agree.
    #[test]
    fn stored_normal_is_not_flipped_toward_the_viewer() {
        let rec = AverageRecord::new(Vec3::splat(0.5), Vec3::Z, 0.6);
        let flip = AveragesGrid { grid: grid_of(rec, None), normal: AveragesNormal::TowardViewer };
        let stored = AveragesGrid { normal: AveragesNormal::AsStored, ..flip.clone() };
        let pi = std::f32::consts::PI;
        let light =
            LightSample { to_light: Vec3::Z, distance: f32::INFINITY, irradiance: Vec3::splat(pi) };
        let front = Vec3::new(0.0, 0.6, 0.8);
        let back = Vec3::new(0.0, 0.6, -0.8);
        let ambient = Vec3::splat(0.1);
        assert_eq!(
            flip.radiance(0, front, &light, 1.0, ambient),
            stored.radiance(0, front, &light, 1.0, ambient)
        );
        // The flipping grid equals the plain grid of records.
        let plain = grid_of(rec, None);
        assert_eq!(
            flip.radiance(0, back, &light, 1.0, ambient),
            plain.radiance(0, back, &light, 1.0, ambient)
        );
        let dark = flip.radiance(0, back, &light, 1.0, ambient);
        let lit = stored.radiance(0, back, &light, 1.0, ambient);
        let albedo = rec.color();
        assert!((dark - albedo * ambient).abs().max_element() < 1e-6, "ambient only: {dark}");
        let full = albedo * (ambient + Vec3::ONE);
        assert!((lit - full).abs().max_element() < 1e-5, "n·l = 1 as stored: {lit} vs {full}");
        assert!(!flip.needs_visibility(0, back, &light));
        assert!(stored.needs_visibility(0, back, &light));
        assert_eq!(stored.opacity(0, back), Opacity::Alpha(rec.opacity()));
        assert_eq!((stored.len(), stored.index_of(UVec3::ONE)), (1, Some(0)));
    }
}
