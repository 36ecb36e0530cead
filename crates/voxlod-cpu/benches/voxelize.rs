//! Conservative voxelization at 256³: occupancy only (what Open3D measures) and with per-voxel
//! triangle lists, on
//! - `leaves_1M`: a forest-like stand-in of ~1 M triangles — 500 k small quads (0.2–1.5 voxels
//!   across, random orientations) scattered through the crowns of 300 "trees" (emitted tree by
//!   tree), over a ground plane spanning the grid;
//! - `torus_120k`: a smooth torus of ~120 k triangles filling the grid.
//!
//! The meshes are generated here, deterministically, because the procedural forest and the
//! asset loaders are being written in parallel; swap in `builtin:forest` and a 120 k-triangle
//! glTF model once they land. Targets (issue 2, 2 cores): ≥ 2 M triangles/s per core for the
//! 1 M-triangle scene, occupancy only; < 80 ms for the 120 k-triangle model.
//!
//! Run with `cargo bench -p voxlod-cpu --bench voxelize`. On a machine shared with other
//! work, wall-clock times include waiting for a core; `VOXLOD_BENCH_CPU_TIME=20 cargo bench -p
//! voxlod-cpu --bench voxelize` instead prints, per voxelization, the wall time and the CPU time
//! of all its threads (user + system, from `/proc/self/stat`) averaged over 20 calls.

use std::f32::consts::TAU;
use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{IVec3, Vec3, vec3};
use voxlod_cpu::random::rand_f32;
use voxlod_cpu::voxelize::lattice::Lattice;
use voxlod_cpu::voxelize::raster::for_each_voxel;
use voxlod_cpu::voxelize::{Mode, Options, voxelize};
use voxlod_format::GridSpec;
use voxlod_scene::Geometry;

const RES: u32 = 256;

fn push_quad(g: &mut Geometry, corners: [Vec3; 4]) {
    let base = g.positions.len() as u32;
    g.positions.extend(corners);
    g.indices.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
}

/// ~1 M triangles in a 100 × 40 × 100 box: a ground quad and 500 k leaf quads in 300 crowns.
fn leaves(quads: u32) -> Geometry {
    let mut g = Geometry::default();
    let (w, h) = (100.0, 40.0);
    push_quad(&mut g, [vec3(0.0, 0.0, 0.0), vec3(w, 0.0, 0.0), vec3(w, 0.0, w), vec3(0.0, 0.0, w)]);
    let r = |i: u32, d: u32| rand_f32(i, 7, d);
    let crowns: Vec<(Vec3, f32)> = (0..300)
        .map(|t| {
            let centre =
                vec3(5.0 + 90.0 * r(t, 0), h * (0.3 + 0.5 * r(t, 1)), 5.0 + 90.0 * r(t, 2));
            (centre, 3.0 + 5.0 * r(t, 3))
        })
        .collect();
    let voxel = w / RES as f32;
    for i in 0..quads {
        // Tree by tree, as a procedural generator emits them.
        let (centre, radius) = crowns[(i as u64 * 300 / quads as u64) as usize];
        let q = |d: u32| rand_f32(i, 1, d);
        // A point in the crown's ball, a random frame, a size of 0.2–1.5 voxels.
        let dir = vec3(q(0) * 2.0 - 1.0, q(1) * 2.0 - 1.0, q(2) * 2.0 - 1.0);
        let p = centre + dir.normalize_or_zero() * radius * q(3).cbrt();
        let n = vec3(q(4) * 2.0 - 1.0, q(5) * 2.0 - 1.0, q(6) * 2.0 - 1.0).normalize_or(Vec3::Y);
        let (s, c) = (q(7) * TAU).sin_cos();
        let u = n.any_orthonormal_vector();
        let u = u * c + n.cross(u) * s;
        let v = n.cross(u);
        let size = voxel * (0.2 + 1.3 * q(8));
        let (u, v) = (u * size * 0.5, v * size * 0.5);
        push_quad(&mut g, [p - u - v, p + u - v, p + u + v, p - u + v]);
    }
    g.normals = vec![Vec3::Y; g.positions.len()];
    g
}

/// A torus with `major × minor` quads (2 triangles each), shared vertices.
fn torus(major: u32, minor: u32) -> Geometry {
    let mut g = Geometry::default();
    let (big, small) = (1.0, 0.38);
    for i in 0..major {
        for j in 0..minor {
            let (a, b) = (i as f32 / major as f32 * TAU, j as f32 / minor as f32 * TAU);
            let ring = big + small * b.cos();
            g.positions.push(vec3(ring * a.cos(), small * b.sin(), ring * a.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % major) * minor + j % minor;
    for i in 0..major {
        for j in 0..minor {
            let (p, q, r, s) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            g.indices.extend([[p, q, r], [p, r, s]]);
        }
    }
    g.normals = vec![Vec3::Y; g.positions.len()];
    g
}

fn fitted(g: &Geometry) -> GridSpec {
    let (lo, hi) = g.bounds().expect("the scene has triangles");
    GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), RES).expect("a valid grid")
}

fn bench_scene(c: &mut Criterion, name: &str, g: &Geometry) {
    let grid = fitted(g);
    let lists = Options { mode: Mode::Conservative, triangle_lists: true, ..Options::default() };
    let occupancy = Options { triangle_lists: false, ..lists };
    let v = voxelize(g, &grid, &lists).expect("voxelizes");
    eprintln!(
        "{name}: {} triangles, grid {}, {} occupied voxels, {} (voxel, triangle) pairs",
        g.triangle_count(),
        grid.dims,
        v.voxels.len(),
        v.triangles.len()
    );
    let mut group = c.benchmark_group(format!("voxelize_conservative_{RES}"));
    group.sample_size(10);
    group.throughput(Throughput::Elements(g.triangle_count() as u64));
    group.bench_function(format!("{name}/occupancy"), |b| {
        b.iter(|| voxelize(black_box(g), &grid, &occupancy).expect("voxelizes"))
    });
    group.bench_function(format!("{name}/lists"), |b| {
        b.iter(|| voxelize(black_box(g), &grid, &lists).expect("voxelizes"))
    });
    group.finish();
}

/// The per-triangle rasterizer alone, on one core: snapped triangles in, voxels counted.
fn bench_raster(c: &mut Criterion, name: &str, g: &Geometry) {
    let grid = fitted(g);
    let lattice = Lattice::new(g, &grid).expect("snaps");
    let tris: Vec<[IVec3; 3]> =
        g.indices.iter().map(|t| t.map(|i| lattice.vertex(i).expect("in range"))).collect();
    let mut group = c.benchmark_group(format!("raster_one_core_{RES}"));
    group.sample_size(10);
    group.throughput(Throughput::Elements(tris.len() as u64));
    for (mode, thin) in [("conservative", false), ("thin", true)] {
        group.bench_function(format!("{name}/{mode}"), |b| {
            b.iter(|| {
                let mut count = 0u64;
                for t in black_box(&tris) {
                    for_each_voxel(t, thin, grid.dims, |_| count += 1);
                }
                count
            })
        });
    }
    group.finish();
}

/// User + system CPU seconds of this process (all threads), from `/proc/self/stat`.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("Linux /proc");
    let fields: Vec<&str> = stat[stat.rfind(')').expect("comm") + 2..].split(' ').collect();
    let ticks: f64 =
        fields[11].parse::<f64>().expect("utime") + fields[12].parse::<f64>().expect("stime");
    ticks / 100.0
}

/// Wall and CPU time per call of `voxelize`, averaged over `n` calls.
fn cpu_time_report(name: &str, g: &Geometry, n: u32) {
    let grid = fitted(g);
    for lists in [false, true] {
        let options =
            Options { mode: Mode::Conservative, triangle_lists: lists, ..Options::default() };
        voxelize(g, &grid, &options).expect("voxelizes");
        let (wall, cpu) = (std::time::Instant::now(), cpu_seconds());
        for _ in 0..n {
            black_box(voxelize(black_box(g), &grid, &options).expect("voxelizes"));
        }
        let wall = wall.elapsed().as_secs_f64() / n as f64;
        let cpu = (cpu_seconds() - cpu) / n as f64;
        let what = if lists { "lists" } else { "occupancy" };
        println!(
            "{name}/{what}: wall {:.1} ms, CPU {:.1} ms (all threads), {:.2} M triangles per CPU-second",
            wall * 1e3,
            cpu * 1e3,
            g.triangle_count() as f64 / cpu / 1e6
        );
    }
}

/// CPU time per triangle of the rasterizer alone (one thread).
fn raster_cpu_report(name: &str, g: &Geometry, n: u32) {
    let grid = fitted(g);
    let lattice = Lattice::new(g, &grid).expect("snaps");
    let tris: Vec<[IVec3; 3]> =
        g.indices.iter().map(|t| t.map(|i| lattice.vertex(i).expect("in range"))).collect();
    for thin in [false, true] {
        let cpu = cpu_seconds();
        let mut count = 0u64;
        for _ in 0..n {
            for t in black_box(&tris) {
                for_each_voxel(t, thin, grid.dims, |_| count += 1);
            }
        }
        let ns = (cpu_seconds() - cpu) / n as f64 / tris.len() as f64 * 1e9;
        println!(
            "{name}/raster thin={thin}: {ns:.0} ns CPU per triangle ({} voxels)",
            count / n as u64
        );
    }
}

fn benches(c: &mut Criterion) {
    let leaves = leaves(500_000);
    let torus = torus(346, 174);
    if let Some(n) = std::env::var("VOXLOD_BENCH_CPU_TIME").ok().and_then(|n| n.parse().ok()) {
        raster_cpu_report("leaves_1M", &leaves, n);
        raster_cpu_report("torus_120k", &torus, n);
        cpu_time_report("leaves_1M", &leaves, n);
        cpu_time_report("torus_120k", &torus, n);
        return;
    }
    bench_scene(c, "leaves_1M", &leaves);
    bench_raster(c, "leaves_1M", &leaves);
    bench_scene(c, "torus_120k", &torus);
    bench_raster(c, "torus_120k", &torus);
}

criterion_group!(voxelize_benches, benches);
criterion_main!(voxelize_benches);
