//! Heitz–Neyret differential cone tracing with coverage masks through a `MicrosurfacePayload`
//! octree, against voxlod-cone's [`DifferentialRenderer`] shaded by
//! [`voxlod_gpu::differential::shade_element`] on the CPU ([`reference`]), and the kernel's
//! `f32` Smith functions against `f64`.
//!
//! - **CPU reference rows** (scenes, proptest): the kernel's sampling algorithm ported to Rust
//!   over the flat layout, corners moved to the sample point with `add_scaled_at` as
//!   `differential.wgsl` does, equals [`Octree::sample_at_level`] **bit for bit** at random
//!   positions and fractional levels. Bound: exact.
//! - **GPU rows** (scenes, proptest): images compared on 8-bit sRGB: at most [`BOUND`] steps
//!   per channel for at least [`FRACTION`] of the pixels, and the total element count within
//!   [`ELEMENTS`] of the CPU's. Why not every pixel: the march is continuous in the
//!   arithmetic's rounding (world positions in `f32`, WGSL's `exp`/`log2`/`atan2`/`pow`,
//!   fused multiply-adds) except where a discrete choice flips — a mask-table cell (θ or `v`
//!   on a cell boundary moves a few of the 128 rays: a few rays' share of one element), an
//!   element landing within rounding of the march's end, the shadow cache's distance test.
//!   Measured on lavapipe (Mesa 22.3.6): no pixel over one step, the largest linear RGBA
//!   difference 1.2e-7 (scenes) and 1.4e-6 (random cases), the same element counts.
//! - **Smith rows**: the kernel's `f32` Λ (from `cos θ`, `sin θ`, `σ` over θ ∈ [1e-6, π/2],
//!   σ ∈ [1e-6, 1e6], and the special inputs) and `erfc` (x ∈ [−9, 9.5]) against voxlod-octree's
//!   `f64` [`lambda`] / [`erfc_f64`] at the same inputs: relative error at most [`SMITH_BOUND`]
//!   where the `f64` value lies in `[1e-30, 1e28]` (Λ) or `[1e-30, 2]` (erfc), and below `1e-29`
//!   where it is smaller; never negative, never above the clamp. On the CPU row the same check
//!   runs the Rust mirror of the kernel's arithmetic (`lambda_cs_f32`, `erfc_f32`). Measured:
//!   worst 1.5e-5 (Rust `f32`), 3.2e-5 (lavapipe).
//! - **Control row**: the scenes' check against a CPU reference rendered with elements 5 %
//!   longer must FAIL.

use glam::{DVec3, UVec3, Vec3};
use voxlod_cone::{
    Compositing, DepthOfField, DifferentialOptions, DifferentialRenderer, Light, PinholeCamera,
};
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_cpu::appearance::microsurface;
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::random::rand_f32;
use voxlod_cpu::voxelize;
use voxlod_format::records::MicrosurfaceRecord;
use voxlod_format::{GridSpec, morton};
use voxlod_gpu::differential::{DifferentialKernel, reference};
use voxlod_octree::microsurface::smith::{LAMBDA_MAX_F32, lambda, lambda_cs_f32};
use voxlod_octree::microsurface::special::{erfc_f32, erfc_f64};
use voxlod_octree::{BuildOptions, FlatOctree, MicrosurfacePayload, NONE, Octree, Payload};
use voxlod_scene::Image;

use crate::harness::{Executor, Measure};
use crate::images::{ImageBound, compare};

/// Per-channel bound, 8-bit sRGB steps (module docs).
pub const BOUND: u8 = 2;
/// Fraction of the pixels that must be within [`BOUND`].
pub const FRACTION: f64 = 0.98;
/// Largest relative difference of the total element count.
pub const ELEMENTS: f64 = 0.005;
/// Relative bound of the `f32` Smith functions against `f64` (module docs).
pub const SMITH_BOUND: f64 = 1e-4;

/// One frame: a renderer's octree, camera, light and options, and the ambient term.
struct Case {
    name: String,
    tree: Octree<MicrosurfacePayload>,
    camera: PinholeCamera,
    light: Light,
    options: DifferentialOptions,
    ambient: Vec3,
}

fn record(local: Vec3, n: Vec3, albedo: Vec3, slope: Vec3, spread: f32) -> MicrosurfaceRecord {
    let n = n.normalize();
    let t = spread;
    let m = [n.x * n.x, n.y * n.y, n.z * n.z, n.x * n.y, n.x * n.z, n.y * n.z]
        .map(|x| x * (1.0 - 3.0 * t));
    MicrosurfaceRecord {
        centroid: local.to_array(),
        plane_normal: (n * (1.0 - t)).to_array(),
        normal_moments: [m[0] + t, m[1] + t, m[2] + t, m[3], m[4], m[5]],
        height_variance: 0.02 * spread,
        albedo: albedo.to_array(),
        albedo_slope: slope.to_array(),
        specular: 0.3,
        roughness: 1.0 / 34.0,
    }
}

/// The box `[12, 40) × [−4, 40) × [10, 28)` in a 32³ grid, leaves from its distance field,
/// colour rising with height on its top.
fn box_tree() -> Octree<MicrosurfacePayload> {
    let (lo, hi) = (Vec3::new(12.0, -4.0, 10.0), Vec3::new(40.0, 20.0, 28.0));
    let sdf = |p: Vec3| {
        let q = (lo - p).max(p - hi);
        q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
    };
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(32)).unwrap();
    let mut voxels = Vec::new();
    for z in 0..32u32 {
        for y in 0..32u32 {
            for x in 0..32u32 {
                let c = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
                let d = sdf(c);
                if d.abs() <= 0.87 {
                    let e = 1e-2;
                    let g = Vec3::new(
                        sdf(c + Vec3::X * e) - sdf(c - Vec3::X * e),
                        sdf(c + Vec3::Y * e) - sdf(c - Vec3::Y * e),
                        sdf(c + Vec3::Z * e) - sdf(c - Vec3::Z * e),
                    )
                    .normalize();
                    let local = c - d * g - (c - 0.5);
                    let r = record(
                        local,
                        g,
                        Vec3::new(0.3 + 0.02 * x as f32, 0.5, 0.7),
                        Vec3::new(0.2, -0.1, 0.0),
                        0.04,
                    );
                    voxels.push((UVec3::new(x, y, z), MicrosurfacePayload::from_record(&r)));
                }
            }
        }
    }
    Octree::build(grid, voxels, &BuildOptions { depth: None, dense_log2: 2 }).unwrap()
}

/// builtin:sphere (an icosphere) voxelized at 32³, leaves fitted to 32 ray samples per voxel.
fn sphere_tree() -> (Octree<MicrosurfacePayload>, GridSpec) {
    let scene = voxlod_scene::procedural::from_spec("sphere?subdiv=3").unwrap();
    let geometry = scene.geometry();
    let (lo, hi) = scene.bounds().unwrap();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 32).unwrap();
    let vox = voxelize::voxelize(&geometry, &grid, &voxelize::Options::default()).unwrap();
    let ctx = SamplingContext::new(&scene, &geometry, &vox).unwrap();
    let records =
        precompute(&ctx, &PrecomputeOptions { rays: 32, seed: 0 }, microsurface::fit).unwrap();
    let tree = Octree::from_brick_map(
        grid,
        &records.records,
        MicrosurfacePayload::from_record,
        &BuildOptions::default(),
    )
    .unwrap();
    (tree, grid)
}

fn camera(eye: Vec3, target: Vec3, fov: f32, side: u32) -> PinholeCamera {
    PinholeCamera { eye, target, up: Vec3::Y, fov_y_deg: fov, width: side, height: side }
}

fn scene_cases() -> Vec<Case> {
    let sun =
        Light::Directional { to_light: Vec3::new(0.3, 1.0, -0.5), irradiance: Vec3::splat(2.0) };
    let base = DifferentialOptions { background: Vec3::new(0.2, 0.3, 0.4), ..Default::default() };
    let boxed = box_tree();
    let edge = camera(Vec3::new(-10.0, 35.0, -20.0), Vec3::new(20.0, 15.0, 16.0), 40.0, 32);
    let mut cases = vec![
        Case {
            name: "box masks".into(),
            tree: boxed.clone(),
            camera: edge,
            light: sun,
            options: base,
            ambient: Vec3::splat(0.1),
        },
        Case {
            name: "box blending bias 4".into(),
            tree: boxed.clone(),
            camera: edge,
            light: sun,
            options: DifferentialOptions {
                lod_bias: 4.0,
                compositing: Compositing::AlphaBlending,
                ..base
            },
            ambient: Vec3::splat(0.1),
        },
        Case {
            name: "box depth of field".into(),
            tree: boxed,
            camera: edge,
            light: sun,
            options: DifferentialOptions {
                depth_of_field: Some(DepthOfField { lens_radius: 1.5, focus_distance: 20.0 }),
                shadows: false,
                ..base
            },
            ambient: Vec3::splat(0.1),
        },
    ];
    let (sphere, grid) = sphere_tree();
    let centre = (grid.origin + grid.voxel_size * grid.dims.as_dvec3() * 0.5).as_vec3();
    let lamp =
        Light::Point { position: centre + Vec3::new(2.0, 3.0, 2.5), intensity: Vec3::splat(20.0) };
    for (bias, dist) in [(1.0, 3.5), (2.0, 8.0)] {
        cases.push(Case {
            name: format!("sphere bias {bias}"),
            tree: sphere.clone(),
            camera: camera(centre + Vec3::new(0.4, 0.8, -dist), centre, 35.0, 32),
            light: lamp,
            options: DifferentialOptions { lod_bias: bias, ..base },
            ambient: Vec3::splat(0.05),
        });
    }
    cases
}

/// Random voxel sets with random records, cameras, lights and options.
fn property_cases() -> Vec<Case> {
    (0..8u32)
        .map(|seed| {
            let r = |i: u32, d: u32| rand_f32(seed.wrapping_mul(7919).wrapping_add(i), 31, d);
            let side = 8 + (r(0, 0) * 17.0) as u32;
            let grid = GridSpec::new(DVec3::new(-1.0, 0.5, 2.0), 0.25, UVec3::splat(side)).unwrap();
            let mut voxels = std::collections::BTreeMap::new();
            for i in 0..(side * side * 2) {
                let c = UVec3::new(
                    (r(i, 1) * side as f32) as u32,
                    (r(i, 2) * side as f32) as u32,
                    (r(i, 3) * side as f32) as u32,
                )
                .min(UVec3::splat(side - 1));
                let n = Vec3::new(r(i, 4) - 0.5, r(i, 5) - 0.5, r(i, 6) - 0.5);
                let n = if n.length() < 0.1 { Vec3::Y } else { n };
                let rec = record(
                    Vec3::new(r(i, 7), r(i, 8), r(i, 9)),
                    n,
                    Vec3::new(r(i, 10), r(i, 11), r(i, 12)),
                    Vec3::new(r(i, 13) - 0.5, r(i, 14) - 0.5, 0.0) * 0.6,
                    0.1 * r(i, 15),
                );
                voxels.insert(c.to_array(), MicrosurfacePayload::from_record(&rec));
            }
            let voxels = voxels.into_iter().map(|(c, p)| (UVec3::from(c), p));
            let dense_log2 = (r(0, 16) * 4.0) as u32;
            let tree =
                Octree::build(grid, voxels, &BuildOptions { depth: None, dense_log2 }).unwrap();
            let centre = (grid.origin + grid.voxel_size * grid.dims.as_dvec3() * 0.5).as_vec3();
            let extent = side as f32 * 0.25;
            let eye = centre
                + Vec3::new(r(0, 17) - 0.5, r(0, 18) - 0.5, r(0, 19) - 0.5).normalize()
                    * extent
                    * (1.0 + 2.0 * r(0, 20));
            let light = if seed % 2 == 0 {
                Light::Directional {
                    to_light: Vec3::new(r(0, 21) - 0.5, 1.0, r(0, 22) - 0.5),
                    irradiance: Vec3::splat(2.0),
                }
            } else {
                Light::Point {
                    position: centre + Vec3::new(0.0, extent, 0.0),
                    intensity: Vec3::splat(5.0),
                }
            };
            let options = DifferentialOptions {
                lod_bias: [0.0, 1.0, 3.0][seed as usize % 3],
                element_factor: [1.0, 0.5, 2.0][seed as usize % 3],
                compositing: if seed % 4 == 3 {
                    Compositing::AlphaBlending
                } else {
                    Compositing::CoverageMasks
                },
                shadows: seed % 3 != 1,
                depth_of_field: (seed % 5 == 2)
                    .then_some(DepthOfField { lens_radius: 0.2, focus_distance: extent }),
                max_distance: if seed % 4 == 1 { 2.0 * extent } else { f32::INFINITY },
                background: Vec3::new(0.1, 0.1, 0.1),
            };
            Case {
                name: format!("random {seed}"),
                tree,
                camera: camera(eye, centre, 30.0 + 50.0 * r(0, 23), 16),
                light,
                options,
                ambient: Vec3::splat(0.1),
            }
        })
        .collect()
}

fn renderer(c: &Case) -> Result<DifferentialRenderer<'_>, String> {
    DifferentialRenderer::new(&c.tree, c.camera, c.light, c.options).map_err(|e| e.to_string())
}

/// Images and element counts of the kernel against the CPU on `cases`.
fn compare_cases(backend: &Executor, cases: &[Case], what: &str) -> Result<Measure, String> {
    let ctx = match backend {
        Executor::Cpu => return flat_sampling(cases, what),
        Executor::Gpu(ctx) => ctx,
    };
    let kernel = DifferentialKernel::new(ctx);
    let mut measures = Vec::new();
    let (mut cpu_elements, mut gpu_elements) = (0u64, 0u64);
    let (mut cpu_s, mut gpu_s) = (0.0, 0.0);
    let mut linear = 0.0f32;
    for c in cases {
        let r = renderer(c)?;
        let t = std::time::Instant::now();
        let (want, wc) = reference(&r, c.ambient);
        cpu_s += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let up = kernel.upload(&c.tree).map_err(|e| e.to_string())?;
        let (got, gc) = kernel.render(&up, &r, c.ambient).map_err(|e| e.to_string())?;
        gpu_s += t.elapsed().as_secs_f64();
        measures.push(compare(
            &c.name.replace(' ', "_"),
            &got,
            &want,
            ImageBound { per_pixel: BOUND, fraction: FRACTION },
        ));
        for (a, b) in got.pixels.iter().zip(&want.pixels) {
            linear = linear.max((*a - *b).abs().max_element());
        }
        cpu_elements += wc[0];
        gpu_elements += gc[0];
    }
    let mut m = Measure::combine(&measures);
    let rel = (gpu_elements as f64 - cpu_elements as f64).abs() / cpu_elements.max(1) as f64;
    m.pass &= rel <= ELEMENTS;
    m.note = format!(
        "{what}: largest linear RGBA difference {linear:.2e}; elements GPU {gpu_elements} vs \
         CPU {cpu_elements} ({:.3} %, allowed {:.1} %); \
         CPU reference {cpu_s:.2} s, kernel (compilation included) {gpu_s:.2} s; {}",
        100.0 * rel,
        100.0 * ELEMENTS,
        m.note
    );
    Ok(m)
}

/// The box, blending and depth-of-field frames and the sampled sphere (module docs).
pub fn scenes(backend: &Executor) -> Result<Measure, String> {
    compare_cases(
        backend,
        &scene_cases(),
        "box 32³ (masks, blending, DoF), sphere 32³ (bias 1, 2); 32² px",
    )
}

/// Random octrees, records, cameras, lights and options.
pub fn property(backend: &Executor) -> Result<Measure, String> {
    compare_cases(backend, &property_cases(), "8 random octrees × options; 16² px")
}

/// The control: the scenes against a reference with elements 5 % longer must fail.
pub fn control(backend: &Executor) -> Result<Measure, String> {
    let cases = scene_cases();
    let mut measures = Vec::new();
    let kernel = match backend {
        Executor::Gpu(ctx) => Some(DifferentialKernel::new(ctx)),
        Executor::Cpu => None,
    };
    for c in &cases {
        let longer =
            DifferentialOptions { element_factor: c.options.element_factor * 1.05, ..c.options };
        let r = DifferentialRenderer::new(&c.tree, c.camera, c.light, longer)
            .map_err(|e| e.to_string())?;
        let (want, _) = reference(&r, c.ambient);
        let got: Image = match &kernel {
            None => reference(&renderer(c)?, c.ambient).0,
            Some(k) => {
                let up = k.upload(&c.tree).map_err(|e| e.to_string())?;
                k.render(&up, &renderer(c)?, c.ambient).map_err(|e| e.to_string())?.0
            }
        };
        measures.push(compare(
            &format!("control_{}", c.name.replace(' ', "_")),
            &got,
            &want,
            ImageBound { per_pixel: BOUND, fraction: FRACTION },
        ));
    }
    let m = Measure::combine(&measures);
    let caught = !m.pass;
    Ok(Measure {
        max_error: m.max_error,
        bound: m.bound,
        pass: caught,
        note: format!(
            "the scenes vs a reference with elements 5 % longer (must FAIL the check): {} → {}",
            m.note,
            if caught { "caught" } else { "NOT caught" }
        ),
    })
}

/// The probe's inputs: (cos θ, sin θ, σ, x) over the whole range, and special values.
fn smith_inputs() -> Vec<[f32; 4]> {
    let mut v = Vec::new();
    let sigmas = [1e-6f32, 1e-3, 0.05, 0.3, 1.0, 10.0, 1e6];
    for i in 0..=300 {
        let t = i as f64 / 300.0;
        let theta = 1e-6f64.powf(1.0 - t) * (std::f64::consts::FRAC_PI_2 - 1e-7).powf(t);
        let (s, c) = (theta as f32).sin_cos();
        let x = -9.0 + 18.5 * (i as f32 / 300.0);
        for &sigma in &sigmas {
            v.push([c, s, sigma, x]);
        }
    }
    // Normal incidence, σ = 0, below and at the horizon, tiny cos.
    v.extend([
        [1.0, 0.0, 0.3, 0.0],
        [0.6, 0.8, 0.0, 1.5],
        [0.0, 1.0, 0.3, 9.5],
        [-0.2, 0.98, 0.3, -0.5],
        [1e-38, 1.0, 0.3, 2.0],
    ]);
    v
}

/// The kernel's `f32` Λ and erfc against `f64` (module docs).
pub fn smith(backend: &Executor) -> Result<Measure, String> {
    let inputs = smith_inputs();
    let values: Vec<[f32; 2]> = match backend {
        Executor::Cpu => {
            inputs.iter().map(|q| [lambda_cs_f32(q[0], q[1], q[2]), erfc_f32(q[3])]).collect()
        }
        Executor::Gpu(ctx) => {
            DifferentialKernel::new(ctx).probe(&inputs).map_err(|e| e.to_string())?
        }
    };
    let (mut worst, mut bad, mut compared) = (0.0f64, Vec::new(), 0usize);
    for (q, got) in inputs.iter().zip(&values) {
        let want_l = lambda(q[0] as f64 / q[1] as f64, q[2] as f64);
        let want_e = erfc_f64(q[3] as f64);
        for (g, w, hi) in [(got[0] as f64, want_l, 1e28), (got[1] as f64, want_e, 2.0)] {
            if !(g >= 0.0 && g <= LAMBDA_MAX_F32 as f64) {
                bad.push(format!("{q:?}: {g:e} out of range"));
            } else if (1e-30..=hi).contains(&w) {
                let r = (g - w).abs() / w;
                compared += 1;
                worst = worst.max(r);
                if r > SMITH_BOUND {
                    bad.push(format!("{q:?}: {g:e} vs {w:e}"));
                }
            } else if w < 1e-30 && g > 1e-29 {
                bad.push(format!("{q:?}: {g:e} vs {w:e} (tiny)"));
            } else if w > hi && g < 1e27 {
                bad.push(format!("{q:?}: {g:e} vs {w:e} (huge)"));
            }
        }
    }
    Ok(Measure {
        max_error: worst,
        bound: SMITH_BOUND,
        pass: bad.is_empty(),
        note: format!(
            "Λ and erfc at {} inputs ({compared} compared in range): worst relative {worst:.2e}{}",
            inputs.len(),
            if bad.is_empty() {
                String::new()
            } else {
                format!("; {} bad, first: {}", bad.len(), bad[0])
            }
        ),
    })
}

// ---- the CPU rows: the kernel's flat-layout sampling, in Rust ----

fn flat_find(f: &FlatOctree<MicrosurfacePayload>, top: u32, level: u32, c: UVec3) -> u32 {
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

/// `differential.wgsl`'s `sample_level`.
fn flat_sample_level(
    f: &FlatOctree<MicrosurfacePayload>,
    top: u32,
    pos: Vec3,
    level: u32,
) -> MicrosurfacePayload {
    let mut out = MicrosurfacePayload::empty();
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
    let size = (1u32 << level) as f32;
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
        let wv = Vec3::select(off.cmpeq(glam::IVec3::ZERO), 1.0 - fr, fr);
        let w = (wv.x * wv.y) * wv.z;
        out.add_scaled_at(&f.payload[node as usize], w, (fr - off.as_vec3()) * size, size);
    }
    out
}

fn flat_sample(
    f: &FlatOctree<MicrosurfacePayload>,
    top: u32,
    pos: Vec3,
    level: f32,
) -> MicrosurfacePayload {
    let l0 = level.floor() as u32;
    let t = level - l0 as f32;
    let mut out = flat_sample_level(f, top, pos, l0);
    if t > 0.0 && l0 < f.depth {
        let upper = flat_sample_level(f, top, pos, l0 + 1);
        let mut mixed = MicrosurfacePayload::empty();
        mixed.add_scaled(&out, 1.0 - t);
        mixed.add_scaled(&upper, t);
        out = mixed;
    }
    out
}

fn flat_sampling(cases: &[Case], what: &str) -> Result<Measure, String> {
    let (mut bad, mut n) = (0usize, 0usize);
    for (k, c) in cases.iter().enumerate() {
        let f = FlatOctree::from_octree(&c.tree).map_err(|e| e.to_string())?;
        let res = (1u32 << c.tree.depth()) as f32;
        for i in 0..1000u32 {
            let r = |d: u32| rand_f32(k as u32 * 1000 + i, 91, d);
            let mut pos = Vec3::new(r(0), r(1), r(2)) * (res + 4.0) - 2.0;
            if i % 4 == 0 {
                let l = (r(3) * (c.tree.depth() + 1) as f32) as u32;
                let scale = (1u32 << l) as f32;
                pos = (pos / scale).floor() * scale + if i % 8 == 0 { scale * 0.5 } else { 0.0 };
            }
            let level =
                [0.0, 1.0, r(4) * c.tree.depth() as f32, c.tree.depth() as f32][i as usize % 4];
            n += 1;
            if flat_sample(&f, c.tree.first_dense(), pos, level)
                != c.tree.sample_at_level(pos, level)
            {
                bad += 1;
            }
        }
    }
    Ok(Measure {
        max_error: bad as f64,
        bound: 0.0,
        pass: bad == 0,
        note: format!(
            "{what}: the kernel's flat-layout sampling with corners moved to the point (Rust \
             port) vs Octree::sample_at_level at {n} positions × levels: {bad} differ (bit for bit)"
        ),
    })
}
