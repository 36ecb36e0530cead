//! Transmittance shadow maps against the ray-traced transmittance, and the traversed length
//! (the refraction thickness reference) against closed forms.

use glam::{DVec3, Vec3};
use voxlod_scene::{Geometry, Light};

use super::*;
use crate::raycast::Bvh;
use crate::voxelize::slicemap::{self as sm, Faces, Options, SliceCamera, Slicing};
use crate::voxelize::tests::{blob, cube};

/// Appends a horizontal quad at height `y` over `[x0, x1] × [z0, z1]` (two triangles).
fn quad(g: &mut Geometry, y: f32, x0: f32, x1: f32, z0: f32, z1: f32) {
    let b = g.positions.len() as u32;
    g.positions.extend([
        Vec3::new(x0, y, z0),
        Vec3::new(x1, y, z0),
        Vec3::new(x1, y, z1),
        Vec3::new(x0, y, z1),
    ]);
    g.indices.extend([[b, b + 2, b + 1], [b, b + 3, b + 2]]);
}

/// A ground quad (triangles 0, 1) at y = 0 over [−4, 4]², three leaf layers (triangles 2..8)
/// over [−1, 1]² at y = 1, 1.6, 2.3, and an opaque roof (triangles 8, 9) at y = 3 over
/// [2, 3] × [−1, 1].
fn scene() -> Geometry {
    let mut g = Geometry::default();
    quad(&mut g, 0.0, -4.0, 4.0, -4.0, 4.0);
    for y in [1.0, 1.6, 2.3] {
        quad(&mut g, y, -1.0, 1.0, -1.0, 1.0);
    }
    quad(&mut g, 3.0, 2.0, 3.0, -1.0, 1.0);
    g
}

fn leaves(t: usize) -> bool {
    (2..8).contains(&t)
}

fn sun() -> Light {
    Light::Directional { to_light: Vec3::Y, irradiance: Vec3::ONE }
}

#[test]
fn layers_between_a_point_and_the_light_attenuate_it() {
    let g = scene();
    let bvh = Bvh::new(&g).unwrap();
    let o = ShadowOptions { size: 64, slices: 32, sigma: 0.5, bias: 0.05, ..Default::default() };
    let map = TransmittanceShadowMap::build(&g, leaves, &sun(), &o).unwrap();
    assert_eq!(map.faces.len(), 1);
    let reference = RayTracedTransmittance::new(&g, &bvh, leaves, &sun(), 0.5, 1e-4).unwrap();
    for (p, layers, blocked) in [
        (Vec3::new(0.1, 0.0, 0.2), 3, false),
        (Vec3::new(0.1, 1.3, 0.2), 2, false),
        (Vec3::new(0.1, 2.0, 0.2), 1, false),
        (Vec3::new(0.1, 2.3, 0.2), 0, false), // on the top leaf: its own layer does not count
        (Vec3::new(2.5, 0.0, 0.0), 0, true),
        (Vec3::new(-3.0, 0.0, 3.0), 0, false),
    ] {
        assert_eq!(reference.crossings(p), (blocked, layers), "reference at {p}");
        assert_eq!(map.lookup(p.as_dvec3()), Some((blocked, layers)), "map at {p}");
        let t = if blocked { 0.0 } else { 0.5f32.powi(layers as i32) };
        assert_eq!(map.transmittance(p), t);
        assert_eq!(reference.transmittance(p), t);
    }
    // Outside the maps' bounds: fully lit.
    assert_eq!(map.transmittance(Vec3::new(50.0, 0.0, 0.0)), 1.0);
    assert!(map.memory_bytes() > 64 * 64 * 4);
}

#[test]
fn a_point_light_inside_the_scene_sees_every_direction() {
    // The light at the centre of a closed transmissive cube [−1, 1]³; the ground below it.
    let mut g = cube(Vec3::splat(-1.0), 2.0, &[]);
    let walls = g.indices.len();
    quad(&mut g, -3.0, -6.0, 6.0, -6.0, 6.0);
    let light = Light::Point { position: Vec3::ZERO, intensity: Vec3::ONE };
    let walls_only = |t: usize| t < walls;
    let o = ShadowOptions { size: 64, slices: 32, sigma: 0.25, bias: 0.25, ..Default::default() };
    let map = TransmittanceShadowMap::build(&g, walls_only, &light, &o).unwrap();
    assert_eq!(map.faces.len(), 6);
    let bvh = Bvh::new(&g).unwrap();
    let reference = RayTracedTransmittance::new(&g, &bvh, walls_only, &light, 0.25, 1e-4).unwrap();
    // Points in every direction outside the cube: one wall between them and the light; the
    // ground under the light too; a point inside the cube: none.
    for p in [
        Vec3::new(2.5, 0.3, 0.1),
        Vec3::new(-2.0, 1.0, -0.5),
        Vec3::new(0.2, 2.8, 0.4),
        Vec3::new(0.3, -0.2, -2.2),
        Vec3::new(0.5, -3.0, 0.7),
        Vec3::new(4.0, -3.0, -2.0),
    ] {
        assert_eq!(reference.crossings(p), (false, 1), "reference at {p}");
        assert_eq!(map.lookup(p.as_dvec3()), Some((false, 1)), "map at {p}");
    }
    assert_eq!(map.lookup(DVec3::new(0.3, 0.2, 0.1)), Some((false, 0)));
}

#[test]
fn bad_shadow_options_are_named() {
    let g = scene();
    for o in [
        ShadowOptions { sigma: 1.5, ..Default::default() },
        ShadowOptions { bias: -1.0, ..Default::default() },
        ShadowOptions { slices: 0, ..Default::default() },
    ] {
        let err = TransmittanceShadowMap::build(&g, leaves, &sun(), &o).unwrap_err().to_string();
        assert!(err.contains("sigma") || err.contains("slices"), "{err}");
    }
    let empty = Geometry::default();
    assert!(TransmittanceShadowMap::build(&empty, leaves, &sun(), &Default::default()).is_err());
}

#[test]
fn traversed_length_sums_inside_intervals() {
    let g = cube(Vec3::ZERO, 2.0, &[]);
    let bvh = Bvh::new(&g).unwrap();
    let l = traversed_length(&bvh, &g, Vec3::new(0.5, 0.7, -3.0), Vec3::Z, 0.0);
    assert!((l - 2.0).abs() < 1e-5, "{l}");
    // Two cubes along the ray: the gap between them is outside.
    let mut two = g.clone();
    let second = cube(Vec3::new(0.0, 0.0, 3.0), 1.5, &[]);
    let base = two.positions.len() as u32;
    two.positions.extend(second.positions);
    two.indices.extend(second.indices.iter().map(|t| t.map(|i| i + base)));
    let bvh2 = Bvh::new(&two).unwrap();
    let l = traversed_length(&bvh2, &two, Vec3::new(0.5, 0.7, -3.0), Vec3::Z, 0.0);
    assert!((l - 3.5).abs() < 1e-5, "{l}");
    // A ray through the cube's edge-sharing diagonal counts each hit once.
    let l = traversed_length(
        &bvh,
        &g,
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(1.0, 1.0, 0.0).normalize(),
        0.0,
    );
    assert!((l - 8f32.sqrt()).abs() < 1e-4, "{l}");
}

/// The slicemap's traversed volume (front/back local maps, Fig. 9 rules) against the exact
/// ray-cast lengths on a closed bumpy blob: close at 256 slices, and closer than at 32.
#[test]
fn slicemap_thickness_approaches_the_ray_cast_length() {
    let g = blob(12, 0.3);
    let bvh = Bvh::new(&g).unwrap();
    let cam = SliceCamera::from_camera(
        &voxlod_scene::Camera::look_at(Vec3::new(0.4, 0.6, 4.0), Vec3::ZERO, Vec3::Y, 40.0),
        48,
        48,
        1.0,
        8.0,
    );
    let frame = cam.frame();
    let mut errors = Vec::new();
    for slices in [32, 256] {
        let o =
            Options { slices, slicing: Slicing::Local, faces: Faces::Split, ..Options::default() };
        let map = sm::build(&g, &cam, &o).unwrap();
        let (mut sum, mut n, mut depth) = (0.0, 0, 0.0);
        for y in 0..48 {
            for x in 0..48 {
                let (origin, dir) = frame.ray(glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                let exact = traversed_length(&bvh, &g, origin.as_vec3(), dir.as_vec3(), 0.0) as f64;
                if exact > 0.0 {
                    sum += (map.thickness(x, y).unwrap() - exact).abs();
                    depth += exact;
                    n += 1;
                }
            }
        }
        errors.push((sum / n as f64, depth / n as f64));
    }
    let ((e32, mean), (e256, _)) = (errors[0], errors[1]);
    assert!(e256 < 0.01 * mean, "mean error {e256} at 256 slices vs mean length {mean}");
    assert!(e256 < e32, "{e256} at 256 slices vs {e32} at 32");
}
