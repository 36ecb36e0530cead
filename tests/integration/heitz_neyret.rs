//! `voxlod heitz-neyret` end to end on a tiny setting: every method at every zoom, the
//! grazing-colour bins of a radial scene, the representations' bytes, depth of field, the
//! report; and bad arguments.

use std::process::Command;

#[test]
fn heitz_neyret_command_measures_every_method_at_every_zoom() {
    let dir = std::env::temp_dir().join(format!("voxlod-heitz-neyret-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_voxlod"))
        .args(["heitz-neyret", "builtin:bumpy-sphere?subdiv=3", "builtin:forest?trees=1&leaves=40"])
        .args(["--res", "16", "--size", "16", "--zooms", "1,4", "--spp", "4", "--rays", "8"])
        .args(["--repeats", "2", "--json", "--quiet", "-o"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = crate::json_result(&out.stdout, "heitz-neyret");
    assert_eq!(v["image_size"], 16);
    let scenes = v["scenes"].as_array().unwrap();
    assert_eq!(scenes.len(), 2);
    // The CLI marks a bumpy sphere radial and in the model's domain, the forest outside it.
    let (bumpy, forest) = (&scenes[0], &scenes[1]);
    assert_eq!(bumpy["case"]["radial"], true);
    assert_eq!(bumpy["case"]["in_domain"], true);
    assert_eq!(forest["case"]["in_domain"], false);
    assert_eq!(forest["case"]["radial"], false);
    let methods = ["masks", "masks_mean_colour", "blending", "averages", "averages_directional"];
    for s in scenes {
        assert_eq!(s["resolution"], 16);
        assert!(s["voxels"].as_u64().unwrap() > 0, "{s}");
        let reps = s["representations"].as_array().unwrap();
        assert_eq!(reps.len(), 2);
        for r in reps {
            assert!(r["payload_bytes_per_node"].as_u64().unwrap() > 0, "{r}");
            assert!(r["total_bytes_per_voxel"].as_f64().unwrap() > 0.0, "{r}");
        }
        let zooms = s["zooms"].as_array().unwrap();
        assert_eq!(zooms.len(), 2);
        // Farther away, one pixel covers more voxels.
        let footprint = |z: &serde_json::Value| z["footprint_voxels"].as_f64().unwrap();
        assert!(footprint(&zooms[1]) > 3.0 * footprint(&zooms[0]), "{zooms:?}");
        for z in zooms {
            let err = z["truth_error_mse"].as_f64().unwrap();
            assert_eq!(err, z["truth_seed_mse"].as_f64().unwrap() / 2.0, "{z}");
            let rows = z["rows"].as_array().unwrap();
            let names: Vec<_> = rows.iter().map(|r| r["method"].as_str().unwrap()).collect();
            assert_eq!(names, methods);
            for r in rows {
                let (mse, ssim) = (r["mse"].as_f64().unwrap(), r["ssim"].as_f64().unwrap());
                assert!(mse.is_finite() && mse >= 0.0 && ssim <= 1.0, "{r}");
                assert!(r["silhouette_thickness_px"].as_f64().unwrap().is_finite(), "{r}");
                assert!(r["elements_per_pixel"].as_f64().unwrap() > 0.0, "{r}");
                let cpu = &r["cpu"];
                assert!(cpu["min_ms"].as_f64().unwrap() <= cpu["max_ms"].as_f64().unwrap());
                // CPU run: the GPU-only fields are left out.
                assert!(r.get("gpu").is_none() && r.get("gpu_worst_step").is_none(), "{r}");
            }
        }
    }
    // Grazing bins only on the radial scene, each with one colour per method.
    let bins = bumpy["zooms"][0]["grazing"].as_array().unwrap();
    assert!(bins.iter().any(|b| b["pixels"].as_u64().unwrap() > 0), "{bins:?}");
    assert!(bins.iter().all(|b| b["method_rgb"].as_array().unwrap().len() == methods.len()));
    assert!(forest["zooms"][0]["grazing"].as_array().unwrap().is_empty());
    // Depth of field on the first in-domain scene.
    let dof = &v["depth_of_field"];
    assert_eq!(dof["scene"], "bumpy-sphere");
    assert!(dof["masks_coverage_ratio"].as_f64().unwrap() > 0.0, "{dof}");
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("silhouette px") && report.contains("B/node"), "{report}");
    let _ = std::fs::remove_dir_all(&dir);

    for (args, needle) in [
        (vec!["heitz-neyret", "builtin:cube", "--res", "12"], "'12' for '--res"),
        (vec!["heitz-neyret", "builtin:cube", "--zooms", "0.1"], "'0.1' for '--zooms"),
        (vec!["heitz-neyret", "builtin:cube", "--rays", "0"], "'0' for '--rays"),
        (vec!["heitz-neyret", "no/such/file.obj", "--res", "8", "--size", "8"], "no/such/file.obj"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_voxlod")).args(&args).output().unwrap();
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}
