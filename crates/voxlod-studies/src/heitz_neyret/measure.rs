//! The study's pipeline (module docs of [`super`]): records, octrees, the renders per zoom and
//! their measures.

use std::time::Instant;

use glam::{Vec3, Vec4};
use voxlod_cone::{
    Compositing, DepthOfField, DifferentialOptions, DifferentialRenderer, Light, PinholeCamera,
    PrimaryOptions, PrimaryRenderer, ShadeInput, SurfaceMedium, SurfaceShadeInput,
};
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::{averages, microsurface};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_cpu::shading::shade;
use voxlod_cpu::voxelize;
use voxlod_format::GridSpec;
use voxlod_gpu::differential::{DifferentialKernel, GpuMicrosurfaceOctree, shade_element};
use voxlod_octree::{AveragePayload, BuildOptions, Directional, MicrosurfacePayload, Octree};
use voxlod_scene::{Camera, Image, MaterialSample, Scene, Srgb8Image};

use super::{
    DepthOfFieldResult, GrazingBin, HeitzNeyretConfig, HeitzNeyretResult, Method, MethodRow,
    Representation, SceneCase, SceneResult, TimeRange, ZoomResult,
};
use crate::Error;
use crate::backend::Backend;
use crate::ground_truths::{SeededTruth, seeded_truth};

/// Ambient term of the voxel shading and the ground truth (as the other studies use).
const AMBIENT: f32 = 0.1;

/// `μ = |v·n|` bin edges of the grazing-colour measure.
const MU_BINS: [f32; 5] = [0.0, 0.1, 0.25, 0.5, 1.0];

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// An RGBA image from a renderer's linear pixels.
fn image(width: u32, height: u32, pixels: &[Vec4]) -> Image {
    let mut out = Image::new(width, height, Vec4::ZERO);
    out.pixels.copy_from_slice(pixels);
    out
}

/// What one scene's renders share.
struct Frame<'a> {
    scene: &'a Scene,
    micro: &'a Octree<MicrosurfacePayload>,
    averages: &'a Octree<AveragePayload>,
    directional: &'a Octree<Directional<AveragePayload>>,
    light: Light,
    /// The Averages baseline's specular lobe: the scene's single material's, else none.
    lobe: (Vec3, f32),
    repeats: u32,
}

/// A rendered image with its work.
struct Rendered {
    image: Image,
    elements: u64,
    shadow_elements: u64,
    cpu: TimeRange,
}

/// Runs `f` `repeats` times: its last result and the min and max wall time.
fn timed<T>(repeats: u32, mut f: impl FnMut() -> T) -> (T, TimeRange) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    let mut out = None;
    for _ in 0..repeats {
        let t = Instant::now();
        out = Some(f());
        let e = ms(t);
        (lo, hi) = (lo.min(e), hi.max(e));
    }
    (out.expect("at least one repeat"), TimeRange { min_ms: lo, max_ms: hi })
}

impl Frame<'_> {
    fn differential(
        &self,
        camera: PinholeCamera,
        options: DifferentialOptions,
        mean_colour: bool,
    ) -> Result<Rendered, Error> {
        let r = DifferentialRenderer::new(self.micro, camera, self.light, options)?;
        let light = self.light;
        let ambient = Vec3::splat(AMBIENT);
        let shader = |s: &SurfaceShadeInput| {
            if mean_colour {
                let mut m = *s;
                m.illumination.albedo = s.illumination.mean_albedo;
                m.illumination.ambient_albedo = s.illumination.mean_albedo;
                shade_element(&m, &light, ambient)
            } else {
                shade_element(s, &light, ambient)
            }
        };
        let (img, cpu) = timed(self.repeats, || r.render(&shader));
        Ok(Rendered {
            image: image(img.width, img.height, &img.pixels),
            elements: img.elements,
            shadow_elements: img.shadow_elements,
            cpu,
        })
    }

    fn primary<M: SurfaceMedium>(
        &self,
        tree: &Octree<M>,
        camera: PinholeCamera,
    ) -> Result<Rendered, Error> {
        let o = PrimaryOptions { background: self.scene.background, ..PrimaryOptions::default() };
        let r = PrimaryRenderer::new(tree, camera, self.light, o)?;
        let light = self.scene.light();
        let (specular, shininess) = self.lobe;
        let shader = |s: &ShadeInput| {
            let m = MaterialSample { albedo: s.albedo, alpha: 1.0, specular, shininess };
            shade(
                &m,
                s.normal,
                s.to_viewer,
                &light.sample(s.position),
                s.visibility,
                Vec3::splat(AMBIENT),
            )
        };
        let (img, cpu) = timed(self.repeats, || r.render(&shader));
        Ok(Rendered {
            image: image(img.width, img.height, &img.pixels),
            elements: img.samples,
            shadow_elements: img.shadow_samples,
            cpu,
        })
    }

    fn method(&self, m: Method, camera: PinholeCamera) -> Result<Rendered, Error> {
        let o = DifferentialOptions { background: self.scene.background, ..Default::default() };
        match m {
            Method::Masks => self.differential(camera, o, false),
            Method::MasksMeanColour => self.differential(camera, o, true),
            Method::Blending => self.differential(
                camera,
                DifferentialOptions { compositing: Compositing::AlphaBlending, ..o },
                false,
            ),
            Method::Averages => self.primary(self.averages, camera),
            Method::AveragesDirectional => self.primary(self.directional, camera),
        }
    }
}

fn pinhole(c: &Camera, size: u32) -> PinholeCamera {
    PinholeCamera {
        eye: c.eye,
        target: c.target,
        up: c.up,
        fov_y_deg: c.fov_y_deg,
        width: size,
        height: size,
    }
}

/// Coverage measures of `a` against the truth `t` (module docs of [`super`]): silhouette
/// thickness in pixels and coverage excess; and the edge pixel count.
fn coverage(a: &Image, t: &Image) -> (f64, f64, usize) {
    let sum = |img: &Image| img.pixels.iter().map(|p| p.w as f64).sum::<f64>();
    let edge = t.pixels.iter().filter(|p| (0.05..=0.95).contains(&p.w)).count();
    let (sa, st) = (sum(a), sum(t));
    ((sa - st) / edge.max(1) as f64, (sa - st) / st.max(1e-9), edge)
}

/// The grazing-colour bins of a zoom (module docs of [`super`]).
fn grazing(
    truth: &ground_truth::GroundTruth,
    camera: &Camera,
    centre: Vec3,
    background: Vec3,
    images: &[Image],
) -> Vec<GrazingBin> {
    // A method's colour where it covers the pixel: the background it composited taken out
    // (a silhouette a fraction of a pixel thinner must not read as a colour error).
    let colour = |p: Vec4| {
        if p.w > 0.05 { (p.truncate() - (1.0 - p.w) * background) / p.w } else { p.truncate() }
    };
    let mut bins: Vec<GrazingBin> = MU_BINS
        .windows(2)
        .map(|w| GrazingBin {
            mu_min: w[0],
            mu_max: w[1],
            pixels: 0,
            truth_rgb: [0.0; 3],
            method_rgb: vec![[0.0; 3]; images.len()],
        })
        .collect();
    let mut sums = vec![(Vec3::ZERO, vec![Vec3::ZERO; images.len()]); bins.len()];
    for (i, texel) in truth.gbuffer.texels.iter().enumerate() {
        if texel.triangle == u32::MAX || truth.image.pixels[i].w < 0.999 {
            continue;
        }
        let n = (texel.position - centre).normalize_or_zero();
        let v = (camera.eye - texel.position).normalize_or_zero();
        let mu = n.dot(v).abs();
        let Some(b) = bins.iter().position(|b| mu >= b.mu_min && mu <= b.mu_max) else {
            continue;
        };
        bins[b].pixels += 1;
        sums[b].0 += truth.image.pixels[i].truncate();
        for (k, img) in images.iter().enumerate() {
            sums[b].1[k] += colour(img.pixels[i]);
        }
    }
    for (b, (t, m)) in bins.iter_mut().zip(sums) {
        let n = b.pixels.max(1) as f32;
        b.truth_rgb = (t / n).to_array();
        b.method_rgb = m.iter().map(|c| (*c / n).to_array()).collect();
    }
    bins
}

/// The GPU side of a scene: the kernel and the uploaded octree.
struct Gpu<'a> {
    kernel: DifferentialKernel<'a>,
    tree: GpuMicrosurfaceOctree,
}

fn run_scene(
    case: &SceneCase,
    config: &HeitzNeyretConfig,
    backend: Backend<'_>,
    want_dof: bool,
    say: &dyn Fn(&str),
) -> Result<(SceneResult, Option<DepthOfFieldResult>), Error> {
    let scene = crate::scenes::load(&case.spec)?;
    let geometry = scene.geometry();
    let bvh = Bvh::new(&geometry)?;
    let (lo, hi) = scene.bounds()?;
    let centre = (lo + hi) * 0.5;
    say(&format!("{}: voxelizing at {}³ and fitting records", case.label, config.resolution));
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), config.resolution)?;
    let vox = voxelize::voxelize(&geometry, &grid, &voxelize::Options::default())?;
    let ctx = SamplingContext::new(&scene, &geometry, &vox)?;
    let popts = PrecomputeOptions { rays: config.rays, seed: 0 };
    let t = Instant::now();
    let micro_records = precompute(&ctx, &popts, microsurface::fit)?;
    let micro_fit = ms(t);
    let t = Instant::now();
    let avg_records = precompute(&ctx, &popts, averages::fit)?;
    let avg_fit = ms(t);
    // Dense top levels down to 8³ only: at small resolutions the default 64³ would be the
    // whole octree and hide what the payloads cost per voxel.
    let build = BuildOptions { depth: None, dense_log2: 3 };
    let t = Instant::now();
    let micro = Octree::from_brick_map(
        grid,
        &micro_records.records,
        MicrosurfacePayload::from_record,
        &build,
    )?;
    let micro_build = ms(t);
    let t = Instant::now();
    let averages =
        Octree::from_brick_map(grid, &avg_records.records, AveragePayload::from_record, &build)?;
    let avg_build = ms(t);
    let directional: Octree<Directional<AveragePayload>> = Octree::from_brick_map(
        grid,
        &avg_records.records,
        |r| Directional::isotropic(AveragePayload::from_record(r)),
        &build,
    )?;
    let representation =
        |name: &str, s: voxlod_octree::MemoryStats, node, fit, build| Representation {
            name: name.into(),
            payload_bytes_per_node: node,
            payload_bytes_per_voxel: s.per_voxel(s.payload_bytes),
            total_bytes_per_voxel: s.per_voxel(s.total_bytes()),
            fit_ms: fit,
            build_ms: build,
        };
    let representations = vec![
        representation(
            "Heitz–Neyret",
            micro.memory_stats(),
            size_of::<MicrosurfacePayload>(),
            micro_fit,
            micro_build,
        ),
        representation(
            "Averages",
            averages.memory_stats(),
            size_of::<AveragePayload>(),
            avg_fit,
            avg_build,
        ),
    ];
    let lobe = match scene.materials.as_slice() {
        [m] => (m.specular, m.shininess),
        _ => (Vec3::ZERO, 0.0),
    };
    let frame = Frame {
        scene: &scene,
        micro: &micro,
        averages: &averages,
        directional: &directional,
        light: crate::scenes::cone_light(scene.light()),
        lobe,
        repeats: config.repeats,
    };
    let gpu = match backend {
        Backend::Cpu => None,
        Backend::Gpu(ctx) => {
            let kernel = DifferentialKernel::new(ctx);
            let tree = kernel.upload(&micro)?;
            Some(Gpu { kernel, tree })
        }
    };
    let size = config.image_size;
    let pixels = (size as f64).powi(2);
    let base = scene.default_camera()?;
    let mut zooms = Vec::new();
    let mut images = Vec::new();
    for &zoom in &config.zooms {
        say(&format!("{}: zoom {zoom}", case.label));
        let mut camera = base;
        camera.eye = camera.target + (camera.eye - camera.target) * zoom;
        let gt = ground_truth::Options {
            width: size,
            height: size,
            spp: config.spp,
            seed: 0,
            ambient: Vec3::splat(AMBIENT),
            shadows: true,
            light_filter: None,
        };
        let SeededTruth { truth, srgb8: truth8, ms: truth_ms, seed_mse: truth_seed_mse } =
            seeded_truth(&scene, &geometry, &bvh, &camera, &gt)?;
        let cam = pinhole(&camera, size);
        let probe = DifferentialRenderer::new(&micro, cam, frame.light, Default::default())?;
        let footprint_voxels =
            probe.footprint_voxels(centre.distance(camera.eye) / grid.voxel_size as f32);
        images.push((format!("{} ×{zoom}: mesh", case.label), truth8.clone()));
        let mut rows = Vec::new();
        let mut rendered = Vec::new();
        let mut edge_pixels = 0;
        let covered: f64 = truth.image.pixels.iter().map(|p| p.w as f64).sum();
        let per_covered = |ms: f64| ms * 1e3 / covered.max(1.0);
        for m in Method::ALL {
            let r = frame.method(m, cam)?;
            let img8 = r.image.to_srgb8();
            let c = voxlod_eval::compare(&img8, &truth8)?;
            let (thickness, excess, edge) = coverage(&r.image, &truth.image);
            edge_pixels = edge;
            let (mut gpu_time, mut gpu_us, mut gpu_step) = (None, None, None);
            if let (Method::Masks, Some(g)) = (m, &gpu) {
                let renderer = DifferentialRenderer::new(
                    &micro,
                    cam,
                    frame.light,
                    DifferentialOptions { background: scene.background, ..Default::default() },
                )?;
                // One untimed frame first: a driver may compile the pipeline on first use.
                g.kernel.render(&g.tree, &renderer, Vec3::splat(AMBIENT))?;
                let (res, range) = timed(config.repeats, || {
                    g.kernel.render(&g.tree, &renderer, Vec3::splat(AMBIENT))
                });
                let (gimg, _) = res?;
                gpu_step = Some(worst_step(&gimg.to_srgb8(), &img8));
                gpu_us = Some(per_covered(range.min_ms));
                gpu_time = Some(range);
            }
            rows.push(MethodRow {
                method: m,
                mse: c.mse,
                ssim: c.ssim,
                silhouette_thickness_px: thickness,
                coverage_excess: excess,
                elements_per_pixel: r.elements as f64 / pixels,
                shadow_elements_per_pixel: r.shadow_elements as f64 / pixels,
                cpu: r.cpu,
                cpu_us_per_covered_pixel: per_covered(r.cpu.min_ms),
                gpu: gpu_time,
                gpu_us_per_covered_pixel: gpu_us,
                gpu_worst_step: gpu_step,
            });
            images.push((format!("{} ×{zoom}: {}", case.label, m.label()), img8));
            rendered.push(r.image);
        }
        let grazing = if case.radial {
            grazing(&truth, &camera, centre, scene.background, &rendered)
        } else {
            Vec::new()
        };
        zooms.push(ZoomResult {
            zoom,
            footprint_voxels,
            edge_pixels,
            covered_pixels: covered,
            truth_ms,
            truth_seed_mse,
            truth_error_mse: truth_seed_mse / 2.0,
            rows,
            grazing,
        });
    }
    let dof = if want_dof { Some(depth_of_field(&frame, case, &base, size)?) } else { None };
    Ok((
        SceneResult {
            case: case.clone(),
            triangles: scene.triangle_count(),
            resolution: config.resolution,
            voxels: micro.voxel_count(),
            depth: micro.depth(),
            representations,
            zooms,
            images,
        },
        dof,
    ))
}

/// The largest difference of any channel of any pixel, 8-bit sRGB steps.
fn worst_step(a: &Srgb8Image, b: &Srgb8Image) -> u8 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0))
        .max()
        .unwrap_or(0)
}

/// A thin lens focused halfway between the eye and the target, radius 2 % of their distance:
/// the scene out of focus. Total coverage with the lens over the pinhole's, masks and blending.
fn depth_of_field(
    frame: &Frame,
    case: &SceneCase,
    camera: &Camera,
    size: u32,
) -> Result<DepthOfFieldResult, Error> {
    let cam = pinhole(camera, size);
    let distance = camera.eye.distance(camera.target);
    let lens = DepthOfField { lens_radius: 0.02 * distance, focus_distance: 0.5 * distance };
    let base = DifferentialOptions { background: frame.scene.background, ..Default::default() };
    let coverage = |c: Compositing, dof: Option<DepthOfField>| -> Result<f64, Error> {
        let o = DifferentialOptions { compositing: c, depth_of_field: dof, shadows: false, ..base };
        let r = DifferentialRenderer::new(frame.micro, cam, frame.light, o)?;
        let img = r.render(&|s: &SurfaceShadeInput| s.illumination.albedo);
        Ok(img.pixels.iter().map(|p| p.w as f64).sum())
    };
    let ratio =
        |c| -> Result<f64, Error> { Ok(coverage(c, Some(lens))? / coverage(c, None)?.max(1e-9)) };
    Ok(DepthOfFieldResult {
        scene: case.label.clone(),
        lens_radius: lens.lens_radius,
        focus_distance: lens.focus_distance,
        masks_coverage_ratio: ratio(Compositing::CoverageMasks)?,
        blending_coverage_ratio: ratio(Compositing::AlphaBlending)?,
    })
}

/// Runs the study; `say` receives a short message at each stage.
pub fn run(
    config: &HeitzNeyretConfig,
    backend: Backend<'_>,
    say: &dyn Fn(&str),
) -> Result<HeitzNeyretResult, Error> {
    config.validate()?;
    let mut scenes = Vec::new();
    let mut dof = None;
    for case in &config.scenes {
        let want_dof = config.depth_of_field && case.in_domain && dof.is_none();
        let (s, d) = run_scene(case, config, backend, want_dof, say)?;
        scenes.push(s);
        dof = dof.or(d);
    }
    Ok(HeitzNeyretResult {
        backend: backend.describe(),
        machine: crate::machine::describe(),
        image_size: config.image_size,
        spp: config.spp,
        rays: config.rays,
        scenes,
        depth_of_field: dof,
    })
}
