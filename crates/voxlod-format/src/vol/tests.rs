use std::path::Path;

use glam::{DVec3, UVec3, Vec3};

use super::*;
use crate::records::{AverageRecord, MAX_VOXEL_OPTICAL_DEPTH};

fn mem() -> &'static Path {
    Path::new("<memory>")
}

/// A 3 × 2 × 1 grid of voxels of 0.5 at (−1, 2, 0.25) with three Averages voxels.
fn averages() -> (GridSpec, BrickMap<AverageRecord>) {
    let grid = GridSpec::new(DVec3::new(-1.0, 2.0, 0.25), 0.5, UVec3::new(3, 2, 1)).unwrap();
    let rec = |c: Vec3, a: f32| AverageRecord::new(c, Vec3::Y, a);
    let map = BrickMap::from_voxels(
        grid.dims,
        [
            (UVec3::new(0, 0, 0), rec(Vec3::new(1.0, 0.0, 0.0), 1.0)),
            (UVec3::new(2, 0, 0), rec(Vec3::new(0.2, 0.5, 0.8), 0.5)),
            (UVec3::new(1, 1, 0), rec(Vec3::splat(0.18), 0.25)),
        ],
    )
    .unwrap();
    (grid, map)
}

#[test]
fn header_bytes_follow_the_documented_layout() {
    // Mitsuba 3's gridvolume documentation: 'V' 'O' 'L', version byte 3, encoding i32 1,
    // cells x, y, z as i32, channels i32, bbox as six f32 (min xyz, max xyz), little-endian.
    let v = VolGrid {
        dims: UVec3::new(3, 2, 1),
        channels: 3,
        bbox_min: Vec3::new(-1.0, 2.0, 0.25),
        bbox_max: Vec3::new(0.5, 3.0, 0.75),
        data: (0..18).map(|i| i as f32).collect(),
    };
    let bytes = encode(&v).unwrap();
    #[rustfmt::skip]
    let header: [u8; 48] = [
        0x56, 0x4F, 0x4C, 0x03, // "VOL", version 3
        0x01, 0x00, 0x00, 0x00, // encoding 1 = float32
        0x03, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, // 3 × 2 × 1
        0x03, 0x00, 0x00, 0x00, // 3 channels
        0x00, 0x00, 0x80, 0xBF, 0x00, 0x00, 0x00, 0x40, 0x00, 0x00, 0x80, 0x3E, // −1, 2, 0.25
        0x00, 0x00, 0x00, 0x3F, 0x00, 0x00, 0x40, 0x40, 0x00, 0x00, 0x40, 0x3F, // 0.5, 3, 0.75
    ];
    assert_eq!(bytes[..48], header);
    assert_eq!(bytes.len(), 48 + 18 * 4);
    // Value c of cell (x, y, z) at ((z·Y + y)·X + x)·channels + c: x fastest.
    let at = |x: usize, y: usize, c: usize| {
        let i = 48 + 4 * ((y * 3 + x) * 3 + c);
        f32::from_le_bytes(bytes[i..i + 4].try_into().unwrap())
    };
    assert_eq!(at(1, 0, 0), 3.0);
    assert_eq!(at(0, 1, 2), 11.0);
    assert_eq!(at(2, 1, 1), 16.0);
    assert_eq!(v.index(UVec3::new(2, 1, 0)), 15);
}

#[test]
fn averages_round_trip_as_density_and_albedo() {
    let (grid, map) = averages();
    let (density, albedo) = density_and_albedo(&grid, &map).unwrap();
    assert_eq!((density.channels, albedo.channels), (1, 3));
    // The box is the grid's world box: cell (i, j, k) covers origin + [i, i+1)·size.
    assert_eq!(density.bbox_min, Vec3::new(-1.0, 2.0, 0.25));
    assert_eq!(density.bbox_max, Vec3::new(0.5, 3.0, 0.75));
    let back = decode(&encode(&density).unwrap(), mem()).unwrap();
    assert_eq!(back, density);
    let back = decode(&encode(&albedo).unwrap(), mem()).unwrap();
    assert_eq!(back, albedo);
    for c in (0..2).flat_map(|y| (0..3).map(move |x| UVec3::new(x, y, 0))) {
        match map.get(c) {
            Some(r) => {
                let depth = -(1.0 - r.opacity() as f64).ln();
                let sigma = depth.min(MAX_VOXEL_OPTICAL_DEPTH as f64) / grid.voxel_size;
                assert!((density.get(c).unwrap()[0] as f64 - sigma).abs() < 1e-5 * sigma.max(1.0));
                assert_eq!(albedo.get(c).unwrap(), r.color().to_array());
            }
            None => {
                assert_eq!(density.get(c).unwrap(), [0.0]);
                assert_eq!(albedo.get(c).unwrap(), [0.0; 3]);
            }
        }
    }
    // An opaque voxel: the capped optical depth ln 510 across its 0.5 edge.
    let opaque = density.get(UVec3::ZERO).unwrap()[0];
    assert!((opaque - 510f32.ln() / 0.5).abs() < 1e-4, "{opaque}");
    assert_eq!(density.get(UVec3::new(3, 0, 0)), None);
}

#[test]
fn written_files_read_back_and_failed_writes_leave_nothing() {
    let dir = std::env::temp_dir().join(format!("voxlod-vol-test-{}", std::process::id()));
    let (grid, map) = averages();
    let (density, _) = density_and_albedo(&grid, &map).unwrap();
    let path = dir.join("density.vol");
    write(&path, &density).unwrap();
    assert_eq!(read(&path).unwrap(), density);
    let mut bad = density.clone();
    bad.data[4] = f32::NAN;
    let missing = dir.join("never.vol");
    assert!(write(&missing, &bad).is_err());
    assert!(!missing.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn occupancy_is_opaque_density() {
    let grid = GridSpec::new(DVec3::ZERO, 0.25, UVec3::new(2, 2, 2)).unwrap();
    let map = BrickMap::from_voxels(grid.dims, [(UVec3::new(1, 1, 1), ())]).unwrap();
    let v = occupancy_density(&grid, &map).unwrap();
    assert_eq!(v.data.iter().filter(|&&x| x > 0.0).count(), 1);
    assert!((v.get(UVec3::ONE).unwrap()[0] - MAX_VOXEL_OPTICAL_DEPTH / 0.25).abs() < 1e-4);
}

#[test]
fn refuses_what_the_format_cannot_hold() {
    let ok = VolGrid {
        dims: UVec3::new(2, 1, 1),
        channels: 1,
        bbox_min: Vec3::ZERO,
        bbox_max: Vec3::ONE,
        data: vec![0.0, 1.0],
    };
    ok.validate().unwrap();
    let refused = |v: VolGrid, needle: &str| {
        let e = encode(&v).unwrap_err();
        assert!(e.to_string().contains(needle), "{e}");
    };
    refused(VolGrid { channels: 2, data: vec![0.0; 4], ..ok.clone() }, "2 channels");
    refused(VolGrid { data: vec![0.0, f32::INFINITY], ..ok.clone() }, "cell [1, 0, 0] channel 0");
    refused(VolGrid { bbox_max: Vec3::new(1.0, 0.0, 1.0), ..ok.clone() }, "bounding box");
    refused(VolGrid { bbox_min: Vec3::splat(f32::NAN), ..ok.clone() }, "bounding box");
    refused(VolGrid { data: vec![0.0; 3], ..ok.clone() }, "3 values");
    // Checked before any allocation: a 1025³ grid is 2³⁰ + 3·2²⁰ + … values.
    let big = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(1025)).unwrap();
    let empty = BrickMap::<()>::new(big.dims);
    let e = VolGrid::from_brick_map(&big, &empty, [0.0], |_| [1.0]).unwrap_err();
    assert!(matches!(e, Error::Unrepresentable { format: "vol", .. }), "{e}");
    // A grid far from the origin whose box collapses in f32 is refused, not written flat.
    let far = GridSpec::new(DVec3::splat(1e9), 1e-3, UVec3::ONE).unwrap();
    let one = BrickMap::from_voxels(far.dims, [(UVec3::ZERO, ())]).unwrap();
    let e = occupancy_density(&far, &one).unwrap_err();
    assert!(e.to_string().contains("bounding box"), "{e}");
}

#[test]
fn malformed_files_are_errors_never_panics() {
    let (grid, map) = averages();
    let (_, albedo) = density_and_albedo(&grid, &map).unwrap();
    let bytes = encode(&albedo).unwrap();
    for len in 0..bytes.len() {
        assert!(decode(&bytes[..len], mem()).is_err(), "truncated to {len} bytes");
    }
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(decode(&longer, mem()).is_err());
    let patched = |offset: usize, with: &[u8]| {
        let mut b = bytes.clone();
        b[offset..offset + with.len()].copy_from_slice(with);
        decode(&b, mem()).unwrap_err()
    };
    assert!(patched(0, b"VOX").to_string().contains("VOL"));
    assert!(matches!(patched(3, &[4]), Error::UnsupportedVersion { found: 4, .. }));
    assert!(matches!(patched(3, &[2]), Error::Malformed { offset: 3, .. }));
    assert!(matches!(patched(4, &2i32.to_le_bytes()), Error::Unsupported { offset: 4, .. }));
    assert!(matches!(patched(12, &0i32.to_le_bytes()), Error::Malformed { offset: 12, .. }));
    assert!(matches!(patched(8, &(-5i32).to_le_bytes()), Error::Malformed { offset: 8, .. }));
    assert!(matches!(patched(20, &4i32.to_le_bytes()), Error::Malformed { offset: 20, .. }));
    // Huge dims are refused by count, before anything is allocated.
    let e = patched(8, &i32::MAX.to_le_bytes());
    assert!(e.to_string().contains("exceed"), "{e}");
}
