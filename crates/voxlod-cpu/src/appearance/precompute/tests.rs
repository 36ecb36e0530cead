//! Tests of the precompute driver, with the Averages fit and the subgrid build.

use glam::{DVec3, UVec3, Vec3};
use proptest::prelude::*;
use voxlod_format::GridSpec;
use voxlod_scene::{Geometry, Material, Scene};

use super::*;
use crate::appearance::subgrid::{self, DirectionalRule, directional_opacity};
use crate::appearance::{Appearance, Opacity, averages};
use crate::render::test_scenes::{icosphere, quad, scene, sun};
use crate::voxelize::{self, Voxelization, voxelize};

fn prepare(scene: &Scene, res: u32) -> (Geometry, Voxelization) {
    let g = scene.geometry();
    let grid = GridSpec::new(DVec3::ZERO, 4.0 / res as f64, UVec3::splat(res)).unwrap();
    let v = voxelize(&g, &grid, &voxelize::Options::default()).unwrap();
    (g, v)
}

/// A sphere of radius 1.5 in the 4-unit grid, `material`.
fn ball(material: Material) -> Scene {
    scene(vec![icosphere("ball", 3, Vec3::splat(2.0), 1.5)], vec![material], sun(Vec3::Y, 1.0))
}

/// A plane through the 4³ grid's voxel (1, 1, 1) perpendicular to `axis` at local offset
/// `h`, made of two triangles reaching 10⁴ voxels out, front face toward `+axis` or `−axis`.
fn plane(axis: usize, h: f32, flip: bool, double_sided: bool) -> Scene {
    let (a, b) = (Vec3::AXES[(axis + 1) % 3] * 2e4, Vec3::AXES[(axis + 2) % 3] * 2e4);
    let mut corner = Vec3::splat(2.0) - (a + b) / 2.0;
    corner[axis] = 1.0 + h;
    let mesh = if flip { quad("p", corner, b, a, 0) } else { quad("p", corner, a, b, 0) };
    let m = Material { double_sided, ..Material::diffuse("grey", Vec3::splat(0.5)) };
    scene(vec![mesh], vec![m], sun(Vec3::Y, 1.0))
}

proptest! {
    /// A voxel crossed by a plane (two big triangles): Averages is ≥ 0.99 opaque from every
    /// direction; the subgrid is ≥ 0.99 opaque face-on and at least 0.2 from any direction, and
    /// its sub-cells away from the plane (an empty sub-volume) are exactly 0. Seen edge-on, no
    /// rule over a 3×3×3 subgrid can make the plane's layer more than its third of the
    /// footprint (design note §6): over 20 000 directions the one-layer subgrid measures at
    /// least 0.25 with Lines (32 lines resolve 1/32) and 0.42 with Circles.
    #[test]
    fn a_voxel_crossed_by_a_plane_is_opaque(
        axis in 0usize..3,
        h in 0.02f32..0.98,
        flip in any::<bool>(),
        double_sided in any::<bool>(),
        x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0,
    ) {
        let sc = plane(axis, h, flip, double_sided);
        let (g, v) = prepare(&sc, 4);
        let ctx = SamplingContext::new(&sc, &g, &v).unwrap();
        let opts = PrecomputeOptions { rays: 600, seed: 3 };
        let avg = precompute(&ctx, &opts, averages::fit).unwrap();
        let sub = precompute(&ctx, &opts, |s| Some(subgrid::build(s))).unwrap();
        let dir = Vec3::new(x, y, z).try_normalize().unwrap_or(Vec3::X);
        let i = avg.index_of(UVec3::ONE).expect("the crossed voxel has a record");
        let Opacity::Alpha(a) = avg.opacity(i, dir) else { panic!("Averages opacity is alpha") };
        prop_assert!(a >= 0.99, "Averages: {a}");
        let alpha = sub.records.get(UVec3::ONE).unwrap();
        let layer = (3.0 * h).floor() as usize;
        for (c, &a) in alpha.iter().enumerate() {
            let along = [c % 3, c / 3 % 3, c / 9][axis];
            if along != layer {
                prop_assert_eq!(a, 0, "cell {} away from the plane", c);
            }
        }
        for rule in [DirectionalRule::Lines, DirectionalRule::Circles] {
            for d in [Vec3::AXES[axis], -Vec3::AXES[axis]] {
                let o = directional_opacity(alpha, d, rule);
                prop_assert!(o >= 0.99, "{:?} face-on: {} ({:?})", rule, o, alpha);
            }
            let o = directional_opacity(alpha, dir, rule);
            prop_assert!(o >= 0.2, "{:?} along {}: {}", rule, dir, o);
        }
    }
}

/// The virtual mesh with projected-area scaling makes a voxel crossed by a plane nearly
/// transparent edge-on (≤ 0.05 over 64 directions in the plane) and keeps it ≥ 0.99 face-on;
/// without it the edge-on floor is the subgrid's third. A record whose normals cover every
/// direction (an isotropic SGGX) keeps ≥ 0.99 of its subgrid opacity from every direction.
#[test]
fn projected_area_makes_a_plane_transparent_edge_on() {
    use crate::appearance::virtual_mesh::{self, VirtualMeshGrid, projected_area_ratio};
    for axis in 0..3 {
        let sc = plane(axis, 0.45, false, false);
        let (g, v) = prepare(&sc, 4);
        let ctx = SamplingContext::new(&sc, &g, &v).unwrap();
        let opts = PrecomputeOptions { rays: 600, seed: 3 };
        let grid = precompute(&ctx, &opts, virtual_mesh::fit).unwrap();
        let plain = VirtualMeshGrid::new(grid.clone());
        let scaled = VirtualMeshGrid { projected_area: true, ..VirtualMeshGrid::new(grid) };
        let i = scaled.index_of(UVec3::ONE).expect("the crossed voxel has a record");
        let alpha = |app: &VirtualMeshGrid, d: Vec3| match app.opacity(i, d) {
            Opacity::Alpha(a) => a,
            other => panic!("virtual-mesh opacity is alpha, not {other:?}"),
        };
        for d in [Vec3::AXES[axis], -Vec3::AXES[axis]] {
            assert!(alpha(&scaled, d) >= 0.99, "axis {axis}, face-on {d}: {}", alpha(&scaled, d));
        }
        let (u, w) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
        for k in 0..64 {
            let (s, c) = (std::f32::consts::TAU * k as f32 / 64.0).sin_cos();
            let d = u * c + w * s;
            assert!(alpha(&scaled, d) <= 0.05, "axis {axis}, edge-on {d}: {}", alpha(&scaled, d));
            assert!(alpha(&plain, d) >= 0.2, "axis {axis}, edge-on {d}: {}", alpha(&plain, d));
        }
    }
    // Normals spread over every direction: an isotropic SGGX, ratio 1 everywhere (to the
    // byte quantization of the semi-axes).
    let semi = voxlod_format::records::SCALE_RANGE.encode(0.56);
    let rec = voxlod_format::records::VirtualMeshRecord {
        axes: [[127, 0, 0], [0, 127, 0], [0, 0, 127]],
        scales: [semi; 3],
        ..Default::default()
    };
    for k in 0..200u32 {
        let z = 1.0 - 2.0 * (k as f32 + 0.5) / 200.0;
        let phi = k as f32 * 2.399_963;
        let d = Vec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
        let r = projected_area_ratio(&rec, d);
        assert!((0.99..=1.0).contains(&r), "{d}: {r}");
    }
}

/// Records exist exactly for the voxels whose samples have a front hit, in the voxelization's
/// Morton order; the brick map is valid.
#[test]
fn records_follow_the_voxelization_and_skip_voxels_without_front_hits() {
    let sc = ball(Material::diffuse("grey", Vec3::splat(0.5)));
    let (g, v) = prepare(&sc, 12);
    let ctx = SamplingContext::new(&sc, &g, &v).unwrap();
    let opts = PrecomputeOptions { rays: 40, seed: 0 };
    let grid = precompute(&ctx, &opts, averages::fit).unwrap();
    grid.records.validate().unwrap();
    assert!(grid.specular.is_none());
    let mut buf = VoxelSamples::default();
    let mut expected = Vec::new();
    for i in 0..ctx.voxel_count() {
        ctx.sample_voxel(i, 0, 40, &mut buf);
        if let Some(r) = averages::fit(&buf) {
            expected.push((ctx.coord(i), r));
        }
    }
    assert!(expected.len() < ctx.voxel_count(), "some voxels have no front hit");
    assert!(expected.len() > ctx.voxel_count() / 2);
    let got: Vec<_> = grid.records.iter().map(|(c, r)| (c, *r)).collect();
    assert_eq!(got, expected);
    assert_eq!(grid.len(), expected.len());
}

/// The same seed gives bit-identical records with any thread count; another seed differs.
#[test]
fn same_seed_gives_bit_identical_records() {
    let sc = ball(Material::diffuse("grey", Vec3::splat(0.5)));
    let (g, v) = prepare(&sc, 10);
    let ctx = SamplingContext::new(&sc, &g, &v).unwrap();
    let opts = PrecomputeOptions { rays: 30, seed: 9 };
    let run = |threads: usize, opts: PrecomputeOptions| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| precompute(&ctx, &opts, averages::fit).unwrap())
    };
    let (a, b) = (run(1, opts), run(3, opts));
    assert_eq!(a.records.values(), b.records.values());
    assert_eq!(a.records.bricks(), b.records.bricks());
    let sub = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| precompute(&ctx, &opts, |s| Some(subgrid::build(s))).unwrap())
    };
    assert_eq!(sub(1).records.values(), sub(2).records.values());
    let other = run(2, PrecomputeOptions { seed: 10, ..opts });
    assert_ne!(a.records.values(), other.records.values());
}

/// Specular side records appear only for scenes with a specular material, one per record:
/// the mean level and the level-weighted exponent.
#[test]
fn specular_side_records_only_for_specular_scenes() {
    let shiny = Material {
        specular: Vec3::new(0.3, 0.3, 0.6),
        shininess: 32.0,
        ..Material::diffuse("shiny", Vec3::splat(0.5))
    };
    let sc = ball(shiny);
    let (g, v) = prepare(&sc, 8);
    let ctx = SamplingContext::new(&sc, &g, &v).unwrap();
    assert!(ctx.has_specular());
    let grid = precompute(&ctx, &PrecomputeOptions { rays: 30, seed: 0 }, averages::fit).unwrap();
    let side = grid.specular.as_ref().expect("a specular scene gets side records");
    assert_eq!(side.len(), grid.len());
    for s in side {
        assert_eq!(*s, SpecularRecord::new(0.4, 32.0));
    }
    // Mixed hits: the level is the mean, the exponent ignores the diffuse hits.
    let mut samples = VoxelSamples::default();
    ctx.sample_voxel(0, 0, 1, &mut samples);
    let mut ray = samples.rays[0];
    let surface = |specular, shininess| crate::appearance::voxel_samples::SurfaceSample {
        point: Vec3::splat(0.5),
        normal: Vec3::Z,
        albedo: Vec3::ONE,
        specular,
        shininess,
    };
    ray.surface = Some(surface(0.6, 64.0));
    let mut diffuse = ray;
    diffuse.surface = Some(surface(0.0, 0.0));
    let mixed = VoxelSamples { rays: vec![ray, diffuse] };
    assert_eq!(specular_record(&mixed), SpecularRecord::new(0.3, 64.0));
    assert_eq!(specular_record(&VoxelSamples::default()), SpecularRecord::new(0.0, 0.0));
}

#[test]
fn zero_rays_is_an_error() {
    let sc = ball(Material::diffuse("grey", Vec3::splat(0.5)));
    let (g, v) = prepare(&sc, 4);
    let ctx = SamplingContext::new(&sc, &g, &v).unwrap();
    let opts = PrecomputeOptions { rays: 0, seed: 0 };
    assert!(precompute(&ctx, &opts, averages::fit).is_err());
    assert_eq!(PrecomputeOptions::default(), PrecomputeOptions { rays: 150, seed: 0 });
}
