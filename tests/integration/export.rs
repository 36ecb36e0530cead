//! `voxlod export` end to end: a small textured scene and a `.vxl` file out to MagicaVoxel
//! `.vox` and Mitsuba 3 `.vol`, read back with voxlod-format's readers.

use std::path::{Path, PathBuf};
use std::process::Output;

use glam::{DVec3, UVec3};
use voxlod::format::{Occupancy, vol, vox, vxl};

use crate::voxlod;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxlod-export-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "exit {:?}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    crate::json_result(&out.stdout, "export")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn sorted(coords: impl Iterator<Item = UVec3>) -> Vec<UVec3> {
    let mut v: Vec<UVec3> = coords.collect();
    let lo = v.iter().fold(UVec3::MAX, |a, c| a.min(*c));
    v.iter_mut().for_each(|c| *c -= lo);
    v.sort_unstable_by_key(|c| (c.z, c.y, c.x));
    v
}

#[test]
fn a_textured_scene_exports_to_vox_and_vol() {
    let dir = temp_dir("scene");
    let scene = ["export", "builtin:box-textured", "--res", "20", "--rays", "8", "--json"];
    let vox_path = dir.join("box.vox");
    let summary = json(&voxlod(&[&scene[..], &["-o", s(&vox_path)]].concat()));
    assert_eq!(
        (summary["format"].as_str(), summary["records"].as_str()),
        (Some("vox"), Some("averages"))
    );
    let voxels = summary["voxels"].as_u64().unwrap() as usize;
    assert!(voxels > 500, "{summary}");
    let palette = &summary["palette"];
    assert!(palette["colors"].as_u64().unwrap() <= 255, "{summary}");
    let rms = palette["rms_error_srgb8"].as_f64().unwrap();
    assert!(rms <= palette["rms_error_median_cut_srgb8"].as_f64().unwrap() + 0.05, "{summary}");
    let file = vox::read(&vox_path).unwrap();
    let (_, occupancy) = file.to_brick_map().unwrap();
    assert_eq!(occupancy.len(), voxels);
    assert_eq!(
        summary["files"][0]["bytes"].as_u64(),
        Some(std::fs::metadata(&vox_path).unwrap().len())
    );

    let vol_path = dir.join("box.vol");
    let summary = json(&voxlod(&[&scene[..], &["-o", s(&vol_path)]].concat()));
    assert_eq!(summary["voxels"].as_u64(), Some(voxels as u64));
    let density = vol::read(&vol_path).unwrap();
    let albedo = vol::read(dir.join("box.albedo.vol")).unwrap();
    assert_eq!(summary["files"][1]["path"].as_str(), Some(s(&dir.join("box.albedo.vol"))));
    let dims: Vec<u32> =
        summary["dims"].as_array().unwrap().iter().map(|d| d.as_u64().unwrap() as u32).collect();
    assert_eq!((density.dims.to_array().to_vec(), density.channels, albedo.channels), (dims, 1, 3));
    // The box is the grid's: voxel (i, j, k) covers origin + [i, i+1)·size, as in voxlod.
    let origin: Vec<f64> =
        summary["origin"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let size = summary["voxel_size"].as_f64().unwrap();
    let origin = DVec3::from_slice(&origin);
    assert_eq!(density.bbox_min, origin.as_vec3());
    assert_eq!(density.bbox_max, (origin + density.dims.as_dvec3() * size).as_vec3());
    let filled = density.data.iter().filter(|&&d| d > 0.0).count();
    assert!(filled > 0 && filled <= voxels, "{filled} of {voxels}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_vxl_file_exports_to_the_same_occupancy_and_bad_outputs_are_refused() {
    let dir = temp_dir("vxl");
    let vxl_path = dir.join("bunny.vxl");
    let out = voxlod(&["voxelize", "builtin:bunny", "--res", "20", "-o", s(&vxl_path)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let original = vxl::read::<Occupancy>(&vxl_path).unwrap();

    let vox_path = dir.join("bunny.vox");
    let summary = json(&voxlod(&["export", s(&vxl_path), "-o", s(&vox_path), "--json"]));
    assert_eq!(
        (summary["input_kind"].as_str(), summary["records"].as_str()),
        (Some("vxl"), Some("occupancy"))
    );
    let (_, back) = vox::read(&vox_path).unwrap().to_brick_map().unwrap();
    assert_eq!(sorted(back.coords()), sorted(original.map.coords()));

    let vol_path = dir.join("bunny.vol");
    let summary = json(&voxlod(&["export", s(&vxl_path), "-o", s(&vol_path), "--json"]));
    assert_eq!(summary["files"].as_array().unwrap().len(), 1, "occupancy has no albedo");
    let density = vol::read(&vol_path).unwrap();
    for c in original.map.coords() {
        assert!(density.get(c).unwrap()[0] > 0.0);
    }
    assert_eq!(density.data.iter().filter(|&&d| d > 0.0).count(), original.map.len());

    for bad in ["bunny.vdb", "bunny"] {
        let path = dir.join(bad);
        let out = voxlod(&["export", s(&vxl_path), "-o", s(&path)]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(".vox") && err.contains(".vol"), "{err}");
        assert!(!path.exists());
    }
    let out = voxlod(&["export", s(&dir.join("missing.vxl")), "-o", s(&dir.join("x.vox"))]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.vxl"));
    assert!(!dir.join("x.vox").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
