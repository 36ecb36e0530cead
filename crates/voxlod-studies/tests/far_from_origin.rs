//! The bunny at offsets 0, 10⁴, 10⁶ and 10⁷ — its OBJ text with the offset added in `f64`, and a
//! glTF placing it by a root node translation — voxelizes to the same voxels and renders the same
//! ground truth: the loaders re-centre it, so nothing downstream depends on where it sits.

use std::io;
use std::path::Path;

use glam::{DVec3, UVec3, Vec3};
use voxlod_cpu::raycast::Bvh;
use voxlod_cpu::render::ground_truth;
use voxlod_cpu::voxelize::{self, Mode};
use voxlod_format::GridSpec;
use voxlod_scene::{Image, Scene, gltf, obj};

const OFFSETS: [f64; 4] = [0.0, 1e4, 1e6, 1e7];
const BUNNY: &str = include_str!("../../../assets/bunny/bunny.obj");

fn no_files(p: &Path) -> io::Result<Vec<u8>> {
    Err(io::Error::new(io::ErrorKind::NotFound, format!("{} is not here", p.display())))
}

/// The bunny's OBJ text with `d` added to every coordinate in `f64` (shortest round-trip
/// decimal), as a GIS or CAD export writes it.
fn bunny_obj(d: f64) -> String {
    BUNNY
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
    let zero = outcome(&load(&bunny_obj(0.0)));
    let in_world = |d: f64| {
        let mut s = load(&bunny_obj(d));
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
    let zero_scene = load(&bunny_obj(0.0));
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
        let scene = load(&bunny_obj(d));
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
