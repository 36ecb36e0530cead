//! `voxlod cone` end to end on a tiny setting: the sweep's rows, the references'
//! own error, the leak experiment's rows, the report, and bad arguments; plus the one AO falloff
//! shared by the cone tracer and the ray-traced reference.

use std::process::Command;

#[test]
fn cone_and_reference_share_the_ao_falloff() {
    for r in [0.01f32, 1.0, 37.5] {
        for i in 0..=40 {
            let t = r * i as f32 / 20.0;
            assert_eq!(
                voxlod_cone::falloff(t, r),
                voxlod::cpu::render::indirect::falloff(t, r),
                "t {t}, R {r}"
            );
        }
    }
}

#[test]
fn cone_command_measures_the_sweep_and_the_leaks() {
    let dir = std::env::temp_dir().join(format!("voxlod-cone-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_voxlod"))
        .args(["cone", "builtin:cornell", "--res", "8,16", "--cones", "1,6", "--apertures", "30"])
        .args(["--steps", "0.5", "--size", "16", "--spp", "16", "--json", "--quiet", "-o"])
        .arg(&dir)
        .args(["--lod-scene", "none"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = crate::json_result(&out.stdout, "cone");
    let rows = v["rows"].as_array().unwrap();
    // 2 resolutions × 2 cone counts × 2 opacity pre-filters (isotropic, directional).
    assert_eq!(rows.len(), 8, "{rows:?}");
    assert_eq!(rows[0]["opacity"], "isotropic");
    assert_eq!(rows[1]["opacity"], "directional");
    for r in rows {
        let (mse, ssim) = (r["ao_mse"].as_f64().unwrap(), r["ao_ssim"].as_f64().unwrap());
        assert!(mse.is_finite() && mse >= 0.0 && ssim <= 1.0, "{r}");
        assert!(r["steps_per_pixel"].as_f64().unwrap() > 0.0, "{r}");
    }
    // The Cornell box occludes itself and bounces light: the cones measure something.
    assert!(rows.iter().any(|r| r["ao_mse"].as_f64().unwrap() > 0.0), "{rows:?}");
    assert!(rows.iter().all(|r| r["ao_ssim"].as_f64().unwrap() < 1.0), "{rows:?}");
    assert_eq!(rows[0]["depth"], 3);
    assert_eq!(rows[4]["depth"], 4);
    let (seeds, error) = (&v["reference_seed_mse"], &v["reference_error_mse"]);
    for k in ["ao", "indirect"] {
        let (s, e) = (seeds[k].as_f64().unwrap(), error[k].as_f64().unwrap());
        assert!(s >= 0.0 && e == s / 2.0, "{seeds} {error}");
    }
    let octrees = v["octrees"].as_array().unwrap();
    assert_eq!(octrees[0]["resolution"], 8);
    assert!(octrees.iter().all(|o| o["voxels"].as_u64().unwrap() > 0), "{octrees:?}");
    // Leaks: 3 depths × 1 step × 2 options, each a fraction in [0, 1].
    let leaks = v["leaks"].as_array().unwrap();
    assert_eq!(leaks.len(), 6);
    for l in leaks {
        let f = l["leak"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&f), "{l}");
    }
    assert!(dir.join("report.md").exists());
    assert!(v["lod"].is_null());
    // The references and the best rows are written out: 8-bit images and linear float data.
    assert!(v["best_rows"]["ao"].as_str().unwrap().contains("step"), "{v}");
    assert!(dir.join("assets/cone_references.png").exists());
    for name in ["ao_reference", "ao_best", "indirect_reference", "indirect_best"] {
        let bytes =
            std::fs::read(dir.join(format!("assets/cone_reference_data/{name}.npy"))).unwrap();
        let (shape, data) = voxlod::eval::npy::decode_f32(&bytes).unwrap();
        assert_eq!(shape[..2], [16, 16], "{name}");
        assert!(data.iter().all(|x| x.is_finite() && *x >= 0.0), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);

    for (args, needle) in [
        (vec!["cone", "builtin:cube", "--res", "12"], "'12' for '--res"),
        (vec!["cone", "builtin:cube", "--apertures", "180"], "'180' for '--apertures"),
        (vec!["cone", "no/such/file.obj"], "no/such/file.obj"),
        // Convex: no surface sees another, every cone leaves the octree at its apex; an error,
        // not a row of MSE 0 / SSIM 1 measured from no sample.
        (
            vec![
                "cone",
                "builtin:cube",
                "--res",
                "8",
                "--cones",
                "1",
                "--size",
                "16",
                "--spp",
                "4",
            ],
            "no cone took an octree sample",
        ),
    ] {
        let out =
            Command::new(env!("CARGO_BIN_EXE_voxlod")).args(&args).arg("--quiet").output().unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn cone_command_measures_primary_visibility_with_lod() {
    let dir = std::env::temp_dir().join(format!("voxlod-cone-lod-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_voxlod"))
        .args(["cone", "builtin:cornell", "--res", "8", "--cones", "1", "--apertures", "30"])
        .args(["--steps", "1", "--size", "16", "--spp", "4", "--lod-scene", "builtin:bunny"])
        .args(["--lod-res", "32", "--lod-size", "16", "--lod-spp", "4", "--lod-bias", "0,2"])
        .args(["--lod-zoom-out", "4", "--json", "--quiet", "-o"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = crate::json_result(&out.stdout, "cone");
    let p = &v["lod"];
    let rows = p["rows"].as_array().unwrap();
    // 2 opacity pre-filters × 2 biases.
    assert_eq!(rows.len(), 4, "{rows:?}");
    for pair in rows.chunks(2) {
        let (finest, lod) = (&pair[0], &pair[1]);
        assert_eq!(finest["bias"], 0.0);
        assert_eq!(finest["mse_finest"], 0.0);
        assert!(finest["mse_truth"].as_f64().unwrap() > 0.0, "{finest}");
        let s = |r: &serde_json::Value| r["samples_per_pixel"].as_f64().unwrap();
        assert!(s(lod) < s(finest), "{lod} vs {finest}");
    }
    let [near, far] =
        ["nearest_voxels", "farthest_voxels"].map(|k| p["footprint"][k].as_f64().unwrap());
    assert!(0.0 < near && near <= far, "{p}");
    assert!(dir.join("assets/cone_lod_images.png").exists());
    let _ = std::fs::remove_dir_all(&dir);

    for (extra, needle) in [
        ("--lod-bias=-1", "'-1' for '--lod-bias"),
        ("--lod-bias=nan", "'nan' for '--lod-bias"),
        ("--lod-res=12", "'12' for '--lod-res"),
        ("--lod-step=0", "'0' for '--lod-step"),
        ("--lod-zoom-out=0", "'0' for '--lod-zoom-out"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_voxlod"))
            .args(["cone", "builtin:cornell", "--quiet", extra])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{extra:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{extra:?}: {err}");
    }
}

/// `voxlod cone --backend gpu`: the sweep's cones traced by the GPU kernel give the CPU's rows
/// (the same AO and indirect errors against the same references, within the kernel's
/// rounding) and name the adapter; an adapter that is not there is an error, never a
/// fall-back to the CPU. Skipped (with a message) where no adapter exists.
#[test]
fn cone_command_traces_on_the_gpu_backend() {
    let run = |backend: &str, adapter: Option<&str>| {
        let dir = std::env::temp_dir().join(format!(
            "voxlod-cone-{backend}-{}-{}",
            std::process::id(),
            adapter.is_some()
        ));
        let mut c = Command::new(env!("CARGO_BIN_EXE_voxlod"));
        c.args(["cone", "builtin:cornell", "--res", "16", "--cones", "6", "--apertures", "30"])
            .args(["--steps", "0.5", "--size", "16", "--spp", "4", "--json", "--quiet"])
            .args(["--lod-scene", "none", "--backend", backend, "-o"])
            .arg(&dir);
        if let Some(a) = adapter {
            c.env("VOXLOD_ADAPTER", a);
        }
        let out = c.output().unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        out
    };
    let missing = run("gpu", Some("no-such-adapter-xyz"));
    assert!(!missing.status.success());
    let err = String::from_utf8_lossy(&missing.stderr);
    let no_adapter = voxlod::gpu::adapters().is_empty();
    // Without any adapter, opening the backend fails before the name is looked at.
    let needle = if no_adapter { "no GPU adapter" } else { "no-such-adapter-xyz" };
    assert!(err.contains(needle), "{err}");
    if no_adapter {
        eprintln!(
            "no GPU adapter: the GPU sweep is not checked here (the equivalence suite says so)"
        );
        return;
    }
    let json = |out: std::process::Output| -> serde_json::Value {
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        crate::json_result(&out.stdout, "cone")
    };
    let (cpu, gpu) = (json(run("cpu", None)), json(run("gpu", None)));
    assert!(cpu["backend"].as_str().unwrap().starts_with("cpu"), "{}", cpu["backend"]);
    assert!(gpu["backend"].as_str().unwrap().starts_with("gpu: "), "{}", gpu["backend"]);
    let (a, b) = (cpu["rows"].as_array().unwrap(), gpu["rows"].as_array().unwrap());
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x["opacity"], y["opacity"]);
        assert_eq!(x["steps_per_pixel"], y["steps_per_pixel"], "{x} vs {y}");
        for k in ["ao_mse", "ao_ssim", "indirect_mse", "indirect_ssim"] {
            let (p, q) = (x[k].as_f64().unwrap(), y[k].as_f64().unwrap());
            // 8-bit images of values equal to ~1e-5: at most a few pixels one step apart.
            assert!((p - q).abs() <= 1e-3, "{k}: cpu {p} vs gpu {q}");
        }
    }
}
