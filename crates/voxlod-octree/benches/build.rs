//! Octree build time and sampling rate on a synthetic sphere shell (~200 k voxels in a 256³
//! grid: voxel centres within half a voxel of a sphere of radius 126), generated here because
//! this crate cannot use the voxelizers of voxlod-cpu.
//!
//! `cargo bench -p voxlod-octree --bench build -- --warm-up-time 1 --measurement-time 3`.
//! Before the criterion runs it prints the memory breakdown per occupied voxel and the mean
//! wall and CPU time of each build (CPU of the build call only, all threads; the input clone
//! and the drop of the result are outside). Throughput is in voxels per second for builds,
//! samples per second for sampling. Each build includes the ones above it:
//! - `build/topology`: [`Topology`] alone, the occupied levels and their child structure (an
//!   SVO without payloads, closure or links), whose throughput target is 20 M voxels/s on 2
//!   cores;
//! - `build/links`: the octree with an opacity-only payload (4 bytes, trivial prefilter): the
//!   topology, the closure nodes and tiles, the dense top levels and the neighbour links;
//! - `build/averages`, `build/averages+directional`: the same with Averages pre-filtering (28
//!   bytes), and with six directional opacities on top;
//! - `sample/*`: quadrilinear samples at random points near the shell, footprints 1–16 voxels,
//!   in random order and in Morton order (coherent, as the steps of neighbouring cones are), and
//!   trilinear samples at level 0.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec3, UVec3, Vec3};
use voxlod_format::{GridSpec, morton};
use voxlod_octree::{AveragePayload, BuildOptions, Directional, Octree, Payload, Topology};

const RES: u32 = 256;
const RADIUS: f32 = 126.0;

/// Opacity only: what the build costs without a real payload.
#[derive(Clone, Copy, Debug, Default)]
struct Opacity(f32);

impl Payload for Opacity {
    fn empty() -> Self {
        Self(0.0)
    }
    fn prefilter(c: &[Self; 8]) -> Self {
        Self(c.iter().map(|x| x.0).sum::<f32>() * 0.125)
    }
    fn add_scaled(&mut self, o: &Self, w: f32) {
        self.0 += w * o.0;
    }
    fn opacity(&self) -> f32 {
        self.0
    }
    fn check(&self) -> Option<&'static str> {
        (!(0.0..=1.0).contains(&self.0)).then_some("opacity outside [0, 1]")
    }
    fn max_abs_diff(&self, o: &Self) -> f32 {
        (self.0 - o.0).abs()
    }
}

/// Voxels of the shell, Morton-sorted, with radial normals and a colour by position.
fn shell() -> Vec<(u64, AveragePayload)> {
    let c = Vec3::splat(RES as f32 / 2.0);
    let mut v = Vec::new();
    for z in 0..RES {
        for y in 0..RES {
            for x in 0..RES {
                let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5 - c;
                if (p.length() - RADIUS).abs() <= 0.5 {
                    let colour = (p / RADIUS) * 0.5 + 0.5;
                    let payload = AveragePayload::new(colour, p, 0.8);
                    v.push((morton::encode(UVec3::new(x, y, z)), payload));
                }
            }
        }
    }
    v.sort_unstable_by_key(|e| e.0);
    v
}

fn grid() -> GridSpec {
    GridSpec::new(DVec3::ZERO, 1.0 / RES as f64, UVec3::splat(RES)).expect("valid grid")
}

fn report(tree: &Octree<AveragePayload>, topology: &Topology) {
    let s = tree.memory_stats();
    let pv = |b| s.per_voxel(b);
    eprintln!(
        "sphere shell: {} voxels in {RES}³, depth {}, dense down to level {} ({}³)",
        s.occupied_voxels,
        tree.depth(),
        tree.first_dense(),
        1 << (tree.depth() - tree.first_dense())
    );
    for l in &s.levels {
        eprintln!(
            "  level {:2} ({:3}³ {}): {:9} nodes, {:8} occupied",
            l.level,
            l.resolution,
            if l.dense { "dense " } else { "sparse" },
            l.nodes,
            l.occupied
        );
    }
    eprintln!(
        "  bytes per occupied voxel: topology {:.2}, neighbour links {:.2}, payloads {:.2}, \
         dense top levels {:.2}; total {:.2} ({:.1} MB)",
        pv(s.topology_bytes),
        pv(s.link_bytes),
        pv(s.payload_bytes),
        pv(s.dense_bytes),
        pv(s.total_bytes()),
        s.total_bytes() as f64 / 1e6
    );
    eprintln!(
        "  topology alone (occupied levels: codes, masks, first-child indices): {:.2} B/voxel",
        s.per_voxel(topology.memory_bytes())
    );
}

/// CPU time of this process so far (all threads), from `/proc/self/task/*/schedstat` (ns on
/// CPU); `None` off Linux. Wall-clock figures on a loaded shared machine measure the load, CPU
/// time the work.
fn cpu_ns() -> Option<u64> {
    let mut total = 0;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let s = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        total += s.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total)
}

/// User and kernel CPU time of this process so far, in seconds, from `/proc/self/stat`
/// (clock ticks, 10 ms); `None` off Linux.
fn user_sys() -> Option<(f64, f64)> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let f: Vec<&str> = s.rsplit_once(')')?.1.split_whitespace().collect();
    Some((f.get(11)?.parse::<f64>().ok()? / 100.0, f.get(12)?.parse::<f64>().ok()? / 100.0))
}

/// Mean wall and CPU time of `runs` calls of `run` on inputs made by `setup` (not timed), the
/// result dropped outside the timed span; printed with the throughput.
fn time_cpu<I, T>(
    what: &str,
    n: u64,
    runs: u32,
    mut setup: impl FnMut() -> I,
    mut run: impl FnMut(I) -> T,
) {
    drop(black_box(run(setup())));
    let (mut wall, mut cpu, mut user, mut sys) = (0.0, Some(0.0), 0.0, 0.0);
    for _ in 0..runs {
        let input = setup();
        let (c0, us0, t0) = (cpu_ns(), user_sys(), std::time::Instant::now());
        let out = black_box(run(input));
        let (t1, c1, us1) = (t0.elapsed().as_secs_f64(), cpu_ns(), user_sys());
        drop(out);
        wall += t1;
        cpu = cpu.zip(c1.zip(c0)).map(|(sum, (c1, c0))| sum + (c1 - c0) as f64 * 1e-9);
        if let (Some((u1, s1)), Some((u0, s0))) = (us1, us0) {
            user += u1 - u0;
            sys += s1 - s0;
        }
    }
    let r = runs as f64;
    let (wall, cpu) = (wall / r, cpu.map(|c| c / r));
    let threads = rayon::current_num_threads();
    match cpu {
        Some(cpu) => eprintln!(
            "  {what}: wall {:.2} ms ({:.2} M/s), CPU {:.2} ms ({:.2} M per CPU-second; {threads} threads; user {:.1} ms, kernel {:.1} ms)",
            wall * 1e3,
            n as f64 / wall / 1e6,
            cpu * 1e3,
            n as f64 / cpu / 1e6,
            user * 1e3 / r,
            sys * 1e3 / r
        ),
        None => eprintln!("  {what}: wall {:.2} ms ({:.2} M/s)", wall * 1e3, n as f64 / wall / 1e6),
    }
}

fn bench(c: &mut Criterion) {
    let voxels = shell();
    let n = voxels.len() as u64;
    let options = BuildOptions::default();
    let tree = Octree::from_morton_sorted(grid(), voxels.clone(), &options).expect("built");
    let codes: Vec<u64> = voxels.iter().map(|v| v.0).collect();
    let topology = Topology::from_morton_sorted(grid(), codes.clone(), &options).expect("built");
    report(&tree, &topology);
    drop(topology);

    let opacity: Vec<(u64, Opacity)> =
        voxels.iter().map(|&(k, p)| (k, Opacity(p.opacity))).collect();
    let directional: Vec<(u64, Directional<AveragePayload>)> =
        voxels.iter().map(|&(k, p)| (k, Directional::isotropic(p))).collect();
    eprintln!("build, mean of 40, 20, 10, 10 runs (CPU: the build call only):");
    let topo = |v| Topology::from_morton_sorted(grid(), v, &options).expect("built");
    time_cpu("(a) topology", n, 40, || codes.clone(), topo);
    let links = |v| Octree::from_morton_sorted(grid(), v, &options).expect("built");
    time_cpu("(b) + closure, tiles, links (opacity payload)", n, 20, || opacity.clone(), links);
    let averages = |v| Octree::from_morton_sorted(grid(), v, &options).expect("built");
    time_cpu("(c) + Averages prefilter", n, 10, || voxels.clone(), averages);
    let directional_build = |v| Octree::from_morton_sorted(grid(), v, &options).expect("built");
    time_cpu("(d) + directional opacities", n, 10, || directional.clone(), directional_build);

    let mut g = c.benchmark_group("build");
    g.throughput(Throughput::Elements(n));
    g.sample_size(10);
    g.bench_function("topology", |b| b.iter_batched(|| codes.clone(), topo, BatchSize::LargeInput));
    g.bench_function("links", |b| b.iter_batched(|| opacity.clone(), links, BatchSize::LargeInput));
    g.bench_function("averages", |b| {
        b.iter_batched(|| voxels.clone(), averages, BatchSize::LargeInput)
    });
    g.bench_function("averages+directional", |b| {
        b.iter_batched(|| directional.clone(), directional_build, BatchSize::LargeInput)
    });
    g.finish();

    // Points within 4 voxels of the shell, deterministic.
    let points: Vec<(Vec3, f32)> = (0..65_536u32)
        .map(|i| {
            let h = |k: u32| {
                ((i.wrapping_mul(0x9e37_79b9) ^ k.wrapping_mul(0x85eb_ca6b))
                    .wrapping_mul(0xc2b2_ae35)
                    >> 8) as f32
                    / (1 << 24) as f32
            };
            let dir = Vec3::new(h(1) - 0.5, h(2) - 0.5, h(3) - 0.5).normalize_or(Vec3::X);
            let r = RADIUS + (h(4) - 0.5) * 8.0;
            (Vec3::splat(RES as f32 / 2.0) + dir * r, 1.0 + 15.0 * h(5))
        })
        .collect();
    let mut g = c.benchmark_group("sample");
    g.throughput(Throughput::Elements(points.len() as u64));
    g.bench_function("quadrilinear", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(p, d) in &points {
                acc += tree.sample(black_box(p), d).opacity;
            }
            acc
        })
    });
    // The same points in Morton order of their voxel: neighbouring samples share nodes, as the
    // steps of one cone and neighbouring pixels' cones do.
    let mut coherent = points.clone();
    coherent.sort_by_key(|(p, _)| morton::encode(p.max(Vec3::ZERO).as_uvec3()));
    g.bench_function("quadrilinear_coherent", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(p, d) in &coherent {
                acc += tree.sample(black_box(p), d).opacity;
            }
            acc
        })
    });
    g.bench_function("trilinear_level0", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(p, _) in &points {
                acc += tree.sample_level(black_box(p), 0).opacity;
            }
            acc
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
