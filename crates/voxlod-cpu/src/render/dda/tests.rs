//! DDA tests: against a brute-force slab test over every voxel of small grids (visited set,
//! order and `t`s), brick skipping and occupied-voxel walks against plain stepping, and the exact cases of the tie rules.

use glam::{DVec3, IVec3, UVec3, Vec3};
use proptest::prelude::*;
use voxlod_format::{BrickMap, GridSpec};

use super::*;
use crate::render::bricks::{DenseBricks, Occupancy, brick_masks};

/// Per voxel, the ray's parameter interval inside it, in f64, with the half-open rule for
/// axes the ray is parallel to (components below `f32::MIN_POSITIVE`, as the DDA treats them).
fn brute_force(
    grid: &GridSpec,
    o: Vec3,
    d: Vec3,
    t_min: f32,
    t_max: f32,
) -> Vec<(UVec3, f64, f64)> {
    // Grid-space ray as the DDA rounds it to f32, then exact arithmetic from there.
    let og = ((o.as_dvec3() - grid.origin) / grid.voxel_size).as_vec3().as_dvec3();
    let dg = (d / grid.voxel_size as f32).as_dvec3();
    let mut out = Vec::new();
    for x in 0..grid.dims.x {
        for y in 0..grid.dims.y {
            for z in 0..grid.dims.z {
                let c = UVec3::new(x, y, z);
                let (mut t0, mut t1) = (t_min as f64, t_max as f64);
                for a in 0..3 {
                    let lo = c[a] as f64;
                    if (d[a] / grid.voxel_size as f32).abs() < f32::MIN_POSITIVE {
                        if !(og[a] >= lo && og[a] < lo + 1.0) {
                            t0 = f64::INFINITY;
                        }
                    } else {
                        let (ta, tb) = ((lo - og[a]) / dg[a], (lo + 1.0 - og[a]) / dg[a]);
                        t0 = t0.max(ta.min(tb));
                        t1 = t1.min(ta.max(tb));
                    }
                }
                if t0.is_finite() || t1.is_finite() {
                    out.push((c, t0, t1));
                }
            }
        }
    }
    out
}

fn check_against_brute_force(grid: &GridSpec, o: Vec3, d: Vec3, t_min: f32, t_max: f32) {
    let visited: Vec<DdaVoxel> = Dda::new(grid, o, d, t_min, t_max).collect();
    let reference = brute_force(grid, o, d, t_min, t_max);
    let scale = (o.as_dvec3() - grid.origin).length() / d.length() as f64 + 1.0;
    let eps = 1e-4 * scale;
    let context = format!("grid {grid:?}, ray {o} + t·{d}, t in [{t_min}, {t_max}]");
    for w in visited.windows(2) {
        assert!(w[0].t_enter <= w[1].t_enter, "out of order: {w:?}, {context}");
        assert_ne!(w[0].voxel, w[1].voxel, "{context}");
    }
    for v in &visited {
        let &(_, t0, t1) = reference.iter().find(|r| r.0 == v.voxel).expect("voxel in grid");
        assert!(t1 - t0 >= -eps, "visited {v:?} the ray misses ({t0}, {t1}), {context}");
        assert!((v.t_enter as f64 - t0).abs() <= eps, "{v:?} vs ({t0}, {t1}), {context}");
        assert!((v.t_exit as f64 - t1).abs() <= eps, "{v:?} vs ({t0}, {t1}), {context}");
    }
    for &(c, t0, t1) in &reference {
        if t1 - t0 > eps {
            assert!(
                visited.iter().any(|v| v.voxel == c),
                "missed {c} over ({t0}, {t1}); visited {:?}, {context}",
                visited.iter().map(|v| v.voxel).collect::<Vec<_>>()
            );
        }
    }
}

fn unit_grid(dims: UVec3) -> GridSpec {
    GridSpec::new(DVec3::ZERO, 1.0, dims).unwrap()
}

fn walk(grid: &GridSpec, o: Vec3, d: Vec3) -> Vec<UVec3> {
    Dda::new(grid, o, d, 0.0, f32::INFINITY).map(|v| v.voxel).collect()
}

/// The voxels of a walk, one `step()` at a time until it returns `None`, each checked to lie in
/// the brick its index names in `map`, then with the index cleared (plain stepping has none).
fn collect_walk(map: &BrickMap<()>, mut step: impl FnMut() -> Option<DdaVoxel>) -> Vec<DdaVoxel> {
    let mut got = Vec::new();
    while let Some(v) = step() {
        assert_eq!(v.brick as usize, map.brick_index(v.voxel / 8).unwrap(), "{v:?}");
        got.push(DdaVoxel { brick: u32::MAX, ..v });
    }
    got
}

/// A direction component: often exactly 0, ±1 or a denormal, else random.
fn component() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -1.0f32..1.0,
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => Just(1.0f32),
        1 => Just(-1.0f32),
        1 => Just(1e-40f32),
    ]
}

/// An origin coordinate: often exactly on a plane, else random, inside or outside the grid.
fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![3 => -3.0f32..10.0, 1 => (-3i32..10).prop_map(|i| i as f32)]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    #[test]
    fn visits_what_brute_force_says(
        dims in (1u32..7, 1u32..7, 1u32..7),
        origin in (-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0),
        size in prop_oneof![Just(1.0f64), 0.01f64..3.0],
        o in (coordinate(), coordinate(), coordinate()),
        d in (component(), component(), component()),
        t_range in prop_oneof![Just((0.0f32, f32::INFINITY)), (0.0f32..4.0, 0.0f32..12.0)],
    ) {
        let grid = GridSpec::new(DVec3::new(origin.0, origin.1, origin.2), size,
            UVec3::new(dims.0, dims.1, dims.2)).unwrap();
        let world = |g: Vec3| (grid.origin + g.as_dvec3() * size).as_vec3();
        let o = world(Vec3::new(o.0, o.1, o.2));
        let d = Vec3::new(d.0, d.1, d.2);
        if (d / size as f32).abs().max_element() < f32::MIN_POSITIVE {
            // No direction left after flushing denormals: nothing is visited.
            prop_assert!(Dda::new(&grid, o, d, t_range.0, t_range.1).next().is_none());
        } else {
            check_against_brute_force(&grid, o, d, t_range.0, t_range.1);
        }
    }

    #[test]
    fn brick_skipping_equals_stepping_filtered_by_brick(
        dims in (1u32..40, 1u32..40, 1u32..40),
        voxels in proptest::collection::vec((0u32..40, 0u32..40, 0u32..40), 0..12),
        o in (-5.0f32..45.0, -5.0f32..45.0, -5.0f32..45.0),
        d in (component(), component(), component()),
    ) {
        let dims = UVec3::new(dims.0, dims.1, dims.2);
        let occupied: std::collections::HashSet<UVec3> =
            voxels.iter().map(|&(x, y, z)| UVec3::new(x, y, z) % dims).collect();
        let map = BrickMap::from_voxels(dims, occupied.iter().map(|&c| (c, ()))).unwrap();
        let grid = unit_grid(dims);
        let d = Vec3::new(d.0, d.1, d.2);
        let o = Vec3::new(o.0, o.1, o.2);
        let expected: Vec<DdaVoxel> = Dda::new(&grid, o, d, 0.0, f32::INFINITY)
            .filter(|v| map.brick_index(v.voxel / 8).is_some())
            .collect();
        for dense in [false, true] {
            let mut dda = Dda::new(&grid, o, d, 0.0, f32::INFINITY);
            let table = DenseBricks::new(&map).unwrap();
            let got = collect_walk(&map, || {
                if dense { dda.next_occupied_brick(&table) } else { dda.next_occupied_brick(&map) }
            });
            prop_assert_eq!(&got, &expected);
        }
    }

    #[test]
    fn occupied_voxel_walk_equals_stepping_filtered_by_voxel(
        dims in (1u32..40, 1u32..40, 1u32..40),
        voxels in proptest::collection::vec((0u32..40, 0u32..40, 0u32..40), 0..300),
        lump in 0u32..5,
        o in (-5.0f32..45.0, -5.0f32..45.0, -5.0f32..45.0),
        d in (component(), component(), component()),
        t_max in prop_oneof![Just(f32::INFINITY), 0.0f32..60.0],
    ) {
        // Voxels snapped to multiples of `lump` + 1 cluster into fewer blocks and bricks, so
        // walks meet full, partly empty and empty blocks of allocated bricks.
        let dims = UVec3::new(dims.0, dims.1, dims.2);
        let occupied: std::collections::HashSet<UVec3> = voxels
            .iter()
            .map(|&(x, y, z)| (UVec3::new(x, y, z) / (lump + 1) * (lump + 1)) % dims)
            .collect();
        let map = BrickMap::from_voxels(dims, occupied.iter().map(|&c| (c, ()))).unwrap();
        let grid = unit_grid(dims);
        let (o, d) = (Vec3::new(o.0, o.1, o.2), Vec3::new(d.0, d.1, d.2));
        let expected: Vec<DdaVoxel> = Dda::new(&grid, o, d, 0.0, t_max)
            .filter(|v| occupied.contains(&v.voxel))
            .collect();
        let masks = brick_masks(&map);
        let table = DenseBricks::new(&map).unwrap();
        let occupancy = Occupancy { bricks: &table, masks: &masks };
        let mut dda = Dda::new(&grid, o, d, 0.0, t_max);
        let got = collect_walk(&map, || dda.next_occupied_voxel(&occupancy));
        prop_assert_eq!(&got, &expected);
    }
}

/// A coordinate of a larger grid: often on a brick or 2³-brick block boundary (multiples of 8
/// and 16, where block jumps tie with brick and voxel planes), else random.
fn block_coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![
        2 => -5.0f32..110.0,
        1 => (-1i32..8).prop_map(|i| (i * 16) as f32),
        1 => (-1i32..14).prop_map(|i| (i * 8) as f32),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Grids up to 13 bricks (7 blocks of 2³ bricks) per axis with a few clumps of voxels, so
    /// that walks cross empty blocks in one jump, through partial blocks at the grid's end and
    /// through block corners and edges: the same voxels, `t`s and normals as plain stepping.
    #[test]
    fn empty_block_jumps_equal_stepping(
        dims in (1u32..100, 1u32..100, 1u32..100),
        clumps in proptest::collection::vec((0u32..100, 0u32..100, 0u32..100), 1..6),
        o in (block_coordinate(), block_coordinate(), block_coordinate()),
        jitter in (-3i32..4, -3i32..4, -3i32..4),
        parallel in (0u32..8, 0u32..8, 0u32..8),
        t_max in prop_oneof![3 => Just(f32::INFINITY), 1 => 0.0f32..200.0],
    ) {
        let dims = UVec3::new(dims.0, dims.1, dims.2);
        // Aimed at the first clump (an integer offset: exact ties at brick and block corners
        // when the origin is on a boundary), each axis sometimes parallel.
        let clump = UVec3::new(clumps[0].0, clumps[0].1, clumps[0].2) % dims;
        let target = clump.as_ivec3() + IVec3::new(jitter.0, jitter.1, jitter.2);
        let mut d = target.as_vec3() + 0.5 * (parallel.0 % 2) as f32 - Vec3::new(o.0, o.1, o.2);
        for (a, p) in [parallel.0, parallel.1, parallel.2].into_iter().enumerate() {
            if p == 0 {
                d[a] = 0.0;
            }
        }
        let d = (d.x, d.y, d.z);
        // Each clump: a 3³ cube of voxels, clipped to the grid.
        let occupied: std::collections::HashSet<UVec3> = clumps
            .iter()
            .flat_map(|&(x, y, z)| {
                let c = UVec3::new(x, y, z) % dims;
                (0..27u32).map(move |k| c + UVec3::new(k % 3, k / 3 % 3, k / 9))
            })
            .filter(|c| c.cmplt(dims).all())
            .collect();
        let map = BrickMap::from_voxels(dims, occupied.iter().map(|&c| (c, ()))).unwrap();
        let grid = unit_grid(dims);
        let (o, d) = (Vec3::new(o.0, o.1, o.2), Vec3::new(d.0, d.1, d.2));
        let table = DenseBricks::new(&map).unwrap();
        let masks = brick_masks(&map);
        let by_brick: Vec<DdaVoxel> = Dda::new(&grid, o, d, 0.0, t_max)
            .filter(|v| map.brick_index(v.voxel / 8).is_some())
            .collect();
        let mut dda = Dda::new(&grid, o, d, 0.0, t_max);
        let got = collect_walk(&map, || dda.next_occupied_brick(&table));
        prop_assert_eq!(&got, &by_brick);
        let by_voxel: Vec<DdaVoxel> =
            by_brick.iter().copied().filter(|v| occupied.contains(&v.voxel)).collect();
        let occupancy = Occupancy { bricks: &table, masks: &masks };
        let mut dda = Dda::new(&grid, o, d, 0.0, t_max);
        let got = collect_walk(&map, || dda.next_occupied_voxel(&occupancy));
        prop_assert_eq!(&got, &by_voxel);
    }
}

#[test]
fn brick_masks_mark_voxels_and_their_blocks() {
    let voxels =
        [UVec3::new(0, 0, 0), UVec3::new(7, 7, 7), UVec3::new(3, 4, 5), UVec3::new(9, 1, 2)];
    let map = BrickMap::from_voxels(UVec3::new(16, 8, 8), voxels.iter().map(|&c| (c, ()))).unwrap();
    let masks = brick_masks(&map);
    assert_eq!(masks.len(), 2);
    for x in 0..16 {
        for y in 0..8 {
            for z in 0..8 {
                let c = UVec3::new(x, y, z);
                let block = |v: UVec3| v / 2 == c / 2;
                if let Some(b) = map.brick_index(c / 8) {
                    let m = &masks[b];
                    assert_eq!(m.has_voxel(c % 8), voxels.contains(&c), "{c}");
                    assert_eq!(m.has_block(c % 8), voxels.iter().any(|&v| block(v)), "{c}");
                    let l = c % 8;
                    let linear = l.x + 8 * l.y + 64 * l.z;
                    assert_eq!(m.has_voxel_linear(linear), m.has_voxel(l), "{c}");
                    assert_eq!(m.has_block_linear(linear), m.has_block(l), "{c}");
                }
            }
        }
    }
}

#[test]
fn axis_aligned_rays_walk_one_row() {
    let g = unit_grid(UVec3::new(4, 3, 5));
    let row: Vec<UVec3> = (0..5).map(|k| UVec3::new(2, 1, k)).collect();
    assert_eq!(walk(&g, Vec3::new(2.5, 1.5, -1.0), Vec3::Z), row);
    let back: Vec<UVec3> = row.iter().rev().copied().collect();
    assert_eq!(walk(&g, Vec3::new(2.5, 1.5, 9.0), Vec3::NEG_Z), back);
    // Exactly in the plane x = 2 (between columns 1 and 2): the + side, column 2.
    assert_eq!(walk(&g, Vec3::new(2.0, 1.5, -1.0), Vec3::Z), row);
    // In the plane of the grid's max face: outside.
    assert!(walk(&g, Vec3::new(4.0, 1.5, -1.0), Vec3::Z).is_empty());
    // Signed zeros and denormals in the other components change nothing.
    let d = Vec3::new(-0.0, 1e-40, 1.0);
    assert_eq!(walk(&g, Vec3::new(2.5, 1.5, -1.0), d), row);
    // The t values are the plane distances.
    let v: Vec<_> = Dda::new(&g, Vec3::new(2.5, 1.5, -1.0), Vec3::Z, 0.0, f32::INFINITY).collect();
    assert_eq!((v[0].t_enter, v[0].t_exit, v[4].t_exit), (1.0, 2.0, 6.0));
    assert_eq!(v[0].entry_normal, IVec3::NEG_Z);
    assert_eq!(v[1].entry_normal, IVec3::NEG_Z);
}

#[test]
fn diagonals_through_corners_step_all_axes_at_once() {
    let g = unit_grid(UVec3::splat(5));
    let diag: Vec<UVec3> = (0..5).map(UVec3::splat).collect();
    assert_eq!(walk(&g, Vec3::splat(-1.0), Vec3::ONE), diag);
    assert_eq!(walk(&g, Vec3::splat(-1.0), Vec3::ONE.normalize()), diag);
    let back: Vec<UVec3> = diag.iter().rev().copied().collect();
    assert_eq!(walk(&g, Vec3::splat(7.0), Vec3::NEG_ONE), back);
    // A 2D diagonal through edges.
    let edge: Vec<UVec3> = (0..5).map(|k| UVec3::new(k, k, 2)).collect();
    assert_eq!(walk(&g, Vec3::new(0.0, 0.0, 2.5), Vec3::new(1.0, 1.0, 0.0)), edge);
}

#[test]
fn starts_inside_on_planes_and_far_away() {
    let g = unit_grid(UVec3::splat(6));
    // Starting exactly on plane x = 3 and moving −x: the first voxel is column 2.
    let v: Vec<_> = Dda::new(&g, Vec3::new(3.0, 0.5, 0.5), Vec3::NEG_X, 0.0, 10.0).collect();
    assert_eq!(v[0].voxel, UVec3::new(2, 0, 0));
    assert_eq!(v[0].entry_normal, IVec3::ZERO, "started inside");
    // t_min inside the grid, t_max before its end.
    let v: Vec<_> = Dda::new(&g, Vec3::new(-1.0, 0.5, 0.5), Vec3::X, 2.5, 4.5).collect();
    assert_eq!(v.iter().map(|v| v.voxel.x).collect::<Vec<_>>(), [1, 2, 3]);
    assert_eq!((v[0].t_enter, v[2].t_exit), (2.5, 4.5));
    // A camera a million voxels away still walks the right row.
    let far = walk(&g, Vec3::new(2.5, 3.5, -1e6), Vec3::Z);
    assert_eq!(far, (0..6).map(|k| UVec3::new(2, 3, k)).collect::<Vec<_>>());
}

#[test]
fn degenerate_rays_visit_nothing() {
    let g = unit_grid(UVec3::splat(4));
    for (o, d) in [
        (Vec3::ONE, Vec3::ZERO),
        (Vec3::ONE, Vec3::splat(1e-40)),
        (Vec3::NAN, Vec3::X),
        (Vec3::ONE, Vec3::new(f32::NAN, 1.0, 0.0)),
        (Vec3::ONE, Vec3::INFINITY),
    ] {
        assert!(walk(&g, o, d).is_empty(), "{o} {d}");
    }
    assert!(Dda::new(&g, Vec3::ONE, Vec3::X, 3.0, 1.0).next().is_none());
    assert!(Dda::new(&g, Vec3::ONE, Vec3::X, f32::NAN, 1.0).next().is_none());
}

#[test]
fn a_skipped_block_is_left_through_an_edge_as_stepping_leaves_it() {
    // From (1.5, 0, 0.5) along (1, 2, 0) the ray leaves the empty block [0, 2)² through x = 2
    // at t = 0.5, exactly where it crosses the block's middle plane y = 1: stepping moves both
    // axes at once into (2, 1, 0), entering through −y (the larger direction component).
    let dims = UVec3::new(8, 8, 2);
    let voxels = [UVec3::new(2, 1, 0), UVec3::new(5, 7, 0)];
    let map = BrickMap::from_voxels(dims, voxels.iter().map(|&c| (c, ()))).unwrap();
    let (grid, o, d) = (unit_grid(dims), Vec3::new(1.5, 0.0, 0.5), Vec3::new(1.0, 2.0, 0.0));
    let expected: Vec<DdaVoxel> =
        Dda::new(&grid, o, d, 0.0, f32::INFINITY).filter(|v| voxels.contains(&v.voxel)).collect();
    assert_eq!(expected[0].voxel, UVec3::new(2, 1, 0));
    assert_eq!(expected[0].entry_normal, IVec3::new(0, -1, 0));
    let masks = brick_masks(&map);
    let table = DenseBricks::new(&map).unwrap();
    let mut dda = Dda::new(&grid, o, d, 0.0, f32::INFINITY);
    let occupancy = Occupancy { bricks: &table, masks: &masks };
    assert_eq!(collect_walk(&map, || dda.next_occupied_voxel(&occupancy)), expected);
}

#[test]
fn an_empty_brick_block_is_left_through_an_edge_as_stepping_leaves_it() {
    // From (12, 0, 4.5) along (1, 2, 0) the ray leaves the empty 2³-brick block [0, 16)²
    // through x = 16 at t = 4, exactly where it crosses the block's middle plane y = 8:
    // stepping moves both axes at once, into brick (2, 1, 0) and its voxel (16, 8, 4),
    // entered through −y (the larger direction component).
    let dims = UVec3::new(48, 48, 16);
    let voxels = [UVec3::new(16, 8, 4), UVec3::new(17, 10, 4), UVec3::new(40, 40, 4)];
    let map = BrickMap::from_voxels(dims, voxels.iter().map(|&c| (c, ()))).unwrap();
    let (grid, o, d) = (unit_grid(dims), Vec3::new(12.0, 0.0, 4.5), Vec3::new(1.0, 2.0, 0.0));
    let expected: Vec<DdaVoxel> =
        Dda::new(&grid, o, d, 0.0, f32::INFINITY).filter(|v| voxels.contains(&v.voxel)).collect();
    assert_eq!(expected[0].voxel, UVec3::new(16, 8, 4));
    assert_eq!((expected[0].t_enter, expected[0].entry_normal), (4.0, IVec3::new(0, -1, 0)));
    let masks = brick_masks(&map);
    let table = DenseBricks::new(&map).unwrap();
    assert!(table.empty_block_f(Vec3A::new(1.0, 0.0, 0.0)), "the walk starts in an empty block");
    let mut dda = Dda::new(&grid, o, d, 0.0, f32::INFINITY);
    let occupancy = Occupancy { bricks: &table, masks: &masks };
    assert_eq!(collect_walk(&map, || dda.next_occupied_voxel(&occupancy)), expected);
}
