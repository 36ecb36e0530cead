//! Every study's presets validate, and a bad field is refused with an error that names the
//! study, the field and the value before anything runs.

use voxlod_studies::Error;
use voxlod_studies::cone::{ConeConfig, LodConfig};
use voxlod_studies::filtered::FilteredConfig;
use voxlod_studies::report::Config;
use voxlod_studies::volume::VolumeConfig;

/// The (study, field, value) an error names, or a panic naming what came back instead.
fn named(result: Result<(), Error>) -> (&'static str, &'static str, String) {
    match result {
        Err(Error::InvalidConfig { study, field, value, .. }) => (study, field, value),
        other => panic!("expected InvalidConfig, got {other:?}"),
    }
}

#[test]
fn presets_validate() {
    for config in [Config::quick(), Config::full()] {
        config.validate().unwrap();
    }
    FilteredConfig::quick().validate().unwrap();
    FilteredConfig::full().validate().unwrap();
    for preset in voxlod_studies::volume::PRESETS {
        VolumeConfig::quick(preset).validate().unwrap();
    }
    ConeConfig::quick().validate().unwrap();
    ConeConfig::full().validate().unwrap();
    LodConfig::quick().validate().unwrap();
}

#[test]
fn bad_filtered_fields_are_named() {
    let base = FilteredConfig::quick();
    let cases = [
        (FilteredConfig { resolutions: vec![], ..base.clone() }, "resolutions"),
        (FilteredConfig { resolutions: vec![64, 1], ..base.clone() }, "resolutions"),
        (FilteredConfig { higher_image: Some(0), ..base.clone() }, "higher_image"),
        (FilteredConfig { rays: 0, ..base.clone() }, "rays"),
        (FilteredConfig { heldout: 0, ..base.clone() }, "heldout"),
        (FilteredConfig { thresholds: vec![0.1, f32::NAN], ..base.clone() }, "thresholds"),
        (FilteredConfig { image_thresholds: vec![-1.0], ..base.clone() }, "image_thresholds"),
    ];
    for (config, field) in cases {
        let (study, got, _) = named(config.validate());
        assert_eq!((study, got), ("filtered appearance", field));
    }
}

#[test]
fn bad_volume_fields_are_named() {
    let base = VolumeConfig::quick("smoke");
    let cases = [
        (VolumeConfig { preset: "fog".into(), ..base.clone() }, "preset", "fog"),
        (VolumeConfig { resolution: 0, ..base.clone() }, "resolution", "0"),
        (VolumeConfig { metavoxel_sizes: vec![], ..base.clone() }, "metavoxel_sizes", "[]"),
        // 64 is not a multiple of 24; 64 / 0 is not defined.
        (VolumeConfig { metavoxel_sizes: vec![8, 24], ..base.clone() }, "metavoxel_sizes", "24"),
        (VolumeConfig { metavoxel_sizes: vec![0], ..base.clone() }, "metavoxel_sizes", "0"),
        (VolumeConfig { image: 0, ..base.clone() }, "image", "0"),
        (VolumeConfig { mesh_spp: 0, ..base.clone() }, "mesh_spp", "0"),
    ];
    for (config, field, value) in cases {
        assert_eq!(named(config.validate()), ("volume", field, value.to_string()));
    }
    // 1024³ at M = 4 would be 256 metavoxels per axis: over the 128 the volume kernels index.
    let fine = VolumeConfig { resolution: 1024, metavoxel_sizes: vec![4], ..base };
    assert_eq!(named(fine.validate()).1, "metavoxel_sizes");
}

#[test]
fn the_report_checks_its_own_fields_and_the_studies_it_carries() {
    let base = Config::quick();
    let cases = [
        (Config { scenes: vec![], ..base.clone() }, ("report", "scenes")),
        (Config { resolutions: vec![0], ..base.clone() }, ("report", "resolutions")),
        (Config { image_size: 0, ..base.clone() }, ("report", "image_size")),
        (Config { gt_spp: 0, ..base.clone() }, ("report", "gt_spp")),
        (Config { views: 0, ..base.clone() }, ("report", "views")),
        (
            Config { ambient: glam::Vec3::new(0.1, -1.0, 0.1), ..base.clone() },
            ("report", "ambient"),
        ),
        (
            Config {
                filtered: Some(FilteredConfig { rays: 0, ..FilteredConfig::quick() }),
                ..base.clone()
            },
            ("filtered appearance", "rays"),
        ),
        (
            Config {
                volume: Some(VolumeConfig { image: 0, ..VolumeConfig::quick("smoke") }),
                ..base.clone()
            },
            ("volume", "image"),
        ),
        (
            Config { cone: Some(ConeConfig { spp: 0, ..ConeConfig::quick() }), ..base.clone() },
            ("cone", "spp"),
        ),
    ];
    for (config, want) in cases {
        let (study, field, _) = named(config.validate());
        assert_eq!((study, field), want);
    }
}

#[test]
fn run_refuses_a_bad_config_before_it_starts() {
    // Would otherwise load three scenes and render for a minute; fails in the check.
    let config = Config { views: 0, ..Config::quick() };
    let err = voxlod_studies::report::run(&config, voxlod_studies::backend::Backend::Cpu, &|_| {})
        .unwrap_err();
    let message = err.to_string();
    assert!(message.contains("views") && message.contains("report"), "{message}");
    let volume = VolumeConfig { preset: "fog".into(), ..VolumeConfig::quick("smoke") };
    let err = voxlod_studies::volume::run(&volume, voxlod_studies::backend::Backend::Cpu, &|_| {})
        .unwrap_err();
    assert!(err.to_string().contains("fog"), "{err}");
}
