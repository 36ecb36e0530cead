//! Malformed glTF input: every case is an error naming the file and the element.

use std::path::Path;

use glam::Vec3;

use super::*;

#[test]
fn structural_errors_name_file_and_element() {
    let cases: [(String, &str); 12] = [
        (
            doc(r#"[{"mesh": 0, "children": [1]}, {"children": [2]}, {"children": [0]}]"#, "", ""),
            "nodes[0]: the node graph has a cycle: nodes[1] → nodes[2] → nodes[0] → nodes[1]",
        ),
        (doc(r#"[{"mesh": 0, "children": [0]}]"#, "", ""), "nodes[0]: is its own child"),
        (
            doc(r#"[{"mesh": 0, "children": [2]}, {"children": [2]}, {}]"#, "", ""),
            "nodes[2]: has two parents, nodes[0] and nodes[1]",
        ),
        (
            doc(r#"[{"mesh": 0, "children": [7]}]"#, "", ""),
            "nodes[0].children[0]: refers to an element that does not exist",
        ),
        (
            doc(r#"[{"mesh": 0}]"#, r#", "indices": 5"#, ""),
            "meshes[0].primitives[0].indices: refers to an element",
        ),
        (
            doc(r#"[{"mesh": 0}]"#, "", "").replace(r#""POSITION": 0"#, r#""POSITION": 9"#),
            r#"meshes[0].primitives[0].attributes["POSITION"]: accessor 9 does not exist"#,
        ),
        (doc(r#"[{"mesh": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0]}]"#, "", ""), "nodes[0]"),
        (doc(r#"[{"mesh": "zero"}]"#, "", ""), "t.gltf: nodes[0]: invalid type"),
        (
            doc(r#"[{"mesh": 0}]"#, "", "").replace("\"scene\": 0", "\"scene\": \"hello\""),
            "t.gltf: scene: invalid type",
        ),
        (
            doc(r#"[{"mesh": 0}]"#, "", "").replace("2.0", "1.0"),
            "asset.version: glTF 1.0 is not supported",
        ),
        (
            "{\"asset\": {\"version\": \"2.0\"},\n \"nodes\": [}".to_owned(),
            "t.gltf: JSON: expected value at line 2 column 12",
        ),
        (
            doc(
                r#"[{"mesh": 0}]"#,
                "",
                r#", "extensionsRequired": ["KHR_draco_mesh_compression"]"#,
            ),
            "extensionsRequired[0] = \"KHR_draco_mesh_compression\": extension not supported",
        ),
    ];
    for (json, expect) in cases {
        let e = err_of(&json);
        assert!(
            e.starts_with("mem/t.gltf: ") && e.contains(expect),
            "expected {expect:?}, got {e:?}"
        );
    }
}

#[test]
fn data_errors_name_buffer_view_and_accessor() {
    let base = doc(r#"[{"mesh": 0}]"#, "", "");
    let cases = [
        (
            base.replace(r#""count": 3, "type": "VEC3"},"#, r#""count": 7, "type": "VEC3"},"#),
            "accessors[0]: 7 elements of 12 bytes (stride 12) from offset 0 run past the end of bufferViews[0] (72 bytes)",
        ),
        (
            base.replace(r#""count": 3, "type": "VEC3"},"#, r#""count": 3, "type": "VEC2"},"#),
            "accessors[0]: POSITION of meshes[0].primitives[0] must be VEC3, is VEC2",
        ),
        (
            base.replace(
                r#""componentType": 5126, "count": 3, "type": "VEC3"},"#,
                r#""componentType": 5123, "count": 3, "type": "VEC3"},"#,
            ),
            "must be FLOAT, is U16",
        ),
        (
            base.replace(r#""byteLength": 72}],"#, r#""byteLength": 72, "byteOffset": 8}],"#),
            "bufferViews[0]: bytes 8..80 lie beyond buffers[0] (72 bytes)",
        ),
        (
            base.replace("\"byteLength\": 72, \"uri\"", "\"byteLength\": 80, \"uri\""),
            "buffers[0]: holds 72 bytes, but byteLength is 80",
        ),
        (
            base.replace("base64,", "base64,*"),
            "buffers[0]: bad data URI: invalid base64 character '*' at offset 0",
        ),
        (
            base.replace("data:application/octet-stream;base64,", "missing.bin#"),
            "buffers[0]: cannot read mem/missing.bin#",
        ),
        (
            base.replace("\"uri\": \"data:", "\"urn\": \"data:"),
            "buffers[0]: has no uri and the file has no GLB binary chunk",
        ),
        (
            doc(r#"[{"mesh": 0}]"#, r#", "indices": 1"#, ""),
            "accessors[1]: indices of meshes[0].primitives[0] must be SCALAR of U8/U16/U32, is VEC3 F32",
        ),
        (
            base.replace(
                r#"{"bufferView": 0, "componentType": 5126"#,
                r#"{"bufferView": 0, "byteOffset": 100000000000000000000, "componentType": 5126"#,
            ),
            "accessors[0]: invalid type",
        ),
    ];
    for (json, expect) in cases {
        let e = err_of(&json);
        assert!(
            e.starts_with("mem/t.gltf: ") && e.contains(expect),
            "expected {expect:?}, got {e:?}"
        );
    }
}

#[test]
fn indices_out_of_range_and_non_finite_values() {
    // indices accessor 2: three u16 at offset 72 of a second view.
    let with_indices = |idx: [u16; 3], pos: [f32; 9]| {
        let data = bin(&[&pos[..], &[0.0, 0.0, 1.0].repeat(3)].concat(), &idx);
        doc(r#"[{"mesh": 0}]"#, r#", "indices": 2"#, "")
            .replace(r#""type": "VEC3"}],"#, r#""type": "VEC3"}, {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],"#)
            .replace(r#"[{"buffer": 0, "byteLength": 72}]"#, r#"[{"buffer": 0, "byteLength": 72}, {"buffer": 0, "byteOffset": 72, "byteLength": 6}]"#)
            .replace("\"byteLength\": 72, \"uri\"", "\"byteLength\": 80, \"uri\"")
            .replace(&b64(&bin(&[&TRI[..], &[0.0, 0.0, 1.0].repeat(3)].concat(), &[])), &b64(&data))
    };
    assert_eq!(
        load_json(&with_indices([2, 1, 0], TRI)).unwrap().0.meshes[0].indices,
        vec![[2, 1, 0]]
    );
    let e = err_of(&with_indices([0, 1, 3], TRI));
    assert!(
        e.contains(
            "accessors[2]: index 2 = 3 is out of range: POSITION (accessors[0]) has 3 vertices"
        ),
        "{e}"
    );
    let mut bad = TRI;
    bad[4] = f32::INFINITY;
    let e = err_of(&with_indices([0, 1, 2], bad));
    assert!(e.contains("accessors[0]: element 1 of POSITION of meshes[0].primitives[0] is not finite: [1.0, inf, 0.0]"), "{e}");
}

#[test]
fn glb_container_errors() {
    let json = doc(r#"[{"mesh": 0}]"#, "", "");
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    let padded = json.len().next_multiple_of(4);
    glb.extend(((12 + 8 + padded) as u32).to_le_bytes());
    glb.extend((padded as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(json.as_bytes());
    glb.resize(12 + 8 + padded, b' ');
    let load = |b: &[u8]| load_from_bytes(Path::new("t.glb"), b, no_files);
    assert_eq!(load(&glb).unwrap().0.triangle_count(), 1);
    for (bytes, expect) in [
        (glb[..glb.len() - 1].to_vec(), "GLB header: declares"),
        ([&glb[..8], &4u32.to_le_bytes()[..]].concat(), "GLB header: declares 4 bytes"),
        (glb[..6].to_vec(), "GLB header: truncated"),
        ([&glb[..4], &1u32.to_le_bytes()[..], &glb[8..]].concat(), "container version 1"),
        ([&glb[..16], b"BIN\0", &glb[20..]].concat(), "GLB chunk 0: the first chunk must be JSON"),
        (
            [&glb[..12], &u32::MAX.to_le_bytes()[..], &glb[16..]].concat(),
            "GLB chunk 0: 4294967295 bytes",
        ),
    ] {
        let e = load(&bytes).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.starts_with("t.glb: ") && e.contains(expect), "expected {expect:?}, got {e:?}");
    }
}

/// A one-triangle GLB with indices, normals and texture coordinates in its binary chunk.
fn small_glb() -> Vec<u8> {
    let data = bin(
        &[&TRI[..], &[0.0, 0.0, 1.0].repeat(3), &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]].concat(),
        &[0, 1, 2],
    );
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"children": [1], "scale": [1, 2, 1]}}, {{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}, "indices": 3}}]}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}},
          {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"}},
          {{"bufferView": 0, "byteOffset": 72, "componentType": 5126, "count": 3, "type": "VEC2"}},
          {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 96}}, {{"buffer": 0, "byteOffset": 96, "byteLength": 6}}],
        "buffers": [{{"byteLength": {}}}]}}"#,
        data.len()
    );
    let padded = json.len().next_multiple_of(4);
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + padded + 8 + data.len()) as u32).to_le_bytes());
    glb.extend((padded as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(json.as_bytes());
    glb.resize(12 + 8 + padded, b' ');
    glb.extend((data.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(data);
    glb
}

mod fuzz {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn the_unmutated_file_loads() {
        let (scene, _) = load_from_bytes(Path::new("f.glb"), &small_glb(), no_files).unwrap();
        assert_eq!(scene.meshes[0].positions[2], Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(scene.meshes[0].uvs.len(), 3);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// Random byte edits anywhere in a GLB (header, JSON, binary chunk) give a scene or an
        /// error, never a panic; an error always names the file.
        #[test]
        fn mutated_glb_never_panics(edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6)) {
            let mut glb = small_glb();
            for (at, byte) in edits {
                let i = at.index(glb.len());
                glb[i] = byte;
            }
            if let Err(e) = load_from_bytes(Path::new("f.glb"), &glb, no_files) {
                prop_assert!(e.to_string().starts_with("f.glb: "), "{}", e);
            }
        }

        /// Digits of the JSON replaced by other digits or by huge numbers: every index, count,
        /// offset and length the document holds gets out of range somewhere.
        #[test]
        fn mutated_gltf_numbers_never_panic(edits in prop::collection::vec((any::<prop::sample::Index>(), 0usize..12), 1..4)) {
            let glb = small_glb();
            let len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
            let mut json = String::from_utf8(glb[20..20 + len].to_vec()).unwrap();
            let digits: Vec<usize> = json.char_indices().filter(|(_, c)| c.is_ascii_digit()).map(|(i, _)| i).collect();
            for (at, d) in edits {
                let i = digits[at.index(digits.len())];
                let with = ["0", "1", "2", "3", "4", "5", "7", "9", "65535", "4294967295", "99999999999", "-1"][d];
                json.replace_range(i..i + 1, with);
            }
            let bin = glb[20 + len + 8..].to_vec();
            let json = json.replace(r#""buffers": [{"byteLength""#, r#""buffers": [{"uri": "b.bin", "byteLength""#);
            let files = |p: &Path| if p == Path::new("b.bin") { Ok(bin.clone()) } else { no_files(p) };
            if let Err(e) = load_from_bytes(Path::new("f.gltf"), json.as_bytes(), files) {
                prop_assert!(e.to_string().starts_with("f.gltf: "), "{}", e);
            }
        }
    }
}
