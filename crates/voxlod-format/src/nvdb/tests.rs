use std::path::Path;

use glam::{DMat3, DVec3, IVec3, UVec3, Vec3};

use super::layout::{GRID_BYTES, HEADER_BYTES, META_BYTES, Sizes};
use super::*;
use crate::records::AverageRecord;

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}
fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_bits(u64_at(b, at))
}
fn i32_at(b: &[u8], at: usize) -> i32 {
    u32_at(b, at) as i32
}

/// A deterministic pseudo-random sequence (64-bit LCG, high bits).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> u32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 33) as u32
    }
    fn unit(&mut self) -> f32 {
        self.next() as f32 / (1u64 << 31) as f32
    }
}

fn unit_map() -> IndexToWorld {
    IndexToWorld { matrix: DMat3::IDENTITY, translation: DVec3::ZERO }
}

fn float_grid(voxels: Vec<(IVec3, f32)>) -> NvdbGrid<f32> {
    NvdbGrid {
        name: "density".into(),
        class: GridClass::FogVolume,
        map: unit_map(),
        background: 0.0,
        voxels,
    }
}

fn sorted<T: Copy>(mut v: Vec<(IVec3, T)>) -> Vec<(IVec3, T)> {
    v.sort_by_key(|(c, _)| c.to_array());
    v
}

/// Voxels scattered in clusters far apart (several root tiles, several nodes per level), with
/// values of every magnitude.
fn scattered(seed: u64, n: usize) -> Vec<(IVec3, f32)> {
    let mut rng = Lcg(seed);
    let centres = [
        IVec3::ZERO,
        IVec3::new(9000, 10, 3),
        IVec3::new(-5000, 4200, 100),
        IVec3::new(100, 100, 20000),
    ];
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    while out.len() < n {
        let c = centres[rng.next() as usize % 4]
            + IVec3::new(rng.next() as i32 % 300, rng.next() as i32 % 300, rng.next() as i32 % 300);
        if seen.insert(c) {
            let v = (rng.unit() - 0.3) * 10f32.powi(rng.next() as i32 % 13 - 6);
            out.push((c, v));
        }
    }
    out
}

#[test]
fn float_grids_round_trip_exactly_through_several_root_tiles() {
    let voxels = scattered(7, 5000);
    let grid = float_grid(voxels.clone());
    let (bytes, summary) = encode(&[AnyGrid::Float(grid.clone())]).unwrap();
    assert_eq!(summary[0].voxels, 5000);
    assert_eq!(summary[0].nodes[3], 4, "one root tile per cluster: {summary:?}");
    assert!(summary[0].nodes[0] > summary[0].nodes[1] && summary[0].nodes[1] >= 4, "{summary:?}");
    let back = decode(&bytes, Path::new("mem.nvdb")).unwrap();
    let [AnyGrid::Float(b)] = &back[..] else { panic!("{back:?}") };
    assert_eq!((&b.name, b.class, b.map, b.background), (&grid.name, grid.class, grid.map, 0.0));
    // Same active set, bit-identical values.
    let (a, b) = (sorted(voxels), sorted(b.voxels.clone()));
    assert_eq!(a.len(), b.len());
    for ((ca, va), (cb, vb)) in a.iter().zip(&b) {
        assert_eq!((ca, va.to_bits()), (cb, vb.to_bits()));
    }
}

#[test]
fn density_and_colour_of_an_averages_grid_round_trip_in_one_file() {
    let grid = GridSpec::new(DVec3::new(-1.0, 2.0, 0.5), 0.125, UVec3::new(40, 30, 20)).unwrap();
    let mut rng = Lcg(3);
    let mut cells = std::collections::BTreeMap::new();
    while cells.len() < 900 {
        let c = UVec3::new(rng.next() % 40, rng.next() % 30, rng.next() % 20);
        let rec =
            AverageRecord::new(Vec3::new(rng.unit(), rng.unit(), rng.unit()), Vec3::Y, rng.unit());
        cells.insert(c.to_array(), rec);
    }
    let map =
        BrickMap::from_voxels(grid.dims, cells.iter().map(|(c, r)| (UVec3::from_array(*c), *r)))
            .unwrap();
    let (density, color) = density_and_color(&grid, &map).unwrap();
    let dir = std::env::temp_dir().join(format!("voxlod-nvdb-test-{}", std::process::id()));
    let path = dir.join("averages.nvdb");
    let summary = write(&path, &[density.clone().into(), color.clone().into()]).unwrap();
    assert_eq!(
        summary.iter().map(|s| (s.name.as_str(), s.grid_type)).collect::<Vec<_>>(),
        [("density", GridType::Float), ("color", GridType::Vec3f)]
    );
    let back = read(&path).unwrap();
    let [AnyGrid::Float(d), AnyGrid::Vec3f(c)] = &back[..] else { panic!("{back:?}") };
    assert_eq!(d.class, GridClass::FogVolume);
    for (c0, r) in map.iter() {
        let i = c0.as_ivec3();
        let dv = d.voxels.iter().find(|v| v.0 == i).unwrap().1;
        assert_eq!(dv, extinction_from_opacity(r.opacity(), 0.125), "density at {c0}");
        assert_eq!(c.voxels.iter().find(|v| v.0 == i).unwrap().1, r.color(), "colour at {c0}");
    }
    assert_eq!((d.voxels.len(), c.voxels.len()), (map.len(), map.len()));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_map_puts_index_ijk_on_the_centre_of_voxlod_voxel_ijk() {
    let grid = GridSpec::new(DVec3::new(10.0, -3.0, 0.25), 0.5, UVec3::new(8, 8, 8)).unwrap();
    let map = BrickMap::from_voxels(
        grid.dims,
        [(UVec3::new(0, 0, 0), 1.0f32), (UVec3::new(7, 3, 5), 2.0)],
    )
    .unwrap();
    let g = NvdbGrid::from_brick_map("density", GridClass::FogVolume, &grid, &map, |&v| v).unwrap();
    for c in [UVec3::ZERO, UVec3::new(7, 3, 5)] {
        // voxlod: centre = origin + (c + ½)·size; VDB: index c is the centre.
        assert_eq!(g.map.apply(c.as_dvec3()), grid.voxel_center(c));
        assert_eq!(grid.voxel_of(g.map.apply(c.as_dvec3())), Some(c));
    }
    // Without the half-voxel translation, index c would land on the voxel's corner.
    assert_ne!(g.map.translation, grid.origin);
    let (bytes, _) = encode(&[g.into()]).unwrap();
    let at = HEADER_BYTES + META_BYTES + "density".len() + 1;
    let grid_bytes = &bytes[at..];
    // mVecD and mMatD as stored.
    let t: Vec<f64> = (0..3).map(|r| f64_at(grid_bytes, 528 + 8 * r)).collect();
    assert_eq!(t, [10.25, -2.75, 0.5]);
    assert_eq!((f64_at(grid_bytes, 384), f64_at(grid_bytes, 384 + 8)), (0.5, 0.0));
    // World bbox: NanoVDB's GridStats convention, the map of the index box [min, max + 1].
    let world: Vec<f64> = (0..6).map(|i| f64_at(grid_bytes, 560 + 8 * i)).collect();
    assert_eq!(world, [10.25, -2.75, 0.5, 10.25 + 4.0, -2.75 + 2.0, 0.5 + 3.0]);
    // Voxel size.
    assert_eq!(f64_at(grid_bytes, 608), 0.5);
}

#[test]
fn the_file_and_grid_headers_follow_nanovdb_32_4() {
    let voxels = vec![
        (IVec3::new(1, 2, 3), 0.5f32),
        (IVec3::new(4, 2, 3), 1.5),
        (IVec3::new(4100, 0, 0), -1.0),
    ];
    let (bytes, summary) = encode(&[float_grid(voxels).into()]).unwrap();
    // Segment header.
    assert_eq!(&bytes[0..8], b"NanoVDB0");
    assert_eq!(u32_at(&bytes, 8), (32 << 21) | (4 << 10) | 2);
    assert_eq!(
        (u16::from_le_bytes([bytes[12], bytes[13]]), u16::from_le_bytes([bytes[14], bytes[15]])),
        (1, 0)
    );
    // Metadata record.
    let m = &bytes[HEADER_BYTES..];
    let sz = Sizes::of(4);
    let size = GRID_BYTES + 64 + sz.root + 2 * 32 + 2 * sz.upper + 2 * sz.lower + 2 * sz.leaf;
    assert_eq!((u64_at(m, 0), u64_at(m, 8)), (size as u64, size as u64));
    assert_eq!(u64_at(m, 16), name_hash("density"));
    assert_eq!(u64_at(m, 24), 3);
    assert_eq!((u32_at(m, 32), u32_at(m, 36)), (1, 2), "type float, class fog volume");
    assert_eq!((0..6).map(|i| i32_at(m, 88 + 4 * i)).collect::<Vec<_>>(), [1, 0, 0, 4100, 2, 3]);
    assert_eq!(u32_at(m, 136), 8, "name length with its NUL");
    assert_eq!((0..4).map(|i| u32_at(m, 140 + 4 * i)).collect::<Vec<_>>(), [2, 2, 2, 1]);
    assert_eq!(&m[META_BYTES..META_BYTES + 8], b"density\0");
    // Grid.
    let g = &m[META_BYTES + 8..];
    assert_eq!(g.len(), size);
    assert_eq!(&g[0..8], b"NanoVDB0");
    assert_eq!(u64_at(g, 8), summary[0].checksum);
    assert_eq!(u32_at(g, 20), 62, "bbox, min/max, average, deviation, breadth first");
    assert_eq!((u32_at(g, 24), u32_at(g, 28), u64_at(g, 32)), (0, 1, size as u64));
    assert_eq!(&g[40..48], b"density\0");
    // Tree: offsets to the first leaf, lower, upper and the root; counts; voxels.
    let tree = GRID_BYTES;
    let upper = 672 + 64 + sz.root + 64;
    assert_eq!(
        (0..4).map(|i| u64_at(g, tree + 8 * i) as usize + tree).collect::<Vec<_>>(),
        [upper + 2 * sz.upper + 2 * sz.lower, upper + 2 * sz.upper, upper, 736]
    );
    assert_eq!(u64_at(g, tree + 56), 3);
    // Root: bbox, tile count, background 0, min −1, max 1.5; tile keys and child offsets.
    let root = 736;
    assert_eq!((0..6).map(|i| i32_at(g, root + 4 * i)).collect::<Vec<_>>(), [1, 0, 0, 4100, 2, 3]);
    assert_eq!(u32_at(g, root + 24), 2);
    let f = |at: usize| f32::from_le_bytes(g[at..at + 4].try_into().unwrap());
    assert_eq!((f(root + 28), f(root + 32), f(root + 36)), (0.0, -1.0, 1.5));
    assert!((f(root + 40) - 1.0 / 3.0).abs() < 1e-7, "average {}", f(root + 40));
    assert_eq!(u64_at(g, root + 64), 0);
    assert_eq!(u64_at(g, root + 96), 1 << 42, "key of the upper node at x = 4096");
    assert_eq!(u64_at(g, root + 96 + 8) as usize, upper + sz.upper - root);
    // The first leaf: active bbox (1, 2, 3) … (4, 2, 3), flags, its two mask bits, values.
    let leaf = upper + 2 * sz.upper + 2 * sz.lower;
    assert_eq!((0..3).map(|i| i32_at(g, leaf + 4 * i)).collect::<Vec<_>>(), [1, 2, 3]);
    assert_eq!(&g[leaf + 12..leaf + 16], &[3, 0, 0, 2]);
    let bit = |x: usize, y: usize, z: usize| (x << 6) | (y << 3) | z;
    assert_eq!(u64_at(g, leaf + 16 + 8 * (bit(1, 2, 3) / 64)) >> (bit(1, 2, 3) % 64) & 1, 1);
    assert_eq!(f(leaf + sz.leaf_values + 4 * bit(4, 2, 3)), 1.5);
    // The checksum covers the bytes: its low half is the CRC-32 of the header after byte 16.
    assert_eq!(summary[0].checksum as u32, crc32fast::hash(&g[16..root + sz.root + 64]));
}

/// The grids of `the_checksums_match_the_ones_nanovdb_computes`, in `path` if given.
fn reference_grids(path: Option<&Path>) -> Vec<GridSummary> {
    let one = float_grid(vec![(IVec3::new(1, 2, 3), 1.0)]);
    let color = NvdbGrid {
        name: "color".into(),
        class: GridClass::Unknown,
        map: IndexToWorld {
            matrix: DMat3::from_diagonal(DVec3::splat(0.5)),
            translation: DVec3::new(1.0, 2.0, 3.0),
        },
        background: Vec3::ZERO,
        voxels: vec![
            (IVec3::new(1, 2, 3), Vec3::new(0.25, 0.5, 1.0)),
            (IVec3::new(5000, -7, 3), Vec3::X),
        ],
    };
    let mut out = Vec::new();
    let (one, color) = (AnyGrid::from(one), AnyGrid::from(color));
    for (name, g) in [("ref_one.nvdb", one.clone()), ("ref_vec3.nvdb", color.clone())] {
        match path {
            Some(dir) => out.extend(write(dir.join(name), &[g]).unwrap()),
            None => out.extend(encode(&[g]).unwrap().1),
        }
    }
    if let Some(dir) = path {
        write(dir.join("ref_both.nvdb"), &[one, color]).unwrap();
    }
    out
}

#[test]
fn the_checksums_match_the_ones_nanovdb_computes() {
    // The same grids built by NanoVDB 32.4's GridBuilder (OpenVDB 10.0.1's headers: background
    // 0, the same class, voxel size and translation, ChecksumMode::Full) have these checksums
    // and sizes. With VOXLOD_NVDB_REFERENCE_DIR set, the files are written there (each grid
    // alone, and both in one file) to compare with NanoVDB's io::writeGrid(s) byte for byte.
    let s =
        reference_grids(std::env::var_os("VOXLOD_NVDB_REFERENCE_DIR").as_deref().map(Path::new));
    assert_eq!(
        (s[0].checksum, s[0].bytes),
        (0xeddf3a41d1fff678, 307_232),
        "{:#018x}",
        s[0].checksum
    );
    assert_eq!(
        (s[1].checksum, s[1].bytes),
        (0x5a1b0a254115786a, 1_211_776),
        "{:#018x}",
        s[1].checksum
    );
}

#[test]
fn corrupted_truncated_and_compressed_files_are_refused() {
    let (bytes, _) = encode(&[float_grid(scattered(1, 300)).into()]).unwrap();
    let p = Path::new("x.nvdb");
    // A flipped bit in the last leaf's values: the tail CRC.
    let mut b = bytes.clone();
    let n = b.len() - 100;
    b[n] ^= 1;
    assert!(matches!(decode(&b, p), Err(Error::ChecksumMismatch { .. })), "{:?}", decode(&b, p));
    // In the grid's name: the head CRC (and the metadata's name no longer matches either).
    let mut b = bytes.clone();
    b[HEADER_BYTES + META_BYTES + 8 + 40] = b'D';
    let err = decode(&b, p).unwrap_err();
    assert!(matches!(err, Error::ChecksumMismatch { .. }), "{err}");
    // Truncated.
    for len in [0usize, 10, HEADER_BYTES + 100, bytes.len() - 1] {
        let err = decode(&bytes[..len], p).unwrap_err();
        assert!(matches!(err, Error::Malformed { .. }), "{len}: {err}");
    }
    // Compressed (the codec field of the segment header).
    let mut b = bytes.clone();
    b[14] = 2;
    let err = decode(&b, p).unwrap_err();
    assert!(matches!(err, Error::Unsupported { .. }) && err.to_string().contains("blosc"), "{err}");
    // Another major version.
    let mut b = bytes.clone();
    b[8..12].copy_from_slice(&((31u32 << 21) | (1 << 10)).to_le_bytes());
    assert!(matches!(decode(&b, p), Err(Error::UnsupportedVersion { found: 31, .. })));
    // A disabled checksum (all ones) is accepted.
    let mut b = bytes.clone();
    let g = HEADER_BYTES + META_BYTES + 8;
    b[g + 8..g + 16].fill(0xff);
    assert_eq!(decode(&b, p).unwrap(), decode(&bytes, p).unwrap());
}

#[test]
fn what_nanovdb_cannot_hold_is_refused_with_the_voxel_named() {
    let check = |grid: NvdbGrid<f32>, needle: &str| {
        let err = encode(&[grid.into()]).unwrap_err();
        assert!(matches!(err, Error::Unrepresentable { format: "nvdb", .. }), "{err}");
        assert!(err.to_string().contains(needle), "{needle:?} not in: {err}");
    };
    check(float_grid(vec![]), "no active voxel");
    check(
        float_grid(vec![(IVec3::ONE, 1.0), (IVec3::new(3, -4, 5), f32::NAN)]),
        "voxel [3, -4, 5]",
    );
    check(float_grid(vec![(IVec3::new(0, 1 << 30, 0), 1.0)]), "index coordinates are limited");
    check(float_grid(vec![(IVec3::new(0, i32::MIN, 0), 1.0)]), "index coordinates are limited");
    check(float_grid(vec![(IVec3::new(9, 9, 9), 1.0), (IVec3::new(9, 9, 9), 2.0)]), "given twice");
    let mut g = float_grid(vec![(IVec3::ONE, 1.0)]);
    g.name = "x".repeat(256);
    check(g, "256 bytes");
    let mut g = float_grid(vec![(IVec3::ONE, 1.0)]);
    g.map.matrix = DMat3::from_diagonal(DVec3::new(1.0, 1.0, 2.0));
    check(g, "uniform scale");
    let mut g = float_grid(vec![(IVec3::ONE, 1.0)]);
    g.map.matrix.y_axis = DVec3::new(0.5, 0.0, 0.0).normalize() * 0.0 + DVec3::new(0.6, 0.8, 0.0);
    check(g, "orthogonal");
    assert!(matches!(encode(&[]), Err(Error::Unrepresentable { .. })));
    // A rotated map is fine.
    let mut g = float_grid(vec![(IVec3::ONE, 1.0)]);
    g.map.matrix = DMat3::from_rotation_y(0.3) * 0.25;
    let (bytes, _) = encode(&[g.clone().into()]).unwrap();
    let back = decode(&bytes, Path::new("r.nvdb")).unwrap();
    assert_eq!(back, [AnyGrid::Float(g)]);
}

#[test]
fn nanovdb_string_hash() {
    // stringHash: h ← h·67 + c + (h >> 56), from 0.
    assert_eq!(name_hash(""), 0);
    assert_eq!(name_hash("a"), 97);
    assert_eq!(name_hash("ab"), 97 * 67 + 98);
}

mod properties {
    use proptest::prelude::*;

    use super::*;

    /// Up to 40 voxels around up to three anchors anywhere in the supported index range
    /// (negative included), with any finite `f32` bits (subnormals, −0 and extremes included).
    fn voxels() -> impl Strategy<Value = Vec<(IVec3, f32)>> {
        let anchor = prop::array::uniform3(-MAX_INDEX + 64..MAX_INDEX - 64);
        let value = any::<u32>().prop_map(f32::from_bits).prop_filter("finite", |v| v.is_finite());
        (
            prop::collection::vec(anchor, 1..=3),
            prop::collection::vec((0usize..3, prop::array::uniform3(-40i32..40), value), 1..40),
        )
            .prop_map(|(anchors, offsets)| {
                let mut seen = std::collections::HashSet::new();
                offsets
                    .into_iter()
                    .map(|(a, o, v)| {
                        (IVec3::from_array(anchors[a % anchors.len()]) + IVec3::from_array(o), v)
                    })
                    .filter(|(c, _)| seen.insert(*c))
                    .collect()
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        /// Any grid round-trips to the same active set with bit-identical values.
        #[test]
        fn any_float_grid_round_trips(voxels in voxels()) {
            let grid = float_grid(voxels.clone());
            let (bytes, summary) = encode(&[grid.into()]).unwrap();
            prop_assert_eq!(summary[0].voxels as usize, voxels.len());
            let back = decode(&bytes, Path::new("p.nvdb")).unwrap();
            let AnyGrid::Float(b) = &back[0] else { panic!("{back:?}") };
            let bits = |v: Vec<(IVec3, f32)>| sorted(v).into_iter().map(|(c, x)| (c, x.to_bits())).collect::<Vec<_>>();
            prop_assert_eq!(bits(b.voxels.clone()), bits(voxels));
        }

        /// Corrupted bytes, with the checksum disabled so that the walk itself meets them, give
        /// an error or a grid, never a panic.
        #[test]
        fn corrupted_files_never_panic(seed in any::<u64>(), flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..16)) {
            let mut rng = Lcg(seed);
            let voxels: Vec<(IVec3, f32)> = (0..20).map(|i| (IVec3::new(i * 37, (rng.next() % 5000) as i32, -(i * 11)), i as f32)).collect();
            let (mut bytes, _) = encode(&[float_grid(voxels).into()]).unwrap();
            let g = HEADER_BYTES + META_BYTES + 8;
            bytes[g + 8..g + 16].fill(0xff);
            // Flips in the headers, the root and the node tables, where offsets live.
            let hot = g + GRID_BYTES + 64 + 256;
            for (at, x) in flips {
                let i = if x % 2 == 0 { at.index(hot) } else { at.index(bytes.len()) };
                bytes[i] ^= x | 1;
            }
            let _ = decode(&bytes, Path::new("c.nvdb"));
        }
    }
}
