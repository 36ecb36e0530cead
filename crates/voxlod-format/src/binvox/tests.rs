//! Tests of binvox export and import: the axis order against hand-written bytes, round trips,
//! and malformed files.

use std::collections::BTreeSet;
use std::path::Path;

use glam::{DVec3, UVec3};
use proptest::prelude::*;

use super::*;

fn path() -> &'static Path {
    Path::new("<test>")
}

fn file(header: &str, runs: &[u8]) -> Vec<u8> {
    let mut b = header.as_bytes().to_vec();
    b.extend_from_slice(runs);
    b
}

const CUBE2: &str = "#binvox 1\ndim 2 2 2\ntranslate 0.0 0.0 0.0\nscale 1.0\ndata\n";

fn malformed_at(result: Result<impl std::fmt::Debug>) -> (u64, String) {
    match result {
        Err(Error::Malformed { offset, reason, format: "binvox", .. }) => (offset, reason),
        other => panic!("expected Error::Malformed, got {other:?}"),
    }
}

/// binvox's `get_index` is `x·D² + z·D + y` (y fastest); trimesh reads the same bytes by
/// reshaping to (x, z, y) and transposing. In a 2³ cube a single voxel at (1,0,0) is index 4,
/// (0,1,0) is index 1, (0,0,1) is index 2: we read and write exactly those bytes.
#[test]
fn axis_order_is_binvox_order() {
    let unit = GridSpec::new(DVec3::ZERO, 0.5, UVec3::splat(2)).unwrap();
    for (voxel, runs) in [
        (UVec3::new(1, 0, 0), [0u8, 4, 1, 1, 0, 3]),
        (UVec3::new(0, 1, 0), [0, 1, 1, 1, 0, 6]),
        (UVec3::new(0, 0, 1), [0, 2, 1, 1, 0, 5]),
    ] {
        let bytes = file(CUBE2, &runs);
        let (grid, map) = decode(&bytes, path()).unwrap();
        assert_eq!(grid, unit);
        assert_eq!(map.coords().collect::<Vec<_>>(), [voxel], "runs {runs:?}");
        let ours = BrickMap::from_voxels(unit.dims, [(voxel, ())]).unwrap();
        assert_eq!(encode(&unit, &ours).unwrap(), bytes, "voxel {voxel}");
    }
}

#[test]
fn header_variants_that_tools_write_are_read() {
    // No translate/scale (viewvox files), CRLF line ends, extra spaces, version 2 values.
    let (grid, map) = decode(&file("#binvox 1\r\ndim 2 2 2\r\ndata\r\n", &[1, 8]), path()).unwrap();
    assert_eq!((grid.origin, grid.voxel_size), (DVec3::ZERO, 0.5));
    assert_eq!(map.len(), 8);
    let header = "#binvox  2\ndim  2 2 2 \nscale 4\ntranslate -1 2e0 3.5\ndata\n";
    let (grid, map) = decode(&file(header, &[0, 7, 9, 1]), path()).unwrap();
    assert_eq!((grid.origin, grid.voxel_size), (DVec3::new(-1.0, 2.0, 3.5), 2.0));
    assert_eq!(map.coords().collect::<Vec<_>>(), [UVec3::ONE]);
    let info = decode_info(&file(header, &[0, 7, 9, 1]), path()).unwrap();
    assert_eq!((info.header.version, info.header.dim, info.occupied), (2, 2, 1));
}

#[test]
fn malformed_headers_are_errors_at_their_line() {
    let runs = [0u8, 8];
    let cases: &[(&str, u64)] = &[
        ("", 0),
        ("#binvox", 0),
        ("solid cube\n", 0),
        ("#binvox\n", 0),
        ("#binvox 0\n", 0),
        ("#binvox 1 2\n", 0),
        ("#binvox 1\ndata\n", 15),
        ("#binvox 1\ndim 2 2 3\ndata\n", 10),
        ("#binvox 1\ndim 0 0 0\ndata\n", 10),
        ("#binvox 1\ndim -2 -2 -2\ndata\n", 10),
        ("#binvox 1\ndim 2 2\ndata\n", 10),
        ("#binvox 1\ndim 4194304 4194304 4194304\ndata\n", 10),
        ("#binvox 1\ndim 2 2 2\ndim 2 2 2\ndata\n", 20),
        ("#binvox 1\ndim 2 2 2\ntranslate 0 0 nan\ndata\n", 20),
        ("#binvox 1\ndim 2 2 2\ntranslate 0 0\ndata\n", 20),
        ("#binvox 1\ndim 2 2 2\nscale 0\ndata\n", 20),
        ("#binvox 1\ndim 2 2 2\nscale -1\ndata\n", 20),
        ("#binvox 1\ndim 2 2 2\nscale inf\ndata\n", 20),
        ("#binvox 1\ndim 2 2 2\nscale 5e-324\ndata\n", 38),
        ("#binvox 1\ndim 2 2 2\ncolour 1\ndata\n", 20),
        ("#binvox 1\ndim 2 2 2\n\ndata\n", 20),
        ("#binvox 1\ndim 2 2 2\ndata now\n", 20),
        ("#binvox 1\ndim 2 2 2\ndata", 20),
        ("#binvox 1\ndim 2 2 2\n\u{e9}\ndata\n", 20),
    ];
    for &(header, offset) in cases {
        let (at, reason) = malformed_at(decode(&file(header, &runs), path()));
        assert_eq!(at, offset, "{header:?}: {reason}");
    }
    // A header that never ends within the limit.
    let long = format!("#binvox 1\ndim 2 2 2\ntranslate 0 0 {}\ndata\n", "0".repeat(5000));
    assert!(malformed_at(decode(&file(&long, &runs), path())).1.contains("within"));
    match decode(&file("#binvox 3\ndim 2 2 2\ndata\n", &runs), path()) {
        Err(Error::UnsupportedVersion { found: 3, supported: 2, format: "binvox", .. }) => {}
        other => panic!("expected UnsupportedVersion, got {other:?}"),
    }
}

#[test]
fn malformed_runs_are_errors_at_their_byte() {
    let data = CUBE2.len() as u64;
    let cases: &[(&[u8], u64, &str)] = &[
        (&[], data, "truncated"),
        (&[0, 7], data + 2, "truncated"),
        (&[0, 7, 1], data + 2, "truncated"),
        (&[0, 0, 0, 8], data + 1, "length 0"),
        (&[2, 8], data, "value 2"),
        (&[0, 7, 1, 2], data + 3, "overruns"),
        (&[0, 9], data + 1, "overruns"),
        (&[0, 8, 0], data + 2, "after the last run"),
        (&[0, 8, b'\n'], data + 2, "after the last run"),
    ];
    for &(runs, offset, what) in cases {
        let (at, reason) = malformed_at(decode(&file(CUBE2, runs), path()));
        assert_eq!(at, offset, "{runs:?}: {reason}");
        assert!(reason.contains(what), "{runs:?}: {reason}");
        assert!(decode_info(&file(CUBE2, runs), path()).is_err());
    }
}

#[test]
fn export_refuses_what_binvox_cannot_hold() {
    let big = GridSpec::new(DVec3::ZERO, 1.0, UVec3::new(MAX_EXPORT_DIM + 1, 1, 1)).unwrap();
    let map = BrickMap::<()>::new(big.dims);
    assert!(matches!(encode(&big, &map), Err(Error::GridTooLarge { .. })));
    let huge = GridSpec::new(DVec3::ZERO, 1e308, UVec3::splat(4)).unwrap();
    assert!(matches!(
        encode(&huge, &BrickMap::<()>::new(huge.dims)),
        Err(Error::InvalidGrid { .. })
    ));
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(4)).unwrap();
    assert!(matches!(encode(&grid, &map), Err(Error::InvalidGrid { .. })));
    // Nothing is created when the arguments are refused.
    let dir = std::env::temp_dir().join(format!("voxlod-binvox-refuse-{}", std::process::id()));
    assert!(write(dir.join("x.binvox"), &big, &map).is_err());
    assert!(!dir.join("x.binvox").exists());
}

#[test]
fn full_and_sparse_cubes_round_trip_and_memory_follows_occupancy() {
    // Every voxel set: runs of 255 ones.
    let grid = GridSpec::new(DVec3::splat(-3.0), 0.5, UVec3::splat(9)).unwrap();
    let all: Vec<_> =
        (0..9u32.pow(3)).map(|i| (UVec3::new(i % 9, i / 9 % 9, i / 81), ())).collect();
    let map = BrickMap::from_voxels(grid.dims, all).unwrap();
    let (back_grid, back) = decode(&encode(&grid, &map).unwrap(), path()).unwrap();
    assert_eq!(back_grid, grid);
    assert_eq!(back.len(), 729);
    // Two voxels in a 512³ cube: 1 MB of empty runs, two bricks in memory.
    let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(512)).unwrap();
    let two = [(UVec3::new(511, 0, 7), ()), (UVec3::new(3, 500, 2), ())];
    let bytes = encode(&grid, &BrickMap::from_voxels(grid.dims, two).unwrap()).unwrap();
    let (_, back) = decode(&bytes, path()).unwrap();
    assert_eq!(back.bricks().len(), 2);
    let set: BTreeSet<_> = back.coords().map(|c| c.to_array()).collect();
    assert_eq!(set, BTreeSet::from([two[0].0.to_array(), two[1].0.to_array()]));
}

#[test]
fn files_round_trip() {
    let dir = std::env::temp_dir().join(format!("voxlod-binvox-test-{}", std::process::id()));
    let grid = GridSpec::new(DVec3::new(0.1, 0.2, 0.3), 0.1, UVec3::new(10, 3, 7)).unwrap();
    let map = BrickMap::from_voxels(grid.dims, [(UVec3::new(9, 2, 6), 1u32)]).unwrap();
    write(dir.join("a.binvox"), &grid, &map).unwrap();
    let (cube, back) = read(dir.join("a.binvox")).unwrap();
    assert_eq!(cube.origin, grid.origin);
    assert_eq!(back.coords().collect::<Vec<_>>(), [UVec3::new(9, 2, 6)]);
    assert_eq!(read_info(dir.join("a.binvox")).unwrap().occupied, 1);
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(matches!(read(dir.join("a.binvox")), Err(Error::Io { .. })));
}

/// A random grid (any normal origin, voxel sizes from 1e-200 to 1e200) and sparse occupancy.
fn grid_and_map() -> impl Strategy<Value = (GridSpec, BrickMap<()>)> {
    let origin = [prop::num::f64::NORMAL; 3];
    (origin, -200.0f64..200.0, 1u32..40, 1u32..40, 1u32..40).prop_flat_map(|(o, e, x, y, z)| {
        let grid = GridSpec::new(DVec3::from_array(o), 10f64.powf(e), UVec3::new(x, y, z)).unwrap();
        proptest::collection::btree_set((0..x, 0..y, 0..z), 0..300).prop_map(move |set| {
            let voxels = set.into_iter().map(|(a, b, c)| (UVec3::new(a, b, c), ()));
            (grid, BrickMap::from_voxels(grid.dims, voxels).unwrap())
        })
    })
}

proptest! {
    #[test]
    fn round_trip_preserves_occupancy_and_world_positions((grid, map) in grid_and_map()) {
        let bytes = encode(&grid, &map).unwrap();
        let (cube, back) = decode(&bytes, path()).unwrap();
        back.validate().unwrap();
        let d = grid.dims.max_element();
        prop_assert_eq!(cube.dims, UVec3::splat(d));
        prop_assert_eq!(cube.origin, grid.origin);
        let ulp = grid.voxel_size.next_up() - grid.voxel_size;
        prop_assert!((cube.voxel_size - grid.voxel_size).abs() <= ulp,
            "voxel size {} read back as {}", grid.voxel_size, cube.voxel_size);
        if cube_scale(grid.voxel_size, d) / d as f64 == grid.voxel_size || d.is_power_of_two() {
            prop_assert_eq!(cube.voxel_size, grid.voxel_size);
        }
        let ours: Vec<_> = map.coords().collect();
        let theirs: Vec<_> = back.coords().collect();
        prop_assert_eq!(ours, theirs);
        prop_assert_eq!(decode_info(&bytes, path()).unwrap().occupied, map.len() as u64);
    }

    /// Damaged files (truncated, or any byte changed) decode to an error or to a consistent
    /// map; `decode_info` agrees with `decode`.
    #[test]
    fn damaged_files_never_panic(
        (grid, map) in grid_and_map(),
        at in any::<prop::sample::Index>(),
        xor in 1u8..=255,
    ) {
        let bytes = encode(&grid, &map).unwrap();
        let i = at.index(bytes.len());
        let mut flipped = bytes.clone();
        flipped[i] ^= xor;
        for damaged in [&bytes[..i], &flipped[..]] {
            match (decode(damaged, path()), decode_info(damaged, path())) {
                (Ok((g, m)), Ok(info)) => {
                    m.validate().unwrap();
                    prop_assert_eq!(m.dims(), g.dims);
                    prop_assert_eq!(info.occupied, m.len() as u64);
                }
                (Err(_), Err(_)) => {}
                (a, b) => prop_assert!(false, "decode {:?} vs decode_info {:?}", a.map(|_| ()), b),
            }
        }
    }
}
