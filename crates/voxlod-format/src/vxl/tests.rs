//! Tests of the `.vxl` container: round trips, the documented byte layout, and corrupt files.

use std::collections::BTreeMap;
use std::fmt::Debug;
use std::path::Path;

use glam::{DVec3, UVec3};
use proptest::prelude::*;

use super::*;
use crate::morton;

const PATH: &str = "<test>";

fn path() -> &'static Path {
    Path::new(PATH)
}

/// Recomputes the header's CRC after a test edited the body on purpose.
fn reseal(bytes: &mut [u8]) {
    let crc = crc32(&bytes[HEADER_LEN..]);
    bytes[24..28].copy_from_slice(&crc.to_le_bytes());
}

fn put_u32(bytes: &mut [u8], at: usize, v: u32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

fn put_u64(bytes: &mut [u8], at: usize, v: u64) {
    bytes[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

fn malformed_at(result: Result<impl Debug>) -> (u64, String) {
    match result {
        Err(Error::Malformed { offset, reason, format: "vxl", .. }) => (offset, reason),
        other => panic!("expected Error::Malformed, got {other:?}"),
    }
}

/// A random grid (normal floats of any sign and magnitude for the origin, any positive normal
/// voxel size) with a sparse map of up to 300 voxels.
fn grid_and_map<T: Debug + Clone>(
    value: impl Strategy<Value = T> + Clone,
) -> impl Strategy<Value = (GridSpec, BrickMap<T>)> {
    let origin = [prop::num::f64::NORMAL; 3];
    let size = prop::num::f64::POSITIVE | prop::num::f64::NORMAL;
    (origin, size, 1u32..40, 1u32..40, 1u32..40).prop_flat_map(move |(o, size, x, y, z)| {
        let grid = GridSpec::new(DVec3::from_array(o), size, UVec3::new(x, y, z)).unwrap();
        let voxel = ((0..x, 0..y, 0..z), value.clone());
        proptest::collection::vec(voxel, 0..300).prop_map(move |voxels| {
            let unique: BTreeMap<u64, (UVec3, T)> = voxels
                .into_iter()
                .map(|((a, b, c), v)| {
                    let c = UVec3::new(a, b, c);
                    (morton::encode(c), (c, v))
                })
                .collect();
            (grid, BrickMap::from_voxels(grid.dims, unique.into_values()).unwrap())
        })
    })
}

fn meta_strategy() -> impl Strategy<Value = Vec<(String, String)>> {
    proptest::collection::btree_map("[a-z_]{1,12}", "\\PC{0,24}", 0..5)
        .prop_map(|m| m.into_iter().collect())
}

/// Asserts two maps hold the same voxels with bit-identical records.
fn assert_same_map<T: VxlRecord + Debug>(a: &BrickMap<T>, b: &BrickMap<T>) {
    assert_eq!(a.dims(), b.dims());
    assert_eq!(a.bricks(), b.bricks());
    assert_eq!(
        bytemuck::cast_slice::<T, u8>(a.values()),
        bytemuck::cast_slice::<T, u8>(b.values())
    );
    let ca: Vec<_> = a.coords().collect();
    let cb: Vec<_> = b.coords().collect();
    assert_eq!(ca, cb);
}

fn round_trip<T: VxlRecord + Debug>(grid: &GridSpec, map: &BrickMap<T>, meta: &[(String, String)]) {
    let bytes = encode(grid, map, meta).unwrap();
    let file = decode::<T>(&bytes, path()).unwrap();
    assert_eq!(file.version, VERSION);
    // Bit-exact grid (the strategy never makes NaN, so == is bitwise here).
    assert_eq!(file.grid, *grid);
    assert_eq!(file.meta, meta);
    file.map.validate().unwrap();
    assert_same_map(&file.map, map);
    let info = decode_info(&bytes, path()).unwrap();
    assert!(info.checksum_ok && info.holds::<T>());
    assert_eq!((info.brick_count, info.voxel_count), (map.bricks().len() as u64, map.len() as u64));
    assert_eq!(info.file_len, bytes.len() as u64);
    assert_eq!(info.grid, *grid);
}

proptest! {
    #[test]
    fn round_trip_u32((grid, map) in grid_and_map(any::<u32>()), meta in meta_strategy()) {
        round_trip(&grid, &map, &meta);
    }

    #[test]
    fn round_trip_occupancy((grid, map) in grid_and_map(Just(Occupancy)), meta in meta_strategy()) {
        round_trip(&grid, &map, &meta);
    }

    #[test]
    fn round_trip_f32x4_keeps_every_bit((grid, map) in grid_and_map(any::<[u32; 4]>())) {
        // Arbitrary bit patterns, NaN payloads included, must come back unchanged.
        let map = map.map(|v| v.map(f32::from_bits));
        round_trip(&grid, &map, &[]);
    }

    /// Any single corrupted byte anywhere (header fields are each checked; the body is covered
    /// by the CRC, which detects every error burst of up to 32 bits), any truncation and any
    /// appended byte is an error.
    #[test]
    fn corrupted_truncated_or_extended_files_are_errors(
        (grid, map) in grid_and_map(any::<u16>()),
        at in any::<prop::sample::Index>(),
        xor in 1u8..=255,
        extra in any::<u8>(),
    ) {
        let bytes = encode(&grid, &map, &[("k".into(), "v".into())]).unwrap();
        let i = at.index(bytes.len());
        let mut flipped = bytes.clone();
        flipped[i] ^= xor;
        prop_assert!(decode::<u16>(&flipped, path()).is_err(), "flip of byte {} by {:#x}", i, xor);
        prop_assert!(decode::<u16>(&bytes[..i], path()).is_err(), "truncated to {}", i);
        let mut longer = bytes.clone();
        longer.push(extra);
        prop_assert!(decode::<u16>(&longer, path()).is_err());
        // read_info never panics on these either; it may still describe a body-corrupted file.
        let _ = decode_info(&flipped, path());
        prop_assert!(decode_info(&bytes[..i], path()).is_err());
    }

    /// Corruption that a CRC would not catch (the checksum recomputed after the damage): the
    /// structural checks must refuse it, or what decodes must be a consistent map.
    #[test]
    fn resealed_corruption_never_panics_and_never_yields_a_broken_map(
        (grid, map) in grid_and_map(any::<u32>()),
        at in any::<prop::sample::Index>(),
        xor in 1u8..=255,
    ) {
        let mut bytes = encode(&grid, &map, &[("scene".into(), "test".into())]).unwrap();
        let i = HEADER_LEN + at.index(bytes.len() - HEADER_LEN);
        bytes[i] ^= xor;
        reseal(&mut bytes);
        if let Ok(file) = decode::<u32>(&bytes, path()) {
            file.map.validate().unwrap();
            prop_assert_eq!(file.map.dims(), file.grid.dims);
            file.grid.validate().unwrap();
            prop_assert_eq!(file.map.coords().count(), file.map.len());
        }
        let _ = decode_info(&bytes, path());
        // Occupancy files have no payload: every body byte is structure or metadata.
        let occ = map.map(|_| Occupancy);
        let mut bytes = encode(&grid, &occ, &[]).unwrap();
        let i = HEADER_LEN + at.index(bytes.len() - HEADER_LEN);
        bytes[i] ^= xor;
        reseal(&mut bytes);
        if let Ok(file) = decode::<Occupancy>(&bytes, path()) {
            file.map.validate().unwrap();
            prop_assert_eq!(file.map.dims(), file.grid.dims);
        }
    }
}

/// A 20×9×17 grid with three voxels in three bricks, the last on the grid's far boundary.
fn sample() -> (GridSpec, BrickMap<u32>) {
    let grid = GridSpec::new(DVec3::new(-1.0, 2.0, 0.5), 0.125, UVec3::new(20, 9, 17)).unwrap();
    let voxels =
        [(UVec3::new(0, 0, 0), 10), (UVec3::new(19, 8, 16), 20), (UVec3::new(3, 8, 9), 30)];
    (grid, BrickMap::from_voxels(grid.dims, voxels).unwrap())
}

/// The module docs' byte table, written out by hand for a one-voxel occupancy file.
#[test]
fn layout_matches_the_documented_table() {
    let grid = GridSpec::new(DVec3::new(1.5, -2.0, 0.25), 0.5, UVec3::new(3, 9, 17)).unwrap();
    let voxel = UVec3::new(2, 8, 16); // brick (0, 1, 2), local (2, 0, 0)
    let map = BrickMap::from_voxels(grid.dims, [(voxel, Occupancy)]).unwrap();
    let bytes = encode(&grid, &map, &[("scene".into(), "t".into())]).unwrap();

    let mut expected = Vec::new();
    expected.extend_from_slice(&[0x89, b'V', b'X', b'L', b'\r', b'\n', 0x1a, b'\n']);
    expected.extend_from_slice(&1u32.to_le_bytes());
    expected.extend_from_slice(&0u32.to_le_bytes());
    expected.extend_from_slice(&162u64.to_le_bytes()); // 72 fixed + 14 metadata + 76 brick
    expected.extend_from_slice(&[0; 4]); // CRC, checked below
    expected.extend_from_slice(&0u32.to_le_bytes());
    for v in [1.5f64, -2.0, 0.25, 0.5] {
        expected.extend_from_slice(&v.to_le_bytes());
    }
    for d in [3u32, 9, 17] {
        expected.extend_from_slice(&d.to_le_bytes());
    }
    expected.extend_from_slice(b"occ ");
    expected.extend_from_slice(&0u32.to_le_bytes()); // record size
    expected.extend_from_slice(&1u32.to_le_bytes()); // metadata entries
    expected.extend_from_slice(&1u64.to_le_bytes()); // bricks
    expected.extend_from_slice(&1u64.to_le_bytes()); // voxels
    assert_eq!(expected.len(), FIXED_END);
    expected.extend_from_slice(&5u32.to_le_bytes());
    expected.extend_from_slice(b"scene");
    expected.extend_from_slice(&1u32.to_le_bytes());
    expected.extend_from_slice(b"t");
    // Brick (0,1,2): Morton y0 -> bit 1, z1 -> bit 5. Local (2,0,0): x1 -> bit 3.
    expected.extend_from_slice(&0b100010u64.to_le_bytes());
    expected.extend_from_slice(&(1u64 << 8).to_le_bytes());
    expected.extend_from_slice(&[0; 7 * 8]);
    expected.extend_from_slice(&0u32.to_le_bytes()); // first
    assert_eq!(bytes.len(), expected.len());
    assert_eq!(bytes[..24], expected[..24]);
    assert_eq!(bytes[28..], expected[28..]);
    assert_eq!(bytes[24..28], crc32(&expected[HEADER_LEN..]).to_le_bytes());
}

#[test]
fn every_single_byte_flip_and_truncation_of_a_small_file_is_an_error() {
    let (grid, map) = sample();
    let bytes = encode(&grid, &map, &[("mode".into(), "solid".into())]).unwrap();
    for i in 0..bytes.len() {
        for xor in [0x01, 0x80, 0xff] {
            let mut b = bytes.clone();
            b[i] ^= xor;
            assert!(decode::<u32>(&b, path()).is_err(), "flip {xor:#x} at byte {i}");
        }
        assert!(decode::<u32>(&bytes[..i], path()).is_err(), "truncated to {i} bytes");
    }
}

#[test]
fn extreme_coordinates_and_empty_maps_round_trip() {
    let max = GridSpec::MAX_DIM;
    let grid = GridSpec::new(DVec3::splat(-1e300), 1e-300, UVec3::splat(max)).unwrap();
    let corners = [UVec3::ZERO, UVec3::splat(max - 1), UVec3::new(max - 1, 0, max - 1)];
    let map = BrickMap::from_voxels(grid.dims, corners.map(|c| (c, c.x ^ c.z))).unwrap();
    round_trip(&grid, &map, &[]);
    let one = GridSpec::new(DVec3::ZERO, 1.0, UVec3::ONE).unwrap();
    round_trip(&one, &BrickMap::<Occupancy>::new(one.dims), &[]);
    round_trip(&one, &BrickMap::<[f32; 3]>::new(one.dims), &[("k".into(), String::new())]);
}

#[test]
fn newer_and_zero_versions_are_refused() {
    let (grid, map) = sample();
    let mut bytes = encode(&grid, &map, &[]).unwrap();
    for v in [VERSION + 1, u32::MAX] {
        put_u32(&mut bytes, 8, v);
        match decode::<u32>(&bytes, path()) {
            Err(Error::UnsupportedVersion { found, supported, format: "vxl", .. }) => {
                assert_eq!((found, supported), (v, VERSION));
            }
            other => panic!("expected UnsupportedVersion, got {other:?}"),
        }
        assert!(matches!(decode_info(&bytes, path()), Err(Error::UnsupportedVersion { .. })));
    }
    put_u32(&mut bytes, 8, 0);
    assert_eq!(malformed_at(decode::<u32>(&bytes, path())).0, 8);
}

#[test]
fn wrong_magic_is_named_at_its_offset() {
    let (grid, map) = sample();
    let bytes = encode(&grid, &map, &[]).unwrap();
    let binvox = b"#binvox 1\ndim 2 2 2\ndata\n\x00\x08";
    let (offset, reason) = malformed_at(decode::<u32>(binvox, path()));
    assert_eq!(offset, 0);
    assert!(reason.contains("magic"), "{reason}");
    let mut b = bytes.clone();
    b[3] = b'Z';
    assert_eq!(malformed_at(decode::<u32>(&b, path())).0, 3);
    assert_eq!(malformed_at(decode::<u32>(&[], path())).0, 0);
    let err = decode::<u32>(&[], path()).unwrap_err().to_string();
    assert!(err.contains(PATH), "{err}");
}

#[test]
fn records_of_another_type_are_refused() {
    let (grid, map) = sample();
    let bytes = encode(&grid, &map, &[]).unwrap();
    match decode::<f32>(&bytes, path()) {
        Err(Error::RecordMismatch { expected, found, expected_size, found_size, .. }) => {
            assert_eq!((expected.as_str(), found.as_str()), ("f32", "u32"));
            assert_eq!((expected_size, found_size), (4, 4));
        }
        other => panic!("expected RecordMismatch, got {other:?}"),
    }
    assert!(matches!(decode::<Occupancy>(&bytes, path()), Err(Error::RecordMismatch { .. })));
    assert!(matches!(decode::<[f32; 4]>(&bytes, path()), Err(Error::RecordMismatch { .. })));
}

#[test]
fn checksum_mismatch_is_reported() {
    let (grid, map) = sample();
    let mut bytes = encode(&grid, &map, &[]).unwrap();
    let last = bytes.len() - 1; // inside the payload: structure still readable
    bytes[last] ^= 0x40;
    assert!(matches!(decode::<u32>(&bytes, path()), Err(Error::ChecksumMismatch { .. })));
    let info = decode_info(&bytes, path()).unwrap();
    assert!(!info.checksum_ok);
    assert_eq!(info.voxel_count, 3);
    // Corruption of the counts cannot be described: the error is the checksum's.
    bytes[VOXEL_COUNT_AT + 7] ^= 0x40;
    assert!(matches!(decode_info(&bytes, path()), Err(Error::ChecksumMismatch { .. })));
}

const BRICK_COUNT_AT: usize = 88;
const VOXEL_COUNT_AT: usize = 96;

/// Offset of brick `i`'s entry in `sample()` encoded with no metadata.
fn brick_at(i: usize) -> usize {
    FIXED_END + i * BRICK_ENTRY_LEN
}

#[test]
fn inconsistent_brick_tables_are_refused_with_their_offset() {
    let (grid, map) = sample();
    assert_eq!(map.bricks().len(), 3);
    let bytes = encode(&grid, &map, &[]).unwrap();
    let edit = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut b = bytes.clone();
        f(&mut b);
        reseal(&mut b);
        malformed_at(decode::<u32>(&b, path()))
    };

    // Unsorted Morton codes: swap the codes and masks of bricks 0 and 1 (one voxel each, so
    // the `first` offsets stay right and only the order is wrong).
    let (offset, reason) = edit(&|b| {
        let (x, y) = (brick_at(0), brick_at(1));
        let zero = b[x..x + 72].to_vec();
        b.copy_within(y..y + 72, x);
        b[y..y + 72].copy_from_slice(&zero);
    });
    assert_eq!(offset, brick_at(1) as u64, "{reason}");
    assert!(reason.contains("Morton order"), "{reason}");

    // Bricks outside the grid: shrink the x extent so that the voxel at x = 19 falls outside.
    let (offset, reason) = edit(&|b| put_u32(b, 64, 12));
    assert_eq!(offset, brick_at(2) as u64, "{reason}");
    assert!(reason.contains("outside"), "{reason}");

    // A brick beyond the grid's brick extent altogether.
    let (offset, _) = edit(&|b| put_u64(b, brick_at(2), morton::encode(UVec3::new(3, 0, 0))));
    assert_eq!(offset, brick_at(2) as u64);

    // A mask bit for a voxel outside the grid: brick (2,1,2) starts at voxel (16,8,16) and its
    // local voxel 2 is (0,1,0), so voxel (16,9,16), beyond the grid's 9 voxels in y.
    let (offset, reason) = edit(&|b| b[brick_at(2) + 8] |= 1 << 2);
    assert_eq!(offset, brick_at(2) as u64, "{reason}");
    assert!(reason.contains("outside"), "{reason}");

    // Mask count vs payload: local voxel 1 of that brick, (17,8,16), is inside the grid, but
    // setting it gives the masks one voxel more than there are records.
    let (offset, reason) = edit(&|b| b[brick_at(2) + 8] |= 1 << 1);
    assert_eq!(offset, VOXEL_COUNT_AT as u64, "{reason}");

    // A `first` that disagrees with the masks before it.
    let (offset, _) = edit(&|b| put_u32(b, brick_at(1) + 72, 7));
    assert_eq!(offset, brick_at(1) as u64);

    // An empty brick.
    let (offset, reason) = edit(&|b| b[brick_at(2) + 8..brick_at(2) + 72].fill(0));
    assert_eq!(offset, brick_at(2) as u64, "{reason}");
    assert!(reason.contains("empty"), "{reason}");

    // A Morton code with bit 63 set (the 63-bit code space has no such brick).
    let (offset, _) = edit(&|b| b[brick_at(0) + 7] |= 0x80);
    assert_eq!(offset, brick_at(0) as u64);
}

#[test]
fn absurd_counts_are_refused_before_any_allocation() {
    let (grid, map) = sample();
    let bytes = encode(&grid, &map, &[]).unwrap();
    let edit = |at: usize, v: u64, width: usize| {
        let mut b = bytes.clone();
        b[at..at + width].copy_from_slice(&v.to_le_bytes()[..width]);
        reseal(&mut b);
        b
    };
    // Terabytes of bricks or records, and counts whose byte size overflows u64.
    for v in [1 << 40, u64::MAX / 76 + 1, u64::MAX] {
        let b = edit(BRICK_COUNT_AT, v, 8);
        assert_eq!(malformed_at(decode::<u32>(&b, path())).0, BRICK_COUNT_AT as u64);
        let b = edit(VOXEL_COUNT_AT, v, 8);
        assert_eq!(malformed_at(decode::<u32>(&b, path())).0, BRICK_COUNT_AT as u64);
    }
    let b = edit(84, u32::MAX as u64, 4);
    assert_eq!(malformed_at(decode::<u32>(&b, path())).0, 84);

    // Occupancy has no payload bytes to bound the voxel count: the bricks bound it.
    let occ = map.map(|_| Occupancy);
    let mut b = encode(&grid, &occ, &[]).unwrap();
    put_u64(&mut b, VOXEL_COUNT_AT, u64::MAX);
    reseal(&mut b);
    assert_eq!(malformed_at(decode::<Occupancy>(&b, path())).0, VOXEL_COUNT_AT as u64);

    // More bricks than the grid holds (a 1-voxel grid holds one brick).
    let one = GridSpec::new(DVec3::ZERO, 1.0, UVec3::ONE).unwrap();
    let mut b = encode(&one, &BrickMap::<Occupancy>::new(one.dims), &[]).unwrap();
    put_u64(&mut b, BRICK_COUNT_AT, 2);
    b.extend_from_slice(&[0; 2 * BRICK_ENTRY_LEN]);
    let body = (b.len() - HEADER_LEN) as u64;
    put_u64(&mut b, 16, body);
    reseal(&mut b);
    let (offset, reason) = malformed_at(decode::<Occupancy>(&b, path()));
    assert_eq!(offset, BRICK_COUNT_AT as u64, "{reason}");
}

#[test]
fn bad_metadata_is_refused_on_both_sides() {
    let (grid, map) = sample();
    let dup = [("a".to_string(), "1".to_string()), ("a".to_string(), "2".to_string())];
    assert!(matches!(encode(&grid, &map, &dup), Err(Error::InvalidMetadata { .. })));
    let empty = [(String::new(), "1".to_string())];
    assert!(matches!(encode(&grid, &map, &empty), Err(Error::InvalidMetadata { .. })));

    // A file written with keys "a" and "b", then edited to repeat "a", or to hold invalid UTF-8.
    let meta = [("a".to_string(), "x".to_string()), ("b".to_string(), "y".to_string())];
    let bytes = encode(&grid, &map, &meta).unwrap();
    let second_key = FIXED_END + 4 + 1 + 4 + 1 + 4;
    let mut b = bytes.clone();
    b[second_key] = b'a';
    reseal(&mut b);
    assert_eq!(malformed_at(decode::<u32>(&b, path())).0, (second_key - 4) as u64);
    let mut b = bytes.clone();
    b[second_key] = 0xff;
    reseal(&mut b);
    assert_eq!(malformed_at(decode::<u32>(&b, path())).0, second_key as u64);
}

#[test]
fn encode_checks_its_arguments() {
    let (grid, map) = sample();
    let other = GridSpec { dims: UVec3::splat(32), ..grid };
    assert!(matches!(encode(&other, &map, &[]), Err(Error::InvalidGrid { .. })));
    let bad = GridSpec { voxel_size: f64::NAN, ..grid };
    assert!(encode(&bad, &map, &[]).is_err());
}

#[test]
fn files_round_trip_and_missing_files_are_io_errors() {
    let (grid, map) = sample();
    let dir = std::env::temp_dir().join(format!("voxlod-vxl-test-{}", std::process::id()));
    let file = dir.join("sample.vxl");
    write(&file, &grid, &map, &[("scene".into(), "sample".into())]).unwrap();
    let back = read::<u32>(&file).unwrap();
    assert_same_map(&back.map, &map);
    assert_eq!(back.meta_value("scene"), Some("sample"));
    assert_eq!(read_info(&file).unwrap().meta_value("scene"), Some("sample"));
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(matches!(read::<u32>(&file), Err(Error::Io { .. })));
    assert!(matches!(read_info(&file), Err(Error::Io { .. })));
}
