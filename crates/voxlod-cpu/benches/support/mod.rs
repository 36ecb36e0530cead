//! Scenes, views and kernels shared by the `raycast` and `render` benches.

#![allow(dead_code)] // each bench uses a subset

use std::path::Path;

use glam::Vec2;
use rayon::prelude::*;
use voxlod_cpu::raycast::Bvh;
use voxlod_scene::procedural::{ForestParams, forest};
use voxlod_scene::{Camera, Geometry, Scene};

/// The image edge of the primary-ray benches: 512×512 pixels.
pub const SIZE: u32 = 512;

/// The bunny of `assets/bunny/bunny.obj` (npm `bunny`, 3 674 triangles).
pub fn bunny() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj");
    Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The 2CylinderEngine glTF model of `assets/` (121 496 triangles).
pub fn engine() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/2CylinderEngine/2CylinderEngine.glb");
    Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The large scene: the procedural forest at about 1 M triangles (alpha-masked leaves).
pub fn large() -> Scene {
    forest(&ForestParams::with_target_triangles(1_000_000)).expect("forest parameters are valid")
}

/// The scene's framing view (its own camera, or one fitting its bounds): many rays miss.
pub fn framing(scene: &Scene) -> Camera {
    scene.default_camera().expect("a non-empty scene")
}

/// A close-up: a 12° view from the framing direction at a third of the distance, aimed at
/// the centre of the bounds, where every ray of the bunny hits.
pub fn close_up(scene: &Scene) -> Camera {
    let (lo, hi) = scene.bounds().expect("a non-empty scene");
    let c = (lo + hi) * 0.5;
    let f = framing(scene);
    Camera::look_at(c + (f.eye - c) / 3.0, c, f.up, 12.0)
}

/// Casts one closest-hit ray through the centre of every pixel of a `size²` image, in
/// parallel over rows on the current rayon pool; returns the number of hits.
pub fn primary_rays(bvh: &Bvh, camera: &Camera, size: u32) -> u64 {
    let frame = camera.frame(size, size);
    (0..size)
        .into_par_iter()
        .map(|y| {
            let mut hits = 0u64;
            for x in 0..size {
                let dir = frame.ray_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                hits += bvh.intersect(frame.eye, dir, 0.0, f32::INFINITY).is_some() as u64;
            }
            hits
        })
        .sum()
}

/// [`primary_rays`] traced as packets of 2×2 pixels (`Bvh::intersect_packet`); `size` must
/// be even.
pub fn primary_packets(bvh: &Bvh, camera: &Camera, size: u32) -> u64 {
    let frame = camera.frame(size, size);
    (0..size / 2)
        .into_par_iter()
        .map(|by| {
            let mut hits = 0u64;
            for bx in 0..size / 2 {
                let ray = |dx: u32, dy: u32| {
                    let p = Vec2::new((2 * bx + dx) as f32 + 0.5, (2 * by + dy) as f32 + 0.5);
                    frame.ray_dir(p)
                };
                let dirs = [ray(0, 0), ray(1, 0), ray(0, 1), ray(1, 1)];
                let h = bvh.intersect_packet(frame.eye, &dirs, 0.0, f32::INFINITY);
                hits += h.iter().filter(|h| h.is_some()).count() as u64;
            }
            hits
        })
        .sum()
}

/// A rayon pool of `threads` threads.
pub fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool")
}

/// The geometry and BVH of a scene.
pub fn prepare(scene: &Scene) -> (Geometry, Bvh) {
    let g = scene.geometry();
    let bvh = Bvh::new(&g).expect("a valid scene");
    (g, bvh)
}

/// CPU time the calling thread has run (from `/proc/thread-self/schedstat`, nanoseconds):
/// unlike wall time, it does not count time other processes took from this thread, so rates
/// per CPU-second measure per-core speed on a busy machine. Zero where unavailable.
pub fn thread_cpu_time() -> std::time::Duration {
    let ns = std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .unwrap_or(0);
    std::time::Duration::from_nanos(ns)
}

/// Runs `f` on a fresh 1-thread pool and returns its result with the CPU time it took.
pub fn single_core<T: Send>(f: impl FnOnce() -> T + Send) -> (T, std::time::Duration) {
    pool(1).install(|| {
        let start = thread_cpu_time();
        let out = f();
        (out, thread_cpu_time() - start)
    })
}

/// The procedural forest at about `target` triangles (alpha-masked leaves).
pub fn forest_of(target: u64) -> Scene {
    forest(&ForestParams::with_target_triangles(target)).expect("forest parameters are valid")
}

/// Voxelizes `geometry` (conservative, with triangle lists) into the grid of `resolution`
/// voxels along the longest side of `scene`'s bounds.
pub fn voxelized(
    scene: &Scene,
    geometry: &Geometry,
    resolution: u32,
) -> voxlod_cpu::voxelize::Voxelization {
    let (lo, hi) = scene.bounds().expect("a non-empty scene");
    let grid = voxlod_format::GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), resolution)
        .expect("a valid grid");
    voxlod_cpu::voxelize::voxelize(geometry, &grid, &voxlod_cpu::voxelize::Options::default())
        .expect("voxelized")
}
