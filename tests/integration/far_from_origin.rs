//! The CLI with a model far from the world origin: the bunny's OBJ at 0 and at 10⁷ (offset added
//! in `f64`). Voxel files keep the grid's world origin in `f64`, a camera and a point light given
//! in world coordinates land where they would at 0, and a `.vol` export holds the same grid.

use std::path::{Path, PathBuf};
use std::process::Output;

use glam::DVec3;
use voxlod::format::{Occupancy, binvox, vol, vxl};

use crate::{json_result, voxlod};

const OFFSET: f64 = 1e7;

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxlod-far-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The bunny asset with `d` added to every coordinate in `f64`, written to `dir`.
fn bunny_at(dir: &Path, d: f64) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bunny/bunny.obj");
    let text: String = std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|line| match line.strip_prefix("v ") {
            Some(xyz) => {
                let v: Vec<String> = xyz
                    .split_whitespace()
                    .map(|x| (x.parse::<f64>().unwrap() + d).to_string())
                    .collect();
                format!("v {}\n", v.join(" "))
            }
            None => format!("{line}\n"),
        })
        .collect();
    let out = dir.join(format!("bunny-{d}.obj"));
    std::fs::write(&out, text).unwrap();
    out.to_str().unwrap().to_owned()
}

fn ok(out: Output, command: &str) -> serde_json::Value {
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    json_result(&out.stdout, command)
}

fn dvec3(v: &serde_json::Value) -> DVec3 {
    DVec3::from_slice(
        &v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect::<Vec<_>>(),
    )
}

#[test]
fn far_models_keep_world_coordinates_at_the_edges() {
    let dir = temp_dir();
    let (near, far) = (bunny_at(&dir, 0.0), bunny_at(&dir, OFFSET));
    let p = |name: &str| dir.join(name).to_str().unwrap().to_owned();

    // Voxelize: the same voxels; the files hold the world origin, exact in f64.
    let mut grids = Vec::new();
    for (scene, name) in [(&near, "near"), (&far, "far")] {
        let vxl_path = p(&format!("{name}.vxl"));
        let summary =
            ok(voxlod(&["voxelize", scene, "--res", "32", "-o", &vxl_path, "--json"]), "voxelize");
        let file = vxl::read::<Occupancy>(Path::new(&vxl_path)).unwrap();
        assert_eq!(file.grid.origin, dvec3(&summary["origin"]));
        let binvox_path = p(&format!("{name}.binvox"));
        ok(voxlod(&["voxelize", scene, "--res", "32", "-o", &binvox_path, "--json"]), "voxelize");
        let info = binvox::read_info(Path::new(&binvox_path)).unwrap();
        assert_eq!(info.header.translate, file.grid.origin, "binvox keeps the world origin");
        grids.push((file, dvec3(&summary["scene_origin"])));
    }
    let [(n, n_origin), (f, f_origin)] = [grids.remove(0), grids.remove(0)];
    assert_eq!((n_origin, f_origin), (DVec3::ZERO, DVec3::splat(OFFSET)));
    assert_eq!(n.map.coords().collect::<Vec<_>>(), f.map.coords().collect::<Vec<_>>());
    assert_eq!(n.grid.dims, f.grid.dims);
    let moved = f.grid.origin - n.grid.origin - DVec3::splat(OFFSET);
    assert!(moved.abs().max_element() < 1e-8, "the far grid sits {moved} off");

    // Render: a camera and a point light in world coordinates, 10⁷ + 0.25 and all.
    let mut images = Vec::new();
    for (scene, d) in [(&near, 0.0), (&far, OFFSET)] {
        let at = |x: f64, y: f64, z: f64| format!("{},{},{}", x + d, y + d, z + d);
        let camera = format!("eye={};target={}", at(6.25, 9.0, 14.0), at(0.0, 4.5, 0.0));
        let light = format!("point={};intensity=400", at(3.0, 12.0, 6.0));
        let png = p(&format!("render-{d}.png"));
        let args = ["render", scene, "--camera", &camera, "--light", &light, "--size", "32x32"];
        let summary =
            ok(voxlod(&[&args[..], &["--spp", "2", "-o", &png, "--json"]].concat()), "render");
        assert_eq!(dvec3(&summary["scene_origin"]), DVec3::splat(d));
        images.push(std::fs::read(&png).unwrap());
    }
    assert!(images[0] == images[1], "the renders at 0 and 10⁷ differ");

    // Export to Mitsuba: the .vol box is relative to the scene origin — the same file.
    let mut vols = Vec::new();
    for (scene, name) in [(&near, "near"), (&far, "far")] {
        let vol = p(&format!("{name}.vol"));
        let args = ["export", scene, "--res", "16", "--rays", "4", "-o", &vol, "--json"];
        let summary = ok(voxlod(&args), "export");
        assert_eq!(
            dvec3(&summary["scene_origin"]),
            if name == "far" { DVec3::splat(OFFSET) } else { DVec3::ZERO }
        );
        vols.push(vol::read(Path::new(&vol)).unwrap());
    }
    assert_eq!((&vols[0].dims, &vols[0].data), (&vols[1].dims, &vols[1].data));
    // The box: the bunny's lowest y, -0.003149, is 9999999.996851 in the far file, which f64
    // resolves to 2⁻²⁹ only; every other bound is bit-identical.
    let moved = (vols[0].bbox_min - vols[1].bbox_min)
        .abs()
        .max((vols[0].bbox_max - vols[1].bbox_max).abs());
    assert!(moved.abs().max_element() <= 2f32.powi(-29), "the .vol box moved by {moved}");
    let _ = std::fs::remove_dir_all(&dir);
}
