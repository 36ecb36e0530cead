//! `voxlod volume` end to end on a tiny setting: the tables' JSON, the report on
//! disk, and a one-line error for an unknown preset.

use crate::voxlod;

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
    let v = crate::json_result(&out.stdout, "volume");
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
    assert!(err.contains("'fog'") && err.contains("smoke"), "{err}");
    assert!(!dir.exists(), "nothing written on error");
}

/// `voxlod volume --backend gpu` builds and marches on the adapter, says so (the JSON's
/// `backend`), and scores like the CPU run: the four kernels match the CPU within the
/// equivalence suite's bounds, so each model's MSE against the reference agrees to 5 % and its
/// SSIM to 0.005. No adapter fails loudly unless `VOXLOD_ALLOW_NO_GPU=1`.
#[test]
fn volume_on_the_gpu_scores_like_the_cpu_and_says_which_backend() {
    if voxlod::gpu::adapters().is_empty() {
        eprintln!(
            "!!!!!!!! NO GPU ADAPTER FOUND: `voxlod volume --backend gpu` was NOT checked !!!!!!!!"
        );
        let allowed = std::env::var("VOXLOD_ALLOW_NO_GPU").is_ok_and(|v| v == "1");
        assert!(allowed, "no GPU adapter (set VOXLOD_ALLOW_NO_GPU=1 to allow)");
        return;
    }
    let run = |backend: &str| {
        let dir =
            std::env::temp_dir().join(format!("voxlod-volume-{backend}-{}", std::process::id()));
        let out = voxlod(&[
            "volume",
            "smoke",
            "--particles",
            "300",
            "--res",
            "16",
            "--m",
            "8",
            "--image",
            "32",
            "--spp",
            "1",
            "--backend",
            backend,
            "-o",
            dir.to_str().unwrap(),
            "--json",
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v = crate::json_result(&out.stdout, "volume");
        let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        (v, report)
    };
    let ((cpu, _), (gpu, report)) = (run("cpu"), run("gpu"));
    assert_eq!(cpu["backend"], "cpu (rayon)");
    let name = gpu["backend"].as_str().unwrap();
    assert!(name.starts_with("gpu: "), "{name}");
    assert!(report.contains(&format!("Volume built and marched on {name}")), "{report}");
    let (a, b) = (cpu["attenuation"].as_array().unwrap(), gpu["attenuation"].as_array().unwrap());
    assert_eq!(a.len(), b.len());
    for (c, g) in a.iter().zip(b) {
        assert_eq!(c["model"], g["model"]);
        let (mc, mg) =
            (c["metrics"]["mse"].as_f64().unwrap(), g["metrics"]["mse"].as_f64().unwrap());
        assert!((mc - mg).abs() <= 0.05 * mc + 1e-7, "MSE cpu {mc} vs gpu {mg}");
        let (sc, sg) =
            (c["metrics"]["ssim"].as_f64().unwrap(), g["metrics"]["ssim"].as_f64().unwrap());
        assert!((sc - sg).abs() <= 0.005, "SSIM cpu {sc} vs gpu {sg}");
    }
}
