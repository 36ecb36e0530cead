//! Tests of the metavoxel pipeline: each rule against its brute-force or reference
//! counterpart, and the extremes. Volumes are tiny (a few metavoxels of 4³–8³ voxels).

use glam::{Vec3, Vec4};
use voxlod_scene::particles::{ColorMode, DisplacedSphere, DisplacementMap, FLAG_EMISSIVE};
use voxlod_scene::procedural::Rng;
use voxlod_scene::{Camera, Image};

use super::binning::{bin, bin_brute_force, prepare};
use super::fill::{fill, fill_unaccelerated, fill_with};
use super::march::{render, render_exact, render_front_to_back, sort_order};
use super::*;
use crate::render::test_scenes::quad;

fn sphere(center: Vec3, inner: f32, amplitude: f32, density: f32) -> DisplacedSphere {
    DisplacedSphere {
        center,
        inner,
        amplitude,
        color: Vec3::new(0.9, 0.7, 0.5),
        color_outer: Vec3::new(0.2, 0.3, 0.4),
        density,
        rot_cos: 1.0,
        rot_sin: 0.0,
        color_mode: ColorMode::Constant as u32,
        flags: 0,
    }
}

/// `n` random particles in the cube [−1, 1]³ (some poking out), mixed colour modes, some
/// emissive.
fn cloud(n: usize, seed: u64, density: f32) -> Vec<DisplacedSphere> {
    (0..n)
        .map(|i| {
            let mut r = Rng::stream(seed, &[i as u64]);
            let c = Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
            let mut s =
                sphere(c, r.range(0.05, 0.3), r.range(0.0, 0.2), density * r.range(0.5, 1.0));
            let (sn, cs) = voxlod_scene::procedural::rng::sin_cos_turns(r.next_f32());
            (s.rot_sin, s.rot_cos) = (sn, cs);
            s.color_mode = r.below(3);
            if r.below(4) == 0 {
                s.flags = FLAG_EMISSIVE;
            }
            s
        })
        .collect()
}

fn map() -> DisplacementMap {
    DisplacementMap::noise(5, 8, 3.0, 3).unwrap()
}

fn spec(to_light: Vec3, k: u32, m: u32) -> VolumeSpec {
    VolumeSpec::fit(Vec3::splat(-1.2), Vec3::splat(1.2), to_light, k, m).unwrap()
}

fn settings(attenuation: Attenuation) -> BuildSettings {
    BuildSettings { attenuation, ..Default::default() }
}

fn opts(size: u32, step: f32) -> MarchOptions {
    MarchOptions { width: size, height: size, step }
}

fn finite(img: &Image) -> bool {
    img.pixels.iter().all(|p| p.is_finite() && p.w >= -1e-6 && p.w <= 1.0 + 1e-6)
}

/// Max and mean absolute channel difference of two images.
fn diff(a: &Image, b: &Image) -> (f32, f32) {
    let mut max = 0.0f32;
    let mut sum = 0.0f64;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let d = (*p - *q).abs().max_element();
        max = max.max(d);
        sum += d as f64;
    }
    (max, (sum / a.pixels.len() as f64) as f32)
}

const LIGHT: Vec3 = Vec3::new(0.3, 0.9, 0.2);

#[test]
fn binning_matches_brute_force() {
    let mut spheres = cloud(300, 1, 1.0);
    spheres.push(sphere(Vec3::splat(9.0), 0.5, 0.1, 1.0)); // outside the volume
    spheres.push(sphere(Vec3::ZERO, 5.0, 1.0, 1.0)); // larger than the volume
    spheres.push(sphere(Vec3::new(-1.2, 0.3, 1.2), 0.0, 0.0, 1.0)); // a point on the boundary
    for to_light in [Vec3::Y, LIGHT, Vec3::ONE] {
        let spec = spec(to_light, 4, 4);
        let fast = bin(&spheres, &spec);
        assert_eq!(fast.bins, bin_brute_force(&spheres, &spec), "light {to_light}");
        // Sorted by key, particles ascending, the big particle everywhere.
        assert!(fast.bins.windows(2).all(|w| spec.key(w[0].coord) < spec.key(w[1].coord)));
        assert!(fast.bins.iter().all(|b| b.particles.windows(2).all(|p| p[0] < p[1])));
        assert_eq!(fast.bins.len(), 64);
        assert!(fast.bins.iter().all(|b| !b.particles.contains(&300)));
    }
}

#[test]
fn fill_early_accept_and_reject_equal_the_unaccelerated_fill() {
    let spheres = cloud(60, 2, 3.0);
    // One slab per metavoxel (M = 8), and several with a partial last one (M = 20); a noise
    // map (bounds inside [0, 1]: early exits at r_lo and r_hi) and constant maps (r_lo = r_hi,
    // at inner, between, at outer).
    let maps = [map(), DisplacementMap::constant(0.0), DisplacementMap::constant(0.4)];
    let cases = maps.iter().flat_map(|map| [(map, 2, 8), (map, 1, 20)]);
    for (map, k, m) in cases.chain([(&DisplacementMap::constant(1.0), 2, 8)]) {
        let spec = spec(LIGHT, k, m);
        let binning = bin(&spheres, &spec);
        let prepared = prepare(&spheres, &spec);
        let mut covered = 0;
        for b in &binning.bins {
            let (mv, emission) = fill(&spheres, &prepared, map, &spec, b);
            let (voxels, emission_ref) =
                fill_unaccelerated(&spheres, &prepared, map, &spec, b.coord);
            let bits =
                |v: &[Vec4]| v.iter().map(|x| x.to_array().map(f32::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(&mv.voxels), bits(&voxels), "metavoxel {:?} M {m}", b.coord);
            assert_eq!(emission, emission_ref, "metavoxel {:?} M {m}", b.coord);
            // The portable build too (fill takes the AVX2 one where the CPU has it).
            let (portable, emission_portable) =
                fill_with(&spheres, &prepared, map, &spec, b, false);
            assert_eq!(bits(&portable.voxels), bits(&voxels), "portable, {:?} M {m}", b.coord);
            assert_eq!(emission_portable, emission_ref, "portable, {:?} M {m}", b.coord);
            assert_eq!(portable.occupied, mv.occupied);
            covered += voxels.iter().filter(|v| v.w > 0.0).count();
            // Every voxel written lies in the occupied box.
            let [lo, hi] = mv.occupied;
            let m = m as usize;
            for (i, v) in voxels.iter().enumerate() {
                let e = emission_ref.as_ref().map_or(Vec3::ZERO, |e| e[i]);
                if *v != Vec4::ZERO || e != Vec3::ZERO {
                    let q = [i % m, i / m % m, i / (m * m)];
                    assert!(
                        (0..3).all(|a| lo[a] as usize <= q[a] && q[a] < hi[a] as usize),
                        "voxel {q:?} outside the occupied box {lo:?}..{hi:?}"
                    );
                }
            }
        }
        assert!(covered > 100, "the test covers voxels: {covered}");
    }
}

/// The volume with every metavoxel's occupied box the whole metavoxel: propagation and the
/// march then walk every voxel, as without empty-space skipping.
fn without_skipping(mut mvs: Vec<Metavoxel>, m: u32) -> Vec<Metavoxel> {
    for mv in &mut mvs {
        mv.occupied = [[0; 3], [m; 3]];
    }
    mvs
}

#[test]
fn empty_space_skipping_changes_no_bit() {
    let mut spheres = cloud(40, 9, 4.0);
    // A particle whose bounding sphere reaches a metavoxel without covering a voxel centre
    // there (an occupied but empty metavoxel).
    spheres.push(sphere(Vec3::new(0.05, -0.4, 0.1), 0.01, 0.0, 2.0));
    let map = map();
    let camera = Camera::look_at(Vec3::new(0.4, 0.9, 3.5), Vec3::ZERO, Vec3::Y, 40.0);
    for att in [Attenuation::Chapter, Attenuation::BeerLambert, Attenuation::Exact] {
        let spec = spec(LIGHT, 3, 8);
        let settings = settings(att);
        // Propagation: the same voxels and light with and without the boxes.
        let binning = bin(&spheres, &spec);
        let prepared = prepare(&spheres, &spec);
        let filled: Vec<(Metavoxel, Option<Vec<Vec3>>)> =
            binning.bins.iter().map(|b| fill(&spheres, &prepared, &map, &spec, b)).collect();
        assert!(filled.iter().any(|(mv, _)| mv.is_empty()), "an empty metavoxel is tested");
        let mut full: Vec<(Metavoxel, Option<Vec<Vec3>>)> = filled
            .iter()
            .map(|(mv, e)| (without_skipping(vec![mv.clone()], 8).remove(0), e.clone()))
            .collect();
        let mut skipped = filled.clone();
        propagate::propagate(&mut skipped, &spec, &settings, None);
        propagate::propagate(&mut full, &spec, &settings, None);
        for ((a, _), (b, _)) in skipped.iter().zip(&full) {
            assert_eq!(a.voxels, b.voxels, "{att:?} metavoxel {:?}", a.coord);
            assert_eq!(a.light_top, b.light_top, "{att:?} metavoxel {:?}", a.coord);
        }
        // March: the same image with and without the boxes, from outside and inside.
        let v = build(&spheres, &map, &spec, &settings, None, None).unwrap();
        let mut w = v.clone();
        w.metavoxels = without_skipping(w.metavoxels, 8);
        for cam in [camera, Camera::look_at(Vec3::new(0.1, 0.2, 0.3), Vec3::ZERO, Vec3::Y, 70.0)] {
            let a = render(&v, &cam, &opts(48, 0.7), None).unwrap();
            let b = render(&w, &cam, &opts(48, 0.7), None).unwrap();
            assert_eq!(a.pixels, b.pixels, "{att:?}");
            assert!(a.pixels.iter().any(|p| p.w > 0.01), "the image shows the volume");
        }
    }
}

#[test]
fn displacement_decides_the_shell_only() {
    // Inner radius 2 voxels, outer 4: centres within 2 are in, beyond 4 out, between by the map.
    let spec = spec(Vec3::Y, 1, 16);
    let vs = spec.frame.voxel_size;
    let c = spec.frame.to_world(Vec3::splat(8.0));
    let s = sphere(c, 2.0 * vs, 2.0 * vs, 1.0);
    let b = bin(&[s], &spec);
    let count = |value: f32| {
        let (mv, _) = fill(&[s], &b.prepared, &DisplacementMap::constant(value), &spec, &b.bins[0]);
        mv.voxels.iter().filter(|v| v.w > 0.0).count()
    };
    let (inner, outer, half) = (count(0.0), count(1.0), count(0.5));
    let ball = |r: f32| {
        let mut n = 0;
        for z in 0..16 {
            for y in 0..16 {
                for x in 0..16 {
                    let q = Vec3::new(x as f32, y as f32, z as f32) + 0.5 - 8.0;
                    n += usize::from(q.length_squared() <= r * r);
                }
            }
        }
        n
    };
    assert_eq!((inner, half, outer), (ball(2.0), ball(3.0), ball(4.0)));
}

#[test]
fn sort_order_is_a_visibility_order_and_top_to_bottom_per_column() {
    let spheres = cloud(200, 3, 1.0);
    let spec = spec(LIGHT, 4, 4);
    let volume =
        build(&spheres, &map(), &spec, &settings(Attenuation::Chapter), None, None).unwrap();
    assert!(volume.metavoxels.len() > 30);
    let eyes = [Vec3::new(0.3, 4.0, 3.0), Vec3::new(0.3, -4.0, 3.0), Vec3::new(0.1, 0.05, -0.1)];
    for eye in eyes {
        let order = sort_order(&volume, eye);
        assert_eq!(order.len(), volume.metavoxels.len());
        let pos: Vec<usize> = {
            let mut p = vec![0; order.len()];
            for (n, &(i, _)) in order.iter().enumerate() {
                p[i] = n;
            }
            p
        };
        // Top to bottom within every column.
        for (i, a) in volume.metavoxels.iter().enumerate() {
            for (j, b) in volume.metavoxels.iter().enumerate() {
                if a.coord[..2] == b.coord[..2] && a.coord[2] < b.coord[2] {
                    assert!(pos[i] < pos[j], "eye {eye}: {:?} after {:?}", a.coord, b.coord);
                }
            }
        }
        // The over group comes first, then the under group.
        let first_under = order.iter().position(|o| !o.1).unwrap_or(order.len());
        assert!(order[first_under..].iter().all(|o| !o.1));
    }
}

#[test]
fn over_under_order_equals_the_per_pixel_march_from_both_sides_and_inside() {
    // One volume, cameras above the perpendicular (looking down), below it (looking up), level
    // with the light's perpendicular, and inside the volume; the sorted metavoxel march must
    // equal the per-pixel front-to-back march. Tolerance: 1e-4 on 99 % of the channels-max
    // per pixel (float rounding, and samples landing exactly on a metavoxel face), 0.05 max.
    let spheres = cloud(150, 4, 4.0);
    let spec = spec(LIGHT, 3, 6);
    for att in [Attenuation::Chapter, Attenuation::BeerLambert] {
        let volume = build(&spheres, &map(), &spec, &settings(att), None, None).unwrap();
        let cams = [
            Camera::look_at(Vec3::new(1.0, 3.5, 2.5), Vec3::ZERO, Vec3::Y, 50.0),
            Camera::look_at(Vec3::new(-1.0, -3.5, 2.5), Vec3::ZERO, Vec3::Y, 50.0),
            Camera::look_at(Vec3::new(3.5, 0.2, 0.5), Vec3::ZERO, Vec3::Y, 50.0),
            Camera::look_at(Vec3::new(0.1, 0.2, 0.3), Vec3::new(1.0, -0.3, -1.0), Vec3::Y, 80.0),
        ];
        for cam in cams {
            let a = render(&volume, &cam, &opts(40, 1.0), None).unwrap();
            let b = render_front_to_back(&volume, &cam, &opts(40, 1.0), None).unwrap();
            let mut d: Vec<f32> = a
                .pixels
                .iter()
                .zip(&b.pixels)
                .map(|(p, q)| (*p - *q).abs().max_element())
                .collect();
            d.sort_by(f32::total_cmp);
            let (p99, max) = (d[d.len() * 99 / 100], d[d.len() - 1]);
            assert!(p99 <= 1e-4 && max <= 0.05, "{att:?} eye {}: p99 {p99}, max {max}", cam.eye);
            let covered = a.pixels.iter().filter(|p| p.w > 0.05).count();
            assert!(covered > 100, "the camera sees the volume: {covered}");
        }
    }
}

#[test]
fn attenuation_models_against_the_exact_reference() {
    // Beer–Lambert with a fine step converges to the exact march; the chapter's 1/(1+d) is
    // more transparent and further off on dense media.
    let spheres = cloud(80, 5, 3.0);
    let spec = spec(LIGHT, 2, 8);
    let cam = Camera::look_at(Vec3::new(1.5, 2.0, 3.5), Vec3::ZERO, Vec3::Y, 45.0);
    let vol = |att| build(&spheres, &map(), &spec, &settings(att), None, None).unwrap();
    let exact = render(&vol(Attenuation::Exact), &cam, &opts(48, 1.0), None).unwrap();
    let exact2 = render_exact(&vol(Attenuation::Exact), &cam, &opts(48, 1.0), None).unwrap();
    assert_eq!(exact, exact2);
    // The march converges to the exact integral of the same lit field as the step shrinks.
    let beer = vol(Attenuation::BeerLambert);
    let exact_beer = render_exact(&beer, &cam, &opts(48, 1.0), None).unwrap();
    let (_, coarse) = diff(&render(&beer, &cam, &opts(48, 1.0), None).unwrap(), &exact_beer);
    let (_, fine) = diff(&render(&beer, &cam, &opts(48, 0.125), None).unwrap(), &exact_beer);
    assert!(fine < 0.25 * coarse && fine < 0.01, "march error: step 1 {coarse}, step 1/8 {fine}");
    // Against the reference (exact march, exact per-voxel light), 1/(1+d) is further off than
    // exp(−d) at the chapter's one-voxel step.
    let beer1 = render(&beer, &cam, &opts(48, 1.0), None).unwrap();
    let chapter = render(&vol(Attenuation::Chapter), &cam, &opts(48, 1.0), None).unwrap();
    let (_, err_beer) = diff(&beer1, &exact);
    let (_, err_chap) = diff(&chapter, &exact);
    assert!(err_chap > err_beer, "1/(1+d) {err_chap} vs exp(-d) {err_beer}");
    let alpha = |img: &Image| img.pixels.iter().map(|p| p.w).sum::<f32>();
    assert!(alpha(&chapter) < alpha(&exact), "1/(1+d) is more transparent");
}

#[test]
fn memory_follows_occupied_metavoxels_not_the_bounds() {
    // One small particle: 1 to 8 metavoxels whatever K, never K³·M³ voxels.
    let s = [sphere(Vec3::new(0.1, 0.2, -0.1), 0.02, 0.01, 1.0)];
    let mut sizes = Vec::new();
    for k in [2, 8, 32] {
        let spec = spec(LIGHT, k, 4);
        let v = build(&s, &map(), &spec, &settings(Attenuation::Chapter), None, None).unwrap();
        assert!((1..=8).contains(&v.metavoxels.len()), "K={k}: {}", v.metavoxels.len());
        let voxel_bytes = v.bytes() - (k as u64).pow(3) * 4;
        let per = (64 * 16 + 16 * 4 + size_of::<Metavoxel>()) as u64;
        assert_eq!(voxel_bytes, v.metavoxels.len() as u64 * per);
        sizes.push(v.bytes());
        assert!(v.bytes() * 50 < spec.dense_bytes() || k == 2, "K={k}");
    }
    let dense32 = spec(LIGHT, 32, 4).dense_bytes();
    assert!(sizes[2] * 100 < dense32, "{sizes:?} vs dense {dense32}");
    // A build that would exceed its budget fails before allocating.
    let small = BuildSettings { max_bytes: 100, ..Default::default() };
    let err = build(&s, &map(), &spec(LIGHT, 2, 4), &small, None, None).unwrap_err();
    assert!(matches!(err, Error::OutOfMemory { .. }), "{err}");
}

#[test]
fn culling_keeps_what_the_eye_sees_and_what_shadows_it() {
    let spheres = cloud(200, 6, 1.0);
    let spec = spec(Vec3::Y, 4, 4);
    let s = settings(Attenuation::BeerLambert);
    let full = build(&spheres, &map(), &spec, &s, None, None).unwrap();
    // A narrow camera looking at the lower part of the volume.
    let cam = Camera::look_at(Vec3::new(0.0, -0.6, 5.0), Vec3::new(0.0, -0.9, 0.0), Vec3::Y, 12.0);
    let frame = cam.frame(32, 32);
    let culled = build(&spheres, &map(), &spec, &s, Some(&frame), None).unwrap();
    assert!(culled.metavoxels.len() < full.metavoxels.len(), "something culled");
    assert!(culled.stats.occupied == full.stats.occupied);
    // The image is the same: nothing visible, and nothing shadowing the visible, was dropped.
    let a = render(&full, &cam, &opts(32, 1.0), None).unwrap();
    let b = render(&culled, &cam, &opts(32, 1.0), None).unwrap();
    assert_eq!(a, b);
}

#[test]
fn volume_shadow_on_the_scene_matches_a_column_walk() {
    let spheres = [sphere(Vec3::new(0.0, 0.5, 0.0), 0.4, 0.1, 5.0)];
    for to_light in [Vec3::Y, Vec3::ONE] {
        let spec = spec(to_light, 2, 8);
        let v = build(&spheres, &map(), &spec, &settings(Attenuation::BeerLambert), None, None)
            .unwrap();
        let l = to_light.normalize();
        let below = Vec3::new(0.0, 0.5, 0.0) - l * 1.0;
        let t_below = v.transmittance_to_light(below);
        assert!(t_below < 0.05, "under the dense particle: {t_below}");
        assert_eq!(v.transmittance_to_light(Vec3::new(0.0, 0.5, 0.0) + l * 1.0), 1.0);
        assert_eq!(v.transmittance_to_light(Vec3::splat(50.0)), 1.0);
        // Brute force: walk the voxels from the point's voxel up to the top of the volume.
        let q = spec.frame.to_voxel(below).floor();
        let mut t = 1.0;
        for z in 0..q.z as i32 {
            let g = [q.x as u32, q.y as u32, z as u32];
            let c = g.map(|x| x / 8);
            if let Some(mv) = v.metavoxel(c) {
                let l = g.map(|x| (x % 8) as usize);
                t *= (-mv.voxels[(l[2] * 8 + l[1]) * 8 + l[0]].w * spec.frame.voxel_size).exp();
            }
        }
        assert!((t - t_below).abs() < 1e-5, "{t} vs {t_below}");
    }
}

#[test]
fn scene_shadow_on_the_volume_darkens_only_what_the_mesh_blocks() {
    // A slab of medium under a light straight above; a quad above half of it (x < 0).
    let spheres: Vec<_> = (0..9)
        .flat_map(|i| (0..9).map(move |j| (i, j)))
        .map(|(i, j)| {
            sphere(Vec3::new(i as f32 * 0.25 - 1.0, 0.0, j as f32 * 0.25 - 1.0), 0.2, 0.0, 1.0)
        })
        .collect();
    let mesh = quad(
        "roof",
        Vec3::new(-3.0, 0.8, 3.0),
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -6.0),
        0,
    );
    let scene = voxlod_scene::Scene { meshes: vec![mesh], ..Default::default() };
    let geometry = scene.geometry();
    let bvh = crate::raycast::Bvh::new(&geometry).unwrap();
    let spec = spec(Vec3::Y, 2, 8);
    let s = BuildSettings { ambient: Vec3::ZERO, ..settings(Attenuation::BeerLambert) };
    let lit = build(&spheres, &map(), &spec, &s, None, None).unwrap();
    let shadowed = build(&spheres, &map(), &spec, &s, None, Some(&bvh)).unwrap();
    let radiance = |v: &Volume, x: f32| {
        let q = spec.frame.to_voxel(Vec3::new(x, 0.0, 0.1)).floor();
        let g = [q.x as u32, q.y as u32, q.z as u32];
        let mv = v.metavoxel(g.map(|c| c / 8)).unwrap();
        let l = g.map(|c| (c % 8) as usize);
        mv.voxels[(l[2] * 8 + l[1]) * 8 + l[0]].truncate().length()
    };
    assert!(radiance(&lit, -0.5) > 0.1 && radiance(&lit, 0.5) > 0.1);
    assert_eq!(radiance(&shadowed, -0.5), 0.0, "under the roof");
    assert_eq!(radiance(&shadowed, 0.5), radiance(&lit, 0.5), "beside the roof");
}

#[test]
fn depth_buffer_stops_rays_and_composite_blends_premultiplied() {
    let spheres = cloud(100, 7, 5.0);
    let spec = spec(LIGHT, 2, 8);
    let v =
        build(&spheres, &map(), &spec, &settings(Attenuation::BeerLambert), None, None).unwrap();
    let cam = Camera::look_at(Vec3::new(0.0, 0.5, 4.0), Vec3::ZERO, Vec3::Y, 45.0);
    let o = opts(24, 1.0);
    let free = render(&v, &cam, &o, None).unwrap();
    let at_eye = render(&v, &cam, &o, Some(&vec![0.0; 576])).unwrap();
    assert!(at_eye.pixels.iter().all(|p| *p == Vec4::ZERO));
    let half: Vec<f32> = vec![4.0; 576];
    let partial = render(&v, &cam, &o, Some(&half)).unwrap();
    let (alpha_free, alpha_half): (f32, f32) =
        (free.pixels.iter().map(|p| p.w).sum(), partial.pixels.iter().map(|p| p.w).sum());
    assert!(alpha_half < alpha_free && alpha_half > 0.0, "{alpha_half} vs {alpha_free}");
    assert!(render(&v, &cam, &o, Some(&[1.0; 3])).is_err(), "wrong depth length");
    let mesh = Image::new(24, 24, Vec4::new(0.2, 0.4, 0.6, 1.0));
    let out = composite(&free, &mesh).unwrap();
    for ((c, v), m) in out.pixels.iter().zip(&free.pixels).zip(&mesh.pixels) {
        let expect = v.truncate() + m.truncate() * (1.0 - v.w);
        assert!((c.truncate() - expect).abs().max_element() < 1e-6);
        assert!((c.w - 1.0).abs() < 1e-6);
    }
    assert!(composite(&free, &Image::new(3, 3, Vec4::ONE)).is_err());
}

#[test]
fn extremes_give_finite_images_without_panics() {
    let m = map();
    let cams = [
        Camera::look_at(Vec3::new(0.5, 2.5, 3.0), Vec3::ZERO, Vec3::Y, 50.0),
        // Inside the dense particle at the centre.
        Camera::look_at(Vec3::new(0.01, 0.02, 0.03), Vec3::new(1.0, 0.0, 0.0), Vec3::Y, 60.0),
    ];
    let dense_centre = sphere(Vec3::ZERO, 0.3, 0.1, 1e6);
    let cases: Vec<(&str, Vec<DisplacedSphere>)> = vec![
        ("density 0", cloud(50, 8, 0.0)),
        ("density 1e6", {
            let mut c = cloud(50, 8, 1e6);
            c.push(dense_centre);
            c
        }),
        ("outside the volume", vec![sphere(Vec3::splat(30.0), 1.0, 0.5, 1.0)]),
        ("larger than the volume", vec![sphere(Vec3::ZERO, 40.0, 10.0, 0.5), dense_centre]),
        ("empty", Vec::new()),
    ];
    for to_light in [Vec3::Y, Vec3::X, Vec3::NEG_Z, Vec3::ONE, Vec3::new(1.0, -1.0, 1.0)] {
        let spec = spec(to_light, 2, 6);
        for (name, spheres) in &cases {
            for att in [Attenuation::Chapter, Attenuation::BeerLambert, Attenuation::Exact] {
                let v = build(spheres, &m, &spec, &settings(att), None, None).unwrap();
                for cam in &cams {
                    let img = render(&v, cam, &opts(12, 1.0), None).unwrap();
                    assert!(finite(&img), "{name}, light {to_light}, {att:?}, eye {}", cam.eye);
                    if *name == "density 0" || *name == "empty" || name.starts_with("outside") {
                        assert!(img.pixels.iter().all(|p| p.w == 0.0), "{name}: transparent");
                    }
                    if *name == "density 1e6" && cam.eye.length() < 0.1 {
                        assert!(img.pixels.iter().all(|p| p.w > 0.999), "{name}: opaque inside");
                    }
                }
                let t = v.transmittance_to_light(Vec3::new(0.0, -1.0, 0.0));
                assert!((0.0..=1.0).contains(&t), "{name}: {t}");
            }
        }
    }
    // 10⁵ overlapping particles (one light, one model: binning 10⁵ particles per build).
    let mut many: Vec<_> =
        (0..100_000).map(|_| sphere(Vec3::new(0.02, 0.0, 0.0), 0.03, 0.01, 10.0)).collect();
    many.push(dense_centre);
    let v =
        build(&many, &m, &spec(LIGHT, 2, 6), &settings(Attenuation::Chapter), None, None).unwrap();
    assert!(v.stats.bin_entries > 100_000, "every particle binned: {:?}", v.stats);
    for cam in &cams {
        assert!(finite(&render(&v, cam, &opts(12, 1.0), None).unwrap()));
    }
    // Bad input is an error naming what.
    let bad = [sphere(Vec3::ZERO, -1.0, 0.0, 1.0)];
    let spec = spec(Vec3::Y, 2, 4);
    let err = build(&bad, &m, &spec, &settings(Attenuation::Chapter), None, None).unwrap_err();
    assert!(err.to_string().contains("particle"), "{err}");
    assert!(VolumeSpec::fit(Vec3::ZERO, Vec3::ONE, Vec3::ZERO, 2, 4).is_err());
    assert!(VolumeSpec::fit(Vec3::ZERO, Vec3::NAN, Vec3::Y, 2, 4).is_err());
    assert!(VolumeSpec::fit(Vec3::ZERO, Vec3::ONE, Vec3::Y, 0, 4).is_err());
    let v = build(&[], &m, &spec, &settings(Attenuation::Chapter), None, None).unwrap();
    let cam = cams[0];
    assert!(render(&v, &cam, &opts(8, 0.0), None).is_err());
    assert!(render(&v, &cam, &opts(0, 1.0), None).is_err());
}

#[test]
fn builds_and_renders_are_deterministic_across_thread_counts() {
    let spheres = cloud(120, 9, 2.0);
    let spec = spec(LIGHT, 3, 4);
    let cam = Camera::look_at(Vec3::new(1.0, 1.5, 3.0), Vec3::ZERO, Vec3::Y, 50.0);
    let run = || {
        let v =
            build(&spheres, &map(), &spec, &settings(Attenuation::Chapter), None, None).unwrap();
        (v.metavoxels.clone(), render(&v, &cam, &opts(20, 1.0), None).unwrap())
    };
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(run);
    let many = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(run);
    assert_eq!(one, many);
}

/// A dense blob at (0, 0.3, 0) over a ground plane at y = −1 under a light from `to_light`:
/// the volume (Beer–Lambert, density `density`), the scene and its BVH.
fn blob_over_ground(
    density: f32,
    to_light: Vec3,
) -> (Volume, voxlod_scene::Scene, voxlod_scene::Geometry, crate::raycast::Bvh) {
    use crate::render::test_scenes::{scene, sun};
    let spheres = [sphere(Vec3::new(0.0, 0.3, 0.0), 0.4, 0.1, density)];
    let spec = spec(to_light, 2, 8);
    let v =
        build(&spheres, &map(), &spec, &settings(Attenuation::BeerLambert), None, None).unwrap();
    let ground = quad("ground", Vec3::new(-2.0, -1.0, 2.0), Vec3::X * 4.0, Vec3::NEG_Z * 4.0, 0);
    let white = voxlod_scene::Material::diffuse("white", Vec3::ONE);
    let s = scene(vec![ground], vec![white], sun(to_light, 3.0));
    let g = s.geometry();
    let bvh = crate::raycast::Bvh::new(&g).unwrap();
    (v, s, g, bvh)
}

#[test]
fn volume_shadow_darkens_the_mesh_by_exactly_its_transmittance() {
    use crate::render::ground_truth::{self, LightFilter, Options};
    use crate::render::pixel_samples::Streams;
    use crate::render::surface::{Lighting, MeshTracer};
    use crate::shading::shade;
    let to_light = LIGHT.normalize();
    let (v, s, g, bvh) = blob_over_ground(5.0, to_light);
    let tracer = MeshTracer::new(&s, &g, &bvh).unwrap();
    let streams = Streams::new(0);
    let eye = Vec3::new(0.2, 3.0, 2.5);
    let ambient = Vec3::splat(0.1);
    // Under the blob (along the light from its centre to the ground) and far beside it.
    let under = Vec3::new(0.0, 0.3, 0.0) - to_light * (1.3 / to_light.y);
    let beside = Vec3::new(1.5, -1.0, 1.5);
    let shaded = |p: Vec3, filter: Option<&dyn LightFilter>| {
        let dir = (p - eye).normalize();
        let sp = tracer.trace(eye, dir, 0, 0, &streams).expect("the ray hits the ground");
        let lighting = Lighting { shadows: true, ambient, filter };
        (sp, dir, tracer.radiance(&sp, dir, 0, 0, &streams, lighting))
    };
    let (sp, dir, dark) = shaded(under, Some(&v));
    let (_, _, lit) = shaded(under, None);
    let t = v.transmittance_to_light(sp.position);
    assert!(t < 0.2, "under the blob: {t}");
    let light = tracer.light.sample(sp.position);
    assert_eq!(dark, shade(&sp.material, sp.normal, -dir, &light, t, ambient));
    let direct = |r: Vec3| r - ambient; // white albedo
    assert!((direct(dark) - direct(lit) * t).abs().max_element() < 1e-6, "{dark} vs {lit}·{t}");
    let (sp, _, outside) = shaded(beside, Some(&v));
    assert_eq!(v.transmittance_to_light(sp.position), 1.0, "beside the shadow");
    assert_eq!(outside, shaded(beside, None).2);

    // The whole render: darker under the blob, unchanged beside it.
    let cam = Camera::look_at(eye, Vec3::new(0.0, -1.0, 0.0), Vec3::Y, 60.0);
    let o = Options { width: 24, height: 24, spp: 4, ambient, ..Options::default() };
    let plain = ground_truth::render(&s, &g, &bvh, &cam, &o).unwrap();
    let shadowed =
        ground_truth::render(&s, &g, &bvh, &cam, &Options { light_filter: Some(&v), ..o }).unwrap();
    let frame = cam.frame(24, 24);
    let px = |p: Vec3| {
        let (q, _) = frame.project(p).unwrap();
        (q.x as u32, q.y as u32)
    };
    let (x, y) = px(under);
    assert!(shadowed.image.get(x, y).x < 0.5 * plain.image.get(x, y).x);
    let (x, y) = px(beside);
    assert_eq!(shadowed.image.get(x, y), plain.image.get(x, y));
}

#[test]
fn volume_shadow_extremes_density_zero_and_a_million() {
    use crate::render::ground_truth::{self, Options};
    for to_light in [Vec3::Y, LIGHT.normalize(), Vec3::new(1.0, 1.0, -1.0).normalize()] {
        let cam = Camera::look_at(Vec3::new(0.2, 3.0, 2.5), Vec3::NEG_Y, Vec3::Y, 60.0);
        let ambient = Vec3::splat(0.1);
        let o = Options { width: 16, height: 16, spp: 2, ambient, ..Options::default() };
        let under = Vec3::new(0.0, 0.3, 0.0) - to_light * (1.3 / to_light.y);
        // Density 0: factor exactly 1 everywhere, the same bits as without the filter.
        let (v, s, g, bvh) = blob_over_ground(0.0, to_light);
        assert_eq!(v.transmittance_to_light(under), 1.0);
        let plain = ground_truth::render(&s, &g, &bvh, &cam, &o).unwrap();
        let with = Options { light_filter: Some(&v), ..o };
        assert_eq!(ground_truth::render(&s, &g, &bvh, &cam, &with).unwrap(), plain);
        // Density 10⁶: factor ≈ 0, the point is lit by the ambient term only, nothing NaN.
        let (v, s, g, bvh) = blob_over_ground(1e6, to_light);
        let t = v.transmittance_to_light(under);
        assert!((0.0..1e-6).contains(&t), "light {to_light}: {t}");
        let with = Options { light_filter: Some(&v), ..o };
        let out = ground_truth::render(&s, &g, &bvh, &cam, &with).unwrap();
        assert!(out.image.pixels.iter().all(|p| p.is_finite()));
        let (q, _) = cam.frame(16, 16).project(under).unwrap();
        let p = out.image.get(q.x as u32, q.y as u32).truncate();
        assert!((p - ambient).abs().max_element() < 1e-3, "light {to_light}: {p}");
    }
}

#[test]
fn from_parts_rebuilds_the_index_and_rejects_bad_parts() {
    let spec = spec(Vec3::Y, 3, 4);
    let v =
        build(&cloud(60, 3, 2.0), &map(), &spec, &settings(Attenuation::BeerLambert), None, None)
            .unwrap();
    let again =
        Volume::from_parts(spec, v.attenuation, v.metavoxels.clone(), v.stats, v.times).unwrap();
    assert_eq!(again, v);
    let mut reversed = v.metavoxels.clone();
    reversed.reverse();
    assert!(Volume::from_parts(spec, v.attenuation, reversed, v.stats, v.times).is_err());
    let mut short = v.metavoxels.clone();
    short[0].voxels.pop();
    assert!(Volume::from_parts(spec, v.attenuation, short, v.stats, v.times).is_err());
}
