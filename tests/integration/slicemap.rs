//! `voxlod slicemap` end to end on a tiny setting: every part's rows in the JSON, the report
//! and `slicemap.json` on disk, the preset's scenes without a scene argument, and one-line
//! errors for bad arguments.

use crate::voxlod;

#[test]
fn slicemap_measures_holes_shadows_and_thickness() {
    let dir = std::env::temp_dir().join(format!("voxlod-slicemap-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = voxlod(&[
        "slicemap",
        "builtin:bunny",
        "--res",
        "24",
        "--map-size",
        "48",
        "--slices",
        "8,64",
        "--image",
        "40",
        "-o",
        dir.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = crate::json_result(&out.stdout, "slicemap");
    assert_eq!(v["schema_version"], 1, "{v}");
    // Holes: the exact voxelizers, three axes, their union, the conservative map.
    let aligned = v["holes"]["aligned"].as_array().unwrap();
    assert_eq!(aligned.len(), 7, "{v}");
    let row = |m: &str| aligned.iter().find(|r| r["method"] == m).unwrap();
    let cons = row("exact conservative voxelizer")["voxels"].as_u64().unwrap();
    let z = row("slicemap along z, standard");
    assert!(z["missed_conservative"].as_u64().unwrap() > 0, "{z}");
    assert_eq!(z["extra"], 0, "{z}");
    let merged = row("x, y and z maps merged (sum of the three)");
    assert!(merged["missed_thin"].as_u64() < z["missed_thin"].as_u64(), "{merged}");
    let c = row("slicemap along z, conservative (emulated)");
    assert!(c["missed_conservative"].as_u64().unwrap() * 50 < cons, "{c}");
    // Perspective: uniform and local per slice count, the exact cells never fewer than set.
    let cells = v["holes"]["perspective"].as_array().unwrap();
    assert_eq!(cells.len(), 4, "{v}");
    for r in cells {
        assert_eq!(r["cells"]["extra"], 0, "{r}");
        assert!(r["cells"]["exact"].as_u64() >= r["cells"]["set"].as_u64(), "{r}");
    }
    // Shadows: the reference, opaque layers, one row per slice count.
    let shadows = v["shadows"]["rows"].as_array().unwrap();
    assert_eq!(shadows.len(), 4, "{v}");
    assert_eq!(shadows[0]["mean_abs_error"], 0.0);
    for r in &shadows[2..] {
        let e = r["mean_abs_error"].as_f64().unwrap();
        assert!((0.0..0.2).contains(&e), "{r}");
    }
    // Refraction: a closed mesh; the slicemap beats two depth maps.
    let r = &v["refraction"];
    assert_eq!(r["boundary_edges"], 0, "{r}");
    let t = r["thickness"].as_array().unwrap();
    assert_eq!(t.len(), 3, "{r}");
    assert!(t[2]["mean_abs_error"].as_f64() < t[0]["mean_abs_error"].as_f64(), "{r}");
    assert_eq!(r["effects"].as_array().unwrap().len(), 6);
    for f in ["report.md", "report.json", "slicemap.json"] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    std::fs::remove_dir_all(&dir).unwrap();

    // Without a scene, each part runs on the preset's scene (the refraction: the bunny).
    let out = voxlod(&[
        "slicemap",
        "--parts",
        "refraction",
        "--slices",
        "8",
        "--image",
        "24",
        "-o",
        dir.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = crate::json_result(&out.stdout, "slicemap");
    assert_eq!(v["refraction"]["scene"], "builtin:bunny", "{v}");
    assert!(v["holes"].is_null() && v["shadows"].is_null(), "{v}");
    std::fs::remove_dir_all(&dir).unwrap();

    for bad in [
        vec!["slicemap", "builtin:nothing"],
        vec!["slicemap", "builtin:bunny", "--slices", "0"],
        vec!["slicemap", "builtin:bunny", "--parts", "holes,shade"],
        vec!["slicemap", "builtin:bunny", "--sigma", "1.5"],
    ] {
        let out = voxlod(&bad);
        assert!(!out.status.success(), "{bad:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{bad:?}: {err}");
    }
}
