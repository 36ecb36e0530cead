//! Conservative voxelization at 256³: occupancy only (what Open3D measures) and with per-voxel
//! triangle lists, on three scenes from 3.7 k to 1.2 M triangles:
//! - `forest_1.2M`: the procedural forest sized to 1.2 M triangles
//!   (`ForestParams::with_target_triangles(1_200_000)`: ground, trunks, branches, leaf quads);
//! - `engine_121k`: the 2CylinderEngine glTF model of `assets/` (121 496 triangles);
//! - `bunny_3.7k`: the bunny of `assets/`.
//!
//! Targets (2 cores): ≥ 2 M triangles/s per core for the 1 M+-triangle scene,
//! occupancy only; < 80 ms for the 120 k-triangle model.
//!
//! Run with `cargo bench -p voxlod-cpu --bench voxelize`. On a machine shared with other
//! work, wall-clock times include waiting for a core; `VOXLOD_BENCH_CPU_TIME=20 cargo bench -p
//! voxlod-cpu --bench voxelize` instead prints, per voxelization, the wall time and the CPU time
//! of all its threads (user + system, from `/proc/self/stat`) averaged over 20 calls.

#[path = "support/mod.rs"]
mod support;

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::IVec3;
use voxlod_cpu::voxelize::lattice::Lattice;
use voxlod_cpu::voxelize::raster::for_each_voxel;
use voxlod_cpu::voxelize::{Mode, Options, voxelize};
use voxlod_format::GridSpec;
use voxlod_scene::Geometry;
use voxlod_scene::procedural::{ForestParams, forest};

const RES: u32 = 256;

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
    let forest = forest(&ForestParams::with_target_triangles(1_200_000))
        .expect("valid forest parameters")
        .geometry();
    let scenes = [
        ("forest_1.2M", forest),
        ("engine_121k", support::engine().geometry()),
        ("bunny_3.7k", support::bunny().geometry()),
    ];
    if let Some(n) = std::env::var("VOXLOD_BENCH_CPU_TIME").ok().and_then(|n| n.parse().ok()) {
        for (name, g) in &scenes {
            raster_cpu_report(name, g, n);
            cpu_time_report(name, g, n);
        }
        return;
    }
    for (name, g) in &scenes {
        bench_scene(c, name, g);
        bench_raster(c, name, g);
    }
}

criterion_group!(voxelize_benches, benches);
criterion_main!(voxelize_benches);
