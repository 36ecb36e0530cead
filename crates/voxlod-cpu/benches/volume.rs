//! The metavoxel pipeline per stage: binning, fill, propagation (all with culling
//! against the view) and the eye march at 512×512, for 10³, 10⁴ and 10⁵ particles of radius 4–16
//! voxels in a 1024³ volume (32³ metavoxels of 32³), and the smoke-column preset (10⁴ particles)
//! as a whole frame.
//!
//! Particle placement: uniform in a ball of radius 128 voxels at the volume's centre (a dense
//! cluster, as effects are; uniform over the whole 1024³ would occupy most of the 32 768
//! metavoxels and need tens of GB with this retained-volume reference).
//!
//! `cargo bench -p voxlod-cpu --bench volume`. Before the criterion runs it prints the stage
//! times of builds (median of 3) and the bytes held, and the smoke frame's stages.
//! `VOXLOD_BENCH_VOLUME_MAX=10000` skips the larger particle counts,
//! `VOXLOD_BENCH_VOLUME_COUNTS=1000,10000` picks them; criterion runs only up to 10⁴ (a 10⁵
//! build takes seconds). A criterion filter matching nothing (`-- none`) prints the figures
//! only.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use voxlod_cpu::volume::{self, BuildSettings, MarchOptions, Volume, VolumeSpec, march};
use voxlod_scene::Camera;
use voxlod_scene::particles::{
    ColorMode, DisplacedSphere, DisplacementMap, SmokeParams, bounds, smoke_column,
};
use voxlod_scene::procedural::Rng;

const SIZE: u32 = 512;

fn cluster(n: usize, spec: &VolumeSpec) -> Vec<DisplacedSphere> {
    let vs = spec.frame.voxel_size;
    let centre = spec.frame.to_world(Vec3::splat(512.0));
    (0..n)
        .map(|i| {
            let mut r = Rng::stream(11, &[i as u64]);
            let r_in = r.range(3.0, 12.0);
            DisplacedSphere {
                center: centre + r.in_unit_ball() * 128.0 * vs,
                inner: r_in * vs,
                amplitude: r.range(1.0, 16.0 - r_in) * vs,
                color: Vec3::splat(r.range(0.6, 0.9)),
                color_outer: Vec3::ONE,
                density: 0.02 / vs,
                rot_cos: 1.0,
                rot_sin: 0.0,
                color_mode: ColorMode::DisplacementAo as u32,
                flags: 0,
            }
        })
        .collect()
}

fn median3(mut f: impl FnMut() -> Volume) -> (Volume, [Duration; 4]) {
    let mut runs: Vec<(Volume, [Duration; 4])> = (0..3)
        .map(|_| {
            let v = f();
            let t = v.times;
            (v, [t.binning + t.culling, t.fill, t.propagation, Duration::ZERO])
        })
        .collect();
    let mut out = [Duration::ZERO; 4];
    for (s, o) in out.iter_mut().enumerate() {
        let mut d: Vec<Duration> = runs.iter().map(|r| r.1[s]).collect();
        d.sort();
        *o = d[1];
    }
    (runs.pop().expect("three runs").0, out)
}

fn stages(c: &mut Criterion) {
    let max: usize = std::env::var("VOXLOD_BENCH_VOLUME_MAX")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    let spec =
        VolumeSpec::fit(Vec3::splat(-1.0), Vec3::splat(1.0), Vec3::new(0.3, 0.9, 0.2), 32, 32)
            .expect("a valid volume");
    let map = DisplacementMap::noise(3, 32, 3.0, 4).expect("a valid map");
    let camera = Camera::look_at(Vec3::new(0.6, 0.5, 1.4), Vec3::ZERO, Vec3::Y, 30.0);
    let frame = camera.frame(SIZE, SIZE);
    let settings = BuildSettings::default();
    let options = MarchOptions { width: SIZE, height: SIZE, step: 1.0 };
    let mut group = c.benchmark_group("volume");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    // `VOXLOD_BENCH_VOLUME_COUNTS=1000,10000` picks the particle counts (default all up to MAX).
    let counts: Vec<usize> = std::env::var("VOXLOD_BENCH_VOLUME_COUNTS")
        .ok()
        .map(|s| s.split(',').filter_map(|n| n.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![1_000, 10_000, 100_000]);
    for n in counts.into_iter().filter(|&n| n <= max) {
        let spheres = cluster(n, &spec);
        let build =
            || volume::build(&spheres, &map, &spec, &settings, Some(&frame), None).expect("built");
        let (v, t) = median3(build);
        let m0 = std::time::Instant::now();
        march::render(&v, &camera, &options, None).expect("rendered");
        eprintln!(
            "{n} particles, 1024³ (32³ × 32³), {SIZE}²: occupied {} kept {} metavoxels, \
             {:.1} MiB (dense {:.0} MiB); binning+cull {:.3} s, fill {:.3} s, propagation {:.3} s, \
             march {:.3} s",
            v.stats.occupied,
            v.stats.kept,
            v.bytes() as f64 / 1048576.0,
            spec.dense_bytes() as f64 / 1048576.0,
            t[0].as_secs_f64(),
            t[1].as_secs_f64(),
            t[2].as_secs_f64(),
            m0.elapsed().as_secs_f64()
        );
        if n > 10_000 {
            continue; // one build of 10⁵ particles takes seconds: the figure above only
        }
        group.bench_function(format!("binning/{n}"), |b| {
            b.iter(|| black_box(volume::binning::bin(&spheres, &spec)))
        });
        group.bench_function(format!("build/{n}"), |b| b.iter(|| black_box(build())));
        group.bench_function(format!("march/{n}"), |b| {
            b.iter(|| black_box(march::render(&v, &camera, &options, None).expect("rendered")))
        });
    }
    // The smoke-column preset, one whole frame at 512×512 in a 256³ volume (8³ × 32³).
    let system = smoke_column(&SmokeParams::default()).expect("valid preset");
    let spheres = system.at(system.time);
    let (lo, hi) = bounds(&spheres).expect("particles alive");
    let spec = VolumeSpec::fit(lo, hi, Vec3::new(0.45, 0.85, 0.3), 8, 32).expect("valid volume");
    let centre = (lo + hi) * 0.5;
    let camera =
        Camera::framing(Vec3::new(0.35, 0.25, 1.0), centre, 0.75 * (hi - lo).max_element(), 45.0);
    let frame = camera.frame(SIZE, SIZE);
    let frame_fn = || {
        let v = volume::build(&spheres, &system.displacement, &spec, &settings, Some(&frame), None)
            .expect("built");
        march::render(&v, &camera, &options, None).expect("rendered")
    };
    let t = std::time::Instant::now();
    frame_fn();
    let frame_s = t.elapsed().as_secs_f64();
    let v = volume::build(&spheres, &system.displacement, &spec, &settings, Some(&frame), None)
        .expect("built");
    let m0 = std::time::Instant::now();
    march::render(&v, &camera, &options, None).expect("rendered");
    let s = v.times;
    eprintln!(
        "smoke preset ({} particles), 256³, {SIZE}²: one frame {frame_s:.3} s; kept {} \
         metavoxels; binning+cull {:.3} s, fill {:.3} s, propagation {:.3} s, march {:.3} s",
        spheres.len(),
        v.stats.kept,
        (s.binning + s.culling).as_secs_f64(),
        s.fill.as_secs_f64(),
        s.propagation.as_secs_f64(),
        m0.elapsed().as_secs_f64()
    );
    group.bench_function("smoke-frame/10000", |b| b.iter(|| black_box(frame_fn())));
    group.finish();
}

criterion_group!(benches, stages);
criterion_main!(benches);
