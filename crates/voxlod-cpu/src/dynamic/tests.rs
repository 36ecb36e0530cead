//! Dynamic scenes: splitting, object spaces, caches (records and skin weights), and the
//! transformed frame against re-voxelization on a rotating cube and glTF's `simple_skin`.

use std::collections::HashSet;
use std::path::Path;

use glam::{DVec3, Mat4, Quat, UVec3, Vec2, Vec3};
use voxlod_format::GridSpec;
use voxlod_octree::dynamic::{DynamicWorld, Filter, FrameOptions};
use voxlod_scene::animation::{AnimatedProperty, Channel, Interpolation, Transform};
use voxlod_scene::mesh::SkinBinding;
use voxlod_scene::procedural::primitives::cube;
use voxlod_scene::{Animation, Material, Node, Scene, Skin};

use super::*;
use crate::voxelize::Mode;

/// A 1.2³ cube on node 0 (at (4.03, 3.02, 4.01), its faces off the voxel boundaries), turning about y by 90° over one second, above a
/// static floor; 8³-ish world of 0.1 voxels.
fn spinning_cube() -> Scene {
    let t = Transform { translation: Vec3::new(4.03, 3.02, 4.01), ..Default::default() };
    let node = Node {
        name: "spinner".into(),
        parent: None,
        local: t.matrix(),
        world: t.matrix(),
        trs: Some(t),
    };
    let mut body = cube(Vec3::splat(-0.6), Vec3::splat(0.6));
    for p in &mut body.positions {
        *p += t.translation;
    }
    body.node = Some(0);
    body.material = 0;
    let mut floor = voxlod_scene::procedural::primitives::quad(
        Vec3::new(1.0, 1.0, 7.0),
        Vec3::new(6.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -6.0),
        false,
    );
    floor.material = 1;
    let q = |deg: f32| Quat::from_rotation_y(deg.to_radians()).to_array();
    let anim = Animation {
        name: "spin".into(),
        channels: vec![Channel {
            node: 0,
            property: AnimatedProperty::Rotation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: [q(0.0), q(90.0)].concat(),
        }],
    };
    Scene {
        name: "spin".into(),
        meshes: vec![body, floor],
        materials: vec![
            Material::diffuse("red", Vec3::new(0.8, 0.2, 0.1)),
            Material::diffuse("grey", Vec3::splat(0.5)),
        ],
        nodes: vec![node],
        animations: vec![anim],
        ..Default::default()
    }
}

fn world_grid() -> GridSpec {
    GridSpec::new(DVec3::ZERO, 0.1, UVec3::splat(80)).unwrap()
}

fn occupancy_of(codes: impl Iterator<Item = UVec3>) -> HashSet<UVec3> {
    codes.collect()
}

/// (intersection, union, missing, extra) of transformed against re-voxelized occupancy.
fn compare(a: &HashSet<UVec3>, reference: &HashSet<UVec3>) -> (usize, usize, usize, usize) {
    let inter = a.intersection(reference).count();
    (inter, a.union(reference).count(), reference.len() - inter, a.len() - inter)
}

#[test]
fn a_rotating_cube_splits_into_a_rigid_object_and_a_static_floor() {
    let ds = DynamicScene::new(spinning_cube(), 0).unwrap();
    assert_eq!(ds.statics, vec![1]);
    assert_eq!(ds.objects.len(), 1);
    assert_eq!(ds.objects[0].kind, ObjectKind::Rigid { node: 0 });
    let (g, scale) = ds.object_geometry(&ds.objects[0]).unwrap();
    assert!((scale - 1.0).abs() < 1e-9);
    let (lo, hi) = g.bounds().unwrap();
    assert!((lo - Vec3::splat(-0.6)).length() < 1e-5 && (hi - Vec3::splat(0.6)).length() < 1e-5);
    // Posed at t = 0.5 (45°): a corner of the cube at radius 0.6·√2 in x.
    let pose = ds.pose(0.5).unwrap();
    let posed = ds.posed_scene(&pose).unwrap();
    let (plo, phi) = posed.meshes[0]
        .positions
        .iter()
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    assert!(((phi.x - plo.x) / 2.0 - 0.6 * 2f32.sqrt()).abs() < 1e-4, "{plo} {phi}");
    assert_eq!(posed.meshes[1], ds.scene.meshes[1], "the floor does not move");
    // Looping: t = 1.25 is t = 0.25.
    assert_eq!(ds.pose(1.25).unwrap(), ds.pose(0.25).unwrap());
}

/// Against the thin (6-separating) re-voxelization, as the paper compares: at 0° both filters
/// agree closely; at 45° about y nearest sampling misses voxels (holes) that 8-neighbour keeps.
#[test]
fn the_transformed_cube_agrees_with_re_voxelization_and_nearest_has_holes_at_45_degrees() {
    let ds = DynamicScene::new(spinning_cube(), 0).unwrap();
    let grid = world_grid();
    let options = CacheOptions { mode: Mode::Thin, records: RecordSource::Pieces };
    let cache = build_cache(&ds, 0, grid.voxel_size, &options).unwrap();
    assert!(cache.len() > 500, "{}", cache.len());
    let world = DynamicWorld::new(grid, []).unwrap();
    let mut results = Vec::new();
    for time in [0.0f32, 0.5] {
        let pose = ds.pose(time).unwrap();
        let placements = ds.placements(&pose).unwrap();
        let posed = ds.posed_scene(&pose).unwrap();
        let geometry = geometry_of(&posed, &[0]);
        let reference =
            revoxelize(&posed, &geometry, &grid, Mode::Thin, RecordSource::Pieces).unwrap();
        let reference = occupancy_of(reference.records.coords());
        for filter in [Filter::Nearest, Filter::EightNeighbour] {
            let opts = FrameOptions { filter, ..FrameOptions::default() };
            let (leaves, stats) = world.leaves(&[(&cache, &placements[0])], &opts).unwrap();
            assert_eq!(stats.blend.clipped_contributions, 0);
            let ours = occupancy_of(leaves.iter().map(|l| voxlod_format::morton::decode(l.0)));
            let (inter, union, miss, _) = compare(&ours, &reference);
            results.push((inter as f64 / union as f64, miss));
        }
    }
    // [0° nearest, 0° 8-neighbour, 45° nearest, 45° 8-neighbour]
    assert!(results[0].0 > 0.9 && results[1].0 > 0.9, "{results:?}");
    assert!(results[3].0 > results[2].0, "{results:?}");
    assert!(results[2].1 > 20 && results[3].1 * 4 <= results[2].1, "{results:?}");
}

#[test]
fn fragment_records_average_the_pieces() {
    let ds = DynamicScene::new(spinning_cube(), 0).unwrap();
    let g = ds.static_geometry();
    let grid = world_grid();
    let vox = crate::voxelize::voxelize(&g, &grid, &Default::default()).unwrap();
    let records = fragment_records(&ds.scene, &g, &vox).unwrap();
    assert_eq!(records.len(), vox.voxels.len());
    for r in records.values() {
        assert!((r.color() - Vec3::splat(0.5)).abs().max_element() < 0.01);
        assert!((r.normal() - Vec3::Y).length() < 0.02);
        assert_eq!(r.opacity, 255);
    }
}

/// A strip along x with joint 0 at x = 0 and joint 1 at x = 4 (weights linear in x): a voxel's
/// weight is the area-weighted value at its pieces' centroids.
#[test]
fn skin_weights_are_interpolated_at_the_pieces_centroids() {
    let positions = vec![Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(4.0, 1.0, 0.0), Vec3::Y];
    let geometry = voxlod_scene::Geometry {
        positions: positions.clone(),
        normals: vec![Vec3::Z; 4],
        uvs: vec![Vec2::ZERO; 4],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![0, 0],
    };
    let influences: Vec<([u16; 4], [f32; 4])> =
        positions.iter().map(|p| ([0, 1, 0, 0], [1.0 - p.x / 4.0, p.x / 4.0, 0.0, 0.0])).collect();
    let grid = GridSpec::new(DVec3::new(0.0, 0.0, -0.5), 1.0, UVec3::new(4, 1, 1)).unwrap();
    let vox = crate::voxelize::voxelize(&geometry, &grid, &Default::default()).unwrap();
    let coords: Vec<UVec3> = (0..4).map(|x| UVec3::new(x, 0, 0)).collect();
    let skins = voxel_skins(&geometry, &influences, &vox, &coords).unwrap();
    for (x, s) in skins.iter().enumerate() {
        let w1 = (0..4)
            .filter(|&k| s.joints[k] == 1 && s.weights[k] > 0)
            .map(|k| s.weight(k))
            .sum::<f32>();
        let expected = (x as f32 + 0.5) / 4.0;
        assert!((w1 - expected).abs() <= 1.0 / 255.0, "voxel {x}: {w1} vs {expected}");
        assert!(s.is_normalized());
    }
}

#[test]
fn bad_rigs_are_refused_with_the_object_named() {
    // A non-uniform rest scale on the moving node.
    let mut s = spinning_cube();
    let t = Transform { scale: Vec3::new(1.0, 2.0, 1.0), ..s.nodes[0].trs.unwrap() };
    s.nodes[0].trs = Some(t);
    s.nodes[0].local = t.matrix();
    s.nodes[0].world = t.matrix();
    let ds = DynamicScene::new(s, 0).unwrap();
    let e = build_cache(&ds, 0, 0.1, &CacheOptions::default()).unwrap_err().to_string();
    assert!(e.contains("spinner") && e.contains("non-uniformly"), "{e}");
    // A skinned vertex whose weights sum to zero: the scene does not validate.
    let mut s = spinning_cube();
    let n = s.meshes[0].positions.len();
    s.meshes[0].skin = Some(SkinBinding {
        skin: 0,
        joints: vec![[0; 4]; n],
        weights: vec![[0.0; 4]; n],
        bind_positions: s.meshes[0].positions.clone(),
        bind_normals: s.meshes[0].normals.clone(),
    });
    s.skins = vec![Skin {
        name: "rig".into(),
        joints: vec![0],
        inverse_bind_matrices: vec![Mat4::IDENTITY],
    }];
    let e = DynamicScene::new(s, 0).unwrap_err().to_string();
    assert!(e.contains("skin weights of vertex 0"), "{e}");
    // A morph-weights channel.
    let mut s = spinning_cube();
    s.animations[0].channels[0].property = AnimatedProperty::MorphWeights;
    s.animations[0].channels[0].values = vec![0.0, 1.0];
    let e = DynamicScene::new(s, 0).unwrap_err().to_string();
    assert!(e.contains("morph"), "{e}");
    // An object larger than a cache holds at this voxel size.
    let ds = DynamicScene::new(spinning_cube(), 0).unwrap();
    let e = build_cache(&ds, 0, 0.001, &CacheOptions::default()).unwrap_err().to_string();
    assert!(e.contains("1024"), "{e}");
}

/// glTF `simple_skin`: the bottom of the strip follows joint 0, the top joint 1; at t = 1 the
/// transformed strip overlaps its re-voxelization.
#[test]
fn simple_skin_caches_and_moves_with_its_joints() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/gltf/good/simple_skin/simple_skin.gltf");
    let scene = Scene::load(&path).unwrap();
    let ds = DynamicScene::new(scene, 0).unwrap();
    assert_eq!(ds.objects.len(), 1);
    assert!(matches!(ds.objects[0].kind, ObjectKind::Skinned { skin: 0 }));
    let grid = GridSpec::new(DVec3::new(-2.5, -1.0, -1.0), 0.05, UVec3::splat(80)).unwrap();
    let options = CacheOptions { mode: Mode::Conservative, records: RecordSource::Pieces };
    let cache = build_cache(&ds, 0, grid.voxel_size, &options).unwrap();
    let skins = &cache.skin.as_ref().unwrap().voxels;
    for (v, s) in skins.iter().enumerate() {
        let y = voxlod_octree::dynamic::unpack_position(cache.positions[v]).y as f64 * 0.05
            + 0.025
            + cache.grid.origin.y;
        let w1: f32 = (0..4).filter(|&k| s.joints[k] == 1).map(|k| s.weight(k)).sum();
        // Vertex weights: joint 1 gets y/2, from 0 at y = 0 to 1 at y = 2.
        let expected = (y / 2.0).clamp(0.0, 1.0) as f32;
        assert!((w1 - expected).abs() < 0.02, "voxel at y = {y}: {w1} vs {expected}");
    }
    let world = DynamicWorld::new(grid, []).unwrap();
    let pose = ds.pose(1.0).unwrap();
    let placements = ds.placements(&pose).unwrap();
    let posed = ds.posed_scene(&pose).unwrap();
    let reference =
        revoxelize(&posed, &posed.geometry(), &grid, Mode::Conservative, RecordSource::Pieces)
            .unwrap();
    let reference = occupancy_of(reference.records.coords());
    let (leaves, _) = world.leaves(&[(&cache, &placements[0])], &FrameOptions::default()).unwrap();
    let ours = occupancy_of(leaves.iter().map(|l| voxlod_format::morton::decode(l.0)));
    let (inter, union, _, _) = compare(&ours, &reference);
    assert!(inter as f64 / union as f64 > 0.4, "IoU {}", inter as f64 / union as f64);
}

/// The crowd's caches at a coarse voxel (0.08): every walker voxel gets a normalized skin —
/// including voxels whose listed triangles miss the exact voxel box by the voxelizer's snapping
/// (they once had no pieces, hence no weights).
#[test]
fn the_crowds_caches_build_at_a_coarse_voxel() {
    let scene = voxlod_scene::procedural::from_spec("crowd?walkers=2&rigid=2&sides=8").unwrap();
    let ds = DynamicScene::new(scene, 0).unwrap();
    assert_eq!((ds.objects.len(), ds.statics.len()), (4, 1));
    let options = CacheOptions { records: RecordSource::Pieces, ..Default::default() };
    for o in 0..ds.objects.len() {
        let cache = build_cache(&ds, o, 0.08, &options).unwrap();
        cache.validate().unwrap();
        assert!(cache.len() > 100, "{}", cache.len());
        assert!(cache.records.iter().all(|r| r.color != [0; 3]), "no black fragment records");
    }
}
