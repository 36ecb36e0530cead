//! The default report on a tiny configuration: every stage runs, the report is written, and
//! the numbers it reports are consistent with each other.

use std::time::Duration;

use glam::Vec3;
use voxlod_studies::backend::Backend;
use voxlod_studies::filtered::FilteredConfig;
use voxlod_studies::report::{self, Config, SceneCase};
use voxlod_studies::volume::VolumeConfig;

fn tiny() -> Config {
    Config {
        scenes: vec![SceneCase::new("builtin:bunny", "bunny")],
        resolutions: vec![12, 48],
        image_size: 40,
        gt_spp: 16,
        views: 2,
        section_budget: Duration::from_secs(600),
        ambient: Vec3::splat(0.1),
        filtered: Some(FilteredConfig {
            resolutions: vec![16],
            higher_image: Some(40),
            rays: 64,
            heldout: 128,
            thresholds: vec![0.1, 1e9],
            image_thresholds: vec![0.02],
            contribution_samples: 8,
            ..FilteredConfig::quick()
        }),
        volume: Some(VolumeConfig {
            preset: "smoke".into(),
            particles: 150,
            resolution: 32,
            metavoxel_sizes: vec![8, 16],
            image: 32,
            mesh_spp: 2,
        }),
        cone: None,
        turntable: None,
        command: "the report test".into(),
    }
}

const METHODS: [&str; 5] = [
    "Averages",
    "[VJK21]",
    "virtual mesh (lines)",
    "virtual mesh (circles)",
    "virtual mesh (lines × area)",
];

#[test]
fn tiny_experiment_writes_a_consistent_report() {
    let outcome = report::run(&tiny(), Backend::Cpu, &|_| {}).unwrap();
    let scene = &outcome.scenes[0];
    assert_eq!(scene.triangles, 3674);
    assert_eq!(scene.rows.len(), 2);
    assert_eq!(scene.gt_noise.len(), 2);
    for row in &scene.rows {
        assert!(row.voxels > 0 && row.memory_bytes > 0);
        for v in [row.mse.mean, row.mse.min, row.mse.max] {
            assert!((0.0..1.0).contains(&v), "{row:?}");
        }
        assert!(row.mse.min <= row.mse.mean && row.mse.mean <= row.mse.max);
        assert!(row.ssim.max <= 1.0 && row.ssim.min > 0.0, "{row:?}");
    }
    // Finer voxels follow the surface better: 48³ is closer to the mesh than 12³.
    assert!(scene.rows[1].mse.mean < scene.rows[0].mse.mean, "{:?}", scene.rows);
    // The ground truth's own noise is far below the baseline's error.
    let noise = scene.gt_noise.iter().map(|m| m.mse).fold(0.0, f64::max);
    assert!(noise < scene.rows[1].mse.min / 2.0, "noise {noise} vs {:?}", scene.rows[1].mse);

    // Every representation at 16³, rendered at 16² and 40², scored, with honest byte counts.
    let filtered = scene.filtered.as_ref().unwrap();
    assert_eq!(filtered.rows.len(), 2 * (METHODS.len() + 3), "{:?}", filtered.rows);
    for row in &filtered.rows {
        assert!(row.voxels > 0 && row.memory_bytes > 0, "{row:?}");
        assert!(row.bytes_per_voxel >= row.record_bytes, "{row:?}");
        assert!((0.0..1.0).contains(&row.mse.mean) && row.ssim.mean > 0.0, "{row:?}");
        assert!(row.render_cold_ms > 0.0 && row.precompute_ms > 0.0, "{row:?}");
    }
    let bytes = |m: &str| filtered.rows.iter().find(|r| r.method == m).unwrap().record_bytes;
    assert_eq!(bytes("Averages"), 8.0);
    assert_eq!(bytes("[VJK21]"), 12.0);
    assert_eq!(bytes("virtual mesh (lines)"), 136.0);
    // An infinite threshold picks Averages everywhere: its tag plus its record.
    let loose = filtered.rows.iter().find(|r| r.method.contains("1000000000")).unwrap();
    assert_eq!(loose.mix, Some([1.0, 0.0, 0.0]));
    assert_eq!(loose.record_bytes, 12.0);
    // The image-error selector's row and the predictor check at the one resolution.
    assert!(filtered.rows.iter().any(|r| r.method == "Adaptive (image) τ=0.02"));
    assert_eq!(filtered.predictor.len(), 1);
    let check = &filtered.predictor[0];
    assert_eq!((check.resolution, check.samples), (16, 8));
    assert!((-1.0..=1.0).contains(&check.image_spearman), "{check:?}");

    let dir = std::env::temp_dir().join(format!("voxlod-report-{}", std::process::id()));
    let written = outcome.report.write(&dir).unwrap();
    let md = std::fs::read_to_string(&written.markdown).unwrap();
    assert!(md.contains("bunny") && md.contains("baseline (opaque cubes)"), "{md}");
    assert!(md.contains("The ground truth's own error"), "{md}");
    assert!(dir.join("assets/ssim-vs-memory.svg").exists());
    assert!(md.contains("filtered appearance 16^3"), "{md}");
    assert!(md.contains("Adaptive selector errors against measured voxel contributions"), "{md}");
    for m in METHODS {
        assert!(md.contains(m), "{m} missing from the report");
    }
    // The procedural-volume section: both attenuation models scored against the exact
    // march, one row per metavoxel size, the sparse volume smaller than the dense one at M = 8.
    let volume = outcome.volume.as_ref().expect("the volume section ran");
    assert!(md.contains("Procedural volume: smoke"), "{md}");
    assert_eq!(volume.sizes.len(), 2);
    assert!(volume.attenuation.iter().all(|r| r.metrics.ssim > 0.5), "{:?}", volume.attenuation);
    let m8 = &volume.sizes[0];
    assert!(m8.occupied > 0 && m8.volume_bytes < m8.dense_bytes, "{m8:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_exhausted_budget_skips_resolutions_and_says_so() {
    let config = Config { section_budget: Duration::ZERO, ..tiny() };
    let outcome = report::run(&config, Backend::Cpu, &|_| {}).unwrap();
    assert_eq!(outcome.scenes[0].skipped, vec![12, 48]);
    assert!(outcome.scenes[0].rows.is_empty());
    assert_eq!(outcome.scenes[0].filtered.as_ref().unwrap().skipped, vec![16]);
}
