//! Tests of the `virtual_mesh` module.

use std::f32::consts::PI;

use super::*;
use crate::appearance::nonexp::test_lines::plane;
use crate::appearance::voxel_samples::{RaySample, SurfaceSample};
use crate::random::rand_f32;
use proptest::prelude::*;
use voxlod_format::BrickMap;

/// Samples whose case-(a) hits have the given normals and albedos.
fn hits(normals: &[Vec3], albedo: impl Fn(usize) -> Vec3) -> VoxelSamples {
    let rays = normals
        .iter()
        .enumerate()
        .map(|(i, &n)| RaySample {
            dir: -n,
            entry: Vec3::splat(0.5) + n * 0.5,
            chord: 1.0,
            occluded: true,
            surface: Some(SurfaceSample {
                point: Vec3::splat(0.5),
                normal: n,
                albedo: albedo(i),
                specular: 0.0,
                shininess: 1.0,
            }),
        })
        .collect();
    VoxelSamples { rays }
}

/// Normals of a sphere cap of half-angle `theta` around `axis` (a curved surface).
fn cap(axis: Vec3, theta: f32, n: u32) -> Vec<Vec3> {
    let a = axis.normalize();
    let b = hughes_moeller(a.as_dvec3()).as_vec3();
    let c = b.cross(a);
    (0..n)
        .map(|i| {
            let t = theta * rand_f32(77, i, 0).sqrt();
            let p = std::f32::consts::TAU * rand_f32(77, i, 1);
            (a * t.cos() + (b * p.cos() + c * p.sin()) * t.sin()).normalize()
        })
        .collect()
}

fn light() -> LightSample {
    LightSample {
        to_light: Vec3::new(0.3, 0.5, 0.8).normalize(),
        distance: f32::INFINITY,
        irradiance: Vec3::splat(PI),
    }
}

fn present_faces(rec: &VirtualMeshRecord) -> Vec<usize> {
    (0..8).filter(|&f| rec.normals[f].iter().any(|n| *n != [0; 3])).collect()
}

#[test]
fn face_table_covers_the_octants_of_its_vertices() {
    let axes = [DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z];
    let mut seen = [false; 8];
    for (f, tri) in FACES.iter().enumerate() {
        let centroid: DVec3 = tri.iter().map(|&i| axes[i]).sum();
        assert_eq!(face_of(centroid), f, "face {f} {tri:?}");
        // One vertex per axis.
        let mut k: Vec<usize> = tri.iter().map(|i| i / 2).collect();
        k.sort();
        assert_eq!(k, [0, 1, 2]);
        seen[f] = true;
    }
    assert!(seen.iter().all(|s| *s));
    // Snapping: tiny negative coordinates count as +.
    assert_eq!(face_of(DVec3::new(1.0, -1e-9, -1e-7)), 0);
    assert_eq!(face_of(DVec3::new(1.0, -1e-5, 0.0)), 1);
}

#[test]
fn all_equal_normals_give_one_fixed_face_with_finite_vertices() {
    for n in [Vec3::Z, Vec3::new(0.0, 0.6, 0.8), Vec3::new(-1.0, 2.0, 0.5).normalize()] {
        let rec = fit(&hits(&[n; 30], |_| Vec3::splat(0.4))).unwrap();
        assert_eq!(present_faces(&rec), [0], "{n}");
        assert_eq!(rec.distribution, 0);
        assert!((rec.normal(0, 0) - n).length() < 0.01);
        assert_eq!((rec.normals[0][1], rec.normals[0][2]), ([0; 3], [0; 3]));
        for k in 0..3 {
            assert!(rec.axis(k).is_finite() && (rec.axis(k).length() - 1.0).abs() < 1e-5);
            assert!(rec.scale(k).is_finite() && rec.scale(k) > 0.0);
        }
        // The flat axis keeps its size: 0.1/√π = 0.0564 within a log step, not 0.039.
        assert!((rec.scale(0) / 0.0564 - 1.0).abs() < 0.02, "{}", rec.scale(0));
        assert!((rec.scale(1) / 0.5642 - 1.0).abs() < 0.02, "{}", rec.scale(1));
    }
}

#[test]
fn a_triangle_on_a_voxel_face_gives_a_finite_record() {
    let s = plane(3, 150, Vec3::Z, Vec3::new(0.3, 0.6, 0.0), Vec3::splat(0.7), false);
    assert!(s.surfaces().count() > 10);
    let rec = fit(&s).unwrap();
    assert_eq!(present_faces(&rec).len(), 1);
    for v in [Vec3::Z, Vec3::NEG_Z, Vec3::X, Vec3::new(1.0, 1.0, 0.0)] {
        let r = shade_record(&rec, None, v, &light(), 1.0, Vec3::splat(0.05), 16);
        assert!(r.is_finite() && r.min_element() >= 0.0, "{v}: {r}");
    }
}

#[test]
fn octant_assignment_is_stable_under_sign_flips() {
    let normals: Vec<DVec3> = (0..200)
        .map(|i| {
            let v = Vec3::new(
                rand_f32(1, i, 0) - 0.5,
                rand_f32(1, i, 1) - 0.5,
                rand_f32(1, i, 2) - 0.2,
            );
            v.normalize().as_dvec3()
        })
        .collect();
    let fit = sggx::estimate(&normals.iter().map(|n| n.as_vec3()).collect::<Vec<_>>());
    let frame = fit.unwrap().frame;
    let base: Vec<usize> = assign_faces(normals.iter().copied(), &frame).collect();
    // Flipping axis k relabels faces by flipping sign k of their octant.
    let sign = |f: usize| {
        let mut c = DVec3::ZERO;
        for i in FACES[f] {
            c[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
        }
        c
    };
    for k in 0..3 {
        let mut flipped = frame;
        flipped[k] = -flipped[k];
        let got: Vec<usize> = assign_faces(normals.iter().copied(), &flipped).collect();
        for (a, b) in base.iter().zip(&got) {
            let mut s = sign(*a);
            s[k] = -s[k];
            assert_eq!(face_of(s), *b, "axis {k}");
        }
    }
    // The canonical frame does not depend on the normals' own signs: E is even.
    let neg: Vec<Vec3> = normals.iter().map(|n| -n.as_vec3()).collect();
    assert_eq!(sggx::estimate(&neg).unwrap().frame, frame);
}

#[test]
fn extremal_normals_lie_on_the_cone_120_degrees_apart() {
    for (i, theta) in [0.1, 0.5, 1.2, 1.5].into_iter().enumerate() {
        let axis = Vec3::new(
            rand_f32(i as u32, 0, 0) - 0.5,
            rand_f32(i as u32, 0, 1) - 0.5,
            rand_f32(i as u32, 0, 2) - 0.5,
        )
        .as_dvec3()
        .normalize();
        let ns = extremal_normals(axis, theta);
        let proj: Vec<DVec3> = ns.iter().map(|n| (*n - axis * n.dot(axis)).normalize()).collect();
        for j in 0..3 {
            assert!((ns[j].length() - 1.0).abs() < 1e-12);
            assert!((ns[j].dot(axis).acos() - theta).abs() < 1e-9, "θ {theta}");
            let a = proj[j].dot(proj[(j + 1) % 3]).clamp(-1.0, 1.0).acos();
            assert!((a - std::f64::consts::TAU / 3.0).abs() < 1e-9, "{a}");
        }
        // Azimuth 0 is b1 = b2 × axis.
        let b1 = hughes_moeller(axis).cross(axis);
        assert!((proj[0] - b1).length() < 1e-9);
    }
    // Both Hughes–Möller branches give a unit perpendicular.
    for d in [DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(0.6, 0.0, -0.8)] {
        let p = hughes_moeller(d);
        assert!(p.dot(d).abs() < 1e-15 && (p.length() - 1.0).abs() < 1e-15);
    }
}

#[test]
fn distribution_rule_is_greedy_five_degrees_with_clamped_acos() {
    let rot = |deg: f64| DVec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
    // Three inputs, the second a duplicate of the first: two kept, not a distribution (the
    // reference code's dead branch would keep input 2 twice).
    let (kept, d) = distinct_normals(&[rot(0.0), rot(1.0), rot(20.0)]);
    assert_eq!((kept, d), (vec![rot(0.0), rot(20.0)], false));
    // Identical normals whose dot product rounds above 1 count once (no NaN).
    let mut above_one = 0;
    for i in 0..200 {
        let n = DVec3::new(i as f64 + 1.0, 3.0, 7.0).normalize();
        above_one += (n.dot(n) > 1.0) as u32;
        assert_eq!(distinct_normals(&[n; 5]), (vec![n], false));
    }
    assert!(above_one > 0, "no candidate exercised dot > 1");
    // The threshold.
    assert_eq!(distinct_normals(&[rot(0.0), rot(4.9)]).0.len(), 1);
    assert_eq!(distinct_normals(&[rot(0.0), rot(5.1)]).0.len(), 2);
    // Four distinct normals make a distribution.
    let four = [rot(0.0), rot(6.0), rot(12.0), rot(18.0), rot(24.0)];
    let (kept, d) = distinct_normals(&four);
    assert!(d && kept.len() == 4);
}

/// The dot-product bound decides exactly as `acos` against 5° does: at the bound and its
/// neighbours, and over a million dot products near it and across [−1.1, 1.1].
#[test]
fn distinct_dot_bound_agrees_with_acos() {
    let by_acos = |x: f64| x.clamp(-1.0, 1.0).acos() > DISTINCT_ANGLE;
    let b = *DISTINCT_DOT;
    assert!(!by_acos(b) && by_acos(f64::from_bits(b.to_bits() - 1)));
    for i in 0..1_000_000u64 {
        let near = f64::from_bits(b.to_bits() - 500_000 + i);
        let wide = -1.1 + 2.2 * i as f64 / 1e6;
        for x in [near, wide] {
            assert_eq!(x < b, by_acos(x), "{x}");
        }
    }
}

#[test]
fn cone_axis_is_normalized_and_theta_is_floored() {
    // Normals on a 30° circle: θmax is 30°, not the 36° of an unnormalized mean.
    let ring: Vec<DVec3> = (0..12)
        .map(|i| {
            let p = std::f64::consts::TAU * i as f64 / 12.0;
            let t = 30f64.to_radians();
            DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
        })
        .collect();
    let (axis, theta) = cone(&ring).unwrap();
    assert!((axis - DVec3::Z).length() < 1e-12);
    assert!((theta - 30f64.to_radians()).abs() < 1e-9, "{}", theta.to_degrees());
    let (_, theta) = cone(&[DVec3::X, DVec3::X]).unwrap();
    assert_eq!(theta, THETA_MIN);
    assert!(cone(&[]).is_none());
}

#[test]
fn curved_surface_gives_distribution_faces_with_face_colours() {
    // A cap of normals around a tilted axis, coloured by the sign of the x component.
    let ns = cap(Vec3::new(0.2, 0.1, 1.0), 0.8, 150);
    let colour = |n: Vec3| if n.x > 0.2 { Vec3::new(0.8, 0.1, 0.1) } else { Vec3::splat(0.3) };
    let s = hits(&ns, |i| colour(ns[i]));
    let rec = fit(&s).unwrap();
    assert!(rec.distribution != 0, "a curved surface is a distribution somewhere");
    let frame = sggx::estimate(&ns).unwrap().frame;
    let faces: Vec<usize> = assign_faces(ns.iter().map(|n| n.as_dvec3()), &frame).collect();
    for f in 0..8 {
        let members: Vec<usize> = (0..ns.len()).filter(|&i| faces[i] == f).collect();
        if members.is_empty() {
            assert_eq!(rec.normals[f], [[0; 3]; 3]);
            continue;
        }
        let mean = members.iter().map(|&i| colour(ns[i])).sum::<Vec3>() / members.len() as f32;
        assert!((rec.face_color(f) - mean).abs().max_element() < 0.01, "face {f}");
    }
    // Determinism: the same samples give the same bytes, also with shared fits.
    assert_eq!(fit(&s).unwrap(), rec);
    let shared = sggx::estimate_samples(&s).unwrap();
    assert_eq!(fit_with(&s, &shared, subgrid::build(&s)), rec);
}

#[test]
fn weights_are_exact_projected_areas() {
    // A regular octahedron (identity frame, equal semi-axes) with two fixed-set faces:
    // face 0 (+++) white with normal (1,1,1)/√3, face 7 (−++) black with normal (−1,1,1)/√3.
    let mut rec = VirtualMeshRecord {
        axes: [[127, 0, 0], [0, 127, 0], [0, 0, 127]],
        scales: [SCALE_RANGE.encode(0.5); 3],
        ..Default::default()
    };
    rec.colors[0] = [255; 3];
    rec.normals[0][0] = encode_dir(Vec3::ONE.normalize());
    rec.normals[7][0] = encode_dir(Vec3::new(-1.0, 1.0, 1.0).normalize());
    let l = LightSample { to_light: Vec3::Y, distance: 1.0, irradiance: Vec3::splat(PI) };
    let v = Vec3::new(0.3, 0.4, 1.0).normalize();
    let r = shade_record(&rec, None, v, &l, 1.0, Vec3::ZERO, 16);
    // Face areas ∝ |n_f·v| for a regular octahedron; white shade = n0·l.
    let (a0, a7) = (Vec3::ONE.dot(v).abs(), Vec3::new(-1.0, 1.0, 1.0).dot(v).abs());
    let expected = a0 / (a0 + a7) * rec.normal(0, 0).dot(Vec3::Y);
    assert!((r.x - expected).abs() < 1e-5, "{r} vs {expected}");
    // Seen from below only the fallback applies: mean over both stored normals.
    let r = shade_record(&rec, None, Vec3::NEG_Y, &l, 1.0, Vec3::ZERO, 16);
    let expected = 0.5 * rec.normal(0, 0).dot(Vec3::Y);
    assert!((r.x - expected).abs() < 1e-5, "fallback {r} vs {expected}");
}

#[test]
fn sixteen_samples_converge_to_256() {
    let ns = cap(Vec3::new(-0.3, 0.2, 1.0), 1.0, 150);
    let rec = fit(&hits(&ns, |_| Vec3::splat(0.8))).unwrap();
    let mut worst = 0.0f32;
    for i in 0..40 {
        let v = Vec3::new(rand_f32(9, i, 0) - 0.5, rand_f32(9, i, 1) - 0.5, rand_f32(9, i, 2))
            .normalize();
        let a = shade_record(&rec, None, v, &light(), 1.0, Vec3::splat(0.05), 16);
        let b = shade_record(&rec, None, v, &light(), 1.0, Vec3::splat(0.05), 256);
        worst = worst.max((a - b).abs().max_element() / b.max_element().max(0.05));
    }
    assert!(worst < 0.03, "relative difference 16 vs 256 samples: {worst}");
}

#[test]
fn axis_aligned_and_face_perpendicular_views_are_finite() {
    let curved = fit(&hits(&cap(Vec3::Z, 1.2, 150), |_| Vec3::ONE)).unwrap();
    let flat = fit(&hits(&[Vec3::X; 10], |_| Vec3::ONE)).unwrap();
    for rec in [curved, flat] {
        let mut views = vec![Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        for k in 0..3 {
            views.push(rec.axis(k));
        }
        let v: [Vec3; 6] = std::array::from_fn(|i| {
            let a = rec.axis(i / 2) * rec.scale(i / 2);
            if i % 2 == 0 { a } else { -a }
        });
        for tri in FACES {
            let n = (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]).normalize();
            views.push(n); // perpendicular to the face
            views.push((v[tri[1]] - v[tri[0]]).normalize()); // in the face's plane
        }
        for view in views {
            let r = shade_record(&rec, None, view, &light(), 1.0, Vec3::splat(0.1), 16);
            assert!(r.is_finite() && r.min_element() >= 0.0, "{view}: {r}");
        }
    }
}

#[test]
fn grid_wrapper_selects_the_opacity_rule() {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::ONE).unwrap();
    let mut rec = fit(&hits(&[Vec3::Z; 4], |_| Vec3::ONE)).unwrap();
    // A thin plane: the middle z-layer opaque.
    rec.opacity = std::array::from_fn(|c| if c / 9 == 1 { 255 } else { 0 });
    let records = BrickMap::from_voxels(UVec3::ONE, [(UVec3::ZERO, rec)]).unwrap();
    let mut g = VirtualMeshGrid::new(AppearanceGrid { grid, records, specular: None });
    assert_eq!(g.len(), 1);
    assert_eq!(g.index_of(UVec3::ZERO), Some(0));
    let alpha = |g: &VirtualMeshGrid, d: Vec3| match g.opacity(0, d) {
        Opacity::Alpha(a) => a,
        other => panic!("{other:?}"),
    };
    let face_on = alpha(&g, Vec3::Z);
    let lines = alpha(&g, Vec3::X);
    g.rule = DirectionalRule::Circles;
    let circles = alpha(&g, Vec3::X);
    assert!(face_on >= 0.99, "{face_on}");
    assert_eq!(lines, subgrid::directional_opacity(&rec.opacity, Vec3::X, DirectionalRule::Lines));
    assert_eq!(
        circles,
        subgrid::directional_opacity(&rec.opacity, Vec3::X, DirectionalRule::Circles)
    );
    assert_ne!(lines, circles);
    let r = g.radiance(0, Vec3::Z, &light(), 1.0, Vec3::ZERO);
    assert!(r.is_finite() && r.x > 0.0);
    // The specular side record reaches shade().
    g.grid.specular = Some(vec![SpecularRecord::new(1.0, 32.0)]);
    let l = LightSample { to_light: Vec3::Z, distance: 1.0, irradiance: Vec3::splat(PI) };
    let spec = g.radiance(0, Vec3::Z, &l, 1.0, Vec3::ZERO);
    assert!(spec.x > r.x, "{spec} vs {r}");
}

proptest! {
    #[test]
    fn shading_is_bounded(
        x in -1f32..1.0, y in -1f32..1.0, z in -1f32..1.0,
        lx in -1f32..1.0, ly in -1f32..1.0, theta in 0.05f32..1.5, ambient in 0f32..0.3,
    ) {
        let v = Vec3::new(x, y, z);
        let l = Vec3::new(lx, ly, 0.3);
        prop_assume!(v.length() > 1e-3);
        let rec = fit(&hits(&cap(Vec3::new(0.1, 0.9, 0.2), theta, 60), |i| {
            Vec3::new(0.9, 0.5, (i % 3) as f32 * 0.3)
        })).unwrap();
        let light = LightSample { to_light: l.normalize(), distance: 1.0, irradiance: Vec3::splat(2.0) };
        let r = shade_record(&rec, None, v, &light, 1.0, Vec3::splat(ambient), 16);
        prop_assert!(r.is_finite() && r.min_element() >= 0.0, "{}", r);
        prop_assert!(r.max_element() <= 0.9 * (2.0 / PI + ambient) + 1e-4, "{}", r);
    }
}

/// The authors' random face sampling: deterministic per record, seed and view; another seed
/// draws other points; 40 random samples land near the converged (256 fixed points) value;
/// faces without a distribution are not sampled, so they shade the same either way.
#[test]
fn random_face_sampling_is_seeded_and_converges() {
    let ns = cap(Vec3::new(-0.3, 0.2, 1.0), 1.0, 150);
    let rec = fit(&hits(&ns, |_| Vec3::splat(0.8))).unwrap();
    assert!(rec.distribution != 0, "a curved cap gives distribution faces");
    let params = |seed| VirtualMeshParams {
        samples_per_face: AUTHORS_SAMPLES_PER_FACE,
        sampling: FaceSampling::authors(seed),
        ..Default::default()
    };
    let (mut worst, mut differ) = (0.0f32, 0);
    for i in 0..40 {
        let v = Vec3::new(rand_f32(9, i, 0) - 0.5, rand_f32(9, i, 1) - 0.5, rand_f32(9, i, 2))
            .normalize();
        let shade = |p: &VirtualMeshParams| {
            shade_record_with(&rec, None, v, &light(), 1.0, Vec3::splat(0.05), p)
        };
        let a = shade(&params(1));
        assert_eq!(a, shade(&params(1)), "view {i}: the same seed draws the same points");
        differ += (a != shade(&params(2))) as u32;
        let converged = shade_record(&rec, None, v, &light(), 1.0, Vec3::splat(0.05), 256);
        worst = worst.max((a - converged).abs().max_element() / converged.max_element().max(0.05));
    }
    assert!(differ >= 30, "another seed changes the value in {differ} of 40 views");
    assert!(worst > 0.0 && worst < 0.08, "relative difference 40 random vs 256 fixed: {worst}");

    // A flat voxel has one fixed-set face: no sampling, the same value bit for bit.
    let flat = fit(&hits(&[Vec3::Z; 8], |_| Vec3::splat(0.5))).unwrap();
    assert_eq!(flat.distribution, 0);
    let v = Vec3::new(0.2, 0.1, 1.0).normalize();
    assert_eq!(
        shade_record_with(&flat, None, v, &light(), 1.0, Vec3::ZERO, &params(3)),
        shade_record(&flat, None, v, &light(), 1.0, Vec3::ZERO, 16),
    );
}

/// A record key depends on every byte: records that differ in one opacity byte get other keys.
#[test]
fn record_keys_differ_between_records() {
    let rec = fit(&hits(&cap(Vec3::Z, 0.8, 60), |_| Vec3::ONE)).unwrap();
    let mut other = rec;
    other.opacity[13] ^= 1;
    assert_ne!(record_key(&rec), record_key(&other));
    assert_eq!(record_key(&rec), record_key(&rec.clone()));
}

/// Seen from where no stored normal faces the viewer, ours shades with every stored normal,
/// the authors' leave the voxel unshaded (black), through the grid as through the function.
#[test]
fn fallback_when_no_normal_faces_the_viewer() {
    let mut rec = VirtualMeshRecord {
        axes: [[127, 0, 0], [0, 127, 0], [0, 0, 127]],
        scales: [SCALE_RANGE.encode(0.5); 3],
        ..Default::default()
    };
    rec.colors[0] = [255; 3];
    rec.normals[0][0] = encode_dir(Vec3::ONE.normalize());
    let l = LightSample { to_light: Vec3::Y, distance: 1.0, irradiance: Vec3::splat(PI) };
    let ambient = Vec3::splat(0.1);
    let ours = shade_record(&rec, None, Vec3::NEG_Y, &l, 1.0, ambient, 16);
    assert!(ours.x > 0.1, "ours: the stored normal, lit: {ours}");
    let p = VirtualMeshParams { fallback: ShadingFallback::Unshaded, ..Default::default() };
    assert_eq!(shade_record_with(&rec, None, Vec3::NEG_Y, &l, 1.0, ambient, &p), Vec3::ZERO);
    // From the front both agree: the fallback is not reached.
    let front = Vec3::new(0.2, 0.3, 1.0).normalize();
    assert_eq!(
        shade_record_with(&rec, None, front, &l, 1.0, ambient, &p),
        shade_record(&rec, None, front, &l, 1.0, ambient, 16)
    );
    let grid = GridSpec::new(glam::DVec3::ZERO, 1.0, UVec3::ONE).unwrap();
    let records = BrickMap::from_voxels(grid.dims, [(UVec3::ZERO, rec)]).unwrap();
    let g = VirtualMeshGrid::with_params(AppearanceGrid { grid, records, specular: None }, p);
    assert_eq!(g.params(), p);
    assert_eq!(g.radiance(0, Vec3::NEG_Y, &l, 1.0, ambient), Vec3::ZERO);
}
