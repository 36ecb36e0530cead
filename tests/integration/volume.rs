//! `voxlod volume` end to end on a tiny setting (issue 6): the tables' JSON, the report on
//! disk, and a one-line error for an unknown preset.

use std::process::Command;

fn voxlod(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_voxlod"))
        .args(args)
        .arg("--quiet")
        .output()
        .expect("the voxlod binary runs")
}

#[test]
fn volume_preset_writes_the_report_and_measures_the_trade() {
    let dir = std::env::temp_dir().join(format!("voxlod-volume-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = voxlod(&[
        "volume",
        "smoke",
        "--particles",
        "300",
        "--res",
        "16",
        "--m",
        "4,8,16",
        "--image",
        "32",
        "--spp",
        "1",
        "-o",
        dir.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    let att = v["attenuation"].as_array().unwrap();
    assert_eq!(att.len(), 3, "{v}");
    assert_eq!(att[0]["model"], "reference");
    assert_eq!(att[0]["metrics"]["mse"].as_f64(), Some(0.0));
    for row in &att[1..] {
        let mse = row["metrics"]["mse"].as_f64().unwrap();
        assert!(mse > 0.0 && mse < 0.1, "{row}");
    }
    // The mesh is rendered alone and, per model, again under the volume's shadow.
    assert!(v["mesh_s"].as_f64().is_some_and(|s| s > 0.0), "{v}");
    for row in att {
        assert!(row["shadowed_mesh_s"].as_f64().is_some_and(|s| s > 0.0), "{row}");
    }
    let sizes = v["sizes"].as_array().unwrap();
    assert_eq!(sizes.len(), 3);
    for row in sizes {
        let (sparse, dense) = (row["volume_bytes"].as_u64().unwrap(), row["dense_bytes"].as_u64());
        assert_eq!(dense, Some(16u64.pow(3) * 16), "{row}");
        assert!(sparse > 0 && row["kept"].as_u64().unwrap() > 0, "{row}");
    }
    assert!(dir.join("report.md").is_file() && dir.join("report.json").is_file());
    std::fs::remove_dir_all(&dir).unwrap();

    let bad = voxlod(&["volume", "fog", "-o", dir.to_str().unwrap()]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("unknown preset 'fog'"), "{err}");
    assert!(!dir.exists(), "nothing written on error");
}
