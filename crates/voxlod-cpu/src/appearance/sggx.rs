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
mod tests {
    use glam::UVec3;
    use voxlod_format::GridSpec;

    use super::*;
    use crate::appearance::nonexp::test_lines::plane;
    use crate::appearance::{Appearance, AppearanceGrid};
    use crate::random::rand_f32;
    use proptest::prelude::*;

    /// A rotated anisotropic test matrix with projected areas (1, 0.5, 0.3).
    fn test_matrix() -> Mat3 {
        let r = Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
        r * Mat3::from_diagonal(Vec3::new(1.0, 0.25, 0.09)) * r.transpose()
    }

    /// Surface-like: normal `n`, roughness 0.1.
    fn surface_matrix(n: Vec3) -> Mat3 {
        let nn = Mat3::from_cols(n * n.x, n * n.y, n * n.z);
        nn * 0.99 + Mat3::from_diagonal(Vec3::splat(0.01))
    }

    /// `∫ g(ω) dω` over the sphere by the midpoint rule in (θ, φ).
    fn integrate(nt: usize, np: usize, g: impl Fn(Vec3) -> f64) -> f64 {
        let (dt, dp) = (std::f64::consts::PI / nt as f64, std::f64::consts::TAU / np as f64);
        let mut sum = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            let (st, ct) = t.sin_cos();
            for j in 0..np {
                let (sp, cp) = ((j as f64 + 0.5) * dp).sin_cos();
                let w = Vec3::new((st * cp) as f32, (st * sp) as f32, ct as f32);
                sum += g(w) * st * dt * dp;
            }
        }
        sum
    }

    #[test]
    fn projected_area_integral_of_d_matches_sigma() {
        for (s, nt, np) in
            [(test_matrix(), 300, 600), (surface_matrix(Vec3::new(0.0, 0.6, 0.8)), 1000, 1000)]
        {
            for wi in [Vec3::Z, Vec3::X, Vec3::new(1.0, -1.0, 1.0).normalize()] {
                let integral = integrate(nt, np, |w| ndf(s, w) as f64 * w.dot(wi).max(0.0) as f64);
                let sigma = projected_area(s, wi) as f64;
                assert!(
                    (integral / sigma - 1.0).abs() < 0.01,
                    "S {s}, ωi {wi}: ∫D⟨ω,ωi⟩ = {integral}, σ = {sigma}"
                );
            }
        }
    }

    #[test]
    fn vndf_samples_are_visible_and_follow_the_vndf() {
        let s = test_matrix();
        let wi = Vec3::new(0.3, -0.5, 0.8).normalize();
        let vndf = Vndf::new(s, wi);
        // 6 bins in z × 8 in φ over the sphere (world frame).
        let bin = |w: Vec3| {
            let a = (((w.z + 1.0) * 3.0) as usize).min(5);
            let p = ((w.y.atan2(w.x) + PI) / TAU * 8.0) as usize;
            a * 8 + p.min(7)
        };
        let n = 100_000u32;
        let mut hist = [0f64; 48];
        for i in 0..n {
            let u = Vec2::new(rand_f32(5, i, 0), rand_f32(5, i, 1));
            let wm = vndf.sample(u);
            assert!(wm.dot(wi) > 0.0, "sample {wm} not visible from {wi}");
            assert!((wm.length() - 1.0).abs() < 1e-5);
            hist[bin(wm)] += 1.0 / n as f64;
        }
        let sigma = projected_area(s, wi) as f64;
        let mut expected = [0f64; 48];
        let (nt, np) = (600usize, 1200usize);
        let (dt, dp) = (std::f64::consts::PI / nt as f64, std::f64::consts::TAU / np as f64);
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            for j in 0..np {
                let p = (j as f64 + 0.5) * dp;
                let w = Vec3::new(
                    (t.sin() * p.cos()) as f32,
                    (t.sin() * p.sin()) as f32,
                    t.cos() as f32,
                );
                let d = ndf(s, w) as f64 * w.dot(wi).max(0.0) as f64 / sigma;
                expected[bin(w)] += d * t.sin() * dt * dp;
            }
        }
        for k in 0..48 {
            assert!(
                (hist[k] - expected[k]).abs() < 0.004,
                "bin {k}: sampled {} vs D_ωi {}",
                hist[k],
                expected[k]
            );
        }
    }

    #[test]
    fn shading_pattern_is_fixed_and_strictly_visible() {
        let pts: Vec<Vec2> = (0..16).map(|i| shading_point(i, 16)).collect();
        assert_eq!(pts[0], Vec2::new(1.0 / 32.0, 0.0));
        assert_eq!(pts[1], Vec2::new(3.0 / 32.0, 0.5));
        assert_eq!(pts[3], Vec2::new(7.0 / 32.0, 0.75));
        // Stratified in both coordinates: each 1/16 strip of either axis holds one point.
        let mut ys: Vec<u32> = pts.iter().map(|p| (p.y * 16.0) as u32).collect();
        ys.sort();
        assert_eq!(ys, (0..16).collect::<Vec<_>>());
        let s = surface_matrix(Vec3::Z);
        for wi in [Vec3::Z, Vec3::X, Vec3::NEG_Z, Vec3::new(1.0, 0.0, 1e-6).normalize()] {
            let vndf = Vndf::new(s, wi);
            for p in &pts {
                let wm = vndf.sample(*p);
                assert!(wm.is_finite() && wm.dot(wi) > 0.0, "{wi}: {wm}");
            }
        }
    }

    #[test]
    fn all_equal_normals_give_a_finite_positive_definite_fit() {
        let n = Vec3::new(0.0, 0.6, 0.8);
        let fit = estimate(&[n; 20]).unwrap();
        assert_eq!(fit.sigma[0], 1.0);
        assert!((fit.sigma[1] - 0.1).abs() < 1e-12 && (fit.sigma[2] - 0.1).abs() < 1e-12);
        let s = fit.matrix();
        assert!(s.is_finite() && s.determinant() > 0.0, "{s}");
        // Heitz's surface-like matrix n nᵀ + 0.01 (I − n nᵀ).
        let heitz = Mat3::from_cols(n * n.x, n * n.y, n * n.z) * 0.99
            + Mat3::from_diagonal(Vec3::splat(0.01));
        assert!((s - heitz).abs().to_cols_array().iter().all(|d| *d < 1e-6), "{s} vs {heitz}");
        let t = fit.semi_axes();
        let pi = std::f64::consts::PI;
        assert!((t[0] - 0.1 / pi.sqrt()).abs() < 1e-12 && (t[1] - 1.0 / pi.sqrt()).abs() < 1e-12);
        assert!(estimate(&[]).is_none());
        assert!(estimate(&[Vec3::ZERO, Vec3::NAN]).is_none());
    }

    #[test]
    fn projected_area_along_each_axis_is_its_sigma_and_semi_axes_agree() {
        let normals: Vec<Vec3> = (0..50)
            .map(|i| {
                let t = i as f32 * 0.3;
                Vec3::new(t.cos() * 0.4, t.sin() * 0.2, 1.0).normalize()
            })
            .collect();
        let fit = estimate(&normals).unwrap();
        let s = fit.matrix();
        let t = fit.semi_axes();
        for k in 0..3 {
            let pa = projected_area(s, fit.frame[k].as_vec3()) as f64;
            assert!((pa - fit.sigma[k]).abs() < 1e-6, "axis {k}: {pa} vs {}", fit.sigma[k]);
            let (j, l) = ((k + 1) % 3, (k + 2) % 3);
            assert!((std::f64::consts::PI * t[j] * t[l] - fit.sigma[k]).abs() < 1e-12);
        }
        assert_eq!(fit.sigma.iter().copied().fold(0.0, f64::max), 1.0);
        // The principal axis of a bundle of normals around z is z.
        assert!(fit.frame[0].z > 0.99, "{:?}", fit.frame[0]);
    }

    #[test]
    fn record_round_trip_stays_positive_definite_and_shades_boundedly() {
        let samples =
            plane(4, 150, Vec3::new(0.2, 0.3, 1.0), Vec3::splat(0.5), Vec3::splat(0.6), false);
        let rec = fit(&samples).unwrap();
        let shared = estimate_samples(&samples).unwrap();
        assert_eq!(record(&samples, &shared, nonexp::fit(&samples.rays)), rec);
        let s = rec.matrix();
        assert!(s.is_finite() && s.determinant() > 0.0, "{s}");
        assert_eq!((rec.density, rec.gamma), (255, 0), "a plane is an opaque surface");
        assert!((rec.color() - Vec3::splat(0.6)).abs().max_element() < 0.01);
        // All-equal normals survive quantization as PD.
        let flat = estimate(&[Vec3::X; 3]).unwrap().matrix();
        let d = SggxRecord::new(flat, Vec3::ONE, 1.0, 1.0).matrix();
        assert!(d.is_finite() && d.determinant() > 0.0, "{d}");
        // No front hit: no record.
        let back = plane(4, 150, Vec3::Z, Vec3::splat(0.5), Vec3::ONE, false);
        let none = VoxelSamples {
            rays: back
                .rays
                .iter()
                .map(|r| super::super::voxel_samples::RaySample { surface: None, ..*r })
                .collect(),
        };
        assert!(fit(&none).is_none());
    }

    #[test]
    fn flat_surface_shading_matches_lambert() {
        // A nearly flat surface facing the light and the viewer shades close to the Lambert
        // value of its normal.
        let n = Vec3::Z;
        let s = estimate(&[n; 8]).unwrap().matrix();
        let m =
            MaterialSample { albedo: Vec3::ONE, alpha: 1.0, specular: Vec3::ZERO, shininess: 1.0 };
        let light =
            LightSample { to_light: Vec3::Z, distance: f32::INFINITY, irradiance: Vec3::splat(PI) };
        let r = shade_record(s, &m, Vec3::Z, &light, 1.0, Vec3::ZERO);
        assert!((r.x - 1.0).abs() < 0.02 && r.x <= 1.0, "{r}");
        // Seen from below the surface, the symmetric SGGX shows the −n side: unlit.
        let r = shade_record(s, &m, Vec3::NEG_Z, &light, 1.0, Vec3::ZERO);
        assert!(r.x < 0.02, "{r}");
    }

    #[test]
    fn grid_answers_with_the_record() {
        use voxlod_format::BrickMap;
        use voxlod_format::records::SpecularRecord;
        let samples = plane(6, 150, Vec3::Y, Vec3::splat(0.5), Vec3::splat(0.5), false);
        let rec = fit(&samples).unwrap();
        let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(2)).unwrap();
        let records = BrickMap::from_voxels(grid.dims, [(UVec3::new(1, 0, 1), rec)]).unwrap();
        let mut g = AppearanceGrid { grid, records, specular: None };
        assert_eq!(
            (g.len(), g.index_of(UVec3::new(1, 0, 1)), g.index_of(UVec3::ZERO)),
            (1, Some(0), None)
        );
        assert_eq!(
            g.opacity(0, Vec3::X),
            Opacity::NonExponential { sigma: rec.sigma_t(), gamma: rec.gamma() }
        );
        let light = LightSample { to_light: Vec3::Y, distance: 1.0, irradiance: Vec3::splat(PI) };
        let diffuse = g.radiance(0, Vec3::Y, &light, 1.0, Vec3::ZERO);
        assert!((diffuse.x - rec.color().x).abs() < 0.02 * rec.color().x, "{diffuse}");
        for v in [Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z, Vec3::NEG_Y] {
            assert!(g.radiance(0, v, &light, 1.0, Vec3::splat(0.1)).is_finite());
        }
        g.specular = Some(vec![SpecularRecord::new(1.0, 64.0)]);
        let shiny = g.radiance(0, Vec3::Y, &light, 1.0, Vec3::ZERO);
        assert!(shiny.x > diffuse.x, "{shiny} vs {diffuse}");
    }

    proptest! {
        #[test]
        fn projected_area_is_positive_and_even(
            x in -1f32..1.0, y in -1f32..1.0, z in -1f32..1.0,
            a in 0.1f32..1.0, b in 0.1f32..1.0, c in 0.1f32..1.0, angle in 0f32..6.3,
        ) {
            let w = Vec3::new(x, y, z);
            prop_assume!(w.length() > 1e-3);
            let w = w.normalize();
            let r = Mat3::from_axis_angle(Vec3::new(c, a, b).normalize(), angle);
            let s = r * Mat3::from_diagonal(Vec3::new(a * a, b * b, c * c)) * r.transpose();
            let (p, q) = (projected_area(s, w), projected_area(s, -w));
            prop_assert!(p > 0.0);
            prop_assert_eq!(p, q);
            prop_assert!(ndf(s, w) > 0.0 && ndf(s, w) == ndf(s, -w));
        }

        #[test]
        fn shading_is_bounded(
            x in -1f32..1.0, y in -1f32..1.0, z in -1f32..1.0, lx in -1f32..1.0, albedo in 0f32..1.0,
        ) {
            let v = Vec3::new(x, y, z);
            prop_assume!(v.length() > 1e-3);
            let m = MaterialSample { albedo: Vec3::splat(albedo), alpha: 1.0, specular: Vec3::ZERO, shininess: 1.0 };
            let light = LightSample { to_light: Vec3::new(lx, 1.0, 0.2).normalize(), distance: 1.0, irradiance: Vec3::splat(2.0) };
            let r = shade_record(test_matrix(), &m, v, &light, 1.0, Vec3::splat(0.1));
            prop_assert!(r.is_finite() && r.min_element() >= 0.0);
            prop_assert!(r.max_element() <= albedo * (2.0 / PI + 0.1) + 1e-5, "{}", r);
        }
    }
}
