//! Tests of the ray-traced AO and one-bounce references against analytic values.

use std::f32::consts::PI;

use glam::Vec3;
use voxlod_scene::{Material, Scene};

use super::*;
use crate::render::ground_truth::gbuffer;
use crate::render::test_scenes::{camera, quad, scene, sun};

fn white() -> Material {
    Material::diffuse("white", Vec3::ONE)
}

/// A 40×40 floor at z = 0 facing +z.
fn floor() -> voxlod_scene::Mesh {
    quad("floor", Vec3::new(-20.0, -20.0, 0.0), Vec3::X * 40.0, Vec3::Y * 40.0, 0)
}

fn setup(scene: &Scene, eye: Vec3, target: Vec3, size: u32) -> (Geometry, Bvh, GBuffer) {
    let g = scene.geometry();
    let bvh = Bvh::new(&g).unwrap();
    let gb = gbuffer(scene, &g, &bvh, &camera(eye, target), size, size).unwrap();
    (g, bvh, gb)
}

/// AO under an infinite ceiling at height `h`, linear falloff, cosine-weighted quadrature.
fn ceiling_ao(h: f32, r: f32) -> f32 {
    let n = 20_000;
    let occ: f32 = (0..n)
        .map(|i| {
            let u = (i as f32 + 0.5) / n as f32;
            falloff(h / (1.0 - u).sqrt(), r)
        })
        .sum();
    1.0 - occ / n as f32
}

#[test]
fn ao_under_a_ceiling_matches_the_analytic_value() {
    // Floor at z = 0, a 40×40 ceiling at z = 1 facing down; the camera between them looks at
    // the floor's centre. R = 3.
    let ceiling = quad("ceiling", Vec3::new(-20.0, -20.0, 1.0), Vec3::Y * 40.0, Vec3::X * 40.0, 0);
    let s = scene(vec![floor(), ceiling], vec![white()], sun(Vec3::Z, 1.0));
    let (g, bvh, gb) = setup(&s, Vec3::new(0.0, 0.0, 0.5), Vec3::ZERO, 8);
    let o = Options { spp: 1024, seed: 0, ao_radius: 3.0 };
    let ao = ambient_occlusion(&s, &g, &bvh, &gb, &o).unwrap();
    let mean = ao.iter().sum::<f32>() / ao.len() as f32;
    let expected = ceiling_ao(1.0, 3.0);
    assert!((mean - expected).abs() < 0.01, "AO {mean} vs analytic {expected}");
    // Without the ceiling: 1.
    let open = scene(vec![floor()], vec![white()], sun(Vec3::Z, 1.0));
    let (g, bvh, gb) = setup(&open, Vec3::new(0.0, 0.0, 0.5), Vec3::ZERO, 8);
    let ao = ambient_occlusion(&open, &g, &bvh, &gb, &o).unwrap();
    assert!(ao.iter().all(|&a| a == 1.0), "{ao:?}");
}

#[test]
fn one_bounce_from_a_lit_floor_matches_the_analytic_value() {
    // A 0.2×0.2 receiver at z = 1 facing down over a floor of radiance 1 (white, E = π from
    // straight above). It sees the floor over sin²θ = 400/401 of its cosine-weighted
    // hemisphere, minus its own shadow (a 0.2² patch 1 below: ≈ 0.04/π of it).
    let receiver = quad("receiver", Vec3::new(-0.1, -0.1, 1.0), Vec3::Y * 0.2, Vec3::X * 0.2, 0);
    let s = scene(vec![floor(), receiver], vec![white()], sun(Vec3::Z, PI));
    let (g, bvh, gb) = setup(&s, Vec3::new(0.0, 0.0, 0.9), Vec3::new(0.0, 0.0, 1.0), 4);
    assert!(gb.texels.iter().all(|t| t.triangle != u32::MAX && t.normal.z < -0.99));
    let o = Options { spp: 1024, seed: 0, ao_radius: 1.0 };
    let e = indirect_diffuse(&s, &g, &bvh, &gb, &o).unwrap();
    let mean = e.iter().map(|v| v.x).sum::<f32>() / e.len() as f32;
    let expected = 400.0 / 401.0 - 0.04 / PI;
    assert!((mean - expected).abs() < 0.01, "E/π {mean} vs analytic {expected}");
    // Another seed: a different estimate of the same value.
    let e1 = indirect_diffuse(&s, &g, &bvh, &gb, &Options { seed: 1, ..o }).unwrap();
    assert_ne!(e, e1);
    let mean1 = e1.iter().map(|v| v.x).sum::<f32>() / e1.len() as f32;
    assert!((mean - mean1).abs() < 0.01, "{mean} vs {mean1}");
}

#[test]
fn bad_options_are_errors() {
    let s = scene(vec![floor()], vec![white()], sun(Vec3::Z, 1.0));
    let (g, bvh, gb) = setup(&s, Vec3::new(0.0, 0.0, 0.5), Vec3::ZERO, 2);
    let e = ambient_occlusion(&s, &g, &bvh, &gb, &Options { spp: 0, ..Default::default() });
    assert!(e.unwrap_err().to_string().contains("spp"));
    let bad = Options { ao_radius: f32::NAN, ..Default::default() };
    assert!(
        ambient_occlusion(&s, &g, &bvh, &gb, &bad).unwrap_err().to_string().contains("ao_radius")
    );
}

#[test]
fn cosine_directions_have_mean_cosine_two_thirds() {
    for n in [Vec3::Z, Vec3::NEG_Z, Vec3::new(1.0, -2.0, 0.5).normalize()] {
        let m: f32 = (0..4096)
            .map(|s| cosine_direction(n, rand_f32(7, s, 1), rand_f32(7, s, 2)).dot(n))
            .sum::<f32>()
            / 4096.0;
        assert!((m - 2.0 / 3.0).abs() < 0.02, "{n}: {m}");
    }
}
