//! The \[VJK21\] baseline's appearance: an SGGX distribution of normals (Heitz et al. 2015)
//! fitted to a voxel's sampled normals, its operators (projected area, D, VNDF sampling), its
//! record ([`SggxRecord`]: SGGX matrix, mean colour, \[VJK21\] σ and γ) and how it is shaded
//! (design note §3).
//!
//! Rules (each tested below):
//! - **Estimator** (the authors' `SGGX::estimate`): `E = (1/N)Σ nnᵀ` over the case-(a) normals,
//!   unweighted (isotropic lines already sample surfaces by area); its eigenframe from
//!   [`symmetric_eigen`] (descending eigenvalues, canonical signs, right-handed); projected
//!   areas `σ_k = (1/N)Σ|e_k·n|` floored at [`SIGMA_FLOOR`]; `S = R diag(σ²) Rᵀ`, scaled so that
//!   `max σ_k = 1` (the bytes use their full range; the VNDF is scale-invariant).
//! - **Decode**: [`SggxRecord::matrix`] repairs positive definiteness (adds `10⁻³·tr S·I` when
//!   `det S ≤ 10⁻⁶(tr S/3)³`).
//! - **Shading**: the radiance toward `v` is the mean of [`shade`] over [`SHADING_SAMPLES`]
//!   visible normals drawn by VNDF sampling for `ωi = v` at the fixed Hammersley points of
//!   [`shading_point`] (the diffuse-microflake estimator with `shade()` as the per-flake
//!   response; specular materials feed the same normals to its Blinn–Phong).
//! - **Opacity**: [`Opacity::NonExponential`] with the record's σ and γ (fitted by
//!   [`super::nonexp::fit`]).

use std::f32::consts::{PI, TAU};

use glam::{DVec3, Mat3, Vec2, Vec3};
use voxlod_format::records::SggxRecord;
use voxlod_scene::{LightSample, MaterialSample};

use super::eigen::symmetric_eigen;
use super::voxel_samples::VoxelSamples;
use super::{Opacity, nonexp};
use super::{RecordAppearance, record_material};
use crate::shading::shade;
use voxlod_format::records::SpecularRecord;

/// Floor of the projected areas `σ_k` before normalization: Heitz's roughness 0.1 for a flat
/// surface, and what keeps a rank-deficient fit (all normals equal) positive definite.
pub const SIGMA_FLOOR: f64 = 0.1;

/// Visible normals averaged per shading evaluation.
pub const SHADING_SAMPLES: u32 = 16;

/// An SGGX fit: the eigenframe of `E[nnᵀ]` and the projected areas along it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SggxFit {
    /// Unit eigenvectors of `E[nnᵀ]`, descending eigenvalue, canonical signs, right-handed.
    pub frame: [DVec3; 3],
    /// Eigenvalues of `E[nnᵀ]`, descending.
    pub eigenvalues: [f64; 3],
    /// Projected areas `σ_k` along `frame[k]`, floored at [`SIGMA_FLOOR`] and then scaled so
    /// the largest is 1.
    pub sigma: [f64; 3],
}

impl SggxFit {
    /// `S = Σ_k σ_k² e_k e_kᵀ`.
    pub fn matrix(&self) -> Mat3 {
        let mut m = [[0.0f64; 3]; 3];
        for k in 0..3 {
            let (e, s2) = (self.frame[k], self.sigma[k] * self.sigma[k]);
            for (i, row) in m.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    *x += s2 * e[i] * e[j];
                }
            }
        }
        Mat3::from_cols_array_2d(&m.map(|r| r.map(|x| x as f32)))
    }

    /// Semi-axes of the SGGX ellipsoid along the frame, `T_k = √(σ_j σ_l / σ_k) / √π`, so that
    /// its projected area along `e_k` is `π T_j T_l = σ_k` (the authors' `T_diag`).
    pub fn semi_axes(&self) -> [f64; 3] {
        let s = self.sigma;
        std::array::from_fn(|k| {
            let (j, l) = ((k + 1) % 3, (k + 2) % 3);
            (s[j] * s[l] / s[k]).sqrt() / std::f64::consts::PI.sqrt()
        })
    }
}

/// Fits an SGGX distribution to unit normals (module docs). Non-finite or zero normals are
/// skipped (and the rest renormalized); `None` when none remains.
pub fn estimate(normals: &[Vec3]) -> Option<SggxFit> {
    let ns: Vec<DVec3> = normals
        .iter()
        .map(|n| n.as_dvec3())
        .filter(|n| n.is_finite() && n.length_squared() > 0.0)
        .map(|n| n.normalize())
        .collect();
    if ns.is_empty() {
        return None;
    }
    let inv = 1.0 / ns.len() as f64;
    let mut e = [[0.0f64; 3]; 3];
    for n in &ns {
        for (i, row) in e.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x += n[i] * n[j] * inv;
            }
        }
    }
    let (eigenvalues, frame) = symmetric_eigen(e);
    let mut sigma = frame.map(|a| ns.iter().map(|n| a.dot(*n).abs()).sum::<f64>() * inv);
    sigma = sigma.map(|s| s.max(SIGMA_FLOOR));
    let top = sigma.iter().copied().fold(0.0, f64::max);
    sigma = sigma.map(|s| s / top);
    Some(SggxFit { frame, eigenvalues, sigma })
}

/// Fits a voxel's [`SggxRecord`]: the SGGX of its case-(a) normals, the mean case-(a) albedo
/// and the \[VJK21\] σ, γ of [`nonexp::fit`] over all its lines. `None` when no line hit a front
/// face inside the voxel (such a voxel has no appearance record, note §2).
pub fn fit(samples: &VoxelSamples) -> Option<SggxRecord> {
    let sggx = estimate_samples(samples)?;
    Some(record(samples, &sggx, nonexp::fit(&samples.rays)))
}

/// The SGGX fit of a voxel's case-(a) normals ([`estimate`]); `None` without one.
pub fn estimate_samples(samples: &VoxelSamples) -> Option<SggxFit> {
    estimate(&samples.surfaces().map(|s| s.normal).collect::<Vec<_>>())
}

/// The record of a voxel from an SGGX fit and a \[VJK21\] fit already made (so a precompute
/// that also builds the virtual mesh shares them): the matrix, the mean case-(a) albedo (0
/// without case-(a) hits), σ and γ.
pub fn record(samples: &VoxelSamples, sggx: &SggxFit, transmittance: nonexp::VjkFit) -> SggxRecord {
    let (sum, n) = samples.surfaces().fold((Vec3::ZERO, 0u32), |(a, n), s| (a + s.albedo, n + 1));
    let color = if n > 0 { sum / n as f32 } else { Vec3::ZERO };
    SggxRecord::new(sggx.matrix(), color, transmittance.sigma(), transmittance.gamma())
}

/// Projected area `σ(ω) = √(ωᵀSω)` of the distribution along unit `w`.
#[inline]
pub fn projected_area(s: Mat3, w: Vec3) -> f32 {
    w.dot(s * w).max(0.0).sqrt()
}

/// The normal distribution `D(ω) = 1 / (π √det S (ωᵀS⁻¹ω)²)`, written with the adjugate as
/// `det(S)^{3/2} / (π (ωᵀ adj(S) ω)²)` (Mitsuba 3 `sggx_ndf_pdf`). 0 for a singular `S`.
#[inline]
pub fn ndf(s: Mat3, w: Vec3) -> f32 {
    let det = s.determinant();
    if det <= 0.0 {
        return 0.0;
    }
    // adj(S) = det·S⁻¹; S symmetric.
    let q = w.dot((s.inverse() * det) * w);
    if q <= 0.0 {
        return 0.0;
    }
    det * det.sqrt() / (PI * q * q)
}

/// A right-handed orthonormal basis `(s, t)` completing unit `n` (Duff et al. 2017).
#[inline]
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// VNDF sampling of an SGGX distribution for one incident direction (Heitz et al. 2015,
/// supplemental; Mitsuba 3 `sggx_sample_vndf`): the set-up is done once per direction, then
/// every [`Vndf::sample`] is a cosine-hemisphere draw mapped through it.
#[derive(Clone, Copy, Debug)]
pub struct Vndf {
    /// World axes of the sampling frame `(ω_k, ω_j, ω_i)`.
    frame: Mat3,
    /// Columns `m_k, m_j, m_i` in that frame.
    m: Mat3,
}

impl Vndf {
    /// The sampler for distribution `s` (positive definite) and unit incident direction `wi`.
    pub fn new(s: Mat3, wi: Vec3) -> Self {
        let (wk, wj) = basis(wi);
        let q = |a: Vec3, b: Vec3| a.dot(s * b);
        let (skk, sjj, sii) = (q(wk, wk), q(wj, wj), q(wi, wi));
        let (skj, ski, sji) = (q(wk, wj), q(wk, wi), q(wj, wi));
        let det = skk * sjj * sii - skj * skj * sii - ski * ski * sjj - sji * sji * skk
            + 2.0 * skj * ski * sji;
        let inv_sqrt_sii = 1.0 / sii.max(f32::MIN_POSITIVE).sqrt();
        let tmp = (sjj * sii - sji * sji).max(f32::MIN_POSITIVE).sqrt();
        let mk = Vec3::new(det.abs().sqrt() / tmp, 0.0, 0.0);
        let mj = Vec3::new(-inv_sqrt_sii * (ski * sji - skj * sii) / tmp, inv_sqrt_sii * tmp, 0.0);
        let mi = Vec3::new(ski, sji, sii) * inv_sqrt_sii;
        Self { frame: Mat3::from_cols(wk, wj, wi), m: Mat3::from_cols(mk, mj, mi) }
    }

    /// The visible normal for `u ∈ [0, 1)²`: a cosine-weighted hemisphere point
    /// (`r = √u.x`, `φ = 2π u.y`) mapped through the distribution. Its dot product with `wi` is
    /// positive whenever `u.x < 1`.
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let r = u.x.max(0.0).sqrt();
        let (sin, cos) = (TAU * u.y).sin_cos();
        let h = Vec3::new(r * cos, r * sin, (1.0 - u.x).max(0.0).sqrt());
        let wm = (self.m * h).normalize_or(Vec3::Z);
        (self.frame * wm).normalize_or(self.frame.z_axis)
    }
}

/// Point `i` of the fixed 16-point (generally `count`-point, `count ≥ 1`) Hammersley pattern
/// used for shading: `((i + ½)/count, radical-inverse₂(i))`. The first coordinate stays below 1, so every
/// VNDF sample is strictly visible.
#[inline]
pub fn shading_point(i: u32, count: u32) -> Vec2 {
    Vec2::new((i as f32 + 0.5) / count as f32, radical_inverse2(i))
}

/// Base-2 radical inverse (van der Corput) of `i`, exact in f32 for `i < 2²⁴`.
#[inline]
pub fn radical_inverse2(i: u32) -> f32 {
    (i.reverse_bits() >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Radiance of one SGGX voxel toward `to_viewer`: the mean of [`shade`] over the
/// [`SHADING_SAMPLES`] VNDF-sampled visible normals (module docs).
pub fn shade_record(
    s: Mat3,
    material: &MaterialSample,
    to_viewer: Vec3,
    light: &LightSample,
    visibility: f32,
    ambient: Vec3,
) -> Vec3 {
    let v = to_viewer.normalize_or(Vec3::Z);
    let vndf = Vndf::new(s, v);
    let mut sum = Vec3::ZERO;
    for i in 0..SHADING_SAMPLES {
        let wm = vndf.sample(shading_point(i, SHADING_SAMPLES));
        sum += shade(material, wm, v, light, visibility, ambient);
    }
    sum / SHADING_SAMPLES as f32
}

impl RecordAppearance for SggxRecord {
    type Params = ();

    fn opacity(&self, _: (), _dir: Vec3) -> Opacity {
        Opacity::NonExponential { sigma: self.sigma_t(), gamma: self.gamma() }
    }

    fn radiance(
        &self,
        _: (),
        specular: Option<&SpecularRecord>,
        to_viewer: Vec3,
        light: &LightSample,
        visibility: f32,
        ambient: Vec3,
    ) -> Vec3 {
        let m = record_material(self.color(), specular);
        shade_record(self.matrix(), &m, to_viewer, light, visibility, ambient)
    }
}

#[cfg(test)]
mod tests;
