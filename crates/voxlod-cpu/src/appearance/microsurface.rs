//! Heitz and Neyret (2012) leaf records ([`MicrosurfaceRecord`], pre-filtered up the octree as
//! voxlod-octree's `MicrosurfacePayload`) fitted to a voxel's ray samples ([`fit`]).
//!
//! # Why the ray samples, not an exact integral over the clipped triangles
//! The records are fitted, like every other representation here, to the same
//! [`VoxelSamples`]: the closest front-facing hits of isotropic random lines through the voxel.
//! Their density on a surface is proportional to its area (Cauchy–Crofton), so equal weights
//! give area-weighted statistics, and they see what a viewer can see (the visible side of a
//! sheet, not faces hidden inside the voxel); comparisons with Averages then measure the
//! representation, not the sampling. An exact computation would clip every triangle to the
//! voxel and integrate positions, normals and second moments in closed form, but the
//! texture-mapped albedo and its height profile `s(h) = erf(h/(√2σh))` are not polynomial and
//! would still need sampling. The price of sampling is noise: with `k` hits a centroid is
//! uncertain by about `σ/√k` (a few hundredths of a voxel for the paper's 150 lines).
//!
//! # Rules (each tested below)
//! - Every case-(a) hit counts once ([`VoxelSamples::surfaces`]); none: no record.
//! - **Plane**: through the hits' centroid, normal the mean of their unit normals; where the
//!   normals cancel (`|mean| < `[`CANCELLING_NORMALS`], a two-sided sheet seen from both sides)
//!   the principal eigenvector of `Σ n nᵀ` with its canonical sign, as Averages does.
//! - **Heights** `h = n̂·(p − centroid)`, `σh²` their mean square; **normal moments** `E[n nᵀ]`.
//! - **Colour**: `ā` the mean albedo, `aₛ = Σ s(h)(a − ā) / Σ s(h)²` with `s(h) =
//!   erf(h/(√2·σh))` (the paper's projection, §5.2); 0 without height spread.
//! - **Material**: the mean specular level, and the mean of `1/(e + 2)` over the hits'
//!   Blinn-Phong exponents `e` (the Beckmann slope variance per axis of the lobe).

use glam::{DVec3, Vec3};
use voxlod_format::records::MicrosurfaceRecord;
use voxlod_octree::microsurface::special::erf_f64;

use super::eigen::symmetric_eigen;
use super::voxel_samples::VoxelSamples;

/// Below this mean-normal length a voxel's normals are taken as cancelling (module docs).
pub const CANCELLING_NORMALS: f64 = 0.25;

/// The record of a voxel's samples (module docs), or `None` without a case-(a) hit.
pub fn fit(samples: &VoxelSamples) -> Option<MicrosurfaceRecord> {
    let hits: Vec<_> = samples.surfaces().collect();
    if hits.is_empty() {
        return None;
    }
    let n = hits.len() as f64;
    let (mut centroid, mut mean_n, mut albedo) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    let mut m = [[0.0f64; 3]; 3];
    let (mut specular, mut roughness) = (0.0, 0.0);
    for s in &hits {
        let nd = s.normal.as_dvec3();
        centroid += s.point.as_dvec3();
        mean_n += nd;
        for (i, row) in m.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x += nd[i] * nd[j];
            }
        }
        albedo += s.albedo.as_dvec3();
        specular += s.specular as f64;
        roughness += 1.0 / (s.shininess.max(0.0) as f64 + 2.0);
    }
    centroid /= n;
    mean_n /= n;
    albedo /= n;
    for row in &mut m {
        for x in row {
            *x /= n;
        }
    }
    let plane =
        if mean_n.length() >= CANCELLING_NORMALS { mean_n } else { symmetric_eigen(m).1[0] };
    let unit = plane.normalize_or_zero();
    let heights: Vec<f64> = hits.iter().map(|s| unit.dot(s.point.as_dvec3() - centroid)).collect();
    let var = heights.iter().map(|h| h * h).sum::<f64>() / n;
    let mut slope = DVec3::ZERO;
    if var > 0.0 {
        let scale = 1.0 / (2.0 * var).sqrt();
        let (mut num, mut den) = (DVec3::ZERO, 0.0);
        for (s, &h) in hits.iter().zip(&heights) {
            let prof = erf_f64(h * scale);
            num += (s.albedo.as_dvec3() - albedo) * prof;
            den += prof * prof;
        }
        if den > 1e-12 {
            slope = num / den;
        }
    }
    let moments = [m[0][0], m[1][1], m[2][2], m[0][1], m[0][2], m[1][2]];
    Some(MicrosurfaceRecord {
        centroid: centroid.as_vec3().to_array(),
        plane_normal: plane.as_vec3().to_array(),
        normal_moments: moments.map(|x| x as f32),
        height_variance: var as f32,
        albedo: albedo.as_vec3().to_array(),
        albedo_slope: slope.as_vec3().to_array(),
        specular: (specular / n) as f32,
        roughness: (roughness / n) as f32,
    })
}

/// The unit plane normal of a record (zero if it has none).
pub fn plane_normal(r: &MicrosurfaceRecord) -> Vec3 {
    Vec3::from(r.plane_normal).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::appearance::voxel_samples::{RaySample, SurfaceSample};

    fn hit(point: Vec3, normal: Vec3, albedo: Vec3) -> RaySample {
        RaySample {
            dir: -normal,
            entry: point + normal * 0.5,
            chord: 1.0,
            occluded: true,
            surface: Some(SurfaceSample { point, normal, albedo, specular: 0.25, shininess: 62.0 }),
        }
    }

    #[test]
    fn a_flat_surface_gives_its_plane_and_no_spread() {
        let rays: Vec<_> = (0..50)
            .map(|i| {
                let p = Vec3::new((i % 7) as f32 / 7.0, (i % 5) as f32 / 5.0, 0.3);
                hit(p, Vec3::Z, Vec3::splat(0.4))
            })
            .collect();
        let r = fit(&VoxelSamples { rays }).unwrap();
        assert!((r.centroid[2] - 0.3).abs() < 1e-6);
        assert_eq!(plane_normal(&r), Vec3::Z);
        assert_eq!(r.height_variance, 0.0);
        assert_eq!(r.albedo_slope, [0.0; 3]);
        assert_eq!(r.normal_moments, [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
        assert!((r.specular - 0.25).abs() < 1e-7 && (r.roughness - 1.0 / 64.0).abs() < 1e-7);
    }

    /// Two terraces at z = 0.4 (red) and 0.6 (green): σh² = 0.01, and ā ± aₛ·s(±0.1) are the
    /// two colours exactly.
    #[test]
    fn height_correlated_colour_is_projected_on_the_profile() {
        let (red, green) = (Vec3::new(0.8, 0.1, 0.1), Vec3::new(0.1, 0.8, 0.1));
        let rays: Vec<_> = (0..40)
            .map(|i| {
                let up = i % 2 == 0;
                let p = Vec3::new((i % 9) as f32 / 9.0, 0.5, if up { 0.6 } else { 0.4 });
                hit(p, Vec3::Z, if up { green } else { red })
            })
            .collect();
        let r = fit(&VoxelSamples { rays }).unwrap();
        assert!((r.height_variance - 0.01).abs() < 1e-6);
        let (a, s) = (Vec3::from(r.albedo), Vec3::from(r.albedo_slope));
        let prof = erf_f64(1.0 / 2f64.sqrt()) as f32;
        assert!((a + s * prof - green).length() < 1e-5 && (a - s * prof - red).length() < 1e-5);
    }

    #[test]
    fn a_single_sample_and_cancelling_normals_stay_defined() {
        let one = fit(&VoxelSamples { rays: vec![hit(Vec3::splat(0.5), Vec3::Y, Vec3::ONE)] });
        let one = one.unwrap();
        assert_eq!((one.height_variance, one.albedo_slope), (0.0, [0.0; 3]));
        assert_eq!(plane_normal(&one), Vec3::Y);
        // A two-sided sheet seen from both sides: the normals cancel, the plane is the axis.
        let n = Vec3::new(0.0, 0.6, 0.8);
        let rays = vec![hit(Vec3::splat(0.5), n, Vec3::ONE), hit(Vec3::splat(0.5), -n, Vec3::ONE)];
        let r = fit(&VoxelSamples { rays }).unwrap();
        let p = Vec3::from(r.plane_normal);
        assert!((p.length() - 1.0).abs() < 1e-5 && p.dot(n).abs() > 0.9999 && p.z > 0.0, "{p}");
        assert_eq!(fit(&VoxelSamples::default()), None);
    }
}
