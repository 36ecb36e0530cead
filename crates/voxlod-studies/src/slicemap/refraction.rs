//! The traversed volume for refraction (Eisemann and Décoret 2006, §3.3): the thickness an eye
//! ray travels through a closed object, from front and back slicemaps, against the exact
//! in/out interval lengths by ray casting; and the paper's three effects driven by it.
//!
//! Front- and back-facing triangles go into two layers of one locally sliced map from the
//! camera; per pixel, the Fig. 9 rules count the inner voxels
//! ([`voxlod_cpu::voxelize::slicemap::query`]) and the thickness is their number times the
//! column's slice depth over the cosine of the ray. The exact thickness sums the intervals
//! between entering and leaving hits of the pixel-centre ray
//! ([`voxlod_cpu::voxelize::slicemap::shadow::traversed_length`]). The "two depth maps" row is
//! the estimate the paper improves on: the distance between the nearest and the farthest
//! surface (the column's local range), right only for convex objects.
//!
//! # The effects (one shading model, three inputs)
//! Every pixel that sees the object takes its first hit's position and normal from the
//! G-buffer (ray cast, identical for all methods); only the thickness `L` differs. With `r` the
//! object's bounding radius and `d` the ray:
//! - refraction: the ray leaves toward `normalize(d − bend·(L/r)·n_t)` (`n_t` the normal's part
//!   across the ray) to a checkerboard plane behind the object;
//! - attenuation: the background is weighted by `exp(−absorption·L/r)`, the rest is the
//!   object's tint;
//! - frosted glass: the checkerboard is averaged over a disc of radius `blur·L` on the plane
//!   (the paper reads a coarser level of a mip pyramid), 32 fixed samples.
//!
//! The reference image is the same model with the exact thickness, so the image error measures
//! the thickness alone.

use glam::{DVec2, Vec2, Vec3};
use serde::Serialize;
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth::{self, GBuffer};
use voxlod_cpu::voxelize::slicemap::shadow::traversed_length;
use voxlod_cpu::voxelize::slicemap::{self as sm, Faces, Options, SliceCamera, Slicing};
use voxlod_cpu::voxelize::{self as vox, Mode};
use voxlod_eval::heatmap::error_heatmap;
use voxlod_eval::metrics::{ImageMetrics, compare};
use voxlod_format::GridSpec;
use voxlod_gpu::slicemap::SlicemapRenderer;
use voxlod_gpu::slicemap::query::SlicemapQueries;
use voxlod_scene::{Image, Scene, Srgb8Image};

use super::{Timing, time};
use crate::Error;

/// What the refraction part measures.
#[derive(Clone, Debug, PartialEq)]
pub struct RefractionConfig {
    /// Scene spec (a closed mesh).
    pub scene: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Slice counts of the front/back maps.
    pub slices: Vec<u32>,
    /// Slice count whose effect images are shown.
    pub shown_slices: u32,
    /// Views: the scene's camera orbited about the vertical axis (their pixels pooled).
    pub views: u32,
    /// Bending of the refracted ray per unit of `L/r`.
    pub bend: f32,
    /// Absorption per unit of `L/r`.
    pub absorption: f32,
    /// Frosted-glass blur radius per unit of thickness.
    pub blur: f32,
    /// Checkerboard squares across the image's width on the background plane.
    pub checker: u32,
    /// Timed runs per figure.
    pub repeats: u32,
}

/// The thickness of one method against the exact one.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ThicknessRow {
    /// Method.
    pub method: String,
    /// Slices (slicemap rows).
    pub slices: Option<u32>,
    /// Mean absolute error over pixels where either thickness is non-zero (world units).
    pub mean_abs_error: f64,
    /// The mean absolute error over the mean exact thickness.
    pub relative_error: f64,
    /// 95th percentile of the absolute error.
    pub p95_abs_error: f64,
    /// Largest absolute error.
    pub max_abs_error: f64,
    /// Pixels whose error exceeds the depth of one of their column's slices, fraction.
    pub over_one_slice: Option<f64>,
    /// CPU time: maps and per-pixel thickness, ms.
    pub cpu_ms: Timing,
    /// GPU-path time: maps and the inner-voxel kernel, ms.
    pub gpu_ms: Option<Timing>,
}

/// One effect's image for one method against the reference.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EffectRow {
    /// Effect (refraction, attenuation, frosted glass).
    pub effect: String,
    /// Method.
    pub method: String,
    /// Against the image with the exact thickness.
    pub image: ImageMetrics,
}

/// The refraction part's results.
#[derive(Clone, Debug)]
pub struct RefractionResult {
    /// Scene spec.
    pub scene: String,
    /// Boundary edges of the mesh (0: closed).
    pub boundary_edges: u64,
    /// Pixels whose ray meets the object, over all views.
    pub pixels: usize,
    /// Views measured.
    pub views: u32,
    /// Mean exact thickness over them.
    pub mean_thickness: f64,
    /// Thickness rows: two depth maps, then one per slice count.
    pub thickness: Vec<ThicknessRow>,
    /// Effect rows.
    pub effects: Vec<EffectRow>,
    /// Images: label and picture.
    pub images: Vec<(String, Srgb8Image)>,
}

/// Golden-angle disc samples in the unit disc.
fn disc(n: u32) -> Vec<Vec2> {
    (0..n)
        .map(|k| {
            let r = ((k as f32 + 0.5) / n as f32).sqrt();
            let a = k as f32 * 2.399_963;
            Vec2::new(r * a.cos(), r * a.sin())
        })
        .collect()
}

/// The shading model of the module docs.
struct Effects<'a> {
    config: &'a RefractionConfig,
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    plane: f32,
    square: f32,
    radius: f32,
    disc: Vec<Vec2>,
}

#[derive(Clone, Copy, PartialEq)]
enum Effect {
    Refraction,
    Attenuation,
    Frosted,
}

impl Effects<'_> {
    fn checker(&self, p: Vec3) -> Vec3 {
        let d = p - self.eye;
        let (u, v) = (d.dot(self.right) / self.square, d.dot(self.up) / self.square);
        if (u.floor() as i64 + v.floor() as i64).rem_euclid(2) == 0 {
            Vec3::new(0.85, 0.85, 0.8)
        } else {
            Vec3::new(0.12, 0.14, 0.2)
        }
    }

    /// Where the ray `o + t·d` meets the background plane.
    fn on_plane(&self, o: Vec3, d: Vec3) -> Vec3 {
        let depth = (o - self.eye).dot(self.forward);
        let t = (self.plane - depth) / d.dot(self.forward).max(0.05);
        o + d * t
    }

    fn shade(&self, effect: Effect, dir: Vec3, hit: Option<(Vec3, Vec3)>, l: f32) -> Vec3 {
        let Some((p, n)) = hit else { return self.checker(self.on_plane(self.eye, dir)) };
        let c = self.config;
        let s = l / self.radius;
        match effect {
            Effect::Refraction => {
                let nt = n - dir * n.dot(dir);
                let d = (dir - nt * (c.bend * s)).normalize();
                self.checker(self.on_plane(p, d))
            }
            Effect::Attenuation => {
                let a = (-c.absorption * s).exp();
                self.checker(self.on_plane(p, dir)) * a + Vec3::new(0.55, 0.25, 0.1) * (1.0 - a)
            }
            Effect::Frosted => {
                let nt = n - dir * n.dot(dir);
                let d = (dir - nt * (0.25 * c.bend * s)).normalize();
                let q = self.on_plane(p, d);
                let rho = c.blur * l;
                let sum: Vec3 = self
                    .disc
                    .iter()
                    .map(|o| self.checker(q + (self.right * o.x + self.up * o.y) * rho))
                    .sum();
                sum / self.disc.len() as f32
            }
        }
    }

    fn image(&self, effect: Effect, gb: &GBuffer, dirs: &[Vec3], thickness: &[f32]) -> Srgb8Image {
        let mut img = Image::new(gb.width, gb.height, glam::Vec4::ONE);
        for (i, t) in gb.texels.iter().enumerate() {
            let hit = (t.triangle != u32::MAX).then_some((t.position, t.normal));
            img.pixels[i] = self.shade(effect, dirs[i], hit, thickness[i]).extend(1.0);
        }
        img.to_srgb8()
    }
}

fn grey(values: &[f32], max: f32, width: u32, height: u32) -> Srgb8Image {
    let mut img = Srgb8Image::new(width, height, [0, 0, 0]);
    for (p, &v) in img.pixels.iter_mut().zip(values) {
        let g = (255.0 * (v / max.max(1e-30)).clamp(0.0, 1.0)) as u8;
        *p = [g, g, g];
    }
    img
}

fn row(
    method: String,
    slices: Option<u32>,
    test: &[f32],
    exact: &[f32],
    slice: Option<&[f32]>,
) -> ThicknessRow {
    let mut errs = Vec::new();
    let (mut over, mut sum_exact) = (0usize, 0.0f64);
    for i in 0..exact.len() {
        if exact[i] > 0.0 || test[i] > 0.0 {
            let e = (test[i] as f64 - exact[i] as f64).abs();
            errs.push(e);
            sum_exact += exact[i] as f64;
            if let Some(s) = slice
                && e > s[i] as f64
            {
                over += 1;
            }
        }
    }
    let n = errs.len().max(1) as f64;
    let mean = errs.iter().sum::<f64>() / n;
    errs.sort_by(f64::total_cmp);
    let p95 = errs
        .get(((errs.len() as f64 * 0.95) as usize).min(errs.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    ThicknessRow {
        method,
        slices,
        mean_abs_error: mean,
        relative_error: mean / (sum_exact / n).max(1e-30),
        p95_abs_error: p95,
        max_abs_error: errs.last().copied().unwrap_or(0.0),
        over_one_slice: slice.map(|_| over as f64 / n),
        cpu_ms: Timing::default(),
        gpu_ms: None,
    }
}

/// One view's measurements: per slice count the thickness and slice depth per pixel, the two
/// depth maps', the exact one, and the images and effect metrics of the shown slice count.
struct View {
    exact: Vec<f32>,
    two: Vec<f32>,
    sliced: Vec<(u32, Vec<f32>, Vec<f32>)>,
    timings: Vec<(Timing, Option<Timing>)>,
    effects: Vec<(String, String, ImageMetrics)>,
    images: Vec<(String, Srgb8Image)>,
}

#[allow(clippy::too_many_arguments)]
fn view(
    c: &RefractionConfig,
    scene: &Scene,
    g: &voxlod_scene::Geometry,
    bvh: &Bvh,
    camera: &voxlod_scene::Camera,
    first: bool,
    gpu: Option<(&SlicemapRenderer, &SlicemapQueries)>,
    progress: &dyn Fn(&str),
) -> Result<View, Error> {
    let (lo, hi) = scene.bounds()?;
    let (w, h) = (c.width, c.height);
    let gb = ground_truth::gbuffer(scene, g, bvh, camera, w, h)?;
    let cam: SliceCamera = camera_through(camera, scene, w, h)?;
    let frame = cam.frame();
    let forward = frame.forward.as_vec3();
    let rays: Vec<(Vec3, Vec3)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (o, d) = frame.ray(DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
            (o.as_vec3(), d.as_vec3())
        })
        .collect();
    let exact: Vec<f32> = rays.iter().map(|&(o, d)| traversed_length(bvh, g, o, d, 0.0)).collect();
    let repeats = if first { c.repeats.max(1) } else { 1 };
    let mut out = View {
        exact,
        two: Vec::new(),
        sliced: Vec::new(),
        timings: Vec::new(),
        effects: Vec::new(),
        images: Vec::new(),
    };
    for &slices in &c.slices {
        progress(&format!("slicemap refraction: {slices} slices"));
        let o =
            Options { slices, slicing: Slicing::Local, faces: Faces::Split, ..Options::default() };
        let per_pixel = |map: &sm::Slicemap, inner: &dyn Fn(u32, u32) -> u32| {
            let mut t = vec![0f32; (w * h) as usize];
            let mut slice = vec![0f32; (w * h) as usize];
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    if let Some((lo, hi)) = map.range(x, y) {
                        let depth = (hi - lo) / slices as f32 / rays[i].1.dot(forward);
                        t[i] = inner(x, y) as f32 * depth;
                        slice[i] = depth;
                    }
                }
            }
            (t, slice)
        };
        let ((t, slice, map), cpu_ms) = time(repeats, || {
            let map = sm::build(g, &cam, &o)?;
            let (t, slice) = per_pixel(&map, &|x, y| map.inner_voxels(x, y).unwrap_or(0));
            Ok((t, slice, map))
        })?;
        let gpu_ms = match (gpu, first) {
            (Some((r, q)), true) => Some(
                time(repeats, || {
                    let map = r.build(g, &cam, &o)?;
                    let inner = q.inner_voxels(&map)?;
                    Ok(per_pixel(&map, &|x, y| inner[(y * w + x) as usize]))
                })?
                .1,
            ),
            _ => None,
        };
        if out.two.is_empty() {
            // The two-depth-map estimate from the same local ranges.
            out.two = (0..(w * h) as usize)
                .map(|i| {
                    let (x, y) = (i as u32 % w, i as u32 / w);
                    map.range(x, y).map_or(0.0, |(lo, hi)| (hi - lo) / rays[i].1.dot(forward))
                })
                .collect();
        }
        out.sliced.push((slices, t, slice));
        out.timings.push((cpu_ms, gpu_ms));
    }
    // The shown slice count, or the last one measured.
    let (shown, sliced, _) = out
        .sliced
        .iter()
        .find(|(n, _, _)| *n == c.shown_slices)
        .or(out.sliced.last())
        .cloned()
        .expect("validated: at least one slice count");
    let dirs: Vec<Vec3> = rays.iter().map(|r| r.1).collect();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let eye = frame.eye.as_vec3();
    let plane = (centre - eye).dot(forward) + 1.5 * radius;
    let tan = (camera.fov_y_deg.to_radians() * 0.5).tan();
    let width_on_plane = 2.0 * plane * tan * w as f32 / h as f32;
    let fx = Effects {
        config: c,
        eye,
        forward,
        right: frame.right.as_vec3(),
        up: frame.up.as_vec3(),
        plane,
        square: width_on_plane / c.checker.max(1) as f32,
        radius,
        disc: disc(32),
    };
    let exact = &out.exact;
    if first {
        let max_l = exact.iter().copied().fold(0.0, f32::max);
        let err: Vec<f32> = exact.iter().zip(&sliced).map(|(a, b)| (a - b).abs()).collect();
        out.images = vec![
            ("L exact".to_string(), grey(exact, max_l, w, h)),
            ("L two depths".to_string(), grey(&out.two, max_l, w, h)),
            (format!("L slicemap {shown}"), grey(&sliced, max_l, w, h)),
            ("L error x10".to_string(), grey(&err, max_l * 0.1, w, h)),
        ];
    }
    for (name, short, effect) in [
        ("refraction", "refract", Effect::Refraction),
        ("attenuation", "absorb", Effect::Attenuation),
        ("frosted glass", "frost", Effect::Frosted),
    ] {
        let reference = fx.image(effect, &gb, &dirs, exact);
        let slicemap = fx.image(effect, &gb, &dirs, &sliced);
        let depth = fx.image(effect, &gb, &dirs, &out.two);
        let method = format!("slicemap, {shown} slices");
        out.effects.push((name.into(), method, compare(&slicemap, &reference)?));
        out.effects.push((name.into(), "two depth maps".into(), compare(&depth, &reference)?));
        if first {
            let heat = error_heatmap(&slicemap, &reference, 0.1)?;
            out.images.push((format!("{short} exact"), reference));
            out.images.push((format!("{short} slicemap"), slicemap));
            out.images.push((format!("{short} two depths"), depth));
            out.images.push((format!("{short} err x10"), heat));
        }
    }
    Ok(out)
}

/// A perspective map through `camera`, its depth range the scene's bounding sphere.
fn camera_through(
    camera: &voxlod_scene::Camera,
    scene: &Scene,
    width: u32,
    height: u32,
) -> Result<SliceCamera, Error> {
    let (lo, hi) = scene.bounds()?;
    let c = ((lo + hi) * 0.5).as_dvec3();
    let r = ((hi - lo).length() * 0.5) as f64;
    let forward = (camera.target - camera.eye).as_dvec3().normalize_or_zero();
    let depth = (c - camera.eye.as_dvec3()).dot(forward);
    let far = (depth + r) * 1.001;
    let near = (depth - r).max(far * 1e-3);
    Ok(SliceCamera::from_camera(camera, width, height, near, far))
}

/// Runs the refraction part (module docs): every view's pixels pooled in the error rows, the
/// effects' metrics averaged over the views, times and images from the first view.
pub fn run(
    config: &RefractionConfig,
    gpu: Option<(&SlicemapRenderer, &SlicemapQueries)>,
    progress: &dyn Fn(&str),
) -> Result<RefractionResult, Error> {
    let c = config;
    progress(&format!("slicemap refraction: {}", c.scene));
    let scene: Scene = crate::scenes::load(&c.scene)?;
    let g = scene.geometry();
    let (lo, hi) = scene.bounds()?;
    let small = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 16)?;
    let solid = vox::Options { mode: Mode::Solid, triangle_lists: false, ..Default::default() };
    let boundary_edges = vox::voxelize(&g, &small, &solid)?.boundary_edges.unwrap_or(0);
    let bvh = Bvh::new(&g)?;
    let cameras =
        crate::views::orbit_views(scene.default_camera()?, (lo + hi) * 0.5, c.views as usize);
    let mut views = Vec::new();
    for (k, camera) in cameras.iter().enumerate() {
        progress(&format!("slicemap refraction: view {}", k + 1));
        views.push(view(c, &scene, &g, &bvh, camera, k == 0, gpu, progress)?);
    }
    let exact: Vec<f32> = views.iter().flat_map(|v| v.exact.iter().copied()).collect();
    let pixels = exact.iter().filter(|&&l| l > 0.0).count();
    if pixels == 0 {
        return Err(Error::NothingToMeasure {
            scene: c.scene.clone(),
            why: "no pixel's ray passes through the object".into(),
        });
    }
    let mean_thickness = exact.iter().map(|&l| l as f64).sum::<f64>() / pixels as f64;
    let two: Vec<f32> = views.iter().flat_map(|v| v.two.iter().copied()).collect();
    let mut thickness = vec![row("two depth maps (far − near)".into(), None, &two, &exact, None)];
    for (i, &slices) in c.slices.iter().enumerate() {
        let t: Vec<f32> = views.iter().flat_map(|v| v.sliced[i].1.iter().copied()).collect();
        let s: Vec<f32> = views.iter().flat_map(|v| v.sliced[i].2.iter().copied()).collect();
        let mut r = row(format!("slicemap, {slices} slices"), Some(slices), &t, &exact, Some(&s));
        (r.cpu_ms, r.gpu_ms) = views[0].timings[i];
        thickness.push(r);
    }
    let n = views.len() as f64;
    let effects = (0..views[0].effects.len())
        .map(|i| {
            let (effect, method, _) = views[0].effects[i].clone();
            let mse = views.iter().map(|v| v.effects[i].2.mse).sum::<f64>() / n;
            let ssim = views.iter().map(|v| v.effects[i].2.ssim).sum::<f64>() / n;
            let psnr = if mse > 0.0 { 10.0 * (1.0 / mse).log10() } else { f64::INFINITY };
            EffectRow { effect, method, image: ImageMetrics { mse, psnr, ssim } }
        })
        .collect();
    let images = std::mem::take(&mut views[0].images);
    Ok(RefractionResult {
        scene: c.scene.clone(),
        boundary_edges,
        pixels,
        views: cameras.len() as u32,
        mean_thickness,
        thickness,
        effects,
        images,
    })
}
