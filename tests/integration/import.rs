//! `voxlod import` end to end: a scene exported to `.vox` and `.vol` by `voxlod export`, imported
//! back into `.vxl`, compared with the exported voxels; and `voxlod render --turntable`'s report.

use std::path::{Path, PathBuf};
use std::process::Output;

use voxlod::format::records::AverageRecord;
use voxlod::format::vxl;

use crate::voxlod;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxlod-import-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn ok(out: &Output, command: &str) -> serde_json::Value {
    assert!(
        out.status.success(),
        "exit {:?}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    crate::json_result(&out.stdout, command)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn exported_vox_and_vol_import_back_to_the_same_voxels() {
    let dir = temp_dir("round-trip");
    let (vox, vol) = (dir.join("a.vox"), dir.join("a.vol"));
    // The Averages records of a scene, exported twice.
    let from_vox = dir.join("from-vox.vxl");
    let mut dims = Vec::new();
    for out in [&vox, &vol] {
        let args = ["export", "builtin:cornell", "--res", "16", "--rays", "4", "--json", "-o"];
        dims.push(ok(&voxlod(&[&args[..], &[s(out)]].concat()), "export")["dims"].clone());
    }
    let v = ok(
        &voxlod(&["import", s(&vox), "-o", s(&from_vox), "--voxel-size", "0.5", "--json"]),
        "import",
    );
    assert_eq!((v["format"].as_str(), v["records"].as_str()), (Some("vox"), Some("averages")));
    let from_vol = dir.join("from-vol.vxl");
    let v = ok(&voxlod(&["import", s(&vol), "-o", s(&from_vol), "--json"]), "import");
    assert_eq!(v["albedo"].as_str(), Some(s(&dir.join("a.albedo.vol"))), "{v}");
    // .vol keeps the grid: the same voxels, opacities and colours as the .vox's colours (the
    // palette is exact below 256 colours).
    let a = vxl::read::<AverageRecord>(&from_vol).unwrap();
    let b = vxl::read::<AverageRecord>(&from_vox).unwrap();
    assert_eq!(serde_json::json!(a.grid.dims.to_array()), dims[1]);
    assert_eq!(a.map.len(), b.map.len());
    assert_eq!(b.grid.voxel_size, 0.5);
    // The .vox holds the bounding box of the voxels: compare from each minimum.
    let lo = a.map.coords().fold(glam::UVec3::MAX, |m, c| m.min(c));
    for (c, r) in b.map.iter() {
        let original = a.map.get(c + lo).unwrap_or_else(|| panic!("{c} not in the .vol import"));
        assert_eq!(r.color, original.color, "{c}");
        assert!(original.opacity > 0);
    }
    // Back out again: the .vox import re-exports to the very same bytes.
    let again = dir.join("again.vox");
    ok(&voxlod(&["export", s(&from_vox), "-o", s(&again), "--json"]), "export");
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&vox).unwrap());
    // Refused: options of the other format, a missing albedo.
    let out = voxlod(&["import", s(&vox), "-o", s(&dir.join("x.vxl")), "--f32"]);
    assert!(!out.status.success());
    let out = voxlod(&["import", s(&vol), "-o", s(&dir.join("x.vxl")), "--albedo", "missing.vol"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.vol"));
    assert!(!dir.join("x.vxl").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn render_turntable_writes_a_report_linking_the_animation() {
    let dir = temp_dir("turntable");
    let png = dir.join("bunny.png");
    let args = ["render", "builtin:bunny", "--size", "24x24", "--spp", "1", "--turntable", "3"];
    let more = ["--turntable-res", "8", "--turntable-rays", "2", "--json", "-o", s(&png)];
    let v = ok(&voxlod(&[&args[..], &more[..]].concat()), "render");
    let t = &v["turntable"];
    assert_eq!((t["frames"].as_u64(), t["frame_ms"].as_u64()), (Some(3), Some(100)), "{v}");
    assert_eq!(t["panels"].as_array().unwrap().len(), 3, "{v}");
    let report = std::fs::read_to_string(dir.join("bunny-turntable/report.md")).unwrap();
    assert!(report.contains("![builtin:bunny: a turn in 3 frames"), "{report}");
    assert!(report.contains("(assets/turntable.png)"), "{report}");
    let bytes = std::fs::read(dir.join("bunny-turntable/assets/turntable.png")).unwrap();
    let anim = voxlod::eval::animation::decode_apng(&bytes).unwrap();
    assert_eq!((anim.frames.len(), anim.frame_ms), (3, 100));
    std::fs::remove_dir_all(&dir).unwrap();
}
