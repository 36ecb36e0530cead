//! Voxel transformation (Yalçıner and Sahillioğlu 2020, §4.1–4.2) against re-voxelization, per
//! frame, on `builtin:crowd` with 1, 4, 16 and 64 skinned walkers (17 joints, 3.5 k triangles
//! each) and as many rotating rigid objects, in a world grid of 10 cm voxels:
//! - `transform/nearest`, `transform/8-neighbour`: place and move every cached voxel (linear
//!   blend skinning or a rigid matrix) into world cells;
//! - `transform+blend/8-neighbour`: the same, then the fixed-point blend with the static voxels
//!   and the occupied leaves;
//! - `pose`: skinning and moving the meshes' vertices (what re-voxelizing needs first);
//! - `voxelize/conservative`, `voxelize/thin`: voxelizing the moved triangles, occupancy only,
//!   as the paper compares its transform with a voxelizer.
//!
//! Throughput is in moving objects. Run with `cargo bench -p voxlod-cpu --bench dynamic`; the
//! `voxlod dynamic` study measures whole frames (octree, injection, cone tracing) and memory.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use voxlod_cpu::dynamic::{
    CacheOptions, DynamicScene, RecordSource, build_cache, geometry_of, static_voxels,
};
use voxlod_cpu::voxelize::{self, Mode};
use voxlod_format::GridSpec;
use voxlod_octree::dynamic::{DynamicWorld, Filter, FrameOptions, Placement, VoxelCache};

const VOXEL: f64 = 0.1;
const TIME: f32 = 0.37;

fn bench_count(c: &mut Criterion, walkers: u32) {
    let scene =
        voxlod_scene::procedural::from_spec(&format!("crowd?walkers={walkers}&rigid={walkers}"))
            .expect("the crowd builds");
    let ds = DynamicScene::new(scene, 0).expect("the crowd is animated");
    let (lo, hi) = ds.scene.bounds().expect("the crowd has triangles");
    // The rest bounds grown by a metre on every side: the walkers stay on their circles.
    let (lo, hi) = (lo.as_dvec3() - DVec3::ONE, hi.as_dvec3() + DVec3::ONE);
    let grid = GridSpec::new(lo, VOXEL, ((hi - lo) / VOXEL).ceil().as_uvec3()).expect("a grid");
    let options = CacheOptions { records: RecordSource::Pieces, ..Default::default() };
    let caches: Vec<VoxelCache> = (0..ds.objects.len())
        .map(|o| build_cache(&ds, o, VOXEL, &options).expect("the cache builds"))
        .collect();
    let world = DynamicWorld::new(grid, static_voxels(&ds, &grid, &options).expect("statics"))
        .expect("the world");
    let pose = ds.pose(TIME).expect("a pose");
    let placements = ds.placements(&pose).expect("placements");
    let objects: Vec<(&VoxelCache, &Placement)> = caches.iter().zip(&placements).collect();
    let moving: Vec<usize> = ds.objects.iter().flat_map(|o| o.meshes.iter().copied()).collect();
    let posed = ds.posed_scene(&pose).expect("the posed scene");
    let moved = geometry_of(&posed, &moving);
    eprintln!(
        "crowd of {walkers}: {} objects, {} moving triangles, {} cached voxels, grid {}",
        ds.objects.len(),
        moved.triangle_count(),
        caches.iter().map(VoxelCache::len).sum::<usize>(),
        grid.dims
    );
    let mut group = c.benchmark_group(format!("dynamic_frame/walkers_{walkers}"));
    group.sample_size(10);
    group.throughput(Throughput::Elements(ds.objects.len() as u64));
    for filter in [Filter::Nearest, Filter::EightNeighbour] {
        let o = FrameOptions { filter, ..Default::default() };
        group.bench_function(format!("transform/{}", filter.name()), |b| {
            b.iter(|| world.transform_all(black_box(&objects), &o).expect("transforms"))
        });
    }
    let o = FrameOptions { filter: Filter::EightNeighbour, ..Default::default() };
    group.bench_function("transform+blend/8-neighbour", |b| {
        b.iter(|| world.leaves(black_box(&objects), &o).expect("blends"))
    });
    group.bench_function("pose", |b| b.iter(|| ds.posed_scene(black_box(&pose)).expect("poses")));
    for mode in [Mode::Conservative, Mode::Thin] {
        let v = voxelize::Options { mode, triangle_lists: false, ..Default::default() };
        let name = if mode == Mode::Thin { "thin" } else { "conservative" };
        group.bench_function(format!("voxelize/{name}"), |b| {
            b.iter(|| voxelize::voxelize(black_box(&moved), &grid, &v).expect("voxelizes"))
        });
    }
    group.finish();
}

fn dynamic(c: &mut Criterion) {
    for walkers in [1, 4, 16, 64] {
        bench_count(c, walkers);
    }
}

criterion_group!(benches, dynamic);
criterion_main!(benches);
