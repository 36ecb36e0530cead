//! Cone tracing throughput: octree samples ("cone steps") per second for the diffuse cones, and
//! the time of a 1280×720 frame of 6 diffuse cones + 1 specular cone per pixel (CPU, rayon).
//!
//! Scene: a closed 64³ room (1-voxel walls, floor, ceiling) with a 16³ block in it, lit through
//! the ceiling by a directional light (shadows marched in the octree). Shading points: the
//! first voxel hit of a pinhole camera's rays marched through the geometry octree (a ray, level
//! 0), with the voxel's mean normal.
//!
//! `cargo bench -p voxlod-cone --bench cone`; the full-resolution frame runs once per criterion
//! sample (10 samples).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec3, UVec3, Vec3};
use rayon::prelude::*;
use voxlod_cone::{
    Cone, ConeTracer, Light, March, RadiancePayload, Shadows, TraceOptions, inject, trace,
};
use voxlod_format::GridSpec;
use voxlod_octree::{AveragePayload, BuildOptions, Octree};

const N: u32 = 64;

fn room() -> Octree<AveragePayload> {
    let mut v = Vec::new();
    for x in 0..N {
        for y in 0..N {
            for z in 0..N {
                let wall = [x, y, z].iter().any(|&c| c == 0 || c == N - 1);
                let block = (24..40).contains(&x) && y < 17 && (24..40).contains(&z);
                if !(wall || block) {
                    continue;
                }
                let c = Vec3::new(x as f32, y as f32, z as f32) - (N as f32 - 1.0) * 0.5;
                let n = if block {
                    Vec3::Y
                } else {
                    // inward normal of the nearest wall
                    let a = c.abs();
                    if a.x >= a.y && a.x >= a.z {
                        Vec3::new(-c.x.signum(), 0.0, 0.0)
                    } else if a.y >= a.z {
                        Vec3::new(0.0, -c.y.signum(), 0.0)
                    } else {
                        Vec3::new(0.0, 0.0, -c.z.signum())
                    }
                };
                let albedo = if x == 0 { Vec3::new(0.8, 0.1, 0.1) } else { Vec3::splat(0.7) };
                v.push((UVec3::new(x, y, z), AveragePayload::new(albedo, n, 1.0)));
            }
        }
    }
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(N)).unwrap();
    Octree::build(grid, v, &BuildOptions::default()).unwrap()
}

/// Shading points of a `w × h` pinhole camera inside the room (first level-0 hit of each ray).
fn shading_points(geometry: &Octree<AveragePayload>, w: u32, h: u32) -> Vec<(Vec3, Vec3)> {
    let eye = Vec3::new(32.0, 40.0, 60.0);
    let target = Vec3::new(32.0, 16.0, 32.0);
    let f = (target - eye).normalize();
    let r = f.cross(Vec3::Y).normalize();
    let u = r.cross(f);
    let tan = 35f32.to_radians().tan();
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let sx = (2.0 * x / w as f32 - 1.0) * tan * w as f32 / h as f32;
            let sy = (1.0 - 2.0 * y / h as f32) * tan;
            let dir = (f + r * sx + u * sy).normalize();
            let march = March {
                start_voxels: 0.0,
                step_factor: 0.5,
                max_distance: f32::INFINITY,
                opacity_cutoff: 0.5,
                ao: None,
            };
            let hit = trace(geometry, &Cone { apex: eye, dir, aperture: 0.0 }, &march);
            // The march stops half a step past where opacity reached 0.5: step back a voxel.
            let t = (hit.steps as f32) * 0.5 - 1.0;
            let p = eye + dir * t;
            let n = geometry.sample(p, 1.0).normal();
            (p, if n == Vec3::ZERO { -dir } else { n })
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let geometry = room();
    let light =
        Light::Directional { to_light: Vec3::new(0.3, 1.0, 0.2), irradiance: Vec3::splat(3.0) };
    let radiance: Octree<RadiancePayload> = inject(&geometry, &light, &Shadows::MARCH).unwrap();
    let tracer =
        ConeTracer::new(&radiance, TraceOptions { ao_radius: 8.0, ..Default::default() }).unwrap();

    let small = shading_points(&geometry, 160, 90);
    let steps: u64 =
        small.par_iter().map(|&(p, n)| tracer.ao_and_diffuse(p, n, true, true).2 as u64).sum();
    let mut g = c.benchmark_group("cone");
    g.sample_size(10);
    g.throughput(Throughput::Elements(steps));
    g.bench_function("diffuse_6x30deg_steps_160x90", |b| {
        b.iter(|| {
            small.par_iter().map(|&(p, n)| tracer.ao_and_diffuse(p, n, true, true).1).sum::<Vec3>()
        })
    });
    g.finish();

    let eye = Vec3::new(32.0, 40.0, 60.0);
    let frame = |points: &[(Vec3, Vec3)]| -> Vec<Vec3> {
        points
            .par_iter()
            .map(|&(p, n)| {
                let (_, d, _) = tracer.ao_and_diffuse(p, n, false, true);
                let s = tracer.specular(p, n, (eye - p).normalize(), 0.5);
                d + s.radiance
            })
            .collect()
    };
    let quarter = shading_points(&geometry, 320, 180);
    let mut g = c.benchmark_group("frame");
    g.sample_size(10);
    g.throughput(Throughput::Elements(quarter.len() as u64));
    g.bench_function("320x180_6_diffuse_1_specular", |b| b.iter(|| black_box(frame(&quarter))));
    g.finish();

    // One full 1280×720 frame, timed once (criterion's 10 samples would take minutes on a
    // loaded 2-core machine).
    let full = shading_points(&geometry, 1280, 720);
    let start = std::time::Instant::now();
    black_box(frame(&full));
    let t = start.elapsed();
    println!(
        "frame/1280x720_6_diffuse_1_specular (one run, {} threads): {:.3} s",
        rayon::current_num_threads(),
        t.as_secs_f64()
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
