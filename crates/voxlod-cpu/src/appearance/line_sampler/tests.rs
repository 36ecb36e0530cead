//! Tests of the sampler, one per rule of the design note §1.

use std::sync::Arc;

use glam::{DVec3, UVec3, Vec2, Vec3, Vec4};
use voxlod_format::GridSpec;
use voxlod_scene::{AlphaMode, Geometry, Material, Mesh, Scene, Texture};

use super::*;
use crate::render::test_scenes::{quad, scene, sun};
use crate::voxelize::{self, Voxelization, voxelize};

/// A scene of one square plane `z = height` spanning `±half` in x and y around the 4³ grid's
/// centre, front face toward +z, with `material`.
fn plane_scene(height: f32, half: f32, material: Material) -> Scene {
    let corner = Vec3::new(2.0 - half, 2.0 - half, height);
    let mesh = quad("plane", corner, Vec3::X * 2.0 * half, Vec3::Y * 2.0 * half, 0);
    scene(vec![mesh], vec![material], sun(Vec3::Z, 1.0))
}

fn grid() -> GridSpec {
    GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(4)).unwrap()
}

fn prepare(scene: &Scene) -> (Geometry, Voxelization) {
    let g = scene.geometry();
    let v = voxelize(&g, &grid(), &voxelize::Options::default()).unwrap();
    (g, v)
}

/// Samples `rays` lines of the voxel at `c` (seed 0).
fn sample(scene: &Scene, c: UVec3, rays: u32) -> VoxelSamples {
    let (g, v) = prepare(scene);
    let ctx = SamplingContext::new(scene, &g, &v).unwrap();
    let mut out = VoxelSamples::default();
    ctx.sample_voxel(v.voxels.index_of(c).unwrap(), 0, rays, &mut out);
    out
}

fn grey() -> Material {
    Material::diffuse("grey", Vec3::splat(0.5))
}

/// The face choice picks axis k with frequency |d_k| / Σ|d|, and its remainder is uniform.
#[test]
fn face_choice_frequencies_match_projected_areas() {
    let n = 100_000;
    for d in [Vec3::new(0.2, -0.5, 0.7), Vec3::new(-1.0, 0.0, 0.0), Vec3::new(0.3, 0.3, -0.3)] {
        let mut counts = [0u32; 3];
        let mut remainder = 0.0f64;
        for i in 0..n {
            let (k, r) = choose_face(d, (i as f32 + 0.5) / n as f32);
            counts[k] += 1;
            assert!((0.0..1.0).contains(&r) && d[k] != 0.0, "{d}: {k}, {r}");
            remainder += r as f64;
        }
        let a = d.abs();
        for k in 0..3 {
            let expected = a[k] / (a.x + a.y + a.z);
            let got = counts[k] as f32 / n as f32;
            assert!((got - expected).abs() < 1e-3, "{d}: axis {k} {got} vs {expected}");
        }
        assert!((remainder / n as f64 - 0.5).abs() < 1e-3);
    }
    assert_eq!(choose_face(Vec3::ZERO, 0.25), (2, 0.25));
}

/// Over 10⁵ sampled lines: directions are uniform, each line enters through the face its
/// direction chose with the right frequency, and the mean chord is 2/3 voxel (Cauchy: 4V/S).
#[test]
fn sampled_lines_are_isotropic_with_mean_chord_two_thirds() {
    let n = 100_000u32;
    let (mut chord_sum, mut z2, mut mean) = (0.0f64, 0.0f64, DVec3::ZERO);
    let (mut faces, mut shares) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..n {
        let (d, e, len) = sample_line(i % 1000, i / 1000, 0);
        assert!((d.length() - 1.0).abs() < 1e-5);
        assert!(len > 0.0 && len <= 3f32.sqrt() + 1e-5, "{len}");
        let k = (0..3)
            .find(|&k| e[k] == if d[k] > 0.0 { 0.0 } else { 1.0 })
            .expect("the entry lies on a face the line enters through");
        for j in 0..3 {
            if j != k {
                assert!(e[j] > 0.0 && e[j] < 1.0, "{e}");
            }
        }
        let a = d.abs();
        faces[k] += 1.0;
        for j in 0..3 {
            shares[j] += (a[j] / (a.x + a.y + a.z)) as f64;
        }
        chord_sum += len as f64;
        z2 += (d.z * d.z) as f64;
        mean += d.as_dvec3();
    }
    let n = n as f64;
    let mean_chord = chord_sum / n;
    assert!((mean_chord - 2.0 / 3.0).abs() < 0.01, "mean chord {mean_chord}");
    assert!((z2 / n - 1.0 / 3.0).abs() < 0.01 && (mean / n).length() < 0.01);
    for k in 0..3 {
        assert!((faces[k] - shares[k]).abs() / n < 0.005, "{faces:?} vs {shares:?}");
    }
}

/// A plane of two big triangles through the voxel blocks every line, in every direction bin
/// (dominant axis and sign); hits outside the voxel count; front hits carry the normal.
#[test]
fn big_plane_gives_hits_equal_to_rays_from_every_direction() {
    let s = sample(&plane_scene(1.5, 1e4, grey()), UVec3::ONE, 1200);
    let mut bins = [[0u32; 2]; 6];
    for r in &s.rays {
        let k = r.dir.abs().max_position();
        let bin = 2 * k + (r.dir[k] < 0.0) as usize;
        bins[bin][0] += 1;
        bins[bin][1] += r.occluded as u32;
    }
    for (b, [rays, hits]) in bins.iter().enumerate() {
        assert!(*rays > 50 && hits == rays, "bin {b}: {hits} hits of {rays} rays");
    }
    let inside = s.rays.iter().filter(|r| r.surface.is_some()).count();
    assert!(inside > 0 && inside < s.rays.len() / 2, "{inside} case-(a) hits");
    assert_eq!(s.occluded(), s.rays.len());
    assert_eq!(s.opacity(), 1.0);
    for x in s.surfaces() {
        assert!((x.point.z - 0.5).abs() < 1e-6 && x.normal == Vec3::Z, "{x:?}");
        assert_eq!(x.albedo, Vec3::splat(0.5));
    }
}

/// A single-sided plane hit from behind books an occlusion without a normal; hit from the
/// front, a surface sample.
#[test]
fn back_facing_hits_occlude_without_a_normal() {
    let s = sample(&plane_scene(1.5, 1e4, grey()), UVec3::ONE, 600);
    let mut back = 0;
    for r in &s.rays {
        assert!(r.occluded);
        if r.dir.z > 0.0 {
            // The front face looks toward +z: lines travelling up see its back.
            assert!(r.surface.is_none(), "{r:?}");
            let t = (0.5 - r.entry.z) / r.dir.z;
            back += (r.entry + r.dir * t).cmpge(Vec3::ZERO).all() as u32
                * (r.entry + r.dir * t).cmple(Vec3::ONE).all() as u32;
        }
    }
    assert!(back > 50, "only {back} back-facing hits inside the voxel");
}

/// Double-sided: every inside hit is front-facing, its normal flipped toward the line's origin
/// exactly where the geometric normal faces along the line.
#[test]
fn double_sided_hits_are_front_facing_with_flipped_normals() {
    let m = Material { double_sided: true, ..grey() };
    let s = sample(&plane_scene(1.5, 1e4, m), UVec3::ONE, 600);
    let (mut up, mut down) = (0, 0);
    for r in &s.rays {
        let t = (0.5 - r.entry.z) / r.dir.z;
        let p = r.entry + r.dir * t;
        let inside = p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all();
        // Away from the voxel's boundary, where this recomputation may round the other way.
        let clear = (p - Vec3::splat(0.5)).abs().max_element() < 0.5 - 1e-4
            || (p - Vec3::splat(0.5)).abs().max_element() > 0.5 + 1e-4;
        if clear {
            assert_eq!(r.surface.is_some(), inside, "{r:?}");
        }
        if let Some(x) = r.surface {
            assert!(x.normal.dot(r.dir) < 0.0);
            assert_eq!(x.normal, if r.dir.z > 0.0 { Vec3::NEG_Z } else { Vec3::Z });
            if r.dir.z > 0.0 { up += 1 } else { down += 1 }
        }
    }
    assert!(up > 30 && down > 30, "{up} / {down}");
}

/// A triangle lying exactly on a voxel face is inside the closed voxel box (the grid's tie
/// rule): its hits are case (a) at local z = 0 exactly.
#[test]
fn a_triangle_on_a_voxel_face_counts_as_inside() {
    let s = sample(&plane_scene(1.0, 1e4, grey()), UVec3::ONE, 300);
    let surfaces: Vec<_> = s.surfaces().collect();
    assert!(surfaces.len() > 30);
    assert!(surfaces.iter().all(|x| x.point.z == 0.0), "{surfaces:?}");
}

#[test]
fn alpha_masked_and_blended_materials_filter_hits() {
    let transparent = Material {
        base_color: Vec4::new(0.5, 0.5, 0.5, 0.2),
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        ..grey()
    };
    let s = sample(&plane_scene(1.5, 1e4, transparent), UVec3::ONE, 300);
    assert_eq!(s.occluded(), 0);
    let half = Material {
        base_color: Vec4::new(0.5, 0.5, 0.5, 0.5),
        alpha_mode: AlphaMode::Blend,
        ..grey()
    };
    let s = sample(&plane_scene(1.5, 1e4, half), UVec3::ONE, 1000);
    let o = s.opacity();
    assert!((o - 0.5).abs() < 0.06, "blended coverage 0.5 occludes {o}");
}

/// The colour is the textured albedo at the hit's UV, the ground truth's material sample.
#[test]
fn colours_are_textured_albedos_at_the_hit() {
    let texture = Texture {
        name: "ramp".into(),
        width: 4,
        height: 1,
        texels: Arc::from(vec![
            [0, 0, 0, 255],
            [80, 0, 0, 255],
            [160, 0, 0, 255],
            [240, 0, 0, 255],
        ]),
        srgb: false,
        sampler: Default::default(),
    };
    let material = Material {
        base_color: Vec4::ONE,
        base_color_texture: Some(voxlod_scene::TextureRef { texture: 0 }),
        double_sided: true,
        ..grey()
    };
    // UV (s, t) over the 10 × 10 quad from (−3, −3).
    let mut sc = plane_scene(1.5, 5.0, material);
    sc.textures.push(texture);
    let s = sample(&sc, UVec3::ONE, 300);
    let mut seen = 0;
    for x in s.surfaces() {
        let world = Vec3::ONE + x.point;
        let uv = Vec2::new((world.x + 3.0) / 10.0, (world.y + 3.0) / 10.0);
        let expected = sc.material_sample(0, uv).albedo;
        assert!((x.albedo - expected).abs().max_element() < 1e-3, "{} vs {expected}", x.albedo);
        seen += 1;
    }
    assert!(seen > 30);
    // The texture varies across the voxel.
    let reds: Vec<f32> = s.surfaces().map(|x| x.albedo.x).collect();
    assert!(
        reds.iter().cloned().fold(0.0, f32::max) - reds.iter().cloned().fold(1.0, f32::min) > 0.01
    );
}

/// The same seed gives bit-identical lines; another seed different ones; rays R..R+H drawn
/// alone equal the tail of 0..R+H (held-out rays are independent of the fitted ones).
#[test]
fn sampling_is_deterministic_and_held_out_rays_are_independent() {
    let sc = plane_scene(1.3, 1e4, grey());
    let (g, v) = prepare(&sc);
    let ctx = SamplingContext::new(&sc, &g, &v).unwrap();
    let i = v.voxels.index_of(UVec3::ONE).unwrap();
    let (mut a, mut b, mut c) =
        (VoxelSamples::default(), VoxelSamples::default(), VoxelSamples::default());
    ctx.sample_voxel(i, 0, 200, &mut a);
    ctx.sample_voxel(i, 0, 150, &mut b);
    ctx.sample_voxel(i, 150, 50, &mut c);
    assert_eq!(&a.rays[..150], &b.rays[..]);
    assert_eq!(&a.rays[150..], &c.rays[..]);
    let same = std::thread::spawn({
        let a = a.clone();
        move || a
    })
    .join()
    .unwrap();
    assert_eq!(a, same);
    let seeded = SamplingContext::new(&sc, &g, &v).unwrap().with_seed(7);
    seeded.sample_voxel(i, 0, 200, &mut b);
    ctx.sample_voxel_seeded(i, 7, 0, 200, &mut c);
    assert_eq!(b, c);
    assert_ne!(a, b);
    // Another voxel draws other lines.
    ctx.sample_voxel(v.voxels.index_of(UVec3::new(2, 1, 1)).unwrap(), 0, 200, &mut c);
    assert_ne!(
        a.rays.iter().map(|r| r.dir).collect::<Vec<_>>(),
        c.rays.iter().map(|r| r.dir).collect::<Vec<_>>()
    );
}

#[test]
fn mismatched_inputs_are_errors() {
    let sc = plane_scene(1.5, 10.0, grey());
    let (g, v) = prepare(&sc);
    let mut bad = g.clone();
    bad.normals.pop();
    assert!(SamplingContext::new(&sc, &bad, &v).is_err());
    let mut bad = g.clone();
    bad.positions[0].x = f32::NAN;
    assert!(SamplingContext::new(&sc, &bad, &v).is_err());
    let mut bad = g.clone();
    bad.materials[0] = 3;
    assert!(SamplingContext::new(&sc, &bad, &v).is_err());
    let fewer = Geometry { indices: vec![g.indices[0]], materials: vec![0], ..g.clone() };
    assert!(SamplingContext::new(&sc, &fewer, &v).is_err(), "lists name triangle 1");
    let mut no_lists = v.clone();
    no_lists.triangles.clear();
    assert!(SamplingContext::new(&sc, &g, &no_lists).is_err());
    // An empty scene samples nothing and is fine.
    let empty = Scene { meshes: Vec::<Mesh>::new(), ..sc.clone() };
    let (eg, ev) = prepare(&empty);
    assert_eq!(SamplingContext::new(&empty, &eg, &ev).unwrap().voxel_count(), 0);
}

#[test]
fn polynomial_sin_cos_matches_the_library_and_directions_are_unit() {
    for i in 0..100_000 {
        let u = i as f32 / 100_000.0;
        let (s, c) = sin_cos_turns(u);
        let (es, ec) = (std::f64::consts::TAU * u as f64).sin_cos();
        assert!((s as f64 - es).abs() < 3e-7 && (c as f64 - ec).abs() < 3e-7, "{u}: {s}, {c}");
        let d = uniform_direction(u, 1.0 - u);
        assert!((d.length() - 1.0).abs() < 1e-6, "{d}");
    }
    assert_eq!(uniform_direction(0.0, 0.0), Vec3::Z);
}

#[test]
fn chords_of_lines_through_the_voxel() {
    assert_eq!(chord(Vec3::new(0.0, 0.5, 0.5), Vec3::X), 1.0);
    assert_eq!(chord(Vec3::new(1.0, 0.5, 0.5), Vec3::NEG_X), 1.0);
    let diag = Vec3::ONE.normalize();
    assert!((chord(Vec3::ZERO, diag) - 3f32.sqrt()).abs() < 1e-6);
    // Leaving at once through an edge, and no direction at all.
    assert_eq!(chord(Vec3::new(0.0, 1.0, 0.5), Vec3::new(1.0, 1.0, 0.0).normalize()), 0.0);
    assert_eq!(chord(Vec3::new(0.0, 0.5, 0.5), Vec3::ZERO), 0.0);
}
