//! Tests of the `primary` module.

use std::sync::Mutex;

use glam::{DVec3, UVec3};
use voxlod_format::GridSpec;
use voxlod_octree::BuildOptions;

use super::*;

/// A 64³ grid (1-unit voxels) with an opaque white slab `z ∈ [40, 48)` facing −z.
fn wall() -> Octree<AveragePayload> {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(64)).unwrap();
    let mut v = Vec::new();
    for z in 40..48 {
        for y in 0..64 {
            for x in 0..64 {
                let p = AveragePayload::new(Vec3::ONE, Vec3::NEG_Z, 1.0);
                v.push((UVec3::new(x, y, z), p));
            }
        }
    }
    Octree::build(grid, v, &BuildOptions { depth: None, dense_log2: 3 }).unwrap()
}

fn camera(eye_z: f32, fov: f32, side: u32) -> PinholeCamera {
    PinholeCamera {
        eye: Vec3::new(32.0, 32.0, eye_z),
        target: Vec3::new(32.0, 32.0, eye_z + 1.0),
        up: Vec3::Y,
        fov_y_deg: fov,
        width: side,
        height: side,
    }
}

const LIGHT: Light = Light::Directional { to_light: Vec3::NEG_Z, irradiance: Vec3::ONE };

fn lambert(s: &ShadeInput) -> Vec3 {
    s.albedo * s.normal.dot(Vec3::NEG_Z).max(0.0) * s.visibility
}

fn with_bias(b: f32) -> PrimaryOptions {
    PrimaryOptions { lod_bias: b, background: Vec3::new(0.1, 0.2, 0.3), ..Default::default() }
}

#[test]
fn footprint_grows_linearly_with_distance() {
    let tree = wall();
    let r = PrimaryRenderer::new(&tree, camera(0.0, 60.0, 100), LIGHT, with_bias(1.0)).unwrap();
    let per_voxel = 2.0 * 30f32.to_radians().tan() / 100.0;
    for t in [1.0f32, 10.0, 100.0, 1000.0] {
        assert!((r.footprint_voxels(t) - t * per_voxel).abs() <= 1e-6 * t, "{t}");
        assert!((r.footprint_voxels(3.0 * t) - 3.0 * r.footprint_voxels(t)).abs() < 1e-5 * t);
    }
    let r2 = PrimaryRenderer::new(&tree, camera(0.0, 60.0, 100), LIGHT, with_bias(2.0)).unwrap();
    assert!((r2.footprint_voxels(50.0) - 2.0 * r.footprint_voxels(50.0)).abs() < 1e-5);
    // The cone's aperture gives the same diameter: d(t) = 2·t·tan(θ/2).
    assert!((2.0 * 50.0 * (0.5 * r.aperture()).tan() - r.footprint_voxels(50.0)).abs() < 1e-4);
}

#[test]
fn diameters_below_one_voxel_give_the_finest_march_exactly() {
    let tree = wall();
    // Eye 20 voxels in front of the cube: every distance in the cube is below 150 voxels,
    // and 150 · 1e-3 · 2·tan(30°)/16 ≈ 0.01 voxel.
    let cam = camera(-20.0, 60.0, 16);
    let fine = PrimaryRenderer::new(&tree, cam, LIGHT, with_bias(0.0)).unwrap().render(&lambert);
    let tiny = PrimaryRenderer::new(&tree, cam, LIGHT, with_bias(1e-3)).unwrap().render(&lambert);
    assert_eq!(fine, tiny);
    assert!(fine.pixels.iter().any(|p| p.w > 0.9 && p.x > 0.5), "the wall is lit and seen");
    // From far away the pixel footprint spans many voxels: fewer samples than level 0.
    let far = camera(-1500.0, 3.0, 16);
    let fine = PrimaryRenderer::new(&tree, far, LIGHT, with_bias(0.0)).unwrap().render(&lambert);
    let lod = PrimaryRenderer::new(&tree, far, LIGHT, with_bias(1.0)).unwrap().render(&lambert);
    assert!(lod.samples * 2 < fine.samples, "{} vs {}", lod.samples, fine.samples);
    assert_ne!(fine.pixels, lod.pixels);
}

#[test]
fn an_empty_octree_gives_the_background() {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(16)).unwrap();
    let tree: Octree<AveragePayload> =
        Octree::build(grid, Vec::new(), &BuildOptions::default()).unwrap();
    let o = with_bias(1.0);
    let img =
        PrimaryRenderer::new(&tree, camera(-5.0, 60.0, 8), LIGHT, o).unwrap().render(&lambert);
    assert_eq!(img.pixels.len(), 64);
    assert!(img.pixels.iter().all(|&p| p == o.background.extend(0.0)), "{:?}", img.pixels[0]);
}

#[test]
fn extreme_apertures_and_a_camera_inside_geometry_stay_finite() {
    let tree = wall();
    let cases = [
        (camera(-10.0, 1e-3, 8), 1.0),
        (camera(-10.0, 179.9, 8), 1.0),
        (camera(44.0, 60.0, 8), 1.0), // inside the slab
        (camera(44.0, 179.9, 8), 1e3),
        (camera(-1e6, 1e-3, 4), 1.0),
    ];
    for (cam, b) in cases {
        let r = PrimaryRenderer::new(&tree, cam, LIGHT, with_bias(b)).unwrap();
        let img = r.render(&lambert);
        for p in &img.pixels {
            assert!(p.is_finite() && (0.0..=1.0).contains(&p.w), "{cam:?} bias {b}: {p}");
        }
    }
    // Inside the slab the first sample is already opaque.
    let r = PrimaryRenderer::new(&tree, camera(44.0, 60.0, 8), LIGHT, with_bias(1.0)).unwrap();
    assert!(r.pixel(4, 4, &lambert).rgba.w > 0.99);
}

#[test]
fn the_level_sampled_where_the_footprint_spans_2_to_the_k_voxels_is_k() {
    let tree = wall();
    for k in 0..4u32 {
        let probe =
            PrimaryRenderer::new(&tree, camera(0.0, 20.0, 63), LIGHT, with_bias(1.0)).unwrap();
        let d = probe.distance_for_footprint((1u32 << k) as f32).unwrap();
        // The wall's face (z = 40) at distance d from the eye, on the centre pixel's ray.
        let r =
            PrimaryRenderer::new(&tree, camera(40.0 - d, 20.0, 63), LIGHT, with_bias(1.0)).unwrap();
        let seen = Mutex::new(Vec::new());
        let px = r.pixel(31, 31, &|s: &ShadeInput| {
            seen.lock().unwrap().push((s.distance_voxels, s.level, s.diameter));
            lambert(s)
        });
        // A slab one node thick at level 3 composites to ≈ 0.81 (trilinear hat × step
        // correction), not 0.99: coarse levels see surfaces as partly transparent.
        assert!(px.rgba.w > 0.75, "k = {k}: {px:?}");
        let seen = seen.into_inner().unwrap();
        let &(t, level, diameter) = seen.first().expect("a contributing sample");
        // The first contributing sample lies within the trilinear support of the face.
        assert!((t - d).abs() <= 2.0 * (1u32 << k) as f32, "k = {k}: t = {t}, d = {d}");
        assert!((level - k as f32).abs() < 0.02, "k = {k}: level {level}");
        for &(t, level, diameter) in &seen {
            assert!((diameter - r.footprint_voxels(t).max(1.0)).abs() < 1e-3 * diameter);
            assert!((level - diameter.log2()).abs() < 1e-5);
        }
        assert!(diameter >= 1.0);
    }
}

#[test]
fn shadows_darken_what_an_occluder_hides_from_the_light() {
    // Light from −z, a wall at z = 40 and a 16×16 plate at z = 17..21 between the light and
    // the wall; the eye sits between plate and wall, looking at the wall's shadowed part.
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(64)).unwrap();
    let mut v = Vec::new();
    for y in 0..64 {
        for x in 0..64 {
            v.push((UVec3::new(x, y, 40), AveragePayload::new(Vec3::ONE, Vec3::NEG_Z, 1.0)));
        }
    }
    // 4 voxels thick: a 1-voxel plate lets about half the light through a cone that reads
    // it between levels 0 and 1 (the known thin-wall leak, crate README).
    for z in 17..21 {
        for y in 24..40 {
            for x in 24..40 {
                let p = AveragePayload::new(Vec3::ONE, Vec3::NEG_Z, 1.0);
                v.push((UVec3::new(x, y, z), p));
            }
        }
    }
    let tree = Octree::build(grid, v, &BuildOptions::default()).unwrap();
    let cam = PinholeCamera {
        eye: Vec3::new(32.0, 32.0, 30.0),
        target: Vec3::new(32.0, 32.0, 40.0),
        up: Vec3::Y,
        fov_y_deg: 10.0,
        width: 4,
        height: 4,
    };
    let lit = |shadows| {
        let o = PrimaryOptions { shadows, ..with_bias(1.0) };
        PrimaryRenderer::new(&tree, cam, LIGHT, o).unwrap().pixel(2, 2, &lambert)
    };
    let (on, off) = (lit(true), lit(false));
    assert!(off.rgba.x > 0.9 && on.rgba.x < 0.1, "{on:?} {off:?}");
    assert!(on.shadow_samples > 0 && off.shadow_samples == 0);
}

#[test]
fn directional_opacities_keep_a_thin_wall_opaque_at_coarse_levels() {
    // A 1-voxel wall at z = 40 seen face-on where the footprint spans 8 voxels (level 3):
    // its level-3 coverage is 1/8, its opacity of crossing along z is 1.
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(64)).unwrap();
    let leaf = AveragePayload::new(Vec3::ONE, Vec3::NEG_Z, 1.0);
    let voxels: Vec<_> =
        (0..64).flat_map(|y| (0..64).map(move |x| (UVec3::new(x, y, 40), leaf))).collect();
    let o = BuildOptions { depth: None, dense_log2: 3 };
    let iso = Octree::build(grid, voxels.clone(), &o).unwrap();
    let dir: Octree<Directional<AveragePayload>> =
        Octree::build(grid, voxels.into_iter().map(|(c, p)| (c, Directional::isotropic(p))), &o)
            .unwrap();
    let probe = PrimaryRenderer::new(&iso, camera(0.0, 20.0, 63), LIGHT, with_bias(1.0)).unwrap();
    let d = probe.distance_for_footprint(8.0).unwrap();
    let cam = camera(40.0 - d, 20.0, 63);
    let a = PrimaryRenderer::new(&iso, cam, LIGHT, with_bias(1.0)).unwrap();
    let b = PrimaryRenderer::new(&dir, cam, LIGHT, with_bias(1.0)).unwrap();
    let (a, b) = (a.pixel(31, 31, &lambert).rgba.w, b.pixel(31, 31, &lambert).rgba.w);
    assert!(a < 0.4 && b > 0.7, "isotropic {a}, directional {b}");
    // At level 0 both see the same opaque wall.
    let a0 = PrimaryRenderer::new(&iso, cam, LIGHT, with_bias(0.0)).unwrap();
    assert!(a0.pixel(31, 31, &lambert).rgba.w > 0.99);
}

#[test]
fn bad_options_are_named_errors() {
    let tree = wall();
    let cam = camera(0.0, 60.0, 8);
    let err = |cam: PinholeCamera, o: PrimaryOptions| {
        PrimaryRenderer::new(&tree, cam, LIGHT, o).unwrap_err().to_string()
    };
    assert!(err(cam, with_bias(-1.0)).contains("lod_bias"));
    assert!(err(cam, with_bias(f32::NAN)).contains("lod_bias"));
    assert!(err(cam, with_bias(f32::MAX)).contains("lod_bias"));
    let o = with_bias(1.0);
    assert!(err(cam, PrimaryOptions { step_factor: 0.0, ..o }).contains("step_factor"));
    assert!(err(cam, PrimaryOptions { max_distance: 0.0, ..o }).contains("max_distance"));
    assert!(err(cam, PrimaryOptions { opacity_cutoff: 0.0, ..o }).contains("opacity_cutoff"));
    let g = Vec3::splat(f32::INFINITY);
    assert!(err(cam, PrimaryOptions { background: g, ..o }).contains("background"));
    assert!(err(PinholeCamera { fov_y_deg: 180.0, ..cam }, o).contains("fov_y_deg"));
    assert!(err(PinholeCamera { width: 0, ..cam }, o).contains("width"));
    assert!(err(PinholeCamera { up: Vec3::Z, ..cam }, o).contains("camera up"));
    assert!(err(PinholeCamera { target: cam.eye, ..cam }, o).contains("camera target"));
}
