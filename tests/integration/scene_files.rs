//! Loading real and broken scene files.
//!
//! - Every file of the vendored bad corpus (`tests/data/{gltf,obj}/bad`, from Debian's
//!   assimp-testmodels plus a few hand-made files; see `tests/data/LICENSE.md`) must be an error
//!   — not a panic — whose message names the file and the element at fault. The expected text
//!   for each file is listed below, and the list must match the directory.
//! - The good corpus and `assets/` load with the expected contents, checked against values
//!   computed independently of the loader (triangle counts and bounds from the source data,
//!   the same model in three containers, spec arithmetic for skinning).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use voxlod::scene::{self, AlphaMode, Scene, WrapMode};

use glam::{Vec2, Vec3};

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// The scene files (.obj, .gltf, .glb) under `dir`, relative to `base`, sorted.
fn scene_files(base: &Path, dir: &Path) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = entry.unwrap().path();
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if p.is_dir() {
                stack.push(p);
            } else if matches!(ext, "obj" | "gltf" | "glb") {
                out.insert(p.strip_prefix(base).unwrap().to_string_lossy().replace('\\', "/"));
            }
        }
    }
    out
}

/// Every bad file, with text its error message must contain besides the file's path.
const BAD: &[(&str, &str)] = &[
    (
        "gltf/bad/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
        "accessors[2]: element 0 of POSITION of meshes[0].primitives[0] is not finite: [-inf",
    ),
    (
        "gltf/bad/IncorrectVertexArrays/Cube.gltf",
        "meshes[1].primitives[0]: TRIANGLES needs a multiple of 3 vertices or indices, has 35",
    ),
    (
        "gltf/bad/IndexOutOfRange/AllIndicesOutOfRange.gltf",
        "accessors[0]: index 0 = 65535 is out of range: POSITION (accessors[2]) has 24 vertices",
    ),
    (
        "gltf/bad/IndexOutOfRange/IndexOutOfRange.gltf",
        "accessors[0]: index 0 = 255 is out of range: POSITION (accessors[2]) has 24 vertices",
    ),
    (
        "gltf/bad/Mesh_PrimitiveMode/Mesh_PrimitiveMode_00.gltf",
        "scenes[0]: no triangles to load (1 points and 0 line primitives skipped)",
    ),
    (
        "gltf/bad/Mesh_PrimitiveMode/Mesh_PrimitiveMode_01.gltf",
        "scenes[0]: no triangles to load (0 points and 1 line primitives skipped)",
    ),
    (
        "gltf/bad/Mesh_PrimitiveMode/Mesh_PrimitiveMode_02.gltf",
        "scenes[0]: no triangles to load (0 points and 1 line primitives skipped)",
    ),
    (
        "gltf/bad/Mesh_PrimitiveMode/Mesh_PrimitiveMode_03.gltf",
        "scenes[0]: no triangles to load (0 points and 1 line primitives skipped)",
    ),
    ("gltf/bad/MissingBin/BoxTextured.gltf", "buffers[0]: cannot read"),
    (
        "gltf/bad/RecursiveNodes/RecursiveNodes.gltf",
        "nodes[0]: the node graph has a cycle: nodes[1] → nodes[0] → nodes[1]",
    ),
    ("gltf/bad/SchemaFailures/sceneWrongType.gltf", "scene: invalid type: string \"hello\""),
    ("gltf/bad/TestNoRootNode/NoScene.gltf", "scene: refers to an element that does not exist"),
    ("gltf/bad/TestNoRootNode/SceneWithoutNodes.gltf", "scenes[0]: no triangles to load"),
    (
        "gltf/bad/crafted/accessor_past_view.gltf",
        "accessors[0]: 4 elements of 12 bytes (stride 12) from offset 0 run past the end of bufferViews[0] (36 bytes)",
    ),
    (
        "gltf/bad/crafted/bad_data_uri.gltf",
        "buffers[0]: bad data URI: invalid base64 character '#'",
    ),
    (
        "gltf/bad/crafted/truncated.glb",
        "GLB header: declares 472 bytes, but the file has 462 bytes",
    ),
    ("gltf/bad/crafted/two_parents.gltf", "nodes[2]: has two parents, nodes[0] and nodes[1]"),
    (
        "gltf/bad/crafted/view_past_buffer.gltf",
        "bufferViews[0]: bytes 0..48 lie beyond buffers[0] (36 bytes)",
    ),
    (
        "gltf/bad/issue_3269/texcoord_crash.gltf",
        "meshes[0].primitives[0]: its material's baseColorTexture reads TEXCOORD_0, which the primitive does not have",
    ),
    ("gltf/bad/wrongTypes/badArray.gltf", "meshes[0]: invalid type: map, expected a sequence"),
    (
        "gltf/bad/wrongTypes/badExtension.gltf",
        "materials[0]: invalid type: string \"Not an object\"",
    ),
    ("gltf/bad/wrongTypes/badNumber.gltf", "materials[0]: invalid type: string \"not a number\""),
    ("gltf/bad/wrongTypes/badObject.gltf", "materials[0]: invalid type: string \"not an object\""),
    ("gltf/bad/wrongTypes/badString.gltf", "scenes[0]: invalid type: integer `42`"),
    ("gltf/bad/wrongTypes/badUint.gltf", "materials[0]: invalid type: integer `-1`"),
    ("obj/bad/box_UTF16BE.obj", "line 1: UTF-16 text"),
    ("obj/bad/crafted/missing_texture.obj", "missing_texture.mtl: material 'm': map_Kd texture"),
    ("obj/bad/crafted/nan_vertex.obj", "line 3: 'v': nan is not a finite number"),
    (
        "obj/bad/crafted/relative_index_out_of_range.obj",
        "line 4: face corner '-4' refers to vertex -4, but there are 3 defined so far",
    ),
    ("obj/bad/crafted/short_kd.obj", "short_kd.mtl: line 3: 'Kd' needs 3 numbers, found 2"),
    ("obj/bad/cube_mtllib_after_g.obj", "line 2: mtllib 'cube_mtllib_after_g.mat': cannot read"),
    ("obj/bad/empty.obj", "no triangles to load"),
    (
        "obj/bad/malformed.obj",
        "line 23: face corner '12' refers to vertex 12, but there are 8 in the file",
    ),
    ("obj/bad/malformed2.obj", "line 23: face without vertices"),
    ("obj/bad/number_formats.obj", "line 11: 'v': '3.1+e2' is not a number"),
    ("obj/bad/point_cloud.obj", "no triangles to load"),
    ("obj/bad/testline.obj", "no triangles to load (0 points and 6 polylines skipped)"),
    ("obj/bad/testpoints.obj", "no triangles to load (6 points and 0 polylines skipped)"),
];

#[test]
fn every_bad_file_is_an_error_naming_file_and_element() {
    let base = data_dir();
    let mut found = scene_files(&base, &base.join("gltf/bad"));
    found.extend(scene_files(&base, &base.join("obj/bad")));
    let listed: BTreeSet<String> = BAD.iter().map(|(f, _)| (*f).to_owned()).collect();
    assert_eq!(
        found, listed,
        "every vendored bad file needs an expected error in BAD, and vice versa"
    );
    let mut failures = Vec::new();
    for (rel, expect) in BAD {
        let path = base.join(rel);
        let outcome = std::panic::catch_unwind(|| Scene::load(&path));
        match outcome {
            Err(_) => failures.push(format!("{rel}: the loader panicked")),
            Ok(Ok(scene)) => {
                failures.push(format!("{rel}: loaded {} triangles", scene.triangle_count()))
            }
            Ok(Err(e)) => {
                let msg = e.to_string();
                if !msg.contains(&path.display().to_string()) || !msg.contains(expect) {
                    failures.push(format!("{rel}:\n   expected {expect:?}\n   got      {msg:?}"));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} bad files:\n{}",
        failures.len(),
        BAD.len(),
        failures.join("\n")
    );
}

fn load(rel: &str) -> Scene {
    let path = data_dir().join(rel);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn area(scene: &Scene) -> f64 {
    let g = scene.geometry();
    (0..g.triangle_count())
        .map(|t| {
            let [a, b, c] = g.triangle(t);
            f64::from((b - a).cross(c - a).length()) * 0.5
        })
        .sum()
}

fn assert_close(what: &str, got: f64, want: f64, rel: f64) {
    let diff = (got - want).abs();
    assert!(
        diff <= rel * want.abs().max(1e-30),
        "{what}: got {got}, want {want} (|Δ| = {diff:e}, bound {rel:e} relative)"
    );
}

#[test]
fn bunny_asset() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bunny/bunny.obj");
    let (scene, report) = scene::obj::load_with_report(&path).unwrap();
    assert_eq!((scene.triangle_count(), scene.meshes.len()), (3674, 1));
    let m = &scene.meshes[0];
    assert_eq!((m.positions.len(), m.uvs.len()), (1839, 0));
    assert_eq!(report.normals_computed, 1839);
    assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    // Bounds and signed volume of the npm package's data, computed when converting it.
    let (lo, hi) = scene.bounds().unwrap();
    assert_eq!(lo, Vec3::new(-4.958475, -0.003149, -3.729833));
    assert_eq!(hi, Vec3::new(4.94885, 9.654748, 3.810639));
    let volume: f64 = (0..m.triangle_count())
        .map(|t| {
            let [a, b, c] = m.triangle(t).map(|p| p.as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert_close("signed volume (outward winding)", volume, 194.28837, 1e-5);
}

#[test]
fn engine_asset_is_the_121k_triangle_model() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/2CylinderEngine/2CylinderEngine.glb");
    let (scene, report) = scene::gltf::load_with_report(&path).unwrap();
    // Reference values from a NumPy traversal of the same file (node matrices applied to the
    // indexed vertices), independent of this loader.
    assert_eq!(scene.triangle_count(), 121_496);
    assert_eq!((scene.nodes.len(), scene.materials.len(), scene.textures.len()), (82, 34, 0));
    let (lo, hi) = scene.bounds().unwrap();
    for (got, want) in
        [(lo, [-371.69226, -180.97156, -139.99999]), (hi, [371.69217, 92.04156, 127.99999])]
    {
        for k in 0..3 {
            assert_close("bounds", f64::from(got[k]), want[k], 1e-5);
        }
    }
    assert_close("surface area", area(&scene), 2_663_488.59, 1e-4);
    assert!(scene.camera.is_some());
    assert_eq!((report.points_skipped, report.lines_skipped, report.normals_computed), (0, 0, 0));
}

#[test]
fn box_textured_is_the_same_in_three_containers() {
    let glb = Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/BoxTextured/BoxTextured.glb"),
    )
    .unwrap();
    let files = load("gltf/good/BoxTextured-glTF/BoxTextured.gltf");
    let embedded = load("gltf/good/BoxTextured-glTF-Embedded/BoxTextured.gltf");
    assert_eq!(glb.triangle_count(), 12);
    assert_close("area of the unit cube", area(&glb), 6.0, 1e-6);
    assert_eq!(glb.bounds().unwrap(), (Vec3::splat(-0.5), Vec3::splat(0.5)));
    let tex = &glb.textures[0];
    assert_eq!(
        (tex.width, tex.height, tex.srgb, tex.sampler.wrap_u),
        (211, 211, true, WrapMode::Repeat)
    );
    assert_eq!(glb.materials[0].base_color_texture.map(|t| t.texture), Some(0));
    // The file's first texture coordinates (6, 0), (5, 0): kept as they are (glTF's convention
    // is voxlod's), repeated by the sampler.
    assert_eq!(&glb.meshes[0].uvs[..2], &[Vec2::new(6.0, 0.0), Vec2::new(5.0, 0.0)]);
    for other in [&files, &embedded] {
        assert_eq!(other.meshes, glb.meshes);
        assert_eq!(other.textures[0].texels, glb.textures[0].texels);
    }
}

/// The area of the single polygon of an OBJ file, by Newell's formula on the file's numbers.
fn obj_polygon_area(text: &str) -> f64 {
    let v: Vec<[f64; 3]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [c[0], c[1], c[2]]
        })
        .collect();
    let face = text.lines().find_map(|l| l.strip_prefix("f ")).unwrap();
    let corners: Vec<[f64; 3]> = face
        .split_whitespace()
        .map(|c| v[c.split('/').next().unwrap().parse::<usize>().unwrap() - 1])
        .collect();
    let mut n = [0.0f64; 3];
    for (i, a) in corners.iter().enumerate() {
        let b = corners[(i + 1) % corners.len()];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

#[test]
fn concave_obj_faces_keep_their_area_and_orientation() {
    // assimp's concave_polygon.obj is one 66-corner face: a ring whose bridge edge is
    // traversed twice. A fan triangulation would cover the hole.
    let rel = "obj/good/concave_polygon.obj";
    let scene = load(rel);
    assert_eq!(scene.triangle_count(), 64);
    let want = obj_polygon_area(&std::fs::read_to_string(data_dir().join(rel)).unwrap());
    assert_close("concave polygon area", area(&scene), want, 1e-4);
    let m = &scene.meshes[0];
    for t in 0..m.triangle_count() {
        let [a, b, c] = m.triangle(t);
        assert!((b - a).cross(c - a).x >= 0.0, "triangle {t} flipped (the face's normal is +x)");
    }
    assert_eq!(scene.materials[m.material].name, "test");
}

#[test]
fn textured_obj_with_backslash_path_and_concave_face() {
    let path = data_dir().join("obj/good/textured_cube/cube.obj");
    let (scene, report) = scene::obj::load_with_report(&path).unwrap();
    assert_eq!((scene.triangle_count(), report.polygons_triangulated), (16, 7));
    let cube = scene.meshes.iter().find(|m| m.name.ends_with("cube")).unwrap();
    let logo = &scene.materials[cube.material];
    let tex = &scene.textures[logo.base_color_texture.unwrap().texture];
    assert_eq!((tex.width, tex.height, tex.sampler.wrap_v), (211, 211, WrapMode::ClampToEdge));
    assert_eq!((logo.specular, logo.shininess), (Vec3::splat(0.25), 50.0));
    assert!(cube.uvs.iter().all(|uv| [0.0, 1.0].contains(&uv.x) && [0.0, 1.0].contains(&uv.y)));
    let l = scene.meshes.iter().find(|m| m.name.ends_with("l_shape")).unwrap();
    assert_eq!(scene.materials[l.material].alpha_mode, AlphaMode::Blend);
    let l_area: f32 =
        (0..4).map(|t| l.triangle(t)).map(|[a, b, c]| (b - a).cross(c - a).z * 0.5).sum();
    assert!((l_area - 3.0).abs() < 1e-6, "every triangle counter-clockwise, total 3: {l_area}");
    assert_close("total area", area(&scene), 9.0, 1e-6);
}

#[test]
fn obj_quirks_of_real_exporters() {
    // Latin-1 material names (3ds Max), a material named '' (Blender), mixed points/lines/faces.
    let spaces = load("obj/good/box_mat_with_spaces.obj");
    let names: Vec<&str> = spaces.materials.iter().map(|m| m.name.as_str()).collect();
    assert!(
        names.contains(&"Material name with many, many spaces") && names.contains(&"Terraindæk"),
        "{names:?}"
    );
    assert_eq!(
        spaces.materials[spaces.meshes[0].material].name,
        "Material name with many, many spaces"
    );
    assert_eq!(load("obj/good/empty_mat.obj").materials[0].name, "(unnamed)");
    let (mixed, report) =
        scene::obj::load_with_report(&data_dir().join("obj/good/testmixed.obj")).unwrap();
    assert_eq!((mixed.triangle_count(), report.points_skipped, report.lines_skipped), (12, 6, 6));
    assert_eq!(report.unknown_materials, vec!["Default".to_owned()]);
    for (rel, triangles) in [
        ("obj/good/box.obj", 12),
        ("obj/good/box_without_lineending.obj", 12),
        ("obj/good/cube_usemtl.obj", 12),
        ("obj/good/multiple_spaces.obj", 1),
        ("obj/good/regr_3429812.obj", 4),
        ("obj/good/space_in_material_name.obj", 64),
    ] {
        assert_eq!(load(rel).triangle_count(), triangles, "{rel}");
    }
}

#[test]
fn gltf_primitive_modes_match_the_triangle_list() {
    // Same quad drawn as a list (13–15, three index types), strips (04, 11) and fans (05, 12).
    let dir = "gltf/good/Mesh_PrimitiveMode";
    let reference = load(&format!("{dir}/Mesh_PrimitiveMode_13.gltf"));
    let want = area(&reference);
    let facing = |s: &Scene| {
        let [a, b, c] = s.meshes[0].triangle(0);
        (b - a).cross(c - a).normalize()
    };
    for k in ["04", "05", "11", "12", "13", "14", "15"] {
        let path = data_dir().join(format!("{dir}/Mesh_PrimitiveMode_{k}.gltf"));
        let (scene, report) = scene::gltf::load_with_report(&path).unwrap();
        assert_eq!(scene.triangle_count(), 2, "{k}");
        assert_close(&format!("area of mode {k}"), area(&scene), want, 1e-6);
        let m = &scene.meshes[0];
        let n0 = facing(&scene);
        for t in 0..2 {
            let [a, b, c] = m.triangle(t);
            assert!(
                (b - a).cross(c - a).normalize().dot(n0) > 0.99,
                "mode {k}: triangle {t} wound the other way"
            );
        }
        assert!(n0.dot(facing(&reference)) > 0.99, "mode {k} faces like the list");
        assert_eq!(
            report.strips_and_fans_converted,
            usize::from(["04", "05", "11", "12"].contains(&k))
        );
    }
}

#[test]
fn gltf_skins_cameras_morphs_normals_and_texture_transforms() {
    // Rest pose: both joints' world matrices are translate(0, 1, 0) and both inverse bind
    // matrices translate(−0.5, −1, 0), so every vertex moves by (−0.5, 0, 0).
    let skin = load("gltf/good/simple_skin/simple_skin.gltf");
    assert_eq!(skin.triangle_count(), 8);
    assert_eq!(skin.bounds().unwrap(), (Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 2.0, 0.0)));
    assert_eq!(
        (skin.skins[0].joints.as_slice(), skin.animations[0].channels.len()),
        (&[1, 2][..], 1)
    );
    assert_eq!(skin.meshes[0].skin.as_ref().map(|s| s.joints.len()), Some(10));

    let cams = load("gltf/good/cameras/Cameras.gltf");
    let cam = cams.camera.unwrap();
    assert_eq!(cam.eye, Vec3::new(0.5, 0.5, 3.0));
    assert!((cam.fov_y_deg - 0.7f32.to_degrees()).abs() < 1e-4);

    let morph = load("gltf/good/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf");
    assert_eq!((morph.triangle_count(), morph.animations.len()), (12, 1));

    let path = data_dir().join("gltf/good/BoxBadNormals-glTF-Binary/BoxBadNormals.glb");
    let (bad_normals, report) = scene::gltf::load_with_report(&path).unwrap();
    assert_eq!(report.normals_computed, 4, "four zero-length normals replaced");
    assert!(bad_normals.meshes[0].normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));

    // KHR_texture_transform: "Offset U", "Offset V" and "Offset UV" share texture coordinates
    // and differ only by their offsets (0.5, 0), (0, 0.5), (0.5, 0.5).
    let tt = load("gltf/good/textureTransform/TextureTransformTest.gltf");
    assert_eq!((tt.triangle_count(), tt.textures.len()), (24, 5));
    let uvs = |name: &str| {
        &tt.meshes.iter().find(|m| m.name.starts_with(&format!("{name} ("))).unwrap().uvs
    };
    for ((a, b), c) in uvs("Offset U").iter().zip(uvs("Offset V")).zip(uvs("Offset UV")) {
        assert!(
            (*a - *b - Vec2::new(0.5, -0.5)).length() < 1e-6
                && (*c - *b - Vec2::new(0.5, 0.0)).length() < 1e-6
        );
    }
    assert_eq!(tt.textures[0].sampler.wrap_u, WrapMode::ClampToEdge);
}
