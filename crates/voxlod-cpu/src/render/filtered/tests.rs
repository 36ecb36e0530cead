//! Tests of the filtered renderer on a test-only [`Appearance`] (records given per voxel):
//! opaque grids, termination, \[VJK21\] γ = 1 against exponential compositing, cache against
//! no cache, the shadow ray's 19 ignored voxels, determinism and bad input.

use std::f32::consts::PI;

use glam::{DVec3, IVec3, UVec3, Vec2, Vec3, Vec4};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_scene::{LightSample, MaterialSample};

use super::*;
use crate::random::rand_f32;
use crate::render::test_scenes::{camera, sun};
use crate::shading::shade;

/// One voxel of the test appearance.
#[derive(Clone, Copy, Debug)]
struct Voxel {
    albedo: Vec3,
    opacity: Opacity,
}

/// Uniform records per voxel, shaded by [`shade`] with normal +y. With `directional`, an
/// [`Opacity::Alpha`] is scaled by `0.25 + 0.75·|dir.x|`, so the direction it is evaluated
/// for shows.
struct TestApp {
    grid: GridSpec,
    voxels: BrickMap<Voxel>,
    directional: bool,
}

impl Appearance for TestApp {
    fn grid(&self) -> &GridSpec {
        &self.grid
    }
    fn len(&self) -> usize {
        self.voxels.len()
    }
    fn index_of(&self, c: UVec3) -> Option<usize> {
        self.voxels.index_of(c)
    }
    fn opacity(&self, index: usize, dir: Vec3) -> Opacity {
        match self.voxels.values()[index].opacity {
            Opacity::Alpha(a) if self.directional => {
                Opacity::Alpha(a * (0.25 + 0.75 * dir.x.abs()))
            }
            o => o,
        }
    }
    fn radiance(
        &self,
        index: usize,
        to_viewer: Vec3,
        light: &LightSample,
        vis: f32,
        ambient: Vec3,
    ) -> Vec3 {
        let m = MaterialSample {
            albedo: self.voxels.values()[index].albedo,
            alpha: 1.0,
            specular: Vec3::ZERO,
            shininess: 0.0,
        };
        shade(&m, Vec3::Y, to_viewer, light, vis, ambient)
    }
}

/// A unit-voxel grid of `dims` at the origin with the voxels `f` gives.
fn app(dims: UVec3, f: impl Fn(UVec3) -> Option<Voxel>) -> TestApp {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, dims).unwrap();
    let mut v = Vec::new();
    for x in 0..dims.x {
        for y in 0..dims.y {
            for z in 0..dims.z {
                let c = UVec3::new(x, y, z);
                v.extend(f(c).map(|voxel| (c, voxel)));
            }
        }
    }
    TestApp { grid, voxels: BrickMap::from_voxels(dims, v).unwrap(), directional: false }
}

fn alpha(albedo: Vec3, a: f32) -> Option<Voxel> {
    Some(Voxel { albedo, opacity: Opacity::Alpha(a) })
}

/// A colour that differs per voxel.
fn colour_of(c: UVec3) -> Vec3 {
    Vec3::new(
        0.2 + 0.1 * (c.x % 7) as f32,
        0.3 + 0.05 * (c.y % 9) as f32,
        0.1 + 0.08 * (c.z % 5) as f32,
    )
}

/// A frame over `cache` with or without its slots, and with shadow-ray bounds and step
/// pattern if given.
fn frame_of<'c>(
    cache: &'c FrameCache<'_, TestApp>,
    light: Light,
    options: &'c Options,
    cached: bool,
    (bounds, pattern): (Option<&'c LightBounds>, Option<&'c ShadowPattern>),
) -> Frame<'c, TestApp> {
    let shadows = ShadowRays { bounds, pattern };
    frame(cache, light, Vec3::ZERO, options, cached.then_some(&cache.slots), shadows)
}

/// No shadow-ray bounds and no step pattern: every shadow ray walks the DDA unbounded.
const PLAIN: (Option<&LightBounds>, Option<&ShadowPattern>) = (None, None);

/// A random unit direction and an origin outside the `dims` box aiming through it.
fn random_ray(i: u32, dims: Vec3) -> (Vec3, Vec3) {
    let r = |d| rand_f32(i, 0, d);
    let z = 2.0 * r(0) - 1.0;
    let phi = 2.0 * PI * r(1);
    let s = (1.0 - z * z).sqrt();
    let dir = Vec3::new(s * phi.cos(), s * phi.sin(), z);
    let target = Vec3::new(r(2), r(3), r(4)) * dims;
    (target - dir * 3.0 * dims.max_element(), dir)
}

const UP_PI: fn() -> Light = || sun(Vec3::Y, PI);

#[test]
fn solid_voxels_are_opaque_after_the_first_voxel() {
    let dims = UVec3::new(12, 10, 9);
    let a = app(dims, |c| {
        let inside = c.cmpge(UVec3::splat(2)).all() && c.cmplt(dims - 2).all();
        (inside && (c.x + c.y) % 3 != 0).then(|| alpha(colour_of(c), 1.0)).flatten()
    });
    let cache = FrameCache::new(&a).unwrap();
    let options = Options { shadows: false, ..Options::default() };
    // Uncached: the rays start at different eyes, which one frame (one cache key) never does.
    let f = frame_of(&cache, UP_PI(), &options, false, PLAIN);
    let lookup = cache.lookup.dense.as_ref().unwrap();
    let mut hits = 0;
    for i in 0..400 {
        let (eye, dir) = random_ray(i, dims.as_vec3());
        let r = f.trace(eye, dir, f32::INFINITY, lookup);
        // The first voxel with a record, by the plain (no brick skipping) walk.
        let first =
            Dda::new(&a.grid, eye, dir, 0.0, f32::INFINITY).find(|v| a.index_of(v.voxel).is_some());
        match first {
            None => {
                assert_eq!(r, RayResult { radiance: Vec3::ZERO, transmittance: 1.0, voxels: 0 })
            }
            Some(v) => {
                hits += 1;
                assert_eq!((r.voxels, r.transmittance), (1, 0.0), "ray {i}");
                // Light straight up at π, normal +y: radiance = albedo.
                assert!((r.radiance - colour_of(v.voxel)).abs().max_element() < 1e-6, "ray {i}");
            }
        }
    }
    assert!(hits > 100, "{hits} rays hit");
    let cam = camera(Vec3::new(6.0, 5.0, 30.0), Vec3::new(6.0, 5.0, 4.5));
    let img = render(
        &mut FrameCache::new(&a).unwrap(),
        &cam,
        &UP_PI(),
        Vec3::X,
        &Options { width: 32, height: 32, ..options },
    )
    .unwrap();
    assert_eq!(img.get(16, 16).w, 1.0);
    assert_eq!(img.get(0, 0), Vec4::new(1.0, 0.0, 0.0, 0.0), "background, no coverage");
}

#[test]
fn the_walk_stops_below_a_transmittance_of_one_thousandth() {
    // α = 1/2: T = 2⁻⁹ ≈ 0.00195 after 9 voxels, 2⁻¹⁰ ≈ 0.000977 < 0.001 after 10.
    let white = Vec3::ONE;
    for (row, expected) in [(20, 10), (10, 10), (9, 9)] {
        let a = app(UVec3::new(24, 1, 1), |c| (c.x < row).then(|| alpha(white, 0.5)).flatten());
        let cache = FrameCache::new(&a).unwrap();
        let options = Options { shadows: false, ..Options::default() };
        for cached in [true, false] {
            let f = frame_of(&cache, UP_PI(), &options, cached, PLAIN);
            let r = f.trace(
                Vec3::new(-5.0, 0.5, 0.5),
                Vec3::X,
                f32::INFINITY,
                cache.lookup.dense.as_ref().unwrap(),
            );
            assert_eq!(r.voxels, expected, "row of {row}");
            assert_eq!(r.transmittance, 0.5f32.powi(expected as i32));
            let c = 1.0 - r.transmittance;
            assert!((r.radiance - Vec3::splat(c)).abs().max_element() < 1e-6, "{}", r.radiance);
        }
    }
}

/// The oracle: a plain DDA walk (no brick skipping, no cache) with exponential
/// transmittance `e^(−σℓ)` for γ = 1 voxels and `1 − α` for alpha voxels, each voxel's
/// values for the direction from its centre to the eye.
fn oracle(a: &TestApp, eye: Vec3, dir: Vec3, light: &Light) -> (Vec3, f32, u32) {
    let (mut c, mut t, mut n) = (Vec3::ZERO, 1.0f32, 0);
    for v in Dda::new(&a.grid, eye, dir, 0.0, f32::INFINITY) {
        let Some(i) = a.index_of(v.voxel) else { continue };
        let centre = a.grid.voxel_center(v.voxel).as_vec3();
        let to_eye = (eye - centre).normalize();
        let radiance = a.radiance(i, to_eye, &light.sample(centre), 1.0, Vec3::ZERO);
        let next = match a.opacity(i, to_eye) {
            Opacity::Alpha(al) => t * (1.0 - al),
            Opacity::NonExponential { sigma, gamma } => {
                assert_eq!(gamma, 1.0);
                t * (-sigma * (v.t_exit - v.t_enter)).exp()
            }
        };
        c += (t - next) * radiance;
        t = next;
        n += 1;
        if t < MIN_TRANSMITTANCE {
            break;
        }
    }
    (c, t, n)
}

#[test]
fn vjk21_voxels_with_gamma_one_composite_exponentially() {
    // A 20³ sparse cloud mixing γ = 1 voxels (σ up to 3) and directional alpha voxels.
    let dims = UVec3::splat(20);
    let mut a = app(dims, |c| {
        let id = c.x + 20 * (c.y + 20 * c.z);
        let r = |d| rand_f32(id, 1, d);
        if r(0) > 0.3 {
            return None;
        }
        let opacity = if r(1) < 0.6 {
            Opacity::NonExponential { sigma: 3.0 * r(2), gamma: 1.0 }
        } else {
            Opacity::Alpha(r(2))
        };
        Some(Voxel { albedo: colour_of(c), opacity })
    });
    a.directional = true;
    let cache = FrameCache::new(&a).unwrap();
    let options = Options { shadows: false, ..Options::default() };
    let light = sun(Vec3::new(0.2, 1.0, 0.3), 2.0);
    let lookup = cache.lookup.dense.as_ref().unwrap();
    let mut deep = 0;
    for cached in [false, true] {
        let f = frame_of(&cache, light, &options, cached, PLAIN);
        // One eye per frame (the cache's key); rays toward random points of the grid.
        let eye = Vec3::new(-13.0, 31.0, 27.0);
        for i in 0..300 {
            let target = Vec3::new(rand_f32(i, 2, 0), rand_f32(i, 2, 1), rand_f32(i, 2, 2));
            let dir = (target * dims.as_vec3() - eye).normalize();
            let r = f.trace(eye, dir, f32::INFINITY, lookup);
            let (c, t, _) = oracle(&a, eye, dir, &light);
            assert!((r.transmittance - t).abs() < 1e-5, "ray {i}: T {} vs {t}", r.transmittance);
            assert!((r.radiance - c).abs().max_element() < 1e-5, "ray {i}: {} vs {c}", r.radiance);
            deep += (r.voxels > 3) as u32;
        }
    }
    assert!(deep > 100, "{deep} rays composited more than 3 voxels");
    // Along an axis through voxel centres every chord is 1: σ matches α = 1 − e^(−σ).
    let sigmas = [0.3f32, 1.1, 0.05, 2.0, 0.7];
    let column = |vjk: bool| {
        app(UVec3::new(1, 1, 5), |c| {
            let s = sigmas[c.z as usize];
            let opacity = if vjk {
                Opacity::NonExponential { sigma: s, gamma: 1.0 }
            } else {
                Opacity::Alpha(1.0 - (-s).exp())
            };
            Some(Voxel { albedo: colour_of(c), opacity })
        })
    };
    let (vjk, alphas) = (column(true), column(false));
    let trace = |a: &TestApp| {
        let cache = FrameCache::new(a).unwrap();
        let f = frame_of(&cache, light, &options, true, PLAIN);
        f.trace(
            Vec3::new(0.5, 0.5, -3.0),
            Vec3::Z,
            f32::INFINITY,
            cache.lookup.dense.as_ref().unwrap(),
        )
    };
    let (x, y) = (trace(&vjk), trace(&alphas));
    assert!((x.transmittance - y.transmittance).abs() < 1e-6);
    assert!((x.transmittance - (-sigmas.iter().sum::<f32>()).exp()).abs() < 1e-6);
    assert!(
        (x.radiance - y.radiance).abs().max_element() < 1e-6,
        "{} vs {}",
        x.radiance,
        y.radiance
    );
}

#[test]
fn brick_skipping_walks_skip_no_voxel() {
    // Small clusters far apart in a 240 × 64 × 200 grid: most bricks are empty and skipped;
    // the result must be that of the plain walk.
    let dims = UVec3::new(240, 64, 200);
    let centres: Vec<UVec3> = (0..7u32)
        .map(|i| {
            let r = |k| rand_f32(i, 3, k);
            (Vec3::new(r(0), r(1), r(2)) * (dims - 6).as_vec3()).as_uvec3() + 3
        })
        .collect();
    let a = app(dims, |c| {
        let near = centres.iter().any(|m| (c.as_ivec3() - m.as_ivec3()).abs().max_element() <= 2);
        let id = c.x + 240 * (c.y + 64 * c.z);
        (near && rand_f32(id, 4, 0) < 0.7).then(|| alpha(colour_of(c), 0.3)).flatten()
    });
    let cache = FrameCache::new(&a).unwrap();
    let lookup = cache.lookup.dense.as_ref().unwrap();
    let options = Options { shadows: false, ..Options::default() };
    let light = UP_PI();
    let f = frame_of(&cache, light, &options, true, PLAIN);
    let eye = Vec3::new(-90.0, 150.0, 260.0);
    let mut hits = 0;
    for i in 0..700 {
        let m = centres[i as usize % centres.len()].as_vec3() + 0.5;
        let jitter = Vec3::new(rand_f32(i, 5, 0), rand_f32(i, 5, 1), rand_f32(i, 5, 2)) * 6.0;
        let dir = (m - 3.0 + jitter - eye).normalize();
        let r = f.trace(eye, dir, f32::INFINITY, lookup);
        let (c, t, n) = oracle(&a, eye, dir, &light);
        assert_eq!(r.voxels, n, "ray {i}");
        assert!((r.transmittance - t).abs() < 1e-6, "ray {i}: T {} vs {t}", r.transmittance);
        assert!((r.radiance - c).abs().max_element() < 1e-5, "ray {i}: {} vs {c}", r.radiance);
        hits += (n > 0) as u32;
    }
    assert!(hits > 300, "{hits} rays met voxels");
    // Shadow rays, with and without their light-space bounds: a voxel's visibility is the
    // product over its light path.
    let (mut shadowed, mut lit) = (0, 0);
    for to_light in [Vec3::new(0.3, 0.2, -0.4), Vec3::new(-0.1, 0.05, 1.0), Vec3::Y] {
        let light = sun(to_light, 1.0);
        let bounds = light_bounds(&light, &cache.lookup.map, cache.grid()).unwrap();
        let pattern = shadow_pattern(&light, cache.grid()).unwrap();
        let to_light = to_light.normalize();
        let d = to_light / a.grid.voxel_size as f32;
        for (i, c) in cache.lookup.map.coords().enumerate().step_by(3) {
            let centre = c.as_vec3() + 0.5;
            let mut expected = 1.0f32;
            for v in Dda::in_grid_space(a.grid.dims, centre, d, 0.0, f32::INFINITY) {
                let near = (v.voxel.as_ivec3() - c.as_ivec3()).length_squared() <= 2;
                if !near && a.index_of(v.voxel).is_some() && expected >= MIN_TRANSMITTANCE {
                    expected *= 0.7;
                }
            }
            for b in [
                (None, None),
                (Some(&bounds), None),
                (None, Some(&pattern)),
                (Some(&bounds), Some(&pattern)),
            ] {
                let g = frame_of(&cache, light, &options, false, b);
                assert_eq!(g.shadow(c, lookup), expected, "voxel {i} at {c}, {to_light}");
            }
            if expected < 1.0 { shadowed += 1 } else { lit += 1 }
        }
    }
    assert!(shadowed > 100 && lit > 100, "{shadowed} shadowed, {lit} lit");
}

/// A floor at y = 1 (α = 0.7), a plate at y = 5 (\[VJK21\], σ = 2, γ = 0.3) and a solid post.
fn floor_plate_post() -> TestApp {
    let mut a = app(UVec3::new(20, 9, 20), |c| {
        let plate = c.y == 5 && (6..12).contains(&c.x) && (6..12).contains(&c.z);
        let post = (14..16).contains(&c.x) && (14..16).contains(&c.z) && c.y >= 1;
        if c.y == 1 {
            alpha(colour_of(c), 0.7)
        } else if plate {
            Some(Voxel {
                albedo: colour_of(c),
                opacity: Opacity::NonExponential { sigma: 2.0, gamma: 0.3 },
            })
        } else if post {
            alpha(colour_of(c), 0.95)
        } else {
            None
        }
    });
    a.directional = true;
    a
}

#[test]
fn cached_frames_equal_uncached_ones_and_keep_what_they_may() {
    let a = floor_plate_post();
    let mut cache = FrameCache::new(&a).unwrap();
    let options =
        Options { width: 40, height: 32, ambient: Vec3::splat(0.05), ..Options::default() };
    let cam1 = camera(Vec3::new(-12.0, 20.0, 30.0), Vec3::new(10.0, 2.0, 10.0));
    let turned = camera(cam1.eye, Vec3::new(8.0, 3.0, 12.0));
    let cam2 = camera(Vec3::new(30.0, 14.0, -6.0), Vec3::new(10.0, 2.0, 10.0));
    let l1 = sun(Vec3::new(0.3, 1.0, 0.2), PI);
    let l2 = Light::Point { position: Vec3::new(4.0, 12.0, 16.0), intensity: Vec3::splat(400.0) };
    let bg = Vec3::new(0.1, 0.2, 0.3);
    let check = |cache: &mut FrameCache<'_, TestApp>, cam: &Camera, light: &Light| {
        let cached = render(cache, cam, light, bg, &options).unwrap();
        let reference = render_uncached(cache, cam, light, bg, &options).unwrap();
        assert_eq!(cached, reference);
        cached
    };
    let cold = check(&mut cache, &cam1, &l1);
    let (views, shadows) = (cache.cached_views(), cache.cached_shadows());
    assert!(views > 100 && shadows > 100, "{views} views, {shadows} shadows");
    // Warm: the same frame from the cache alone.
    assert_eq!(check(&mut cache, &cam1, &l1), cold);
    assert_eq!((cache.cached_views(), cache.cached_shadows()), (views, shadows));
    // Turning about the eye keeps the view slots; moving the eye drops them, not the shadows.
    check(&mut cache, &turned, &l1);
    assert!(cache.cached_views() >= views);
    check(&mut cache, &cam2, &l1);
    assert!(cache.cached_views() < views + 50 && cache.cached_shadows() >= shadows);
    // A new light drops the shadows; the ambient term and the shadow switch drop the views.
    check(&mut cache, &cam2, &l2);
    let after_light = cache.cached_shadows();
    assert!(after_light < shadows + 50, "{after_light}");
    let no_shadows = Options { shadows: false, ..options };
    let lit = render(&mut cache, &cam2, &l2, bg, &no_shadows).unwrap();
    assert_eq!(lit, render_uncached(&cache, &cam2, &l2, bg, &no_shadows).unwrap());
    assert_eq!(check(&mut cache, &cam1, &l1), cold);
    cache.clear();
    assert_eq!((cache.cached_views(), cache.cached_shadows()), (0, 0));
    assert_eq!(check(&mut cache, &cam1, &l1), cold);
    cache.clear_view();
    assert_eq!((cache.cached_views(), cache.cached_shadows()), (0, shadows));
    // A layout-built cache is the same cache.
    let mut from_layout = FrameCache::with_layout(&a, &a.voxels).unwrap();
    assert_eq!(render(&mut from_layout, &cam1, &l1, bg, &options).unwrap(), cold);
}

/// The image of `f` with every camera ray walked to infinity (no screen tiles).
fn untiled(f: &Frame<'_, TestApp>, camera: &Camera, lookup: &impl BrickLookup) -> Image {
    let (w, h) = (f.options.width, f.options.height);
    let frame = camera.frame(w, h);
    let mut image = Image::new(w, h, Vec4::ZERO);
    for y in 0..h {
        for x in 0..w {
            let mut sum = Vec4::ZERO;
            for offset in PATTERN_4 {
                let dir = frame.ray_dir(Vec2::new(x as f32, y as f32) + offset);
                let r = f.trace(frame.eye, dir, f32::INFINITY, lookup);
                sum += (r.radiance + r.transmittance * f.background).extend(1.0 - r.transmittance);
            }
            image.pixels[(y * w + x) as usize] = sum / 4.0;
        }
    }
    image
}

#[test]
fn screen_tiles_skip_only_rays_that_meet_nothing() {
    let a = floor_plate_post();
    let cache = FrameCache::new(&a).unwrap();
    let options = Options {
        width: 45,
        height: 37,
        ambient: Vec3::ZERO,
        shadows: false,
        ..Options::default()
    };
    let lookup = cache.lookup.dense.as_ref().unwrap();
    let f = frame_of(&cache, UP_PI(), &options, false, PLAIN);
    let cameras = [
        // Outside, the model small on screen; grazing along the floor; inside the grid (bricks
        // behind the eye plane); looking away from everything.
        camera(Vec3::new(-40.0, 50.0, 70.0), Vec3::new(10.0, 2.0, 10.0)),
        camera(Vec3::new(-10.0, 1.5, 3.0), Vec3::new(20.0, 1.5, 12.0)),
        camera(Vec3::new(10.0, 4.0, 10.0), Vec3::new(15.0, 1.0, 15.0)),
        camera(Vec3::new(-10.0, 4.0, 10.0), Vec3::new(-30.0, 4.0, 10.0)),
    ];
    for (i, cam) in cameras.iter().enumerate() {
        let tiles = ScreenTiles::new(&cam.frame(45, 37), &cache.lookup.map, cache.grid());
        let skipped = (0..37).step_by(8).flat_map(|y| (0..45).step_by(8).map(move |x| (x, y)));
        let skipped = skipped.filter(|&(x, y)| tiles.t_max(x, y).is_none()).count();
        let expected = [(1, 30), (1, 30), (0, 0), (30, 30)][i];
        assert!(
            (expected.0..=expected.1).contains(&skipped),
            "camera {i}: {skipped} tiles skipped"
        );
        assert_eq!(f.render(cam), untiled(&f, cam, lookup), "camera {i}");
    }
}

#[test]
fn images_do_not_depend_on_the_thread_count() {
    let a = floor_plate_post();
    let cam = camera(Vec3::new(-12.0, 20.0, 30.0), Vec3::new(10.0, 2.0, 10.0));
    let options = Options { width: 48, height: 48, ..Options::default() };
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut cache = FrameCache::new(&a).unwrap();
            render(&mut cache, &cam, &sun(Vec3::new(0.3, 1.0, 0.2), PI), Vec3::ZERO, &options)
                .unwrap()
        })
    };
    assert_eq!(on(1), on(2));
}

#[test]
fn shadow_rays_ignore_exactly_the_voxel_and_its_18_near_neighbours() {
    let dims = UVec3::splat(9);
    let c = UVec3::splat(4);
    let options = Options::default();
    let visibility = |other: Option<(IVec3, Opacity)>, to_light: Vec3| {
        let a = app(dims, |v| {
            if v == c {
                return alpha(Vec3::ONE, 1.0);
            }
            let (o, opacity) = other?;
            (v.as_ivec3() == c.as_ivec3() + o).then_some(Voxel { albedo: Vec3::ONE, opacity })
        });
        let cache = FrameCache::new(&a).unwrap();
        let light = sun(to_light, 1.0);
        let bounds = light_bounds(&light, &cache.lookup.map, cache.grid());
        let pattern = shadow_pattern(&light, cache.grid());
        let lookup = cache.lookup.dense.as_ref().unwrap();
        let unbounded = frame_of(&cache, light, &options, false, PLAIN).shadow(c, lookup);
        let bounded = (bounds.as_ref(), None);
        let bounded = frame_of(&cache, light, &options, false, bounded).shadow(c, lookup);
        let patterned = (bounds.as_ref(), pattern.as_ref());
        let patterned = frame_of(&cache, light, &options, false, patterned).shadow(c, lookup);
        assert_eq!(unbounded, bounded);
        assert_eq!(unbounded, patterned);
        patterned
    };
    assert_eq!(visibility(None, Vec3::new(0.3, 1.0, -0.2)), 1.0, "the voxel itself is ignored");
    let mut ignored = 1; // the voxel itself
    let mut blocked = 0;
    for x in -2..=2 {
        for y in -2..=2 {
            for z in -2..=2 {
                let o = IVec3::new(x, y, z);
                if o == IVec3::ZERO {
                    continue;
                }
                // The light exactly behind that voxel's centre: the shadow ray crosses it.
                let v = visibility(Some((o, Opacity::Alpha(1.0))), o.as_vec3());
                match v {
                    1.0 => ignored += 1,
                    0.0 => blocked += 1,
                    v => panic!("offset {o}: visibility {v}"),
                }
                assert_eq!(v == 1.0, o.length_squared() <= 2, "offset {o}");
            }
        }
    }
    assert_eq!((ignored, blocked), (19, 124 - 18));
    // Farther voxels attenuate by their own opacity for the light direction and chord.
    let v = visibility(Some((IVec3::new(0, 3, 0), Opacity::Alpha(0.3))), Vec3::Y);
    assert!((v - 0.7).abs() < 1e-6, "{v}");
    let vjk = Opacity::NonExponential { sigma: 0.8, gamma: 1.0 };
    let v = visibility(Some((IVec3::new(0, 3, 0), vjk)), Vec3::Y);
    assert!((v - (-0.8f32).exp()).abs() < 1e-6, "{v}");
}

#[test]
fn shadowed_voxels_get_ambient_only() {
    // Light straight up at π, ambient 0.1: a lit voxel shows albedo · 1.1, one under the
    // opaque post-free plate (made solid here) albedo · 0.1.
    let a = app(UVec3::new(16, 8, 16), |c| {
        let plate = c.y == 5 && (6..10).contains(&c.x) && (6..10).contains(&c.z);
        (c.y == 1 || plate).then(|| alpha(Vec3::ONE, 1.0)).flatten()
    });
    let mut cache = FrameCache::new(&a).unwrap();
    let options =
        Options { width: 64, height: 64, ambient: Vec3::splat(0.1), ..Options::default() };
    let cam = camera(Vec3::new(-14.0, 24.0, 8.0), Vec3::new(8.0, 2.0, 8.0));
    let img = render(&mut cache, &cam, &UP_PI(), Vec3::ZERO, &options).unwrap();
    let at = |p: Vec3| {
        let (q, _) = cam.frame(64, 64).project(p).unwrap();
        img.get(q.x as u32, q.y as u32)
    };
    let lit = at(Vec3::new(2.5, 2.0, 3.5));
    assert!((lit - Vec4::new(1.1, 1.1, 1.1, 1.0)).abs().max_element() < 1e-4, "{lit}");
    let shadowed = at(Vec3::new(8.5, 2.0, 8.0));
    assert!((shadowed - Vec4::new(0.1, 0.1, 0.1, 1.0)).abs().max_element() < 1e-4, "{shadowed}");
}

/// An appearance whose `index_of` breaks its own contract.
struct Broken {
    inner: TestApp,
    shift: usize,
    extra: usize,
}

impl Appearance for Broken {
    fn grid(&self) -> &GridSpec {
        &self.inner.grid
    }
    fn len(&self) -> usize {
        self.inner.len() + self.extra
    }
    fn index_of(&self, c: UVec3) -> Option<usize> {
        self.inner.index_of(c).map(|i| (i + self.shift) % (self.inner.len() + 1))
    }
    fn opacity(&self, _: usize, _: Vec3) -> Opacity {
        Opacity::Alpha(1.0)
    }
    fn radiance(&self, _: usize, _: Vec3, _: &LightSample, _: f32, _: Vec3) -> Vec3 {
        Vec3::ONE
    }
}

#[test]
fn bad_inputs_are_errors() {
    let a = app(UVec3::splat(8), |c| (c.y == 0).then(|| alpha(Vec3::ONE, 1.0)).flatten());
    let mut cache = FrameCache::new(&a).unwrap();
    let cam = camera(Vec3::splat(20.0), Vec3::splat(4.0));
    let l = UP_PI();
    let ok = Options { width: 4, height: 4, ..Options::default() };
    assert!(render(&mut cache, &cam, &l, Vec3::ZERO, &ok).is_ok());
    for bad in [
        Options { width: 0, ..ok },
        Options { height: MAX_IMAGE_EDGE_PLUS_ONE, ..ok },
        Options { ambient: Vec3::NAN, ..ok },
        Options { ambient: Vec3::splat(-1.0), ..ok },
    ] {
        assert!(render(&mut cache, &cam, &l, Vec3::ZERO, &bad).is_err(), "{bad:?}");
        assert!(render_uncached(&cache, &cam, &l, Vec3::ZERO, &bad).is_err(), "{bad:?}");
    }
    assert!(render(&mut cache, &cam, &l, Vec3::INFINITY, &ok).is_err());
    let degenerate = Camera::look_at(Vec3::ONE, Vec3::ONE, Vec3::Y, 40.0);
    assert!(render(&mut cache, &degenerate, &l, Vec3::ZERO, &ok).is_err());
    let dark = Light::Directional { to_light: Vec3::ZERO, irradiance: Vec3::ONE };
    assert!(render(&mut cache, &cam, &dark, Vec3::ZERO, &ok).is_err());
    let nan_light = Light::Point { position: Vec3::NAN, intensity: Vec3::ONE };
    assert!(render(&mut cache, &cam, &nan_light, Vec3::ZERO, &ok).is_err());
    // Caches over broken appearances.
    let bad_grid = TestApp {
        grid: GridSpec { voxel_size: -1.0, ..a.grid },
        voxels: a.voxels.clone(),
        directional: false,
    };
    assert!(FrameCache::new(&bad_grid).is_err());
    let wrong = |shift, extra| Broken {
        inner: app(UVec3::splat(8), |c| (c.y == 0).then(|| alpha(Vec3::ONE, 1.0)).flatten()),
        shift,
        extra,
    };
    assert!(FrameCache::new(&wrong(0, 0)).is_ok());
    assert!(FrameCache::new(&wrong(1, 0)).is_err(), "an index out of range");
    assert!(FrameCache::new(&wrong(0, 1)).is_err(), "a record no voxel has");
    let other = BrickMap::<u8>::new(UVec3::splat(9));
    assert!(FrameCache::with_layout(&a, &other).is_err(), "a layout of other dimensions");
    let extra = BrickMap::from_voxels(UVec3::splat(8), [(UVec3::new(3, 3, 3), ())]).unwrap();
    assert!(FrameCache::with_layout(&a, &extra).is_err(), "a layout voxel without a record");
    let huge = TestApp {
        grid: GridSpec { dims: UVec3::splat(1024), ..a.grid },
        voxels: BrickMap::new(UVec3::splat(1024)),
        directional: false,
    };
    assert!(FrameCache::new(&huge).is_err(), "too large to scan");
    assert!(FrameCache::with_layout(&huge, &huge.voxels).is_ok(), "a layout needs no scan");
}

const MAX_IMAGE_EDGE_PLUS_ONE: u32 = crate::render::MAX_IMAGE_EDGE + 1;

/// The \[VJK21\] chord rules: each is cached and uncached alike, switching rules on one cache
/// gives what a fresh cache gives, only non-exponential voxels change, and along an axis
/// through voxel centres (every ray chord 1 = the centre chord) all three agree where
/// compositing starts from T = 1 (the first voxel).
#[test]
fn vjk_chord_rules_cache_alike_and_change_only_vjk_voxels() {
    let a = floor_plate_post();
    let options =
        Options { width: 40, height: 32, ambient: Vec3::splat(0.05), ..Options::default() };
    let cam = camera(Vec3::new(-12.0, 20.0, 30.0), Vec3::new(10.0, 2.0, 10.0));
    let light = sun(Vec3::new(0.3, 1.0, 0.2), PI);
    let bg = Vec3::new(0.1, 0.2, 0.3);
    let mut shared = FrameCache::new(&a).unwrap();
    let mut images = Vec::new();
    for rule in [VjkChord::PerRay, VjkChord::CachedChord, VjkChord::CachedAlpha, VjkChord::PerRay] {
        let o = Options { vjk_chord: rule, ..options };
        let img = render(&mut shared, &cam, &light, bg, &o).unwrap();
        let mut fresh = FrameCache::new(&a).unwrap();
        assert_eq!(img, render(&mut fresh, &cam, &light, bg, &o).unwrap(), "{rule:?}: fresh");
        assert_eq!(img, render_uncached(&fresh, &cam, &light, bg, &o).unwrap(), "{rule:?}");
        images.push(img);
    }
    assert_eq!(images[0], images[3], "back to per-ray chords");
    let changed =
        |i: usize| images[0].pixels.iter().zip(&images[i].pixels).filter(|(p, q)| p != q).count();
    // The plate (σ = 2, γ = 0.3) covers roughly 40 of the 1280 pixels.
    assert!(changed(1) > 10 && changed(2) > 10, "{} and {} pixels", changed(1), changed(2));
    assert_ne!(images[1], images[2]);

    // Alpha-only grids do not see the rule.
    let alphas = app(UVec3::splat(6), |c| {
        (c.y == 2).then(|| Voxel { albedo: colour_of(c), opacity: Opacity::Alpha(0.6) })
    });
    let mut cache = FrameCache::new(&alphas).unwrap();
    let cam = camera(Vec3::new(-4.0, 9.0, 8.0), Vec3::splat(3.0));
    let plain = render(&mut cache, &cam, &light, bg, &options).unwrap();
    for rule in [VjkChord::CachedChord, VjkChord::CachedAlpha] {
        let o = Options { vjk_chord: rule, ..options };
        assert_eq!(render(&mut cache, &cam, &light, bg, &o).unwrap(), plain, "{rule:?}");
    }

    // Centre chords: 1 along an axis, √3 along a body diagonal, √2 along a face diagonal.
    assert_eq!(centre_chord(Vec3::NEG_Y), 1.0);
    assert!((centre_chord(Vec3::ONE) - 3f32.sqrt()).abs() < 1e-6);
    assert!((centre_chord(Vec3::new(1.0, 0.0, -1.0)) - 2f32.sqrt()).abs() < 1e-6);
    assert_eq!(centre_chord(Vec3::ZERO), 1.0);
    // A single voxel seen along +z through its centre: T = f(σ·1, γ) under every rule.
    let one = app(UVec3::ONE, |_| {
        Some(Voxel {
            albedo: Vec3::ONE,
            opacity: Opacity::NonExponential { sigma: 1.5, gamma: 0.3 },
        })
    });
    let want = crate::appearance::transmittance::f(1.5, 0.3);
    for rule in [VjkChord::PerRay, VjkChord::CachedChord, VjkChord::CachedAlpha] {
        let o = Options { vjk_chord: rule, shadows: false, ..options };
        let cache = FrameCache::new(&one).unwrap();
        let f = frame_of(&cache, light, &o, true, PLAIN);
        let eye = Vec3::new(0.5, 0.5, -3.0);
        let r = f.trace(eye, Vec3::Z, f32::INFINITY, cache.lookup.dense.as_ref().unwrap());
        assert!((r.transmittance - want).abs() < 1e-6, "{rule:?}: {} vs {want}", r.transmittance);
    }
}

/// A jittered pixel pattern: the same seed gives the same image, another seed another one,
/// both differ from the fixed pattern, and cached equals uncached.
#[test]
fn jittered_pixel_patterns_are_seeded() {
    let a = floor_plate_post();
    let options = Options { width: 40, height: 32, ..Options::default() };
    let cam = camera(Vec3::new(-12.0, 20.0, 30.0), Vec3::new(10.0, 2.0, 10.0));
    let light = sun(Vec3::new(0.3, 1.0, 0.2), PI);
    let mut cache = FrameCache::new(&a).unwrap();
    let fixed = render(&mut cache, &cam, &light, Vec3::ZERO, &options).unwrap();
    let jitter = |seed| {
        let o = Options { pattern: PixelPattern::Jittered { seed }, ..options };
        let mut cache = FrameCache::new(&a).unwrap();
        let img = render(&mut cache, &cam, &light, Vec3::ZERO, &o).unwrap();
        assert_eq!(img, render_uncached(&cache, &cam, &light, Vec3::ZERO, &o).unwrap());
        img
    };
    let (one, again, two) = (jitter(1), jitter(1), jitter(2));
    assert_eq!(one, again);
    assert_ne!(one, two);
    assert_ne!(one, fixed);
    // Only edge pixels move: the mean coverage stays within a few percent.
    let coverage = |img: &Image| img.pixels.iter().map(|p| p.w).sum::<f32>();
    let (c0, c1) = (coverage(&fixed), coverage(&one));
    assert!((c0 - c1).abs() < 0.05 * c0, "coverage {c0} vs {c1}");
}
