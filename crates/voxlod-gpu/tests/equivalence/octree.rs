//! The octree build: the GPU's lock-free level-by-level build (`voxlod_gpu::octree`) and, on
//! the CPU row, its emulation `FlatOctree::build_level_by_level`, each against the oracle
//! `FlatOctree::from_octree(Octree::build(..))` (the reference build, a different algorithm:
//! closure marks from masks and tile links, not descents).
//!
//! - **Topology, exact**: the level tables, every node (child pointer and mask), every tile's
//!   links and every node's +x/+y/+z neighbour (through `FlatOctree::neighbour`) must be equal;
//!   the error is the number of entries that differ, bound 0 (integer results, and the
//!   scan-allocation gives the reference's Morton order, so nothing is sorted). Voxels are
//!   handed over in a shuffled order.
//! - **Averages payloads**: the largest component difference, bound `8·depth·2⁻²⁴`. Both sides
//!   sum a node's eight children and scale by 1/8, in the same order, so 0 is expected where
//!   additions are correctly rounded (Vulkan); the bound is what any reordering of the eight
//!   additions could cost (test components have magnitude ≤ 1, partial sums < 8: half an ulp
//!   of 8 is 2⁻²², ×1/8 per addition, seven additions per node, for both orders, at each of
//!   `depth` levels: `depth·7·2⁻²⁴ < 8·depth·2⁻²⁴`), so a wrong child, a missing scale or a
//!   swapped field fails it.
//! - **Control**: the shell with one voxel moved by one step, built by the backend, compared
//!   with the unperturbed oracle must differ (its count is in the note).

use std::cell::RefCell;

use glam::{DVec3, UVec3, Vec3};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use voxlod_format::GridSpec;
use voxlod_gpu::octree::OctreeBuilder;
use voxlod_octree::{AveragePayload, BuildOptions, FlatOctree, Octree, Payload};

use crate::harness::{Executor, Measure};

type Voxels = Vec<(UVec3, AveragePayload)>;

fn hash(i: u32, k: u32) -> f32 {
    let h = (i.wrapping_mul(0x9e37_79b9) ^ k.wrapping_mul(0x85eb_ca6b)).wrapping_mul(0xc2b2_ae35);
    (h >> 8) as f32 / (1 << 24) as f32
}

fn payload(c: UVec3) -> AveragePayload {
    let i = c.x ^ c.y.rotate_left(10) ^ c.z.rotate_left(20);
    let colour = Vec3::new(hash(i, 1), hash(i, 2), hash(i, 3));
    let normal = Vec3::new(hash(i, 4), hash(i, 5), hash(i, 6)) - 0.5;
    AveragePayload::new(colour, normal, hash(i, 7))
}

fn with_payloads(coords: impl IntoIterator<Item = UVec3>) -> Voxels {
    coords.into_iter().map(|c| (c, payload(c))).collect()
}

/// A deterministic shuffle (the builds must not care about the order).
fn shuffled(mut v: Voxels, seed: u32) -> Voxels {
    for i in (1..v.len()).rev() {
        let j = (hash(i as u32, seed) * (i + 1) as f32) as usize;
        v.swap(i, j.min(i));
    }
    v
}

fn shell(res: u32, radius: f32) -> Voxels {
    let c = Vec3::splat(res as f32 / 2.0);
    let mut coords = Vec::new();
    for z in 0..res {
        for y in 0..res {
            for x in 0..res {
                let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5 - c;
                if (p.length() - radius).abs() <= 0.5 {
                    coords.push(UVec3::new(x, y, z));
                }
            }
        }
    }
    with_payloads(coords)
}

fn bunny(res: u32) -> (GridSpec, Voxels) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
    let g = voxlod_scene::Scene::load(&path).expect("the bunny asset loads").geometry();
    let (lo, hi) = g.bounds().unwrap();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), res).unwrap();
    let v = voxlod_cpu::voxelize::voxelize(&g, &grid, &Default::default()).expect("voxelizes");
    (grid, with_payloads(v.voxels.iter().map(|(c, _)| c)))
}

fn grid(dims: UVec3) -> GridSpec {
    GridSpec::new(DVec3::ZERO, 1.0, dims).unwrap()
}

/// One test case: a name, the grid, the voxels, the options.
type Case = (String, GridSpec, Voxels, BuildOptions);

fn opts(depth: Option<u32>, dense_log2: u32) -> BuildOptions {
    BuildOptions { depth, dense_log2 }
}

/// The fixed scenes: a sphere shell, the bunny, scattered voxels in a non-power-of-two grid
/// with only the root dense, a full grid, one voxel in a deeper-than-needed tree, an empty
/// grid, and an all-dense tree.
fn scenes() -> Vec<Case> {
    let scattered: std::collections::BTreeSet<[u32; 3]> =
        (0..300u32).map(|i| [i * 7 % 23, i * i % 9, (i * 5 + i / 7) % 31]).collect();
    let (bunny_grid, bunny) = bunny(40);
    vec![
        ("shell 40³ dense 2".into(), grid(UVec3::splat(40)), shell(40, 17.0), opts(None, 2)),
        ("bunny 40 dense 3".into(), bunny_grid, bunny, opts(None, 3)),
        (
            "scattered 23×9×31 dense 0".into(),
            grid(UVec3::new(23, 9, 31)),
            with_payloads(scattered.into_iter().map(UVec3::from)),
            opts(None, 0),
        ),
        (
            "full 8³ dense 1".into(),
            grid(UVec3::splat(8)),
            with_payloads((0..512).map(|i| UVec3::new(i % 8, i / 8 % 8, i / 64))),
            opts(None, 1),
        ),
        (
            "one voxel, depth 5 in 8³".into(),
            grid(UVec3::splat(8)),
            with_payloads([UVec3::splat(7)]),
            opts(Some(5), 0),
        ),
        ("empty 16³".into(), grid(UVec3::splat(16)), Vec::new(), opts(None, 2)),
        ("all dense 12³".into(), grid(UVec3::splat(12)), shell(12, 4.0), opts(None, 6)),
    ]
}

/// The oracle: the reference build in the flat layout.
fn oracle(grid: GridSpec, voxels: &Voxels, o: &BuildOptions) -> FlatOctree<AveragePayload> {
    let tree = Octree::build(grid, voxels.iter().copied(), o).expect("valid test input");
    FlatOctree::from_octree(&tree).expect("fits")
}

fn builder<'a>(backend: &Executor<'a>) -> Result<Option<OctreeBuilder<'a>>, String> {
    match backend {
        Executor::Cpu => Ok(None),
        Executor::Gpu(ctx) => OctreeBuilder::new(ctx).map(Some).map_err(|e| e.to_string()),
    }
}

/// The backend's topology (payloads empty: the GPU's topology-only build) or whole octree.
fn build(
    b: &Option<OctreeBuilder>,
    grid: GridSpec,
    voxels: &Voxels,
    o: &BuildOptions,
    payloads: bool,
) -> Result<FlatOctree<AveragePayload>, String> {
    let e = |e: voxlod_gpu::Error| e.to_string();
    match b {
        None => FlatOctree::build_level_by_level(grid, voxels, o).map_err(|e| e.to_string()),
        Some(b) if payloads => b.build(&grid, voxels, o).map_err(e),
        Some(b) => {
            let coords: Vec<UVec3> = voxels.iter().map(|v| v.0).collect();
            let t = b.build_topology(&grid, &coords, o).map_err(e)?.read_topology().map_err(e)?;
            Ok(FlatOctree {
                depth: t.depth,
                levels: t.levels,
                payload: vec![AveragePayload::empty(); t.nodes.len()],
                nodes: t.nodes,
                tiles: t.tiles,
            })
        }
    }
}

/// Entries that differ (levels, nodes, tiles, neighbours; a length difference counts its
/// excess), and the first.
fn topology_diff(a: &FlatOctree<AveragePayload>, e: &FlatOctree<AveragePayload>) -> (u64, String) {
    let mut bad = 0u64;
    let mut first = String::new();
    let mut note = |what: String| {
        bad += 1;
        if first.is_empty() {
            first = what;
        }
    };
    if a.depth != e.depth {
        note(format!("depth {} vs {}", a.depth, e.depth));
    }
    fn cmp<T: PartialEq + std::fmt::Debug>(
        what: &str,
        a: &[T],
        e: &[T],
        note: &mut impl FnMut(String),
    ) {
        for i in 0..a.len().max(e.len()) {
            if a.get(i) != e.get(i) {
                note(format!("{what} {i}: {:?}, expected {:?}", a.get(i), e.get(i)));
            }
        }
    }
    cmp("level", &a.levels, &e.levels, &mut note);
    cmp("node", &a.nodes, &e.nodes, &mut note);
    cmp("tile", &a.tiles, &e.tiles, &mut note);
    for (l, lv) in e.levels.iter().enumerate() {
        for i in lv.first..lv.first + lv.count {
            for axis in 0..3 {
                let (x, y) = (a.neighbour(l as u32, i, axis), e.neighbour(l as u32, i, axis));
                if x != y {
                    note(format!("level {l} node {i} axis {axis}: {x:?}, expected {y:?}"));
                }
            }
        }
    }
    (bad, first)
}

fn payload_diff(a: &FlatOctree<AveragePayload>, e: &FlatOctree<AveragePayload>) -> f64 {
    if a.payload.len() != e.payload.len() {
        return f64::INFINITY;
    }
    a.payload.iter().zip(&e.payload).map(|(x, y)| x.max_abs_diff(y) as f64).fold(0.0, f64::max)
}

fn exact(cases: Vec<(String, u64, String)>) -> Measure {
    let worst = cases.iter().max_by_key(|c| c.1).cloned();
    let max_error = worst.as_ref().map_or(0, |w| w.1);
    Measure {
        max_error: max_error as f64,
        bound: 0.0,
        pass: max_error == 0,
        note: match worst {
            Some((name, e, first)) if e > 0 => format!("{name}: {e} entries differ; {first}"),
            _ => format!("{} cases, exact", cases.len()),
        },
    }
}

/// Fixed scenes, topology exact, plus the control.
pub fn topology_scenes(backend: &Executor) -> Result<Measure, String> {
    let b = builder(backend)?;
    let mut cases = Vec::new();
    let mut nodes = 0;
    for (k, (name, grid, voxels, o)) in scenes().into_iter().enumerate() {
        let expected = oracle(grid, &voxels, &o);
        nodes += expected.nodes.len();
        let actual = build(&b, grid, &shuffled(voxels, k as u32), &o, false)?;
        let (bad, first) = topology_diff(&actual, &expected);
        cases.push((name, bad, first));
    }
    let mut m = exact(cases);
    m.note = format!("{} ({nodes} nodes)", m.note);
    let mut measures = vec![m, bad_input(&b), control(&b)?];
    if let (Executor::Gpu(ctx), Some(b)) = (backend, &b) {
        measures.push(limits(ctx, b));
    }
    Ok(Measure::combine(&measures))
}

/// An over-limit request is an error with the numbers, before any GPU work: the dense levels
/// of a 256³ tree stored densely down to its leaves (`dense_log2` 8: 19 173 961 nodes, 8 bytes
/// each, 28 more for payloads) against the device's binding limit (128 MiB on lavapipe).
fn limits(ctx: &voxlod_gpu::Context, b: &OctreeBuilder) -> Measure {
    let limit = ctx.limits().max_storage_buffer_binding_size.min(ctx.limits().max_buffer_size);
    let dense: u64 = (0..=8).map(|k| 1u64 << (3 * k)).sum();
    let g = grid(UVec3::splat(256));
    let o = opts(None, 8);
    let voxels = with_payloads([UVec3::new(1, 2, 3)]);
    let (what, bytes, result) = if dense * 8 > limit {
        ("nodes", dense * 8, b.build_topology(&g, &[voxels[0].0], &o).map(|_| ()))
    } else if dense * 28 > limit {
        ("payloads", dense * 28, b.build(&g, &voxels, &o).map(|_| ()))
    } else {
        let note = format!("limits: {limit} bytes bind the largest dense tree; not checked");
        return Measure { max_error: 0.0, bound: 0.0, pass: true, note };
    };
    let (pass, note) = match result {
        Err(e @ voxlod_gpu::Error::BufferTooLarge { bytes: b, limit: l, .. })
            if b == bytes && l == limit =>
        {
            (true, format!("limits: {e}"))
        }
        Err(e) => (false, format!("limits: {dense} dense nodes' {what}: wrong error {e}")),
        Ok(()) => (false, format!("limits: {bytes} bytes of {what} over {limit} built")),
    };
    Measure { max_error: 0.0, bound: 0.0, pass, note }
}

/// Bad input (one fault per case, shuffled in among good voxels) gets the reference build's
/// error, word for word: a voxel given twice (found on the GPU by two voxels reaching one
/// leaf, named by the host), outside the grid, with a NaN payload; dense levels too large.
fn bad_input(b: &Option<OctreeBuilder>) -> Measure {
    let g = grid(UVec3::new(12, 7, 9));
    let good = shell(7, 2.5);
    let nan = AveragePayload::new(Vec3::ONE, Vec3::Z, f32::NAN);
    let mut cases: Vec<(&str, Voxels, BuildOptions)> = Vec::new();
    let mut dup = good.clone();
    dup.extend([good[5], good[2]]);
    cases.push(("duplicates", dup, opts(None, 1)));
    let mut dup_dense = good.clone();
    dup_dense.push(good[3]);
    cases.push(("duplicate, all dense", dup_dense, opts(None, 6)));
    let mut out = good.clone();
    out.push((UVec3::new(3, 7, 1), payload(UVec3::ZERO)));
    cases.push(("outside", out, opts(None, 1)));
    let mut bad = good.clone();
    bad[4].1 = nan;
    cases.push(("NaN payload", bad, opts(None, 1)));
    cases.push(("dense too large", good.clone(), opts(None, 9)));
    let mut wrong = Vec::new();
    for (k, (name, voxels, o)) in cases.iter().enumerate() {
        let expected = Octree::build(g, voxels.iter().copied(), o).err().map(|e| e.to_string());
        let voxels = shuffled(voxels.clone(), 7 + k as u32);
        // The GPU's topology-only build takes no payloads: a payload fault is not its input.
        let topology_only = if *name == "NaN payload" && b.is_some() {
            expected.clone()
        } else {
            build(b, g, &voxels, o, false).err()
        };
        let with_payload = build(b, g, &voxels, o, true).err();
        if expected.is_none() || topology_only != expected || with_payload != expected {
            let actual = topology_only;
            wrong.push(format!("{name}: {actual:?} / {with_payload:?}, expected {expected:?}"));
        }
    }
    Measure {
        max_error: wrong.len() as f64,
        bound: 0.0,
        pass: wrong.is_empty(),
        note: if wrong.is_empty() {
            format!("{} bad inputs get the reference's errors", cases.len())
        } else {
            wrong.join("; ")
        },
    }
}

/// The control: one voxel of the shell moved one step inwards must change the topology.
fn control(b: &Option<OctreeBuilder>) -> Result<Measure, String> {
    let g = grid(UVec3::splat(40));
    let o = opts(None, 2);
    let voxels = shell(40, 17.0);
    let expected = oracle(g, &voxels, &o);
    let mut moved = voxels.clone();
    let i = moved.iter().position(|v| v.0.x < 8 && v.0.y > 16).expect("a voxel on the -x side");
    moved[i].0.x += 1;
    if voxels.iter().any(|v| v.0 == moved[i].0) {
        return Err("the control's moved voxel hit another voxel".into());
    }
    let (differing, _) = topology_diff(&build(b, g, &moved, &o, false)?, &expected);
    Ok(Measure {
        max_error: 0.0,
        bound: 0.0,
        pass: differing > 0,
        note: format!("control: one voxel moved must differ, and {differing} entries do"),
    })
}

/// Fixed scenes, Averages payloads within `8·depth·2⁻²⁴` (module docs), topology exact.
pub fn payload_scenes(backend: &Executor) -> Result<Measure, String> {
    let b = builder(backend)?;
    let mut worst: (f64, f64, String) = (0.0, f64::INFINITY, String::new());
    let mut all_pass = true;
    let mut topology_errors = 0;
    let scenes = scenes();
    let scenes_count = scenes.len();
    for (k, (name, grid, voxels, o)) in scenes.into_iter().enumerate() {
        let expected = oracle(grid, &voxels, &o);
        let actual = build(&b, grid, &shuffled(voxels, 100 + k as u32), &o, true)?;
        topology_errors += topology_diff(&actual, &expected).0;
        let bound = 8.0 * expected.depth as f64 / (1u64 << 24) as f64;
        let err = payload_diff(&actual, &expected);
        all_pass &= err <= bound;
        if worst.2.is_empty() || err / bound > worst.0 / worst.1 {
            worst = (err, bound, name);
        }
    }
    Ok(Measure {
        max_error: worst.0,
        bound: worst.1,
        pass: all_pass && topology_errors == 0,
        note: format!(
            "{} cases; worst relative to its bound 8·depth·2⁻²⁴: {}; topology entries differing: \
             {topology_errors}",
            scenes_count, worst.2
        ),
    })
}

/// Random voxel sets: dims 1–20 per axis (non-powers of two, tiny), density from empty to
/// full, random dense depth and extra depth; topology exact, payloads within their bound.
pub fn property(backend: &Executor) -> Result<Measure, String> {
    let strategy = (
        (1u32..=20, 1u32..=20, 1u32..=20),
        prop_oneof![Just(0.0f64), Just(1.0), 0.0f64..0.3, Just(-1.0)],
        0u32..5,
        0u32..2,
        any::<u32>(),
    );
    let b = builder(backend)?;
    let mut runner = TestRunner::new_with_rng(
        Config { cases: 48, failure_persistence: None, ..Config::default() },
        TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    );
    let worst = RefCell::new((0u64, 0.0f64, String::new()));
    let error = RefCell::new(None);
    let cases = RefCell::new(0);
    let result = runner.run(&strategy, |(dims, density, dense, extra, seed)| {
        let dims = UVec3::new(dims.0, dims.1, dims.2);
        let g = grid(dims);
        let all = (0..dims.x * dims.y * dims.z)
            .map(|i| UVec3::new(i % dims.x, i / dims.x % dims.y, i / (dims.x * dims.y)));
        // density −1: exactly one voxel.
        let coords: Vec<UVec3> = if density < 0.0 {
            vec![UVec3::new(seed % dims.x, seed / 7 % dims.y, seed / 49 % dims.z)]
        } else {
            all.enumerate()
                .filter(|(i, _)| (hash(*i as u32, seed) as f64) < density)
                .map(|(_, c)| c)
                .collect()
        };
        let needed = dims.max_element().next_power_of_two().trailing_zeros();
        let o = opts(if extra == 0 { None } else { Some(needed + extra) }, dense);
        let voxels = with_payloads(coords);
        let expected = oracle(g, &voxels, &o);
        let actual = match build(&b, g, &shuffled(voxels, seed), &o, true) {
            Ok(a) => a,
            Err(e) => {
                *error.borrow_mut() = Some(e);
                return Err(TestCaseError::fail("build failed"));
            }
        };
        let (bad, first) = topology_diff(&actual, &expected);
        let err = payload_diff(&actual, &expected);
        let bound = 8.0 * expected.depth as f64 / (1u64 << 24) as f64;
        *cases.borrow_mut() += 1;
        let mut w = worst.borrow_mut();
        w.1 = w.1.max(err / bound);
        if bad > w.0 {
            *w = (bad, w.1, format!("dims {dims} {o:?}: {first}"));
        }
        if bad > 0 || err > bound {
            return Err(TestCaseError::fail(format!("{bad} entries differ, payload {err:e}")));
        }
        Ok(())
    });
    if let Some(e) = error.into_inner() {
        return Err(e);
    }
    let (bad, payload_ratio, first) = worst.into_inner();
    let note = match &result {
        Ok(()) => format!(
            "{} random cases exact; worst payload error {payload_ratio:.2} × its bound",
            cases.into_inner()
        ),
        Err(e) => format!("{e}; {first}"),
    };
    Ok(Measure { max_error: bad as f64, bound: 0.0, pass: result.is_ok() && bad == 0, note })
}

/// The allocation step's exclusive prefix sum alone, exact, on sizes around the kernel's
/// 512-value blocks, past 512² (three passes of block sums) and past one dispatch dimension: 0/1 flags of varying density
/// and small counts. The CPU row runs the same block decomposition on the CPU (block scans,
/// a scan of the block totals, the add pass) against the sequential oracle.
pub fn prefix_sum(backend: &Executor) -> Result<Measure, String> {
    let b = builder(backend)?;
    let mut worst = (0u64, String::new());
    // 65 535 · 64 + 1: the add pass's 2D dispatch split (x = 65 535, y = 2).
    let sizes = [1usize, 2, 511, 512, 513, 1031, 512 * 512, 512 * 512 + 1, 700_001, 4_194_241];
    for (k, &n) in sizes.iter().enumerate() {
        let values: Vec<u32> = (0..n as u32)
            .map(|i| {
                let h = hash(i, k as u32);
                if k % 3 == 2 { (h * 9.0) as u32 } else { (h < 0.05 + 0.3 * k as f32 / 9.0) as u32 }
            })
            .collect();
        let mut expected = Vec::with_capacity(n);
        let mut acc = 0u32;
        for &v in &values {
            expected.push(acc);
            acc += v;
        }
        let (sums, total) = match &b {
            Some(b) => b.prefix_sum(&values).map_err(|e| e.to_string())?,
            None => blocked_scan(&values),
        };
        let bad = (0..n).filter(|&i| sums.get(i) != expected.get(i)).count() as u64
            + (total != acc) as u64;
        if bad > worst.0 {
            worst = (bad, format!("{n} values: {bad} sums differ (total {total}, expected {acc})"));
        }
    }
    let note = if worst.0 == 0 {
        format!("{} sizes up to 4194241 (2D dispatch), exact", sizes.len())
    } else {
        worst.1
    };
    Ok(Measure { max_error: worst.0 as f64, bound: 0.0, pass: worst.0 == 0, note })
}

/// The kernels' scan decomposition on the CPU: 512-value blocks scanned, their totals scanned
/// recursively, then added.
fn blocked_scan(values: &[u32]) -> (Vec<u32>, u32) {
    let mut out = Vec::with_capacity(values.len());
    let mut totals = Vec::new();
    for block in values.chunks(512) {
        let mut acc = 0;
        for &v in block {
            out.push(acc);
            acc += v;
        }
        totals.push(acc);
    }
    if totals.len() <= 1 {
        return (out, totals.first().copied().unwrap_or(0));
    }
    let (offsets, total) = blocked_scan(&totals);
    for (i, s) in out.iter_mut().enumerate() {
        *s += offsets[i / 512];
    }
    (out, total)
}
