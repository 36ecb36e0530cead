//! The `voxlod` binary end to end: each subcommand on small inputs, JSON output, one-line
//! errors with a non-zero exit, and no output file left behind by a failure.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::voxlod;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxlod-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "exit {:?}\nstdout: {}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout.clone()).unwrap()
}

/// The `result` of a `--json` output (the command's name is the first argument).
fn json(out: &Output) -> serde_json::Value {
    let stdout = ok(out);
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("valid JSON on stdout");
    let command = v["command"].as_str().expect("a command field").to_string();
    crate::json_result(stdout.as_bytes(), &command)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn voxelize_then_info_round_trips_through_both_formats() {
    let dir = temp_dir("voxelize");
    for (file, mode) in [("bunny.vxl", "conservative"), ("bunny.binvox", "solid")] {
        let path = dir.join(file);
        let args = ["voxelize", "builtin:bunny", "--res", "24", "--mode", mode, "-o", s(&path)];
        let summary = json(&voxlod(&[&args[..], &["--json"]].concat()));
        let voxels = summary["voxels"].as_u64().unwrap();
        assert!(voxels > 100, "{summary}");
        let info = json(&voxlod(&["info", s(&path), "--json"]));
        assert_eq!(info["voxels"].as_u64(), Some(voxels), "{info}");
    }
    let info = json(&voxlod(&["info", s(&dir.join("bunny.vxl")), "--json"]));
    assert_eq!(info["meta"]["mode"], "conservative");
    assert_eq!(info["checksum_ok"], true);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn render_and_compare_images() {
    let dir = temp_dir("render");
    let a = dir.join("a.png");
    let b = dir.join("b.png");
    for (path, seed) in [(&a, "0"), (&b, "1")] {
        let args = ["render", "builtin:bunny", "--size", "48x40", "--spp", "4", "--seed", seed];
        ok(&voxlod(&[&args[..], &["--gbuffer", "-o", s(path)]].concat()));
    }
    assert!(dir.join("a.depth.png").exists() && dir.join("a.normal.png").exists());
    let same = json(&voxlod(&["compare-images", s(&a), s(&a), "--json"]));
    assert_eq!(same["mse"], 0.0);
    assert_eq!(same["ssim"], 1.0);
    assert_eq!(same["psnr"], "inf");
    let noisy = json(&voxlod(&["compare-images", s(&a), s(&b), "--json"]));
    let (mse, ssim) = (noisy["mse"].as_f64().unwrap(), noisy["ssim"].as_f64().unwrap());
    assert!(mse > 0.0 && mse < 0.01, "two seeds of the same render differ only by noise: {mse}");
    assert!(ssim > 0.5 && ssim < 1.0, "{ssim}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn errors_are_one_line_nonzero_and_leave_no_file() {
    let dir = temp_dir("errors");
    let (vxl, txt, png) = (dir.join("never.vxl"), dir.join("x.txt"), dir.join("r.png"));
    let cases: [(&[&str], &str); 6] = [
        (&["voxelize", "builtin:nonesuch", "-o", s(&vxl)], "nonesuch"),
        (&["voxelize", "builtin:bunny", "--res", "0", "-o", s(&vxl)], "too large"),
        (&["voxelize", "missing.obj", "-o", s(&vxl)], "missing.obj"),
        (&["voxelize", "builtin:bunny", "-o", s(&txt)], ".vxl or .binvox"),
        (&["render", "builtin:bunny", "--size", "0x3", "-o", s(&png)], "0x3"),
        (&["render", "builtin:bunny", "--camera", "eye=1,2", "-o", s(&png)], "eye"),
    ];
    for (args, needle) in cases {
        let out = voxlod(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: '{needle}' not in {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "files left behind: {left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_failed_write_keeps_the_previous_output() {
    let dir = temp_dir("keep");
    let path = dir.join("grid.vxl");
    ok(&voxlod(&["voxelize", "builtin:bunny", "--res", "8", "-o", s(&path)]));
    let before = std::fs::read(&path).unwrap();
    // The scene fails to load after the output exists: the old file must survive untouched.
    let out = voxlod(&["voxelize", "builtin:forest?trees=0", "-o", s(&path)]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read(&path).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn scenes_lists_builtins_with_parameters() {
    let out = ok(&voxlod(&["scenes"]));
    for name in ["bunny", "engine", "forest", "island"] {
        assert!(out.contains(name), "{name} missing from:\n{out}");
    }
    assert!(out.contains("trees"));
}

#[test]
fn compare_measures_every_representation_and_rejects_bad_arguments() {
    let dir = temp_dir("compare");
    let out = voxlod(&[
        "compare",
        "builtin:cube",
        "--res",
        "12",
        "--image",
        "24",
        "--spp",
        "4",
        "--views",
        "1",
        "--rays",
        "32",
        "--json",
        "-o",
        s(&dir),
    ]);
    let v = json(&out);
    let rows = v[0]["filtered"]["rows"].as_array().expect("rows");
    // 5 fixed methods (Averages, [VJK21], 3 virtual-mesh variants) + 3 Adaptive thresholds,
    // at 12² and 24².
    assert_eq!(rows.len(), 16, "{rows:?}");
    assert!(dir.join("report.md").exists());

    for (args, needle) in [
        (vec!["compare", "builtin:cube", "--res", "0"], "'0' for '--res"),
        (vec!["compare", "builtin:cube", "--thresholds=-1"], "--thresholds"),
        (vec!["compare", "no/such/file.obj", "--res", "8"], "no/such/file.obj"),
    ] {
        let out = voxlod(&args);
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--backend gpu` never falls back to the CPU: an adapter that is not there, or a
/// request without a GPU kernel (solid voxelization), is an error (and leaves no file); where an adapter exists,
/// GPU voxelization writes the CPU's voxels.
#[test]
fn gpu_backend_is_explicit_and_never_falls_back() {
    let dir = temp_dir("gpu");
    let (vxl, png, cmp) = (dir.join("g.vxl"), dir.join("g.png"), dir.join("compare"));
    let run = |args: &[&str], adapter: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_voxlod"));
        c.args(args).arg("--quiet");
        if let Some(a) = adapter {
            c.env("VOXLOD_ADAPTER", a);
        }
        c.output().expect("the voxlod binary runs")
    };
    let cases: [(&[&str], Option<&str>, &str); 4] = [
        (
            &[
                "voxelize",
                "builtin:cube",
                "--res",
                "8",
                "--mode",
                "solid",
                "--backend",
                "gpu",
                "-o",
                s(&vxl),
            ],
            None,
            "solid",
        ),
        (
            &["voxelize", "builtin:cube", "--res", "8", "--backend", "gpu", "-o", s(&vxl)],
            Some("no-such-adapter-anywhere"),
            "adapter",
        ),
        (
            &["render", "builtin:cube", "--size", "8x8", "--backend", "gpu", "-o", s(&png)],
            Some("no-such-adapter-anywhere"),
            "adapter",
        ),
        (
            &["compare", "builtin:cube", "--res", "8", "--backend", "gpu", "-o", s(&cmp)],
            Some("no-such-adapter-anywhere"),
            "adapter",
        ),
    ];
    // Without any adapter every GPU request fails on opening the backend, before the adapter
    // name or the mode is looked at: the error then says so.
    let no_adapter = voxlod::gpu::adapters().is_empty();
    for (args, adapter, needle) in cases {
        let needle = if no_adapter { "no GPU adapter" } else { needle };
        let out = run(args, adapter);
        // The Vulkan loader may print its own lines on stderr: look for ours anywhere.
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded: no fall-back allowed");
        assert!(stderr.contains("error: ") && stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "a failure left a file");
    if !no_adapter {
        let voxels = |backend: &str| {
            let path = dir.join(format!("{backend}.vxl"));
            let args =
                ["voxelize", "builtin:bunny", "--res", "24", "--backend", backend, "-o", s(&path)];
            let out = run(&[&args[..], &["--json"]].concat(), None);
            let v = json(&out);
            assert!(v["backend"].as_str().unwrap().starts_with(backend), "{v}");
            v["voxels"].as_u64().unwrap()
        };
        assert_eq!(voxels("gpu"), voxels("cpu"));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `voxlod compare --backend gpu` renders the ground truth, the baseline, Averages and
/// \[VJK21\] on the adapter and the rest on the CPU, says so per row, and scores like the CPU
/// run (the kernels match the CPU within 1 sRGB step on ≥ 99 % of pixels, so SSIM agrees to
/// well under 0.01). No adapter fails loudly unless `VOXLOD_ALLOW_NO_GPU=1` (the convention of
/// `cargo xtask test --allow-no-gpu` and the equivalence suite): never a silent pass.
#[test]
fn compare_on_the_gpu_scores_like_the_cpu_and_names_each_rows_backend() {
    if voxlod::gpu::adapters().is_empty() {
        eprintln!(
            "!!!!!!!! NO GPU ADAPTER FOUND: `voxlod compare --backend gpu` was NOT checked !!!!!!!!"
        );
        eprintln!("install Mesa's lavapipe (apt-get install mesa-vulkan-drivers) or a GPU driver");
        let allowed = std::env::var("VOXLOD_ALLOW_NO_GPU").is_ok_and(|v| v == "1");
        assert!(allowed, "no GPU adapter (set VOXLOD_ALLOW_NO_GPU=1 to allow)");
        return;
    }
    let dir = temp_dir("compare-gpu");
    let run = |backend: &str| {
        let out = dir.join(backend);
        let args = [
            "compare",
            "builtin:bunny",
            "--res",
            "16",
            "--image",
            "24",
            "--spp",
            "4",
            "--views",
            "1",
            "--rays",
            "16",
            "--thresholds",
            "0.2",
            "--backend",
            backend,
            "--json",
            "-o",
            s(&out),
        ];
        let v = json(&voxlod(&args));
        let report = std::fs::read_to_string(out.join("report.md")).unwrap();
        (v[0].clone(), report)
    };
    let (cpu, cpu_report) = run("cpu");
    let (gpu, gpu_report) = run("gpu");

    // The CPU run is the run it always was: no backend anywhere but in the command line the
    // report's header names.
    assert!(cpu.get("gt_backend").is_none(), "{cpu}");
    let body: Vec<&str> = cpu_report.lines().filter(|l| !l.starts_with("Generated by `")).collect();
    assert!(body.iter().all(|l| !l.contains("backend")), "{cpu_report}");
    // The GPU run names its adapter for the ground truth and every row (the baseline,
    // Averages, [VJK21], the virtual mesh and Adaptive).
    let adapter = gpu["gt_backend"].as_str().expect("gt_backend").to_string();
    assert!(!adapter.is_empty() && adapter != "cpu", "{adapter}");
    assert!(gpu_report.contains("**Backend:**") && gpu_report.contains(&adapter));
    for row in gpu["rows"].as_array().unwrap() {
        assert_eq!(row["backend"], adapter.as_str(), "{row}");
    }
    let filtered = |v: &serde_json::Value| v["filtered"]["rows"].as_array().unwrap().clone();
    let (cpu_rows, gpu_rows) = (filtered(&cpu), filtered(&gpu));
    assert_eq!(cpu_rows.len(), 12, "{cpu_rows:?}");
    assert_eq!(gpu_rows.len(), cpu_rows.len());
    let ssim = |r: &serde_json::Value| r["ssim"]["mean"].as_f64().unwrap();
    let base = |v: &serde_json::Value| ssim(&v["rows"][0]);
    assert!(
        (base(&gpu) - base(&cpu)).abs() < 0.01,
        "baseline SSIM {} vs {}",
        base(&gpu),
        base(&cpu)
    );
    for (c, g) in cpu_rows.iter().zip(&gpu_rows) {
        assert!(c.get("backend").is_none(), "{c}");
        assert_eq!((&c["method"], &c["image"]), (&g["method"], &g["image"]));
        let method = g["method"].as_str().unwrap();
        assert_eq!(g["backend"], adapter.as_str(), "{g}");
        // Averages is precomputed on the adapter, the other representations on the CPU.
        assert!(c.get("precompute_backend").is_none(), "{c}");
        let on = if method == "Averages" { adapter.as_str() } else { "cpu" };
        assert_eq!(g["precompute_backend"], on, "{g}");
        assert!(
            (ssim(g) - ssim(c)).abs() < 0.01,
            "{method} at {}²: SSIM {} on the GPU, {} on the CPU",
            g["image"],
            ssim(g),
            ssim(c)
        );
    }

    // The forest's alpha-masked textured leaves render on the GPU too (once refused): its
    // ground truth comes from the adapter, not the CPU, and so do its Averages (the
    // precompute serves textured and alpha-tested materials: no CPU fallback any more).
    let spec = "builtin:forest?trees=1&leaves=8";
    let args = ["compare", spec, "--res", "12", "--image", "0", "--spp", "4", "--views", "1"];
    let args = [&args[..], &["--rays", "16", "--thresholds", "0.2"]].concat();
    let out =
        voxlod(&[&args[..], &["--backend", "gpu", "--json", "-o", s(&dir.join("f"))]].concat());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let forest = crate::json_result(&out.stdout, "compare");
    assert_eq!(forest[0]["gt_backend"], adapter.as_str(), "{forest}");
    let averages: Vec<_> =
        filtered(&forest[0]).into_iter().filter(|r| r["method"] == "Averages").collect();
    assert!(!averages.is_empty(), "{forest}");
    for r in &averages {
        assert_eq!(r["precompute_backend"], adapter.as_str(), "{r}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
