use std::path::Path;

use glam::{UVec3, Vec3};

use super::*;
use crate::records::quant::{decode_srgb8, from_unorm8};
use crate::{vol, vox};

fn p() -> &'static Path {
    Path::new("test.vol")
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

/// Averages records at distinct random voxels: every opacity code 1–255 appears, 40 colours.
fn averages(dims: UVec3, seed: u64) -> BrickMap<AverageRecord> {
    let mut next = rng(seed);
    let mut seen = std::collections::HashSet::new();
    let mut voxels = Vec::new();
    let mut code = 1u8;
    while voxels.len() < 400 {
        let c = UVec3::new(
            (next() % dims.x as u64) as u32,
            (next() % dims.y as u64) as u32,
            (next() % dims.z as u64) as u32,
        );
        if seen.insert(c) {
            let k = (next() % 40) as u8;
            let color = [k * 6, 255 - k * 5, 17 + k];
            voxels.push((c, AverageRecord { color, opacity: code, normal: [0; 3], _pad: 0 }));
            code = if code == 255 { 1 } else { code + 1 };
        }
    }
    BrickMap::from_voxels(dims, voxels).unwrap()
}

#[test]
fn a_scene_exported_to_vox_imports_with_the_same_occupancy_and_colours() {
    let map = averages(UVec3::new(37, 20, 29), 5);
    let bytes = vox::encode(&map, |r| r.color).unwrap().bytes;
    let file = vox::decode(&bytes, Path::new("scene.vox")).unwrap();
    let (grid, back) = vox_to_averages(&file, 0.25, Path::new("scene.vox")).unwrap();
    assert_eq!(grid.voxel_size, 0.25);
    assert_eq!(back.len(), map.len());
    // Same occupancy up to the whole-voxel translation between the bounding boxes' minima.
    let lo = map.coords().fold(UVec3::MAX, |a, c| a.min(c));
    for (c, r) in back.iter() {
        let original = map.get(c + lo).unwrap_or_else(|| panic!("{c} was not in the scene"));
        // 40 colours: the palette is exact; the opacity is the format's (occupancy only).
        assert_eq!(r.color, original.color);
        assert_eq!((r.opacity, r.normal), (255, [0; 3]));
    }
    // The grid's origin is the bounding box's minimum in whole voxels (voxlod axes), scaled.
    let (min, _) = file.to_brick_map().unwrap();
    assert_eq!(grid.origin, min.as_dvec3() * 0.25);
    // And it is written as .vxl and read back unchanged.
    let path = std::env::temp_dir().join(format!("voxlod-import-{}.vxl", std::process::id()));
    crate::vxl::write(&path, &grid, &back, &[]).unwrap();
    let read = crate::vxl::read::<AverageRecord>(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(read.grid, grid);
    assert!(read.map.iter().eq(back.iter()));
}

#[test]
fn vol_density_imports_to_the_same_opacity() {
    let grid =
        GridSpec::new(glam::DVec3::new(-1.0, 2.0, 0.5), 0.125, UVec3::new(20, 9, 14)).unwrap();
    let map = averages(grid.dims, 9);
    let (density, albedo) = vol::density_and_albedo(&grid, &map).unwrap();
    let density = vol::decode(&vol::encode(&density).unwrap(), p()).unwrap();
    let albedo = vol::decode(&vol::encode(&albedo).unwrap(), p()).unwrap();

    // Full precision: α = 1 − exp(−σ·size) equals the written opacity within f32 rounding, up
    // to the cap of opaque voxels (σ·size = ln 510, α = 509/510).
    let (g, rgba) = vol_to_rgba_f32(&density, Some(&albedo), p()).unwrap();
    assert_eq!((g.dims, g.voxel_size, rgba.len()), (grid.dims, 0.125, map.len()));
    assert!((g.origin - grid.origin).abs().max_element() < 1e-6);
    for (c, r) in map.iter() {
        let got = rgba.get(c).unwrap();
        let alpha = from_unorm8(r.opacity);
        let expected = if r.opacity == 255 { 509.0 / 510.0 } else { alpha };
        assert!((got[3] - expected).abs() <= 2.0 * f32::EPSILON, "{c}: {} vs {expected}", got[3]);
        let sigma = density.get(c).unwrap()[0];
        assert_eq!(got[3], opacity_from_extinction(sigma, 0.125));
        assert_eq!(Vec3::from_slice(&got[..3]), r.color());
    }
    // Quantized: the same unorm8 codes and sRGB8 colours as the records exported.
    let (_, back) = vol_to_averages(&density, Some(&albedo), p()).unwrap();
    for (c, r) in map.iter() {
        let b = back.get(c).unwrap();
        assert_eq!((b.opacity, b.color), (r.opacity, r.color), "{c}");
    }
    // Without the albedo grid: the same opacities, grey.
    let (_, grey) = vol_to_averages(&density, None, p()).unwrap();
    assert!(grey.values().iter().all(|r| r.color == GREY));
    assert_eq!(
        grey.values().iter().map(|r| r.opacity).collect::<Vec<_>>(),
        back.values().iter().map(|r| r.opacity).collect::<Vec<_>>()
    );
    assert_eq!(decode_srgb8(GREY), Vec3::splat(decode_srgb8(GREY).x));
}

#[test]
fn unreadable_volumes_are_refused_with_the_reason() {
    let vol = |dims: UVec3, channels: u32, max: Vec3, data: Vec<f32>| VolGrid {
        dims,
        channels,
        bbox_min: Vec3::ZERO,
        bbox_max: max,
        data,
    };
    let ok = vol(UVec3::new(2, 1, 1), 1, Vec3::new(1.0, 0.5, 0.5), vec![0.0, 3.0]);
    assert!(vol_to_averages(&ok, None, p()).is_ok());
    let message = |v: &VolGrid, a: Option<&VolGrid>| {
        let e = vol_to_averages(v, a, p()).unwrap_err().to_string();
        assert!(e.contains("test.vol"), "{e}");
        e
    };
    let rgb = vol(UVec3::new(2, 1, 1), 3, Vec3::new(1.0, 0.5, 0.5), vec![0.5; 6]);
    assert!(message(&rgb, None).contains("3 channels"));
    assert!(message(&ok, Some(&ok)).contains("1 channels, not 3"));
    let other_box = vol(UVec3::new(2, 1, 1), 3, Vec3::new(2.0, 1.0, 1.0), vec![0.5; 6]);
    assert!(message(&ok, Some(&other_box)).contains("is not the density's"));
    let stretched = vol(UVec3::new(2, 1, 1), 1, Vec3::new(1.0, 0.6, 0.5), vec![0.0, 3.0]);
    assert!(message(&stretched, None).contains("not cubes"));
    let negative = vol(UVec3::new(2, 1, 1), 1, Vec3::new(1.0, 0.5, 0.5), vec![-1.0, 3.0]);
    assert!(message(&negative, None).contains("negative density -1 at cell [0, 0, 0]"));
    let empty = vol(UVec3::new(2, 1, 1), 1, Vec3::new(1.0, 0.5, 0.5), vec![0.0, 0.0]);
    assert!(message(&empty, None).contains("nothing to import"));
    let nan = vol(UVec3::new(2, 1, 1), 1, Vec3::new(1.0, 0.5, 0.5), vec![f32::NAN, 3.0]);
    assert!(vol_to_averages(&nan, None, p()).is_err());
    // An empty .vox scene.
    let file = VoxFile { version: 150, models: vec![], instances: vec![], palette: [[0; 4]; 256] };
    let e = vox_to_averages(&file, 1.0, Path::new("empty.vox")).unwrap_err().to_string();
    assert!(e.contains("empty.vox") && e.contains("no voxel"), "{e}");
}
