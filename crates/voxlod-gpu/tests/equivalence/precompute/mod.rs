//! Kernel 6, the per-voxel appearance precompute (ray sampling, Averages, opacity subgrid).
//!
//! Oracle, shared by both backends: an independent `f64` sampler written here — the lines of
//! `voxlod_cpu::appearance::line_sampler::sample_line` (the random-number contract, exact), each
//! intersected with the voxel's triangles by Möller–Trumbore in `f64` on voxel-local `f64`
//! vertices, the sampler's rules for cases (closed voxel box with the axis-aligned snap, which
//! the sampler defines on the `f32`-rounded local vertices, so the oracle does too,
//! world geometric normal for facing, double-sided flip), the sampler's alpha rules (a hit
//! counts on `Opaque` always, on `Mask` where the material's alpha at the UV interpolated from
//! the oracle's barycentrics is > 0, on `Blend` where `rand_f32(v, i, blend_key(seed) ^ t)` is
//! below it; the closest accepted hit wins) and the textured `material_sample` at the hit's UV
//! for albedo, specular and exponent, then voxlod-cpu's
//! `averages::fit` and `subgrid::build` on those samples. The CPU reference row runs the CPU
//! sampler and driver (`f32` hit tests set up in `f64`); the GPU rows run
//! `voxlod_gpu::precompute` with every line read back. Both are held to the same bounds:
//!
//! - **lines**: the fraction of lines whose case (miss / occluded / surface) or hit triangle
//!   differs from the oracle, **bound 10⁻³**. Why not 0: the oracle decides in `f64`, the
//!   backends in `f32` (and the GPU's division may be off by a few ULP, its multiply-adds
//!   fused), so a line within ~1e-7 of a triangle edge, or two triangles' hits within ~1e-7
//!   (a shared edge seen edge-on), may decide the other way. The note also gives the GPU's
//!   lines that differ from the CPU reference's directly (measured: 0 on llvmpipe).
//! - **voxels**: the fraction of voxels whose Averages record differs from the oracle's in
//!   presence or by more than 1 in any byte (opacity, sRGB colour, snorm normal), or whose
//!   subgrid differs by more than 1 in any byte, **bound 1 %**. Why 1 byte: the sums are `f32`
//!   on the backends (`f64` in the oracle's fit) and may round a byte the other way; why 1 %:
//!   one flipped line moves a voxel's opacity by 1/R (1.7 bytes at R = 150). Textures and
//!   alpha add no new bound: the GPU's texture sample is the CPU's to a few ULP (the lerp), so
//!   only an alpha within ULP of a cutoff or blend number can flip a line, as rare as a graze.
//! - **controls**: the backend's lines with seed + 1 against the oracle of the case's seed
//!   must exceed each bound tenfold (measured: about half the lines and nearly every voxel
//!   differ); and per material scene, the backend's answer against the oracle of that scene's
//!   materials perturbed on purpose must exceed the voxel bound tenfold (measured on both
//!   rows: BoxTextured's texture shifted by one texel 39.7 % of voxels off, worst record Δ 26;
//!   the leaf mask ignored 100 %, Δ 254; the blend alpha 0.7 → 0.6 18.8 %, Δ 10), or the
//!   checks could not fail.
//!
//! Scenes: the bunny at 32³ (150 lines), a single-sided quad lying exactly on a voxel face
//! (hits on the shared face are inside both voxels), a tilted double-sided quad (flipped
//! normals, both sides sampled); the Khronos BoxTextured model at 12³ (a 256² sRGB texture);
//! the forest's leaf material (alpha-masked, textured, double-sided) on a quad half a voxel in
//! front of an opaque red quad in the same voxel layer, and the same with the leaf blended
//! (`Blend`, base alpha 0.7) — 8³ half-unit voxels, 300 lines, where lines through the leaves'
//! rejected texels must reach the red quad; the property rows: random triangle soups (some
//! axis-aligned on voxel faces, some double-sided) in random grids, with random seeds and line
//! counts.
//! Plus: dispatch splitting and 2D dispatches give the same bits; bad input gets the CPU's
//! error; a texture edge over the exact addressing's limit is an error with the numbers.
//! Measured on llvmpipe: every line of every row (textured and alpha scenes included) equals
//! the CPU's bit for bit and in case, and every record and subgrid byte equals the oracle's.

use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

use glam::{UVec3, Vec3};
use voxlod_cpu::appearance::line_sampler::{SamplingContext, dimension_base, sample_line};
use voxlod_cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod_cpu::appearance::voxel_samples::VoxelSamples;
use voxlod_cpu::appearance::{AppearanceGrid, averages, subgrid};
use voxlod_cpu::voxelize::{Options, Voxelization, voxelize};
use voxlod_format::GridSpec;
use voxlod_format::records::AverageRecord;
use voxlod_gpu::precompute::{LineCase, Outputs, Precomputer};
use voxlod_scene::{Geometry, Scene};

use crate::harness::{Executor, Measure};

mod oracle;
mod scenes;

use oracle::oracle;
use scenes::{leaf, perturbed, property_cases, scene_cases};

/// See the module docs.
const LINE_BOUND: f64 = 1e-3;
const VOXEL_BOUND: f64 = 0.01;

/// One case: a scene voxelized, sampled with a seed and a line count.
struct Case {
    name: String,
    scene: Scene,
    geometry: Geometry,
    vox: Voxelization,
    opts: PrecomputeOptions,
}

fn case(name: String, scene: Scene, grid: GridSpec, opts: PrecomputeOptions) -> Case {
    let geometry = scene.geometry();
    let vox = voxelize(&geometry, &grid, &Options::default()).expect("voxelizes");
    Case { name, scene, geometry, vox, opts }
}

/// A backend's (or the oracle's) answer for one case, in the voxelization's voxel order.
struct Answer {
    lines: Vec<Vec<(LineCase, u32)>>,
    records: Vec<Option<AverageRecord>>,
    subgrids: Vec<[u8; 27]>,
    /// GPU only: lines whose direction, entry and chord equal `sample_line`'s bit for bit, of
    /// all lines.
    line_bits: Option<(usize, usize)>,
}

fn record_at(g: &AppearanceGrid<AverageRecord>, c: UVec3) -> Option<AverageRecord> {
    g.records.index_of(c).map(|i| g.records.values()[i])
}

/// The backend's answer for `c` sampled with `seed`.
fn run(backend: &Executor, c: &Case, seed: u32) -> Result<Answer, String> {
    let opts = PrecomputeOptions { seed, ..c.opts };
    match backend {
        Executor::Cpu => {
            let ctx =
                SamplingContext::new(&c.scene, &c.geometry, &c.vox).map_err(|e| e.to_string())?;
            let grid = precompute(&ctx, &opts, averages::fit).map_err(|e| e.to_string())?;
            let mut out = Answer {
                lines: Vec::new(),
                records: Vec::new(),
                subgrids: Vec::new(),
                line_bits: None,
            };
            let mut buf = VoxelSamples::default();
            for i in 0..ctx.voxel_count() {
                ctx.sample_voxel_seeded(i, seed, 0, opts.rays, &mut buf);
                out.subgrids.push(subgrid::build(&buf));
                out.records.push(record_at(&grid, ctx.coord(i)));
                out.lines.push(
                    buf.rays
                        .iter()
                        // The CPU sampler does not report its hit triangle.
                        .map(|r| (LineCase::of(r), u32::MAX))
                        .collect(),
                );
            }
            Ok(out)
        }
        Executor::Gpu(ctx) => {
            let k = Precomputer::new(ctx).map_err(|e| e.to_string())?;
            let r = k
                .run(&c.scene, &c.geometry, &c.vox, &opts, Outputs { lines: true })
                .map_err(|e| e.to_string())?;
            let sampling =
                SamplingContext::new(&c.scene, &c.geometry, &c.vox).map_err(|e| e.to_string())?;
            let (mut same, mut all) = (0, 0);
            for (i, s) in r.samples.iter().flatten().enumerate() {
                for (j, ray) in s.rays.iter().enumerate() {
                    let (d, e, ch) =
                        sample_line(sampling.voxel_id(i), j as u32, dimension_base(seed));
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    all += 1;
                    same += (bits(d) == bits(ray.dir)
                        && bits(e) == bits(ray.entry)
                        && ch.to_bits() == ray.chord.to_bits())
                        as usize;
                }
            }
            Ok(Answer {
                line_bits: Some((same, all)),
                lines: r.cases.expect("asked for lines"),
                records: c.vox.voxels.coords().map(|co| record_at(&r.averages, co)).collect(),
                subgrids: r.voxels.iter().map(|v| v.subgrid).collect(),
            })
        }
    }
}

/// Per case: (name, lines, lines off the oracle, GPU lines off the CPU, voxels, voxels off,
/// worst record byte, worst subgrid byte, first difference).
struct Row {
    name: String,
    lines: usize,
    lines_off: usize,
    voxels: usize,
    voxels_off: usize,
    worst_record: i32,
    worst_subgrid: i32,
    first: String,
    /// GPU only: the direct comparison with the CPU reference.
    note: String,
    /// A control row: which measures it must fail.
    control: Option<Control>,
}

/// Which measures a control row must fail (tenfold).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Control {
    /// Lines and voxels.
    Both,
    /// Voxels only (a perturbation of colour or coverage that moves records, not necessarily
    /// the line cases the CPU row compares).
    Voxels,
}

fn bytes(r: &AverageRecord) -> [i32; 7] {
    [
        r.opacity as i32,
        r.color[0] as i32,
        r.color[1] as i32,
        r.color[2] as i32,
        r.normal[0] as i32,
        r.normal[1] as i32,
        r.normal[2] as i32,
    ]
}

fn compare(name: &str, a: &Answer, o: &Answer, compare_triangles: bool) -> Row {
    let mut row = Row {
        name: name.into(),
        lines: 0,
        lines_off: 0,
        voxels: o.records.len(),
        voxels_off: 0,
        worst_record: 0,
        worst_subgrid: 0,
        first: String::new(),
        note: String::new(),
        control: None,
    };
    for (v, (la, lo)) in a.lines.iter().zip(&o.lines).enumerate() {
        row.lines += lo.len();
        for (j, (x, y)) in la.iter().zip(lo).enumerate() {
            let differs = x.0 != y.0 || (compare_triangles && x.1 != y.1);
            if differs {
                row.lines_off += 1;
                if row.first.is_empty() {
                    row.first = format!("voxel {v} line {j}: {x:?}, oracle {y:?}");
                }
            }
        }
    }
    for v in 0..o.records.len() {
        let rec = match (a.records[v], o.records[v]) {
            (Some(x), Some(y)) => {
                bytes(&x).iter().zip(bytes(&y)).map(|(p, q)| (p - q).abs()).max().unwrap()
            }
            (None, None) => 0,
            _ => 255,
        };
        let sub = a.subgrids[v]
            .iter()
            .zip(&o.subgrids[v])
            .map(|(&p, &q)| (p as i32 - q as i32).abs())
            .max()
            .unwrap();
        row.worst_record = row.worst_record.max(rec);
        row.worst_subgrid = row.worst_subgrid.max(sub);
        if rec > 1 || sub > 1 {
            row.voxels_off += 1;
            if row.first.is_empty() {
                row.first = format!(
                    "voxel {v}: record {:?} vs oracle {:?}, subgrid Δ {sub}",
                    a.records[v], o.records[v]
                );
            }
        }
    }
    row
}

/// Rows per (backend, case set): the lines and voxels rows share one run.
type Cache = HashMap<(String, &'static str), Rc<Vec<Row>>>;

thread_local! {
    static CACHE: RefCell<Cache> = RefCell::default();
}

fn rows(backend: &Executor, set: &'static str) -> Result<Rc<Vec<Row>>, String> {
    let key = (backend.name(), set);
    if let Some(r) = CACHE.with(|c| c.borrow().get(&key).cloned()) {
        return Ok(r);
    }
    let cases = if set == "scenes" { scene_cases() } else { property_cases(16) };
    let mut out = Vec::new();
    let mut controls = Vec::new();
    for c in &cases {
        let o = oracle(c, &c.scene);
        let a = run(backend, c, c.opts.seed)?;
        // The CPU sampler reports no triangle: only its cases are compared.
        let tri = matches!(backend, Executor::Gpu(_));
        let mut row = compare(&c.name, &a, &o, tri);
        if let Executor::Gpu(_) = backend {
            let cpu = run(&Executor::Cpu, c, c.opts.seed)?;
            let direct = compare("gpu-vs-cpu", &a, &cpu, false);
            let (same, all) = a.line_bits.unwrap_or_default();
            row.note = format!(
                "; GPU vs CPU: {} lines differ in case; {same} of {all} lines bit-identical",
                direct.lines_off
            );
        }
        if let Some((wrong, what)) = perturbed(&c.name, &c.scene) {
            // Control: the backend's answer against the oracle of the perturbed scene.
            let mut control = compare(&c.name, &a, &oracle(c, &wrong), false);
            control.name = format!("control ({}: {what})", c.name);
            control.control = Some(Control::Voxels);
            controls.push(control);
        }
        out.push(row);
    }
    if set == "scenes" {
        // Control: seed 1 against the oracle of the case's seed.
        let c = cases.iter().find(|c| c.name == "bunny-32").expect("the bunny case");
        let o = oracle(c, &c.scene);
        let a = run(backend, c, c.opts.seed + 1)?;
        let mut row = compare("control", &a, &o, false);
        row.name = "control (seed+1)".into();
        row.control = Some(Control::Both);
        out.push(row);
    }
    out.extend(controls);
    let rc = Rc::new(out);
    CACHE.with(|c| c.borrow_mut().insert(key, rc.clone()));
    Ok(rc)
}

fn lines_measure(rows: &[Row]) -> Measure {
    let mut measures = Vec::new();
    for r in rows {
        let fraction = r.lines_off as f64 / r.lines.max(1) as f64;
        if r.control == Some(Control::Voxels) {
            continue;
        }
        if r.control.is_some() {
            let pass = fraction > 10.0 * LINE_BOUND;
            measures.push(Measure {
                max_error: 0.0,
                bound: LINE_BOUND,
                pass,
                note: format!(
                    "{} vs the oracle must fail the bound tenfold: {:.1} % of lines differ",
                    r.name,
                    100.0 * fraction
                ),
            });
        } else {
            measures.push(Measure {
                max_error: fraction,
                bound: LINE_BOUND,
                pass: fraction <= LINE_BOUND,
                note: format!(
                    "{}: {} of {} lines off{}{}",
                    r.name,
                    r.lines_off,
                    r.lines,
                    first(r),
                    r.note
                ),
            });
        }
    }
    Measure::combine(&measures)
}

fn first(r: &Row) -> String {
    if r.first.is_empty() { String::new() } else { format!(" ({})", r.first) }
}

fn voxels_measure(rows: &[Row]) -> Measure {
    let measures: Vec<Measure> = rows
        .iter()
        .map(|r| {
            let fraction = r.voxels_off as f64 / r.voxels.max(1) as f64;
            if r.control.is_some() {
                return Measure {
                    max_error: 0.0,
                    bound: VOXEL_BOUND,
                    pass: fraction > 10.0 * VOXEL_BOUND,
                    note: format!(
                        "{} vs the oracle must fail the bound tenfold: {:.1} % of voxels off \
                         (worst Δ record {})",
                        r.name,
                        100.0 * fraction,
                        r.worst_record
                    ),
                };
            }
            Measure {
                max_error: fraction,
                bound: VOXEL_BOUND,
                pass: fraction <= VOXEL_BOUND,
                note: format!(
                    "{}: {} of {} voxels off, worst Δ record {} subgrid {}",
                    r.name, r.voxels_off, r.voxels, r.worst_record, r.worst_subgrid
                ),
            }
        })
        .collect();
    Measure::combine(&measures)
}

pub fn lines_scenes(backend: &Executor) -> Result<Measure, String> {
    Ok(lines_measure(&rows(backend, "scenes")?))
}

pub fn voxels_scenes(backend: &Executor) -> Result<Measure, String> {
    Ok(voxels_measure(&rows(backend, "scenes")?))
}

pub fn lines_property(backend: &Executor) -> Result<Measure, String> {
    Ok(lines_measure(&rows(backend, "property")?))
}

pub fn voxels_property(backend: &Executor) -> Result<Measure, String> {
    Ok(voxels_measure(&rows(backend, "property")?))
}

/// Split dispatches (7 voxels each) and 2D dispatches (3 workgroups wide) give the same bits
/// as one dispatch (GPU); the CPU driver on one thread gives the same bits as on the pool
/// (CPU). Bad input: `rays = 0` gets the CPU's error word for word; a texture edge over
/// [`voxlod_gpu::material::MAX_TEXTURE_EDGE`] gets an error with the numbers on the GPU. Exact.
pub fn dispatches(backend: &Executor) -> Result<Measure, String> {
    // The bunny at 16³ with 64 lines: ~800 voxels, 22 dispatches of 37.
    let bunny = scene_cases().swap_remove(0).scene;
    let (lo, hi) = bunny.bounds().map_err(|e| e.to_string())?;
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 16).map_err(|e| e.to_string())?;
    let c = &case("bunny-16".into(), bunny, grid, PrecomputeOptions { rays: 64, seed: 5 });
    let mut notes = Vec::new();
    let mut bad = 0usize;
    let zero = PrecomputeOptions { rays: 0, seed: 0 };
    let ctx = SamplingContext::new(&c.scene, &c.geometry, &c.vox).map_err(|e| e.to_string())?;
    let cpu_err = precompute(&ctx, &zero, averages::fit).map(|_| ()).unwrap_err().to_string();
    match backend {
        Executor::Cpu => {
            let pool = precompute(&ctx, &c.opts, averages::fit).map_err(|e| e.to_string())?;
            let one = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .map_err(|e| e.to_string())?
                .install(|| precompute(&ctx, &c.opts, averages::fit))
                .map_err(|e| e.to_string())?;
            bad += (pool.records.values() != one.records.values()) as usize;
            notes.push(format!("{} records, 1 thread vs pool", pool.records.len()));
        }
        Executor::Gpu(gpu) => {
            let k = Precomputer::new(gpu).map_err(|e| e.to_string())?;
            let all = Outputs { lines: true };
            let base =
                k.run(&c.scene, &c.geometry, &c.vox, &c.opts, all).map_err(|e| e.to_string())?;
            let split = Precomputer::new(gpu)
                .map_err(|e| e.to_string())?
                .with_voxels_per_dispatch(37)
                .with_dispatch_width(5)
                .run(&c.scene, &c.geometry, &c.vox, &c.opts, all)
                .map_err(|e| e.to_string())?;
            // Without the lines (another binding size), through the one-call entry point.
            let bare = k
                .run(&c.scene, &c.geometry, &c.vox, &c.opts, Outputs::default())
                .map_err(|e| e.to_string())?;
            let grid =
                voxlod_gpu::precompute::averages(gpu, &c.scene, &c.geometry, &c.vox, &c.opts)
                    .map_err(|e| e.to_string())?;
            let same = base.averages.records.values() == split.averages.records.values()
                && base.voxels == split.voxels
                && base.samples == split.samples
                && bare.voxels == base.voxels
                && bare.samples.is_none()
                && grid.records.values() == base.averages.records.values()
                && grid.records.len() == base.averages.records.len();
            bad += (!same) as usize;
            notes.push(format!(
                "{} voxels in dispatches of 37 as 5×8 workgroups, and without lines: {}",
                base.voxels.len(),
                if same { "same bits" } else { "DIFFER" }
            ));
            let err = k
                .run(&c.scene, &c.geometry, &c.vox, &zero, Outputs::default())
                .map(|_| ())
                .unwrap_err()
                .to_string();
            if err != cpu_err {
                bad += 1;
                notes.push(format!("rays = 0: {err:?}, CPU {cpu_err:?}"));
            }
            // Over the kernel's line count: an error with the numbers, before any GPU work.
            let huge = PrecomputeOptions { rays: u32::MAX, seed: 0 };
            match k.run(&c.scene, &c.geometry, &c.vox, &huge, Outputs::default()) {
                Err(voxlod_gpu::Error::TooLarge { requested, .. })
                    if requested == u32::MAX as u64 => {}
                other => {
                    bad += 1;
                    notes.push(format!("rays = 2^32 − 1: {:?}", other.map(|_| ())));
                }
            }
            // Textured materials are served; a texture edge over the exact addressing's limit
            // is not: an error with the numbers (no CPU fallback).
            let mut textured = c.scene.clone();
            let edge = voxlod_gpu::material::MAX_TEXTURE_EDGE + 1;
            let (_, mut texture) = leaf();
            texture.width = edge;
            texture.height = 1;
            texture.texels = std::sync::Arc::from(vec![[255u8; 4]; edge as usize]);
            textured.textures = vec![texture];
            textured.materials[0].base_color_texture =
                Some(voxlod_scene::TextureRef { texture: 0 });
            match k.run(&textured, &c.geometry, &c.vox, &c.opts, Outputs::default()) {
                Err(voxlod_gpu::Error::TooLarge { requested, limit, .. })
                    if requested == edge as u64 && limit == edge as u64 - 1 => {}
                other => {
                    bad += 1;
                    notes.push(format!("texture edge {edge}: {:?}", other.map(|_| ())));
                }
            }
            // A bad voxelization (no triangle lists) gets the CPU's error.
            let mut bare = c.vox.clone();
            bare.triangles.clear();
            let cpu_bare =
                SamplingContext::new(&c.scene, &c.geometry, &bare).map(|_| ()).unwrap_err();
            let gpu_bare = k
                .run(&c.scene, &c.geometry, &bare, &c.opts, Outputs::default())
                .map(|_| ())
                .unwrap_err();
            if gpu_bare.to_string() != cpu_bare.to_string() {
                bad += 1;
                notes.push(format!("no lists: {gpu_bare}, CPU {cpu_bare}"));
            }
        }
    }
    notes.push(format!("rays = 0: {cpu_err}"));
    Ok(Measure { max_error: bad as f64, bound: 0.0, pass: bad == 0, note: notes.join("; ") })
}
