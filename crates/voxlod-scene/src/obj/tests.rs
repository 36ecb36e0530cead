//! Tests of the OBJ loader on small files written to a temporary directory, or resolved from
//! memory.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

use super::*;
use crate::{AlphaMode, WrapMode};

/// A temporary directory removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("voxlod-obj-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }
    fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Loads OBJ text whose companions come from `files` (by file name).
fn load_mem(obj: &str, files: &[(&str, &[u8])]) -> Result<(Scene, LoadReport)> {
    load_from_str(Path::new("mem/t.obj"), obj, |p| {
        let name = p.strip_prefix("mem").ok().and_then(|p| p.to_str());
        files
            .iter()
            .find(|(n, _)| Some(*n) == name)
            .map(|(_, b)| b.to_vec())
            .ok_or_else(|| std::io::ErrorKind::NotFound.into())
    })
}

fn png_2x1() -> Vec<u8> {
    let img = crate::Srgb8Image { width: 2, height: 1, pixels: vec![[255, 0, 0], [0, 0, 255]] };
    img.encode_png().unwrap()
}

fn area(scene: &Scene) -> f32 {
    scene
        .meshes
        .iter()
        .flat_map(|m| (0..m.triangle_count()).map(move |t| m.triangle(t)))
        .map(|[a, b, c]| (b - a).cross(c - a).length() * 0.5)
        .sum()
}

const QUAD: &str = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";

#[test]
fn textured_quad_from_files() {
    let dir = TempDir::new("textured");
    dir.write("tex.png", png_2x1());
    dir.write(
        "m.mtl",
        "newmtl shiny\nKd 0.5 0.25 1\nKs 0.2 0.2 0.2\nNs 32\nd 0.5\nmap_Kd -clamp on tex.png\n",
    );
    let obj = dir.write(
        "quad.obj",
        format!("mtllib m.mtl\n{QUAD}vn 0 0 2\nusemtl shiny\nf 1/1/1 2/2/1 3/3/1 4/4/1\n"),
    );
    let (scene, report) = load_with_report(&obj).unwrap();
    assert_eq!((scene.name.as_str(), scene.triangle_count()), ("quad", 2));
    assert_eq!(report.polygons_triangulated, 1);
    let m = &scene.meshes[0];
    assert!(m.normals.iter().all(|&n| n == Vec3::Z), "file normals, normalized");
    // OBJ's v = 0 is the bottom of the image: voxlod's v = 1.
    assert_eq!(m.uvs[0], Vec2::new(0.0, 1.0));
    assert_eq!(m.uvs[2], Vec2::new(1.0, 0.0));
    let mat = &scene.materials[m.material];
    assert_eq!(mat.base_color, Vec4::new(0.5, 0.25, 1.0, 0.5));
    assert_eq!((mat.specular, mat.shininess), (Vec3::splat(0.2), 32.0));
    assert_eq!(mat.alpha_mode, AlphaMode::Blend);
    let tex = &scene.textures[mat.base_color_texture.unwrap().texture];
    assert_eq!((tex.width, tex.height, tex.srgb), (2, 1, true));
    assert_eq!(tex.sampler.wrap_u, WrapMode::ClampToEdge);
    assert_eq!(tex.texels[1], [0, 0, 255, 255]);
    assert!((area(&scene) - 2.0).abs() < 1e-6);
}

#[test]
fn concave_face_is_ear_clipped_not_fanned() {
    // An L with the notch x > 1, y > 1: a fan from its first corner (1, 2) covers the notch.
    let obj = "v 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nf 1 2 3 4 5 6\n";
    let (scene, report) = load_mem(obj, &[]).unwrap();
    assert_eq!((scene.triangle_count(), report.polygons_triangulated), (4, 1));
    assert!((area(&scene) - 3.0).abs() < 1e-6, "area {}", area(&scene));
    for t in 0..4 {
        let [a, b, c] = scene.meshes[0].triangle(t);
        assert!((b - a).cross(c - a).z > 0.0, "winding kept");
        let centroid = (a + b + c) / 3.0;
        assert!(!(centroid.x > 1.0 && centroid.y > 1.0), "triangle {t} in the notch");
    }
}

#[test]
fn normals_are_computed_when_missing_or_zero() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn 0 0 1\nf 1//1 2//2 3//2\n";
    let (scene, report) = load_mem(obj, &[]).unwrap();
    assert_eq!(report.normals_computed, 1);
    assert!(scene.meshes[0].normals.iter().all(|&n| (n - Vec3::Z).length() < 1e-6));
    let (scene, report) = load_mem("v 0 0 0\nv 0 1 0\nv 1 0 0\nf 1 2 3\n", &[]).unwrap();
    assert_eq!(report.normals_computed, 3);
    assert!((scene.meshes[0].normals[0] + Vec3::Z).length() < 1e-6);
}

#[test]
fn groups_materials_points_lines_and_relative_indices() {
    let obj = "usemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nl 1 2 3\np 1\nf 1 2\ng g2\n\
               usemtl nowhere\nf 1 3 2\nmtllib m.mtl\n";
    let (scene, report) = load_mem(obj, &[("m.mtl", b"newmtl a\nKd 0 1 0\n")]).unwrap();
    assert_eq!(scene.meshes.len(), 2);
    assert_eq!(scene.materials.len(), 2, "a, and the default for 'nowhere'");
    assert_eq!(scene.materials[scene.meshes[0].material].name, "a", "usemtl before mtllib");
    assert_eq!(scene.materials[scene.meshes[1].material].name, "default");
    assert_eq!(report.unknown_materials, vec!["nowhere".to_owned()]);
    assert_eq!((report.points_skipped, report.lines_skipped), (1, 2));
}

#[test]
fn bad_input_names_file_and_place() {
    let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    for (obj, files, expect) in [
        (format!("{v}f 1 2 7\n"), vec![], "t.obj: line 4: face corner '7' refers to vertex 7"),
        (format!("v 0 0 inf\n{v}"), vec![], "t.obj: line 1: 'v': inf is not a finite number"),
        (
            format!("{v}p 1\nl 1 2\n"),
            vec![],
            "t.obj: no triangles to load (1 points and 1 polylines",
        ),
        (String::new(), vec![], "t.obj: no triangles"),
        (
            format!("mtllib gone.mtl\n{v}f 1 2 3\n"),
            vec![],
            "t.obj: line 1: mtllib 'gone.mtl': cannot read mem/gone.mtl",
        ),
        (
            format!("mtllib m.mtl\n{v}f 1 2 3\n"),
            vec![("m.mtl", &b"newmtl a\nKd 1 1\n"[..])],
            "m.mtl: line 2: 'Kd' needs 3 numbers",
        ),
        (
            format!("mtllib m.mtl\n{v}usemtl a\nf 1 2 3\n"),
            vec![("m.mtl", &b"newmtl a\nmap_Kd wood.png\n"[..])],
            "mem/m.mtl: material 'a': map_Kd texture mem/wood.png",
        ),
        (
            format!("mtllib m.mtl\n{v}vt 0 0\nusemtl a\nf 1/1 2 3\n"),
            vec![("m.mtl", &b"newmtl a\nmap_Kd t.png\n"[..]), ("t.png", &png_2x1()[..])],
            "1 of 3 vertices have texture coordinates",
        ),
        (
            format!("mtllib m.mtl\n{v}usemtl a\nf 1 2 3\n"),
            vec![("m.mtl", &b"newmtl a\nmap_Kd t.png\n"[..]), ("t.png", &png_2x1()[..])],
            "0 of 3 vertices have texture coordinates",
        ),
    ] {
        let err = load_mem(&obj, &files).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(err.contains(expect), "{obj:?}: {err}");
    }
}

#[test]
fn partial_uvs_without_texture_are_dropped() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3\n";
    let (scene, report) = load_mem(obj, &[]).unwrap();
    assert!(scene.meshes[0].uvs.is_empty());
    assert_eq!(report.partial_uvs_dropped, 1);
}

mod fuzz {
    use proptest::prelude::*;

    use super::*;

    const OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0 1\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1 4/1/1 5/2/1 6/3/1\n\
        g b\nusemtl b\nf -6//1 -5//1 -4//1\nl 1 2\np 3\n";
    const MTL: &[u8] =
        b"newmtl a\nKd 1 0.5 0.25\nKs 0.5\nNs 10\nd 0.5\nnewmtl b\nKd 0 1 0\nillum 1\n";

    #[test]
    fn the_unmutated_file_loads() {
        let (scene, _) = load_mem(OBJ, &[("m.mtl", MTL)]).unwrap();
        assert_eq!((scene.triangle_count(), scene.materials.len()), (5, 2));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// Characters of the OBJ and the MTL replaced by characters that matter to the syntax:
        /// a scene or an error naming the file, never a panic.
        #[test]
        fn mutated_obj_and_mtl_never_panic(
            edits in prop::collection::vec((any::<bool>(), any::<prop::sample::Index>(), 0usize..16), 1..5),
        ) {
            const CHARS: &[u8] = b"0123456789-/ \n.e";
            let (mut obj, mut mtl) = (OBJ.as_bytes().to_vec(), MTL.to_vec());
            for (in_obj, at, c) in edits {
                let text = if in_obj { &mut obj } else { &mut mtl };
                let i = at.index(text.len());
                text[i] = CHARS[c];
            }
            let obj = String::from_utf8(obj).unwrap();
            if let Err(e) = load_mem(&obj, &[("m.mtl", &mtl)]) {
                prop_assert!(e.to_string().contains("mem/"), "{}", e);
            }
        }
    }
}
