//! Kernel 1, conservative and thin surface voxelization.
//!
//! Oracle: every voxel of each triangle's clipped voxel range tested one by one with
//! `voxlod_cpu::voxelize::overlap` (the per-voxel reference the CPU rasterizer is proven
//! against), counting triangles per voxel. Tolerance: **exact** — occupancy and triangles per
//! voxel are integer results of integer arithmetic on both backends, so the error (voxels
//! whose occupancy or count differs) must be 0.

use std::cell::RefCell;
use std::collections::HashMap;

use glam::{DVec3, UVec3, Vec3};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use voxlod_cpu::random::rand_f32;
use voxlod_cpu::voxelize::lattice::{Lattice, Reach, voxel_span};
use voxlod_cpu::voxelize::{Mode, Options, overlap};
use voxlod_format::GridSpec;
use voxlod_gpu::voxelize::{VoxelizeOptions, Voxelizer};
use voxlod_scene::Geometry;

use crate::harness::{Executor, Measure};

type Counts = HashMap<UVec3, u32>;

/// Triangles per voxel by brute force over each triangle's clipped range.
fn oracle(geometry: &Geometry, grid: &GridSpec, mode: Mode) -> Counts {
    let lattice = Lattice::new(geometry, grid).expect("valid test geometry");
    let mut out = Counts::new();
    for t in 0..geometry.indices.len() {
        let Some(tri) = lattice.triangle(geometry, t, Reach::Surface).expect("valid") else {
            continue;
        };
        let lo = tri[0].min(tri[1]).min(tri[2]);
        let hi = tri[0].max(tri[1]).max(tri[2]);
        let span = |k: usize| {
            let (a, b) = voxel_span(lo[k], hi[k]);
            (a.max(0), b.min(grid.dims[k] as i32 - 1))
        };
        let (sx, sy, sz) = (span(0), span(1), span(2));
        for z in sz.0..=sz.1 {
            for y in sy.0..=sy.1 {
                for x in sx.0..=sx.1 {
                    let v = glam::IVec3::new(x, y, z);
                    let hit = match mode {
                        Mode::Thin => overlap::diamond_overlap(&tri, v),
                        _ => overlap::box_overlap(&tri, v),
                    };
                    if hit {
                        *out.entry(v.as_uvec3()).or_default() += 1;
                    }
                }
            }
        }
    }
    out
}

/// The GPU kernel of `backend`, compiled once per body.
fn kernel<'a>(backend: &Executor<'a>) -> Result<Option<Voxelizer<'a>>, String> {
    match backend {
        Executor::Cpu => Ok(None),
        Executor::Gpu(ctx) => Voxelizer::new(ctx).map(Some).map_err(|e| e.to_string()),
    }
}

/// The backend's triangles per voxel.
fn run(
    kernel: &Option<Voxelizer>,
    geometry: &Geometry,
    grid: &GridSpec,
    mode: Mode,
) -> Result<Counts, String> {
    match kernel {
        None => {
            let opts = Options { mode, triangle_lists: true, ..Default::default() };
            let v =
                voxlod_cpu::voxelize::voxelize(geometry, grid, &opts).map_err(|e| e.to_string())?;
            Ok(v.voxels.iter().map(|(c, r)| (c, r.count)).collect())
        }
        Some(voxelizer) => {
            let v = voxelizer
                .voxelize(geometry, grid, &VoxelizeOptions { mode, counts: true })
                .map_err(|e| e.to_string())?;
            Ok(v.coords().map(|c| (c, v.count(c).unwrap())).collect())
        }
    }
}

/// Voxels whose count differs (occupancy included), and a description of the first.
fn difference(actual: &Counts, expected: &Counts) -> (usize, String) {
    let mut bad = 0;
    let mut first = String::new();
    for (c, &n) in expected.iter() {
        let a = actual.get(c).copied().unwrap_or(0);
        if a != n {
            bad += 1;
            if first.is_empty() {
                first = format!("voxel {c}: {a} triangles, expected {n}");
            }
        }
    }
    for (c, &a) in actual.iter() {
        if !expected.contains_key(c) {
            bad += 1;
            if first.is_empty() {
                first = format!("voxel {c}: {a} triangles, expected none");
            }
        }
    }
    (bad, first)
}

fn soup(n: u32, extent: f32, seed: u32) -> Geometry {
    let mut positions = Vec::new();
    let r = |i: u32, d: u32| rand_f32(seed.wrapping_add(i), 0, d);
    for t in 0..n {
        let size = extent * [0.01, 0.1, 0.4, 1.0][(t % 4) as usize];
        let c = Vec3::new(r(t, 0), r(t, 1), r(t, 2)) * extent * 1.2 - extent * 0.1;
        for v in 0..3 {
            let d = Vec3::new(r(t, 3 + 3 * v), r(t, 4 + 3 * v), r(t, 5 + 3 * v)) - 0.5;
            let mut p = c + d * size;
            if t % 5 == 0 {
                p = (p * 2.0).round() * 0.5; // on voxel faces, edges and centres: ties
            }
            positions.push(p);
        }
        if t % 17 == 0 {
            let k = positions.len();
            positions[k - 1] = positions[k - 3]; // degenerate: a segment
        }
        if t % 23 == 0 {
            let k = positions.len();
            positions[k - 1] = positions[k - 3] * 0.5 + positions[k - 2] * 0.5; // collinear
        }
    }
    Geometry {
        indices: (0..n).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
        positions,
        ..Default::default()
    }
}

fn bunny() -> Geometry {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
    voxlod_scene::Scene::load(&path).expect("the bunny asset loads").geometry()
}

fn measure(cases: Vec<(String, usize, String)>) -> Measure {
    let worst = cases.iter().max_by_key(|c| c.1).cloned();
    let max_error = worst.as_ref().map_or(0, |w| w.1);
    Measure {
        max_error: max_error as f64,
        bound: 0.0,
        pass: max_error == 0,
        note: match worst {
            Some((name, e, first)) if e > 0 => format!("{name}: {e} voxels differ; {first}"),
            _ => format!("{} cases, exact", cases.len()),
        },
    }
}

/// Fixed scenes: the bunny, a triangle soup with ties and degenerate triangles, and
/// triangles with far vertices (the full-width integer arithmetic), in both modes.
pub fn scenes(backend: &Executor) -> Result<Measure, String> {
    let kernel = kernel(backend)?;
    let bunny = bunny();
    let (lo, hi) = bunny.bounds().unwrap();
    let bunny_grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 40).unwrap();
    let soup_grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::new(24, 20, 28)).unwrap();
    let soup = soup(300, 24.0, 7);
    // Vertices 2·10^5 voxels away (lattice values near 2^25.6) reaching into the grid.
    let far = far(2.0e5);
    let far_grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(14)).unwrap();
    let mut cases = Vec::new();
    for mode in [Mode::Conservative, Mode::Thin] {
        for (name, g, grid) in [
            ("bunny 40", &bunny, &bunny_grid),
            ("soup", &soup, &soup_grid),
            ("far", &far, &far_grid),
        ] {
            let expected = oracle(g, grid, mode);
            let actual = run(&kernel, g, grid, mode)?;
            let (bad, first) = difference(&actual, &expected);
            cases.push((format!("{name} {mode:?}"), bad, first));
        }
    }
    Ok(measure(cases))
}

/// Two triangles reaching into a 14³ grid from vertices `r` voxels away.
fn far(r: f32) -> Geometry {
    Geometry {
        positions: vec![
            Vec3::new(-r, 3.3, 4.1),
            Vec3::new(9.7, 0.8 * r, 5.5),
            Vec3::new(5.2, 6.1, 7.25),
            Vec3::new(3.1, 4.2, -0.73 * r),
            Vec3::new(0.93 * r, 0.87 * r, 8.2),
            Vec3::new(6.6, 2.2, 9.1),
        ],
        indices: vec![[0, 1, 2], [3, 4, 5]],
        ..Default::default()
    }
}

/// Triangles up to the lattice's range (vertices 1.5·10^6 voxels away, lattice values near
/// 2^28.5 of the 2^29 limit): the full-width emulated integer arithmetic of the GPU kernel.
pub fn full_range(backend: &Executor) -> Result<Measure, String> {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(14)).unwrap();
    let g = far(1.5e6);
    let kernel = kernel(backend)?;
    let mut cases = Vec::new();
    for mode in [Mode::Conservative, Mode::Thin] {
        let expected = oracle(&g, &grid, mode);
        let actual = run(&kernel, &g, &grid, mode)?;
        let (bad, first) = difference(&actual, &expected);
        cases.push((format!("far 1.5e6 {mode:?}"), bad, first));
    }
    Ok(measure(cases))
}

/// Random grids (dims, origin, voxel size) and random triangles, many on lattice ties.
pub fn property(backend: &Executor) -> Result<Measure, String> {
    let vertex = (0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0, any::<bool>());
    let strategy = (
        (1u32..12, 1u32..12, 1u32..12),
        (-3.0f64..3.0, -3.0f64..3.0, 0.05f64..4.0),
        prop::collection::vec((vertex.clone(), vertex.clone(), vertex), 1..8),
        any::<bool>(),
    );
    let kernel = kernel(backend)?;
    // The same cases on every backend: a fixed seed (PROPTEST_CASES sets how many).
    let mut runner = TestRunner::new_with_rng(
        Config { failure_persistence: None, ..Config::default() },
        TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    );
    let cases = RefCell::new(Vec::new());
    let error = RefCell::new(None);
    let result = runner.run(&strategy, |(dims, (ox, oy, s), tris, thin)| {
        let dims = UVec3::new(dims.0, dims.1, dims.2);
        let grid = GridSpec::new(DVec3::new(ox, oy, ox - oy), s, dims).unwrap();
        let mut positions = Vec::new();
        for (a, b, c) in &tris {
            for &(x, y, z, snap) in [a, b, c] {
                // Up to 30 % outside the grid on every side; half the vertices on half-voxels.
                let g = (Vec3::new(x, y, z) * 1.6 - 0.3) * dims.as_vec3();
                let g = if snap { (g * 2.0).round() * 0.5 } else { g };
                positions.push((grid.origin + g.as_dvec3() * s).as_vec3());
            }
        }
        let n = tris.len() as u32;
        let geometry = Geometry {
            positions,
            indices: (0..n).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
            ..Default::default()
        };
        let mode = if thin { Mode::Thin } else { Mode::Conservative };
        let expected = oracle(&geometry, &grid, mode);
        let actual = match run(&kernel, &geometry, &grid, mode) {
            Ok(a) => a,
            Err(e) => {
                *error.borrow_mut() = Some(e.clone());
                return Err(TestCaseError::fail(e));
            }
        };
        let (bad, first) = difference(&actual, &expected);
        cases.borrow_mut().push((
            format!("{dims} grid, {n} triangles, {mode:?}"),
            bad,
            first.clone(),
        ));
        prop_assert_eq!(bad, 0, "{}", first);
        Ok(())
    });
    if let Some(e) = error.into_inner() {
        return Err(e);
    }
    let mut m = measure(cases.into_inner());
    if let Err(e) = result {
        m.pass = false;
        m.note = format!("minimal failing case: {e}");
    }
    Ok(m)
}
