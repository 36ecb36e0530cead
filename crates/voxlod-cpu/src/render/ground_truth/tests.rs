//! Ground-truth tests: analytic radiance (Lambert plane, umbra), coverage of a half-covered
//! pixel, alpha masks and blending in camera and shadow rays, double-sided materials, point
//! light range, the G-buffer, determinism across thread counts and bad parameters.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec3, Vec4};
use voxlod_scene::{
    AlphaMode, Camera, Light, Material, Sampler, Scene, Texture, TextureRef, WrapMode,
};

use super::*;
use crate::render::test_scenes::{camera, quad, scene, sun};

fn white() -> Material {
    Material::diffuse("white", Vec3::ONE)
}

/// A 4×4 plane at z = 0 facing +z.
fn plane() -> voxlod_scene::Mesh {
    quad("plane", Vec3::new(-2.0, -2.0, 0.0), Vec3::X * 4.0, Vec3::Y * 4.0, 0)
}

/// The occluder: a unit square at height 1 facing +z, material 1.
fn occluder() -> voxlod_scene::Mesh {
    quad("occluder", Vec3::new(-0.5, -0.5, 1.0), Vec3::X, Vec3::Y, 1)
}

fn top_camera() -> Camera {
    camera(Vec3::new(0.0, 0.0, 6.0), Vec3::ZERO)
}

fn run(scene: &Scene, cam: &Camera, options: &Options) -> GroundTruth {
    let g = scene.geometry();
    let bvh = Bvh::new(&g).unwrap();
    render(scene, &g, &bvh, cam, options).unwrap()
}

/// The pixel that sees world point `p` from `cam` in a `size`² image.
fn pixel_of(cam: &Camera, size: u32, p: Vec3) -> (u32, u32) {
    let (q, _) = cam.frame(size, size).project(p).unwrap();
    (q.x as u32, q.y as u32)
}

fn opts(size: u32, spp: u32) -> Options<'static> {
    Options { width: size, height: size, spp, ..Options::default() }
}

#[test]
fn white_lambert_plane_under_irradiance_pi_has_radiance_one() {
    let s = scene(vec![plane()], vec![white()], sun(Vec3::Z, PI));
    let out = run(&s, &camera(Vec3::new(0.3, -0.4, 3.0), Vec3::ZERO), &opts(16, 4));
    for p in &out.image.pixels {
        assert!((*p - Vec4::ONE).abs().max_element() < 1e-5, "{p}");
    }
}

#[test]
fn umbra_is_ambient_only_and_lit_ground_is_analytic() {
    // Light at 45° in x: the occluder's shadow falls on x ∈ [-1.5, -0.5].
    let light = sun(Vec3::new(1.0, 0.0, 1.0), PI * 2f32.sqrt());
    let s = scene(vec![plane(), occluder()], vec![white(), white()], light);
    let cam = top_camera();
    let ambient = Vec3::splat(0.1);
    let out = run(&s, &cam, &Options { ambient, ..opts(32, 16) });
    let (x, y) = pixel_of(&cam, 32, Vec3::new(-1.0, 0.0, 0.0));
    let shadow = out.image.get(x, y);
    assert!((shadow.truncate() - ambient).abs().max_element() < 1e-5, "umbra {shadow}");
    let (x, y) = pixel_of(&cam, 32, Vec3::new(1.2, 0.3, 0.0));
    let lit = out.image.get(x, y);
    assert!((lit.truncate() - Vec3::splat(1.1)).abs().max_element() < 1e-5, "lit {lit}");
    // Without shadows the umbra is lit.
    let out = run(&s, &cam, &Options { ambient, shadows: false, ..opts(32, 4) });
    let (x, y) = pixel_of(&cam, 32, Vec3::new(-1.0, 0.0, 0.0));
    assert!((out.image.get(x, y).x - 1.1).abs() < 1e-5);
}

#[test]
fn an_edge_through_the_pixel_centre_covers_half_of_it() {
    // A quad over x ≤ 0 seen head-on in an odd-sized image: its edge runs through the centre
    // of column 4. Then the same quad turned 45° about the view axis: a diagonal edge.
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let left = quad("left", Vec3::new(-9.0, -9.0, 0.0), Vec3::X * 9.0, Vec3::Y * 18.0, 0);
    let s = scene(vec![left], vec![white()], sun(Vec3::Z, PI));
    for spp in [10, 16, 64, 100] {
        let out = run(&s, &cam, &opts(9, spp));
        for y in 0..9 {
            let c = out.image.get(4, y);
            assert!((c.w - 0.5).abs() <= 1.0 / 8.0, "spp {spp}, row {y}: coverage {}", c.w);
            assert!((c.x - c.w).abs() < 1e-5, "radiance 1 over half the pixel: {c}");
            assert_eq!(out.gbuffer.get(4, y).coverage, c.w);
            assert_eq!(out.image.get(3, y).w, 1.0);
            assert_eq!(out.image.get(5, y).w, 0.0);
        }
    }
    // The half-plane x + y ≤ 0: its edge crosses the centres of the diagonal pixels (i, i).
    let along = Vec3::new(1.0, -1.0, 0.0).normalize() * 20.0;
    let inward = Vec3::new(-1.0, -1.0, 0.0).normalize() * 20.0;
    let diag = quad("diag", -along, inward, along * 2.0, 0);
    let s = scene(vec![diag], vec![white()], sun(Vec3::Z, PI));
    let out = run(&s, &cam, &opts(9, 256));
    let mean: f32 = (0..9).map(|i| out.image.get(i, i).w).sum::<f32>() / 9.0;
    assert!((mean - 0.5).abs() < 0.03, "diagonal coverage {mean}");
}

fn masked(texels: Vec<[u8; 4]>, width: u32) -> (Material, Texture) {
    let texture = Texture {
        name: "mask".into(),
        width,
        height: 1,
        texels: Arc::from(texels),
        srgb: true,
        sampler: Sampler { wrap_u: WrapMode::ClampToEdge, wrap_v: WrapMode::ClampToEdge },
    };
    let m = Material {
        base_color_texture: Some(TextureRef { texture: 0 }),
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        ..white()
    };
    (m, texture)
}

#[test]
fn a_masked_out_quad_lets_light_and_view_through() {
    let light = sun(Vec3::new(1.0, 0.0, 1.0), PI * 2f32.sqrt());
    let cam = top_camera();
    let umbra = Vec3::new(-1.0, 0.0, 0.0);
    for (alpha, lit) in [(0u8, true), (255, false)] {
        let (m, t) = masked(vec![[255, 0, 0, alpha]; 2], 2);
        let mut s = scene(vec![plane(), occluder()], vec![white(), m], light);
        s.textures.push(t);
        let out = run(&s, &cam, &opts(32, 4));
        let (x, y) = pixel_of(&cam, 32, umbra);
        let expected = if lit { 1.0 } else { 0.0 };
        assert!((out.image.get(x, y).x - expected).abs() < 1e-5, "alpha {alpha}");
        // Looking through the occluder's centre: the plane (white) or the red occluder.
        let g = out.gbuffer.get(16, 16);
        assert_eq!(g.albedo, if lit { Vec3::ONE } else { Vec3::X }, "alpha {alpha}");
    }
    // A mask cut along u = 0.5 (left texel clear, right opaque): half a shadow.
    let (m, t) = masked(vec![[255, 255, 255, 0], [255, 255, 255, 255]], 2);
    let mut s = scene(vec![plane(), occluder()], vec![white(), m], light);
    s.textures.push(t);
    let out = run(&s, &cam, &opts(32, 4));
    let (x0, y) = pixel_of(&cam, 32, Vec3::new(-1.4, 0.0, 0.0));
    let (x1, _) = pixel_of(&cam, 32, Vec3::new(-0.6, 0.0, 0.0));
    let (clear, opaque) = (out.image.get(x0, y).x, out.image.get(x1, y).x);
    assert!((clear - 1.0).abs() < 1e-5 && opaque == 0.0, "{clear} {opaque}");
}

#[test]
fn blended_alpha_is_stochastic_coverage() {
    let light = sun(Vec3::new(1.0, 0.0, 1.0), PI * 2f32.sqrt());
    let glass = Material {
        base_color: Vec4::new(1.0, 0.0, 0.0, 0.25),
        alpha_mode: AlphaMode::Blend,
        ..white()
    };
    let s = scene(vec![plane(), occluder()], vec![white(), glass], light);
    let cam = top_camera();
    let out = run(&s, &cam, &opts(32, 256));
    // Means over 3×3 pixels (2304 rays): the standard deviation is under 0.01.
    let block = |x: u32, y: u32| -> Vec4 {
        let mut sum = Vec4::ZERO;
        for j in y - 1..=y + 1 {
            for i in x - 1..=x + 1 {
                sum += out.image.get(i, j);
            }
        }
        sum / 9.0
    };
    let (x, y) = pixel_of(&cam, 32, Vec3::new(-1.0, 0.0, 0.0));
    let shadow = block(x, y).x;
    assert!((shadow - 0.75).abs() < 0.04, "3/4 of the light passes: {shadow}");
    // Through the occluder: 1/4 red occluder over 3/4 lit white plane.
    let c = block(16, 16);
    let occ_radiance = 1.0; // red channel of the lit occluder (albedo (1, 0, 0))
    let expected = Vec3::new(0.25 * occ_radiance + 0.75, 0.75, 0.75);
    assert!((c.truncate() - expected).abs().max_element() < 0.04, "{c} vs {expected}");
}

#[test]
fn double_sided_backs_face_the_viewer() {
    // A quad facing away from the camera, the light on the camera's side.
    let back = quad("back", Vec3::new(-2.0, -2.0, 0.0), Vec3::Y * 4.0, Vec3::X * 4.0, 0);
    let cam = top_camera();
    for (double_sided, expected) in [(true, 1.0), (false, 0.0)] {
        let m = Material { double_sided, ..white() };
        let s = scene(vec![back.clone()], vec![m], sun(Vec3::Z, PI));
        let out = run(&s, &cam, &opts(8, 1));
        assert!((out.image.get(4, 4).x - expected).abs() < 1e-5, "double-sided {double_sided}");
        let n = out.gbuffer.get(4, 4).normal;
        let expected = if double_sided { Vec3::Z } else { Vec3::NEG_Z };
        assert!((n - expected).length() < 1e-6, "{n}");
    }
}

#[test]
fn a_point_light_is_not_shadowed_by_what_lies_beyond_it() {
    let light = Light::Point { position: Vec3::new(0.0, 0.0, 1.0), intensity: Vec3::splat(PI) };
    let lid = quad("lid", Vec3::new(-0.5, -0.5, 2.0), Vec3::X, Vec3::Y, 0);
    let s = scene(vec![plane(), lid], vec![white()], light);
    let cam = camera(Vec3::new(3.0, 0.0, 1.0), Vec3::ZERO);
    let out = run(&s, &cam, &opts(64, 1));
    let (x, y) = pixel_of(&cam, 64, Vec3::ZERO);
    // Directly below the light at distance 1: irradiance π, radiance 1 (minus the falloff
    // across the pixel's footprint, under 1%).
    assert!((out.image.get(x, y).x - 1.0).abs() < 0.02, "{}", out.image.get(x, y));
}

#[test]
fn gbuffer_holds_the_centre_hit_and_matches_the_render() {
    let s =
        scene(vec![plane()], vec![Material::diffuse("grey", Vec3::splat(0.5))], sun(Vec3::Z, PI));
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO);
    let g = s.geometry();
    let bvh = Bvh::new(&g).unwrap();
    let full = render(&s, &g, &bvh, &cam, &opts(9, 4)).unwrap();
    let cheap = gbuffer(&s, &g, &bvh, &cam, 9, 9).unwrap();
    let t = cheap.get(4, 4);
    assert!((t.depth - 2.0).abs() < 1e-6 && t.position.length() < 1e-6, "{t:?}");
    assert!((t.normal - Vec3::Z).length() < 1e-6, "{t:?}");
    assert_eq!((t.albedo, t.coverage), (Vec3::splat(0.5), 1.0));
    for (a, b) in full.gbuffer.texels.iter().zip(&cheap.texels) {
        assert_eq!(GTexel { coverage: b.coverage, ..*a }, *b);
    }
    // Beyond the plane's edge: a miss.
    let wide = gbuffer(&s, &g, &bvh, &camera(Vec3::new(0.0, 0.0, 9.0), Vec3::ZERO), 9, 9).unwrap();
    let miss = wide.get(0, 0);
    assert_eq!((miss.depth, miss.triangle, miss.coverage), (f32::INFINITY, u32::MAX, 0.0));
}

#[test]
fn same_seed_same_bits_on_one_and_two_threads() {
    let glass = Material {
        base_color: Vec4::new(0.2, 0.9, 0.3, 0.5),
        alpha_mode: AlphaMode::Blend,
        ..white()
    };
    let light = sun(Vec3::new(1.0, 0.3, 1.0), 3.0);
    let s = scene(vec![plane(), occluder()], vec![white(), glass], light);
    let cam = camera(Vec3::new(1.0, -2.0, 4.0), Vec3::ZERO);
    let options = Options { seed: 42, ambient: Vec3::splat(0.05), ..opts(24, 16) };
    let images: Vec<GroundTruth> = [1, 2]
        .map(|threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| run(&s, &cam, &options))
        })
        .into();
    let bits = |g: &GroundTruth| -> Vec<u32> {
        g.image.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect()
    };
    assert_eq!(bits(&images[0]), bits(&images[1]));
    assert_eq!(images[0].gbuffer, images[1].gbuffer);
    let other = run(&s, &cam, &Options { seed: 43, ..options });
    assert_ne!(bits(&images[0]), bits(&other), "another seed, another estimate");
}

#[test]
fn bad_parameters_are_errors() {
    let s = scene(vec![plane()], vec![white()], sun(Vec3::Z, PI));
    let g = s.geometry();
    let bvh = Bvh::new(&g).unwrap();
    let cam = top_camera();
    let ok = opts(4, 1);
    for bad in [
        Options { width: 0, ..ok },
        Options { height: 0, ..ok },
        Options { width: 1 << 20, ..ok },
        Options { spp: 0, ..ok },
        Options { ambient: Vec3::NAN, ..ok },
        Options { ambient: Vec3::splat(-1.0), ..ok },
    ] {
        assert!(render(&s, &g, &bvh, &cam, &bad).is_err(), "{bad:?}");
    }
    let degenerate = Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0);
    assert!(render(&s, &g, &bvh, &degenerate, &ok).is_err());
    assert!(gbuffer(&s, &g, &bvh, &degenerate, 4, 4).is_err());
    assert!(gbuffer(&s, &g, &bvh, &cam, 0, 4).is_err());
    let other =
        Bvh::new(&scene(vec![plane(), occluder()], vec![white(); 2], sun(Vec3::Z, 1.0)).geometry())
            .unwrap();
    assert!(render(&s, &g, &other, &cam, &ok).is_err(), "BVH of another geometry");
    let mut dangling = g.clone();
    dangling.materials[0] = 7;
    assert!(render(&s, &dangling, &bvh, &cam, &ok).is_err());
}

/// FNV-1a over the bits of the image's pixels.
fn image_hash(g: &GroundTruth) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for bits in g.image.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)) {
        for byte in bits.to_le_bytes() {
            h = (h ^ byte as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

#[test]
fn without_a_light_filter_the_image_keeps_its_bits() {
    // The hash of this render as it was before the light filter existed (commit adaf1fa):
    // no filter must change no bit. Diffuse and blended materials only (no `powf`): apart
    // from the camera's one `tan` (the platform's libm, here x86-64 glibc) the arithmetic is
    // IEEE-exact, so the hash does not depend on the CPU; another libm may round that `tan`
    // differently and then needs its own hash.
    let glass = Material {
        base_color: Vec4::new(0.2, 0.9, 0.3, 0.5),
        alpha_mode: AlphaMode::Blend,
        ..white()
    };
    let light = sun(Vec3::new(1.0, 0.3, 1.0), 3.0);
    let s = scene(vec![plane(), occluder()], vec![white(), glass], light);
    let cam = camera(Vec3::new(1.0, -2.0, 4.0), Vec3::ZERO);
    let out = run(&s, &cam, &Options { seed: 42, ambient: Vec3::splat(0.05), ..opts(24, 16) });
    assert_eq!(image_hash(&out), 0xd48f_6e30_abe2_e49b, "{:#x}", image_hash(&out));
}

#[test]
fn a_light_filter_scales_the_lit_direct_light_only() {
    // Light at 45° in x: the occluder's shadow falls on x ∈ [-1.5, -0.5]; no ambient, so a
    // pixel is direct light only and a filter of 0.5 (a power of two: every product and sum
    // scales exactly) halves every fully covered pixel bit for bit, the umbra staying 0.
    let light = sun(Vec3::new(1.0, 0.0, 1.0), PI * 2f32.sqrt());
    let s = scene(vec![plane(), occluder()], vec![white(), white()], light);
    let cam = camera(Vec3::new(0.3, -0.4, 3.0), Vec3::ZERO);
    let base = opts(20, 4);
    let plain = run(&s, &cam, &base);
    let with = |f: &dyn LightFilter| run(&s, &cam, &Options { light_filter: Some(f), ..base });
    let half = with(&|_: Vec3| 0.5);
    assert_eq!(half.gbuffer, plain.gbuffer, "the G-buffer does not depend on the filter");
    let mut covered = 0;
    for (h, p) in half.image.pixels.iter().zip(&plain.image.pixels) {
        if p.w == 1.0 {
            covered += 1;
            assert_eq!(h.truncate(), p.truncate() * 0.5, "{h} vs {p}");
        }
    }
    assert!(covered > 300, "{covered} covered pixels");
    assert!(plain.image.pixels.iter().any(|p| p.w == 1.0 && p.x == 0.0), "an umbra is seen");
    // Identity, and out-of-range answers clamped: > 1 is 1, < 0 and NaN are 0.
    assert_eq!(with(&|_: Vec3| 1.0), plain);
    assert_eq!(with(&|_: Vec3| 7.0), plain);
    let dark = Options { shadows: false, ..base };
    let black = run(&s, &cam, &Options { light_filter: Some(&|_: Vec3| 0.0), ..dark });
    for f in [-3.0, f32::NAN] {
        let out = run(&s, &cam, &Options { light_filter: Some(&move |_: Vec3| f), ..dark });
        assert_eq!(out, black, "filter {f}");
    }
    assert!(black.image.pixels.iter().all(|p| p.truncate() == Vec3::ZERO));
    // Evaluated at the hit position: a filter dark only for x > 0.5 leaves the rest unchanged.
    let right = with(&|p: Vec3| if p.x > 0.5 { 0.25 } else { 1.0 });
    let (x, y) = pixel_of(&cam, 20, Vec3::new(1.2, 0.3, 0.0));
    assert_eq!(right.image.get(x, y).truncate(), plain.image.get(x, y).truncate() * 0.25);
    let (x, y) = pixel_of(&cam, 20, Vec3::new(-0.2, 0.3, 0.0));
    assert_eq!(right.image.get(x, y), plain.image.get(x, y));
}
