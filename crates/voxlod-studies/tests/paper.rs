//! The paper setup and its ablation at smoke scale (the coarse bunny at 32³): the pieces hold
//! together, the pairing is exact where nothing changed, and the ground-truth cache returns the
//! same images.

use voxlod_studies::paper::ablation::{self, Toggle};
use voxlod_studies::paper::{self, Crop, PairedDiff, PaperConfig, Variant};

fn config(cache: Option<std::path::PathBuf>) -> PaperConfig {
    PaperConfig { cache, seeds: 2, ..PaperConfig::smoke() }
}

#[test]
fn the_ablation_pairs_each_variant_with_the_setup() {
    let dir = std::env::temp_dir().join(format!("voxlod-paper-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let config = config(Some(dir.clone()));
    let toggles = [
        Toggle::LinesOpacityRule,
        Toggle::Crop,
        Toggle::SunOnly,
        Toggle::CoarseMesh,
        Toggle::FlippedAveragesNormal,
        Toggle::PerRayChord,
    ];
    let result = ablation::run(&config, &toggles, &|_| {}).unwrap();
    let cases = &result.result.cases;
    assert_eq!(cases.len(), 7);
    assert_eq!(cases[0].variant, Variant::paper());
    let methods: Vec<&str> = cases[0].methods.iter().map(|m| m.method.as_str()).collect();
    assert_eq!(
        methods,
        [
            "Averages",
            "[VJK21]",
            "virtual mesh",
            "Adaptive τ=0.1",
            "Adaptive (image) τ=0.01",
            "Adaptive (image) τ=0.02"
        ]
    );
    for c in cases {
        assert_eq!(c.samples, 4);
        for m in &c.methods {
            assert_eq!(m.mse.len(), 4, "{} {}", c.variant.name, m.method);
            assert!(m.mse.iter().all(|x| x.is_finite() && *x > 0.0));
            assert!(m.ssim.iter().all(|x| *x > 0.0 && *x < 1.0));
        }
    }
    let find = |name: &str| cases.iter().find(|c| c.variant.name == name).unwrap();
    let setup = &cases[0];
    // The opacity rule changes the virtual mesh only: every other method's scores are the
    // setup's sample for sample, so their paired difference is exactly zero and unresolved.
    let lines = find(Toggle::LinesOpacityRule.name());
    for m in ["Averages", "[VJK21]"] {
        let d = PairedDiff::of(&lines.method(m).unwrap().mse, &setup.method(m).unwrap().mse);
        assert_eq!((d.mean, d.lo, d.hi), (0.0, 0.0, 0.0), "{m}");
        assert!(!d.resolved());
    }
    assert_ne!(
        lines.method("virtual mesh").unwrap().mse,
        setup.method("virtual mesh").unwrap().mse
    );
    // Each of the authors' choices moves only the method it belongs to.
    let moved = |toggle: Toggle, method: &str| {
        let case = find(toggle.name());
        for m in ["Averages", "[VJK21]", "virtual mesh"] {
            let same = case.method(m).unwrap().mse == setup.method(m).unwrap().mse;
            assert_eq!(same, m != method, "{}: {m}", toggle.name());
        }
    };
    moved(Toggle::FlippedAveragesNormal, "Averages");
    moved(Toggle::PerRayChord, "[VJK21]");
    moved(Toggle::LinesOpacityRule, "virtual mesh");
    // Cropping to the coverage removes background pixels every method gets nearly right: the
    // MSE over what remains is higher.
    let crop = find(Toggle::Crop.name());
    for (c, s) in crop.methods.iter().zip(&setup.methods) {
        assert!(c.mse_mean() > s.mse_mean(), "{}: {} vs {}", c.method, c.mse_mean(), s.mse_mean());
    }
    // The coarse variant is another scene.
    assert_ne!(find(Toggle::CoarseMesh.name()).spec, setup.spec);
    // Tables and report render.
    let tables = result.tables().unwrap();
    assert_eq!(tables.len(), 2);
    assert!(tables[0].to_markdown().contains("virtual mesh − [VJK21]"));

    // A second run of the setup alone loads every ground truth from the cache and measures the
    // same numbers.
    let again = paper::run(&config, &|_| {}).unwrap();
    assert_eq!(again.truths_rendered, 0);
    assert!(again.truths_cached >= 4);
    for (a, b) in again.cases[0].methods.iter().zip(&setup.methods) {
        assert_eq!(a.mse, b.mse);
        assert_eq!(a.ssim, b.ssim);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn crop_keeps_the_covered_box_with_a_margin() {
    use glam::Vec4;
    let mut image = voxlod_scene::Image::new(40, 30, Vec4::new(1.0, 1.0, 1.0, 0.0));
    for (x, y) in [(10, 8), (25, 20), (18, 12)] {
        image.set(x, y, Vec4::new(0.5, 0.5, 0.5, 0.25));
    }
    // x 10..=25 and y 8..=20, one pixel of margin: x 9..=26 (18 wide), y 7..=21 (15 high).
    assert_eq!(Crop::of_coverage(&image), Crop { x: 9, y: 7, width: 18, height: 15 });
    // A single covered pixel grows to the SSIM window (11 × 11).
    let mut dot = voxlod_scene::Image::new(40, 30, Vec4::ZERO);
    dot.set(0, 29, Vec4::ONE);
    let c = Crop::of_coverage(&dot);
    assert_eq!((c.width, c.height), (11, 11));
    assert_eq!((c.x, c.y + c.height), (0, 30));
    // Nothing covered: the whole image.
    let empty = voxlod_scene::Image::new(40, 30, Vec4::ZERO);
    assert_eq!(Crop::of_coverage(&empty), Crop::whole(&empty));
    // apply copies exactly the box.
    let srgb = image.to_srgb8();
    let cropped = Crop { x: 9, y: 7, width: 18, height: 15 }.apply(&srgb);
    assert_eq!(cropped.get(1, 1), srgb.get(10, 8));
    assert_eq!(cropped.get(16, 13), srgb.get(25, 20));
}

#[test]
fn bad_settings_are_refused_by_name() {
    for (config, field) in [
        (PaperConfig { resolutions: vec![8], ..PaperConfig::smoke() }, "resolutions"),
        (PaperConfig { seeds: 0, ..PaperConfig::smoke() }, "seeds"),
        (PaperConfig { views: 0, ..PaperConfig::smoke() }, "views"),
        (PaperConfig { scenes: vec![], ..PaperConfig::smoke() }, "scenes"),
        (PaperConfig { thresholds: vec![f32::NAN], ..PaperConfig::smoke() }, "thresholds"),
    ] {
        let err = paper::run(&config, &|_| {}).unwrap_err().to_string();
        assert!(err.contains(field), "{err}");
    }
}

#[test]
fn the_extras_sweep_rays_downsample_and_time_the_precompute() {
    use voxlod_studies::paper::extras::{self, ExtrasConfig};
    let config = PaperConfig { resolutions: vec![16], seeds: 1, ..PaperConfig::smoke() };
    let e = ExtrasConfig { rays: vec![8, 32], downsample: true, precompute: true };
    let result = extras::run(&config, &e, &|_| {}).unwrap();
    // Three methods (no Adaptive in the sweep) at two ray counts.
    assert_eq!(result.rays.len(), 6);
    assert!(result.rays.iter().all(|r| r.mse.len() == 2 && r.mse[0] > 0.0));
    // More rays change the virtual mesh's images (its fit sees other lines).
    let vm =
        |rays| result.rays.iter().find(|r| r.rays == rays && r.what == "virtual mesh").unwrap();
    assert_ne!(vm(8).mse, vm(32).mse);
    // The downsample experiment: three rows, the fine [VJK21] scored at the coarse side.
    assert_eq!(result.downsample.len(), 3);
    assert!(result.downsample[1].what.contains("32³ at 32²"));
    assert_ne!(result.downsample[0].mse, result.downsample[1].mse);
    let p = &result.precompute[0];
    assert!(p.voxels > 0 && p.precompute_s > 0.0 && p.memory_mb > 0.0);
    assert_eq!(p.paper_table_2, None, "16³ has no Table 2 row");
    assert_eq!(result.tables(32).unwrap().len(), 3);
}
