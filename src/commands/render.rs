//! `voxlod render`: the ground truth of a scene to a PNG (and optionally its G-buffer and a
//! turntable: the ground truth beside the voxel baseline and Averages from an orbiting camera,
//! as an animated PNG in a report).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use glam::Vec3;
use voxlod::cpu::raycast::Bvh;
use voxlod::cpu::render::ground_truth::{self, GBuffer, GTexel};
use voxlod::scene::{Image, Srgb8Image};
use voxlod::studies::turntable::{self, TurntableConfig, TurntableInputs, TurntableResult};

use super::{Ui, backend, load_scene, print_json, write_report};
use crate::cli::{RenderArgs, parse};

#[derive(serde::Serialize)]
struct Summary {
    scene: String,
    triangles: usize,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    bvh_seconds: f64,
    render_seconds: f64,
    rays_per_second: f64,
    backend: String,
    output: String,
    scene_origin: [f64; 3],
    /// With `--turntable`: the report, the animated PNG and the turntable's measurements.
    #[serde(skip_serializing_if = "Option::is_none")]
    turntable: Option<TurntableSummary>,
}

#[derive(serde::Serialize)]
struct TurntableSummary {
    report: String,
    animation: String,
    #[serde(flatten)]
    result: TurntableResult,
}

/// Renders the ground truth of a scene.
pub fn render(ui: &Ui, args: RenderArgs) -> Result<()> {
    let (width, height) = args.size;
    let gpu = backend(args.backend)?;
    let backend_name = super::on(&gpu).describe();
    let spinner = ui.spinner();
    spinner.set_message(format!("loading {}", args.scene));
    let mut scene = load_scene(&args.scene)?;
    let camera = match &args.camera {
        Some(s) => parse::camera(s, scene.default_camera()?, scene.origin)?,
        None => scene.default_camera()?,
    };
    if let Some(light) = args.light {
        scene.lights = vec![light.in_scene(scene.origin)];
    }
    let geometry = scene.geometry();
    spinner.set_message(format!("building the BVH over {} triangles", geometry.triangle_count()));
    let t = Instant::now();
    let bvh = Bvh::new(&geometry)?;
    let bvh_seconds = t.elapsed().as_secs_f64();
    spinner.set_message(format!("rendering {width}×{height} at {} rays per pixel", args.spp));
    let options = ground_truth::Options {
        width,
        height,
        spp: args.spp,
        seed: args.seed,
        ambient: Vec3::splat(0.1),
        shadows: true,
        light_filter: None,
    };
    let (out, render_seconds) = match &gpu {
        None => {
            let t = Instant::now();
            let out = ground_truth::render(&scene, &geometry, &bvh, &camera, &options)?;
            (out, t.elapsed().as_secs_f64())
        }
        Some(ctx) => {
            // Upload (and kernel compilation) outside the timed render, like the BVH build.
            let kernel = voxlod::gpu::ground_truth::GroundTruthKernel::new(ctx)?;
            let uploaded = kernel.upload(&scene, &geometry, &bvh)?;
            let t = Instant::now();
            let out = kernel.render(&uploaded, &camera, &options)?;
            (out, t.elapsed().as_secs_f64())
        }
    };
    spinner.set_message(format!("writing {}", args.output.display()));
    out.image
        .save_png(&args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    if args.gbuffer {
        write_gbuffer(&out.gbuffer, &args.output)?;
    }
    let turntable = match args.turntable {
        None => None,
        Some(frames) => {
            let config = TurntableConfig {
                frames: frames as usize,
                panel: (width, height),
                gt_spp: args.spp,
                seed: args.seed,
                resolution: args.turntable_res,
                rays: args.turntable_rays,
                frame_ms: args.turntable_ms,
                ambient: options.ambient,
            };
            let inputs = TurntableInputs {
                scene: &scene,
                geometry: &geometry,
                bvh: &bvh,
                camera,
                label: &args.scene,
            };
            let progress = |m: &str| spinner.set_message(m.to_string());
            let result = turntable::run(&config, &inputs, super::on(&gpu), &progress)
                .context("rendering the turntable")?;
            let dir = turntable_dir(&args.output);
            spinner.set_message(format!("writing {}", dir.display()));
            let title = format!("Turntable of {}", args.scene);
            let written = write_report(&title, &dir, |r| result.add_to_report(r, "turntable"))?;
            Some(TurntableSummary {
                report: written.markdown.display().to_string(),
                animation: dir.join("assets").join("turntable.png").display().to_string(),
                result,
            })
        }
    };
    spinner.finish_and_clear();
    let rays = width as f64 * height as f64 * args.spp as f64;
    let summary = Summary {
        scene: args.scene,
        triangles: geometry.triangle_count(),
        width,
        height,
        spp: args.spp,
        seed: args.seed,
        bvh_seconds,
        render_seconds,
        rays_per_second: rays / render_seconds,
        backend: backend_name,
        output: args.output.display().to_string(),
        scene_origin: scene.origin.to_array(),
        turntable,
    };
    if args.json {
        return print_json("render", &summary);
    }
    println!("backend: {}", summary.backend);
    if scene.origin != glam::DVec3::ZERO {
        println!(
            "scene origin {} (re-centred; --camera and --light are world coordinates)",
            scene.origin
        );
    }
    println!(
        "{} ({} triangles), {}×{} at {} rays/pixel: BVH {:.3} s, render {:.3} s \
         ({:.2} M camera rays/s, shadow rays extra) → {}",
        summary.scene,
        summary.triangles,
        width,
        height,
        summary.spp,
        bvh_seconds,
        render_seconds,
        summary.rays_per_second / 1e6,
        summary.output
    );
    if let Some(t) = &summary.turntable {
        let r = &t.result;
        println!(
            "turntable: {} frames of {}×{} panels in {:.1} s → {} (report {})",
            r.frames, r.panel[0], r.panel[1], r.elapsed_s, t.animation, t.report
        );
        println!("{}", r.table()?.to_markdown());
    }
    Ok(())
}

/// Where the turntable's report goes: `<stem>-turntable/` next to the output PNG.
fn turntable_dir(output: &Path) -> PathBuf {
    let stem = output.file_stem().and_then(|s| s.to_str()).unwrap_or("render");
    output.with_file_name(format!("{stem}-turntable"))
}

/// Writes `<stem>.depth.png` (normalized distance, near = white), `<stem>.normal.png`
/// (n·0.5+0.5) and `<stem>.albedo.png` next to `output`.
fn write_gbuffer(g: &GBuffer, output: &Path) -> Result<()> {
    let finite = g.texels.iter().map(|t| t.depth).filter(|d| d.is_finite());
    let (near, far) = finite.fold((f32::INFINITY, 0.0f32), |(a, b), d| (a.min(d), b.max(d)));
    let span = (far - near).max(1e-12);
    let to_u8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    let depth = layer(g, |t| {
        let v = if t.depth.is_finite() { 1.0 - (t.depth - near) / span } else { 0.0 };
        [to_u8(v); 3]
    });
    let normal = layer(g, |t| (t.normal * 0.5 + 0.5).to_array().map(to_u8));
    let albedo = Image {
        width: g.width,
        height: g.height,
        pixels: g.texels.iter().map(|t| t.albedo.extend(1.0)).collect(),
    };
    let stem = output.file_stem().and_then(|s| s.to_str()).unwrap_or("render");
    for (name, img) in [("depth", depth), ("normal", normal), ("albedo", albedo.to_srgb8())] {
        let path = output.with_file_name(format!("{stem}.{name}.png"));
        img.save_png(&path).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn layer(g: &GBuffer, f: impl Fn(&GTexel) -> [u8; 3]) -> Srgb8Image {
    Srgb8Image { width: g.width, height: g.height, pixels: g.texels.iter().map(f).collect() }
}
