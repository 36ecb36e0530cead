//! A model far from the world origin: the bunny's OBJ text with an offset of 0, 10⁴, 10⁶ or 10⁷
//! added in `f64`, and a glTF placing it by a root node translation, voxelizes to the same voxels
//! and renders the same ground truth (the loaders re-centre it). Through the CLI, voxel files
//! keep the grid's world origin in `f64`, a camera and a point light given in world coordinates
//! land where they would at 0, and a `.vol` export holds the same grid.

use std::io;
use std::path::{Path, PathBuf};
use std::process::Output;

use glam::{DVec3, UVec3, Vec3};
use voxlod::cpu::raycast::Bvh;
use voxlod::cpu::render::ground_truth;
use voxlod::cpu::voxelize::{self, Mode};
use voxlod::format::{GridSpec, Occupancy, binvox, vol, vxl};
use voxlod::scene::{Image, Scene, gltf, obj};

use crate::{json_result, voxlod};

const OFFSET: f64 = 1e7;
const OFFSETS: [f64; 4] = [0.0, 1e4, 1e6, 1e7];

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxlod-far-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The bunny's OBJ text with `d` added to every coordinate in `f64` (shortest round-trip
/// decimal), as a GIS or CAD export writes it.
fn bunny_text(d: f64) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bunny/bunny.obj");
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|line| match line.strip_prefix("v ") {
            Some(xyz) => {
                let v: Vec<String> = xyz
                    .split_whitespace()
                    .map(|x| (x.parse::<f64>().unwrap() + d).to_string())
                    .collect();
                format!("v {}\n", v.join(" "))
            }
            None => format!("{line}\n"),
        })
        .collect()
}

/// [`bunny_text`] written to `dir`; its path.
fn bunny_at(dir: &Path, d: f64) -> String {
    let out = dir.join(format!("bunny-{d}.obj"));
    std::fs::write(&out, bunny_text(d)).unwrap();
    out.to_str().unwrap().to_owned()
}

fn ok(out: Output, command: &str) -> serde_json::Value {
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    json_result(&out.stdout, command)
}

fn dvec3(v: &serde_json::Value) -> DVec3 {
    DVec3::from_slice(
        &v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect::<Vec<_>>(),
    )
}

#[test]
fn far_models_keep_world_coordinates_at_the_edges() {
    let dir = temp_dir();
    let (near, far) = (bunny_at(&dir, 0.0), bunny_at(&dir, OFFSET));
    let p = |name: &str| dir.join(name).to_str().unwrap().to_owned();

    // Voxelize: the same voxels; the files hold the world origin, exact in f64.
    let mut grids = Vec::new();
    for (scene, name) in [(&near, "near"), (&far, "far")] {
        let vxl_path = p(&format!("{name}.vxl"));
        let summary =
            ok(voxlod(&["voxelize", scene, "--res", "32", "-o", &vxl_path, "--json"]), "voxelize");
        let file = vxl::read::<Occupancy>(Path::new(&vxl_path)).unwrap();
        assert_eq!(file.grid.origin, dvec3(&summary["origin"]));
        let binvox_path = p(&format!("{name}.binvox"));
        ok(voxlod(&["voxelize", scene, "--res", "32", "-o", &binvox_path, "--json"]), "voxelize");
        let info = binvox::read_info(Path::new(&binvox_path)).unwrap();
        assert_eq!(info.header.translate, file.grid.origin, "binvox keeps the world origin");
        grids.push((file, dvec3(&summary["scene_origin"])));
    }
    let [(n, n_origin), (f, f_origin)] = [grids.remove(0), grids.remove(0)];
    assert_eq!((n_origin, f_origin), (DVec3::ZERO, DVec3::splat(OFFSET)));
    assert_eq!(n.map.coords().collect::<Vec<_>>(), f.map.coords().collect::<Vec<_>>());
    assert_eq!(n.grid.dims, f.grid.dims);
    let moved = f.grid.origin - n.grid.origin - DVec3::splat(OFFSET);
    assert!(moved.abs().max_element() < 1e-8, "the far grid sits {moved} off");

    // Render: a camera and a point light in world coordinates, 10⁷ + 0.25 and all.
    let mut images = Vec::new();
    for (scene, d) in [(&near, 0.0), (&far, OFFSET)] {
        let at = |x: f64, y: f64, z: f64| format!("{},{},{}", x + d, y + d, z + d);
        let camera = format!("eye={};target={}", at(6.25, 9.0, 14.0), at(0.0, 4.5, 0.0));
        let light = format!("point={};intensity=400", at(3.0, 12.0, 6.0));
        let png = p(&format!("render-{d}.png"));
        let args = ["render", scene, "--camera", &camera, "--light", &light, "--size", "32x32"];
        let summary =
            ok(voxlod(&[&args[..], &["--spp", "2", "-o", &png, "--json"]].concat()), "render");
        assert_eq!(dvec3(&summary["scene_origin"]), DVec3::splat(d));
        images.push(std::fs::read(&png).unwrap());
    }
    assert!(images[0] == images[1], "the renders at 0 and 10⁷ differ");

    // Export to Mitsuba: the .vol box is relative to the scene origin — the same file.
    let mut vols = Vec::new();
    for (scene, name) in [(&near, "near"), (&far, "far")] {
        let vol = p(&format!("{name}.vol"));
        let args = ["export", scene, "--res", "16", "--rays", "4", "-o", &vol, "--json"];
        let summary = ok(voxlod(&args), "export");
        assert_eq!(
            dvec3(&summary["scene_origin"]),
            if name == "far" { DVec3::splat(OFFSET) } else { DVec3::ZERO }
        );
        vols.push(vol::read(Path::new(&vol)).unwrap());
    }
    assert_eq!((&vols[0].dims, &vols[0].data), (&vols[1].dims, &vols[1].data));
    // The box: the bunny's lowest y, -0.003149, is 9999999.996851 in the far file, which f64
    // resolves to 2⁻²⁹ only; every other bound is bit-identical.
    let moved = (vols[0].bbox_min - vols[1].bbox_min)
        .abs()
        .max((vols[0].bbox_max - vols[1].bbox_max).abs());
    assert!(moved.abs().max_element() <= 2f32.powi(-29), "the .vol box moved by {moved}");
    let _ = std::fs::remove_dir_all(&dir);
}

fn no_files(p: &Path) -> io::Result<Vec<u8>> {
    Err(io::Error::new(io::ErrorKind::NotFound, format!("{} is not here", p.display())))
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = c.iter().enumerate().fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
        for k in 0..4 {
            s.push(if k <= c.len() { A[(n >> (18 - 6 * k) & 63) as usize] as char } else { '=' });
        }
    }
    s
}

/// The bunny (positions of the OBJ load at offset 0) as a glTF primitive under a root node
/// translated by `(d, d, d)`, written as JSON digits.
fn bunny_gltf(at_zero: &Scene, d: f64) -> String {
    let g = at_zero.geometry();
    let mut data: Vec<u8> =
        g.positions.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect();
    let idx_at = data.len();
    data.extend(g.indices.iter().flatten().flat_map(|i| i.to_le_bytes()));
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"translation": [{d}, {d}, {d}], "children": [1]}}, {{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": {nv}, "type": "VEC3"}},
          {{"bufferView": 0, "byteOffset": {idx_at}, "componentType": 5125, "count": {ni}, "type": "SCALAR"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": {len}}}],
        "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{b64}"}}]}}"#,
        nv = g.positions.len(),
        ni = g.indices.len() * 3,
        len = data.len(),
        b64 = base64(&data),
    )
}

/// What a scene turns into: its conservative voxels at 64³ and a small ground-truth image.
struct Outcome {
    origin: DVec3,
    grid: GridSpec,
    voxels: Vec<UVec3>,
    image: Image,
}

fn outcome(scene: &Scene) -> Outcome {
    let geometry = scene.geometry();
    let (lo, hi) = scene.bounds().unwrap();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 64).unwrap();
    let options =
        voxelize::Options { mode: Mode::Conservative, triangle_lists: false, ..Default::default() };
    let vox = voxelize::voxelize(&geometry, &grid, &options).unwrap();
    let bvh = Bvh::new(&geometry).unwrap_or_else(|e| panic!("origin {}: {e}", scene.origin));
    let options = ground_truth::Options {
        width: 48,
        height: 48,
        spp: 2,
        seed: 0,
        ambient: Vec3::splat(0.1),
        shadows: true,
        light_filter: None,
    };
    let camera = scene.default_camera().unwrap();
    let image = ground_truth::render(scene, &geometry, &bvh, &camera, &options).unwrap().image;
    Outcome {
        origin: scene.origin,
        grid,
        voxels: vox.voxels.iter().map(|(c, _)| c).collect(),
        image,
    }
}

/// Largest difference of a pixel channel between two images.
fn max_difference(a: &Image, b: &Image) -> f32 {
    a.pixels.iter().zip(&b.pixels).map(|(p, q)| (*p - *q).abs().max_element()).fold(0.0, f32::max)
}

/// The control: the bunny at 10⁶ stored in world coordinates in `f32`, as without re-centring,
/// voxelizes to other voxels (its vertices snap to f32's 0.0625 spacing).
#[test]
fn without_recentring_the_far_bunny_differs() {
    let load = |text: &str| obj::load_from_str(Path::new("bunny.obj"), text, no_files).unwrap().0;
    let zero = outcome(&load(&bunny_text(0.0)));
    let in_world = |d: f64| {
        let mut s = load(&bunny_text(d));
        for m in &mut s.meshes {
            m.positions.iter_mut().for_each(|p| *p = (p.as_dvec3() + s.origin).as_vec3());
        }
        s.origin = DVec3::ZERO;
        s
    };
    let naive = in_world(1e6);
    let (lo, hi) = naive.bounds().unwrap();
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 64).unwrap();
    let options =
        voxelize::Options { mode: Mode::Conservative, triangle_lists: false, ..Default::default() };
    let vox = voxelize::voxelize(&naive.geometry(), &grid, &options).unwrap();
    assert_ne!(vox.voxels.len(), zero.voxels.len());
}

#[test]
fn the_bunny_voxelizes_and_renders_the_same_at_every_offset() {
    let load = |text: &str| obj::load_from_str(Path::new("bunny.obj"), text, no_files).unwrap().0;
    let zero_scene = load(&bunny_text(0.0));
    let zero = outcome(&zero_scene);
    assert_eq!(zero.origin, DVec3::ZERO);
    assert_eq!(zero.voxels.len(), 13_172, "the bunny's conservative voxels at 64³");
    let gltf_zero = {
        let text = bunny_gltf(&zero_scene, 0.0);
        outcome(
            &gltf::load_from_bytes(Path::new("bunny.gltf"), text.as_bytes(), no_files).unwrap().0,
        )
    };
    for d in OFFSETS {
        let scene = load(&bunny_text(d));
        let obj_far = outcome(&scene);
        let text = bunny_gltf(&zero_scene, d);
        let gltf_far = outcome(
            &gltf::load_from_bytes(Path::new("bunny.gltf"), text.as_bytes(), no_files).unwrap().0,
        );
        for (far, near, what) in [(&obj_far, &zero, "OBJ"), (&gltf_far, &gltf_zero, "glTF")] {
            assert_eq!(far.origin, DVec3::splat(d), "{what} at {d}");
            // The grid fitted to the local bounds: at 10⁷ the file resolves coordinates to 2⁻²⁹,
            // so a bound may move by that much (the bunny's lowest y, -0.003149, is
            // 9999999.996851 in the file).
            assert_eq!(far.grid.dims, near.grid.dims, "{what} at {d}");
            let moved = (far.grid.origin - near.grid.origin).abs().max_element();
            let resolution = 2f64.powi((d.max(1.0).log2().floor() as i32) - 52);
            assert!(moved <= resolution, "{what} at {d}: the grid moved by {moved}");
            assert!(
                far.voxels == near.voxels,
                "{what} at {d}: {} voxels, not {}",
                far.voxels.len(),
                near.voxels.len()
            );
            // Identical in 8-bit sRGB; in float, a few pixels at 10⁷ differ by an ulp where a
            // vertex moved by the file's 2⁻²⁹ resolution.
            assert_eq!(far.image.to_srgb8(), near.image.to_srgb8(), "{what} at {d}");
            let diff = max_difference(&far.image, &near.image);
            assert!(diff <= 1e-6, "{what} at {d}: images differ by up to {diff}");
        }
    }
}
