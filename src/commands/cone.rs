//! `voxlod cone <scene>`: voxel cone tracing (AO and one-bounce diffuse indirect light) on the
//! sparse voxel octree against ray-traced references on the mesh, over cone count × aperture ×
//! octree depth × step length; and the light-leaking experiment (a wall of known thickness
//! between lit floor and a receiver).
//!
//! Pipeline per resolution: conservative voxelization → Averages records (32 lines per voxel) →
//! octree ([`Octree::from_brick_map`], depth = log2 of the resolution) → light injection
//! (shadows marched in the octree) into an isotropic and a directional radiance octree → per
//! option set and octree, AO and `albedo · E/π` from the pixel-centre G-buffer → MSE and SSIM
//! against the references (`voxlod_cpu::render::indirect`, `--spp`
//! rays, seed 0; seed 1 measures the references' own noise).
//!
//! `--backend gpu` traces the sweep's cones with voxlod-gpu's cone kernel (the same AO and
//! `E/π` per pixel as the CPU's `ConeTracer::ao_and_diffuse`, checked by the equivalence
//! suite) and prints the adapter; its trace times are the kernel's (upload of the shading
//! points, dispatches, readback), on lavapipe CPU times of the GPU path.
//!
//! Then, unless `--lod-scene none`, primary visibility with level of detail by distance on
//! `--lod-scene` (`cone_primary`): error, samples and time per LOD bias against the
//! finest-level march and the ground-truth mesh render.

use std::time::Instant;

use anyhow::{Context, Result, ensure};
use glam::{UVec3, Vec3, Vec4};
use rayon::prelude::*;
use serde::Serialize;
use voxlod::cpu::appearance::averages;
use voxlod::cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod::cpu::appearance::sampler::SamplingContext;
use voxlod::cpu::raycast::Bvh;
use voxlod::cpu::render::ground_truth::{self, GBuffer};
use voxlod::cpu::render::indirect;
use voxlod::cpu::voxelize;
use voxlod::eval::report::{Cell, Column, NumberFormat, Plot, Report, Series, Table};
use voxlod::format::GridSpec;
use voxlod::gpu::cone::{ConeKernel, ConeQuery, GpuConeOctree, GpuMedium, ShadingPoint};
use voxlod::scene::{Image, Srgb8Image};
use voxlod_cone::{ConeMedium, ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
use voxlod_octree::{AveragePayload, BuildOptions, Directional, Octree};

use super::{Ui, backend, load_scene, print_json};
use crate::cli::{BackendArg, ConeArgs};

/// One measured option set.
#[derive(Clone, Debug, Serialize)]
pub struct ConeRow {
    /// Voxels along the longest axis.
    pub resolution: u32,
    /// Opacity pre-filter: "isotropic" (mean of the children) or "directional" (six
    /// opacities composited along the axes).
    pub opacity: String,
    /// Octree depth.
    pub depth: u32,
    /// Diffuse cones.
    pub cones: u32,
    /// Full aperture, degrees.
    pub aperture_deg: f32,
    /// Step as a fraction of the diameter.
    pub step: f32,
    /// AO: MSE and SSIM against the ray-traced AO (8-bit sRGB).
    pub ao_mse: f64,
    /// AO SSIM.
    pub ao_ssim: f64,
    /// Indirect light: MSE against the one-bounce path tracer.
    pub indirect_mse: f64,
    /// Indirect SSIM.
    pub indirect_ssim: f64,
    /// Cone tracing time for AO + indirect of the whole image, ms (CPU).
    pub trace_ms: f64,
    /// Octree samples per pixel.
    pub steps_per_pixel: f64,
}

/// One light-leaking measurement.
#[derive(Clone, Debug, Serialize)]
pub struct LeakRow {
    /// Octree depth (grid of 2^depth voxels over the unit cube).
    pub depth: u32,
    /// Wall thickness in voxels (1/32 of the scene).
    pub wall_voxels: u32,
    /// "isotropic" or "directional".
    pub option: String,
    /// Step fraction.
    pub step: f32,
    /// Receiver's `E/π` with the wall divided by without it (truth: 0).
    pub leak: f64,
}

/// The whole outcome (JSON).
#[derive(Debug, Serialize)]
pub struct ConeOutcome {
    /// Scene spec.
    pub scene: String,
    /// Where the sweep's cones were traced: "cpu (rayon)" or "gpu: <adapter>".
    pub backend: String,
    /// AO and indirect noise of the references: MSE between seeds 0 and 1.
    pub reference_noise_mse: [f64; 2],
    /// Reference render times, ms.
    pub reference_ms: [f64; 2],
    /// Per resolution: voxels, octree bytes per voxel, build + injection ms.
    pub octrees: Vec<(u32, u64, f64, f64, f64)>,
    /// Measured option sets.
    pub rows: Vec<ConeRow>,
    /// Light leaking.
    pub leaks: Vec<LeakRow>,
    /// Primary visibility with level of detail by distance (`--lod-scene`; none for "none").
    pub primary: Option<super::cone_primary::PrimaryOutcome>,
}

fn gray(gb: &GBuffer, v: &[f32]) -> Srgb8Image {
    let mut img = Image::new(gb.width, gb.height, Vec4::ZERO);
    for (p, &a) in img.pixels.iter_mut().zip(v) {
        *p = Vec3::splat(a).extend(1.0);
    }
    img.to_srgb8()
}

fn colour(gb: &GBuffer, e: &[Vec3]) -> Srgb8Image {
    let mut img = Image::new(gb.width, gb.height, Vec4::ZERO);
    for ((p, &e), t) in img.pixels.iter_mut().zip(e).zip(&gb.texels) {
        *p = (t.albedo * e).extend(1.0);
    }
    img.to_srgb8()
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The scene's light in voxlod-cone's terms.
pub(super) fn cone_light(l: voxlod::scene::Light) -> Light {
    match l {
        voxlod::scene::Light::Directional { to_light, irradiance } => {
            Light::Directional { to_light, irradiance }
        }
        voxlod::scene::Light::Point { position, intensity } => Light::Point { position, intensity },
    }
}

/// Runs the sweep and the leak experiment, writes `<output>/report.md` (+ JSON, plot).
pub fn cone(ui: &Ui, args: ConeArgs) -> Result<()> {
    ensure!(!args.res.is_empty(), "--res needs at least one resolution");
    for &r in &args.res {
        ensure!(
            r.is_power_of_two() && (4..=1024).contains(&r),
            "--res {r}: a power of two in 4..=1024"
        );
    }
    ensure!((1..=2048).contains(&args.size), "--size {} is out of range 1..=2048", args.size);
    ensure!(args.spp > 0, "--spp must be at least 1");
    ensure!(
        args.ao_radius.is_finite() && args.ao_radius > 0.0,
        "--ao-radius must be finite and > 0"
    );
    ensure!(
        !args.cones.is_empty() && !args.apertures.is_empty() && !args.steps.is_empty(),
        "--cones, --apertures and --steps need values"
    );
    for &a in &args.apertures {
        ensure!((0.0..180.0).contains(&a), "--apertures {a}: a full angle in [0, 180) degrees");
    }
    for &s in &args.steps {
        ensure!((0.05..=4.0).contains(&s), "--steps {s}: a fraction of the diameter in [0.05, 4]");
    }
    for &c in &args.cones {
        ensure!((1..=1024).contains(&c), "--cones {c}: in 1..=1024");
    }
    super::cone_primary::check_args(&args)?;
    // No adapter is an error, never a fall-back to the CPU.
    let (gpu, backend_name) = backend(args.backend)?;
    let kernel = gpu.as_ref().map(ConeKernel::new);
    let spinner = ui.spinner();
    let say = |m: &str| spinner.set_message(m.to_string());
    let outcome = run(&args, kernel.as_ref(), &backend_name, &say)?;
    let report = make_report(&outcome)?;
    let written = report
        .write(&args.output)
        .with_context(|| format!("writing the report into {}", args.output.display()))?;
    spinner.finish_and_clear();
    if args.json {
        return print_json(&outcome);
    }
    println!("backend: {backend_name} (the sweep's cone tracing)");
    for t in tables(&outcome)? {
        println!("\n{}", t.to_markdown());
    }
    println!("\nreport written to {}", written.markdown.display());
    Ok(())
}

fn run(
    args: &ConeArgs,
    gpu: Option<&ConeKernel>,
    backend_name: &str,
    say: &dyn Fn(&str),
) -> Result<ConeOutcome> {
    let scene = load_scene(&args.scene)?;
    let geometry = scene.geometry();
    let bvh = Bvh::new(&geometry)?;
    let camera = scene.default_camera()?;
    let (lo, hi) = scene.bounds()?;
    let radius = args.ao_radius * (hi - lo).length();
    let gb = ground_truth::gbuffer(&scene, &geometry, &bvh, &camera, args.size, args.size)?;
    let hits = gb.texels.iter().filter(|t| t.triangle != u32::MAX).count();
    say("ray-traced references");
    let opts = |seed| indirect::Options { spp: args.spp, seed, ao_radius: radius };
    let t = Instant::now();
    let ao_ref = indirect::ambient_occlusion(&scene, &geometry, &bvh, &gb, &opts(0))?;
    let ao_ms = ms(t);
    let t = Instant::now();
    let ind_ref = indirect::indirect_diffuse(&scene, &geometry, &bvh, &gb, &opts(0))?;
    let ind_ms = ms(t);
    let (ao_ref_img, ind_ref_img) = (gray(&gb, &ao_ref), colour(&gb, &ind_ref));
    let ao_1 = indirect::ambient_occlusion(&scene, &geometry, &bvh, &gb, &opts(1))?;
    let ind_1 = indirect::indirect_diffuse(&scene, &geometry, &bvh, &gb, &opts(1))?;
    let noise = [
        voxlod::eval::mse(&gray(&gb, &ao_1), &ao_ref_img)?,
        voxlod::eval::mse(&colour(&gb, &ind_1), &ind_ref_img)?,
    ];
    let light = cone_light(scene.light());
    let mut rows = Vec::new();
    let mut octrees = Vec::new();
    for &res in &args.res {
        say(&format!("voxelizing and building the octree at {res}³"));
        let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res)?;
        let vox = voxelize::voxelize(&geometry, &grid, &voxelize::Options::default())?;
        let ctx = SamplingContext::new(&scene, &geometry, &vox)?;
        let records = precompute(&ctx, &PrecomputeOptions { rays: 32, seed: 0 }, averages::fit)?;
        let t = Instant::now();
        let options = BuildOptions { depth: None, dense_log2: 4 };
        let tree =
            Octree::from_brick_map(grid, &records.records, AveragePayload::from_record, &options)
                .context("building the octree")?;
        let build_ms = ms(t);
        let t = Instant::now();
        let radiance: Octree<RadiancePayload> = inject(&tree, &light, &Shadows::MARCH)?;
        let inject_ms = ms(t);
        let directional: Octree<Directional<RadiancePayload>> =
            inject(&tree, &light, &Shadows::MARCH)?;
        let stats = radiance.memory_stats();
        octrees.push((
            res,
            tree.voxel_count(),
            stats.per_voxel(stats.total_bytes()),
            build_ms,
            inject_ms,
        ));
        let refs = References { gb: &gb, hits, ao: &ao_ref_img, indirect: &ind_ref_img };
        let uploaded = match gpu {
            Some(k) => Some((
                k,
                k.upload(&radiance).context("uploading the radiance octree")?,
                k.upload(&directional).context("uploading the directional radiance octree")?,
            )),
            None => None,
        };
        for &cones in &args.cones {
            for &aperture in &args.apertures {
                for &step in &args.steps {
                    say(&format!("{res}³: {cones} cones, {aperture}°, step {step}"));
                    let o = TraceOptions {
                        diffuse_cones: cones,
                        diffuse_aperture_deg: aperture,
                        step_factor: step,
                        ao_radius: radius,
                        ..TraceOptions::default()
                    };
                    for opacity in OPACITIES {
                        let on = |directional| {
                            uploaded
                                .as_ref()
                                .map(|(k, iso, dir)| (*k, if directional { dir } else { iso }))
                        };
                        let row = if opacity == "isotropic" {
                            measure(args, &radiance, on(false), o, &refs)?
                        } else {
                            measure(args, &directional, on(true), o, &refs)?
                        };
                        rows.push(ConeRow { resolution: res, opacity: opacity.into(), ..row });
                    }
                }
            }
        }
    }
    say("light leaking");
    let leaks = leak_experiment(&[5, 6, 7], &args.steps)?;
    let primary =
        if args.lod_scene == "none" { None } else { Some(super::cone_primary::run(args, say)?) };
    Ok(ConeOutcome {
        scene: args.scene.clone(),
        backend: backend_name.into(),
        reference_noise_mse: noise,
        reference_ms: [ao_ms, ind_ms],
        octrees,
        rows,
        leaks,
        primary,
    })
}

/// The two opacity pre-filters measured: the mean of the eight children (one opacity) and six
/// directional opacities composited front to back along each axis.
const OPACITIES: [&str; 2] = ["isotropic", "directional"];

/// The references one option set is scored against.
struct References<'a> {
    gb: &'a GBuffer,
    hits: usize,
    ao: &'a Srgb8Image,
    indirect: &'a Srgb8Image,
}

/// AO and `albedo · E/π` by cone tracing `radiance` with `o` from every pixel of the
/// G-buffer — on the CPU, or with the GPU kernel on `gpu`'s upload of the same octree —
/// scored against the references (the row's resolution and opacity are the caller's).
fn measure<M: ConeMedium + GpuMedium + Sync>(
    args: &ConeArgs,
    radiance: &Octree<M>,
    gpu: Option<(&ConeKernel, &GpuConeOctree)>,
    o: TraceOptions,
    refs: &References,
) -> Result<ConeRow> {
    let (cones, aperture, step) = (o.diffuse_cones, o.diffuse_aperture_deg, o.step_factor);
    let gb = refs.gb;
    let tracer = ConeTracer::new(radiance, o)
        .with_context(|| format!("{cones} cones, aperture {aperture}°, step {step}"))?;
    let t = Instant::now();
    let out: Vec<(f32, Vec3, u32)> = match gpu {
        None => gb
            .texels
            .par_iter()
            .map(|x| {
                if x.triangle == u32::MAX {
                    (1.0, Vec3::ZERO, 0)
                } else {
                    tracer.ao_and_diffuse(x.position, x.normal, true, true)
                }
            })
            .collect(),
        Some((kernel, tree)) => {
            // Misses get no cones (AO 1, no light), as above; no specular cone is traced.
            let points = ShadingPoint::from_gbuffer(gb, Vec3::ZERO, 0.0);
            let query = ConeQuery { ambient_occlusion: true, diffuse: true, specular: false };
            kernel
                .trace(tree, &o, query, &points, gb.width)
                .with_context(|| {
                    format!("{cones} cones, aperture {aperture}°, step {step} on the GPU")
                })?
                .iter()
                .map(|s| (s.ao, s.diffuse, s.diffuse_steps))
                .collect()
        }
    };
    let trace_ms = ms(t);
    let ao: Vec<f32> = out.iter().map(|o| o.0).collect();
    let e: Vec<Vec3> = out.iter().map(|o| o.1).collect();
    let steps: u64 = out.iter().map(|o| o.2 as u64).sum();
    // Geometry in view but not one octree sample: every cone left the octree's cube at its
    // apex. That happens when no surface sees another (a convex scene such as builtin:cube,
    // whose visible faces lie on the grid's boundary): the references are then exactly AO 1
    // and no indirect light, the cones agree with them trivially, and a row of MSE 0 / SSIM 1
    // would report a measurement that was never made.
    ensure!(
        refs.hits == 0 || steps > 0,
        "{}: no cone took an octree sample ({cones} cones, {aperture}°, step {step}) although \
         {} pixels see geometry: no surface in view sees another (a convex scene: AO 1 and no \
         indirect light everywhere), so there is nothing to measure; use a scene with \
         occlusion, e.g. builtin:cornell",
        args.scene,
        refs.hits
    );
    let ma = voxlod::eval::compare(&gray(gb, &ao), refs.ao)?;
    let mi = voxlod::eval::compare(&colour(gb, &e), refs.indirect)?;
    Ok(ConeRow {
        resolution: 0,
        opacity: String::new(),
        depth: radiance.depth(),
        cones,
        aperture_deg: aperture,
        step,
        ao_mse: ma.mse,
        ao_ssim: ma.ssim,
        indirect_mse: mi.mse,
        indirect_ssim: mi.ssim,
        trace_ms,
        steps_per_pixel: steps as f64 / gb.texels.len() as f64,
    })
}

/// The wall scene over the unit cube at `2^depth` voxels: a floor (y = 0 layer) on `x < ½`,
/// lit from straight above, and a wall `x ∈ [½, ½ + 1/32)` across the whole cube (if `wall`);
/// its faces are vertical, so unlit. The receiver at `(¾, ¼, ½)` faces −x: it sees only the
/// wall's unlit face (truth 0), or the lit floor without the wall.
fn wall_scene(depth: u32, wall: bool) -> Result<Octree<AveragePayload>> {
    let n = 1u32 << depth;
    let grid = GridSpec::new(glam::DVec3::ZERO, 1.0 / n as f64, UVec3::splat(n))?;
    let thick = (n / 32).max(1);
    let mut v = Vec::new();
    for x in 0..n / 2 {
        for z in 0..n {
            v.push((UVec3::new(x, 0, z), AveragePayload::new(Vec3::ONE, Vec3::Y, 1.0)));
        }
    }
    if wall {
        for x in n / 2..n / 2 + thick {
            let normal = if x == n / 2 { Vec3::NEG_X } else { Vec3::X };
            for y in 0..n {
                for z in 0..n {
                    v.push((UVec3::new(x, y, z), AveragePayload::new(Vec3::ONE, normal, 1.0)));
                }
            }
        }
    }
    Ok(Octree::build(grid, v, &BuildOptions { depth: Some(depth), dense_log2: 4.min(depth) })?)
}

fn leak_experiment(depths: &[u32], steps: &[f32]) -> Result<Vec<LeakRow>> {
    let light =
        Light::Directional { to_light: Vec3::Y, irradiance: Vec3::splat(std::f32::consts::PI) };
    let p = Vec3::new(0.75, 0.25, 0.5);
    let mut rows = Vec::new();
    for &depth in depths {
        let with = wall_scene(depth, true)?;
        let without = wall_scene(depth, false)?;
        for &step in steps {
            let o = TraceOptions { step_factor: step, ..TraceOptions::default() };
            let e = |t: &Octree<AveragePayload>, directional: bool| -> Result<f64> {
                Ok(if directional {
                    let r: Octree<Directional<RadiancePayload>> =
                        inject(t, &light, &Shadows::None)?;
                    ConeTracer::new(&r, o)?.diffuse(p, Vec3::NEG_X).x as f64
                } else {
                    let r: Octree<RadiancePayload> = inject(t, &light, &Shadows::None)?;
                    ConeTracer::new(&r, o)?.diffuse(p, Vec3::NEG_X).x as f64
                })
            };
            for (name, directional) in [("isotropic", false), ("directional", true)] {
                let open = e(&without, directional)?;
                let leak = if open > 0.0 { e(&with, directional)? / open } else { f64::NAN };
                rows.push(LeakRow {
                    depth,
                    wall_voxels: ((1u32 << depth) / 32).max(1),
                    option: name.into(),
                    step,
                    leak,
                });
            }
        }
    }
    Ok(rows)
}

fn tables(o: &ConeOutcome) -> Result<Vec<Table>> {
    let num = |n: &str, f| Column::number(n, f);
    let mut t = Table::new(
        "cone tracing vs ray-traced references",
        vec![
            num("res", NumberFormat::Integer),
            num("depth", NumberFormat::Integer),
            Column::text("opacity"),
            num("cones", NumberFormat::Integer),
            num("aperture°", NumberFormat::Fixed(0)),
            num("step", NumberFormat::Fixed(2)),
            num("AO MSE", NumberFormat::Significant(3)),
            num("AO SSIM", NumberFormat::Fixed(3)),
            num("indirect MSE", NumberFormat::Significant(3)),
            num("indirect SSIM", NumberFormat::Fixed(3)),
            num("trace ms", NumberFormat::Significant(3)),
            num("samples/px", NumberFormat::Significant(3)),
        ],
    );
    for r in &o.rows {
        let mut cells: Vec<Cell> =
            [r.resolution as f64, r.depth as f64].into_iter().map(Cell::Number).collect();
        cells.push(Cell::Text(r.opacity.clone()));
        cells.extend(
            [
                r.cones as f64,
                r.aperture_deg as f64,
                r.step as f64,
                r.ao_mse,
                r.ao_ssim,
                r.indirect_mse,
                r.indirect_ssim,
                r.trace_ms,
                r.steps_per_pixel,
            ]
            .into_iter()
            .map(Cell::Number),
        );
        t.push_row(cells)?;
    }
    let mut l = Table::new(
        "light leaking through a wall 1/32 of the scene thick (truth 0)",
        vec![
            num("depth", NumberFormat::Integer),
            num("wall voxels", NumberFormat::Integer),
            Column::text("opacity"),
            num("step", NumberFormat::Fixed(2)),
            num("leaked fraction", NumberFormat::Significant(3)),
        ],
    );
    for r in &o.leaks {
        l.push_row(vec![
            Cell::Number(r.depth as f64),
            Cell::Number(r.wall_voxels as f64),
            Cell::Text(r.option.clone()),
            Cell::Number(r.step as f64),
            Cell::Number(r.leak),
        ])?;
    }
    let mut out = vec![t, l];
    if let Some(p) = &o.primary {
        out.push(super::cone_primary::table(p)?);
    }
    Ok(out)
}

fn make_report(o: &ConeOutcome) -> Result<Report> {
    let mut r = Report::new(format!("voxel cone tracing: {}", o.scene));
    add_to_report(&mut r, o)?;
    Ok(r)
}

/// The sweep and the leak experiment with `voxlod cone builtin:cornell`'s defaults (`--spp
/// 1024` for the full report): the default report's cone-tracing section.
pub fn report_outcome(full: bool, say: &dyn Fn(&str)) -> Result<ConeOutcome> {
    use clap::Parser;
    let mut argv = vec!["voxlod", "cone", "builtin:cornell"];
    if full {
        argv.extend(["--spp", "1024"]);
    }
    let crate::cli::Command::Cone(args) =
        crate::cli::Cli::try_parse_from(argv)?.command.context("the cone command parses")?
    else {
        anyhow::bail!("`voxlod cone` parsed as another command")
    };
    ensure!(args.backend == BackendArg::Cpu, "the report traces cones on the CPU");
    run(&args, None, "cpu (rayon)", say)
}

/// Appends the cone-tracing section (heading, references, tables, error-vs-time plots).
pub fn add_to_report(r: &mut Report, o: &ConeOutcome) -> Result<()> {
    r.heading(2, format!("Voxel cone tracing: {}", o.scene));
    r.text(format!(
        "References: ray-traced AO and one-bounce path-traced diffuse indirect light on the mesh \
         ({:.0} ms and {:.0} ms, CPU). Their own noise (MSE between seeds 0 and 1): AO {:.5}, \
         indirect {:.4}; errors below these are not resolved. Octrees (res, voxels, bytes/voxel, \
         build ms, injection ms): {:?}. Cones traced on {}. Times are wall-clock times on a \
         shared machine (on a CPU adapter such as lavapipe, CPU times of the GPU path).",
        o.reference_ms[0],
        o.reference_ms[1],
        o.reference_noise_mse[0],
        o.reference_noise_mse[1],
        o.octrees,
        o.backend
    ));
    for t in tables(o)? {
        r.table(t);
    }
    if let Some(p) = &o.primary {
        r.text(super::cone_primary::summary(p));
        r.images(
            "cone_lod_images",
            format!("{}: the mesh and the LOD march at each bias", p.scene),
            super::cone_primary::image_grid(p),
        );
    }
    let mut keys: Vec<(u32, u32, &str)> =
        o.rows.iter().map(|x| (x.resolution, x.aperture_deg as u32, x.opacity.as_str())).collect();
    keys.sort();
    keys.dedup();
    let series = |metric: fn(&ConeRow) -> f64| -> Vec<Series> {
        keys.iter()
            .map(|&(res, ap, opacity)| {
                let pts = o
                    .rows
                    .iter()
                    .filter(|x| {
                        x.resolution == res && x.aperture_deg as u32 == ap && x.opacity == opacity
                    })
                    .map(|x| (x.trace_ms, metric(x)))
                    .collect();
                Series::new(format!("{res}³, {ap}°, {opacity}"), pts)
            })
            .collect()
    };
    for (name, title, y_label, metric) in [
        (
            "cone_ao_error_vs_time",
            "AO error vs cone tracing time",
            "AO MSE (8-bit sRGB)",
            (|x: &ConeRow| x.ao_mse) as fn(&ConeRow) -> f64,
        ),
        (
            "cone_indirect_error_vs_time",
            "indirect light error vs cone tracing time",
            "indirect MSE (8-bit sRGB)",
            |x: &ConeRow| x.indirect_mse,
        ),
    ] {
        r.plot(
            name,
            Plot {
                title: title.into(),
                x_label: "trace time (ms, CPU)".into(),
                y_label: y_label.into(),
                log_x: true,
                log_y: true,
                series: series(metric),
                ..Plot::default()
            },
        );
    }
    Ok(())
}
