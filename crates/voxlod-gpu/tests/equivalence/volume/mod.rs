//! The metavoxel volume kernels (McNabb 2015): binning, fill, light propagation, eye march, and
//! the whole frame, each against an oracle both backends answer to.
//!
//! - **Binning** — oracle: [`bin_brute_force`] (every particle against every metavoxel with
//!   the reference predicate). Bound: **exact** (the same bins, the same particle lists).
//! - **Fill** — oracle: [`fill_unaccelerated`] per kept metavoxel (every particle, every voxel,
//!   always the cube map). Both backends sum a voxel's densities in particle order, so a voxel
//!   that the same particles cover has the same density bits; colours that read the cube map
//!   (`DisplacementAo`) or `√d²` (`RadialRamp`) carry WGSL's 2.5-ulp division and possible
//!   fused multiply-adds, a few ulps: **per value `1e-5` relative (+ `1e-6` absolute)**. A
//!   voxel whose centre lies within those ulps of a displaced surface may be covered on one
//!   backend and not the other (a whole particle's density and colour): **at most 0.2 % of
//!   the voxels** beyond the per-value bound.
//! - **Propagation** — oracle: Listing 5.2 in `f64` on the backend's own fill output (so this
//!   row measures propagation alone). Light decays multiplicatively down a column of up to
//!   `K·M = 32` voxels: each step adds `exp`'s error (WGSL: 3 + 2|x| ulp with |x| ≤ a few)
//!   and the f32 product's, about 1e-6 relative per step: **per value `1e-4` relative
//!   (+ `1e-6` absolute)** on the lit voxels and the column-top light, **all values**.
//! - **March** — oracle: [`render_front_to_back`] (each pixel's samples in ray order through
//!   the whole volume) of the CPU-built volume, which both backends march. The GPU's ray
//!   direction (normalization, division), fused multiply-adds and `exp` move a sample that sits
//!   within rounding of a voxel face to the neighbouring voxel: **1 sRGB step per pixel for
//!   99 % of the pixels** (the CPU's own order-based render against its front-to-back check
//!   is held to the same). The third case is lit with the exact model, which `render` marches
//!   with the reference march; its oracle is the CPU's [`render_exact`] (so on the CPU
//!   backend that case compares the function with itself).
//! - **Whole frame** — oracle: the CPU reference's frame (`build` with culling and the mesh's
//!   shadow, then `render` stopping at the mesh depth). Everything above accumulates:
//!   **2 sRGB steps for 98 % of the pixels**.
//! - **Property** — random particles (count, colour modes, emissive), light directions (axes
//!   and diagonals), cameras (one inside the volume): binning exact and the frame within the
//!   whole-frame bound, every case.
//! - **Control** — the whole-frame check against a frame whose particles are 20 % denser, a
//!   frame lit without the mesh's shadow, and a bin list with one particle dropped: all must
//!   fail the bounds above.

use glam::Vec3;
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::volume::binning::{Bin, Binning, bin, bin_brute_force};
use voxlod_cpu::volume::fill::{fill, fill_unaccelerated};
use voxlod_cpu::volume::march::{render, render_exact, render_front_to_back};
use voxlod_cpu::volume::propagate::propagate;
use voxlod_cpu::volume::{self, Attenuation, BuildSettings, MarchOptions, Metavoxel, VolumeSpec};
use voxlod_gpu::raycast::upload_bvh;
use voxlod_gpu::volume::VolumeKernels;
use voxlod_scene::particles::{DisplacedSphere, DisplacementMap, FLAG_EMISSIVE};
use voxlod_scene::procedural::Rng;
use voxlod_scene::{Camera, Geometry, Image};

use crate::harness::{Executor, Measure};
use crate::images::{ImageBound, compare as compare_srgb};

mod robustness;

pub use robustness::{control, errors, extremes, property};

/// [`compare_srgb`], with the largest linear (premultiplied RGBA) difference in the note.
fn compare(name: &str, actual: &Image, expected: &Image, bound: ImageBound) -> Measure {
    let mut m = compare_srgb(name, actual, expected, bound);
    let linear = actual
        .pixels
        .iter()
        .zip(&expected.pixels)
        .map(|(a, e)| (*a - *e).abs().max_element())
        .fold(0.0f32, f32::max);
    let covered = expected.pixels.iter().filter(|p| p.w > 0.01).count();
    m.note += &format!(
        ", max linear diff {linear:.2e}, {:.0} % of pixels covered",
        100.0 * covered as f64 / expected.pixels.len().max(1) as f64
    );
    m
}

const FILL_REL: f64 = 1e-5;
const FILL_ABS: f64 = 1e-6;
const FILL_FRACTION: f64 = 0.002;
const LIGHT_REL: f64 = 1e-4;
const LIGHT_ABS: f64 = 1e-6;
const MARCH_BOUND: ImageBound = ImageBound { per_pixel: 1, fraction: 0.99 };
const FRAME_BOUND: ImageBound = ImageBound { per_pixel: 2, fraction: 0.98 };

/// `n` random particles in [−1, 1]³ (some poking out): all colour modes, a quarter emissive.
fn cloud(n: usize, seed: u64, density: f32) -> Vec<DisplacedSphere> {
    (0..n)
        .map(|i| {
            let mut r = Rng::stream(seed, &[i as u64]);
            let center = Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
            let (rot_sin, rot_cos) = voxlod_scene::procedural::rng::sin_cos_turns(r.next_f32());
            DisplacedSphere {
                center,
                inner: r.range(0.05, 0.3),
                amplitude: r.range(0.0, 0.2),
                color: Vec3::new(r.range(0.2, 1.0), r.range(0.2, 1.0), r.range(0.2, 1.0)),
                color_outer: Vec3::new(0.2, 0.3, 0.4),
                density: density * r.range(0.5, 1.0),
                rot_cos,
                rot_sin,
                color_mode: r.below(3),
                flags: if r.below(4) == 0 { FLAG_EMISSIVE } else { 0 },
            }
        })
        .collect()
}

fn map() -> DisplacementMap {
    DisplacementMap::noise(5, 8, 3.0, 3).expect("a valid cube map")
}

fn spec(to_light: Vec3, k: u32, m: u32) -> VolumeSpec {
    VolumeSpec::fit(Vec3::splat(-1.2), Vec3::splat(1.2), to_light, k, m).expect("a valid spec")
}

/// A floor quad at y = −0.4 cutting through the cloud: it shadows the voxels below it.
fn floor() -> Geometry {
    Geometry {
        positions: vec![
            Vec3::new(-3.0, -0.4, -3.0),
            Vec3::new(3.0, -0.4, -3.0),
            Vec3::new(3.0, -0.4, 3.0),
            Vec3::new(-3.0, -0.4, 3.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        ..Default::default()
    }
}

fn kernels<'a>(backend: &Executor<'a>) -> Result<Option<VolumeKernels<'a>>, String> {
    match backend {
        Executor::Cpu => Ok(None),
        Executor::Gpu(ctx) => VolumeKernels::new(ctx).map(Some).map_err(|e| e.to_string()),
    }
}

fn binning(
    k: &Option<VolumeKernels>,
    s: &[DisplacedSphere],
    spec: &VolumeSpec,
) -> Result<Binning, String> {
    match k {
        None => Ok(bin(s, spec)),
        Some(k) => k.bin(s, spec).map_err(|e| e.to_string()),
    }
}

/// The cases of the scene rows: (particles, seed, light, K, M, density).
fn cases() -> Vec<(usize, u64, Vec3, u32, u32, f32)> {
    vec![
        (300, 1, Vec3::Y, 4, 8, 4.0),
        (200, 2, Vec3::new(1.0, 1.0, 1.0), 3, 8, 8.0),
        (250, 3, Vec3::new(0.3, -1.0, 0.2), 4, 4, 2.0),
    ]
}

fn exact_bins(name: &str, got: &[Bin], want: &[Bin]) -> Measure {
    let pairs: usize = want.iter().map(|b| b.particles.len()).sum();
    let pass = got == want;
    let mut note = format!("{name}: {} bins, {pairs} pairs", want.len());
    if !pass {
        let wrong =
            got.iter().zip(want).filter(|(a, b)| a != b).count() + got.len().abs_diff(want.len());
        note += &format!("; {wrong} bins DIFFER ({} vs {} bins)", got.len(), want.len());
    }
    Measure { max_error: if pass { 0.0 } else { 1.0 }, bound: 0.0, pass, note }
}

pub fn binning_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let mut out = Vec::new();
    for (n, seed, light, kk, m, _) in cases() {
        let s = cloud(n, seed, 1.0);
        let spec = spec(light, kk, m);
        let got = binning(&k, &s, &spec)?;
        out.push(exact_bins(
            &format!("{n} particles K={kk} M={m}"),
            &got.bins,
            &bin_brute_force(&s, &spec),
        ));
    }
    // Spheres exactly touching metavoxel faces (ties of the predicate) and huge ones.
    let spec = spec(Vec3::Z, 4, 4);
    let f = &spec.frame;
    let mut s = cloud(40, 9, 1.0);
    for (i, sp) in s.iter_mut().enumerate() {
        let q = Vec3::new((i % 4) as f32 * 4.0 + 2.0, (i / 4 % 4) as f32 * 4.0, 8.0);
        sp.center = f.to_world(q);
        sp.inner = 2.0 * f.voxel_size;
        sp.amplitude = if i % 7 == 0 { 40.0 * f.voxel_size } else { 0.0 };
    }
    // Oracle here: the CPU reference's own bins. At exact ties the reference's per-axis range
    // (`floor((x ± r) / M)`, rounded) can drop a metavoxel that the brute force's distance
    // test keeps (16 of these 64 bins differ between the two on the CPU): the GPU mirrors the
    // reference, ranges included, and must equal it.
    let got = binning(&k, &s, &spec)?;
    out.push(exact_bins(
        "face-touching and huge spheres (oracle: cpu bin)",
        &got.bins,
        &bin(&s, &spec).bins,
    ));
    Ok(Measure::combine(&out))
}

/// Per-value comparison: within `rel · max(|a|, |b|) + abs`; the error reported is the
/// relative difference with the scale floored at `abs / rel` (so values near zero, held to
/// the absolute bound, do not dominate it).
fn close(a: f32, b: f32, rel: f64, abs: f64) -> (f64, bool) {
    let (a, b) = (a as f64, b as f64);
    let d = (a - b).abs();
    let scale = a.abs().max(b.abs());
    (d / scale.max(abs / rel), d <= rel * scale + abs)
}

/// A filled metavoxel and its emission (the CPU fill's output).
type Filled = (Metavoxel, Option<Vec<Vec3>>);

fn filled(
    k: &Option<VolumeKernels>,
    s: &[DisplacedSphere],
    map: &DisplacementMap,
    spec: &VolumeSpec,
) -> Result<(Binning, Vec<Filled>), String> {
    let b = binning(k, s, spec)?;
    let out = match k {
        None => b.bins.iter().map(|bin| fill(s, &b.prepared, map, spec, bin)).collect(),
        Some(k) => {
            let v = k.fill(s, &b.prepared, map, spec, &b.bins).map_err(|e| e.to_string())?;
            k.read(&v).map_err(|e| e.to_string())?
        }
    };
    Ok((b, out))
}

pub fn fill_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let map = map();
    let mut out = Vec::new();
    for (n, seed, light, kk, m, density) in cases() {
        let s = cloud(n, seed, density);
        let spec = spec(light, kk, m);
        let (b, got) = filled(&k, &s, &map, &spec)?;
        let (mut worst, mut over, mut values) = (0.0f64, 0usize, 0usize);
        for (bin, (mv, emission)) in b.bins.iter().zip(&got) {
            let subset: Vec<DisplacedSphere> =
                bin.particles.iter().map(|&i| s[i as usize]).collect();
            let prepared: Vec<_> = bin.particles.iter().map(|&i| b.prepared[i as usize]).collect();
            let (want, want_e) = fill_unaccelerated(&subset, &prepared, &map, &spec, bin.coord);
            let zero = vec![Vec3::ZERO; want.len()];
            let (e, we) = (emission.as_ref().unwrap_or(&zero), want_e.as_ref().unwrap_or(&zero));
            for i in 0..want.len() {
                let pairs = [(mv.voxels[i], want[i]), (e[i].extend(0.0), we[i].extend(0.0))];
                let mut bad = false;
                for (a, w) in pairs {
                    for c in 0..4 {
                        let (err, ok) = close(a[c], w[c], FILL_REL, FILL_ABS);
                        // Flipped voxels are counted, the others give the worst error.
                        if ok {
                            worst = worst.max(err);
                        }
                        bad |= !ok;
                    }
                }
                values += 1;
                over += bad as usize;
            }
        }
        let fraction = over as f64 / values.max(1) as f64;
        out.push(Measure {
            max_error: worst,
            bound: FILL_REL,
            pass: fraction <= FILL_FRACTION,
            note: format!(
                "{n} particles K={kk} M={m}: {values} voxels, {over} beyond the bound ({:.3} %, allowed {:.1} %)",
                100.0 * fraction,
                100.0 * FILL_FRACTION
            ),
        });
    }
    Ok(Measure::combine(&out))
}

/// Listing 5.2 in `f64` on filled metavoxels (key order, no blocker): lit voxels and
/// column-top light.
fn propagate_f64(
    filled: &[Filled],
    spec: &VolumeSpec,
    settings: &BuildSettings,
) -> Vec<(Vec<[f64; 4]>, Vec<f64>)> {
    let m = spec.metavoxel_edge as usize;
    let vs = spec.frame.voxel_size as f64;
    let direct = settings.irradiance.as_dvec3() / std::f64::consts::PI;
    let ambient = settings.ambient.as_dvec3();
    let mut out = Vec::new();
    let mut carry = vec![1.0f64; m * m];
    let mut column = None;
    for (mv, emission) in filled {
        if column != Some([mv.coord[0], mv.coord[1]]) {
            carry = vec![1.0; m * m];
            column = Some([mv.coord[0], mv.coord[1]]);
        }
        let top = carry.clone();
        let mut lit: Vec<[f64; 4]> = mv.voxels.iter().map(|v| v.as_dvec4().to_array()).collect();
        for (col, light) in carry.iter_mut().enumerate() {
            for c in 0..m {
                let i = c * m * m + col;
                let v = mv.voxels[i].as_dvec4();
                let e = emission.as_ref().map_or(glam::DVec3::ZERO, |e| e[i].as_dvec3());
                if v == glam::DVec4::ZERO && e == glam::DVec3::ZERO {
                    continue;
                }
                let tau = v.w * vs;
                let t = match settings.attenuation {
                    Attenuation::Chapter => 1.0 / (1.0 + tau),
                    _ => (-tau).exp(),
                };
                let reach = match settings.attenuation {
                    Attenuation::Exact if tau >= 1e-4 => *light * (1.0 - (-tau).exp()) / tau,
                    Attenuation::Exact => *light * (1.0 - 0.5 * tau),
                    _ => *light,
                };
                let rgb = v.truncate() * (direct * reach + ambient) + e;
                lit[i] = [rgb.x, rgb.y, rgb.z, v.w];
                *light *= t;
            }
        }
        out.push((lit, top));
    }
    out
}

pub fn propagation_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let map = map();
    let mut out = Vec::new();
    let models = [Attenuation::BeerLambert, Attenuation::Chapter, Attenuation::Exact];
    for (case, (n, seed, light, kk, m, density)) in cases().into_iter().enumerate() {
        let s = cloud(n, seed, density);
        let spec = spec(light, kk, m);
        let settings = BuildSettings { attenuation: models[case % 3], ..Default::default() };
        let b = binning(&k, &s, &spec)?;
        let (input, lit) = match &k {
            None => {
                let mut f: Vec<_> =
                    b.bins.iter().map(|bin| fill(&s, &b.prepared, &map, &spec, bin)).collect();
                let input = f.clone();
                propagate(&mut f, &spec, &settings, None);
                (input, f)
            }
            Some(k) => {
                let mut v =
                    k.fill(&s, &b.prepared, &map, &spec, &b.bins).map_err(|e| e.to_string())?;
                let input = k.read(&v).map_err(|e| e.to_string())?;
                k.propagate(&mut v, &settings, None).map_err(|e| e.to_string())?;
                (input, k.read(&v).map_err(|e| e.to_string())?)
            }
        };
        let want = propagate_f64(&input, &spec, &settings);
        let (mut worst, mut over, mut values) = (0.0f64, 0usize, 0usize);
        for ((mv, _), (wv, wl)) in lit.iter().zip(&want) {
            let got =
                mv.voxels.iter().flat_map(|v| v.to_array()).chain(mv.light_top.iter().copied());
            let exp = wv.iter().flatten().copied().chain(wl.iter().copied());
            for (a, w) in got.zip(exp) {
                let (err, ok) = close(a, w as f32, LIGHT_REL, LIGHT_ABS);
                worst = worst.max(err);
                values += 1;
                over += !ok as usize;
            }
        }
        out.push(Measure {
            max_error: worst,
            bound: LIGHT_REL,
            pass: over == 0,
            note: format!(
                "{n} particles K={kk} M={m} {}: {values} values, {over} beyond the bound",
                settings.attenuation.name()
            ),
        });
    }
    Ok(Measure::combine(&out))
}

fn camera_outside() -> Camera {
    Camera::framing(Vec3::new(0.6, 0.4, 1.0), Vec3::ZERO, 1.6, 45.0)
}

pub fn march_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let map = map();
    let options = MarchOptions { width: 48, height: 40, step: 1.0 };
    let mut out = Vec::new();
    let cameras = [
        ("outside", camera_outside()),
        (
            "inside",
            Camera::look_at(Vec3::new(0.1, 0.2, 0.3), Vec3::new(1.0, -0.5, -2.0), Vec3::Y, 70.0),
        ),
    ];
    for (case, (n, seed, light, kk, m, density)) in cases().into_iter().enumerate() {
        let s = cloud(n, seed, density);
        let spec = spec(light, kk, m);
        let attenuation =
            [Attenuation::BeerLambert, Attenuation::Chapter, Attenuation::Exact][case];
        let settings = BuildSettings { attenuation, ..Default::default() };
        let v = volume::build(&s, &map, &spec, &settings, None, None).map_err(|e| e.to_string())?;
        let uploaded = match &k {
            None => None,
            Some(k) => Some(k.upload(&v).map_err(|e| e.to_string())?),
        };
        for (name, camera) in &cameras {
            let want = match attenuation {
                Attenuation::Exact => render_exact(&v, camera, &options, None),
                _ => render_front_to_back(&v, camera, &options, None),
            }
            .map_err(|e| e.to_string())?;
            let got = match (&k, &uploaded) {
                (Some(k), Some(u)) => {
                    k.render(u, camera, &options, None).map_err(|e| e.to_string())?
                }
                _ => render(&v, camera, &options, None).map_err(|e| e.to_string())?,
            };
            out.push(compare(&format!("volume-march-{case}-{name}"), &got, &want, MARCH_BOUND));
        }
    }
    Ok(Measure::combine(&out))
}

/// One whole frame on `backend`: build with culling and the floor's shadow, march stopping at
/// the floor's depth.
#[allow(clippy::too_many_arguments)]
fn frame(
    k: &Option<VolumeKernels>,
    s: &[DisplacedSphere],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    settings: &BuildSettings,
    camera: &Camera,
    options: &MarchOptions,
    mesh: Option<(&Geometry, &Bvh, &[f32])>,
) -> Result<Image, String> {
    let e = |e: &dyn std::fmt::Display| e.to_string();
    match k {
        None => {
            let view = camera.frame(options.width, options.height);
            let v = volume::build(s, map, spec, settings, Some(&view), mesh.map(|m| m.1))
                .map_err(|x| e(&x))?;
            render(&v, camera, options, mesh.map(|m| m.2)).map_err(|x| e(&x))
        }
        Some(k) => {
            let gpu_bvh = match mesh {
                Some((g, bvh, _)) => Some(upload_bvh(k.context(), bvh, g).map_err(|x| e(&x))?),
                None => None,
            };
            let (img, _, _) = k
                .frame(s, map, spec, settings, gpu_bvh.as_ref(), camera, options, mesh.map(|m| m.2))
                .map_err(|x| e(&x))?;
            Ok(img)
        }
    }
}

/// Depth of the floor per pixel (the mesh's G-buffer depth: distance along the unit ray).
fn depth(bvh: &Bvh, camera: &Camera, options: &MarchOptions) -> Vec<f32> {
    let f = camera.frame(options.width, options.height);
    (0..options.height)
        .flat_map(|y| (0..options.width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let d = f.ray_dir(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            bvh.intersect(f.eye, d, 0.0, f32::INFINITY).map_or(f32::INFINITY, |h| h.t)
        })
        .collect()
}

/// The CPU reference's frame, the oracle of the frame rows.
#[allow(clippy::too_many_arguments)]
fn reference_frame(
    s: &[DisplacedSphere],
    map: &DisplacementMap,
    spec: &VolumeSpec,
    settings: &BuildSettings,
    camera: &Camera,
    options: &MarchOptions,
    mesh: Option<(&Geometry, &Bvh, &[f32])>,
) -> Result<Image, String> {
    frame(&None, s, map, spec, settings, camera, options, mesh)
}

pub fn frame_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let map = map();
    let options = MarchOptions { width: 48, height: 40, step: 1.0 };
    let g = floor();
    let bvh = Bvh::new(&g).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for (case, (n, seed, light, kk, m, density)) in cases().into_iter().enumerate() {
        let s = cloud(n, seed, density);
        let spec = spec(light, kk, m);
        let settings = BuildSettings::default();
        let camera = camera_outside();
        let d = depth(&bvh, &camera, &options);
        let mesh = Some((&g, &bvh, d.as_slice()));
        let want = reference_frame(&s, &map, &spec, &settings, &camera, &options, mesh)?;
        // The CPU backend's frame is the oracle itself; its row checks the oracle against
        // the CPU's front-to-back march of the same build instead.
        let got = match &k {
            None => {
                let view = camera.frame(options.width, options.height);
                let v = volume::build(&s, &map, &spec, &settings, Some(&view), Some(&bvh))
                    .map_err(|e| e.to_string())?;
                render_front_to_back(&v, &camera, &options, Some(&d)).map_err(|e| e.to_string())?
            }
            Some(_) => frame(&k, &s, &map, &spec, &settings, &camera, &options, mesh)?,
        };
        out.push(compare(&format!("volume-frame-{case}"), &got, &want, FRAME_BOUND));
    }
    Ok(Measure::combine(&out))
}
