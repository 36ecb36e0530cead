//! Differential cone tracing (Heitz–Neyret records, coverage masks) against the alpha-blending
//! primary renderer on Averages: pixels per second on the CPU (rayon), and the elements per
//! pixel each march takes.
//!
//! Scene (generated here: this crate cannot use voxlod-cpu's voxelizer and sampler): a sphere
//! of radius 24 voxels in a 64³ grid, one leaf per voxel within √3/2 of it with its tangent
//! plane (Heitz–Neyret) or its normal, colour and opacity 1 (Averages); a 128² camera whose
//! pixel footprint spans about one voxel at the sphere, a directional light, shadows on.
//!
//! `cargo bench -p voxlod-cone --bench differential -- --warm-up-time 1 --measurement-time 3`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec3, UVec3, Vec3};
use voxlod_cone::{
    Compositing, DifferentialOptions, DifferentialRenderer, Light, PinholeCamera, PrimaryOptions,
    PrimaryRenderer, ShadeInput, SurfaceShadeInput,
};
use voxlod_format::GridSpec;
use voxlod_format::records::MicrosurfaceRecord;
use voxlod_octree::{AveragePayload, BuildOptions, MicrosurfacePayload, Octree};

const N: u32 = 64;
const R: f32 = 24.0;

fn leaves<P>(leaf: impl Fn(Vec3, Vec3) -> P) -> Vec<(UVec3, P)> {
    let c = Vec3::splat(N as f32 / 2.0);
    let mut v = Vec::new();
    for z in 0..N {
        for y in 0..N {
            for x in 0..N {
                let q = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
                let p = q - c;
                if (p.length() - R).abs() <= 0.87 {
                    let n = p.normalize();
                    v.push((UVec3::new(x, y, z), leaf(c + n * R - (q - 0.5), n)));
                }
            }
        }
    }
    v
}

fn bench(c: &mut Criterion) {
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(N)).unwrap();
    let opts = BuildOptions::default();
    let micro = Octree::build(
        grid,
        leaves(|local, n| {
            MicrosurfacePayload::from_record(&MicrosurfaceRecord {
                centroid: local.to_array(),
                plane_normal: n.to_array(),
                normal_moments: [n.x * n.x, n.y * n.y, n.z * n.z, n.x * n.y, n.x * n.z, n.y * n.z],
                height_variance: 0.0,
                albedo: [0.6, 0.5, 0.4],
                albedo_slope: [0.0; 3],
                specular: 0.0,
                roughness: 0.5,
            })
        }),
        &opts,
    )
    .unwrap();
    let averages = Octree::build(
        grid,
        leaves(|_, n| AveragePayload::new(Vec3::new(0.6, 0.5, 0.4), n, 1.0)),
        &opts,
    )
    .unwrap();
    let camera = PinholeCamera {
        eye: Vec3::new(32.0, 40.0, -60.0),
        target: Vec3::splat(32.0),
        up: Vec3::Y,
        fov_y_deg: 45.0,
        width: 128,
        height: 128,
    };
    let light = Light::Directional { to_light: Vec3::new(0.4, 1.0, -0.3), irradiance: Vec3::ONE };
    let pixels = (camera.width * camera.height) as u64;
    let mut g = c.benchmark_group("primary_128x128");
    g.sample_size(10);
    g.throughput(Throughput::Elements(pixels));
    for (name, compositing) in
        [("masks", Compositing::CoverageMasks), ("blending", Compositing::AlphaBlending)]
    {
        let o = DifferentialOptions { compositing, ..Default::default() };
        let r = DifferentialRenderer::new(&micro, camera, light, o).unwrap();
        let shade = |s: &SurfaceShadeInput| s.illumination.albedo * s.visibility;
        let img = r.render(&shade);
        eprintln!(
            "heitz-neyret {name}: {:.1} elements/px, {:.2} shaded/px, {:.1} shadow elements/px",
            img.elements as f64 / pixels as f64,
            img.shaded as f64 / pixels as f64,
            img.shadow_elements as f64 / pixels as f64
        );
        g.bench_function(format!("heitz_neyret_{name}"), |b| b.iter(|| r.render(&shade)));
    }
    let r = PrimaryRenderer::new(&averages, camera, light, PrimaryOptions::default()).unwrap();
    let shade = |s: &ShadeInput| s.albedo * s.visibility;
    let img = r.render(&shade);
    eprintln!(
        "averages, alpha blending: {:.1} samples/px, {:.1} shadow samples/px",
        img.samples as f64 / pixels as f64,
        img.shadow_samples as f64 / pixels as f64
    );
    g.bench_function("averages_alpha_blending", |b| b.iter(|| r.render(&shade)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
