//! `voxlod export` end to end: a small textured scene, a `.vxl` file and a procedural volume
//! out to MagicaVoxel `.vox`, Mitsuba 3 `.vol` and NanoVDB `.nvdb`, read back with
//! voxlod-format's readers; `.nvdb` files also checked by NanoVDB's own `nanovdb_validate`.

use std::path::{Path, PathBuf};
use std::process::Output;

use glam::{DVec3, IVec3, UVec3};
use voxlod::format::nvdb::{self, AnyGrid, GridClass};
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
        assert!(err.contains(".vox") && err.contains(".vol") && err.contains(".nvdb"), "{err}");
        assert!(!path.exists());
    }
    let out = voxlod(&["export", s(&dir.join("missing.vxl")), "-o", s(&dir.join("x.vox"))]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.vxl"));
    assert!(!dir.join("x.vox").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

fn f64s(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// Runs NanoVDB's `nanovdb_validate` (Debian package libnanovdb-tools) on `path`: it must pass
/// every grid, full checksum included. Without the tool this fails under CI (the environment
/// variable `CI` set) and says it skipped otherwise.
fn nanovdb_validate(path: &Path, grids: usize) {
    let out = match std::process::Command::new("nanovdb_validate").arg("-v").arg(path).output() {
        Ok(out) => out,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let msg = "nanovdb_validate not found: install libnanovdb-tools \
                       (apt-get install -y libnanovdb-tools) to check .nvdb files with NanoVDB";
            assert!(std::env::var_os("CI").is_none(), "{msg}");
            eprintln!("skipped: {msg}");
            return;
        }
        Err(e) => panic!("running nanovdb_validate: {e}"),
    };
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(text.matches(": passed").count(), grids, "{text}");
    assert!(!text.contains("failed"), "{text}");
}

#[test]
fn a_scene_exports_to_nvdb_as_density_and_colour_grids_on_voxel_centres() {
    let dir = temp_dir("nvdb");
    let scene = ["export", "builtin:box-textured", "--res", "16", "--rays", "8", "--json"];
    let path = dir.join("box.nvdb");
    let summary = json(&voxlod(&[&scene[..], &["-o", s(&path)]].concat()));
    assert_eq!(summary["format"].as_str(), Some("nvdb"));
    let voxels = summary["voxels"].as_u64().unwrap();
    let grids = summary["grids"].as_array().unwrap();
    assert_eq!(grids.len(), 2, "{summary}");
    assert_eq!(
        (grids[0]["name"].as_str(), grids[1]["name"].as_str()),
        (Some("density"), Some("color"))
    );
    assert_eq!(grids[0]["active_voxels"].as_u64(), Some(voxels));
    let bytes: u64 = grids.iter().map(|g| g["bytes"].as_u64().unwrap()).sum();
    assert!(summary["files"][0]["bytes"].as_u64().unwrap() > bytes, "{summary}");

    let back = nvdb::read(&path).unwrap();
    let [AnyGrid::Float(density), AnyGrid::Vec3f(color)] = &back[..] else { panic!("{back:?}") };
    assert_eq!((density.class, color.class), (GridClass::FogVolume, GridClass::Unknown));
    assert_eq!((density.voxels.len() as u64, color.voxels.len() as u64), (voxels, voxels));
    // Index (i, j, k) is the centre of voxlod's voxel (i, j, k): origin + (i + ½)·size.
    let (origin, size) =
        (DVec3::from_slice(&f64s(&summary["origin"])), summary["voxel_size"].as_f64().unwrap());
    assert_eq!(density.map.translation, origin + DVec3::splat(0.5 * size));
    assert_eq!(
        density.map.apply(DVec3::new(2.0, 0.0, 1.0)),
        origin + DVec3::new(2.5, 0.5, 1.5) * size
    );

    // The same voxels and densities as the .vol export of the same scene.
    let vol_path = dir.join("box.vol");
    json(&voxlod(&[&scene[..], &["-o", s(&vol_path)]].concat()));
    let dense = vol::read(&vol_path).unwrap();
    for &(c, d) in &density.voxels {
        assert!(c.min_element() >= 0, "{c}");
        assert_eq!(dense.get(c.as_uvec3()).unwrap()[0], d, "density at {c}");
    }
    let albedo = vol::read(dir.join("box.albedo.vol")).unwrap();
    for &(c, rgb) in &color.voxels {
        assert_eq!(albedo.get(c.as_uvec3()).unwrap(), rgb.to_array(), "colour at {c}");
    }
    nanovdb_validate(&path, 2);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_volume_density_exports_to_vol_and_nvdb_and_not_to_vox() {
    let dir = temp_dir("volume");
    let args = ["export", "volume:smoke", "--res", "32", "--json"];
    let nvdb_path = dir.join("smoke.nvdb");
    let summary = json(&voxlod(&[&args[..], &["-o", s(&nvdb_path)]].concat()));
    assert_eq!(
        (summary["input_kind"].as_str(), summary["records"].as_str(), summary["dims"][0].as_u64()),
        (Some("volume"), Some("density"), Some(32))
    );
    let voxels = summary["voxels"].as_u64().unwrap() as usize;
    assert!(voxels > 100, "{summary}");
    let back = nvdb::read(&nvdb_path).unwrap();
    let [AnyGrid::Float(density)] = &back[..] else { panic!("{back:?}") };
    assert_eq!(density.voxels.len(), voxels);
    assert!(
        density
            .voxels
            .iter()
            .all(|&(c, d)| d > 0.0 && d.is_finite() && c.cmplt(IVec3::splat(32)).all())
    );

    // Each density is the particles' at the voxel's world centre (the grid's map): the sum of
    // the densities of the particles whose displaced surface holds that point, evaluated here
    // in world space (the export evaluates it in the volume's frame, so a few voxels on a
    // surface may round the other way).
    let system = voxlod::studies::volume::preset("smoke", 0).unwrap();
    let spheres = system.at(system.time);
    let mut differ = Vec::new();
    for &(c, d) in &density.voxels {
        let p = density.map.apply(c.as_dvec3()).as_vec3();
        let expected: f32 = spheres
            .iter()
            .filter(|s| {
                let offset = p - s.center;
                let r = s.surface_radius(s.displacement(&system.displacement, offset));
                offset.length_squared() <= r * r
            })
            .map(|s| s.density)
            .sum();
        if (d - expected).abs() > 1e-4 * expected.max(d) {
            differ.push((c, d, expected));
        }
    }
    assert!(
        differ.len() * 200 < voxels,
        "{} of {voxels} densities differ from the particles': {:?}",
        differ.len(),
        &differ[..differ.len().min(5)]
    );

    let vol_path = dir.join("smoke.vol");
    let summary = json(&voxlod(&[&args[..], &["-o", s(&vol_path)]].concat()));
    assert_eq!(summary["files"].as_array().unwrap().len(), 1, "a volume has no albedo file");
    let dense = vol::read(&vol_path).unwrap();
    assert_eq!(dense.data.iter().filter(|&&d| d > 0.0).count(), voxels);
    for &(c, d) in &density.voxels {
        assert_eq!(dense.get(c.as_uvec3()).unwrap()[0], d, "density at {c}");
    }
    nanovdb_validate(&nvdb_path, 1);

    for (input, res, output, needle) in [
        ("volume:smoke", "32", "smoke.vox", ".nvdb"),
        ("volume:fog", "32", "fog.nvdb", "fog"),
        ("volume:smoke", "129", "odd.nvdb", "129 metavoxels"),
        ("volume:smoke", "8192", "huge.vol", "at most 4096"),
    ] {
        let out = voxlod(&["export", input, "--res", res, "-o", s(&dir.join(output))]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{err}");
        assert!(!dir.join(output).exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
