//! Kernel 4, the voxel renderers: the filtered renderer on Averages and \[VJK21\] (SGGX)
//! records, and the baseline renderer of opaque voxels, on the bunny voxelized at 40³ (records
//! fitted from 32 lines per voxel), 48×48 pixels, directional light with shadows on and off, a
//! point light with shadows, and random cameras and lights. Each body runs once per record
//! kind (one row each).
//!
//! - **CPU reference row**: the claim the GPU kernel rests on — the cached render equals
//!   `render_uncached` (every value evaluated per ray) bit for bit, so evaluating per hit on
//!   the GPU is the same renderer. The baseline renderer caches only a voxel's shadow-ray
//!   visibility, a function of the voxel alone; its row renders on one thread and on the
//!   whole pool (another order of first visits to each voxel) and requires the same bits.
//!   Bound: exact.
//! - **GPU rows**: against the CPU render. Bound: [`GPU_BOUND`], **every channel within
//!   1 step of 8-bit sRGB for at least 99 % of the pixels**. Why: both walk the same DDA
//!   (ported line by line) and shade with the same function, so a ray that visits the same
//!   voxels agrees to ~1e-6 relative (under a step, but able to straddle a rounding boundary:
//!   1 step, not 0). Voxel centres are `f32` on the GPU (`f64` rounded on the CPU) and WGSL's
//!   division is within a few ULP, so a DDA plane crossing can differ by an ULP and flip a
//!   voxel where a camera or shadow ray passes through an edge or corner of the grid: that
//!   moves a pixel by up to a quarter (one of 4 rays) of the local contrast. Such rays are
//!   rare (the note gives the measured count); 1 % of the pixels leaves room for other
//!   adapters' rounding. \[VJK21\] adds `exp`/`log` (transmittance) and `sin`/`cos` (the 16
//!   fixed SGGX shading samples), which WGSL only bounds loosely (`sin`/`cos` to 2⁻¹¹
//!   absolute): their error moves a shading normal by ~10⁻³, a radiance by well under a
//!   step except where it straddles a rounding boundary — within the same bound. Measured on
//!   lavapipe: 0 pixels over 1 step, and no pixel differs at all in 8-bit sRGB.
//! - Bad input (a zero-sized image, a NaN light) gets the CPU path's error, word for word.
//! - **Averages with the normal as stored** (`AveragesNormal::AsStored`, the authors' choice;
//!   kernel flag 4): the same cases and bounds, with a control on the CPU row (on the sunlit
//!   case without shadows the flipping render must fail the GPU bound against it, so the
//!   cases show lit voxels seen from behind their mean normal). The authors' other choices have no kernel: their uploads and render
//!   options are refused with an error naming the option (checked here too).

use std::path::Path;
use std::sync::OnceLock;

use glam::Vec3;
use voxlod_cpu::appearance::averages::{AveragesGrid, AveragesNormal};
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::{Appearance, AppearanceGrid, averages, sggx};
use voxlod_cpu::render::baseline::{self, BaselineVoxel};
use voxlod_cpu::render::filtered::{
    FrameCache, Options, PixelPattern, VjkChord, render, render_uncached,
};
use voxlod_cpu::voxelize::{self, voxelize};
use voxlod_format::records::{AverageRecord, SggxRecord};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_gpu::filtered::{FilteredKernel, GpuRecords, RecordKind};
use voxlod_scene::{Camera, Image, Light, Scene};

use crate::harness::{Executor, Measure};
use crate::images::{ImageBound, compare};

pub const EXACT: ImageBound = ImageBound { per_pixel: 0, fraction: 1.0 };
/// See the module docs.
pub const GPU_BOUND: ImageBound = ImageBound { per_pixel: 1, fraction: 0.99 };

/// Grid resolution and image edge of the cases.
pub const RES: u32 = 40;
pub const SIZE: u32 = 48;

struct Fixture {
    scene: Scene,
    averages: AppearanceGrid<AverageRecord>,
    vjk21: AppearanceGrid<SggxRecord>,
    grid: GridSpec,
    baseline: BrickMap<BaselineVoxel>,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
        let scene = Scene::load(&path).expect("the bunny loads");
        let geometry = scene.geometry();
        let (lo, hi) = scene.bounds().expect("a non-empty scene");
        let spec = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), RES).expect("a grid");
        let vox = voxelize(&geometry, &spec, &voxelize::Options::default()).expect("voxelized");
        let ctx = SamplingContext::new(&scene, &geometry, &vox).expect("a sampling context");
        let opts = PrecomputeOptions { rays: 32, seed: 0 };
        let averages = precompute(&ctx, &opts, averages::fit).expect("Averages");
        let vjk21 = precompute(&ctx, &opts, sggx::fit).expect("[VJK21]");
        let baseline = baseline::build(&scene, &geometry, &vox).expect("baseline voxels");
        Fixture { scene, averages, vjk21, grid: spec, baseline }
    })
}

/// The record grid of a filtered `kind`, as an [`Appearance`], with its layout.
fn app(kind: RecordKind) -> (&'static dyn Appearance, &'static BrickMap<()>) {
    static LAYOUTS: OnceLock<[BrickMap<()>; 2]> = OnceLock::new();
    let f = fixture();
    let layouts =
        LAYOUTS.get_or_init(|| [f.averages.records.map(|_| ()), f.vjk21.records.map(|_| ())]);
    match kind {
        RecordKind::Averages => (&f.averages, &layouts[0]),
        RecordKind::Vjk21 => (&f.vjk21, &layouts[1]),
        RecordKind::Baseline => unreachable!("the baseline's voxels are no Appearance"),
        RecordKind::VirtualMesh | RecordKind::Adaptive => unreachable!("rows of voxels.rs"),
    }
}

/// Voxels with a record of `kind`.
fn voxel_count(kind: RecordKind) -> usize {
    match kind {
        RecordKind::Baseline => fixture().baseline.len(),
        _ => app(kind).0.len(),
    }
}

/// The baseline renderer's CPU image, on the current rayon pool.
fn cpu_baseline(camera: &Camera, light: &Light, bg: Vec3, o: &Options) -> Result<Image, String> {
    let f = fixture();
    let Options { width, height, ambient, shadows, .. } = *o;
    let options = baseline::Options { width, height, ambient, shadows };
    baseline::render(&f.grid, &f.baseline, camera, light, bg, &options).map_err(|e| e.to_string())
}

fn upload(k: &FilteredKernel<'_>, kind: RecordKind) -> Result<GpuRecords, String> {
    let f = fixture();
    match kind {
        RecordKind::Averages => k.upload_averages(&f.averages),
        RecordKind::Vjk21 => k.upload_vjk21(&f.vjk21),
        RecordKind::Baseline => k.upload_baseline(&f.grid, &f.baseline),
        RecordKind::VirtualMesh | RecordKind::Adaptive => unreachable!("rows of voxels.rs"),
    }
    .map_err(|e| e.to_string())
}

fn cpu(
    kind: RecordKind,
    camera: &Camera,
    light: &Light,
    bg: Vec3,
    options: &Options,
) -> Result<Image, String> {
    if kind == RecordKind::Baseline {
        return cpu_baseline(camera, light, bg, options);
    }
    let (a, layout) = app(kind);
    let mut cache = FrameCache::with_layout(a, layout).map_err(|e| e.to_string())?;
    render(&mut cache, camera, light, bg, options).map_err(|e| e.to_string())
}

fn uncached(
    kind: RecordKind,
    camera: &Camera,
    light: &Light,
    bg: Vec3,
    options: &Options,
) -> Result<Image, String> {
    if kind == RecordKind::Baseline {
        let one =
            rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| e.to_string())?;
        return one.install(|| cpu_baseline(camera, light, bg, options));
    }
    let (a, layout) = app(kind);
    let cache = FrameCache::with_layout(a, layout).map_err(|e| e.to_string())?;
    render_uncached(&cache, camera, light, bg, options).map_err(|e| e.to_string())
}

fn prefix(kind: RecordKind) -> &'static str {
    match kind {
        RecordKind::Averages => "averages",
        RecordKind::Vjk21 => "vjk21",
        RecordKind::Baseline => "baseline",
        RecordKind::VirtualMesh | RecordKind::Adaptive => unreachable!("rows of voxels.rs"),
    }
}

pub fn averages_scenes(backend: &Executor) -> Result<Measure, String> {
    scenes_body(backend, RecordKind::Averages)
}

pub fn vjk21_scenes(backend: &Executor) -> Result<Measure, String> {
    scenes_body(backend, RecordKind::Vjk21)
}

pub fn baseline_scenes(backend: &Executor) -> Result<Measure, String> {
    scenes_body(backend, RecordKind::Baseline)
}

pub fn baseline_property(backend: &Executor) -> Result<Measure, String> {
    property(backend, RecordKind::Baseline)
}

pub fn averages_property(backend: &Executor) -> Result<Measure, String> {
    property(backend, RecordKind::Averages)
}

pub fn vjk21_property(backend: &Executor) -> Result<Measure, String> {
    property(backend, RecordKind::Vjk21)
}

pub fn cases() -> Vec<(&'static str, Camera, Light, Options)> {
    let f = fixture();
    let camera = f.scene.default_camera().expect("a camera");
    let (lo, hi) = f.scene.bounds().unwrap();
    let sun = Light::Directional {
        to_light: Vec3::new(0.4, 1.0, 0.3).normalize(),
        irradiance: Vec3::splat(3.0),
    };
    let point = Light::Point { position: hi + (hi - lo) * 0.3, intensity: Vec3::splat(2.0) };
    let base =
        Options { width: SIZE, height: SIZE, ambient: Vec3::splat(0.05), ..Options::default() };
    vec![
        ("filtered-sun-shadows", camera, sun, base),
        ("filtered-sun-no-shadows", camera, sun, Options { shadows: false, ..base }),
        ("filtered-point-shadows", camera, point, base),
    ]
}

fn scenes_body(backend: &Executor, kind: RecordKind) -> Result<Measure, String> {
    let kernel = match backend {
        Executor::Cpu => None,
        Executor::Gpu(ctx) => Some(FilteredKernel::new(ctx).map_err(|e| e.to_string())?),
    };
    let bg = Vec3::new(0.1, 0.2, 0.3);
    let mut measures = Vec::new();
    for (name, camera, light, options) in cases() {
        let name = format!("{}-{name}", prefix(kind));
        let expected = cpu(kind, &camera, &light, bg, &options)?;
        let m = match &kernel {
            None => {
                let u = uncached(kind, &camera, &light, bg, &options)?;
                compare(&name, &u, &expected, EXACT)
            }
            Some(k) => {
                let start = std::time::Instant::now();
                let up = upload(k, kind)?;
                let actual =
                    k.render(&up, &camera, &light, bg, &options).map_err(|e| e.to_string())?;
                let seconds = start.elapsed().as_secs_f64();
                let slug = format!("{name}-{}", crate::ground_truth::backend_slug(backend));
                let mut m = compare(&slug, &actual, &expected, GPU_BOUND);
                // The image must show the bunny, or the comparison proves little.
                let covered = expected.pixels.iter().filter(|p| p.w > 0.0).count();
                if covered * 10 < expected.pixels.len() {
                    m.pass = false;
                }
                m.note += &format!(
                    ", {covered} pixels covered (≥ 10 % required), {} voxels, {seconds:.2} s",
                    voxel_count(kind)
                );
                m
            }
        };
        measures.push(m);
    }
    if let Some(k) = &kernel {
        measures.push(bad_input(k, kind)?);
    } else {
        measures.push(shadow_control(bg, kind)?);
    }
    Ok(Measure::combine(&measures))
}

/// A control on the CPU row: the sun case with and without shadows must differ by more than
/// the GPU bound allows (so the cases exercise the shadow rays the kernel traces).
fn shadow_control(bg: Vec3, kind: RecordKind) -> Result<Measure, String> {
    let all = cases();
    let (on, off) = (&all[0], &all[1]);
    let a = cpu(kind, &on.1, &on.2, bg, &on.3)?;
    let b = cpu(kind, &off.1, &off.2, bg, &off.3)?;
    let name = format!("{}-filtered-shadow-control", prefix(kind));
    let mut m = compare(&name, &a, &b, GPU_BOUND);
    m.pass = !m.pass;
    m.max_error = 0.0;
    m.bound = 0.0;
    m.note = format!("control, shadows on vs off must fail the GPU bound: {}", m.note);
    Ok(m)
}

/// The Averages grid with its normal as stored.
fn as_stored() -> &'static AveragesGrid {
    static G: OnceLock<AveragesGrid> = OnceLock::new();
    G.get_or_init(|| AveragesGrid {
        grid: fixture().averages.clone(),
        normal: AveragesNormal::AsStored,
    })
}

/// Averages with the normal as stored: see the module docs.
pub fn averages_as_stored_scenes(backend: &Executor) -> Result<Measure, String> {
    let g = as_stored();
    let layout = &g.grid.records;
    let bg = Vec3::new(0.1, 0.2, 0.3);
    let err = |e: voxlod_cpu::Error| e.to_string();
    let mut measures = Vec::new();
    for (name, camera, light, options) in cases() {
        let name = format!("averages-as-stored-{name}");
        let mut cache = FrameCache::with_layout(g, layout).map_err(err)?;
        let expected = render(&mut cache, &camera, &light, bg, &options).map_err(err)?;
        let m = match backend {
            Executor::Cpu => {
                let u = render_uncached(&cache, &camera, &light, bg, &options).map_err(err)?;
                let m = compare(&name, &u, &expected, EXACT);
                if !name.ends_with("sun-no-shadows") {
                    m
                } else {
                    // Control, on the sunlit case without shadows (the point light sits where
                    // few voxels seen from behind are lit): the flipping render differs beyond
                    // the GPU bound.
                    let flipped = cpu(RecordKind::Averages, &camera, &light, bg, &options)?;
                    let mut c = compare(&format!("{name}-control"), &flipped, &expected, GPU_BOUND);
                    c.pass = !c.pass;
                    c.max_error = 0.0;
                    c.bound = 0.0;
                    c.note = format!(
                        "control, flipped vs as stored must fail the GPU bound: {}",
                        c.note
                    );
                    Measure::combine(&[m, c])
                }
            }
            Executor::Gpu(ctx) => {
                let k = FilteredKernel::new(ctx).map_err(|e| e.to_string())?;
                let up = k.upload_averages_grid(g).map_err(|e| e.to_string())?;
                let actual =
                    k.render(&up, &camera, &light, bg, &options).map_err(|e| e.to_string())?;
                let slug = format!("{name}-{}", crate::ground_truth::backend_slug(backend));
                compare(&slug, &actual, &expected, GPU_BOUND)
            }
        };
        measures.push(m);
    }
    if let Executor::Gpu(ctx) = backend {
        measures.push(refusals(&FilteredKernel::new(ctx).map_err(|e| e.to_string())?)?);
    }
    Ok(Measure::combine(&measures))
}

/// The render options the kernel does not follow are errors naming them.
fn refusals(k: &FilteredKernel<'_>) -> Result<Measure, String> {
    let (_, camera, light, options) = cases().remove(0);
    let up = upload(k, RecordKind::Vjk21)?;
    let refused = [
        (Options { vjk_chord: VjkChord::CachedChord, ..options }, "vjk_chord"),
        (Options { vjk_chord: VjkChord::CachedAlpha, ..options }, "vjk_chord"),
        (Options { pattern: PixelPattern::Jittered { seed: 1 }, ..options }, "pattern"),
    ];
    let mut differ = Vec::new();
    for (o, field) in refused {
        match k.render(&up, &camera, &light, Vec3::ZERO, &o) {
            Err(e) if e.to_string().contains(field) => {}
            other => differ.push(format!("{field}: got {:?}", other.map(|_| "an image"))),
        }
    }
    Ok(Measure {
        max_error: differ.len() as f64,
        bound: 0.0,
        pass: differ.is_empty(),
        note: if differ.is_empty() {
            "3 authors' render options: errors naming them".into()
        } else {
            differ.join("; ")
        },
    })
}

/// Bad input gets the CPU path's errors.
fn bad_input(k: &FilteredKernel<'_>, kind: RecordKind) -> Result<Measure, String> {
    let (_, camera, light, options) = cases().remove(0);
    let up = upload(k, kind)?;
    let nan = Light::Directional { to_light: Vec3::NAN, irradiance: Vec3::ONE };
    let bad = [
        (camera, light, Vec3::ZERO, Options { width: 0, ..options }),
        (camera, nan, Vec3::ZERO, options),
        (camera, light, Vec3::splat(-1.0), options),
    ];
    let mut differ = Vec::new();
    for (c, l, bg, o) in bad {
        let want = cpu(kind, &c, &l, bg, &o).err();
        let got = k.render(&up, &c, &l, bg, &o).err().map(|e| e.to_string());
        if want.is_none()
            || got.as_deref().map(|g| g.contains(want.as_deref().unwrap())) != Some(true)
        {
            differ.push(format!("want {want:?}, got {got:?}"));
        }
    }
    Ok(Measure {
        max_error: differ.len() as f64,
        bound: 0.0,
        pass: differ.is_empty(),
        note: if differ.is_empty() {
            "3 bad inputs: the CPU's errors".into()
        } else {
            differ.join("; ")
        },
    })
}

/// Random cameras (direction, distance, field of view), light directions and shadows on/off,
/// 32×32 pixels, each image within [`GPU_BOUND`] (`PROPTEST_CASES` sets how many; 32 by
/// default). CPU row: cached equals uncached, bit for bit.
fn property(backend: &Executor, kind: RecordKind) -> Result<Measure, String> {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
    let kernel = match backend {
        Executor::Cpu => None,
        Executor::Gpu(ctx) => Some(FilteredKernel::new(ctx).map_err(|e| e.to_string())?),
    };
    let f = fixture();
    let uploaded = match &kernel {
        None => None,
        Some(k) => Some(upload(k, kind)?),
    };
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(32);
    let mut runner = TestRunner::new_with_rng(
        Config { cases, failure_persistence: None, ..Config::default() },
        TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    );
    let v3 = || (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0);
    let strategy = (v3(), 0.4f32..2.0, 20.0f32..80.0, v3(), any::<bool>());
    let worst = std::cell::Cell::new(0.0f64);
    let count = std::cell::Cell::new(0usize);
    let (lo, hi) = f.scene.bounds().unwrap();
    let bg = Vec3::splat(0.2);
    let result = runner.run(&strategy, |((x, y, z), zoom, fov, (a, b, c), shadows)| {
        let dir = Vec3::new(x, y, z);
        let to_light = Vec3::new(a, b, c);
        prop_assume!(dir.length() > 0.1 && to_light.length() > 0.1);
        let radius = (hi - lo).length() * 0.5;
        let camera = Camera::framing(dir, (lo + hi) * 0.5, radius * zoom, fov);
        let light =
            Light::Directional { to_light: to_light.normalize(), irradiance: Vec3::splat(2.0) };
        let options = Options {
            width: 32,
            height: 32,
            ambient: Vec3::splat(0.05),
            shadows,
            ..Default::default()
        };
        let expected = cpu(kind, &camera, &light, bg, &options).map_err(TestCaseError::fail)?;
        let m = match (&kernel, &uploaded) {
            (Some(k), Some(up)) => {
                let actual = k.render(up, &camera, &light, bg, &options);
                let actual = actual.map_err(|e| TestCaseError::fail(e.to_string()))?;
                compare("filtered-property-gpu", &actual, &expected, GPU_BOUND)
            }
            _ => {
                let u =
                    uncached(kind, &camera, &light, bg, &options).map_err(TestCaseError::fail)?;
                compare("filtered-property-cpu", &u, &expected, EXACT)
            }
        };
        count.set(count.get() + 1);
        worst.set(worst.get().max(m.max_error));
        prop_assert!(m.pass, "{}", m.note);
        Ok(())
    });
    let bound = if kernel.is_some() { 1.0 - GPU_BOUND.fraction } else { 0.0 };
    let mut note = format!(
        "{} random cameras and lights on the bunny at {RES}³, 32×32, shadows random",
        count.get()
    );
    if let Err(e) = &result {
        note += &format!("; minimal failing case: {e}");
    }
    Ok(Measure { max_error: worst.get(), bound, pass: result.is_ok(), note })
}
