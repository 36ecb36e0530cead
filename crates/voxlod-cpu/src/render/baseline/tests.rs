//! Baseline tests, on voxelizations built by hand: the colour average (area, alpha, texture,
//! fallbacks), shadow rays and their 1.5-voxel skip, agreement with the ground truth on a
//! voxel-aligned box, determinism, and bad input.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{DVec3, UVec3, Vec3, Vec4};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::{AlphaMode, Geometry, Material, Sampler, Scene, Texture, TextureRef, WrapMode};

use super::*;
use crate::raycast::Bvh;
use crate::render::ground_truth;
use crate::render::test_scenes::{camera, cuboid, quad, scene, soup, sun};
use crate::voxelize::{Mode, TriangleRange, Voxelization};

/// A voxelization of `occupied` voxels whose lists hold every triangle whose bounding box
/// meets the voxel's closed box (a superset of the exact lists; clipping sorts it out).
fn by_hand(g: &Geometry, grid: GridSpec, occupied: impl Fn(UVec3) -> bool) -> Voxelization {
    let mut voxels = Vec::new();
    let mut triangles = Vec::new();
    for x in 0..grid.dims.x {
        for y in 0..grid.dims.y {
            for z in 0..grid.dims.z {
                let c = UVec3::new(x, y, z);
                if !occupied(c) {
                    continue;
                }
                let (lo, hi) = (grid.voxel_min(c), grid.voxel_min(c + 1));
                let first = triangles.len() as u32;
                for t in 0..g.triangle_count() {
                    let p = g.triangle(t).map(|p| p.as_dvec3());
                    let (tlo, thi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
                    if tlo.cmple(hi).all() && thi.cmpge(lo).all() {
                        triangles.push(t as u32);
                    }
                }
                voxels.push((c, TriangleRange { first, count: triangles.len() as u32 - first }));
            }
        }
    }
    // `from_voxels` keeps each range with its voxel, whatever the order.
    let voxels = BrickMap::from_voxels(grid.dims, voxels).unwrap();
    Voxelization { grid, mode: Mode::Conservative, voxels, triangles, boundary_edges: None }
}

fn unit_voxel() -> GridSpec {
    GridSpec::new(DVec3::ZERO, 1.0, UVec3::ONE).unwrap()
}

fn one_voxel_colour(s: &Scene) -> Vec3 {
    let g = s.geometry();
    let v = by_hand(&g, unit_voxel(), |_| true);
    build(s, &g, &v).unwrap().values()[0].albedo()
}

/// A right triangle in the plane `z`, corner `(lo, lo)`, legs `leg`.
fn tri(z: f32, lo: f32, leg: f32) -> [Vec3; 3] {
    [Vec3::new(lo, lo, z), Vec3::new(lo + leg, lo, z), Vec3::new(lo, lo + leg, z)]
}

fn light() -> Light {
    sun(Vec3::Y, 1.0)
}

#[test]
fn colour_is_the_area_weighted_mean_inside_the_voxel() {
    // Red covers the voxel's whole cross-section (area 1 inside, much more outside); blue is
    // a small triangle of area 1/8 inside.
    let red = soup("red", &[tri(0.5, -1.0, 4.0)], 0);
    let blue = soup("blue", &[tri(0.3, 0.1, 0.5)], 1);
    let mats = vec![Material::diffuse("r", Vec3::X), Material::diffuse("b", Vec3::Z)];
    let s = scene(vec![red, blue], mats, light());
    let expected = BaselineVoxel::from_linear(Vec3::new(1.0, 0.0, 0.125) / 1.125);
    assert_eq!(BaselineVoxel::from_linear(one_voxel_colour(&s)), expected);
}

#[test]
fn alpha_weighs_and_masks() {
    let red = soup("red", &[tri(0.5, -1.0, 4.0)], 0);
    let green = soup("green", &[tri(0.2, -1.0, 4.0)], 1);
    for (mode, alpha, expected) in [
        (AlphaMode::Mask { cutoff: 0.5 }, 0.3, Vec3::X),
        (AlphaMode::Mask { cutoff: 0.5 }, 0.7, Vec3::new(0.5, 0.5, 0.0)),
        (AlphaMode::Blend, 0.25, Vec3::new(0.8, 0.2, 0.0)),
    ] {
        let g = Material {
            base_color: Vec4::new(0.0, 1.0, 0.0, alpha),
            alpha_mode: mode,
            ..Material::default()
        };
        let mats = vec![Material::diffuse("r", Vec3::X), g];
        let s = scene(vec![red.clone(), green.clone()], mats, light());
        let c = one_voxel_colour(&s);
        assert!((c - expected).abs().max_element() < 0.01, "{mode:?} {alpha}: {c}");
    }
}

#[test]
fn textures_are_sampled_where_the_triangle_is_in_the_voxel() {
    // One quad over two voxels along x, textured black (u < 0.5) and white (u > 0.5).
    let q = quad("q", Vec3::new(0.0, 0.0, 0.5), Vec3::X * 2.0, Vec3::Y, 0);
    let texture = Texture {
        name: "bw".into(),
        width: 2,
        height: 1,
        texels: Arc::from(vec![[0, 0, 0, 255], [255, 255, 255, 255]]),
        srgb: false,
        sampler: Sampler { wrap_u: WrapMode::ClampToEdge, wrap_v: WrapMode::ClampToEdge },
    };
    let m = Material {
        base_color_texture: Some(TextureRef { texture: 0 }),
        ..Material::diffuse("t", Vec3::ONE)
    };
    let mut s = scene(vec![q], vec![m], light());
    s.textures.push(texture);
    let g = s.geometry();
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::new(2, 1, 1)).unwrap();
    let map = build(&s, &g, &by_hand(&g, grid, |_| true)).unwrap();
    let dark = map.get(UVec3::ZERO).unwrap().albedo();
    let bright = map.get(UVec3::X).unwrap().albedo();
    // Bilinear from texel centres at u = 1/4 and 3/4: the mean over u ∈ [0, 1/2] is 1/8, over
    // [1/2, 1] it is 7/8.
    assert!((dark.x - 0.125).abs() < 0.02 && (bright.x - 0.875).abs() < 0.02, "{dark} {bright}");
}

#[test]
fn fallbacks_for_touching_masked_and_empty_voxels() {
    // Only touching the voxel along its edge x = 1, y = 1: the triangle's centroid colour.
    let edge = [Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(2.0, 2.0, 0.5)];
    let colour = Vec3::new(0.2, 0.4, 0.6);
    let s = scene(vec![soup("t", &[edge], 0)], vec![Material::diffuse("c", colour)], light());
    assert!((one_voxel_colour(&s) - colour).abs().max_element() < 0.01);
    // Everything masked out: area weights alone.
    let masked = Material {
        base_color: Vec4::new(0.0, 0.0, 1.0, 0.0),
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        ..Material::default()
    };
    let s = scene(vec![soup("m", &[tri(0.5, -1.0, 4.0)], 0)], vec![masked], light());
    assert!((one_voxel_colour(&s) - Vec3::Z).abs().max_element() < 0.01);
    // An empty list (lists kept, this voxel's is empty): the interior grey.
    let s = scene(vec![soup("far", &[tri(5.0, 5.0, 1.0)], 0)], vec![Material::default()], light());
    let g = s.geometry();
    let mut v = by_hand(&g, unit_voxel(), |_| true);
    assert_eq!(v.triangles_of(0).len(), 0);
    v.triangles.push(0);
    let c = build(&s, &g, &v).unwrap().values()[0].albedo();
    assert!((c - Vec3::splat(INTERIOR_ALBEDO)).abs().max_element() < 0.01, "{c}");
}

#[test]
fn bad_voxelizations_are_errors() {
    let s = scene(vec![soup("red", &[tri(0.5, -1.0, 4.0)], 0)], vec![Material::default()], light());
    let g = s.geometry();
    let good = by_hand(&g, unit_voxel(), |_| true);
    assert!(build(&s, &g, &good).is_ok());
    let no_lists = Voxelization { triangles: Vec::new(), ..good.clone() };
    assert!(build(&s, &g, &no_lists).unwrap_err().to_string().contains("triangle_lists"));
    let out_of_range = Voxelization { triangles: vec![7], ..good.clone() };
    assert!(build(&s, &g, &out_of_range).is_err());
    let other_grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(2)).unwrap();
    assert!(build(&s, &g, &Voxelization { grid: other_grid, ..good.clone() }).is_err());
    let no_materials = Scene { materials: Vec::new(), ..s.clone() };
    assert!(build(&no_materials, &g, &good).is_err());
}

/// The voxels of `dims` that `filled` selects, all of one albedo.
fn block(dims: UVec3, filled: impl Fn(UVec3) -> bool, albedo: Vec3) -> BrickMap<BaselineVoxel> {
    let mut v = Vec::new();
    for x in 0..dims.x {
        for y in 0..dims.y {
            for z in 0..dims.z {
                let c = UVec3::new(x, y, z);
                if filled(c) {
                    v.push((c, BaselineVoxel::from_linear(albedo)));
                }
            }
        }
    }
    BrickMap::from_voxels(dims, v).unwrap()
}

fn frame<'a>(
    grid: &'a GridSpec,
    voxels: &'a BrickMap<BaselineVoxel>,
    light: Light,
    options: &'a Options,
) -> Frame<'a> {
    Frame { grid, voxels, light, background: Vec3::ZERO, options }
}

/// A one-voxel-thick floor at y = 1 and a plate at y = 5 over x, z ∈ [8, 12).
fn floor_and_plate() -> (GridSpec, BrickMap<BaselineVoxel>) {
    let dims = UVec3::new(24, 8, 24);
    let grid = GridSpec::new(DVec3::ZERO, 1.0, dims).unwrap();
    let plate = |c: UVec3| c.y == 5 && (8..12).contains(&c.x) && (8..12).contains(&c.z);
    (grid, block(dims, |c| c.y == 1 || plate(c), Vec3::ONE))
}

#[test]
fn shadow_rays_skip_voxels_closer_than_one_and_a_half() {
    let (grid, voxels) = floor_and_plate();
    let options = Options::default();
    let blocked = |to_light: Vec3, c: UVec3| {
        frame(&grid, &voxels, sun(to_light, 1.0), &options).shadow_blocked(c.as_ivec3(), &voxels)
    };
    // Straight up: under the plate is shadowed, elsewhere lit.
    assert!(blocked(Vec3::Y, UVec3::new(9, 1, 9)));
    assert!(!blocked(Vec3::Y, UVec3::new(3, 1, 9)));
    // A light at slope 0.6 over the floor: the path meets the face neighbour (skipped) and
    // leaves the floor layer before the next voxel.
    assert!(!blocked(Vec3::new(1.0, 0.6, 0.0), UVec3::new(2, 1, 2)));
    // At slope 0.3 it still runs inside the floor two voxels away: the known self-shadowing
    // of opaque-cube voxels at grazing light, which the skip only pushes back.
    assert!(blocked(Vec3::new(1.0, 0.3, 0.0), UVec3::new(2, 1, 2)));
    // Edge neighbours are skipped too, corner neighbours are not.
    let dims = grid.dims;
    for (other, expected) in [(UVec3::new(4, 4, 3), false), (UVec3::new(4, 4, 4), true)] {
        let pair = block(dims, |c| c == UVec3::new(3, 3, 3) || c == other, Vec3::ONE);
        let f = frame(&grid, &pair, sun(Vec3::new(1.0, 1.0, 0.9), 1.0), &options);
        assert_eq!(f.shadow_blocked(IVec3::splat(3), &pair), expected, "{other}");
    }
}

#[test]
fn renders_lit_shadowed_and_background_pixels() {
    let (grid, voxels) = floor_and_plate();
    // Light straight up at irradiance π: lit floor radiance 1, shadowed = ambient.
    let cam = camera(Vec3::new(-20.0, 30.0, 10.0), Vec3::new(10.0, 2.0, 10.0));
    let ambient = Vec3::splat(0.1);
    let options = Options { width: 64, height: 64, ambient, shadows: true };
    let blue = Vec3::new(0.0, 0.0, 1.0);
    let img = render(&grid, &voxels, &cam, &sun(Vec3::Y, PI), blue, &options).unwrap();
    let at = |p: Vec3| {
        let (q, _) = cam.frame(64, 64).project(p).unwrap();
        img.get(q.x as u32, q.y as u32)
    };
    let lit = at(Vec3::new(3.5, 2.0, 4.5));
    assert!((lit - Vec4::new(1.1, 1.1, 1.1, 1.0)).abs().max_element() < 1e-3, "{lit}");
    let shadowed = at(Vec3::new(9.5, 2.0, 10.0));
    assert!((shadowed - Vec4::new(0.1, 0.1, 0.1, 1.0)).abs().max_element() < 1e-3, "{shadowed}");
    assert_eq!(img.get(0, 0), Vec4::new(0.0, 0.0, 1.0, 0.0), "background, no coverage");
    // Deterministic on 1 and 2 threads, shadow-cache races included.
    let slanted = sun(Vec3::new(0.3, 1.0, 0.2), PI);
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render(&grid, &voxels, &cam, &slanted, Vec3::ZERO, &options).unwrap())
    };
    assert_eq!(on(1), on(2));
}

#[test]
fn matches_the_ground_truth_inside_the_faces_of_a_voxel_aligned_box() {
    // The box [0.25, 0.75]³ is exactly voxels 4..12 of a 16³ grid over [0, 1]³.
    let albedo = Vec3::new(0.8, 0.5, 0.3);
    let s = scene(
        vec![cuboid("box", Vec3::splat(0.25), Vec3::splat(0.75), 0)],
        vec![Material::diffuse("box", albedo)],
        sun(Vec3::new(0.5, 0.8, 0.35), 3.0),
    );
    let g = s.geometry();
    let grid = GridSpec::new(DVec3::ZERO, 1.0 / 16.0, UVec3::splat(16)).unwrap();
    let inside = |c: UVec3| c.cmpge(UVec3::splat(4)).all() && c.cmplt(UVec3::splat(12)).all();
    let voxels = build(&s, &g, &by_hand(&g, grid, inside)).unwrap();
    let cam = camera(Vec3::new(1.6, 1.3, 2.0), Vec3::splat(0.5));
    let size = 64;
    let options = Options { width: size, height: size, ..Options::default() };
    let base = render(&grid, &voxels, &cam, &s.light(), s.background, &options).unwrap();
    let bvh = Bvh::new(&g).unwrap();
    let gt_options =
        ground_truth::Options { width: size, height: size, spp: 16, ..Default::default() };
    let gt = ground_truth::render(&s, &g, &bvh, &cam, &gt_options).unwrap();
    // Interior pixels: the centre hits of the pixel and its 8 neighbours lie on one face.
    let face = |x: u32, y: u32| gt.gbuffer.get(x, y).triangle / 2;
    let mut compared = 0;
    for y in 1..size - 1 {
        for x in 1..size - 1 {
            let f = face(x, y);
            let interior = f != u32::MAX / 2
                && (y - 1..=y + 1).all(|j| (x - 1..=x + 1).all(|i| face(i, j) == f));
            if !interior {
                continue;
            }
            let (a, b) = (gt.image.get(x, y), base.get(x, y));
            assert_eq!((a.w, b.w), (1.0, 1.0), "pixel ({x}, {y})");
            let err = (a - b).abs().max_element() / a.max_element();
            assert!(err < 0.01, "pixel ({x}, {y}): ground truth {a}, baseline {b}");
            compared += 1;
        }
    }
    assert!(compared > 400, "{compared} interior pixels");
}

#[test]
fn bad_parameters_are_errors() {
    let dims = UVec3::splat(8);
    let grid = GridSpec::new(DVec3::ZERO, 1.0, dims).unwrap();
    let voxels = block(dims, |c| c.y == 0, Vec3::ONE);
    let cam = camera(Vec3::splat(20.0), Vec3::splat(4.0));
    let l = light();
    let ok = Options { width: 4, height: 4, ..Options::default() };
    assert!(render(&grid, &voxels, &cam, &l, Vec3::ZERO, &ok).is_ok());
    for bad in [Options { width: 0, ..ok }, Options { ambient: Vec3::NAN, ..ok }] {
        assert!(render(&grid, &voxels, &cam, &l, Vec3::ZERO, &bad).is_err());
    }
    assert!(render(&grid, &voxels, &cam, &l, Vec3::INFINITY, &ok).is_err());
    let other = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(9)).unwrap();
    assert!(render(&other, &voxels, &cam, &l, Vec3::ZERO, &ok).is_err());
    let bad_grid = GridSpec { voxel_size: -1.0, ..grid };
    assert!(render(&bad_grid, &voxels, &cam, &l, Vec3::ZERO, &ok).is_err());
    let degenerate = Camera::look_at(Vec3::ONE, Vec3::ONE, Vec3::Y, 40.0);
    assert!(render(&grid, &voxels, &degenerate, &l, Vec3::ZERO, &ok).is_err());
    let dark = Light::Directional { to_light: Vec3::ZERO, irradiance: Vec3::ONE };
    assert!(render(&grid, &voxels, &cam, &dark, Vec3::ZERO, &ok).is_err());
}
