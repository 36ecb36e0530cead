//! Tests of the `sggx` module.

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
            let w =
                Vec3::new((t.sin() * p.cos()) as f32, (t.sin() * p.sin()) as f32, t.cos() as f32);
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
    let heitz =
        Mat3::from_cols(n * n.x, n * n.y, n * n.z) * 0.99 + Mat3::from_diagonal(Vec3::splat(0.01));
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
    let m = MaterialSample { albedo: Vec3::ONE, alpha: 1.0, specular: Vec3::ZERO, shininess: 1.0 };
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
