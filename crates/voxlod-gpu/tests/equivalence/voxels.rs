//! Kernel 4, second part: the filtered renderer on **virtual mesh + opacity subgrid** grids
//! (three variants: the Lines rule, the Circles rule, Lines × projected area) and on an
//! **Adaptive** grid mixing Averages, \[VJK21\] and virtual-mesh voxels, on the bunny at 40³
//! (records fitted from 32 lines per voxel; the Adaptive errors from 64 held-out lines), 48×48
//! pixels: the cases of [`crate::filtered`] (directional light with shadows on and off, a
//! point light with shadows) plus the Circles, projected-area and specular variants with
//! shadows, and
//! random cameras, lights, shadows and variants.
//!
//! - **CPU reference row**: the cached render equals `render_uncached` bit for bit (the GPU's
//!   per-voxel passes compute each cached value once per voxel, which is what the cache
//!   holds), and shadows on vs off differ by more than the GPU bound (a control). The
//!   Adaptive row also requires each kind to hold at least 5 % of the voxels, so the mixed
//!   compositing is exercised. Bound: exact.
//! - **GPU rows**: against the CPU render. Bound: [`GPU_BOUND`] — every channel within
//!   **2 steps** of 8-bit sRGB for at least **99 %** of the pixels. Why: the DDA, look-up,
//!   compositing, shadows and shading are the first part's (1 step, 99 %: see
//!   [`crate::filtered`]), and the virtual mesh adds WGSL `sqrt` (barycentric warp, vector
//!   lengths), division (the Lines rule's slab crossings and chords) and, under Circles,
//!   `acos`, each within a few ULP of the CPU's correctly rounded results. A slab crossing
//!   within an ULP of a sub-cell boundary adds or drops that sub-cell for one of the 32 lines,
//!   moving the voxel's opacity by up to 1/32 of the cell's α, and a shading sample whose
//!   `n·v` is within an ULP of 0 is kept on one side and skipped on the other (1/16 of a
//!   face): either moves a pixel by a fraction of the local contrast, a step or two. The
//!   measured worst case on lavapipe is in the rows' notes and the README.
//! - Bad input (a zero-sized image, a NaN light, a negative background) gets the CPU path's
//!   error, word for word; a shading sample count over the kernel's bound is refused at upload
//!   with an error naming `samples_per_face`.

use std::path::Path;
use std::sync::OnceLock;

use glam::Vec3;
use voxlod_cpu::appearance::adaptive::{AdaptiveGrid, AdaptiveOptions, Candidates};
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::subgrid::DirectionalRule;
use voxlod_cpu::appearance::virtual_mesh::{self, VirtualMeshGrid};
use voxlod_cpu::appearance::{Appearance, AppearanceGrid};
use voxlod_cpu::render::filtered::{FrameCache, Options, render, render_uncached};
use voxlod_cpu::voxelize::{self, voxelize};
use voxlod_format::records::{SpecularRecord, VirtualMeshRecord};
use voxlod_gpu::filtered::voxels::MAX_SAMPLES_PER_FACE;
use voxlod_gpu::filtered::{FilteredKernel, GpuRecords};
use voxlod_scene::{Camera, Image, Light, Scene};

use crate::filtered::{EXACT, RES, cases};
use crate::harness::{Executor, Measure};
use crate::images::{ImageBound, compare};

/// See the module docs.
pub const GPU_BOUND: ImageBound = ImageBound { per_pixel: 2, fraction: 0.99 };

/// The Adaptive threshold of the fixture (chosen so that every kind holds a share).
const THRESHOLD: f32 = 0.08;

/// The virtual-mesh variants: Lines, Circles, Lines × projected area, Lines with a specular
/// side record on every voxel (the bunny has none: this exercises the specular lobe), and Lines
/// with the authors' unshaded fallback (`ShadingFallback::Unshaded`).
const VARIANTS: [(&str, DirectionalRule, bool); 5] = [
    ("lines", DirectionalRule::Lines, false),
    ("circles", DirectionalRule::Circles, false),
    ("lines-area", DirectionalRule::Lines, true),
    ("lines-specular", DirectionalRule::Lines, false),
    ("lines-unshaded", DirectionalRule::Lines, false),
];

struct Fixture {
    scene: Scene,
    vmesh: [VirtualMeshGrid; 5],
    adaptive: AdaptiveGrid,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
        let scene = Scene::load(&path).expect("the bunny loads");
        let geometry = scene.geometry();
        let (lo, hi) = scene.bounds().expect("a non-empty scene");
        let spec = voxlod_format::GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), RES).expect("a grid");
        let vox = voxelize(&geometry, &spec, &voxelize::Options::default()).expect("voxelized");
        let ctx = SamplingContext::new(&scene, &geometry, &vox).expect("a sampling context");
        let opts = PrecomputeOptions { rays: 32, seed: 0 };
        let records: AppearanceGrid<VirtualMeshRecord> =
            precompute(&ctx, &opts, virtual_mesh::fit).expect("virtual mesh");
        let mut vmesh = VARIANTS.map(|(_, rule, projected_area)| VirtualMeshGrid {
            rule,
            projected_area,
            ..VirtualMeshGrid::new(records.clone())
        });
        let n = records.records.len();
        vmesh[3].grid.specular = Some(vec![SpecularRecord::new(0.4, 24.0); n]);
        vmesh[4].fallback = voxlod_cpu::appearance::virtual_mesh::ShadingFallback::Unshaded;
        let options = AdaptiveOptions { rays: 32, heldout: 64, ..Default::default() };
        let candidates = Candidates::build(&ctx, &options).expect("Adaptive candidates");
        let adaptive = candidates.select(THRESHOLD).expect("an Adaptive grid");
        Fixture { scene, vmesh, adaptive }
    })
}

/// What a row renders: virtual-mesh variant `0..5`, or the Adaptive grid.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Grid {
    Vmesh(usize),
    Adaptive,
}

impl Grid {
    fn app(self) -> &'static dyn Appearance {
        let f = fixture();
        match self {
            Grid::Vmesh(v) => &f.vmesh[v],
            Grid::Adaptive => &f.adaptive,
        }
    }

    fn name(self) -> String {
        match self {
            Grid::Vmesh(v) => format!("vmesh-{}", VARIANTS[v].0),
            Grid::Adaptive => "adaptive".into(),
        }
    }

    fn cpu(self, camera: &Camera, light: &Light, bg: Vec3, o: &Options) -> Result<Image, String> {
        let mut cache = FrameCache::new(self.app()).map_err(|e| e.to_string())?;
        render(&mut cache, camera, light, bg, o).map_err(|e| e.to_string())
    }

    fn uncached(
        self,
        camera: &Camera,
        light: &Light,
        bg: Vec3,
        o: &Options,
    ) -> Result<Image, String> {
        let cache = FrameCache::new(self.app()).map_err(|e| e.to_string())?;
        render_uncached(&cache, camera, light, bg, o).map_err(|e| e.to_string())
    }

    fn upload(self, k: &FilteredKernel<'_>) -> Result<GpuRecords, String> {
        let f = fixture();
        match self {
            Grid::Vmesh(v) => k.upload_virtual_mesh(&f.vmesh[v]),
            Grid::Adaptive => k.upload_adaptive(&f.adaptive),
        }
        .map_err(|e| e.to_string())
    }
}

pub fn vmesh_scenes(backend: &Executor) -> Result<Measure, String> {
    let mut runs: Vec<(Grid, &'static str, Camera, Light, Options)> =
        cases().into_iter().map(|(n, c, l, o)| (Grid::Vmesh(0), n, c, l, o)).collect();
    let (_, camera, sun, options) = cases().remove(0);
    for v in 1..VARIANTS.len() {
        runs.push((Grid::Vmesh(v), "filtered-sun-shadows", camera, sun, options));
    }
    let body = scenes_body(backend, Grid::Vmesh(0), runs)?;
    match backend {
        Executor::Cpu => Ok(Measure::combine(&[body, fallback_control()?])),
        Executor::Gpu(_) => Ok(body),
    }
}

/// A control on the CPU row: the sun case with our fallback and with the authors' unshaded
/// one must differ by more than the GPU bound allows (so the case reaches the fallback the
/// kernel mirrors).
fn fallback_control() -> Result<Measure, String> {
    let (_, camera, sun, options) = cases().remove(0);
    let bg = Vec3::new(0.1, 0.2, 0.3);
    let a = Grid::Vmesh(0).cpu(&camera, &sun, bg, &options)?;
    let b = Grid::Vmesh(4).cpu(&camera, &sun, bg, &options)?;
    let mut m = compare("vmesh-fallback-control", &a, &b, GPU_BOUND);
    m.pass = !m.pass;
    m.max_error = 0.0;
    m.bound = 0.0;
    m.note = format!("control, ours vs unshaded fallback must fail the GPU bound: {}", m.note);
    Ok(m)
}

pub fn adaptive_scenes(backend: &Executor) -> Result<Measure, String> {
    let runs = cases().into_iter().map(|(n, c, l, o)| (Grid::Adaptive, n, c, l, o)).collect();
    scenes_body(backend, Grid::Adaptive, runs)
}

fn scenes_body(
    backend: &Executor,
    main: Grid,
    runs: Vec<(Grid, &'static str, Camera, Light, Options)>,
) -> Result<Measure, String> {
    let kernel = match backend {
        Executor::Cpu => None,
        Executor::Gpu(ctx) => Some(FilteredKernel::new(ctx).map_err(|e| e.to_string())?),
    };
    let bg = Vec3::new(0.1, 0.2, 0.3);
    let mut measures = Vec::new();
    let mut uploaded: Vec<(Grid, GpuRecords)> = Vec::new();
    for (grid, case, camera, light, options) in runs {
        let name = format!("{}-{case}", grid.name());
        let expected = grid.cpu(&camera, &light, bg, &options)?;
        let m = match &kernel {
            None => {
                compare(&name, &grid.uncached(&camera, &light, bg, &options)?, &expected, EXACT)
            }
            Some(k) => {
                let start = std::time::Instant::now();
                if !uploaded.iter().any(|(g, _)| *g == grid) {
                    uploaded.push((grid, grid.upload(k)?));
                }
                let up = &uploaded.iter().find(|(g, _)| *g == grid).expect("uploaded").1;
                let actual =
                    k.render(up, &camera, &light, bg, &options).map_err(|e| e.to_string())?;
                let seconds = start.elapsed().as_secs_f64();
                let slug = format!("{name}-{}", crate::ground_truth::backend_slug(backend));
                let mut m = compare(&slug, &actual, &expected, GPU_BOUND);
                let covered = expected.pixels.iter().filter(|p| p.w > 0.0).count();
                if covered * 10 < expected.pixels.len() {
                    m.pass = false;
                }
                m.note += &format!(
                    ", {covered} pixels covered (≥ 10 % required), {} voxels, {seconds:.2} s",
                    grid.app().len()
                );
                m
            }
        };
        measures.push(m);
    }
    match &kernel {
        Some(k) => measures.push(bad_input(k, main)?),
        None => {
            measures.push(shadow_control(bg, main)?);
            if main == Grid::Adaptive {
                measures.push(mix_control());
            }
        }
    }
    Ok(Measure::combine(&measures))
}

/// Shadows on vs off must differ by more than the GPU bound (see [`crate::filtered`]).
fn shadow_control(bg: Vec3, grid: Grid) -> Result<Measure, String> {
    let all = cases();
    let (on, off) = (&all[0], &all[1]);
    let a = grid.cpu(&on.1, &on.2, bg, &on.3)?;
    let b = grid.cpu(&off.1, &off.2, bg, &off.3)?;
    let mut m = compare(&format!("{}-shadow-control", grid.name()), &a, &b, GPU_BOUND);
    m.pass = !m.pass;
    m.max_error = 0.0;
    m.bound = 0.0;
    m.note = format!("control, shadows on vs off must fail the GPU bound: {}", m.note);
    Ok(m)
}

/// The Adaptive fixture mixes all three kinds (each ≥ 5 % of the voxels).
fn mix_control() -> Measure {
    let mix = fixture().adaptive.mix();
    let pass = mix.iter().all(|&m| m >= 0.05);
    Measure {
        max_error: 0.0,
        bound: 0.0,
        pass,
        note: format!(
            "control, τ = {THRESHOLD}: Averages {:.1} %, [VJK21] {:.1} %, virtual mesh {:.1} % \
             (each ≥ 5 % required)",
            100.0 * mix[0],
            100.0 * mix[1],
            100.0 * mix[2]
        ),
    }
}

/// Bad input gets the CPU path's errors; too many shading samples an error naming the option.
fn bad_input(k: &FilteredKernel<'_>, grid: Grid) -> Result<Measure, String> {
    let (_, camera, light, options) = cases().remove(0);
    let up = grid.upload(k)?;
    let nan = Light::Directional { to_light: Vec3::NAN, irradiance: Vec3::ONE };
    let bad = [
        (camera, light, Vec3::ZERO, Options { width: 0, ..options }),
        (camera, nan, Vec3::ZERO, options),
        (camera, light, Vec3::splat(-1.0), options),
    ];
    let mut differ = Vec::new();
    for (c, l, bg, o) in bad {
        let want = grid.cpu(&c, &l, bg, &o).err();
        let got = k.render(&up, &c, &l, bg, &o).err().map(|e| e.to_string());
        if want.is_none()
            || got.as_deref().map(|g| g.contains(want.as_deref().unwrap())) != Some(true)
        {
            differ.push(format!("want {want:?}, got {got:?}"));
        }
    }
    let f = fixture();
    let many = VirtualMeshGrid {
        samples_per_face: MAX_SAMPLES_PER_FACE + 1,
        ..VirtualMeshGrid::new(f.vmesh[0].grid.clone())
    };
    match k.upload_virtual_mesh(&many).err().map(|e| e.to_string()) {
        Some(e) if e.contains("samples_per_face") => {}
        other => differ.push(format!("samples_per_face over the bound: got {other:?}")),
    }
    Ok(Measure {
        max_error: differ.len() as f64,
        bound: 0.0,
        pass: differ.is_empty(),
        note: if differ.is_empty() {
            "3 bad inputs: the CPU's errors; too many samples per face: refused by name".into()
        } else {
            differ.join("; ")
        },
    })
}

pub fn vmesh_property(backend: &Executor) -> Result<Measure, String> {
    property(backend, &[Grid::Vmesh(0), Grid::Vmesh(1), Grid::Vmesh(2), Grid::Vmesh(3)])
}

pub fn adaptive_property(backend: &Executor) -> Result<Measure, String> {
    property(backend, &[Grid::Adaptive])
}

/// Random cameras (direction, distance, field of view), light directions, shadows on/off and
/// grids of `grids`, 32×32 pixels, each image within [`GPU_BOUND`] (`PROPTEST_CASES` sets how
/// many; 24 by default). CPU row: cached equals uncached, bit for bit.
fn property(backend: &Executor, grids: &[Grid]) -> Result<Measure, String> {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
    let kernel = match backend {
        Executor::Cpu => None,
        Executor::Gpu(ctx) => Some(FilteredKernel::new(ctx).map_err(|e| e.to_string())?),
    };
    let f = fixture();
    let uploaded = match &kernel {
        None => Vec::new(),
        Some(k) => grids.iter().map(|g| g.upload(k)).collect::<Result<Vec<_>, _>>()?,
    };
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(24);
    let mut runner = TestRunner::new_with_rng(
        Config { cases, failure_persistence: None, ..Config::default() },
        TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    );
    let v3 = || (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0);
    let strategy = (v3(), 0.4f32..2.0, 20.0f32..80.0, v3(), any::<bool>(), 0..grids.len());
    let worst = std::cell::Cell::new(0.0f64);
    let worst_step = std::cell::Cell::new(0u8);
    let count = std::cell::Cell::new(0usize);
    let (lo, hi) = f.scene.bounds().unwrap();
    let bg = Vec3::splat(0.2);
    let result = runner.run(&strategy, |((x, y, z), zoom, fov, (a, b, c), shadows, g)| {
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
        let grid = grids[g];
        let expected = grid.cpu(&camera, &light, bg, &options).map_err(TestCaseError::fail)?;
        let (m, actual) = match &kernel {
            Some(k) => {
                let actual = k.render(&uploaded[g], &camera, &light, bg, &options);
                let actual = actual.map_err(|e| TestCaseError::fail(e.to_string()))?;
                let name = format!("{}-property-gpu", grid.name());
                (compare(&name, &actual, &expected, GPU_BOUND), actual)
            }
            None => {
                let u =
                    grid.uncached(&camera, &light, bg, &options).map_err(TestCaseError::fail)?;
                let name = format!("{}-property-cpu", grid.name());
                (compare(&name, &u, &expected, EXACT), u)
            }
        };
        let step = crate::images::worst_step(&actual, &expected);
        worst_step.set(worst_step.get().max(step));
        count.set(count.get() + 1);
        worst.set(worst.get().max(m.max_error));
        prop_assert!(m.pass, "{}", m.note);
        Ok(())
    });
    let bound = if kernel.is_some() { 1.0 - GPU_BOUND.fraction } else { 0.0 };
    let names: Vec<String> = grids.iter().map(|g| g.name()).collect();
    let mut note = format!(
        "{} random cameras and lights on the bunny at {RES}³ ({}), 32×32, shadows random, \
         worst pixel {} sRGB step(s)",
        count.get(),
        names.join(", "),
        worst_step.get()
    );
    if let Err(e) = &result {
        note += &format!("; minimal failing case: {e}");
    }
    Ok(Measure { max_error: worst.get(), bound, pass: result.is_ok(), note })
}
