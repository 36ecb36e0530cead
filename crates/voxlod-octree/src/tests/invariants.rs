//! Each invariant of `Octree::validate`, broken on purpose: validate must name it.

use glam::UVec3;

use super::{build, payload_of};
use crate::octree::NONE;
use crate::{AveragePayload, Error, Octree, Payload};

/// Depth 4 (16³), dense levels 3 and 4, sparse levels 0–2; a diagonal streak and a blob.
fn tree() -> Octree<AveragePayload> {
    let mut coords: Vec<UVec3> = (0..16).map(|i| UVec3::new(i, i / 2, 15 - i)).collect();
    coords.extend((0..27).map(|i| UVec3::new(4 + i % 3, 9 + i / 3 % 3, 2 + i / 9)));
    coords.sort_by_key(|c| c.to_array());
    coords.dedup();
    build(UVec3::splat(16), &coords, 1)
}

#[track_caller]
fn expect_broken(tree: &Octree<AveragePayload>, level: u32, needle: &str) {
    match tree.validate() {
        Err(e @ Error::Invalid { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains(needle), "expected {needle:?}, got {msg}");
            let Error::Invalid { level: l, .. } = e else { unreachable!() };
            assert_eq!(l, level, "{msg}");
        }
        other => panic!("expected a broken invariant ({needle}), got {other:?}"),
    }
}

#[test]
fn a_built_tree_is_valid_and_morton_ordered() {
    let t = tree();
    assert_eq!((t.depth(), t.first_dense()), (4, 3));
    t.validate().unwrap();
    for l in 0..=t.depth() {
        let codes = t.node_codes(l);
        assert!(codes.windows(2).all(|w| w[0] < w[1]), "level {l}");
        assert_eq!(codes.len(), t.level(l).payload.len());
    }
    // Every input voxel is a level-0 node carrying its payload.
    let codes = t.node_codes(0);
    for c in [UVec3::new(3, 1, 12), UVec3::new(5, 10, 3)] {
        let i = codes.binary_search(&voxlod_format::morton::encode(c)).expect("stored");
        assert_eq!(t.level(0).payload[i], payload_of(c));
    }
}

#[test]
fn a_moved_child_tile_is_found() {
    let mut t = tree();
    let lv = &mut t.levels[2];
    let (a, b) = {
        let set: Vec<usize> = (0..lv.child.len()).filter(|&i| lv.child[i] != NONE).collect();
        (set[0], set[1])
    };
    lv.child.swap(a, b);
    expect_broken(&t, 2, "child tile at 8, expected 0");
}

#[test]
fn a_wrong_leaf_mask_bit_is_found() {
    let mut t = tree();
    let i = t.levels[1].mask.iter().position(|&m| m != 0 && m != 0xff).unwrap();
    let free = (0..8).find(|k| t.levels[1].mask[i] >> k & 1 == 0).unwrap();
    t.levels[1].mask[i] |= 1 << free;
    expect_broken(&t, 1, "masks mark");
}

#[test]
fn a_wrong_inner_mask_bit_is_found() {
    let mut t = tree();
    let i = t.levels[2].mask.iter().position(|&m| m != 0).unwrap();
    t.levels[2].mask[i] ^= 1 << t.levels[2].mask[i].trailing_zeros();
    expect_broken(&t, 2, "mask bit");
}

#[test]
fn a_mask_without_children_is_found() {
    let mut t = tree();
    let i = t.levels[3].child.iter().position(|&c| c == NONE).unwrap();
    t.levels[3].mask[i] = 1;
    expect_broken(&t, 3, "without a child tile");
}

#[test]
fn a_wrong_link_is_found() {
    let mut t = tree();
    let t0 = t.levels[0].tile_links.iter().position(|l| l[1] != NONE).unwrap();
    t.levels[0].tile_links[t0][1] = NONE;
    // Node k = 2 (+y bit set) of that tile now has no +y neighbour.
    expect_broken(&t, 0, "link 1 is");
    let mut t = tree();
    t.levels[0].tile_links[t0][2] = 3;
    expect_broken(&t, 0, "tile link 3 is not the start of a tile");
}

#[test]
fn a_parent_that_is_not_the_prefilter_of_its_children_is_found() {
    for level in [1usize, 3, 4] {
        let mut t = tree();
        let i = t.levels[level].payload.iter().position(|p| p.opacity > 0.0).unwrap();
        t.levels[level].payload[i].opacity += 1e-3;
        expect_broken(&t, level as u32, "differs from the prefilter");
    }
}

#[test]
fn an_unoccupied_node_with_a_payload_is_found() {
    let mut t = tree();
    // A leaf slot its parent's mask says is empty, given content (and its parent updated).
    let p = t.levels[1].mask.iter().position(|&m| m != 0 && m != 0xff).unwrap();
    let k = (0..8).find(|k| t.levels[1].mask[p] >> k & 1 == 0).unwrap();
    let leaf = t.levels[1].child[p] as usize + k;
    t.levels[0].payload[leaf] = payload_of(UVec3::ZERO);
    expect_broken(&t, 1, "differs from the prefilter");
    // With every ancestor re-filtered, only the mask contradicts the content.
    refilter(&mut t);
    expect_broken(&t, 0, "unoccupied leaf with a payload");
}

/// Recomputes every parent payload from its children, bottom-up.
fn refilter(t: &mut Octree<AveragePayload>) {
    for l in 1..=t.depth() as usize {
        let (lower, upper) = t.levels.split_at_mut(l);
        let (below, lv) = (&lower[l - 1], &mut upper[0]);
        for i in 0..lv.payload.len() {
            let kids: [AveragePayload; 8] = std::array::from_fn(|k| {
                let n = if lv.child.is_empty() {
                    8 * i + k
                } else if lv.child[i] == NONE {
                    return AveragePayload::empty();
                } else {
                    lv.child[i] as usize + k
                };
                below.payload[n]
            });
            lv.payload[i] = AveragePayload::prefilter(&kids);
        }
    }
}

#[test]
fn non_finite_payloads_are_found() {
    let mut t = tree();
    t.levels[2].payload[0].color_alpha[1] = f32::NAN;
    expect_broken(&t, 2, "payload");
}

#[test]
fn an_incomplete_dense_level_is_found() {
    let mut t = tree();
    t.levels[3].payload.pop();
    expect_broken(&t, 3, "dense level holds 7 of 8");
}

/// Removing a tile that holds only closure nodes (no occupied one), with every pointer and link
/// rewired consistently, leaves an occupied node without a backward neighbour.
#[test]
fn a_missing_closure_node_is_found() {
    let mut t = tree();
    let parent = &t.levels[1];
    let p = (0..parent.child.len())
        .find(|&i| parent.child[i] != NONE && parent.mask[i] == 0)
        .expect("a tile of closure nodes only");
    let start = parent.child[p];
    t.levels[1].child[p] = NONE;
    for c in &mut t.levels[1].child {
        if *c != NONE && *c > start {
            *c -= 8;
        }
    }
    let leaves = &mut t.levels[0];
    leaves.payload.drain(start as usize..start as usize + 8);
    leaves.tile_links.remove(start as usize / 8);
    for link in leaves.tile_links.iter_mut().flatten() {
        if *link != NONE && *link >= start {
            *link = if *link < start + 8 { NONE } else { *link - 8 };
        }
    }
    assert!(t.levels[1].payload[p].max_abs_diff(&AveragePayload::empty()) == 0.0);
    expect_broken(&t, 0, "lacks backward neighbour");
}

/// The node set of every sparse level is exactly the 2×2×2 tiles of the parents of the
/// backward closure of the occupied nodes (the `octree` module's definition), computed here by
/// brute force from the input voxels.
#[test]
fn sparse_levels_hold_exactly_the_tiles_of_the_backward_closure() {
    use std::collections::BTreeSet;
    for (dims, dense) in [(UVec3::splat(16), 1), (UVec3::new(13, 6, 16), 0), (UVec3::splat(32), 2)]
    {
        let coords: Vec<UVec3> = (0..60u32)
            .map(|i| [i * 7 % dims.x, (i * i + 3) % dims.y, i * 5 / 3 % dims.z])
            .collect::<BTreeSet<_>>()
            .into_iter()
            .map(UVec3::from)
            .collect();
        let t = build(dims, &coords, dense);
        for l in 0..t.first_dense() {
            let occupied: BTreeSet<[u32; 3]> =
                coords.iter().map(|&c| (c >> l).to_array()).collect();
            let mut parents = BTreeSet::new();
            for o in occupied {
                let o = UVec3::from(o);
                for d in 0..8u32 {
                    let e = UVec3::new(d & 1, d >> 1 & 1, d >> 2 & 1);
                    if o.cmpge(e).all() {
                        parents.insert(voxlod_format::morton::encode((o - e) >> 1));
                    }
                }
            }
            let want: Vec<u64> =
                parents.iter().flat_map(|p| (0..8).map(move |k| p << 3 | k)).collect();
            assert_eq!(t.node_codes(l), want, "level {l} of {dims}");
        }
    }
}

/// The SGGX and directional payloads build valid trees too (validate checks their prefilter),
/// and a wall's directional opacity survives to the root where its coverage does not.
#[test]
fn sggx_and_directional_trees_validate() {
    use crate::{Directional, SggxPayload};
    use glam::{Mat3, Vec3};
    // A one-voxel-thick wall x = 0 across a 8³ grid.
    let wall: Vec<UVec3> = (0..64).map(|i| UVec3::new(0, i % 8, i / 8)).collect();
    let g = super::grid(UVec3::splat(8));
    let opts = crate::BuildOptions { depth: None, dense_log2: 1 };
    let s = Octree::build(
        g,
        wall.iter().map(|&c| {
            (c, SggxPayload::new(Mat3::from_diagonal(Vec3::new(1.0, 0.1, 0.1)), Vec3::ONE, 1.0))
        }),
        &opts,
    )
    .unwrap();
    s.validate().unwrap();
    let opaque = crate::AveragePayload::new(Vec3::ONE, Vec3::X, 1.0);
    let d =
        Octree::build(g, wall.iter().map(|&c| (c, Directional::isotropic(opaque))), &opts).unwrap();
    d.validate().unwrap();
    // Along ±x every column crosses the wall: opaque. Along ±y, ±z one column in 8 lies in it
    // (true opacity 1/8), but the rule composites *averaged* child opacities, assuming their
    // coverage uncorrelated: level 1 gives ½ to the nodes holding the wall, level 2
    // ½·(½ + ½ − ¼) = 0.375, the root ½·(0.375 + 0.625·0.375) = 0.3046875 — the documented
    // over-estimate of the standard scheme for a wall seen edge-on.
    let root = d.level(3).payload[0];
    let edge = 0.5 * (0.375 + 0.625 * 0.375);
    let want = [1.0, 1.0, edge, edge, edge, edge];
    assert!(root.opacity.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6), "{root:?}");
    assert!((root.inner.opacity - 0.125).abs() < 1e-6);
}
