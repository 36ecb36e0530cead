//! Extremes: empty input, one voxel, voxels on the grid's max corner, a depth-16 octree over a
//! sparse scene (memory follows occupied voxels, not bounds), and bad input naming its voxel.

use glam::{UVec3, Vec3};
use voxlod_format::{BrickMap, morton};

use super::{assert_close, build, grid, payload_of};
use crate::{AveragePayload, BuildOptions, Error, MAX_DEPTH, Octree, Payload};

#[test]
fn an_empty_input_builds_an_empty_valid_tree() {
    for dense in [0, 2, 6] {
        let t = build(UVec3::new(5, 9, 3), &[], dense);
        t.validate().unwrap();
        assert!(t.is_empty());
        assert_eq!(t.depth(), 4);
        assert_eq!(t.sample(Vec3::splat(2.5), 1.0), AveragePayload::empty());
        assert_eq!(t.sample(Vec3::splat(2.5), 9.0), AveragePayload::empty());
        let s = t.memory_stats();
        assert_eq!((s.sparse_bytes(), s.sparse_nodes(), s.per_voxel(s.total_bytes())), (0, 0, 0.0));
    }
}

#[test]
fn a_single_voxel_is_found_at_every_level() {
    let c = UVec3::new(5, 0, 6);
    let t = build(UVec3::splat(8), &[c], 0);
    assert_eq!((t.depth(), t.first_dense()), (3, 3));
    let p = payload_of(c);
    assert_close(&t.sample(c.as_vec3() + 0.5, 0.0), &p, 1e-7, "leaf centre");
    // Level l: the ancestor's centre holds p / 8^l.
    for l in 1..=3u32 {
        let centre = ((c >> l).as_vec3() + 0.5) * (1u32 << l) as f32;
        let mut want = AveragePayload::empty();
        want.add_scaled(&p, 1.0 / (1u32 << (3 * l)) as f32);
        assert_close(&t.sample_level(centre, l), &want, 1e-7, &format!("level {l}"));
    }
    // The leaf's 7 backward neighbours in range exist (here: x−1 and z−1 only, y = 0), in 2×2×2
    // tiles, so the leaf level holds the tiles of parents (2,0,3), (2,0,2), ... four tiles.
    let coords = t.node_coords(0);
    for b in [UVec3::new(4, 0, 6), UVec3::new(5, 0, 5), UVec3::new(4, 0, 5)] {
        assert!(coords.contains(&b), "backward neighbour {b}");
    }
    assert_eq!(coords.len(), 8 * 2, "parents (2,0,3) and (2,0,2)");
}

#[test]
fn voxels_on_the_max_corner_sample_and_fade_out() {
    for dims in [UVec3::splat(8), UVec3::new(5, 7, 9)] {
        let corner = dims - 1;
        let t = build(dims, &[corner, UVec3::ZERO], 1);
        t.validate().unwrap();
        let p = payload_of(corner);
        assert_close(&t.sample(corner.as_vec3() + 0.5, 1.0), &p, 1e-7, "corner centre");
        // Half a voxel outside the grid's max face: half of the voxel, trilinear against zero
        // (inside the virtual cube for 5×7×9, outside it for 8³).
        let out = corner.as_vec3() + Vec3::new(1.0, 0.5, 0.5);
        let mut half = AveragePayload::empty();
        half.add_scaled(&p, 0.5);
        assert_close(&t.sample_level(out, 0), &half, 1e-7, "max face");
        assert_eq!(t.sample_level(out + 1.0, 0), AveragePayload::empty());
        // The min corner voxel fades the same way below 0.
        assert_close(
            &t.sample_level(Vec3::new(0.0, 0.5, 0.5), 0),
            &{
                let mut h = AveragePayload::empty();
                h.add_scaled(&payload_of(UVec3::ZERO), 0.5);
                h
            },
            1e-7,
            "min face",
        );
    }
}

/// Scattered voxels with 21-bit-ish pseudo-random coordinates inside a `2^depth` cube.
fn scattered(n: u32, depth: u32) -> Vec<UVec3> {
    let mask = (1u32 << depth) - 1;
    let mut v: Vec<UVec3> = (0..n)
        .map(|i| {
            let h = |k: u32| {
                (i.wrapping_add(1).wrapping_mul(0x9e37_79b9) ^ k).wrapping_mul(0x85eb_ca6b)
            };
            UVec3::new(h(1) >> 7, h(2) >> 9, h(3) >> 11) & UVec3::splat(mask)
        })
        .collect();
    v.sort_by_key(|c| morton::encode(*c));
    v.dedup();
    v
}

/// Depth 16: 65536³ virtual voxels (2.8·10¹⁴), a few hundred occupied. It builds, samples, and
/// its memory grows with the occupied voxels: doubling them about doubles the sparse bytes, and
/// per voxel it is bounded by the closure's worst case (8 tiles of 8 nodes per sparse level),
/// far from anything proportional to the bounds.
#[test]
fn depth_16_over_a_sparse_scene_fits_because_only_occupied_nodes_exist() {
    let options = BuildOptions { depth: Some(16), dense_log2: 3 };
    let dims = UVec3::splat(1 << 16);
    let build_n = |n| {
        let coords = scattered(n, 16);
        let voxels = coords.iter().map(|&c| (c, payload_of(c)));
        (Octree::build(grid(dims), voxels, &options).unwrap(), coords)
    };
    let (small, _) = build_n(200);
    let (large, coords) = build_n(400);
    assert_eq!(large.depth(), 16);
    let c = coords[17];
    assert_close(&large.sample(c.as_vec3() + 0.5, 1.0), &payload_of(c), 1e-7, "a leaf");
    let (s, l) = (small.memory_stats(), large.memory_stats());
    let ratio = l.sparse_bytes() as f64 / s.sparse_bytes() as f64;
    assert!(
        (1.85..=2.05).contains(&ratio),
        "sparse bytes {} → {}: ratio {ratio}",
        s.sparse_bytes(),
        l.sparse_bytes()
    );
    let node_bytes = (size_of::<AveragePayload>() + 4 + 1 + 12) as f64;
    let worst = 64.0 * 13.0 * node_bytes;
    assert!(
        l.per_voxel(l.sparse_bytes()) < worst,
        "{} bytes per voxel",
        l.per_voxel(l.sparse_bytes())
    );
    assert!(l.total_bytes() < 64 << 20, "{} bytes", l.total_bytes());
    assert_eq!(l.levels.len(), 17);
    assert_eq!(l.levels[0].occupied, coords.len() as u64);
}

#[test]
fn bad_input_is_an_error_naming_the_voxel() {
    let g = grid(UVec3::splat(8));
    let opts = BuildOptions::default();
    let ok = AveragePayload::new(Vec3::ONE, Vec3::Z, 0.5);
    let mut bad = ok;
    bad.normal_alpha[2] = f32::NAN;
    let e = Octree::build(g, [(UVec3::ONE, ok), (UVec3::new(3, 4, 5), bad)], &opts).unwrap_err();
    assert!(
        matches!(e, Error::InvalidPayload { coord, .. } if coord == UVec3::new(3, 4, 5)),
        "{e}"
    );
    assert!(e.to_string().contains("[3, 4, 5]") && e.to_string().contains("NaN"), "{e}");
    let e = Octree::build(g, [(UVec3::ONE, AveragePayload::new(Vec3::ONE, Vec3::Z, 1.5))], &opts)
        .unwrap_err();
    assert!(e.to_string().contains("opacity outside"), "{e}");
    let e = Octree::build(g, [(UVec3::new(2, 8, 0), ok)], &opts).unwrap_err();
    assert!(matches!(e, Error::OutOfBounds { coord, .. } if coord == UVec3::new(2, 8, 0)), "{e}");
    let e = Octree::build(g, [(UVec3::ONE, ok), (UVec3::ONE, ok)], &opts).unwrap_err();
    assert!(matches!(e, Error::DuplicateVoxel { coord } if coord == UVec3::ONE), "{e}");
    let sorted = vec![(morton::encode(UVec3::ONE), ok), (morton::encode(UVec3::ZERO), ok)];
    let e = Octree::from_morton_sorted(g, sorted, &opts).unwrap_err();
    assert!(matches!(e, Error::OutOfOrder { coord, .. } if coord == UVec3::ZERO), "{e}");
    let deep = BuildOptions { depth: Some(MAX_DEPTH + 1), ..opts };
    assert!(matches!(
        Octree::<AveragePayload>::build(g, [], &deep),
        Err(Error::TooDeep { requested: 22, .. })
    ));
    let shallow = BuildOptions { depth: Some(2), ..opts };
    assert!(matches!(
        Octree::<AveragePayload>::build(g, [], &shallow),
        Err(Error::GridDoesNotFit { depth: 2, .. })
    ));
    let dense = BuildOptions { dense_log2: 9, ..opts };
    assert!(matches!(
        Octree::<AveragePayload>::build(g, [], &dense),
        Err(Error::DenseTooLarge { .. })
    ));
    let mut broken = g;
    broken.voxel_size = f64::NAN;
    assert!(matches!(Octree::<AveragePayload>::build(broken, [], &opts), Err(Error::Grid(_))));
}

#[test]
fn the_deepest_octree_builds_over_a_few_voxels() {
    let dims = UVec3::splat(1 << MAX_DEPTH);
    let coords = [UVec3::ZERO, dims - 1, UVec3::new(123_456, 7, 2_000_000)];
    let t = Octree::build(
        grid(dims),
        coords.map(|c| (c, payload_of(c))),
        &BuildOptions { depth: None, dense_log2: 1 },
    )
    .unwrap();
    assert_eq!(t.depth(), 21);
    // Grid coordinates of 2²¹ still resolve voxel centres in f32 (22 bits of integer part).
    let c = coords[2];
    assert_close(&t.sample(c.as_vec3() + 0.5, 1.0), &payload_of(c), 1e-7, "deep leaf");
}

#[test]
fn a_brick_map_builds_the_same_tree() {
    let coords: Vec<UVec3> =
        (0..50u32).map(|i| UVec3::new(i % 13, i * 7 % 11, i * 3 % 9)).collect();
    let mut coords = coords;
    coords.sort_by_key(|c| c.to_array());
    coords.dedup();
    let map = BrickMap::from_voxels(UVec3::new(13, 11, 9), coords.iter().map(|&c| (c, c))).unwrap();
    let a = Octree::from_brick_map(grid(map.dims()), &map, |&c| payload_of(c), &Default::default())
        .unwrap();
    let b = build(map.dims(), &coords, 6);
    for l in 0..=a.depth() {
        assert_eq!(a.level(l).payload, b.level(l).payload, "level {l}");
        assert_eq!(a.node_codes(l), b.node_codes(l), "level {l}");
    }
}
