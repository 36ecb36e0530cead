//! The study end to end on a tiny case, and its configuration checks.

use super::*;
use crate::backend::Backend;

fn tiny() -> HeitzNeyretConfig {
    HeitzNeyretConfig {
        scenes: vec![
            SceneCase::new("builtin:bumpy-sphere?subdiv=3", "bumpy", true, true),
            SceneCase::new("builtin:forest?trees=1&leaves=50", "forest", false, false),
        ],
        resolution: 16,
        image_size: 16,
        zooms: vec![1.0, 4.0],
        spp: 4,
        rays: 8,
        repeats: 1,
        depth_of_field: true,
    }
}

#[test]
fn a_tiny_run_measures_every_method_at_every_zoom() {
    let result = run(&tiny(), Backend::Cpu, &|_| {}).unwrap();
    assert_eq!(result.scenes.len(), 2);
    let s = &result.scenes[0];
    assert_eq!(s.zooms.len(), 2);
    for z in &s.zooms {
        assert_eq!(z.rows.len(), Method::ALL.len());
        for r in &z.rows {
            assert!(r.ssim > 0.0 && r.ssim <= 1.0 && r.mse >= 0.0, "{r:?}");
            assert!(r.elements_per_pixel > 0.0 && r.cpu.min_ms <= r.cpu.max_ms);
            assert!(r.gpu.is_none());
        }
        // Radial scene: grazing bins with every method's colour.
        assert!(z.grazing.iter().all(|b| b.method_rgb.len() == Method::ALL.len()));
    }
    assert!(s.zooms[0].grazing.iter().any(|b| b.pixels > 0));
    assert!(result.scenes[1].zooms[0].grazing.is_empty());
    assert!(!result.scenes[1].case.in_domain);
    assert_eq!(s.representations[0].payload_bytes_per_node, 88);
    // Depth of field on the first in-domain scene only.
    let dof = result.depth_of_field.as_ref().unwrap();
    assert_eq!(dof.scene, "bumpy");
    assert!(dof.masks_coverage_ratio > 0.0 && dof.blending_coverage_ratio > 0.0);
    // Tables and report sections build; the JSON names its fields.
    assert_eq!(result.tables().unwrap().len(), 3);
    let mut report = voxlod_eval::report::Report::new("test");
    result.add_to_report(&mut report).unwrap();
    let json = serde_json::to_string(&result).unwrap();
    assert!(json.contains("\"silhouette_thickness_px\"") && json.contains("\"masks_mean_colour\""));
}

#[test]
fn bad_configurations_name_the_field() {
    let err = |c: HeitzNeyretConfig| c.validate().unwrap_err().to_string();
    assert!(err(HeitzNeyretConfig { scenes: vec![], ..tiny() }).contains("scenes"));
    assert!(err(HeitzNeyretConfig { resolution: 12, ..tiny() }).contains("resolution"));
    assert!(err(HeitzNeyretConfig { image_size: 4, ..tiny() }).contains("image_size"));
    assert!(err(HeitzNeyretConfig { zooms: vec![f32::NAN], ..tiny() }).contains("zooms"));
    assert!(err(HeitzNeyretConfig { zooms: vec![], ..tiny() }).contains("zooms"));
    assert!(err(HeitzNeyretConfig { spp: 0, ..tiny() }).contains("spp"));
    assert!(err(HeitzNeyretConfig { rays: 0, ..tiny() }).contains("rays"));
    assert!(err(HeitzNeyretConfig { repeats: 0, ..tiny() }).contains("repeats"));
    HeitzNeyretConfig::quick().validate().unwrap();
    HeitzNeyretConfig::full().validate().unwrap();
}
