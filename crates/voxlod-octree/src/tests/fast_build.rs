//! The linear top-down build (`build.rs`) against the straightforward sort-based build of
//! `build::reference`: identical octrees (every array of every level, bit for bit) and the same
//! errors.

use glam::UVec3;
use proptest::prelude::*;
use voxlod_format::morton;

use super::{grid, payload_of};
use crate::build::reference;
use crate::octree::NONE;
use crate::{AveragePayload, BuildOptions, Octree};

fn sorted(coords: &[UVec3]) -> Vec<(u64, AveragePayload)> {
    let mut v: Vec<(u64, AveragePayload)> =
        coords.iter().map(|&c| (morton::encode(c), payload_of(c))).collect();
    v.sort_unstable_by_key(|e| e.0);
    v.dedup_by_key(|e| e.0);
    v
}

#[track_caller]
fn assert_same_build(dims: UVec3, coords: &[UVec3], options: &BuildOptions) {
    let voxels = sorted(coords);
    let fast = Octree::from_morton_sorted(grid(dims), voxels.clone(), options);
    let slow = reference::from_morton_sorted(grid(dims), voxels, options);
    let (fast, (slow, node_links)) = match (fast, slow) {
        (Ok(f), Ok(s)) => (f, s),
        (f, s) => {
            assert_eq!(f.err().map(|e| e.to_string()), s.err().map(|e| e.to_string()));
            return;
        }
    };
    assert_eq!(
        (fast.depth, fast.first_dense, fast.voxels),
        (slow.depth, slow.first_dense, slow.voxels)
    );
    assert_eq!(fast.levels.len(), slow.levels.len());
    for (l, (f, s)) in fast.levels.iter().zip(&slow.levels).enumerate() {
        let what = format!("level {l} of {dims} ({options:?})");
        assert_eq!((f.res_log2, f.dense), (s.res_log2, s.dense), "{what}");
        assert_eq!(f.child, s.child, "child pointers, {what}");
        assert_eq!(f.mask, s.mask, "masks, {what}");
        assert_eq!(f.tile_links, s.tile_links, "tile links, {what}");
        // Every node's neighbour from the tile links against the reference's per-node links.
        let view = fast.level(l as u32);
        for (i, want) in node_links[l].iter().enumerate() {
            let got = [0, 1, 2].map(|a| view.neighbour(i as u32, a).unwrap_or(NONE));
            assert_eq!(&got, want, "node {i}, {what}");
        }
        assert_eq!(node_links[l].len(), if f.dense { 0 } else { f.payload.len() }, "{what}");
        assert!(f.payload == s.payload, "payloads, {what}");
    }
    fast.validate().unwrap();
}

/// A sphere shell of radius `r` voxels in a `res³` grid (a surface: the closure's worst ratio).
fn shell(res: u32, r: f32) -> Vec<UVec3> {
    let c = res as f32 / 2.0;
    let mut v = Vec::new();
    for z in 0..res {
        for y in 0..res {
            for x in 0..res {
                let p = UVec3::new(x, y, z).as_vec3() + 0.5 - c;
                if (p.length() - r).abs() <= 0.5 {
                    v.push(UVec3::new(x, y, z));
                }
            }
        }
    }
    v
}

#[test]
fn fast_build_equals_the_reference_on_shells_and_blocks() {
    let s = shell(48, 21.0);
    for dense in [0, 1, 2, 3, 4, 6] {
        assert_same_build(UVec3::splat(48), &s, &BuildOptions { depth: None, dense_log2: dense });
    }
    // A solid block touching the max faces, and one touching the origin.
    let block: Vec<UVec3> =
        (0..1000).map(|i| UVec3::new(i % 10 + 22, i / 10 % 10 + 22, i / 100 + 22)).collect();
    assert_same_build(UVec3::splat(32), &block, &BuildOptions { depth: None, dense_log2: 2 });
    let origin: Vec<UVec3> = (0..343).map(|i| UVec3::new(i % 7, i / 7 % 7, i / 49)).collect();
    assert_same_build(UVec3::splat(32), &origin, &BuildOptions { depth: Some(7), dense_log2: 1 });
}

#[test]
fn fast_build_equals_the_reference_deep_and_sparse() {
    let dims = UVec3::splat(1 << 16);
    let coords: Vec<UVec3> = (0..300u32)
        .map(|i| {
            let h = |k: u32| {
                (i.wrapping_add(1).wrapping_mul(0x9e37_79b9) ^ k).wrapping_mul(0x85eb_ca6b)
            };
            UVec3::new(h(1) >> 16, h(2) >> 16, h(3) >> 16)
        })
        .collect();
    assert_same_build(dims, &coords, &BuildOptions { depth: Some(16), dense_log2: 3 });
    let max = UVec3::splat(1 << 21);
    let corners = [UVec3::ZERO, max - 1, UVec3::new(123_456, 7, 2_000_000), UVec3::new(1, 0, 1)];
    assert_same_build(max, &corners, &BuildOptions { depth: None, dense_log2: 1 });
    assert_same_build(UVec3::splat(8), &[], &BuildOptions::default());
    assert_same_build(UVec3::ONE, &[UVec3::ZERO], &BuildOptions::default());
}

proptest! {
    #[test]
    fn fast_build_equals_the_reference(
        (dims, coords, dense) in (1u32..=24, 1u32..=24, 1u32..=24, 0u32..=4).prop_flat_map(|(x, y, z, dense)| {
            let coord = (0..x, 0..y, 0..z).prop_map(|(a, b, c)| UVec3::new(a, b, c));
            (Just(UVec3::new(x, y, z)), proptest::collection::vec(coord, 0..300), Just(dense))
        }),
        extra_depth in 0u32..=2,
    ) {
        let needed = dims.max_element().next_power_of_two().trailing_zeros();
        assert_same_build(dims, &coords, &BuildOptions { depth: Some(needed + extra_depth), dense_log2: dense });
    }
}
