//! Tests of the public surface across scenes: every builtin through the registry (valid,
//! deterministic, seed-sensitive, framed by its camera), the spec syntax and its errors, and the
//! listed parameter defaults against the parameter structs' `Default`.

use super::registry::{blinds_params, city_params, crowd_params, forest_params, island_params};
use super::testutil::scene_hash;
use super::*;
use crate::Scene;

/// Small versions of the builtins, cheap enough to build several times.
const SMALL: &[&str] = &[
    "forest?trees=2&leaves=200",
    "island?terrain=24&grass=500&rocks=2",
    "blinds?slats=16",
    "city?blocks=1&max_floors=4",
    "crowd?walkers=2&rigid=2&sides=8",
    "bumpy-sphere?subdiv=2",
    "bumpy-specular?subdiv=2",
    "cornell",
    "cube",
    "sphere?subdiv=1",
];

fn assert_in_view(spec: &str, scene: &Scene) {
    // The camera sees the middle of the scene's bounds, from outside them.
    let cam = scene.default_camera().unwrap();
    cam.validate().unwrap();
    let (lo, hi) = scene.bounds().unwrap();
    let frame = cam.frame(64, 64);
    let (px, depth) = frame.project((lo + hi) * 0.5).expect(spec);
    assert!(depth > 0.0 && px.cmpge(glam::Vec2::ZERO).all() && px.x < 64.0 && px.y < 64.0);
    assert!(scene.light().validated().is_ok(), "{spec}");
}

#[test]
fn every_builtin_builds_valid_deterministic_scenes() {
    assert_eq!(builtin_names().len(), SMALL.len());
    for (name, description) in builtin_names() {
        assert!(!description.is_empty());
        let spec = SMALL.iter().find(|s| s.split('?').next() == Some(name)).unwrap();
        let a = from_spec(spec).unwrap();
        a.validate().unwrap();
        assert!(a.triangle_count() > 0, "{spec}");
        assert_eq!(scene_hash(&a), scene_hash(&from_spec(spec).unwrap()), "{spec}");
        assert_in_view(spec, &a);
        // Seeded scenes change with the seed.
        if builtin_params(name).unwrap().iter().any(|p| p.name == "seed") {
            let b = from_spec(&format!("{spec}&seed=99")).unwrap();
            assert_ne!(scene_hash(&a), scene_hash(&b), "{spec}");
        }
    }
}

#[test]
fn default_scenes_validate_and_have_the_documented_counts() {
    for (name, count) in [
        ("forest", 294_776),
        ("city", 164_184),
        ("blinds", 1_554),
        ("crowd", 60_898),
        ("cornell", 34),
        ("cube", 12),
    ] {
        let s = builtin(name, &[]).unwrap();
        s.validate().unwrap();
        assert_eq!(s.triangle_count(), count, "{name}");
    }
    let s = builtin("island", &[]).unwrap();
    s.validate().unwrap();
    // Grass and rocks are exact; the terrain keeps only quads above the sea floor's margin.
    assert!((138_000..146_000).contains(&s.triangle_count()), "{}", s.triangle_count());
    assert_eq!(builtin("sphere", &[]).unwrap().triangle_count(), 1_280);
}

#[test]
fn listed_defaults_are_the_struct_defaults() {
    let pairs = |name: &str| -> Vec<(&'static str, &'static str)> {
        let params = builtin_params(name).unwrap();
        params.iter().filter_map(|p| p.default.map(|d| (p.name, d))).collect()
    };
    for (k, v) in pairs("forest") {
        assert_eq!(forest_params(&[(k, v)]).unwrap(), ForestParams::default(), "{k}={v}");
    }
    for (k, v) in pairs("island") {
        assert_eq!(island_params(&[(k, v)]).unwrap(), IslandParams::default(), "{k}={v}");
    }
    for (k, v) in pairs("blinds") {
        assert_eq!(blinds_params(&[(k, v)]).unwrap(), BlindsParams::default(), "{k}={v}");
    }
    for (k, v) in pairs("city") {
        assert_eq!(city_params(&[(k, v)]).unwrap(), CityParams::default(), "{k}={v}");
    }
    for (k, v) in pairs("crowd") {
        assert_eq!(crowd_params(&[(k, v)]).unwrap(), CrowdParams::default(), "{k}={v}");
    }
    // (So every listed key with a default is accepted; `triangles` is tested below.)
}

#[test]
fn spec_parsing() {
    assert_eq!(parse_spec("forest").unwrap(), ("forest", vec![]));
    assert_eq!(parse_spec(" forest? ").unwrap(), ("forest", vec![]));
    assert_eq!(
        parse_spec("forest?trees=20&seed = 3").unwrap(),
        ("forest", vec![("trees", "20"), ("seed", "3")])
    );
    for bad in ["", "?trees=2", "forest?trees", "forest?=3", "forest?trees=2&&seed=1"] {
        let e = parse_spec(bad).unwrap_err().to_string();
        assert!(e.contains("scene spec"), "{bad}: {e}");
    }
    let s = from_spec("forest?trees=2&leaves=10&seed=3&alpha=false").unwrap();
    assert!(s.textures.is_empty());
    assert_eq!(
        s.triangle_count() as u64,
        forest_params(&[("trees", "2"), ("leaves", "10")]).unwrap().triangle_count()
    );
}

#[test]
fn bad_specs_say_what_is_valid() {
    let err = |spec: &str| from_spec(spec).unwrap_err().to_string();
    let e = err("jungle?trees=3");
    assert!(e.contains("jungle") && e.contains("forest, island, city, blinds"), "{e}");
    let e = err("forest?tress=3");
    assert!(e.contains("forest.tress") && e.contains("trees, leaves"), "{e}");
    let e = err("cube?size=2");
    assert!(e.contains("cube.size") && e.contains("takes: subdivide, subdivision"), "{e}");
    let e = err("forest?trees=2&trees=3");
    assert!(e.contains("forest.trees") && e.contains("more than once"), "{e}");
    let e = err("forest?trees=0");
    assert!(e.contains("forest.trees") && e.contains("1..=100000"), "{e}");
    let e = err("forest?trees=many");
    assert!(e.contains("forest.trees") && e.contains("integer"), "{e}");
    let e = err("forest?extent=nan");
    assert!(e.contains("forest.extent") && e.contains("[0.001, 1000000]"), "{e}");
    let e = err("forest?alpha=maybe");
    assert!(e.contains("forest.alpha") && e.contains("true or false"), "{e}");
    let e = err("forest?triangles=50000&trees=3");
    assert!(e.contains("forest.triangles") && e.contains("either"), "{e}");
    let e = err("island?blade_width=0");
    assert!(e.contains("island.blade_width") && e.contains("(0, 0.25]"), "{e}");
    let e = err("sphere?subdiv=8");
    assert!(e.contains("sphere.subdiv") && e.contains("0..=7"), "{e}");
    let e = err("forest?trees=100000&leaves=1000000");
    assert!(e.contains("forest.triangles") && e.contains("GiB"), "{e}");
}

#[test]
fn target_triangles_through_the_spec() {
    let s = from_spec("forest?triangles=30000&seed=5").unwrap();
    let n = s.triangle_count();
    assert!((30_000..30_100).contains(&n), "{n}");
    // The ground still spans the (grown or shrunk) extent, centred at the origin.
    let (lo, hi) = s.bounds().unwrap();
    assert!((lo.x + hi.x).abs() < 0.1 * (hi.x - lo.x) && lo.y < 0.0 && hi.y > 1.0, "{lo} {hi}");
}

#[test]
fn every_builtin_takes_the_subdivision_parameters() {
    let a = from_spec("sphere?subdiv=1&subdivide=2").unwrap();
    assert_eq!(a.triangle_count(), 80 * 16);
    let b = from_spec("sphere?subdivide=2&subdiv=1&subdivision=midpoint").unwrap();
    assert_eq!(a, b);
    let c = from_spec("sphere?subdiv=1&subdivide=2&subdivision=loop").unwrap();
    assert_eq!(c.triangle_count(), 80 * 16);
    assert_ne!(a, c);
    c.validate().unwrap();
    let e = from_spec("forest?trees=2&subdivision=loop").unwrap_err().to_string();
    assert!(e.contains("forest.subdivision") && e.contains("needs subdivide"), "{e}");
    let e = from_spec("forest?trees=2&leaves=200&subdivide=9").unwrap_err().to_string();
    assert!(e.contains("forest.subdivide") && e.contains("0..=8"), "{e}");
}
