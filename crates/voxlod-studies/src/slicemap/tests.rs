//! The slicemap study's configuration checks and timing summary.

use super::*;

/// A change to a configuration, and the field its error must name.
type Case = (Box<dyn Fn(&mut SlicemapConfig)>, &'static str);

#[test]
fn presets_are_valid_and_bad_fields_are_named() {
    SlicemapConfig::quick().validate().unwrap();
    SlicemapConfig::full().validate().unwrap();
    let cases: Vec<Case> = vec![
        (Box::new(|c| c.holes.as_mut().unwrap().resolution = 513), "holes.resolution"),
        (Box::new(|c| c.holes.as_mut().unwrap().slices = vec![]), "holes.slices"),
        (Box::new(|c| c.holes.as_mut().unwrap().scenes = vec![]), "holes.scenes"),
        (Box::new(|c| c.holes.as_mut().unwrap().map_size = 0), "holes.map_size"),
        (Box::new(|c| c.shadows.as_mut().unwrap().maps = vec![(512, 600)]), "shadows.maps"),
        (Box::new(|c| c.shadows.as_mut().unwrap().sigma = -0.1), "shadows.sigma"),
        (Box::new(|c| c.shadows.as_mut().unwrap().spp = 0), "shadows image"),
        (Box::new(|c| c.shadows.as_mut().unwrap().bias_pixels = f64::NAN), "shadows.bias_pixels"),
        (Box::new(|c| c.refraction.as_mut().unwrap().slices = vec![0]), "refraction.slices"),
        (Box::new(|c| c.refraction.as_mut().unwrap().width = 5000), "refraction image"),
    ];
    for (change, field) in cases {
        let mut c = SlicemapConfig::quick();
        change(&mut c);
        let err = c.validate().unwrap_err().to_string();
        assert!(err.contains(field), "{field}: {err}");
        assert!(run(&c, Backend::Cpu, &|_| {}).is_err(), "{field}: run validates");
    }
    // Parts left out are not checked.
    let none = SlicemapConfig { holes: None, shadows: None, refraction: None };
    none.validate().unwrap();
}

#[test]
fn for_scene_points_every_part_at_the_scene() {
    let c = SlicemapConfig::quick().for_scene("builtin:cube");
    assert_eq!(c.holes.unwrap().scenes, vec!["builtin:cube".to_string()]);
    assert_eq!(c.shadows.unwrap().scene, "builtin:cube");
    assert_eq!(c.refraction.unwrap().scene, "builtin:cube");
}

#[test]
fn timings_keep_median_and_range() {
    let t = Timing::of(&[5.0, 1.0, 3.0]);
    assert_eq!((t.median_ms, t.min_ms, t.max_ms), (3.0, 1.0, 5.0));
    assert_eq!(t.display(), "3.0 (1.0–5.0)");
    assert_eq!(Timing::of(&[2.0]).display(), "2.0");
    assert_eq!(Timing::of(&[]), Timing::default());
}
