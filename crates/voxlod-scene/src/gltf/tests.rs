//! Tests of the glTF loader on small documents built in memory (buffers as data URIs or
//! resolver files).

use std::path::Path;

use glam::{Vec2, Vec3};

use super::*;
use crate::{AlphaMode, WrapMode};

fn b64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = c.iter().enumerate().fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
        for k in 0..=c.len() {
            s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
        }
    }
    s
}

/// Little-endian bytes of f32s and u16s, each part padded to 4 bytes.
fn bin(floats: &[f32], shorts: &[u16]) -> Vec<u8> {
    let mut b: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    b.extend(shorts.iter().flat_map(|s| s.to_le_bytes()));
    b.resize(b.len().next_multiple_of(4), 0);
    b
}

fn no_files(p: &Path) -> io::Result<Vec<u8>> {
    Err(io::Error::new(io::ErrorKind::NotFound, format!("{} not found", p.display())))
}

fn load_json(json: &str) -> Result<(Scene, LoadReport)> {
    load_from_bytes(Path::new("mem/t.gltf"), json.as_bytes(), no_files)
}

fn err_of(json: &str) -> String {
    match load_json(json) {
        Ok(_) => "loaded".into(),
        Err(e) => e.to_string(),
    }
}

const TRI: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// One triangle (positions at offset 0, normals +z at 36) under `nodes`; `mesh_extra` goes
/// into the primitive, `root_extra` into the root object.
fn doc(nodes: &str, prim_extra: &str, root_extra: &str) -> String {
    let data = bin(&[&TRI[..], &[0.0, 0.0, 1.0].repeat(3)].concat(), &[]);
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": {nodes},
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}} {prim_extra}}}]}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}},
          {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 72}}],
        "buffers": [{{"byteLength": 72, "uri": "data:application/octet-stream;base64,{}"}}]
        {root_extra}}}"#,
        b64(&data)
    )
}

#[test]
fn hierarchy_transforms_positions_normals_and_winding() {
    // Root translates by (10, 0, 0); child mirrors x and stretches y by 2.
    let nodes =
        r#"[{"translation": [10, 0, 0], "children": [1]}, {"mesh": 0, "scale": [-1, 2, 1]}]"#;
    let (scene, report) = load_json(&doc(nodes, "", "")).unwrap();
    let m = &scene.meshes[0];
    // A 1 × 2 triangle at x = 9..10 is far from the origin for its size: re-centred on x = 10.
    assert_eq!(scene.origin, glam::DVec3::new(10.0, 0.0, 0.0));
    assert_eq!(
        m.positions.iter().map(|&p| scene.to_world(p).as_vec3()).collect::<Vec<_>>(),
        vec![Vec3::new(10.0, 0.0, 0.0), Vec3::new(9.0, 0.0, 0.0), Vec3::new(10.0, 2.0, 0.0)]
    );
    // Mirrored: the winding is flipped so the geometric normal still agrees with the normal.
    let [a, b, c] = m.triangle(0);
    assert!((b - a).cross(c - a).z > 0.0);
    assert!(m.normals.iter().all(|&n| (n - Vec3::Z).length() < 1e-6));
    assert_eq!(report.normals_computed, 0);
    assert_eq!(scene.nodes[1].parent, Some(0));
    // Node matrices are in the same local frame as the meshes.
    assert_eq!(scene.nodes[1].world.w_axis.x, 0.0);
    assert_eq!(scene.nodes[0].local, scene.nodes[0].world);
    assert_eq!(scene.materials[m.material].base_color, glam::Vec4::ONE, "glTF default material");
}

#[test]
fn normals_use_the_inverse_transpose() {
    // A triangle in the plane x + y = 0 with its normal, under a non-uniform scale of x by 3:
    // transforming the normal like a position would tilt it off the surface.
    let nodes = r#"[{"mesh": 0, "matrix": [3,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}]"#;
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let slanted = bin(
        &[&[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, -1.0, 0.0][..], &[h, h, 0.0].repeat(3)].concat(),
        &[],
    );
    let json = doc(nodes, "", "")
        .replace(&b64(&bin(&[&TRI[..], &[0.0, 0.0, 1.0].repeat(3)].concat(), &[])), &b64(&slanted));
    let (scene, _) = load_json(&json).unwrap();
    let m = &scene.meshes[0];
    let [a, b, c] = m.triangle(0);
    let face = (b - a).cross(c - a).normalize();
    assert!((m.normals[0].dot(face).abs() - 1.0).abs() < 1e-5, "{} vs {face}", m.normals[0]);
}

#[test]
fn strips_fans_points_and_lines() {
    // Four vertices of a unit square in strip order, drawn four ways by four meshes.
    let quad = bin(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0], &[]);
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "nodes": [{{"mesh": 0}}, {{"mesh": 1}}, {{"mesh": 2}}, {{"mesh": 3}}],
        "meshes": [
          {{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": 5}}]}},
          {{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": 6}}]}},
          {{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": 0}}]}},
          {{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": 3}}]}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 48}}],
        "buffers": [{{"byteLength": 48, "uri": "data:;base64,{}"}}]}}"#,
        b64(&quad)
    );
    let (scene, report) = load_json(&json).unwrap();
    assert_eq!(scene.meshes.len(), 2);
    // Strip 0,1,2 / 1,3,2 (odd triangle swapped); fan 1,2,0 / 2,3,0.
    assert_eq!(scene.meshes[0].indices, vec![[0, 1, 2], [1, 3, 2]]);
    assert_eq!(scene.meshes[1].indices, vec![[1, 2, 0], [2, 3, 0]]);
    assert_eq!(
        (report.points_skipped, report.lines_skipped, report.strips_and_fans_converted),
        (1, 1, 2)
    );
    assert_eq!(report.normals_computed, 8);
    assert!(scene.meshes[0].normals.iter().all(|&n| n == Vec3::Z));
}

#[test]
fn textured_material_with_sampler_transform_and_texcoord_set() {
    let png = crate::Srgb8Image { width: 2, height: 1, pixels: vec![[255, 0, 0], [0, 0, 255]] }
        .encode_png()
        .unwrap();
    let uv = bin(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0], &[]);
    let material = r#", "materials": [{"name": "m", "doubleSided": true, "alphaMode": "MASK", "alphaCutoff": 0.25,
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "baseColorTexture": {"index": 0, "texCoord": 1,
          "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [2, 2]}}}}}],
      "textures": [{"source": 0, "sampler": 0}], "samplers": [{"wrapS": 33071, "wrapT": 33648}],
      "images": [{"uri": "tex.png"}]"#;
    let with_uv = doc(r#"[{"mesh": 0}]"#, r#", "material": 0"#, material)
        .replace(r#""NORMAL": 1}"#, r#""NORMAL": 1, "TEXCOORD_1": 2}"#)
        .replace(r#""type": "VEC3"}],"#, r#""type": "VEC3"}, {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],"#)
        .replace(r#"[{"buffer": 0, "byteLength": 72}]"#, r#"[{"buffer": 0, "byteLength": 72}, {"buffer": 1, "byteLength": 24}]"#)
        .replace(r#"}]
        "#, r#"}, {"byteLength": 24, "uri": "uv.bin"}]
        "#);
    let files = |p: &Path| match p.to_str() {
        Some("mem/tex.png") => Ok(png.clone()),
        Some("mem/uv.bin") => Ok(uv.clone()),
        _ => no_files(p),
    };
    let (scene, _) = load_from_bytes(Path::new("mem/t.gltf"), with_uv.as_bytes(), files).unwrap();
    let m = &scene.meshes[0];
    assert_eq!(m.uvs, vec![Vec2::new(0.5, 0.0), Vec2::new(2.5, 0.0), Vec2::new(0.5, 2.0)]);
    let mat = &scene.materials[m.material];
    assert_eq!(
        (mat.name.as_str(), mat.double_sided, mat.alpha_mode),
        ("m", true, AlphaMode::Mask { cutoff: 0.25 })
    );
    let tex = &scene.textures[mat.base_color_texture.unwrap().texture];
    assert_eq!((tex.width, tex.height, tex.srgb), (2, 1, true));
    assert_eq!(
        (tex.sampler.wrap_u, tex.sampler.wrap_v),
        (WrapMode::ClampToEdge, WrapMode::MirroredRepeat)
    );
    // Without TEXCOORD_1 the texture cannot be mapped: an error, not a silently blank texture.
    let without = with_uv.replace(r#", "TEXCOORD_1": 2"#, r#", "TEXCOORD_0": 2"#);
    let e = load_from_bytes(Path::new("mem/t.gltf"), without.as_bytes(), files)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("meshes[0].primitives[0]: its material's baseColorTexture reads TEXCOORD_1"),
        "{e}"
    );
    let broken = with_uv.replace("tex.png", "gone.png");
    let e = load_from_bytes(Path::new("mem/t.gltf"), broken.as_bytes(), files)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("images[0]: cannot read mem/gone.png"), "{e}");
}

#[test]
fn skin_rest_pose_animation_and_camera() {
    // Joint node 1 at (0, 1, 0) with inverse bind matrix translate(0, -1, 0): the rest pose is
    // the bind pose. All weight on joint 0. A camera on node 2 looks down −z from z = 5.
    let ibm = [1.0, 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., -1., 0., 1.];
    let joints = [0u16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    let data = bin(
        &[
            &TRI[..],
            &[0.0, 0.0, 1.0].repeat(3),
            &[1.0, 0.0, 0.0, 0.0].repeat(3),
            &ibm,
            &[0.0, 1.0],
            &[
                0.0,
                0.0,
                0.0,
                1.0,
                0.0,
                0.0,
                std::f32::consts::FRAC_1_SQRT_2,
                std::f32::consts::FRAC_1_SQRT_2,
            ],
        ]
        .concat(),
        &joints,
    );
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0, 1, 2]}}],
        "nodes": [{{"mesh": 0, "skin": 0, "translation": [100, 0, 0]}}, {{"translation": [0, 1, 0]}}, {{"camera": 0, "translation": [0, 0, 5]}}],
        "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.7, "znear": 0.1}}}}],
        "skins": [{{"joints": [1], "inverseBindMatrices": 3}}],
        "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 1, "path": "rotation"}}}}],
                         "samplers": [{{"input": 4, "output": 5}}]}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "WEIGHTS_0": 2, "JOINTS_0": 6}}}}]}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}},
          {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"}},
          {{"bufferView": 0, "byteOffset": 72, "componentType": 5126, "count": 3, "type": "VEC4"}},
          {{"bufferView": 0, "byteOffset": 120, "componentType": 5126, "count": 1, "type": "MAT4"}},
          {{"bufferView": 0, "byteOffset": 184, "componentType": 5126, "count": 2, "type": "SCALAR"}},
          {{"bufferView": 0, "byteOffset": 192, "componentType": 5126, "count": 2, "type": "VEC4"}},
          {{"bufferView": 0, "byteOffset": 224, "componentType": 5123, "count": 3, "type": "VEC4"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 248}}],
        "buffers": [{{"byteLength": 248, "uri": "data:;base64,{}"}}]}}"#,
        b64(&data)
    );
    let (scene, _) = load_json(&json).unwrap();
    let m = &scene.meshes[0];
    assert_eq!(m.positions[1], Vec3::X, "skinned: the node's own translation is ignored");
    let binding = m.skin.as_ref().unwrap();
    assert_eq!(
        (binding.skin, binding.joints[0], binding.weights[0]),
        (0, [0; 4], [1.0, 0.0, 0.0, 0.0])
    );
    assert_eq!(scene.skins[0].joints, vec![1]);
    let ch = &scene.animations[0].channels[0];
    assert_eq!((ch.node, ch.times.as_slice(), ch.values.len()), (1, &[0.0, 1.0][..], 8));
    let cam = scene.camera.unwrap();
    assert_eq!((cam.eye, cam.target), (Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, 4.0)));
    assert!((cam.fov_y_deg - 0.7f32.to_degrees()).abs() < 1e-4);
    // A joint index beyond the skin's joints is an error naming the JOINTS_0 accessor.
    let bad = json.replace(
        &b64(&data),
        &b64(&{
            let mut d = data.clone();
            d[224] = 5;
            d
        }),
    );
    let e = err_of(&bad);
    assert!(
        e.contains("accessors[6]: element 0: joint 5 does not exist in skins[0] (1 joints)"),
        "{e}"
    );
}

#[test]
fn morph_targets_sparse_accessors_and_empty_scenes() {
    // Target 0 moves vertex 2 by +1 in z through a sparse accessor without a bufferView
    // (index u16 2 at byte 72, value (0,0,1) at byte 76); the mesh's default weight is 0.5.
    let data = bin(&[&TRI[..], &[0.0, 0.0, 1.0].repeat(3), &[0.0], &[0.0, 0.0, 1.0]].concat(), &[]);
    let mut data = data;
    data[72..74].copy_from_slice(&2u16.to_le_bytes());
    let json = doc(r#"[{"mesh": 0}]"#, r#", "targets": [{"POSITION": 2}]"#, "")
        .replace(r#""primitives": ["#, r#""weights": [0.5], "primitives": ["#)
        .replace(r#""type": "VEC3"}],"#, r#""type": "VEC3"}, {"componentType": 5126, "count": 3, "type": "VEC3",
            "sparse": {"count": 1, "indices": {"bufferView": 0, "byteOffset": 72, "componentType": 5123},
                       "values": {"bufferView": 0, "byteOffset": 76}}}],"#)
        .replace("\"byteLength\": 72", "\"byteLength\": 88")
        .replace(&b64(&bin(&[&TRI[..], &[0.0, 0.0, 1.0].repeat(3)].concat(), &[])), &b64(&data));
    let (scene, report) = load_json(&json).unwrap();
    assert_eq!(scene.meshes[0].positions[2], Vec3::new(0.0, 1.0, 0.5));
    assert_eq!(report.morph_targets_applied, 1);
    // An empty scene, or no scene and no nodes: nothing to load is an error naming the file.
    let e = err_of(r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}]}"#);
    assert!(e.contains("mem/t.gltf: scenes[0]: no triangles to load"), "{e}");
    let e = err_of(r#"{"asset": {"version": "2.0"}}"#);
    assert!(e.contains("mem/t.gltf: nodes: no triangles"), "{e}");
}

mod errors;
