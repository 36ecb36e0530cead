//! Validation of the selector's errors against what a voxel's representation measurably does
//! to the rendered image.
//!
//! # Measured contribution
//! Every voxel of the grid is rendered as kind `from` (by default the virtual mesh), the base
//! images; then, for each sampled voxel alone, the same frames are rendered with that one
//! voxel switched to kind `to` (by default Averages: the selector's question, which voxels
//! keep their image when made cheap). The voxel's **measured benefit** is the
//! drop of the squared error against the reference images, summed over the pixels, colour
//! channels and views and divided by their count (a change of MSE on the [0, 1] sRGB scale;
//! positive when the switch helps). The renderer is deterministic, so a switch that changes no
//! pixel measures exactly 0; its shadows are on, so a voxel that only shadows others counts
//! (which makes almost every switch change some pixel a little: the correlations are also
//! given over the voxels whose switch moves a pixel by half an 8-bit step).
//! Errors are computed on the renders' unquantized sRGB values against the 8-bit references.
//!
//! # Predicted benefit
//! - held-out: `E_from − E_to` of the held-out directional errors;
//! - image: `E_from² − E_to²` of the predicted image errors (a root mean square, squared back
//!   to a mean square like the MSE).
//!
//! Each is compared with the measured benefit by its Spearman rank correlation (average ranks
//! for ties), over every sampled voxel and over those whose switch changed the image.

use glam::{UVec3, Vec3};
use rayon::prelude::*;
use voxlod_format::GridSpec;
use voxlod_format::records::Kind;
use voxlod_format::records::quant::linear_to_srgb;
use voxlod_scene::{Camera, Image, Light, LightSample, Srgb8Image};

use super::{AdaptiveGrid, Candidates};
use crate::appearance::{Appearance, Opacity};
use crate::render::filtered::{self, FrameCache};
use crate::{Error, Result};

/// Settings of [`measure`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContributionOptions {
    /// Voxels measured, evenly spaced in the grid's Morton order (all of them if fewer).
    pub samples: usize,
    /// The kind every voxel starts as.
    pub from: Kind,
    /// The kind one voxel at a time is switched to.
    pub to: Kind,
    /// The frames (image size, ambient term, shadows).
    pub render: filtered::Options,
}

impl Default for ContributionOptions {
    fn default() -> Self {
        Self {
            samples: 256,
            from: Kind::VirtualMesh,
            to: Kind::Average,
            render: filtered::Options { width: 64, height: 64, ..Default::default() },
        }
    }
}

/// One measured voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelContribution {
    /// Index of the voxel (brick-map Morton order).
    pub voxel: usize,
    /// Measured drop of the MSE when the voxel alone switches.
    pub measured: f64,
    /// Whether the switch moved some pixel of some view by at least half an 8-bit sRGB step
    /// (it would change the 8-bit image).
    pub changed: bool,
    /// Predicted benefit by the held-out directional error.
    pub heldout: f64,
    /// Predicted benefit by the image error.
    pub image: f64,
}

/// Rank correlations of the two predictors with the measured benefit.
#[derive(Clone, Debug, PartialEq)]
pub struct ContributionCheck {
    /// Every measured voxel.
    pub voxels: Vec<VoxelContribution>,
    /// How many of them changed the 8-bit image when switched ([`VoxelContribution::changed`]).
    pub changed: usize,
    /// Spearman correlation of the held-out prediction with the measured benefit, all voxels.
    pub heldout_spearman: f64,
    /// Spearman correlation of the image prediction with the measured benefit, all voxels.
    pub image_spearman: f64,
    /// As `heldout_spearman`, over the voxels that changed the image.
    pub heldout_spearman_changed: f64,
    /// As `image_spearman`, over the voxels that changed the image.
    pub image_spearman_changed: f64,
}

/// Spearman's rank correlation of `a` and `b` (average ranks for ties); NaN when either is
/// constant or they have fewer than two elements. Errors when their lengths differ.
pub fn spearman(a: &[f64], b: &[f64]) -> Result<f64> {
    if a.len() != b.len() {
        return Err(Error::InvalidParameter {
            name: "spearman",
            value: format!("{} and {} values", a.len(), b.len()),
            reason: "the two series must have the same length".into(),
        });
    }
    let (ra, rb) = (ranks(a), ranks(b));
    let n = a.len() as f64;
    if a.len() < 2 {
        return Ok(f64::NAN);
    }
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in ra.iter().zip(&rb) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    Ok(if saa > 0.0 && sbb > 0.0 { sab / (saa * sbb).sqrt() } else { f64::NAN })
}

/// Ranks from 1, ties sharing their average rank. NaN sorts last.
fn ranks(x: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&i, &j| x[i].total_cmp(&x[j]));
    let mut r = vec![0.0; x.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && x[order[j + 1]] == x[order[i]] {
            j += 1;
        }
        let avg = (i + j) as f64 / 2.0 + 1.0;
        for &k in &order[i..=j] {
            r[k] = avg;
        }
        i = j + 1;
    }
    r
}

/// A grid that answers as `base` everywhere except voxel `switched`, which answers as `alt`.
struct Switched<'a> {
    base: &'a AdaptiveGrid,
    alt: &'a AdaptiveGrid,
    switched: usize,
}

impl Switched<'_> {
    fn pick(&self, index: usize) -> &AdaptiveGrid {
        if index == self.switched { self.alt } else { self.base }
    }
}

impl Appearance for Switched<'_> {
    fn grid(&self) -> &GridSpec {
        self.base.grid()
    }

    fn len(&self) -> usize {
        self.base.len()
    }

    fn index_of(&self, c: UVec3) -> Option<usize> {
        self.base.index_of(c)
    }

    fn opacity(&self, index: usize, dir: Vec3) -> Opacity {
        self.pick(index).opacity(index, dir)
    }

    fn radiance(
        &self,
        index: usize,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        self.pick(index).radiance(index, to_viewer, light, visibility, ambient)
    }

    fn needs_visibility(&self, index: usize, to_viewer: Vec3, light: &LightSample) -> bool {
        self.pick(index).needs_visibility(index, to_viewer, light)
    }
}

/// Per pixel and channel, the sRGB value of `image` (clamped to [0, 1]).
fn srgb(image: &Image) -> Vec<[f64; 3]> {
    image
        .pixels
        .iter()
        .map(|p| std::array::from_fn(|c| linear_to_srgb(p[c].clamp(0.0, 1.0)) as f64))
        .collect()
}

/// Sum of the squared errors of `values` against `reference`.
fn squared_error(values: &[[f64; 3]], reference: &Srgb8Image) -> f64 {
    let mut sum = 0.0;
    for (v, r) in values.iter().zip(&reference.pixels) {
        for c in 0..3 {
            sum += (v[c] - r[c] as f64 / 255.0).powi(2);
        }
    }
    sum
}

/// Measures the benefit of switching each sampled voxel of `candidates` (module docs) in the
/// frames of `cameras` under `light` on `background`, against `references` (one per camera,
/// the size of `options.render`), and ranks both predictors against it. Errors on bad frames,
/// a reference count or size that does not match, `samples = 0` or `from = to`.
pub fn measure(
    candidates: &Candidates,
    cameras: &[Camera],
    light: &Light,
    background: Vec3,
    references: &[Srgb8Image],
    options: &ContributionOptions,
) -> Result<ContributionCheck> {
    let bad = |name: &'static str, value: String, reason: &str| {
        Err(Error::InvalidParameter { name, value, reason: reason.into() })
    };
    if cameras.is_empty() || cameras.len() != references.len() {
        return bad(
            "references",
            format!("{} references for {} cameras", references.len(), cameras.len()),
            "one reference image per camera, at least one camera",
        );
    }
    let (w, h) = (options.render.width, options.render.height);
    if let Some(r) = references.iter().find(|r| (r.width, r.height) != (w, h)) {
        return bad("references", format!("{}×{}", r.width, r.height), "the frames' size");
    }
    if options.samples == 0 || options.from == options.to {
        return bad(
            "contribution options",
            format!("{} samples, {:?} → {:?}", options.samples, options.from, options.to),
            "at least one sample and two different kinds",
        );
    }
    let n = candidates.len();
    let base = candidates.select_kinds(&vec![options.from; n])?;
    let alt = candidates.select_kinds(&vec![options.to; n])?;
    let render = |app: &dyn Appearance| -> Result<Vec<Vec<[f64; 3]>>> {
        let mut cache = FrameCache::new(app)?;
        cameras
            .iter()
            .map(|camera| {
                let image =
                    filtered::render(&mut cache, camera, light, background, &options.render)?;
                Ok(srgb(&image))
            })
            .collect()
    };
    let base_images = render(&base)?;
    let base_error: f64 =
        base_images.iter().zip(references).map(|(b, r)| squared_error(b, r)).sum();
    let samples = options.samples.min(n);
    let picked: Vec<usize> = (0..samples).map(|s| s * n / samples).collect();
    let per_value = (w as f64) * (h as f64) * 3.0 * cameras.len() as f64;
    // Per voxel: the drop of the MSE, and whether some pixel moved by half an 8-bit step.
    let measured: Vec<(f64, bool)> = picked
        .par_iter()
        .map(|&v| {
            let images = render(&Switched { base: &base, alt: &alt, switched: v })?;
            let error: f64 = images.iter().zip(references).map(|(i, r)| squared_error(i, r)).sum();
            let moved = images.iter().zip(&base_images).any(|(i, b)| {
                i.iter().zip(b).any(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() >= 0.5 / 255.0))
            });
            Ok(((base_error - error) / per_value, moved))
        })
        .collect::<Result<_>>()?;
    let (from, to) = (kind_slot(options.from), kind_slot(options.to));
    let heldout: Vec<[f32; 3]> = candidates.errors().collect();
    let image: Vec<[f32; 3]> = candidates.image_errors().collect();
    let voxels: Vec<VoxelContribution> = picked
        .iter()
        .zip(&measured)
        .map(|(&v, &(m, moved))| VoxelContribution {
            voxel: v,
            measured: m,
            changed: moved,
            heldout: (heldout[v][from] - heldout[v][to]) as f64,
            image: (image[v][from] as f64).powi(2) - (image[v][to] as f64).powi(2),
        })
        .collect();
    let column = |f: fn(&VoxelContribution) -> f64, only_changed: bool| -> Vec<f64> {
        voxels.iter().filter(|c| !only_changed || c.changed).map(f).collect()
    };
    let rank = |f: fn(&VoxelContribution) -> f64, only_changed: bool| {
        spearman(&column(f, only_changed), &column(|c| c.measured, only_changed))
    };
    Ok(ContributionCheck {
        changed: voxels.iter().filter(|c| c.changed).count(),
        heldout_spearman: rank(|c| c.heldout, false)?,
        image_spearman: rank(|c| c.image, false)?,
        heldout_spearman_changed: rank(|c| c.heldout, true)?,
        image_spearman_changed: rank(|c| c.image, true)?,
        voxels,
    })
}

/// Position of `kind` in the candidates' error triples.
fn kind_slot(kind: Kind) -> usize {
    match kind {
        Kind::Average => 0,
        Kind::Sggx => 1,
        Kind::VirtualMesh => 2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spearman_matches_hand_computed_cases() {
        let a = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert!((spearman(&a, &[10.0, 20.0, 30.0, 40.0, 50.0]).unwrap() - 1.0).abs() < 1e-12);
        assert!((spearman(&a, &[5.0, 4.0, 3.0, 2.0, 1.0]).unwrap() + 1.0).abs() < 1e-12);
        // Monotone transforms do not change it.
        let cubes: Vec<f64> = a.iter().map(|x| x * x * x).collect();
        assert!((spearman(&a, &cubes).unwrap() - 1.0).abs() < 1e-12);
        // d = (0, 0, 1, −1, 0): ρ = 1 − 6·2 / (5·24) = 0.9 (no ties).
        let r = spearman(&a, &[1.0, 2.0, 4.0, 3.0, 5.0]).unwrap();
        assert!((r - 0.9).abs() < 1e-12, "{r}");
        // Ties share the average rank: ranks of (1, 1, 2) are (1.5, 1.5, 3).
        assert_eq!(ranks(&[1.0, 1.0, 2.0]), vec![1.5, 1.5, 3.0]);
        assert!(spearman(&a, &[1.0; 5]).unwrap().is_nan());
        assert!(spearman(&a, &[1.0; 4]).is_err());
    }
}
