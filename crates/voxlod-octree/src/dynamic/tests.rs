//! Voxel transformation: caches and their files, placement checks, the transform against an
//! `f64` oracle, the blend against a brute-force oracle (exact, order-independent, mass
//! conserving), the filters' holes at 45°, skinning, and the extremes.

use std::collections::BTreeMap;

use glam::{DMat4, DQuat, DVec3, IVec3, UVec3, Vec3};
use proptest::prelude::*;
use voxlod_format::records::{AverageRecord, SkinnedRecord, VoxelSkin};
use voxlod_format::{BrickMap, GridSpec, morton};

use super::blend::corner;
use super::*;
use crate::Error;

fn grid(origin: DVec3, size: f64, dims: u32) -> GridSpec {
    GridSpec::new(origin, size, UVec3::splat(dims)).unwrap()
}

fn red() -> AverageRecord {
    AverageRecord::new(Vec3::new(0.8, 0.1, 0.1), Vec3::Z, 1.0)
}

/// A rigid cache over `dims` in a grid of unit voxels at the origin holding `voxels`.
fn cache_of(dims: u32, voxels: impl IntoIterator<Item = (UVec3, AverageRecord)>) -> VoxelCache {
    let g = grid(DVec3::ZERO, 1.0, dims);
    let map = BrickMap::from_voxels(g.dims, voxels).unwrap();
    VoxelCache::rigid("obj", g, 1.0, &map).unwrap()
}

fn slab(n: u32) -> VoxelCache {
    cache_of(n, (0..n).flat_map(|x| (0..n).map(move |y| (UVec3::new(x, y, 0), red()))))
}

fn world(dims: u32) -> DynamicWorld {
    DynamicWorld::new(grid(DVec3::ZERO, 1.0, dims), []).unwrap()
}

fn opts(filter: Filter) -> FrameOptions {
    FrameOptions { filter, ..FrameOptions::default() }
}

/// Brute force: every contribution summed per world voxel in `u128`/`i128`, in voxel order.
fn oracle(
    grid: &GridSpec,
    inputs: &[(Vec<Placed>, Vec<AverageRecord>)],
    filter: Filter,
) -> BTreeMap<u64, [i128; 8]> {
    let mut out: BTreeMap<u64, [i128; 8]> = BTreeMap::new();
    let table = linear12_table();
    for (placed, records) in inputs {
        for (p, r) in placed.iter().zip(records) {
            if p.status != Placed::INSIDE {
                continue;
            }
            for k in 0..filter.corners() {
                let (c, w) = corner(p, k, filter);
                if w == 0 || c.min_element() < 0 || !c.as_uvec3().cmplt(grid.dims).all() {
                    continue;
                }
                let e = out.entry(morton::encode(c.as_uvec3())).or_default();
                let (w, a) = (w as i128, r.opacity as i128);
                e[0] += w;
                e[1] += w * a;
                for i in 0..3 {
                    e[2 + i] += w * a * table[r.color[i] as usize] as i128;
                    e[5 + i] += w * a * p.normal[i] as i128;
                }
            }
        }
    }
    out
}

fn as_wide(s: &CellSums) -> [i128; 8] {
    [
        s.weight as i128,
        s.alpha as i128,
        s.color[0] as i128,
        s.color[1] as i128,
        s.color[2] as i128,
        s.normal[0] as i128,
        s.normal[1] as i128,
        s.normal[2] as i128,
    ]
}

#[test]
fn positions_pack_ten_bits_per_axis_and_larger_caches_are_refused() {
    let c = UVec3::new(1023, 0, 517);
    assert_eq!(unpack_position(pack_position(c).unwrap()), c);
    assert_eq!(pack_position(UVec3::new(1024, 0, 0)), None);
    let g = GridSpec::new(DVec3::ZERO, 1.0, UVec3::new(1025, 4, 4)).unwrap();
    let map = BrickMap::from_voxels(g.dims, [(UVec3::ZERO, red())]).unwrap();
    let e = VoxelCache::rigid("big", g, 1.0, &map).unwrap_err();
    assert!(matches!(e, Error::CacheTooLarge { max: 1024, .. }), "{e}");
    assert!(e.to_string().contains("'big'") && e.to_string().contains("1025"), "{e}");
}

#[test]
fn caches_round_trip_through_vxl_files_and_bad_files_are_named() {
    let rigid = slab(5);
    let dir = std::env::temp_dir().join(format!("voxlod-cache-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("rigid.vxl");
    rigid.write(&path).unwrap();
    assert_eq!(VoxelCache::read(&path).unwrap(), rigid);
    let g = grid(DVec3::new(-1.0, 2.0, 0.5), 0.25, 8);
    let skin = VoxelSkin::from_influences(&[(0, 0.3), (2, 0.7)]).unwrap();
    let map = BrickMap::from_voxels(
        g.dims,
        [(UVec3::new(1, 2, 3), SkinnedRecord { average: red(), skin })],
    )
    .unwrap();
    let skinned = VoxelCache::skinned("walker", g, 2.0, 4, 3, &map).unwrap();
    assert_eq!(skinned.bytes_per_voxel(), 20);
    let bytes = skinned.encode().unwrap();
    let back = VoxelCache::decode(&bytes, &path).unwrap();
    assert_eq!(back, skinned);
    assert_eq!(back.skin.as_ref().unwrap().skin, 4);
    // A wrong layout version, a missing key, a joint beyond the skin: errors naming the file.
    let text =
        |b: &[u8]| VoxelCache::decode(b, std::path::Path::new("x.vxl")).unwrap_err().to_string();
    let meta = |m: &[(&str, &str)]| {
        let meta: Vec<(String, String)> =
            m.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        voxlod_format::vxl::encode(&g, &map, &meta).unwrap()
    };
    let e = text(&meta(&[("voxlod.cache", "9"), ("object", "o"), ("scale", "1")]));
    assert!(e.contains("x.vxl") && e.contains("version 9"), "{e}");
    let e = text(&meta(&[("voxlod.cache", "1"), ("object", "o"), ("scale", "1")]));
    assert!(e.contains("'skin' is missing"), "{e}");
    let e = text(&meta(&[
        ("voxlod.cache", "1"),
        ("object", "o"),
        ("scale", "1"),
        ("skin", "0"),
        ("joints", "2"),
    ]));
    assert!(e.contains("joint 2 of a skin with 2 joints"), "{e}");
    let occ = BrickMap::from_voxels(g.dims, [(UVec3::ONE, 1u32)]).unwrap();
    let e = text(&voxlod_format::vxl::encode(&g, &occ, &[]).unwrap());
    assert!(e.contains("voxlod.cache"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// An aligned integer translation moves every voxel to exactly one world voxel under both
/// filters, with the record's colour, normal and opacity.
#[test]
fn aligned_translations_are_exact_under_both_filters() {
    let cache = slab(4);
    let w = world(16);
    let m = Placement::Rigid(DMat4::from_translation(DVec3::new(3.0, 5.0, 7.0)));
    for filter in [Filter::Nearest, Filter::EightNeighbour] {
        let (leaves, stats) = w.leaves(&[(&cache, &m)], &opts(filter)).unwrap();
        assert_eq!(leaves.len(), 16, "{filter:?}");
        assert_eq!((stats.blend.clipped_contributions, stats.dropped), (0, 0));
        for (code, p) in &leaves {
            let c = morton::decode(*code);
            assert!((3..7).contains(&c.x) && (5..9).contains(&c.y) && c.z == 7, "{c}");
            assert!((p.opacity - 1.0).abs() < 1e-6);
            assert!((p.color() - red().color()).abs().max_element() < 1.0 / 4095.0 + 1e-6);
            assert!((p.normal() - Vec3::Z).length() < 1e-3);
        }
    }
}

#[test]
fn half_voxel_offsets_split_the_volume_and_the_threshold_decides() {
    let cache = cache_of(1, [(UVec3::ZERO, red())]);
    let w = world(8);
    let m = Placement::Rigid(DMat4::from_translation(DVec3::new(2.5, 2.0, 2.0)));
    let (sums, _) = {
        let (placed, _) = w.transform_all(&[(&cache, &m)], &opts(Filter::EightNeighbour)).unwrap();
        w.sums(&[(&cache, &m)], &placed, &opts(Filter::EightNeighbour)).unwrap()
    };
    assert_eq!(sums.len(), 2);
    for s in &sums.sums {
        assert_eq!(s.weight, FULL_WEIGHT / 2);
        assert!((s.payload().opacity - 0.5).abs() < 1e-6);
    }
    let o = |t| FrameOptions { occupancy_threshold: t, ..opts(Filter::EightNeighbour) };
    assert_eq!(w.leaves(&[(&cache, &m)], &o(0.5)).unwrap().0.len(), 2);
    let (leaves, stats) = w.leaves(&[(&cache, &m)], &o(0.51)).unwrap();
    assert_eq!((leaves.len(), stats.dropped), (0, 2));
    // Nearest puts it whole into the voxel holding its centre, x = 3.
    let (leaves, _) = w.leaves(&[(&cache, &m)], &opts(Filter::Nearest)).unwrap();
    assert_eq!(
        leaves.iter().map(|l| morton::decode(l.0)).collect::<Vec<_>>(),
        [UVec3::new(3, 2, 2)]
    );
    assert!(w.leaves(&[(&cache, &m)], &o(f32::NAN)).is_err());
}

/// The transform's cells equal the `f64` oracle's except within 10⁻⁴ voxel of a cell boundary.
#[test]
fn transformed_cells_match_an_f64_oracle() {
    let cache = cache_of(
        32,
        (0..32)
            .flat_map(|x| (0..32).flat_map(move |y| [(UVec3::new(x, y, (x * 7 + y) % 32), red())])),
    );
    let g = grid(DVec3::new(-40.0, -40.0, -40.0), 1.0, 128);
    for (k, axis) in
        [DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(1.0, 2.0, 3.0).normalize()].iter().enumerate()
    {
        for angle in [0.3f64, std::f64::consts::FRAC_PI_4, 2.0] {
            let m = DMat4::from_rotation_translation(
                DQuat::from_axis_angle(*axis, angle),
                DVec3::new(1000.25, -7.5, 3.125) * (k as f64 - 1.0) * 0.01,
            );
            let frame = place(&cache, &Placement::Rigid(m), &g, 1e-3).unwrap();
            let placed = transform(&cache, &frame, Filter::Nearest);
            let mut near_boundary = 0;
            for (v, p) in placed.iter().enumerate() {
                let i = unpack_position(cache.positions[v]).as_dvec3();
                let exact = (m.transform_point3(i + 0.5) - g.origin) / g.voxel_size;
                let cell = IVec3::from_array(p.cell);
                if cell != exact.floor().as_ivec3() {
                    let dist = (exact - exact.round()).abs().min_element();
                    assert!(dist < 1e-4, "voxel {v}: {cell} vs {exact}");
                    near_boundary += 1;
                }
            }
            assert!(near_boundary * 1000 <= placed.len(), "{near_boundary} of {}", placed.len());
        }
    }
}

/// A square rotated by exactly 45° about z: nearest leaves holes inside it, 8-neighbour none.
#[test]
fn nearest_leaves_holes_at_45_degrees_and_eight_neighbour_does_not() {
    let n = 24;
    let cache = slab(n);
    let w = world(64);
    let centre = DVec3::new(32.0, 32.0, 8.5);
    let rot = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4);
    // Rotate about the square's centre, then put it at `centre`.
    let m = DMat4::from_translation(centre)
        * DMat4::from_quat(rot)
        * DMat4::from_translation(-DVec3::new(n as f64 / 2.0, n as f64 / 2.0, 0.5));
    let m = Placement::Rigid(m);
    // World voxels whose centre is at least 1.5 voxels inside the rotated square.
    let inside = |c: UVec3| {
        let p = c.as_dvec3() + 0.5 - centre;
        let local = rot.inverse() * DVec3::new(p.x, p.y, 0.0);
        c.z == 8 && local.x.abs().max(local.y.abs()) < n as f64 / 2.0 - 1.5
    };
    let interior: Vec<UVec3> = (0..64)
        .flat_map(|x| (0..64).map(move |y| UVec3::new(x, y, 8)))
        .filter(|&c| inside(c))
        .collect();
    let holes = |filter| {
        let (leaves, _) = w.leaves(&[(&cache, &m)], &opts(filter)).unwrap();
        let set: std::collections::HashSet<u64> = leaves.iter().map(|l| l.0).collect();
        interior.iter().filter(|&&c| !set.contains(&morton::encode(c))).count()
    };
    let (nearest, eight) = (holes(Filter::Nearest), holes(Filter::EightNeighbour));
    assert!(nearest > interior.len() / 20, "nearest: {nearest} holes of {}", interior.len());
    assert_eq!(eight, 0, "8-neighbour: {eight} holes of {}", interior.len());
}

#[test]
fn scale_shear_and_resolution_are_refused_with_the_numbers() {
    let cache = slab(3);
    let g = grid(DVec3::ZERO, 1.0, 16);
    let e = place(&cache, &Placement::Rigid(DMat4::from_scale(DVec3::splat(1.5))), &g, 1e-3)
        .unwrap_err();
    assert!(matches!(e, Error::NotRigid { matrix: 0, .. }), "{e}");
    assert!(e.to_string().contains("1.5"), "{e}");
    let shear = DMat4::from_cols_array(&[
        1.0, 0.0, 0.0, 0.0, 0.3, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ]);
    let e = place(&cache, &Placement::Rigid(shear), &g, 1e-3).unwrap_err();
    assert!(matches!(e, Error::NotRigid { .. }), "{e}");
    // A tiny scale drift within the tolerance is accepted.
    assert!(
        place(&cache, &Placement::Rigid(DMat4::from_scale(DVec3::splat(1.0005))), &g, 1e-3).is_ok()
    );
    let fine = grid(DVec3::ZERO, 0.5, 16);
    let e = place(&cache, &Placement::Rigid(DMat4::IDENTITY), &fine, 1e-3).unwrap_err();
    assert!(matches!(e, Error::CacheResolution { .. }), "{e}");
    let mut nan = DMat4::IDENTITY;
    nan.w_axis.x = f64::NAN;
    assert!(matches!(
        place(&cache, &Placement::Rigid(nan), &g, 1e-3),
        Err(Error::InvalidPlacement { .. })
    ));
    let e = place(&cache, &Placement::Skinned(vec![DMat4::IDENTITY]), &g, 1e-3).unwrap_err();
    assert!(e.to_string().contains("rigid cache"), "{e}");
}

/// Partly outside: the outside contributions are clipped and counted, the rest kept, and the
/// volume adds up. Huge and tiny translations.
#[test]
fn objects_outside_the_grid_are_clipped_and_counted() {
    let cache = slab(8);
    let w = world(16);
    let total = 64 * FULL_WEIGHT;
    for filter in [Filter::Nearest, Filter::EightNeighbour] {
        let m = Placement::Rigid(DMat4::from_translation(DVec3::new(12.3, -3.6, 4.0)));
        let (placed, _) = w.transform_all(&[(&cache, &m)], &opts(filter)).unwrap();
        let (sums, stats) = w.sums(&[(&cache, &m)], &placed, &opts(filter)).unwrap();
        assert!(stats.clipped_contributions > 0, "{filter:?}");
        let kept: u64 = sums.sums.iter().map(|s| s.weight).sum();
        assert_eq!(kept + stats.clipped_weight, total, "{filter:?}");
        for huge in [1e12, -3e9, 1e30] {
            let m = Placement::Rigid(DMat4::from_translation(DVec3::new(huge, 0.0, 0.0)));
            let (leaves, stats) = w.leaves(&[(&cache, &m)], &opts(filter)).unwrap();
            assert!(leaves.is_empty());
            assert_eq!(stats.blend.clipped_weight, total, "{huge}");
        }
    }
    // A translation far below the voxel size changes nothing; the same beside a huge origin.
    let m0 = Placement::Rigid(DMat4::from_translation(DVec3::new(4.0, 4.0, 4.0)));
    let m1 = Placement::Rigid(DMat4::from_translation(DVec3::new(4.0 + 1e-9, 4.0, 4.0)));
    let a = w.leaves(&[(&cache, &m0)], &FrameOptions::default()).unwrap().0;
    let b = w.leaves(&[(&cache, &m1)], &FrameOptions::default()).unwrap().0;
    assert_eq!(a, b);
    let far = DynamicWorld::new(grid(DVec3::splat(1e7), 1.0, 16), []).unwrap();
    let m2 =
        Placement::Rigid(DMat4::from_translation(DVec3::splat(1e7) + DVec3::new(4.0, 4.0, 4.0)));
    assert_eq!(far.leaves(&[(&cache, &m2)], &FrameOptions::default()).unwrap().0, a);
}

/// Linear blend skinning: a voxel half on a still joint and half on one moved by two voxels
/// moves by one; joints collapsed onto one point pile every voxel into one world voxel, and the
/// sums stay exact.
#[test]
fn skinned_voxels_blend_their_joint_matrices() {
    let g = grid(DVec3::ZERO, 1.0, 4);
    let half = VoxelSkin::from_influences(&[(0, 0.5), (1, 0.5)]).unwrap();
    let whole = VoxelSkin::rigid(1);
    let map = BrickMap::from_voxels(
        g.dims,
        [
            (UVec3::new(0, 0, 0), SkinnedRecord { average: red(), skin: half }),
            (UVec3::new(2, 0, 0), SkinnedRecord { average: red(), skin: whole }),
        ],
    )
    .unwrap();
    let cache = VoxelCache::skinned("arm", g, 1.0, 0, 2, &map).unwrap();
    let w = world(16);
    let base = DVec3::new(4.0, 4.0, 4.0);
    let joints = Placement::Skinned(vec![
        DMat4::from_translation(base),
        DMat4::from_translation(base + DVec3::new(0.0, 2.0, 0.0)),
    ]);
    let (leaves, _) = w.leaves(&[(&cache, &joints)], &opts(Filter::Nearest)).unwrap();
    let cells: Vec<UVec3> = leaves.iter().map(|l| morton::decode(l.0)).collect();
    // Joint 1 holds 127/255 (the tie's extra unit goes to the first slot, joint 0): 0.996
    // voxel up, the centre at y = 5.496.
    assert_eq!(cells, [UVec3::new(4, 5, 4), UVec3::new(6, 6, 4)]);
    // Collapse: every joint maps the whole bind space onto one point.
    let cache = {
        let g = grid(DVec3::ZERO, 1.0, 64);
        let voxels = (0..64u32).flat_map(|x| (0..64u32).map(move |y| (x, y))).map(|(x, y)| {
            let skin = VoxelSkin::from_influences(&[(x % 3, 1.0), ((y % 3) + 3, 0.7)]).unwrap();
            (UVec3::new(x, y, (x ^ y) % 64), SkinnedRecord { average: red(), skin })
        });
        VoxelCache::skinned(
            "collapse",
            g,
            1.0,
            0,
            6,
            &BrickMap::from_voxels(g.dims, voxels).unwrap(),
        )
        .unwrap()
    };
    let point = DMat4::from_translation(DVec3::new(8.3, 8.7, 8.1));
    let rot =
        |a: f64| point * DMat4::from_rotation_y(a) * DMat4::from_translation(-DVec3::splat(32.0));
    // Rigid joints that all move the bind-space centre onto one point, differently rotated.
    let joints = Placement::Skinned((0..6).map(|k| rot(k as f64)).collect());
    let w = world(16);
    let (placed, _) = w.transform_all(&[(&cache, &joints)], &opts(Filter::EightNeighbour)).unwrap();
    let (sums, stats) =
        w.sums(&[(&cache, &joints)], &placed, &opts(Filter::EightNeighbour)).unwrap();
    let inputs = [(placed[0].clone(), cache.records.clone())];
    let expected = oracle(&w.grid, &inputs, Filter::EightNeighbour);
    assert_eq!(sums.len(), expected.len());
    for ((code, s), (ec, e)) in sums.codes.iter().zip(&sums.sums).zip(&expected) {
        assert_eq!((code, as_wide(s)), (ec, *e));
    }
    let kept: u64 = sums.sums.iter().map(|s| s.weight).sum();
    assert_eq!(kept + stats.clipped_weight, cache.len() as u64 * FULL_WEIGHT);
}

/// A million cached voxels (a 100³ block) rotated in one frame under both filters: the volume
/// adds up exactly and nothing is lost.
#[test]
fn a_million_voxels_in_one_frame() {
    let n = 100u32;
    let g = grid(DVec3::ZERO, 1.0, 128);
    let map = BrickMap::from_voxels(
        g.dims,
        (0..n).flat_map(|x| {
            (0..n).flat_map(move |y| (0..n).map(move |z| (UVec3::new(x, y, z), red())))
        }),
    )
    .unwrap();
    let cache = VoxelCache::rigid("block", g, 1.0, &map).unwrap();
    assert_eq!(cache.len(), 1_000_000);
    let w = world(256);
    let m = Placement::Rigid(
        DMat4::from_translation(DVec3::splat(128.0))
            * DMat4::from_rotation_y(0.4)
            * DMat4::from_translation(-DVec3::splat(50.0)),
    );
    for filter in [Filter::Nearest, Filter::EightNeighbour] {
        let (placed, _) = w.transform_all(&[(&cache, &m)], &opts(filter)).unwrap();
        let (sums, stats) = w.sums(&[(&cache, &m)], &placed, &opts(filter)).unwrap();
        let kept: u64 = sums.sums.iter().map(|s| s.weight).sum();
        assert_eq!((kept, stats.clipped_weight), (1_000_000 * FULL_WEIGHT, 0), "{filter:?}");
    }
}

#[test]
fn too_many_contributions_are_refused_before_any_work() {
    let cache = slab(4);
    let placed = vec![Placed::default(); (MAX_CONTRIBUTIONS / 8 + 1) as usize];
    let records = vec![red(); placed.len()];
    let g = grid(DVec3::ZERO, 1.0, 8);
    let e =
        blend(&g, &[BlendInput { placed: &placed, records: &records }], Filter::EightNeighbour, 0)
            .unwrap_err();
    assert!(matches!(e, Error::FrameTooLarge { .. }), "{e}");
    let _ = cache;
}

/// Static voxels blend with moving ones that overlap them.
#[test]
fn static_and_moving_voxels_blend() {
    let blue = AverageRecord::new(Vec3::new(0.1, 0.1, 0.9), Vec3::Y, 1.0);
    let w = DynamicWorld::new(grid(DVec3::ZERO, 1.0, 8), [(UVec3::new(2, 2, 2), blue)]).unwrap();
    let cache = cache_of(1, [(UVec3::ZERO, red())]);
    let m = Placement::Rigid(DMat4::from_translation(DVec3::splat(2.0)));
    let (leaves, stats) = w.leaves(&[(&cache, &m)], &FrameOptions::default()).unwrap();
    assert_eq!((leaves.len(), stats.touched), (1, 1));
    let p = leaves[0].1;
    assert!((p.opacity - 1.0).abs() < 1e-6, "min(1, 2 voxels of opacity 1)");
    let mean = (red().color() + blue.color()) / 2.0;
    assert!((p.color() - mean).abs().max_element() < 1e-3, "{} vs {mean}", p.color());
    // Empty objects and no objects are fine.
    assert_eq!(w.leaves(&[], &FrameOptions::default()).unwrap().0.len(), 1);
}

/// Random voxels (position, opacity, colour, normal), rotation, translation, filter.
type Frame = (Vec<(UVec3, u8, [u8; 3], [i8; 3])>, [f64; 4], [f64; 3], bool);

fn arb_frame() -> impl Strategy<Value = Frame> {
    (
        prop::collection::vec(
            (
                (0u32..12, 0u32..12, 0u32..12).prop_map(|(x, y, z)| UVec3::new(x, y, z)),
                1u8..=255,
                prop::array::uniform3(any::<u8>()),
                prop::array::uniform3(-127i8..=127),
            ),
            1..200,
        ),
        prop::array::uniform4(-1.0f64..1.0),
        prop::array::uniform3(-6.0f64..20.0),
        any::<bool>(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// The blend equals the brute-force oracle, whatever the order of the voxels and objects,
    /// and the volume is conserved: kept + clipped = voxels · 2¹⁸.
    #[test]
    fn blend_is_exact_order_independent_and_conserves_volume(
        (voxels, q, t, nearest) in arb_frame()
    ) {
        let filter = if nearest { Filter::Nearest } else { Filter::EightNeighbour };
        let rot = DQuat::from_xyzw(q[0], q[1], q[2], q[3] + 1.5).normalize();
        let m = DMat4::from_rotation_translation(rot, DVec3::from_array(t));
        let records: BTreeMap<u64, (UVec3, AverageRecord)> = voxels
            .iter()
            .map(|&(c, a, col, n)| {
                (morton::encode(c), (c, AverageRecord { color: col, opacity: a, normal: n, _pad: 0 }))
            })
            .collect();
        let records: Vec<(UVec3, AverageRecord)> = records.into_values().collect();
        let cache = cache_of(12, records.clone());
        let g = grid(DVec3::ZERO, 1.0, 16);
        let frame = place(&cache, &Placement::Rigid(m), &g, 1e-3).unwrap();
        let placed = transform(&cache, &frame, filter);
        let (sums, stats) =
            blend(&g, &[BlendInput { placed: &placed, records: &cache.records }], filter, 0).unwrap();
        let expected = oracle(&g, &[(placed.clone(), cache.records.clone())], filter);
        prop_assert_eq!(sums.len(), expected.len());
        for ((code, s), (ec, e)) in sums.codes.iter().zip(&sums.sums).zip(&expected) {
            prop_assert_eq!((code, as_wide(s)), (ec, *e));
        }
        let kept: u64 = sums.sums.iter().map(|s| s.weight).sum();
        prop_assert_eq!(kept + stats.clipped_weight, cache.len() as u64 * FULL_WEIGHT);
        // Reversed voxel order, split into two objects in the other order: the same sums.
        let n = placed.len();
        let mut rp = placed.clone();
        let mut rr = cache.records.clone();
        rp.reverse();
        rr.reverse();
        let (a, b) = (n / 3, n);
        let (swapped, _) = blend(
            &g,
            &[
                BlendInput { placed: &rp[a..b], records: &rr[a..b] },
                BlendInput { placed: &rp[..a], records: &rr[..a] },
            ],
            filter,
            0,
        )
        .unwrap();
        prop_assert_eq!(&swapped, &sums);
    }
}
