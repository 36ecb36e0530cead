//! Primary-ray casting through the BVH: 512×512 rays, one per pixel centre, on the bunny from
//! its framing view (most rays miss) and from a close-up (every ray hits), and on a 1 M-triangle
//! forest; on 1 and 2 threads. Throughput is rays per second (divide the 2-thread figure by 2
//! for rays/s per core), single rays and 2×2-pixel packets. Also the BVH builds. Before the
//! criterion runs it prints single-core rates per CPU-second, which other processes on the
//! machine do not distort.
//!
//! `VOXLOD_BENCH_PRESETS=1 cargo bench -p voxlod-cpu --bench raycast` instead prints the
//! measurement behind `Bvh::DEFAULT_PARAMS`: build and trace times of every obvhs preset.

mod support;

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use obvhs::BvhBuildParams;
use voxlod_cpu::raycast::Bvh;

use support::{
    SIZE, bunny, close_up, framing, large, pool, prepare, primary_packets, primary_rays,
    single_core,
};

fn primary(c: &mut Criterion) {
    let bunny = bunny();
    let forest = large();
    let (bg, bunny_bvh) = prepare(&bunny);
    let (fg, forest_bvh) = prepare(&forest);
    let cases = [
        ("bunny", "framing", &bunny_bvh, framing(&bunny)),
        ("bunny", "close-up", &bunny_bvh, close_up(&bunny)),
        ("forest-1M", "framing", &forest_bvh, framing(&forest)),
    ];
    let rays = SIZE as f64 * SIZE as f64;
    eprintln!(
        "bunny: {} triangles, forest: {} triangles; rates below are single-core, per CPU-second",
        bg.triangle_count(),
        fg.triangle_count()
    );
    for (name, view, bvh, camera) in &cases {
        let hits = primary_rays(bvh, camera, SIZE);
        let rate = |f: &(dyn Fn() -> u64 + Sync)| {
            let mut t: Vec<Duration> = (0..7).map(|_| single_core(|| black_box(f())).1).collect();
            t.sort();
            rays / t[3].as_secs_f64() / 1e6
        };
        let single = rate(&|| primary_rays(bvh, camera, SIZE));
        let packets = rate(&|| primary_packets(bvh, camera, SIZE));
        eprintln!(
            "{name}, {view}: {:.1} % of the rays hit; {single:.2} M rays/s single rays, \
             {packets:.2} M rays/s 2×2 packets",
            100.0 * hits as f64 / rays
        );
    }
    let mut group = c.benchmark_group("primary_rays_512x512");
    group.throughput(Throughput::Elements(SIZE as u64 * SIZE as u64));
    group.sample_size(20);
    for (name, view, bvh, camera) in &cases {
        for threads in [1, 2] {
            let p = pool(threads);
            group.bench_function(format!("{name}/{view}/packets/{threads}-thread"), |b| {
                b.iter(|| p.install(|| black_box(primary_packets(bvh, camera, SIZE))))
            });
        }
        let p = pool(2);
        group.bench_function(format!("{name}/{view}/single/2-thread"), |b| {
            b.iter(|| p.install(|| black_box(primary_rays(bvh, camera, SIZE))))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("bvh_build");
    group.sample_size(10);
    for (name, g) in [("bunny", &bg), ("forest-1M", &fg)] {
        group.throughput(Throughput::Elements(g.triangle_count() as u64));
        group.bench_function(name, |b| b.iter(|| black_box(Bvh::new(g).expect("valid"))));
    }
    group.finish();
}

/// Build and trace times of every obvhs preset: the measurement behind `Bvh::DEFAULT_PARAMS`.
/// Single core, CPU time (median of several runs), so that other processes on the machine do
/// not distort the comparison.
fn preset_table() {
    let presets: [(&str, BvhBuildParams); 6] = [
        ("fastest_build", BvhBuildParams::fastest_build()),
        ("very_fast_build", BvhBuildParams::very_fast_build()),
        ("fast_build", BvhBuildParams::fast_build()),
        ("medium_build", BvhBuildParams::medium_build()),
        ("slow_build", BvhBuildParams::slow_build()),
        ("very_slow_build", BvhBuildParams::very_slow_build()),
    ];
    let (bunny, forest) = (bunny(), large());
    let (bg, fg) = (bunny.geometry(), forest.geometry());
    let median = |mut v: Vec<Duration>| {
        v.sort();
        v[v.len() / 2]
    };
    let views = [framing(&bunny), close_up(&bunny), framing(&forest)];
    println!("single core, CPU time; trace rates (2×2 packets) in M rays per CPU-second");
    println!(
        "| preset | build bunny | build forest 1M | bunny framing | bunny close-up | forest framing |"
    );
    println!("|---|---|---|---|---|---|");
    for (name, params) in presets {
        let mut row = format!("| {name} |");
        let mut bvhs = Vec::new();
        // Builds repeated within a sample so that it lasts well over the clock's tick.
        for (g, runs, reps) in [(&bg, 7, 50), (&fg, 3, 1)] {
            let mut times = Vec::new();
            for _ in 0..runs {
                let (bvh, dt) = single_core(|| {
                    let mut last = None;
                    for _ in 0..reps {
                        last = Some(Bvh::with_params(g, params).expect("valid"));
                    }
                    last
                });
                times.push(dt / reps);
                bvhs.push(bvh.expect("built"));
            }
            row += &format!(" {:.1} ms |", median(times).as_secs_f64() * 1e3);
        }
        let (bb, fb) = (&bvhs[0], bvhs.last().expect("built"));
        for (bvh, camera) in [(bb, &views[0]), (bb, &views[1]), (fb, &views[2])] {
            let times: Vec<Duration> = (0..7)
                .map(|_| single_core(|| black_box(primary_packets(bvh, camera, SIZE))).1)
                .collect();
            let rays = (SIZE * SIZE) as f64 / median(times).as_secs_f64();
            row += &format!(" {:.2} |", rays / 1e6);
        }
        println!("{row}");
    }
}

/// A profiling aid: `VOXLOD_BENCH_LOOP=framing|close-up|forest` traces that view with 2×2
/// packets for 20 frames on one thread (run the bench binary under `perf stat`/`perf record`).
fn profile_loop(view: &str) {
    let scene = if view == "forest" { large() } else { bunny() };
    let (_, bvh) = prepare(&scene);
    let camera = if view == "close-up" { close_up(&scene) } else { framing(&scene) };
    let (hits, time) =
        single_core(|| (0..20).map(|_| primary_packets(&bvh, &camera, SIZE)).sum::<u64>());
    let rays = 20.0 * (SIZE * SIZE) as f64;
    println!("{view}: {hits} hits, {:.2} M rays per CPU-second", rays / time.as_secs_f64() / 1e6);
}

fn benches(c: &mut Criterion) {
    if let Some(view) = std::env::var_os("VOXLOD_BENCH_LOOP") {
        profile_loop(&view.to_string_lossy());
        return;
    }
    if std::env::var_os("VOXLOD_BENCH_PRESETS").is_some() {
        preset_table();
        return;
    }
    primary(c);
}

// temporary: compare with obvhs's own traversal
criterion_group!(raycast, benches);
criterion_main!(raycast);
