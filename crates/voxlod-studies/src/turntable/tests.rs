use super::*;

fn small() -> TurntableConfig {
    TurntableConfig {
        frames: 3,
        panel: (24, 20),
        gt_spp: 2,
        resolution: 12,
        rays: 4,
        frame_ms: 250,
        ..TurntableConfig::quick()
    }
}

#[test]
fn each_frame_is_the_ground_truth_beside_the_voxel_panels_from_its_own_view() {
    let scene = crate::scenes::load("builtin:bunny").unwrap();
    let geometry = scene.geometry();
    let bvh = Bvh::new(&geometry).unwrap();
    let camera = scene.default_camera().unwrap();
    let inputs =
        TurntableInputs { scene: &scene, geometry: &geometry, bvh: &bvh, camera, label: "bunny" };
    let config = small();
    let r = run(&config, &inputs, Backend::Cpu, &|_| {}).unwrap();
    assert_eq!((r.frames, r.animation.frames.len(), r.animation.frame_ms), (3, 3, 250));
    let labels: Vec<&str> = r.panels.iter().map(|p| p.panel.as_str()).collect();
    assert_eq!(labels, ["ground truth", "voxels 12^3", "Averages 12^3"]);

    // Frame 1 rebuilt by hand: the camera a third of a turn round, each panel rendered alone,
    // composed the same way. The turntable's frame must be exactly that image.
    let (lo, hi) = scene.bounds().unwrap();
    let view = orbit_views(camera, (lo + hi) * 0.5, 3)[1];
    assert_ne!(view.eye, camera.eye);
    let light = scene.light();
    let (w, h) = config.panel;
    let gt_options = ground_truth::Options {
        width: w,
        height: h,
        spp: 2,
        seed: 0,
        ambient: config.ambient,
        shadows: true,
        light_filter: None,
    };
    let gt = ground_truth::render(&scene, &geometry, &bvh, &view, &gt_options).unwrap();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 12).unwrap();
    let options = voxelize::Options { mode: Mode::Conservative, ..Default::default() };
    let vox = voxelize::voxelize(&geometry, &grid, &options).unwrap();
    let base = baseline::build(&scene, &geometry, &vox).unwrap();
    let b_options =
        baseline::Options { width: w, height: h, ambient: config.ambient, shadows: true };
    let b = baseline::render(&grid, &base, &view, &light, scene.background, &b_options).unwrap();
    let ctx = SamplingContext::new(&scene, &geometry, &vox).unwrap();
    let avg = precompute(&ctx, &PrecomputeOptions { rays: 4, seed: 0 }, averages::fit).unwrap();
    let mut cache = FrameCache::new(&avg).unwrap();
    let a_options = filtered::Options {
        width: w,
        height: h,
        ambient: config.ambient,
        shadows: true,
        ..Default::default()
    };
    let a = filtered::render(&mut cache, &view, &light, scene.background, &a_options).unwrap();
    let panels = [("ground truth", gt.image), ("voxels 12^3", b), ("Averages 12^3", a)]
        .map(|(l, img)| LabeledImage::new(l, img.to_srgb8()));
    let expected = ImageGrid::new(3, panels.to_vec()).compose().unwrap();
    assert_eq!(r.animation.frames[1], expected);
    assert_ne!(r.animation.frames[0], r.animation.frames[1]);

    // The voxel panels are scored against the ground truth of each frame: not identical to it.
    for p in &r.panels[1..] {
        let (mse, ssim) = (p.mse.unwrap(), p.ssim.unwrap());
        assert!(mse.min > 0.0 && mse.max.is_finite(), "{p:?}");
        assert!(ssim.max < 1.0 && ssim.min > 0.0, "{p:?}");
        assert_eq!(
            p.voxels,
            Some(if p.panel.starts_with("voxels") { base.len() } else { avg.records.len() })
        );
    }
    assert!(r.panels[0].mse.is_none());
    // The report section: the animation and the table.
    let mut report = Report::new("t");
    r.add_to_report(&mut report, "turntable-bunny").unwrap();
    assert_eq!(report.sections.len(), 3);
    assert_eq!(r.table().unwrap().rows().len(), 3);
}

#[test]
fn configurations_out_of_range_are_refused_by_name() {
    assert!(TurntableConfig::quick().validate().is_ok());
    assert!(TurntableConfig::full().validate().is_ok());
    let cases = [
        ("frames", TurntableConfig { frames: 0, ..small() }),
        ("frames", TurntableConfig { frames: 3601, ..small() }),
        ("panel", TurntableConfig { panel: (15, 64), ..small() }),
        ("gt_spp", TurntableConfig { gt_spp: 0, ..small() }),
        ("resolution", TurntableConfig { resolution: 0, ..small() }),
        ("rays", TurntableConfig { rays: 0, ..small() }),
        ("frame_ms", TurntableConfig { frame_ms: 0, ..small() }),
        ("ambient", TurntableConfig { ambient: Vec3::new(0.0, f32::NAN, 0.0), ..small() }),
    ];
    for (name, config) in cases {
        match config.validate() {
            Err(Error::InvalidConfig { study: "turntable", field, .. }) => assert_eq!(field, name),
            other => panic!("{name}: {other:?}"),
        }
    }
}

#[test]
fn the_report_adds_a_turntable_only_when_asked_with_its_own_settings() {
    use crate::report::Config;
    assert!(Config::quick().turntable.is_none() && Config::full().turntable.is_none());
    let config = Config::quick().with_turntable(12);
    let t = config.turntable.clone().unwrap();
    let filtered = config.filtered.clone().unwrap();
    assert_eq!((t.frames, t.panel), (12, (config.image_size, config.image_size)));
    assert_eq!((t.gt_spp, t.ambient), (config.gt_spp, config.ambient));
    let finest = filtered.resolutions.iter().copied().max().unwrap();
    assert_eq!((t.resolution, t.rays), (finest, filtered.rays));
    assert!(config.validate().is_ok());
    let bad = Config::quick().with_turntable(0);
    assert!(matches!(bad.validate(), Err(Error::InvalidConfig { study: "turntable", .. })));
}
