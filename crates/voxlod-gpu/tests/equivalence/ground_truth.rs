//! Kernel 3, the ground-truth renderer, on small builtin scenes covering every material kind:
//! `cornell` (point light, shadows), `island` (double-sided grass, the specular sea,
//! directional light), `blinds` (thin slats, many shadow edges) and `forest` with untextured
//! leaves (double-sided, sub-pixel); 48×40 pixels, 16 rays per pixel. [`textured`] adds the
//! textured and alpha-tested materials (the forest's alpha-masked leaves, BoxTextured, an
//! alpha-blended cornell), each with a control that must break the bound.
//!
//! - **CPU reference row**: the CPU renderer's claim of determinism — one thread gives the
//!   image of the default thread pool bit for bit. Bound: exact (every pixel, 0 steps).
//! - **GPU rows**: against the CPU render. Bound: **every channel within 1 step of 8-bit sRGB
//!   for at least 98 % of the pixels**. Why: both backends send the same rays (same PCG3D
//!   numbers, same stratification) and shade with the same function, so a sample's radiance
//!   agrees to ~1e-6 relative — under one sRGB step, but able to straddle a rounding boundary
//!   (hence 1 step, not 0). A sample whose camera or shadow ray passes within a few ULP of an
//!   edge may hit on one backend and miss on the other; it moves its pixel by up to 1/16 of
//!   the local contrast, several steps. Such grazing samples are rare (measured on lavapipe:
//!   see the table's note); 2 % of the pixels leaves room for other adapters' rounding.

use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth::{GBuffer, GroundTruth, Options, render};
use voxlod_gpu::ground_truth::GroundTruthKernel;
use voxlod_scene::Scene;

use crate::harness::{Executor, Measure};
use crate::images::{ImageBound, compare};

const EXACT: ImageBound = ImageBound { per_pixel: 0, fraction: 1.0 };
const GPU_BOUND: ImageBound = ImageBound { per_pixel: 1, fraction: 0.98 };

fn scenes() -> Vec<(&'static str, Scene, Options<'static>)> {
    let b = |name, kv: &[(&str, &str)]| {
        voxlod_scene::procedural::builtin(name, kv).expect("the builtin scene builds")
    };
    let base = Options { width: 48, height: 40, spp: 16, ..Options::default() };
    vec![
        ("gt-cornell", b("cornell", &[]), base),
        (
            "gt-island",
            b("island", &[("terrain", "16"), ("grass", "400"), ("rocks", "2")]),
            Options { seed: 3, ambient: glam::Vec3::splat(0.05), ..base },
        ),
        ("gt-blinds", b("blinds", &[("slats", "12"), ("tilt", "35")]), base),
        (
            "gt-forest",
            b("forest", &[("trees", "2"), ("leaves", "300"), ("alpha", "false")]),
            Options { shadows: true, seed: 9, ..base },
        ),
    ]
}

fn cpu(scene: &Scene, options: &Options) -> Result<GroundTruth, String> {
    let g = scene.geometry();
    let bvh = Bvh::new(&g).map_err(|e| e.to_string())?;
    let camera = scene.default_camera().map_err(|e| e.to_string())?;
    render(scene, &g, &bvh, &camera, options).map_err(|e| e.to_string())
}

/// G-buffer texels: the same triangle at the pixel centre except near ties (at most
/// [`GBUFFER_TIES`] of the pixels, where the centre ray passes within float rounding of an
/// edge), and where the triangle agrees, depth and position within 1e-4 relative (the `t`
/// bound of the raycast kernel), normal and albedo within 1e-4, coverage exactly the image's
/// alpha. Returns `(differing triangles, max error)`.
fn compare_gbuffer(a: &GBuffer, e: &GBuffer) -> (usize, f64) {
    let mut ties = 0;
    let mut worst = 0.0f64;
    for (p, q) in a.texels.iter().zip(&e.texels) {
        if p.triangle != q.triangle {
            ties += 1;
            continue;
        }
        if p.triangle == u32::MAX {
            worst = worst.max(if p.depth == q.depth { 0.0 } else { f64::INFINITY });
            continue;
        }
        let rel = |x: f32, y: f32| ((x - y).abs() / y.abs().max(1e-6)) as f64;
        worst = worst
            .max(rel(p.depth, q.depth))
            .max(((p.position - q.position).length() / q.position.length().max(1e-6)) as f64)
            .max((p.normal - q.normal).abs().max_element() as f64)
            .max((p.albedo - q.albedo).abs().max_element() as f64)
            .max((p.coverage - q.coverage).abs() as f64);
    }
    (ties, worst)
}

const GBUFFER_TIES: f64 = 0.01;
const GBUFFER_BOUND: f64 = 1e-4;

pub fn scenes_body(backend: &Executor) -> Result<Measure, String> {
    let kernel = match backend {
        Executor::Cpu => None,
        Executor::Gpu(ctx) => Some(GroundTruthKernel::new(ctx).map_err(|e| e.to_string())?),
    };
    let mut measures = Vec::new();
    for (name, scene, options) in scenes() {
        let expected = cpu(&scene, &options)?;
        let m = match &kernel {
            None => {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(1)
                    .build()
                    .map_err(|e| e.to_string())?;
                let one = pool.install(|| cpu(&scene, &options))?;
                let mut m = compare(name, &one.image, &expected.image, EXACT);
                if one.gbuffer != expected.gbuffer {
                    m.pass = false;
                    m.note += "; the G-buffer differs with one thread";
                }
                m
            }
            Some(k) => {
                let g = scene.geometry();
                let bvh = Bvh::new(&g).map_err(|e| e.to_string())?;
                let camera = scene.default_camera().map_err(|e| e.to_string())?;
                let start = std::time::Instant::now();
                let gpu = k.upload(&scene, &g, &bvh).map_err(|e| e.to_string())?;
                let actual = k.render(&gpu, &camera, &options).map_err(|e| e.to_string())?;
                let seconds = start.elapsed().as_secs_f64();
                let slug = format!("{name}-{}", backend_slug(backend));
                let mut m = compare(&slug, &actual.image, &expected.image, GPU_BOUND);
                let (ties, worst) = compare_gbuffer(&actual.gbuffer, &expected.gbuffer);
                let n = actual.gbuffer.texels.len();
                if ties as f64 > GBUFFER_TIES * n as f64 || worst > GBUFFER_BOUND {
                    m.pass = false;
                }
                m.note += &format!(
                    ", G-buffer: {ties} of {n} centre triangles differ (allowed {:.0} %), max \
                     error {worst:.2e} (bound {GBUFFER_BOUND:.0e}), {} triangles, {seconds:.2} s",
                    100.0 * GBUFFER_TIES,
                    g.triangle_count()
                );
                m
            }
        };
        measures.push(m);
    }
    Ok(Measure::combine(&measures))
}

pub fn backend_slug(backend: &Executor) -> String {
    backend
        .name()
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' })
        .take(24)
        .collect()
}

/// Random cameras (direction, distance, field of view, seed, shadows on/off) on `cornell` and
/// `blinds`, 24×20 pixels at 4 rays per pixel, each image within the bound of [`scenes_body`]
/// (`PROPTEST_CASES` sets how many; 24 by default, the same cases on every backend).
pub fn property(backend: &Executor) -> Result<Measure, String> {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
    let kernel = match backend {
        Executor::Cpu => None,
        Executor::Gpu(ctx) => Some(GroundTruthKernel::new(ctx).map_err(|e| e.to_string())?),
    };
    let b = |name, kv: &[(&str, &str)]| voxlod_scene::procedural::builtin(name, kv).unwrap();
    let scenes = [b("cornell", &[]), b("blinds", &[("slats", "8"), ("tilt", "-20")])];
    let uploaded = match &kernel {
        None => Vec::new(),
        Some(k) => scenes
            .iter()
            .map(|s| {
                let g = s.geometry();
                let bvh = Bvh::new(&g).map_err(|e| e.to_string())?;
                k.upload(s, &g, &bvh).map_err(|e| e.to_string())
            })
            .collect::<Result<Vec<_>, _>>()?,
    };
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(24);
    let mut runner = TestRunner::new_with_rng(
        Config { cases, failure_persistence: None, ..Config::default() },
        TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    );
    let strategy = (
        0usize..2,
        (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
        0.3f32..2.0,
        20.0f32..90.0,
        any::<u32>(),
        any::<bool>(),
    );
    let worst = std::cell::Cell::new(0.0f64);
    let count = std::cell::Cell::new(0usize);
    let slowest = std::cell::RefCell::new((0.0f64, String::new()));
    let result = runner.run(&strategy, |(which, (x, y, z), zoom, fov, seed, shadows)| {
        let dir = glam::Vec3::new(x, y, z);
        prop_assume!(dir.length() > 0.1);
        let scene = &scenes[which];
        let (lo, hi) = scene.bounds().unwrap();
        let radius = (hi - lo).length() * 0.5;
        let camera = voxlod_scene::Camera::framing(dir, (lo + hi) * 0.5, radius * zoom, fov);
        let options =
            Options { width: 24, height: 20, spp: 4, seed, shadows, ..Options::default() };
        let g = scene.geometry();
        let bvh = Bvh::new(&g).unwrap();
        let expected = render(scene, &g, &bvh, &camera, &options).unwrap().image;
        let start = std::time::Instant::now();
        let m = match &kernel {
            None => {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
                let one = pool.install(|| render(scene, &g, &bvh, &camera, &options)).unwrap();
                compare("gt-property-cpu", &one.image, &expected, EXACT)
            }
            Some(k) => {
                let actual = k.render(&uploaded[which], &camera, &options);
                let actual = actual.map_err(|e| TestCaseError::fail(e.to_string()))?;
                compare("gt-property-gpu", &actual.image, &expected, GPU_BOUND)
            }
        };
        count.set(count.get() + 1);
        worst.set(worst.get().max(m.max_error));
        let secs = start.elapsed().as_secs_f64();
        if secs > slowest.borrow().0 {
            *slowest.borrow_mut() = (
                secs,
                format!("{which} {dir} zoom {zoom} fov {fov} seed {seed} shadows {shadows}"),
            );
        }
        prop_assert!(m.pass, "{}", m.note);
        Ok(())
    });
    let bound = if kernel.is_some() { 1.0 - GPU_BOUND.fraction } else { 0.0 };
    let (secs, case) = slowest.into_inner();
    let mut note = format!(
        "{} random cameras on cornell and blinds, 24×20 at 4 spp; slowest case {secs:.2} s ({case})",
        count.get()
    );
    if let Err(e) = &result {
        note += &format!("; minimal failing case: {e}");
    }
    Ok(Measure { max_error: worst.get(), bound, pass: result.is_ok(), note })
}

/// The sample ranges of the dispatches do not change the image: cornell at 24×20, 20 rays per
/// pixel, in one dispatch and in dispatches of 3 samples (7 dispatches, the last short) must
/// agree **bit for bit** (the same samples added in the same order). On the CPU row, the CPU
/// render against itself with another seed must differ (the comparison can fail).
pub fn dispatch_split(backend: &Executor) -> Result<Measure, String> {
    let scene = voxlod_scene::procedural::builtin("cornell", &[]).unwrap();
    let g = scene.geometry();
    let bvh = Bvh::new(&g).map_err(|e| e.to_string())?;
    let camera = scene.default_camera().map_err(|e| e.to_string())?;
    let options = Options { width: 24, height: 20, spp: 20, ..Options::default() };
    let (a, b, expect_equal) = match backend {
        Executor::Cpu => {
            let a = render(&scene, &g, &bvh, &camera, &options).map_err(|e| e.to_string())?;
            let other = Options { seed: 1, ..options };
            let b = render(&scene, &g, &bvh, &camera, &other).map_err(|e| e.to_string())?;
            (a.image, b.image, false)
        }
        Executor::Gpu(ctx) => {
            let one = GroundTruthKernel::new(ctx).map_err(|e| e.to_string())?;
            let split = GroundTruthKernel::new(ctx)
                .map_err(|e| e.to_string())?
                .with_rays_per_dispatch(24 * 20 * 3);
            let up = one.upload(&scene, &g, &bvh).map_err(|e| e.to_string())?;
            let a = one.render(&up, &camera, &options).map_err(|e| e.to_string())?;
            let b = split.render(&up, &camera, &options).map_err(|e| e.to_string())?;
            if a.gbuffer != b.gbuffer {
                return Err("the G-buffer depends on the dispatch split".into());
            }
            (a.image, b.image, true)
        }
    };
    let differing = a.pixels.iter().zip(&b.pixels).filter(|(p, q)| p != q).count();
    let pass = (differing == 0) == expect_equal;
    let note = if expect_equal {
        format!("1 dispatch vs 7: {differing} of {} pixels differ (bound 0)", a.pixels.len())
    } else {
        format!(
            "control (no dispatches on the CPU): seed 0 vs seed 1 must differ, and {differing} of {} pixels do",
            a.pixels.len()
        )
    };
    // The control row's number is in its note: its error column stays 0 against bound 0, as
    // the filtered shadow control's, so the table never shows "394 > 0 … pass".
    let max_error = if expect_equal { differing as f64 } else { 0.0 };
    Ok(Measure { max_error, bound: 0.0, pass, note })
}

/// The scenes of [`textured`]: `forest` with its alpha-masked textured leaves (`alpha=true`,
/// 2 trees, 300 leaves), the Khronos BoxTextured model (a 256² sRGB base-colour texture) and
/// `cornell` with its two boxes alpha-blended (alpha 0.45: stochastic coverage on camera and
/// shadow rays), 48×40 at 16 rays per pixel.
fn textured_scenes() -> Result<Vec<(&'static str, Scene, Options<'static>)>, String> {
    let b = |name, kv: &[(&str, &str)]| {
        voxlod_scene::procedural::builtin(name, kv).expect("the builtin scene builds")
    };
    let base = Options { width: 48, height: 40, spp: 16, ..Options::default() };
    let boxed = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/BoxTextured/BoxTextured.glb");
    let boxed = Scene::load(&boxed).map_err(|e| format!("{}: {e}", boxed.display()))?;
    if boxed.textures.is_empty() {
        return Err("BoxTextured has no texture".into());
    }
    let mut blend = b("cornell", &[]);
    blend.materials.push(voxlod_scene::Material {
        name: "glass".into(),
        base_color: glam::Vec4::new(0.9, 0.8, 0.2, 0.45),
        alpha_mode: voxlod_scene::AlphaMode::Blend,
        ..Default::default()
    });
    blend.meshes[1].material = blend.materials.len() - 1;
    Ok(vec![
        (
            "gt-forest-alpha",
            b(
                "forest",
                &[("trees", "2"), ("leaves", "300"), ("leaf_size", "0.6"), ("alpha", "true")],
            ),
            Options { seed: 9, ..base },
        ),
        ("gt-box-textured", boxed, Options { ambient: glam::Vec3::splat(0.1), ..base }),
        ("gt-cornell-blend", blend, Options { seed: 5, ..base }),
    ])
}

/// Every texture shifted by one texel along u (texel x takes texel x + 1's value).
fn shift_textures(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for t in &mut s.textures {
        let (w, h) = (t.width as usize, t.height as usize);
        let texels: Vec<[u8; 4]> =
            (0..w * h).map(|i| t.texels[(i / w) * w + (i % w + 1) % w]).collect();
        t.texels = std::sync::Arc::from(texels);
    }
    s
}

/// The control perturbation of each textured scene, and what it shows: the box's texture
/// shifted by one texel (addressing), the forest's leaves made opaque (the mask ignored), the
/// blended boxes' alpha 0.45 → 0.35 (the blend coverage off by 0.1).
fn perturbed(name: &str, scene: &Scene) -> (Scene, &'static str) {
    use voxlod_scene::AlphaMode;
    let mut s = scene.clone();
    match name {
        "gt-box-textured" => (shift_textures(scene), "texture shifted one texel"),
        "gt-forest-alpha" => {
            for m in &mut s.materials {
                m.alpha_mode = AlphaMode::Opaque;
            }
            (s, "alpha mask ignored")
        }
        _ => {
            for m in &mut s.materials {
                if m.alpha_mode == AlphaMode::Blend {
                    m.base_color.w -= 0.1;
                }
            }
            (s, "blend alpha 0.45 → 0.35")
        }
    }
}

/// Kernel 3 on textured, alpha-masked and alpha-blended materials ([`textured_scenes`]).
///
/// - **CPU reference row**: one thread gives the default pool's image and G-buffer bit for
///   bit (exact).
/// - **GPU rows**: the bound of [`scenes_body`] (1 sRGB step for ≥ 98 % of the pixels; the
///   G-buffer's same-triangle and 1e-4 bounds, albedo now textured). Why it still holds: the
///   texture samples agree to 2^-21 (the `materials (exact)` row), far under an sRGB step, and
///   both backends draw the same blend numbers with the same keys and sample indices; what is
///   new is that a sample whose alpha lands within ~1e-6 of a mask cutoff (or of its blend
///   number) can flip, as rare as an edge graze and moving its pixel by the same 1/16.
/// - **Control, both rows**: each scene rendered wrongly on purpose ([`perturbed`]: the box's
///   texture shifted by one texel, the forest's mask ignored, the blend alpha off by 0.1) must
///   break that bound against the unperturbed CPU reference (on the CPU row, the CPU renders
///   the perturbed scene). (A one-texel shift of the forest's leaf texture does not: its
///   leaves are sub-pixel at 48×40 and the shift leaves every pixel within 0 steps.)
pub fn textured(backend: &Executor) -> Result<Measure, String> {
    let kernel = match backend {
        Executor::Cpu => None,
        Executor::Gpu(ctx) => Some(GroundTruthKernel::new(ctx).map_err(|e| e.to_string())?),
    };
    let render_on = |scene: &Scene, options: &Options| -> Result<GroundTruth, String> {
        match &kernel {
            None => cpu(scene, options),
            Some(k) => {
                let g = scene.geometry();
                let bvh = Bvh::new(&g).map_err(|e| e.to_string())?;
                let camera = scene.default_camera().map_err(|e| e.to_string())?;
                let up = k.upload(scene, &g, &bvh).map_err(|e| e.to_string())?;
                k.render(&up, &camera, options).map_err(|e| e.to_string())
            }
        }
    };
    let mut measures = Vec::new();
    for (name, scene, options) in textured_scenes()? {
        let expected = cpu(&scene, &options)?;
        let start = std::time::Instant::now();
        let mut m = match &kernel {
            None => {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(1)
                    .build()
                    .map_err(|e| e.to_string())?;
                let one = pool.install(|| cpu(&scene, &options))?;
                let mut m = compare(name, &one.image, &expected.image, EXACT);
                if one.gbuffer != expected.gbuffer {
                    m.pass = false;
                    m.note += "; the G-buffer differs with one thread";
                }
                m
            }
            Some(_) => {
                let actual = render_on(&scene, &options)?;
                let slug = format!("{name}-{}", backend_slug(backend));
                let mut m = compare(&slug, &actual.image, &expected.image, GPU_BOUND);
                let (ties, worst) = compare_gbuffer(&actual.gbuffer, &expected.gbuffer);
                let n = actual.gbuffer.texels.len();
                if ties as f64 > GBUFFER_TIES * n as f64 || worst > GBUFFER_BOUND {
                    m.pass = false;
                }
                m.note += &format!(
                    ", G-buffer: {ties} of {n} centre triangles differ, max error {worst:.2e}"
                );
                m
            }
        };
        let (wrong, what) = perturbed(name, &scene);
        let control = render_on(&wrong, &options)?;
        let c = compare(&format!("{name}-control"), &control.image, &expected.image, GPU_BOUND);
        let step = crate::images::worst_step(&control.image, &expected.image);
        m.note += &format!(
            "; control ({what}): {:.1} % of pixels over 1 step, worst {step} (must break the \
             bound)",
            100.0 * c.max_error
        );
        if c.pass {
            m.pass = false;
            m.note += " — CONTROL PASSED: the check cannot see it";
        }
        m.note += &format!(", {:.2} s", start.elapsed().as_secs_f64());
        measures.push(m);
    }
    Ok(Measure::combine(&measures))
}
