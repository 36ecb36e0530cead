//! The held-out directional error of a record ([`super`], "The directional error").

use glam::Vec3;
use voxlod_format::records::SpecularRecord;
use voxlod_scene::LightSample;

use super::super::voxel_samples::VoxelSamples;
use super::super::{Opacity, RecordAppearance};

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

pub(super) fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Per-bin statistics of held-out lines: counts, occlusions, Lambert sums.
pub(super) struct HeldOut<'a> {
    pub(super) samples: &'a VoxelSamples,
    /// Bin of each ray.
    pub(super) bin: Vec<u8>,
    pub(super) rays: [u32; 14],
    pub(super) occluded: [u32; 14],
    pub(super) hits: [u32; 14],
    lambert: [[f32; 4]; 14],
}

impl<'a> HeldOut<'a> {
    pub(super) fn new(samples: &'a VoxelSamples) -> Self {
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

    /// Per bin, the record's opacity `1 − T` after one crossing with each held-out line's own
    /// chord, averaged over the bin's lines (0 for a bin without lines).
    pub(super) fn predicted_opacity<R: RecordAppearance>(
        &self,
        record: &R,
        params: R::Params,
    ) -> [f32; 14] {
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
        for (p, &n) in predicted.iter_mut().zip(&self.rays) {
            if n > 0 {
                *p /= n as f32;
            }
        }
        predicted
    }

    /// The directional error of `record` (module docs) given its
    /// [`HeldOut::predicted_opacity`].
    pub(super) fn error<R: RecordAppearance>(
        &self,
        record: &R,
        params: R::Params,
        specular: Option<&SpecularRecord>,
        predicted: &[f32; 14],
    ) -> f32 {
        let mut opacity_sum = 0.0;
        let mut opacity_bins = 0u32;
        let mut shading_sum = 0.0;
        let mut shading_terms = 0u32;
        for b in 0..14 {
            if self.rays[b] == 0 {
                continue;
            }
            let n = self.rays[b] as f32;
            opacity_sum += (predicted[b] - self.occluded[b] as f32 / n).abs();
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

/// The index of the bin nearest to direction `d`.
pub(super) fn nearest_bin(d: Vec3) -> usize {
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
    let h = HeldOut::new(heldout);
    h.error(record, params, specular, &h.predicted_opacity(record, params))
}
