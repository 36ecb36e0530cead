use std::path::Path;

use glam::{IVec3, UVec3};

use super::*;
use crate::Occupancy;

fn mem() -> &'static Path {
    Path::new("<memory>")
}

/// A deterministic pseudo-random stream (splitmix64).
fn rng(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed;
    move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// `n` distinct random voxels in `dims`, each with a random colour.
fn random_map(dims: UVec3, n: usize, seed: u64) -> BrickMap<[u8; 3]> {
    let mut next = rng(seed);
    let mut seen = std::collections::HashSet::new();
    let mut voxels = Vec::new();
    while voxels.len() < n {
        let c = UVec3::new(
            (next() % dims.x as u64) as u32,
            (next() % dims.y as u64) as u32,
            (next() % dims.z as u64) as u32,
        );
        if seen.insert(c) {
            let v = next();
            voxels.push((c, [v as u8, (v >> 8) as u8, (v >> 16) as u8]));
        }
    }
    BrickMap::from_voxels(dims, voxels).unwrap()
}

/// The occupied coordinates of a map read back, shifted so that the original's bounding box
/// minimum is the origin of both.
fn same_occupancy<T>(original: &BrickMap<T>, file: &VoxFile) {
    let (min, back) = file.to_brick_map().unwrap();
    let lo = original.coords().fold(UVec3::MAX, |a, c| a.min(c));
    let mut expected: Vec<UVec3> = original.coords().map(|c| c - lo).collect();
    let mut got: Vec<UVec3> = back.coords().collect();
    expected.sort_unstable_by_key(|c| (c.z, c.y, c.x));
    got.sort_unstable_by_key(|c| (c.z, c.y, c.x));
    assert_eq!(got, expected);
    // The box minimum maps back to voxlod axes: (i, j, k) → MagicaVoxel (i − X/2, Z/2 − 1 − k, j).
    let d = original.dims().as_ivec3();
    let lo = lo.as_ivec3();
    assert_eq!(min, IVec3::new(lo.x - d.x / 2, lo.y, lo.z - d.z + d.z / 2));
}

#[test]
fn header_chunks_and_scene_graph_follow_the_documented_layout() {
    let map =
        BrickMap::from_voxels(UVec3::new(3, 2, 5), [(UVec3::new(2, 1, 4), [9u8, 8, 7])]).unwrap();
    let e = encode(&map, |&c| c).unwrap();
    let b = &e.bytes;
    let i32_at = |o: usize| i32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    assert_eq!(&b[0..4], b"VOX ");
    assert_eq!(i32_at(4), 150);
    assert_eq!(&b[8..12], b"MAIN");
    assert_eq!((i32_at(12), i32_at(16) as usize), (0, b.len() - 20));
    // SIZE: the model of a (3, 2, 5) grid is (X, Z, Y) = (3, 5, 2) rounded up to even.
    assert_eq!(&b[20..24], b"SIZE");
    assert_eq!((i32_at(24), i32_at(28)), (12, 0));
    assert_eq!((i32_at(32), i32_at(36), i32_at(40)), (4, 6, 2));
    // XYZI: one voxel, (i, Z − 1 − k, j) = (2, 0, 1), colour index 1.
    assert_eq!(&b[44..48], b"XYZI");
    assert_eq!((i32_at(48), i32_at(56)), (8, 1));
    assert_eq!(b[60..64], [2, 0, 1, 1]);
    // Root transform node 0 → group 1 → transform 2 (translation) → shape 3 (model 0).
    assert_eq!(&b[64..68], b"nTRN");
    let root = 76;
    assert_eq!((i32_at(root), i32_at(root + 4)), (0, 0)); // id, empty attributes
    assert_eq!((i32_at(root + 8), i32_at(root + 12)), (1, -1)); // child, reserved
    assert_eq!((i32_at(root + 16), i32_at(root + 20)), (-1, 1)); // layer, frames
    let text = String::from_utf8_lossy(b);
    // The model's centre: (2, 3, 1) in the scene's voxels, minus the scene's centre (1, 2, 0).
    assert!(text.contains("\u{2}\0\0\0_t\u{5}\0\0\0\x31 1 1"), "{text:?}");
    assert!(text.contains("nGRP") && text.contains("nSHP"));
    // RGBA last: 256 entries, entry 0 = colour index 1.
    let rgba = b.len() - 1024;
    assert_eq!(&b[rgba - 12..rgba - 8], b"RGBA");
    assert_eq!(b[rgba..rgba + 8], [9, 8, 7, 255, 0, 0, 0, 0]);
    let file = decode(b, mem()).unwrap();
    let identity = VoxRotation::IDENTITY;
    assert_eq!(
        file.instances,
        [VoxInstance { model: 0, rotation: identity, translation: IVec3::ONE }]
    );
    assert_eq!(file.world_voxels().collect::<Vec<_>>(), [(IVec3::new(1, -2, 1), 1)]);
    same_occupancy(&map, &file);
}

#[test]
fn small_grid_round_trips_with_exact_colours() {
    let map = random_map(UVec3::new(40, 17, 33), 600, 1).map(|c| [c[0] & 0xF0, 64, 200]);
    let e = encode(&map, |&c| c).unwrap();
    assert_eq!((e.models, e.palette.error.distinct_colors), (1, 16));
    assert_eq!((e.palette.error.rms, e.palette.error.max), (0.0, 0));
    let file = decode(&e.bytes, mem()).unwrap();
    same_occupancy(&map, &file);
    let (min, back) = file.to_brick_map().unwrap();
    let lo = map.coords().fold(UVec3::MAX, |a, c| a.min(c));
    for (c, index) in back.iter() {
        let original = map.get(c + lo).unwrap();
        let _ = min;
        assert_eq!(file.palette[*index as usize][..3], original[..]);
    }
}

#[test]
fn grids_over_256_become_several_models_placed_by_the_scene_graph() {
    // 600 × 20 × 300 voxels: tiles of 256 along x (3) and along MagicaVoxel's y = voxlod's z (2).
    let dims = UVec3::new(600, 20, 300);
    let mut voxels: Vec<(UVec3, ())> =
        (0..600).map(|x| (UVec3::new(x, 3, 299 - x / 2), ())).collect();
    // The diagonal crosses tiles (0, 0), (1, 0) and (2, 1) of MagicaVoxel's (x, y); these
    // fill (0, 1), (1, 1) and (2, 0) and touch the grid's corners and a tile's edge.
    let more = [(0, 0, 0), (599, 19, 0), (255, 7, 44), (300, 0, 0), (520, 0, 299)];
    voxels.extend(more.map(|(x, y, z)| (UVec3::new(x, y, z), ())));
    let map = BrickMap::from_voxels(dims, voxels).unwrap();
    let e = encode(&map, |_| [200, 200, 200]).unwrap();
    assert_eq!(e.models, 6);
    let file = decode(&e.bytes, mem()).unwrap();
    assert_eq!(file.models.len(), 6);
    assert_eq!(file.instances.len(), 6);
    assert!(file.models.iter().all(|m| m.size.cmple(UVec3::splat(256)).all()));
    assert!(file.models.iter().all(|m| m.size % 2 == UVec3::ZERO));
    same_occupancy(&map, &file);
    let path = std::env::temp_dir().join(format!("voxlod-vox-{}.vox", std::process::id()));
    let written = write(&path, &map, |_| [1, 2, 3]).unwrap();
    same_occupancy(&map, &read(&path).unwrap());
    assert_eq!(std::fs::metadata(&path).unwrap().len(), written.bytes.len() as u64);
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn palette_error_of_many_colours_is_measured_and_lloyd_does_not_worsen_it() {
    // 20 000 voxels of random colours over the whole sRGB cube: the hardest case, no structure.
    let map = random_map(UVec3::splat(64), 20_000, 7);
    let e = encode(&map, |&c| c).unwrap();
    let err = e.palette.error;
    assert_eq!(e.palette.colors.len(), MAX_COLORS);
    assert!(err.distinct_colors > 19_000);
    // Uniform colours in 255 cells: cells of edge ≈ 256/255^(1/3) ≈ 40, so an RMS per channel
    // near 40/√12 ≈ 11.6 is the ideal; the result must be within 1.5× of it.
    println!("random colours: {err:?}");
    assert!(err.rms < 17.5, "{err:?}");
    assert!(err.rms <= err.rms_median_cut + 0.05, "{err:?}");
    // The reported error is the error of the colours the file holds.
    let file = decode(&e.bytes, mem()).unwrap();
    let (mut sum, mut n) = (0.0f64, 0.0f64);
    let lo = map.coords().fold(UVec3::MAX, |a, c| a.min(c));
    let (_, back) = file.to_brick_map().unwrap();
    for (c, index) in back.iter() {
        let p = file.palette[*index as usize];
        let o = map.get(c + lo).unwrap();
        for i in 0..3 {
            sum += (p[i] as f64 - o[i] as f64).powi(2);
            n += 1.0;
        }
    }
    assert!(((sum / n).sqrt() - err.rms).abs() < 1e-9, "{} vs {err:?}", (sum / n).sqrt());
    // A smooth gradient (what shaded albedo looks like) quantizes far better.
    let ramp = BrickMap::from_voxels(
        UVec3::splat(32),
        (0..4096u32).map(|i| {
            (UVec3::new(i % 32, i / 32 % 32, i / 1024), [(i / 16) as u8, (i % 256) as u8, 128])
        }),
    )
    .unwrap();
    let ramp_err = encode(&ramp, |&c| c).unwrap().palette.error;
    println!("gradient: {ramp_err:?}");
    assert!(ramp_err.rms < 6.0, "{ramp_err:?}");
}

#[test]
fn refuses_empty_grids_and_reads_strictly() {
    let empty = BrickMap::<Occupancy>::new(UVec3::splat(4));
    assert!(matches!(
        encode(&empty, |_| [0; 3]),
        Err(Error::Unrepresentable { format: "vox", .. })
    ));
    let map = random_map(UVec3::new(9, 5, 7), 30, 3);
    let bytes = encode(&map, |&c| c).unwrap().bytes;
    for len in 0..bytes.len() {
        assert!(decode(&bytes[..len], mem()).is_err(), "truncated to {len}");
    }
    let patched = |offset: usize, with: &[u8]| {
        let mut b = bytes.clone();
        b[offset..offset + with.len()].copy_from_slice(with);
        decode(&b, mem())
    };
    assert!(patched(0, b"VOY ").is_err());
    assert!(matches!(patched(4, &201i32.to_le_bytes()), Err(Error::UnsupportedVersion { .. })));
    assert!(patched(32, &300i32.to_le_bytes()).is_err()); // model size x over 256
    assert!(patched(63, &[0]).is_err()); // colour index 0 of the first voxel
    assert!(patched(60, &[200]).is_err()); // voxel outside its model
    // A rotation byte in the frame dictionary: a signed permutation reads, anything else is
    // malformed (named, not guessed).
    let text = b"\x02\0\0\0_t";
    let at = bytes.windows(text.len()).position(|w| w == text).unwrap();
    let with_rotation = |r: &str| {
        let mut rotated = bytes[..at].to_vec();
        // Splice in "_r" → r before "_t".
        rotated.extend_from_slice(b"\x02\0\0\0_r");
        rotated.extend_from_slice(&(r.len() as i32).to_le_bytes());
        rotated.extend_from_slice(r.as_bytes());
        rotated.extend_from_slice(&bytes[at..]);
        let grown = 10 + r.len() as i32;
        // Fix the counts: the pair count (just before the key) and the chunk and MAIN lengths.
        let count_at = at - 4;
        rotated[count_at..count_at + 4].copy_from_slice(&2i32.to_le_bytes());
        let trn = rotated[..at].windows(4).rposition(|w| w == b"nTRN").unwrap();
        let n = i32::from_le_bytes(rotated[trn + 4..trn + 8].try_into().unwrap()) + grown;
        rotated[trn + 4..trn + 8].copy_from_slice(&n.to_le_bytes());
        let m = i32::from_le_bytes(rotated[16..20].try_into().unwrap()) + grown;
        rotated[16..20].copy_from_slice(&m.to_le_bytes());
        decode(&rotated, mem())
    };
    let file = with_rotation("17").unwrap();
    assert_eq!(file.instances[0].rotation.rows(), [[0, -1, 0], [1, 0, 0], [0, 0, 1]]);
    assert_eq!(with_rotation("4").unwrap().instances, decode(&bytes, mem()).unwrap().instances);
    for bad in ["0", "3", "7", "15", "128", "-1", "x"] {
        let e = with_rotation(bad).unwrap_err();
        assert!(matches!(e, Error::Malformed { format: "vox", .. }), "{bad}: {e}");
        assert!(e.to_string().contains("rotation"), "{bad}: {e}");
    }
}

/// A `.vox` file built by hand: models `(size, voxels)`, scene-graph chunks, an optional
/// palette.
fn hand_built(models: &[(UVec3, Vec<[u8; 4]>)], graph: &[u8], rgba: Option<&[u8]>) -> Vec<u8> {
    let mut body = Vec::new();
    for (size, voxels) in models {
        let s: Vec<u8> = size.to_array().iter().flat_map(|v| (*v as i32).to_le_bytes()).collect();
        chunk(&mut body, b"SIZE", &s);
        let mut c = (voxels.len() as i32).to_le_bytes().to_vec();
        voxels.iter().for_each(|v| c.extend_from_slice(v));
        chunk(&mut body, b"XYZI", &c);
    }
    body.extend_from_slice(graph);
    if let Some(rgba) = rgba {
        chunk(&mut body, b"RGBA", rgba);
    }
    let mut b = b"VOX ".to_vec();
    b.extend_from_slice(&200i32.to_le_bytes());
    b.extend_from_slice(b"MAIN");
    b.extend_from_slice(&0i32.to_le_bytes());
    b.extend_from_slice(&(body.len() as i32).to_le_bytes());
    b.extend_from_slice(&body);
    b
}

/// A transform node with a rotation byte and a translation in its frame.
fn rotated_node(id: i32, child: i32, r: Option<u8>, t: IVec3) -> Vec<u8> {
    let mut c = id.to_le_bytes().to_vec();
    dict(&mut c, &[]);
    for x in [child, -1, 0, 1] {
        c.extend_from_slice(&x.to_le_bytes());
    }
    let t = format!("{} {} {}", t.x, t.y, t.z);
    match r {
        Some(r) => dict(&mut c, &[("_r", &r.to_string()), ("_t", &t)]),
        None => dict(&mut c, &[("_t", &t)]),
    }
    let mut out = Vec::new();
    chunk(&mut out, b"nTRN", &c);
    out
}

fn graph_chunk(id: &[u8; 4], content: Vec<u8>) -> Vec<u8> {
    let mut out = Vec::new();
    chunk(&mut out, id, &content);
    out
}

/// Every voxel of a 1×2×3 model, coloured 1 + x + y + 2z so each is recognisable.
fn block_1x2x3() -> (UVec3, Vec<[u8; 4]>) {
    let mut voxels = Vec::new();
    for z in 0..3u8 {
        for y in 0..2u8 {
            voxels.push([0, y, z, 1 + y + 2 * z]);
        }
    }
    (UVec3::new(1, 2, 3), voxels)
}

/// World voxels sorted by colour.
fn by_colour(file: &VoxFile) -> Vec<(u8, IVec3)> {
    let mut v: Vec<(u8, IVec3)> = file.world_voxels().map(|(p, c)| (c, p)).collect();
    v.sort_unstable_by_key(|(c, _)| *c);
    v
}

#[test]
fn rotation_bytes_are_the_48_signed_permutations() {
    let valid: Vec<VoxRotation> = (0..=255u8).filter_map(VoxRotation::from_byte).collect();
    assert_eq!(valid.len(), 48);
    for r in &valid {
        assert_eq!(VoxRotation::from_byte(r.to_byte()), Some(*r));
        assert_eq!(r.determinant().abs(), 1);
        // Composition is the matrix product.
        for s in &valid {
            let (a, b, ab) = (r.rows(), s.rows(), r.then_inner(*s).rows());
            for i in 0..3 {
                for j in 0..3 {
                    let dot: i32 = (0..3).map(|k| a[i][k] * b[k][j]).sum();
                    assert_eq!(ab[i][j], dot, "{r:?} · {s:?}");
                }
            }
        }
    }
    assert_eq!(valid.iter().filter(|r| r.determinant() == 1).count(), 24);
    assert_eq!(VoxRotation::from_byte(IDENTITY_ROTATION), Some(VoxRotation::IDENTITY));
}

#[test]
fn a_rotated_1x2x3_model_lands_where_computed_by_hand() {
    // The specification's example rotation: rows (0 1 0), (0 0 −1), (−1 0 0), byte
    // 1 | 2<<2 | 1<<5 | 1<<6 = 105, translated by (10, 20, 30).
    // Voxel (0, y, z) has its centre at (0.5, y + 0.5, z + 0.5) − pivot ⌊(1, 2, 3)/2⌋ = (0, 1, 1),
    // i.e. (0.5, y − 0.5, z − 0.5); R maps it to (y − 0.5, 0.5 − z, −0.5); plus (10, 20, 30):
    // (9.5 + y, 20.5 − z, 29.5), the cell with minimum corner (9 + y, 20 − z, 29).
    let graph = [
        rotated_node(0, 1, Some(105), IVec3::new(10, 20, 30)),
        graph_chunk(b"nSHP", shape_node(1, 0)),
    ]
    .concat();
    let bytes = hand_built(&[block_1x2x3()], &graph, None);
    let file = decode(&bytes, mem()).unwrap();
    let expected = [
        (1, IVec3::new(9, 20, 29)),  // (0, 0, 0)
        (2, IVec3::new(10, 20, 29)), // (0, 1, 0)
        (3, IVec3::new(9, 19, 29)),  // (0, 0, 1)
        (4, IVec3::new(10, 19, 29)), // (0, 1, 1)
        (5, IVec3::new(9, 18, 29)),  // (0, 0, 2)
        (6, IVec3::new(10, 18, 29)), // (0, 1, 2)
    ];
    assert_eq!(by_colour(&file), expected);

    // The same under a parent turning a quarter about z (x' = −y, y' = x; byte 1 | 1<<4 = 17)
    // and moving by (100, 0, 0): the centre (9.5 + y, 20.5 − z, 29.5) goes to
    // (100 − 20.5 + z, 9.5 + y, 29.5), the cell (79 + z, 9 + y, 29).
    let graph = [
        rotated_node(0, 1, Some(17), IVec3::new(100, 0, 0)),
        graph_chunk(b"nGRP", group_node(1, &[2])),
        rotated_node(2, 3, Some(105), IVec3::new(10, 20, 30)),
        graph_chunk(b"nSHP", shape_node(3, 0)),
    ]
    .concat();
    let file = decode(&hand_built(&[block_1x2x3()], &graph, None), mem()).unwrap();
    let expected = [
        (1, IVec3::new(79, 9, 29)),
        (2, IVec3::new(79, 10, 29)),
        (3, IVec3::new(80, 9, 29)),
        (4, IVec3::new(80, 10, 29)),
        (5, IVec3::new(81, 9, 29)),
        (6, IVec3::new(81, 10, 29)),
    ];
    assert_eq!(by_colour(&file), expected);
    assert_eq!(file.instances[0].translation, IVec3::new(80, 10, 30));

    // Without a rotation the model's minimum corner is t − ⌊size/2⌋ (the unrotated rule):
    // voxel (0, 1, 2) at (10, 20, 30) − (0, 1, 1) + (0, 1, 2).
    let graph =
        [rotated_node(0, 1, None, IVec3::new(10, 20, 30)), graph_chunk(b"nSHP", shape_node(1, 0))]
            .concat();
    let file = decode(&hand_built(&[block_1x2x3()], &graph, None), mem()).unwrap();
    assert_eq!(by_colour(&file)[5], (6, IVec3::new(10, 20, 31)));

    // A half turn about z (rows (−1 0 0), (0 −1 0), (0 0 1): byte 4 | 1<<4 | 1<<5 = 52): along
    // the odd axis y of a 3×3×1 model the middle voxel moves by one (the pivot is a corner).
    let (size, voxel) = (UVec3::new(3, 3, 1), [1u8, 1, 0, 9]);
    let graph = [rotated_node(0, 1, Some(52), IVec3::ZERO), graph_chunk(b"nSHP", shape_node(1, 0))]
        .concat();
    let file = decode(&hand_built(&[(size, vec![voxel])], &graph, None), mem()).unwrap();
    assert_eq!(by_colour(&file), [(9, IVec3::new(-1, -1, 0))]);
    // And a reflection (x mirrored: byte 4 | 1<<4 = 20) reads too.
    let graph = [rotated_node(0, 1, Some(20), IVec3::ZERO), graph_chunk(b"nSHP", shape_node(1, 0))]
        .concat();
    let file = decode(&hand_built(&[block_1x2x3()], &graph, None), mem()).unwrap();
    assert_eq!(file.instances[0].rotation.determinant(), -1);
    assert_eq!(by_colour(&file)[0], (1, IVec3::new(-1, -1, -1)));
    // to_brick_map gives voxlod axes: (x, y, z) → (x, z, −1 − y); the mirrored voxels span
    // x = −1, y ∈ {−1, 0}, z ∈ {−1, 0, 1}.
    let (min, map) =
        decode(&hand_built(&[block_1x2x3()], &graph, None), mem()).unwrap().to_brick_map().unwrap();
    assert_eq!((min, map.dims(), map.len()), (IVec3::new(-1, -1, -1), UVec3::new(1, 3, 2), 6));
}

#[test]
fn a_file_without_rgba_gets_magicavoxels_default_palette() {
    let graph =
        [rotated_node(0, 1, None, IVec3::ZERO), graph_chunk(b"nSHP", shape_node(1, 0))].concat();
    let file = decode(&hand_built(&[block_1x2x3()], &graph, None), mem()).unwrap();
    // Entries as the specification lists them (u32 0xAABBGGRR, little-endian RGBA bytes).
    let spec: [(usize, u32); 10] = [
        (0, 0x0000_0000),
        (1, 0xffff_ffff),
        (2, 0xffcc_ffff),
        (7, 0xffff_ccff),
        (37, 0xffff_ffcc),
        (215, 0xff33_0000),
        (216, 0xff00_00ee),
        (226, 0xff00_ee00),
        (236, 0xffee_0000),
        (255, 0xff11_1111),
    ];
    for (i, v) in spec {
        assert_eq!(file.palette[i], v.to_le_bytes(), "entry {i}");
    }
    // Every entry 1–255 is distinct and opaque.
    let distinct: std::collections::HashSet<[u8; 4]> = file.palette[1..].iter().copied().collect();
    assert_eq!(distinct.len(), 255);
    assert!(file.palette[1..].iter().all(|c| c[3] == 255));
    // A file with its own palette keeps it.
    let mut rgba = vec![7u8; 1024];
    rgba[0..4].copy_from_slice(&[1, 2, 3, 4]);
    let file = decode(&hand_built(&[block_1x2x3()], &graph, Some(&rgba)), mem()).unwrap();
    assert_eq!((file.palette[0], file.palette[1], file.palette[2]), ([0; 4], [1, 2, 3, 4], [7; 4]));
}
