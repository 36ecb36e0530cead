//! The octree against the obvious structure: a dense grid of the voxels, box-averaged to each
//! level, sampled trilinearly with zeros outside (the sampling convention of `sample.rs`).

use std::collections::HashMap;

use glam::{IVec3, UVec3, Vec3};
use proptest::prelude::*;

use super::{assert_close, build, payload_of};
use crate::{AveragePayload, Octree, Payload};

/// The dense reference: level-`l` node values as the mean of the `8^l` voxels they cover.
struct Dense {
    levels: Vec<HashMap<IVec3, AveragePayload>>,
}

impl Dense {
    fn new(coords: &[UVec3], depth: u32) -> Self {
        let levels = (0..=depth)
            .map(|l| {
                let mut m: HashMap<IVec3, AveragePayload> = HashMap::new();
                let w = 1.0 / (1u64 << (3 * l)) as f32;
                for &c in coords {
                    let node = (c >> l).as_ivec3();
                    m.entry(node)
                        .or_insert_with(AveragePayload::empty)
                        .add_scaled(&payload_of(c), w);
                }
                m
            })
            .collect();
        Self { levels }
    }

    /// Trilinear between node centres, zero where there is no node.
    fn sample(&self, pos: Vec3, level: u32) -> AveragePayload {
        let u = pos / (1u64 << level) as f32 - 0.5;
        let base = u.floor();
        let f = u - base;
        let mut out = AveragePayload::empty();
        for e in 0..8 {
            let off = IVec3::new(e & 1, e >> 1 & 1, e >> 2 & 1);
            let w = Vec3::select(off.cmpeq(IVec3::ZERO), 1.0 - f, f).element_product();
            if let Some(p) = self.levels[level as usize].get(&(base.as_ivec3() + off)) {
                out.add_scaled(p, w);
            }
        }
        out
    }
}

fn scene() -> impl Strategy<Value = (UVec3, Vec<UVec3>, u32)> {
    (1u32..=12, 1u32..=12, 1u32..=12, 0u32..=3).prop_flat_map(|(x, y, z, dense)| {
        let dims = UVec3::new(x, y, z);
        let coord = (0..x, 0..y, 0..z).prop_map(|(a, b, c)| UVec3::new(a, b, c));
        (
            Just(dims),
            proptest::collection::btree_set(coord.prop_map(|c| c.to_array()), 0..60),
            Just(dense),
        )
            .prop_map(|(d, set, dense)| (d, set.into_iter().map(UVec3::from).collect(), dense))
    })
}

fn positions(dims: UVec3) -> impl Strategy<Value = Vec<Vec3>> {
    let hi = dims.as_vec3() + 2.0;
    proptest::collection::vec(
        (-2.0f32..hi.x, -2.0f32..hi.y, -2.0f32..hi.z).prop_map(|(x, y, z)| Vec3::new(x, y, z)),
        1..24,
    )
}

proptest! {
    /// Level 0 equals trilinear sampling of the dense voxel grid; level `l` equals trilinear
    /// sampling of the grid box-averaged over `2^l`-voxel blocks; for every dense/sparse split.
    #[test]
    fn sampling_equals_the_dense_grid(
        (dims, coords, dense) in scene(),
        pos in positions(UVec3::splat(12)),
    ) {
        let tree = build(dims, &coords, dense);
        let reference = Dense::new(&coords, tree.depth());
        for &p in &pos {
            for level in 0..=tree.depth() {
                let got = tree.sample_level(p, level);
                let want = reference.sample(p, level);
                let d = got.max_abs_diff(&want);
                prop_assert!(d <= 2e-6, "level {level} at {p}: differ by {d}\n{got:?}\n{want:?}");
            }
        }
    }

    /// The quadrilinear sample is the linear blend of the two levels around the footprint's
    /// level.
    #[test]
    fn quadrilinear_blends_two_levels(
        (dims, coords, dense) in scene(),
        p in (0.0f32..12.0, 0.0f32..12.0, 0.0f32..12.0),
        diameter in 0.0f32..40.0,
    ) {
        let p = Vec3::new(p.0, p.1, p.2);
        let tree = build(dims, &coords, dense);
        let level = tree.level_for_diameter(diameter);
        let l0 = level.floor() as u32;
        let t = level - l0 as f32;
        let mut want = AveragePayload::empty();
        want.add_scaled(&tree.sample_level(p, l0), 1.0 - t);
        want.add_scaled(&tree.sample_level(p, (l0 + 1).min(tree.depth())), t);
        let got = tree.sample(p, diameter);
        prop_assert!(got.max_abs_diff(&want) <= 1e-6, "{got:?} vs {want:?}");
    }
}

#[test]
fn footprint_diameter_maps_to_a_clamped_fractional_level() {
    let tree = build(UVec3::splat(16), &[UVec3::ONE], 1);
    assert_eq!(tree.depth(), 4);
    for (d, l) in [(0.0, 0.0), (f32::NAN, 0.0), (0.5, 0.0), (1.0, 0.0), (2.0, 1.0), (8.0, 3.0)] {
        assert_eq!(tree.level_for_diameter(d), l, "diameter {d}");
    }
    assert_eq!(tree.level_for_diameter(1e9), 4.0);
    assert_eq!(tree.level_for_diameter(f32::INFINITY), 4.0);
    assert!((tree.level_for_diameter(3.0) - 3f32.log2()).abs() < 1e-6);
}

#[test]
fn non_finite_positions_sample_empty_space() {
    let tree = build(UVec3::splat(8), &[UVec3::ZERO, UVec3::ONE], 1);
    for p in [Vec3::NAN, Vec3::new(f32::INFINITY, 0.5, 0.5), Vec3::splat(-1e30), Vec3::splat(1e30)]
    {
        assert_eq!(tree.sample(p, 1.0), AveragePayload::empty(), "{p}");
        assert_eq!(tree.sample(p, f32::NAN), AveragePayload::empty(), "{p}");
    }
}

#[test]
fn dense_and_sparse_storage_sample_alike() {
    let mut coords: Vec<UVec3> =
        (0..40u32).map(|i| UVec3::new(i * 7 % 16, i * i % 13, i / 3)).collect();
    coords.sort_by_key(|c| c.to_array());
    coords.dedup();
    let dense = build(UVec3::splat(16), &coords, 4);
    let sparse = build(UVec3::splat(16), &coords, 0);
    assert_eq!((dense.first_dense(), sparse.first_dense()), (0, 4));
    for i in 0..500 {
        let p = Vec3::new(i as f32 * 0.137 % 17.0, i as f32 * 0.291 % 17.0, i as f32 * 0.05 % 17.0);
        for l in 0..=4 {
            let (a, b) = (dense.sample_level(p, l), sparse.sample_level(p, l));
            assert_close(&a, &b, 0.0, &format!("level {l} at {p}"));
        }
    }
}

#[test]
fn world_sampling_goes_through_the_grid() {
    let coords = [UVec3::new(2, 3, 4)];
    let grid =
        voxlod_format::GridSpec::new(glam::DVec3::new(-1.0, 2.0, 0.5), 0.25, UVec3::splat(8))
            .unwrap();
    let tree =
        Octree::build(grid, coords.map(|c| (c, payload_of(c))), &Default::default()).unwrap();
    let centre = grid.voxel_center(coords[0]);
    assert_close(&tree.sample_world(centre, 0.1), &payload_of(coords[0]), 1e-6, "voxel centre");
    // A footprint of two voxels reads level 1: the voxel's parent holds an eighth of it.
    // Parent node (1, 1, 2) of level 1 covers voxels [2, 4) × [2, 4) × [4, 6).
    let parent = grid.origin + glam::DVec3::new(3.0, 3.0, 5.0) * 0.25;
    let mut eighth = AveragePayload::empty();
    eighth.add_scaled(&payload_of(coords[0]), 0.125);
    assert_close(&tree.sample_world(parent, 0.5), &eighth, 1e-6, "parent centre");
}
