//! What the Heitz–Neyret payload costs to build and to sample, against Averages, on the sphere
//! shell of `benches/build.rs` (~200 k voxels in a 256³ grid), generated here with each leaf's
//! tangent plane (the closest point of the sphere, its normal) and a colour rising with
//! height.
//!
//! `cargo bench -p voxlod-octree --bench microsurface -- --warm-up-time 1 --measurement-time 3`.
//! Before criterion it prints the payload bytes per node and per occupied voxel of both
//! octrees. Throughput: voxels per second (builds), samples per second (sampling).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec3, UVec3, Vec3};
use voxlod_format::records::MicrosurfaceRecord;
use voxlod_format::{GridSpec, morton};
use voxlod_octree::{AveragePayload, BuildOptions, MicrosurfacePayload, Octree, Payload};

const RES: u32 = 256;
const RADIUS: f32 = 126.0;

fn shell<P>(leaf: impl Fn(Vec3, Vec3) -> P) -> Vec<(u64, P)> {
    let c = Vec3::splat(RES as f32 / 2.0);
    let mut v = Vec::new();
    for z in 0..RES {
        for y in 0..RES {
            for x in 0..RES {
                let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5 - c;
                if (p.length() - RADIUS).abs() <= 0.5 {
                    let n = p.normalize();
                    // The closest point of the sphere, voxel-local.
                    let local = n * RADIUS - (p - 0.5);
                    v.push((morton::encode(UVec3::new(x, y, z)), leaf(local, n)));
                }
            }
        }
    }
    v.sort_unstable_by_key(|e| e.0);
    v
}

fn micro(local: Vec3, n: Vec3) -> MicrosurfacePayload {
    MicrosurfacePayload::from_record(&MicrosurfaceRecord {
        centroid: local.to_array(),
        plane_normal: n.to_array(),
        normal_moments: [n.x * n.x, n.y * n.y, n.z * n.z, n.x * n.y, n.x * n.z, n.y * n.z],
        height_variance: 0.0,
        albedo: (n * 0.5 + 0.5).to_array(),
        albedo_slope: [0.1, -0.1, 0.0],
        specular: 0.0,
        roughness: 0.5,
    })
}

fn grid() -> GridSpec {
    GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(RES)).expect("valid grid")
}

fn bench(c: &mut Criterion) {
    let ms = shell(micro);
    let av = shell(|_, n| AveragePayload::new(n * 0.5 + 0.5, n, 1.0));
    let opts = BuildOptions::default();
    let mtree = Octree::from_morton_sorted(grid(), ms.clone(), &opts).unwrap();
    let atree = Octree::from_morton_sorted(grid(), av.clone(), &opts).unwrap();
    for (name, s, bytes) in [
        ("microsurface", mtree.memory_stats(), size_of::<MicrosurfacePayload>()),
        ("averages", atree.memory_stats(), size_of::<AveragePayload>()),
    ] {
        eprintln!(
            "{name}: {bytes} B per node; per occupied voxel: payloads {:.1} B (sparse levels), \
             dense top levels {:.1} B, total {:.1} B",
            s.per_voxel(s.payload_bytes),
            s.per_voxel(s.dense_bytes),
            s.per_voxel(s.total_bytes())
        );
    }
    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    g.throughput(Throughput::Elements(ms.len() as u64));
    g.bench_function("microsurface", |b| {
        b.iter(|| black_box(Octree::from_morton_sorted(grid(), ms.clone(), &opts).unwrap()))
    });
    g.bench_function("averages", |b| {
        b.iter(|| black_box(Octree::from_morton_sorted(grid(), av.clone(), &opts).unwrap()))
    });
    g.finish();

    // Points near the shell, footprints 1–16 voxels.
    let points: Vec<(Vec3, f32)> = (0..65_536u32)
        .map(|i| {
            let h = |k: u32| {
                ((i.wrapping_mul(2_654_435_761) ^ k.wrapping_mul(40_503)) % 10_000) as f32
                    / 10_000.0
            };
            let dir = Vec3::new(h(1) - 0.5, h(2) - 0.5, h(3) - 0.5).normalize_or(Vec3::X);
            let p = Vec3::splat(RES as f32 / 2.0) + dir * (RADIUS + 4.0 * (h(4) - 0.5));
            (p, 1.0 + 15.0 * h(5))
        })
        .collect();
    let mut g = c.benchmark_group("sample");
    g.throughput(Throughput::Elements(points.len() as u64));
    g.bench_function("microsurface", |b| {
        b.iter(|| points.iter().map(|&(p, d)| mtree.sample(p, d).opacity()).sum::<f32>())
    });
    g.bench_function("averages", |b| {
        b.iter(|| points.iter().map(|&(p, d)| atree.sample(p, d).opacity()).sum::<f32>())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
