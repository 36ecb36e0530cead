//! Kernel 5, cone tracing from shading points (AO, diffuse `E/π`, specular radiance) through a
//! radiance octree, against voxlod-cone's [`ConeTracer`] on the CPU
//! ([`voxlod_gpu::cone::reference`], per point).
//!
//! - **CPU reference row**: the kernel's sampling algorithm, ported to Rust over the flat
//!   layout ([`FlatOctree`]: the descent from the finest dense level and the +x/+y/+z tile
//!   links of [`FlatOctree::neighbour`]'s rule, as `cone.wgsl` reads them), equals
//!   [`Octree::sample_at_level`] **bit for bit** at random positions (inside, on node centres
//!   and boundaries, outside the cube) and fractional levels, on every scene of the row; so the
//!   GPU walks the same corners with the same weights. Bound: exact.
//! - **GPU rows**: per shading point, the error is the largest of |ΔAO| and, per RGB channel of
//!   `E/π` and of the specular radiance, |Δ| / max(1, |CPU value|) (absolute below 1, relative
//!   above: the scenes' radiances are O(1) up to a lit wall's). Bound: [`BOUND`] **1e-3 for
//!   at least 99 % of the points**, every point within [`HARD`] 0.05. Why: the kernel follows
//!   the CPU's arithmetic in its order, so what differs is rounding — grid coordinates in
//!   `f32` on the GPU (the CPU goes through `f64`), WGSL's `log2`/`exp2`/`pow`/`tan` (Vulkan
//!   allows a few ULP, or 2⁻²¹ absolute for `log2` near 1) and fused multiply-adds — which moves
//!   a continuous march by ~1e-6. The march is discontinuous only where its sample count
//!   changes: a step landing within rounding of `max_distance`, of the AO radius test or of the
//!   opacity cutoff adds or drops one sample (the cube's exit is continuous: its last step's
//!   opacity is scaled by the distance left). One sample of one of `n` cones moves `E/π` by at
//!   most its weight over `n`, hence the fraction and the hard cap rather than a bound on
//!   every point. The note gives the measured worst error, the points over 1e-3 and the
//!   points whose sample count differs. Measured on lavapipe (Mesa 22.3.6): worst 9.0e-6 on
//!   the scenes, 1.2e-6 on the random cases, no point over 1e-3, no sample count differing.
//! - **Control row**: the same check against a CPU reference traced with `step_factor` 5 %
//!   larger must FAIL (more than 1 % of the points over the bound): the check sees a change
//!   of the march that small.

use std::sync::OnceLock;

use glam::{DVec3, UVec3, Vec3};
use voxlod_cone::{ConeMedium, ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
use voxlod_cpu::appearance::averages;
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::random::rand_f32;
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_cpu::voxelize;
use voxlod_format::{GridSpec, morton};
use voxlod_gpu::cone::{ConeKernel, ConeQuery, ConeShade, GpuMedium, ShadingPoint, reference};
use voxlod_octree::{AveragePayload, BuildOptions, Directional, FlatOctree, NONE, Octree, Payload};

use crate::harness::{Executor, Measure};

/// Per-point bound (module docs).
pub const BOUND: f64 = 1e-3;
/// Fraction of the points that must be within [`BOUND`].
pub const FRACTION: f64 = 0.99;
/// Every point within this.
pub const HARD: f64 = 0.05;

type Iso = Octree<RadiancePayload>;
type Dir = Octree<Directional<RadiancePayload>>;

/// One case: an octree pair (isotropic, directional), options, query, points (an image
/// `width` wide).
struct Case {
    name: String,
    iso: Iso,
    dir: Dir,
    options: TraceOptions,
    query: ConeQuery,
    points: Vec<ShadingPoint>,
    width: u32,
}

/// The floor and ceiling of voxlod-cone's doc test (16³, light from above), shading points
/// on the floor with normals tilted around +y.
fn floor_ceiling() -> Case {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(16)).unwrap();
    let mut voxels = Vec::new();
    for x in 0..16 {
        for z in 0..16 {
            voxels.push((UVec3::new(x, 0, z), AveragePayload::new(Vec3::ONE, Vec3::Y, 1.0)));
            voxels.push((UVec3::new(x, 8, z), AveragePayload::new(Vec3::ONE, Vec3::NEG_Y, 1.0)));
        }
    }
    let geometry = Octree::build(grid, voxels, &BuildOptions::default()).unwrap();
    let light = Light::Directional { to_light: Vec3::Y, irradiance: Vec3::splat(3.0) };
    let iso = inject(&geometry, &light, &Shadows::MARCH).unwrap();
    let dir = inject(&geometry, &light, &Shadows::MARCH).unwrap();
    let width = 16;
    let points = (0..width * width)
        .map(|i| {
            let (x, z) = ((i % width) as f32, (i / width) as f32);
            let tilt = Vec3::new((x - 7.5) / 10.0, 1.0, (z - 7.5) / 10.0);
            ShadingPoint {
                position: Vec3::new(x + 0.5, 1.0, z + 0.5),
                normal: tilt,
                to_viewer: Vec3::new(8.0, 6.0, 20.0) - Vec3::new(x, 1.0, z),
                glossiness: (i % 5) as f32 / 4.0,
            }
        })
        .collect();
    let options = TraceOptions { ao_radius: 6.0, ..TraceOptions::default() };
    Case {
        name: "floor+ceiling 16³".into(),
        iso,
        dir,
        options,
        query: ConeQuery::ALL,
        points,
        width,
    }
}

/// builtin:cornell through `voxlod cone`'s pipeline at 32³ (conservative voxelization,
/// Averages from 32 lines per voxel, octree with 16³ dense top, light injected with marched
/// shadows), shading points from the ground-truth G-buffer (32×32, default camera).
fn cornell() -> Case {
    let scene = voxlod_scene::procedural::builtin("cornell", &[]).unwrap();
    let geometry = scene.geometry();
    let bvh = Bvh::new(&geometry).unwrap();
    let camera = scene.default_camera().unwrap();
    let (lo, hi) = scene.bounds().unwrap();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 32).unwrap();
    let vox = voxelize::voxelize(&geometry, &grid, &voxelize::Options::default()).unwrap();
    let ctx = SamplingContext::new(&scene, &geometry, &vox).unwrap();
    let records =
        precompute(&ctx, &PrecomputeOptions { rays: 32, seed: 0 }, averages::fit).unwrap();
    let options = BuildOptions { depth: None, dense_log2: 4 };
    let tree =
        Octree::from_brick_map(grid, &records.records, AveragePayload::from_record, &options)
            .unwrap();
    let light = match scene.light() {
        voxlod_scene::Light::Directional { to_light, irradiance } => {
            Light::Directional { to_light, irradiance }
        }
        voxlod_scene::Light::Point { position, intensity } => Light::Point { position, intensity },
    };
    let iso = inject(&tree, &light, &Shadows::MARCH).unwrap();
    let dir = inject(&tree, &light, &Shadows::MARCH).unwrap();
    let size = 32;
    let gb = ground_truth::gbuffer(&scene, &geometry, &bvh, &camera, size, size).unwrap();
    let points = ShadingPoint::from_gbuffer(&gb, camera.eye, 0.7);
    let radius = 0.1 * (hi - lo).length();
    let options = TraceOptions { ao_radius: radius, ..TraceOptions::default() };
    Case {
        name: "cornell 32³".into(),
        iso,
        dir,
        options,
        query: ConeQuery::ALL,
        points,
        width: size,
    }
}

fn scene_cases() -> &'static [Case] {
    static CASES: OnceLock<Vec<Case>> = OnceLock::new();
    CASES.get_or_init(|| vec![floor_ceiling(), cornell()])
}

/// Random voxel sets in random grids (8..40 per axis, dense top of 1..16 per axis, random
/// colours and opacities), lit from a random direction (injection without shadows, fast),
/// with random options — apertures 0, near 0, random and near 180°, step factors 0.05 … 4,
/// finite or infinite `max_distance` — and random shading points (inside and outside the
/// grid) whose normals and view vectors are exactly along an axis for a third of them.
fn property_cases() -> &'static [Case] {
    static CASES: OnceLock<Vec<Case>> = OnceLock::new();
    CASES.get_or_init(|| (0..10).map(random_case).collect())
}

fn random_case(seed: u32) -> Case {
    let r = |i: u32, d: u32| rand_f32(seed * 7919 + i, 41, d);
    let dims = UVec3::new(
        8 + (r(0, 0) * 32.0) as u32,
        8 + (r(0, 1) * 32.0) as u32,
        8 + (r(0, 2) * 32.0) as u32,
    );
    let grid = GridSpec::new(
        DVec3::new(r(0, 3) as f64 - 0.5, -2.0 * r(0, 4) as f64, 3.0),
        0.25 + r(0, 5) as f64,
        dims,
    )
    .unwrap();
    let n = 40 + (r(0, 6) * 400.0) as u32;
    let mut coords: Vec<UVec3> = (0..n)
        .map(|i| {
            // Clustered in a slab and scattered, so that some cones meet walls.
            let c = Vec3::new(r(i, 10), r(i, 11), r(i, 12)) * dims.as_vec3();
            let c = if i % 2 == 0 { Vec3::new(c.x, dims.y as f32 * 0.5, c.z) } else { c };
            c.as_uvec3().min(dims - 1)
        })
        .collect();
    coords.sort_by_key(|c| morton::encode(*c));
    coords.dedup();
    let voxels: Vec<_> = coords
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let i = i as u32;
            let colour = Vec3::new(r(i, 20), r(i, 21), r(i, 22));
            let normal = Vec3::new(r(i, 23) - 0.5, r(i, 24) - 0.5, r(i, 25) - 0.5);
            (c, AveragePayload::new(colour, normal, 0.2 + 0.8 * r(i, 26)))
        })
        .collect();
    let dense_log2 = (r(0, 7) * 5.0) as u32;
    let geometry = Octree::build(grid, voxels, &BuildOptions { depth: None, dense_log2 }).unwrap();
    let to_light = Vec3::new(r(0, 8) - 0.5, 1.0, r(0, 9) - 0.5);
    let light = Light::Directional { to_light, irradiance: Vec3::splat(std::f32::consts::PI) };
    let iso = inject(&geometry, &light, &Shadows::None).unwrap();
    let dir = inject(&geometry, &light, &Shadows::None).unwrap();
    // (aperture, step) pairs: the short steps go with wide cones, the rays with long steps,
    // so that no case marches thousands of samples (a workgroup of 64 points runs on one
    // lavapipe thread).
    let pairs = [
        (0.0, 1.0 + r(0, 31)),
        (0.01, 4.0),
        (1.0 + 150.0 * r(0, 30), 0.3 + r(0, 31)),
        (179.0, 0.05),
        (179.99, 0.5),
    ];
    let (aperture, step) = pairs[seed as usize % pairs.len()];
    let voxel = grid.voxel_size as f32;
    let extent = dims.max_element() as f32 * voxel;
    let options = TraceOptions {
        // One cone (along the normal: exactly along an axis for the axis-aligned normals)
        // in every other case.
        diffuse_cones: if seed % 2 == 1 { 1 } else { 2 + (r(0, 32) * 5.0) as u32 },
        diffuse_aperture_deg: aperture,
        step_factor: step,
        normal_offset_voxels: 2.0 * r(0, 33),
        start_voxels: 2.0 * r(0, 34),
        ao_radius: (0.05 + r(0, 35)) * extent,
        max_distance: if seed.is_multiple_of(3) {
            (0.2 + r(0, 36)) * extent
        } else {
            f32::INFINITY
        },
        opacity_cutoff: [0.99, 1.0, 0.5][seed as usize % 3],
    };
    let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
    let width = 8;
    let origin = grid.origin.as_vec3();
    let points = (0..64u32)
        .map(|i| {
            let u = Vec3::new(r(i, 40), r(i, 41), r(i, 42)) * 1.2 - 0.1;
            let position = origin + u * dims.as_vec3() * voxel;
            let random = Vec3::new(r(i, 43), r(i, 44), r(i, 45)) * 2.0 - 1.0;
            let (normal, to_viewer) = if i % 3 == 0 {
                (axes[(i / 3) as usize % 6], axes[(i / 3 + 1 + i % 2) as usize % 6])
            } else {
                (random, Vec3::new(r(i, 46), r(i, 47), r(i, 48)) * 2.0 - 1.0)
            };
            ShadingPoint {
                position,
                normal,
                to_viewer,
                glossiness: [0.0, 1.0, r(i, 49)][i as usize % 3],
            }
        })
        .collect();
    let query = match seed % 4 {
        0 => ConeQuery::ALL,
        1 => ConeQuery { ambient_occlusion: true, diffuse: false, specular: false },
        2 => ConeQuery { ambient_occlusion: false, diffuse: true, specular: true },
        _ => ConeQuery { ambient_occlusion: true, diffuse: true, specular: false },
    };
    Case { name: format!("random {seed}"), iso, dir, options, query, points, width }
}

/// The per-point error of the module docs.
fn point_error(a: &ConeShade, e: &ConeShade, q: ConeQuery) -> f64 {
    let rel = |x: Vec3, y: Vec3| {
        (0..3).map(|c| ((x[c] - y[c]).abs() / y[c].abs().max(1.0)) as f64).fold(0.0, f64::max)
    };
    let mut err = 0.0f64;
    if q.ambient_occlusion {
        err = err.max((a.ao - e.ao).abs() as f64);
    }
    if q.diffuse {
        err = err.max(rel(a.diffuse, e.diffuse));
    }
    if q.specular {
        err = err.max(rel(a.specular, e.specular));
    }
    if !err.is_finite() { f64::INFINITY } else { err }
}

#[derive(Default)]
struct Tally {
    points: usize,
    over: usize,
    worst: f64,
    step_diffs: usize,
    worst_at: String,
}

impl Tally {
    fn add(&mut self, name: &str, actual: &[ConeShade], expected: &[ConeShade], q: ConeQuery) {
        for (i, (a, e)) in actual.iter().zip(expected).enumerate() {
            self.points += 1;
            let err = point_error(a, e, q);
            if err > BOUND {
                self.over += 1;
            }
            if (a.diffuse_steps, a.specular_steps) != (e.diffuse_steps, e.specular_steps) {
                self.step_diffs += 1;
            }
            if err > self.worst {
                self.worst = err;
                self.worst_at = format!("{name} point {i}: got {a:?}, CPU {e:?}");
            }
        }
        if actual.len() != expected.len() {
            self.over += expected.len().abs_diff(actual.len());
            self.worst = f64::INFINITY;
        }
    }

    fn measure(&self, what: &str) -> Measure {
        let fraction = self.over as f64 / self.points.max(1) as f64;
        let pass = fraction <= 1.0 - FRACTION && self.worst <= HARD;
        let mut note = format!(
            "{what}: {} points, {} over {BOUND:e} ({:.2} %, allowed {:.0} %), worst {:.2e} \
             (cap {HARD}), {} with another sample count",
            self.points,
            self.over,
            100.0 * fraction,
            100.0 * (1.0 - FRACTION),
            self.worst,
            self.step_diffs
        );
        if !pass || self.worst > BOUND {
            note += &format!("; worst at {}", self.worst_at);
        }
        Measure { max_error: self.worst, bound: BOUND, pass, note }
    }
}

fn cpu_shades<M: ConeMedium + Sync>(
    tree: &Octree<M>,
    options: TraceOptions,
    q: ConeQuery,
    points: &[ShadingPoint],
) -> Result<Vec<ConeShade>, String> {
    use rayon::prelude::*;
    let tracer = ConeTracer::new(tree, options).map_err(|e| e.to_string())?;
    Ok(points.par_iter().map(|p| reference(&tracer, p, q)).collect())
}

fn gpu_shades<M: GpuMedium>(
    kernel: &ConeKernel,
    tree: &Octree<M>,
    options: TraceOptions,
    q: ConeQuery,
    points: &[ShadingPoint],
    width: u32,
) -> Result<Vec<ConeShade>, String> {
    let up = kernel.upload(tree).map_err(|e| e.to_string())?;
    let t = std::time::Instant::now();
    let out = kernel.trace(&up, &options, q, points, width).map_err(|e| e.to_string());
    TRACE_SECONDS.with(|s| s.set(s.get() + t.elapsed().as_secs_f64()));
    out
}

thread_local! {
    /// Seconds spent in `ConeKernel::trace` (compilation on first use included), for notes.
    static TRACE_SECONDS: std::cell::Cell<f64> = const { std::cell::Cell::new(0.0) };
}

/// GPU vs CPU on `cases`, both payloads; on the CPU backend the flat-layout sampling check.
fn compare_cases(backend: &Executor, cases: &[Case], what: &str) -> Result<Measure, String> {
    let ctx = match backend {
        Executor::Cpu => return flat_sampling(cases, what),
        Executor::Gpu(ctx) => ctx,
    };
    let kernel = ConeKernel::new(ctx);
    TRACE_SECONDS.with(|s| s.set(0.0));
    let mut tally = Tally::default();
    for c in cases {
        let (o, q, w) = (c.options, c.query, c.width);
        let want = cpu_shades(&c.iso, o, q, &c.points)?;
        let got = gpu_shades(&kernel, &c.iso, o, q, &c.points, w)?;
        tally.add(&format!("{} isotropic", c.name), &got, &want, q);
        let want = cpu_shades(&c.dir, o, q, &c.points)?;
        let got = gpu_shades(&kernel, &c.dir, o, q, &c.points, w)?;
        tally.add(&format!("{} directional", c.name), &got, &want, q);
    }
    let mut m = tally.measure(what);
    m.note += &format!("; {:.2} s in GPU traces", TRACE_SECONDS.with(|s| s.get()));
    Ok(m)
}

/// The floor+ceiling and cornell scenes (module docs).
pub fn scenes(backend: &Executor) -> Result<Measure, String> {
    compare_cases(
        backend,
        scene_cases(),
        "floor+ceiling 16³, cornell 32³ (32×32 G-buffer); iso + dir",
    )
}

/// Random voxel sets, options and points (module docs).
pub fn property(backend: &Executor) -> Result<Measure, String> {
    compare_cases(backend, property_cases(), "10 random octrees × 64 points; iso + dir")
}

/// The control: the same check against a reference traced with `step_factor` ×1.05 must fail.
pub fn control(backend: &Executor) -> Result<Measure, String> {
    let c = &scene_cases()[1];
    let q = c.query;
    let perturbed = TraceOptions { step_factor: c.options.step_factor * 1.05, ..c.options };
    let want = cpu_shades(&c.iso, perturbed, q, &c.points)?;
    let got = match backend {
        Executor::Cpu => cpu_shades(&c.iso, c.options, q, &c.points)?,
        Executor::Gpu(ctx) => {
            gpu_shades(&ConeKernel::new(ctx), &c.iso, c.options, q, &c.points, c.width)?
        }
    };
    let mut tally = Tally::default();
    tally.add("cornell, step ×1.05", &got, &want, q);
    let m = tally.measure("cornell vs a reference with step_factor ×1.05 (must FAIL the check)");
    let caught = !m.pass;
    Ok(Measure {
        max_error: m.max_error,
        bound: BOUND,
        pass: caught,
        note: format!("{} → {}", m.note, if caught { "caught" } else { "NOT caught" }),
    })
}

/// Bad options get voxlod-cone's error word for word on the GPU path.
pub fn errors(backend: &Executor) -> Result<Measure, String> {
    let c = &scene_cases()[0];
    let bad = [
        TraceOptions { diffuse_aperture_deg: 180.0, ..c.options },
        TraceOptions { step_factor: 0.0, ..c.options },
        TraceOptions { diffuse_cones: 0, ..c.options },
        TraceOptions { ao_radius: f32::NAN, ..c.options },
    ];
    let mut wrong = Vec::new();
    for o in bad {
        let want = ConeTracer::new(&c.iso, o).err().map(|e| e.to_string());
        let got = match backend {
            Executor::Cpu => ConeTracer::new(&c.iso, o).err().map(|e| e.to_string()),
            Executor::Gpu(ctx) => {
                let k = ConeKernel::new(ctx);
                let up = k.upload(&c.iso).map_err(|e| e.to_string())?;
                k.trace(&up, &o, c.query, &c.points, c.width).err().map(|e| e.to_string())
            }
        };
        if want.is_none() || got != want {
            wrong.push(format!("{got:?} vs {want:?}"));
        }
    }
    Ok(Measure {
        max_error: wrong.len() as f64,
        bound: 0.0,
        pass: wrong.is_empty(),
        note: if wrong.is_empty() {
            "4 bad TraceOptions: the same error text".into()
        } else {
            wrong.join("; ")
        },
    })
}

// ---- the CPU row: the kernel's flat-layout sampling, in Rust ----

/// `cone.wgsl`'s `find`.
fn flat_find<P>(f: &FlatOctree<P>, top: u32, level: u32, c: UVec3) -> u32 {
    let mut idx = f.levels[top as usize].first + morton::encode(c >> (top - level)) as u32;
    for lv in (level + 1..=top).rev() {
        let child = f.nodes[idx as usize].child;
        if child == NONE {
            return NONE;
        }
        let o = (c >> (lv - 1 - level)) & UVec3::ONE;
        idx = child + o.x + 2 * o.y + 4 * o.z;
    }
    idx
}

/// `cone.wgsl`'s `sample_level` over the flat layout.
fn flat_sample_level<P: Payload>(f: &FlatOctree<P>, top: u32, pos: Vec3, level: u32) -> P {
    let mut out = P::empty();
    let res = 1i32 << (f.depth - level);
    let u = pos * (1.0 / (1u32 << level) as f32) - 0.5;
    let lower = u.floor();
    if !pos.is_finite()
        || lower.cmplt(Vec3::splat(-1.0)).any()
        || lower.cmpge(Vec3::splat(res as f32)).any()
    {
        return out;
    }
    let base = lower.as_ivec3();
    let fr = u - lower;
    let start = base.max(glam::IVec3::ZERO);
    let s = start.as_uvec3();
    let lv = f.levels[level as usize];
    let mut n = [NONE; 8];
    if lv.dense == 1 {
        for (e, slot) in n.iter_mut().enumerate() {
            let c = s + UVec3::new(e as u32 & 1, e as u32 >> 1 & 1, e as u32 >> 2 & 1);
            if c.cmplt(UVec3::splat(res as u32)).all() {
                *slot = lv.first + morton::encode(c) as u32;
            }
        }
    } else {
        let hop = |i: u32, a: usize| {
            if i == NONE { NONE } else { f.neighbour(level, i, a).unwrap_or(NONE) }
        };
        n[0] = flat_find(f, top, level, s);
        n[1] = hop(n[0], 0);
        n[2] = hop(n[0], 1);
        n[4] = hop(n[0], 2);
        n[3] = hop(n[1], 1);
        n[5] = hop(n[1], 2);
        n[6] = hop(n[2], 2);
        n[7] = hop(n[3], 2);
    }
    for e in 0..8u32 {
        let off = glam::IVec3::new((e & 1) as i32, (e >> 1 & 1) as i32, (e >> 2 & 1) as i32);
        let c = base + off;
        if c.cmplt(glam::IVec3::ZERO).any() || c.cmpge(glam::IVec3::splat(res)).any() {
            continue;
        }
        let d = c - start;
        let node = n[(d.x + 2 * d.y + 4 * d.z) as usize];
        if node == NONE {
            continue;
        }
        let w = Vec3::select(off.cmpeq(glam::IVec3::ZERO), 1.0 - fr, fr).element_product();
        out.add_scaled(&f.payload[node as usize], w);
    }
    out
}

fn flat_sample<P: Payload>(f: &FlatOctree<P>, top: u32, pos: Vec3, level: f32) -> P {
    let l0 = level.floor() as u32;
    let t = level - l0 as f32;
    let mut out = flat_sample_level(f, top, pos, l0);
    if t > 0.0 && l0 < f.depth {
        let upper = flat_sample_level(f, top, pos, l0 + 1);
        let mut mixed = P::empty();
        mixed.add_scaled(&out, 1.0 - t);
        mixed.add_scaled(&upper, t);
        out = mixed;
    }
    out
}

/// Flat-layout samples vs [`Octree::sample_at_level`] at 2000 positions per octree: the
/// number of differing bit patterns.
fn flat_mismatches<P: Payload + PartialEq>(tree: &Octree<P>, seed: u32) -> Result<usize, String> {
    let f = FlatOctree::from_octree(tree).map_err(|e| e.to_string())?;
    let res = (1u32 << tree.depth()) as f32;
    let mut bad = 0;
    for i in 0..2000u32 {
        let r = |d: u32| rand_f32(seed.wrapping_add(i), 77, d);
        let mut pos = Vec3::new(r(0), r(1), r(2)) * (res + 4.0) - 2.0;
        if i % 4 == 0 {
            // On node centres and boundaries of some level.
            let l = (r(3) * (tree.depth() + 1) as f32) as u32;
            let scale = (1u32 << l) as f32;
            pos = (pos / scale).floor() * scale + if i % 8 == 0 { scale * 0.5 } else { 0.0 };
        }
        let level = [0.0, 1.0, r(4) * tree.depth() as f32, tree.depth() as f32][i as usize % 4];
        let a = flat_sample(&f, tree.first_dense(), pos, level);
        let b = tree.sample_at_level(pos, level);
        if a != b {
            bad += 1;
        }
    }
    Ok(bad)
}

fn flat_sampling(cases: &[Case], what: &str) -> Result<Measure, String> {
    let mut bad = 0;
    let mut n = 0;
    for (k, c) in cases.iter().enumerate() {
        bad += flat_mismatches(&c.iso, k as u32 * 5000)?;
        bad += flat_mismatches(&c.dir, k as u32 * 5000 + 2500)?;
        n += 4000;
    }
    Ok(Measure {
        max_error: bad as f64,
        bound: 0.0,
        pass: bad == 0,
        note: format!(
            "{what}: the kernel's flat-layout sampling (Rust port) vs Octree::sample_at_level \
             at {n} positions × levels: {bad} differ (bit for bit)"
        ),
    })
}
