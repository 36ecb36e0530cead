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
use glam::Vec3;
use rayon::prelude::*;
use voxlod_cone::{ConeTracer, Light, RadiancePayload, Shadows, TraceOptions, inject};
use voxlod_octree::Octree;

mod common;
use common::{EYE, room, shading_points};

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

    let eye = EYE;
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
