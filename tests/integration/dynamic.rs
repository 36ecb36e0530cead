//! `voxlod dynamic` end to end on one walker and one rigid object at 10 cm voxels: the caches,
//! the agreement with re-voxelization, the images against the references, the exact
//! rotations, the stability rows, one scaling row, a two-frame sequence, the report, and bad
//! arguments.

use std::process::Command;

fn f(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} in {v}"))
}

#[test]
fn dynamic_command_measures_transformation_against_revoxelization() {
    let dir = std::env::temp_dir().join(format!("voxlod-dynamic-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_voxlod"))
        .args(["dynamic", "builtin:crowd?walkers=1&rigid=1", "--voxel", "0.1"])
        .args(["--times", "0.37", "--walkers", "1", "--frames", "2", "--width", "16"])
        .args(["--spp", "4", "--json", "--quiet", "-o"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = crate::json_result(&out.stdout, "dynamic");
    assert_eq!(v["scene"], "builtin:crowd?walkers=1&rigid=1");
    assert_eq!(f(&v, "voxel_size"), 0.1f32 as f64);

    // One walker and one rigid object, cached by both voxelizers.
    let caches = v["caches"].as_array().unwrap();
    assert_eq!(caches.len(), 4, "{caches:?}");
    for kind in ["rigid", "skinned"] {
        for voxelizer in ["conservative", "thin"] {
            let c = caches
                .iter()
                .find(|c| c["kind"] == kind && c["voxelizer"] == voxelizer)
                .unwrap_or_else(|| panic!("{kind} {voxelizer} in {caches:?}"));
            assert!(c["voxels"].as_u64().unwrap() > 0, "{c}");
            assert!(c["bytes_per_voxel"].as_u64().unwrap() > 0, "{c}");
        }
    }
    // A skinned voxel carries its joints and weights: more bytes than a rigid one.
    let bytes = |kind: &str| {
        caches.iter().find(|c| c["kind"] == kind).unwrap()["bytes_per_voxel"].as_u64().unwrap()
    };
    assert!(bytes("skinned") > bytes("rigid"));

    // Agreement: 1 time × 3 classes × 2 voxelizers × 2 filters × 1 threshold.
    let agreement = v["agreement"].as_array().unwrap();
    assert_eq!(agreement.len(), 12, "{agreement:?}");
    for r in agreement {
        let (iou, missing, extra) = (f(r, "iou"), f(r, "missing_fraction"), f(r, "extra_fraction"));
        assert!(r["reference_voxels"].as_u64().unwrap() > 0, "{r}");
        assert!((0.0..=1.0).contains(&iou) && (0.0..=1.0).contains(&missing), "{r}");
        assert!(extra >= 0.0, "{r}");
        // The transformed voxels land on the re-voxelization, not somewhere else.
        assert!(iou > 0.3, "{r}");
        assert!(f(r, "colour_error").is_finite(), "{r}");
    }
    // Images: 1 time × 2 voxelizers × (nearest, 8-neighbour, re-voxelized).
    let images = v["images"].as_array().unwrap();
    assert_eq!(images.len(), 6, "{images:?}");
    for r in images {
        for k in ["ao_mse", "indirect_mse", "ao_mse_revoxelized", "indirect_mse_revoxelized"] {
            assert!(f(r, k).is_finite() && f(r, k) >= 0.0, "{k} {r}");
        }
        for k in ["ao_ssim", "indirect_ssim", "ao_ssim_revoxelized", "indirect_ssim_revoxelized"] {
            assert!(f(r, k) <= 1.0, "{k} {r}");
        }
    }
    let revox: Vec<_> = images.iter().filter(|r| r["method"] == "re-voxelized").collect();
    assert_eq!(revox.len(), 2);
    assert!(revox.iter().all(|r| f(r, "ao_mse_revoxelized") == 0.0), "{revox:?}");
    // Something was measured: the cone-traced AO differs from the ray-traced one.
    assert!(images.iter().any(|r| f(r, "ao_mse") > 0.0), "{images:?}");

    // Rotations: 5 rotations × 2 filters × 2 voxelizers; at exactly 45° nearest sampling
    // misses at least as much as 8-neighbour.
    let rotations = v["rotations"].as_array().unwrap();
    assert_eq!(rotations.len(), 20, "{rotations:?}");
    for voxelizer in ["conservative", "thin"] {
        let missing = |filter: &str| {
            f(
                rotations
                    .iter()
                    .find(|r| {
                        r["rotation"] == "45° about y"
                            && r["voxelizer"] == voxelizer
                            && r["filter"] == filter
                    })
                    .unwrap(),
                "missing_fraction",
            )
        };
        assert!(missing("nearest") >= missing("8-neighbour"), "{rotations:?}");
    }
    // Stability: 4 methods × 2 voxelizers; a moving object changes the AO it casts.
    let stability = v["stability"].as_array().unwrap();
    assert_eq!(stability.len(), 8, "{stability:?}");
    for r in stability {
        assert!(f(r, "mean_change") >= 0.0 && f(r, "max_change") >= f(r, "mean_change"), "{r}");
    }
    assert!(stability.iter().any(|r| f(r, "mean_change") > 0.0), "{stability:?}");
    // Scaling: one row, with its times and memory.
    let scaling = v["scaling"].as_array().unwrap();
    assert_eq!(scaling.len(), 1);
    let s = &scaling[0];
    assert_eq!(s["walkers"], 1);
    assert_eq!(s["objects"], 2);
    assert!(s["cached_voxels"].as_u64().unwrap() > 0, "{s}");
    for k in ["transform_ms", "voxelize_conservative_ms", "frame_transform_ms", "frame_voxelize_ms"]
    {
        let t = &s[k];
        assert!(f(t, "min") <= f(t, "mean") && f(t, "mean") <= f(t, "max"), "{k} {s}");
    }
    assert!(s["frame_gpu_ms"].is_null(), "a CPU run has no GPU column: {s}");
    // Frames: two, through the CPU pipeline, each with leaves (the floor at least).
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2);
    assert!(frames.iter().all(|r| r["leaves"].as_u64().unwrap() > 0), "{frames:?}");
    assert_eq!(v["backend"], "cpu (rayon)");
    assert!(!v["machine"].as_str().unwrap().is_empty());
    assert!(dir.join("report.md").exists());
    let _ = std::fs::remove_dir_all(&dir);

    for (args, needle) in [
        (vec!["dynamic", "builtin:crowd", "--voxel", "0"], "'0' for '--voxel"),
        (vec!["dynamic", "builtin:crowd", "--walkers", "257"], "'257' for '--walkers"),
        (vec!["dynamic", "no/such/file.gltf"], "no/such/file.gltf"),
        // A scene without an animation: an error that says so, not an empty table.
        (vec!["dynamic", "builtin:cube", "--walkers", "0"], "no animation"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_voxlod")).args(&args).output().unwrap();
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}
