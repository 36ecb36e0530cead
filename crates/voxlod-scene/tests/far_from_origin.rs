//! The same model written at offsets 0, 10⁴, 10⁶ and 10⁷ (OBJ text with the offset added in
//! `f64`; glTF with the offset in a root node's translation) loads to the same local scene: the
//! loaders read in `f64` and re-centre, and the offset lands in `Scene::origin`.

use std::io;
use std::path::Path;

use glam::{DVec3, Vec3};
use voxlod_scene::{Scene, gltf, obj};

/// Offsets per axis: a different sign and magnitude on each axis.
fn offsets() -> [DVec3; 4] {
    [0.0, 1e4, 1e6, 1e7].map(|d| DVec3::new(d, -d, 0.5 * d))
}

fn no_files(p: &Path) -> io::Result<Vec<u8>> {
    Err(io::Error::new(io::ErrorKind::NotFound, format!("{} is not here", p.display())))
}

/// A closed latitude-longitude sphere of radius ≈ 1 around (0.1, 0.3, -0.2): vertices and
/// triangles. With `decimal`, coordinates have six decimals as exporters write them (not
/// representable in binary); without, they are multiples of 2⁻¹⁰.
fn sphere(decimal: bool) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let (rings, segments) = (6u32, 9u32);
    let round = |x: f64| {
        if decimal { (x * 1e6).round() / 1e6 } else { (x * 1024.0).round() / 1024.0 }
    };
    let centre = DVec3::new(0.1, 0.3, -0.2);
    let mut v = vec![centre + DVec3::Y, centre - DVec3::Y];
    for r in 1..rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..segments {
            let phi = std::f64::consts::TAU * s as f64 / segments as f64;
            let p = centre
                + DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
                    * (1.0 + 0.013 * s as f64);
            v.push(p);
        }
    }
    let v: Vec<DVec3> =
        v.into_iter().map(|p| DVec3::new(round(p.x), round(p.y), round(p.z))).collect();
    let at = |r: u32, s: u32| 2 + (r - 1) * segments + s % segments;
    let mut t = Vec::new();
    for s in 0..segments {
        t.push([0, at(1, s + 1), at(1, s)]);
        t.push([1, at(rings - 1, s), at(rings - 1, s + 1)]);
        for r in 1..rings - 1 {
            t.push([at(r, s), at(r, s + 1), at(r + 1, s)]);
            t.push([at(r, s + 1), at(r + 1, s + 1), at(r + 1, s)]);
        }
    }
    (v, t)
}

/// OBJ text of `sphere` with `offset` added to every coordinate in `f64`, printed with the
/// shortest decimal that reads back to the same `f64`.
fn obj_text(decimal: bool, offset: DVec3) -> String {
    let (v, t) = sphere(decimal);
    let mut s = String::new();
    for p in v {
        let p = p + offset;
        s += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for [a, b, c] in t {
        s += &format!("f {} {} {}\n", a + 1, b + 1, c + 1);
    }
    s
}

fn load_obj(decimal: bool, offset: DVec3) -> Scene {
    obj::load_from_str(Path::new("far.obj"), &obj_text(decimal, offset), no_files)
        .unwrap_or_else(|e| panic!("offset {offset}: {e}"))
        .0
}

/// Units in the last place of `x` in `f32`.
fn ulp(x: f32) -> f32 {
    let a = x.abs();
    f32::from_bits(a.to_bits() + 1) - a
}

/// Largest difference between two position lists in units of the first's `f32` spacing.
fn max_ulps(a: &[Vec3], b: &[Vec3]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs() / ulp(p[k])))
        .fold(0.0, f32::max)
}

#[test]
fn obj_far_from_the_origin_loads_to_the_same_local_scene() {
    let at_zero = [load_obj(false, DVec3::ZERO), load_obj(true, DVec3::ZERO)];
    for (s, decimal) in at_zero.iter().zip([false, true]) {
        assert_eq!(s.origin, DVec3::ZERO, "a model around the world origin keeps it");
        // Every vertex is the file's (tobj orders them by first use).
        let (v, _) = sphere(decimal);
        for p in &s.meshes[0].positions {
            assert!(v.iter().any(|w| (w.as_vec3() - *p).abs().max_element() == 0.0), "{p}");
        }
    }
    for offset in offsets() {
        let [dyadic, decimal] = [false, true].map(|d| load_obj(d, offset));
        for (s, zero) in [&dyadic, &decimal].into_iter().zip(&at_zero) {
            // The offset moves into the origin exactly.
            assert_eq!(s.origin, offset);
            assert_eq!(s.meshes[0].indices, zero.meshes[0].indices);
            for (n, m) in s.meshes[0].normals.iter().zip(&zero.meshes[0].normals) {
                assert!((*n - *m).length() < 1e-6, "offset {offset}: normal {n} vs {m}");
            }
        }
        // Coordinates the file holds exactly at every offset load bit-identical.
        assert_eq!(dyadic.meshes[0].positions, at_zero[0].meshes[0].positions, "offset {offset}");
        // Decimal coordinates: the file at 10⁷ resolves 2⁻²⁹ only, so a coordinate may round to
        // the neighbouring f32; never further.
        let ulps = max_ulps(&at_zero[1].meshes[0].positions, &decimal.meshes[0].positions);
        assert!(ulps <= 1.0, "offset {offset}: {ulps} units in the last place");
        // And world positions are the offset ones to within the f32 spacing of the local ones.
        for (p, q) in decimal.meshes[0].positions.iter().zip(&at_zero[1].meshes[0].positions) {
            let err = (decimal.to_world(*p) - offset - q.as_dvec3()).abs().max_element();
            assert!(err <= 1.2e-7, "offset {offset}: {p} is {err} from {q}");
        }
    }
}

#[test]
fn without_recentring_far_vertices_would_collapse() {
    // The control: the same file converted to f32 in world coordinates (what a loader without
    // re-centring stores) merges vertices at 10⁷, where f32's spacing is 1.
    let (v, _) = sphere(true);
    let far: Vec<Vec3> = v.iter().map(|p| (*p + DVec3::splat(1e7)).as_vec3()).collect();
    let distinct = |ps: &[Vec3]| {
        let mut k: Vec<[u32; 3]> = ps.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
        k.sort_unstable();
        k.dedup();
        k.len()
    };
    assert!(distinct(&far) < v.len() / 2, "{} of {} distinct", distinct(&far), v.len());
    let scene = load_obj(true, DVec3::splat(1e7));
    assert_eq!(distinct(&scene.meshes[0].positions), v.len());
}

/// Little-endian bytes of `f32`s.
fn le(floats: &[f32]) -> Vec<u8> {
    floats.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// The dyadic sphere as a glTF primitive under a root node translated by `translation` (written
/// as JSON digits), rotated by a child node (45° about y, scale 2), with a camera node and an
/// animation that moves the root from `translation` to `translation` + (1, 0, 0).
fn gltf_text(translation: [f64; 3]) -> String {
    let (v, t) = sphere(false);
    let positions: Vec<f32> = v.iter().flat_map(|p| p.as_vec3().to_array()).collect();
    let indices: Vec<u8> = t.iter().flatten().flat_map(|&i| (i as u16).to_le_bytes()).collect();
    let mut data = le(&positions);
    let idx_at = data.len();
    data.extend(&indices);
    data.resize(data.len().next_multiple_of(4), 0);
    let times_at = data.len();
    data.extend(le(&[0.0, 1.0]));
    let moves_at = data.len();
    let tr = translation.map(|x| x as f32);
    data.extend(le(&[tr[0], tr[1], tr[2], tr[0] + 1.0, tr[1], tr[2]]));
    let [x, y, z] = translation;
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [
          {{"translation": [{x}, {y}, {z}], "children": [1, 2]}},
          {{"mesh": 0, "rotation": [0, 0.3826834323650898, 0, 0.9238795325112867], "scale": [2, 2, 2]}},
          {{"camera": 0, "translation": [0.5, 1, 6]}}],
        "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.7, "znear": 0.1}}}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
        "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 0, "path": "translation"}}}}],
          "samplers": [{{"input": 2, "output": 3}}]}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": {nv}, "type": "VEC3"}},
          {{"bufferView": 0, "byteOffset": {idx_at}, "componentType": 5123, "count": {ni}, "type": "SCALAR"}},
          {{"bufferView": 0, "byteOffset": {times_at}, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]}},
          {{"bufferView": 0, "byteOffset": {moves_at}, "componentType": 5126, "count": 2, "type": "VEC3"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": {len}}}],
        "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{b64}"}}]}}"#,
        nv = v.len(),
        ni = t.len() * 3,
        len = data.len(),
        b64 = base64::encode(&data),
    )
}

fn load_gltf(translation: [f64; 3]) -> Scene {
    gltf::load_from_bytes(Path::new("far.gltf"), gltf_text(translation).as_bytes(), no_files)
        .unwrap_or_else(|e| panic!("translation {translation:?}: {e}"))
        .0
}

#[test]
fn gltf_node_translations_far_from_the_origin_compose_in_f64() {
    let zero = load_gltf([0.0; 3]);
    assert_eq!(zero.origin, DVec3::ZERO);
    let cam0 = zero.camera.expect("the camera node");
    for offset in offsets() {
        let far = load_gltf(offset.to_array());
        assert_eq!(far.origin, offset);
        let ulps = max_ulps(&zero.meshes[0].positions, &far.meshes[0].positions);
        assert!(ulps <= 1.0, "offset {offset}: {ulps} units in the last place");
        let cam = far.camera.expect("the camera node");
        assert!((cam.eye - cam0.eye).length() < 1e-6, "offset {offset}: eye {}", cam.eye);
        assert!((far.to_world(cam.eye) - offset - cam0.eye.as_dvec3()).length() < 1e-6);
        // Node matrices share the meshes' local frame, at rest and when the animation poses
        // the root (its translation keys moved by the origin too).
        for (n, m) in far.nodes.iter().zip(&zero.nodes) {
            assert!(n.world.abs_diff_eq(m.world, 1e-6), "offset {offset}: {}", n.name);
        }
        let pose = far.animations[0].pose(&far.nodes, 0.0).unwrap();
        assert!(pose.world[1].abs_diff_eq(far.nodes[1].world, 1e-6), "offset {offset}");
        let moved = far.animations[0].pose(&far.nodes, 1.0).unwrap();
        let step = moved.world[1].w_axis.truncate() - far.nodes[1].world.w_axis.truncate();
        assert!((step - Vec3::X).length() < 1e-6, "offset {offset}: the key moves by {step}");
    }
    // Digits past f32's: a root at 10⁷ + 0.3 (f32 holds 10⁷) keeps its 0.3.
    let d = DVec3::new(1e7 + 0.3, 0.0, 0.0);
    let far = load_gltf(d.to_array());
    for (p, q) in far.meshes[0].positions.iter().zip(&zero.meshes[0].positions) {
        let err = (far.to_world(*p) - d - q.as_dvec3()).abs().max_element();
        assert!(err < 1e-6, "{p} vs {q}: {err}");
    }
}
