//! The cases: the scenes (bunny, face-aligned and tilted quads, BoxTextured, leaf layers), the
//! random triangle soups of the property rows, and the perturbed materials of the controls.

use glam::{DVec3, UVec3, Vec2, Vec3, Vec4};
use voxlod_cpu::appearance::precompute::PrecomputeOptions;
use voxlod_cpu::random::rand_f32;
use voxlod_format::GridSpec;
use voxlod_scene::{AlphaMode, Material, Mesh, Scene};

use super::{Case, case};

/// The forest's leaf: its alpha-masked, double-sided material (texture 0) and leaf texture.
pub(super) fn leaf() -> (Material, voxlod_scene::Texture) {
    let forest = voxlod_scene::procedural::builtin(
        "forest",
        &[("trees", "1"), ("leaves", "1"), ("alpha", "true")],
    )
    .expect("the builtin forest builds");
    let mut m = forest
        .materials
        .iter()
        .find(|m| matches!(m.alpha_mode, AlphaMode::Mask { .. }))
        .expect("the forest's leaf material is alpha-masked")
        .clone();
    m.base_color_texture = Some(voxlod_scene::TextureRef { texture: 0 });
    (m, forest.textures[0].clone())
}

/// Two quads across the 8³ grid of half-unit voxels, both in the voxel layer z ∈ [1, 1.5]: in
/// front (z = 1.15) material `front` (textured with `texture`, UVs 0..3: nine leaves across,
/// each about two voxels), behind (z = 1.4) an opaque red one. Lines through what the front
/// material's alpha rejects reach the red quad.
pub(super) fn layered(front: Material, texture: voxlod_scene::Texture) -> Scene {
    let q = |z: f32, uv: f32, material| {
        let p = [Vec3::new(0.3, 0.3, z), Vec3::new(3.7, 0.3, z), Vec3::new(3.7, 3.7, z)];
        Mesh {
            name: "quad".into(),
            positions: vec![p[0], p[1], p[2], Vec3::new(0.3, 3.7, z)],
            normals: vec![Vec3::Z; 4],
            uvs: vec![Vec2::ZERO, Vec2::new(uv, 0.0), Vec2::splat(uv), Vec2::new(0.0, uv)],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material,
            ..Default::default()
        }
    };
    Scene {
        meshes: vec![q(1.15, 3.0, 0), q(1.4, 1.0, 1)],
        materials: vec![
            front,
            Material { base_color: Vec4::new(0.8, 0.1, 0.1, 1.0), ..Default::default() },
        ],
        textures: vec![texture],
        ..Default::default()
    }
}

/// Every texture shifted by one texel along u (texel x takes texel x + 1's value).
pub(super) fn shift_textures(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for t in &mut s.textures {
        let (w, h) = (t.width as usize, t.height as usize);
        let texels: Vec<[u8; 4]> =
            (0..w * h).map(|i| t.texels[(i / w) * w + (i % w + 1) % w]).collect();
        t.texels = std::sync::Arc::from(texels);
    }
    s
}

/// The material scenes' controls: each scene's materials perturbed on purpose (the oracle
/// then samples the perturbed scene; the backend ran on the true one).
pub(super) fn perturbed(name: &str, scene: &Scene) -> Option<(Scene, &'static str)> {
    let mut s = scene.clone();
    match name {
        "box-textured" => Some((shift_textures(scene), "texture shifted one texel")),
        "leaf-mask" => {
            for m in &mut s.materials {
                m.alpha_mode = AlphaMode::Opaque;
            }
            Some((s, "alpha mask ignored"))
        }
        "leaf-blend" => {
            for m in &mut s.materials {
                if m.alpha_mode == AlphaMode::Blend {
                    m.base_color.w -= 0.1;
                }
            }
            Some((s, "blend alpha 0.7 → 0.6"))
        }
        _ => None,
    }
}

pub(super) fn quad(corners: [Vec3; 4], double_sided: bool, color: Vec3) -> Scene {
    let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize();
    Scene {
        meshes: vec![Mesh {
            name: "quad".into(),
            positions: corners.to_vec(),
            normals: vec![n; 4],
            uvs: vec![Vec2::ZERO; 4],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material: 0,
            ..Default::default()
        }],
        materials: vec![Material {
            base_color: color.extend(1.0),
            double_sided,
            specular: Vec3::splat(0.3),
            shininess: 32.0,
            ..Default::default()
        }],
        ..Default::default()
    }
}

pub(super) fn scene_cases() -> Vec<Case> {
    let bunny = Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny/bunny.obj"),
    )
    .expect("the bunny asset loads");
    let (lo, hi) = bunny.bounds().expect("bounds");
    let bunny_grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 32).expect("grid");
    let unit = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(4)).expect("grid");
    let face = [
        Vec3::new(0.5, 0.5, 2.0),
        Vec3::new(3.5, 0.5, 2.0),
        Vec3::new(3.5, 3.5, 2.0),
        Vec3::new(0.5, 3.5, 2.0),
    ];
    let tilted = [
        Vec3::new(0.3, 0.2, 1.1),
        Vec3::new(3.7, 0.4, 1.9),
        Vec3::new(3.6, 3.8, 2.9),
        Vec3::new(0.2, 3.5, 2.2),
    ];
    let opts = PrecomputeOptions::default();
    let boxed = Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/BoxTextured/BoxTextured.glb"),
    )
    .expect("the BoxTextured asset loads");
    assert!(!boxed.textures.is_empty(), "BoxTextured has its texture");
    let (lo, hi) = boxed.bounds().expect("bounds");
    let box_grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), 12).expect("grid");
    let half = GridSpec::new(DVec3::ZERO, 0.5, UVec3::splat(8)).expect("grid");
    let (leaf, texture) = leaf();
    let blend = Material {
        alpha_mode: AlphaMode::Blend,
        base_color: leaf.base_color.truncate().extend(0.7),
        ..leaf.clone()
    };
    let layered_opts = PrecomputeOptions { rays: 300, seed: 7 };
    vec![
        case("box-textured".into(), boxed, box_grid, opts),
        case("leaf-mask".into(), layered(leaf, texture.clone()), half, layered_opts),
        case("leaf-blend".into(), layered(blend, texture), half, layered_opts),
        case("bunny-32".into(), bunny, bunny_grid, opts),
        case("plane-on-face".into(), quad(face, false, Vec3::new(0.7, 0.2, 0.1)), unit, opts),
        case(
            "double-sided".into(),
            quad(tilted, true, Vec3::new(0.1, 0.6, 0.3)),
            unit,
            PrecomputeOptions { rays: 200, seed: 3 },
        ),
    ]
}

/// Random soups in random grids (module docs), `count` cases from `seed`.
pub(super) fn property_cases(count: u32) -> Vec<Case> {
    (0..count)
        .map(|k| {
            let r = |d: u32| rand_f32(0x9E37 + k, 11, d);
            let dims = UVec3::new(
                2 + (r(0) * 6.0) as u32,
                2 + (r(1) * 6.0) as u32,
                2 + (r(2) * 5.0) as u32,
            );
            let size = 0.1 + 1.9 * r(3) as f64;
            let origin = (DVec3::new(r(4) as f64, r(5) as f64, r(6) as f64) - 0.5) * 20.0;
            let grid = GridSpec::new(origin, size, dims).expect("grid");
            let extent = dims.as_vec3() * size as f32;
            let o = origin.as_vec3();
            let tris = 1 + (r(7) * 30.0) as u32;
            let mut positions = Vec::new();
            for t in 0..tris {
                let q = |d: u32| rand_f32(k * 1000 + t, 12, d);
                let centre = o + Vec3::new(q(0), q(1), q(2)) * extent;
                let scale = size as f32 * [0.3, 1.0, 3.0][(t % 3) as usize];
                for v in 0..3 {
                    let mut p = centre
                        + (Vec3::new(q(3 + 3 * v), q(4 + 3 * v), q(5 + 3 * v)) - 0.5) * scale;
                    if t % 4 == 0 {
                        // On a voxel face: axis-aligned triangles at a grid plane.
                        let z = ((centre.z - o.z) / size as f32).round() * size as f32 + o.z;
                        p.z = z;
                    }
                    positions.push(p);
                }
            }
            let normals: Vec<Vec3> = positions
                .chunks(3)
                .flat_map(|p| {
                    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(Vec3::Z);
                    [n, n, n]
                })
                .collect();
            let n = positions.len();
            let half = (tris / 2) as usize * 3;
            let mesh = |range: std::ops::Range<usize>, material| Mesh {
                name: "soup".into(),
                positions: positions[range.clone()].to_vec(),
                normals: normals[range.clone()].to_vec(),
                uvs: vec![Vec2::ZERO; range.len()],
                indices: (0..range.len() as u32 / 3)
                    .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                    .collect(),
                material,
                ..Default::default()
            };
            let mut meshes = vec![mesh(half..n, 1)];
            if half > 0 {
                meshes.insert(0, mesh(0..half, 0));
            }
            let scene = Scene {
                meshes,
                materials: vec![
                    Material { base_color: Vec4::new(0.9, 0.5, 0.1, 1.0), ..Default::default() },
                    Material {
                        base_color: Vec4::new(0.2, 0.3, 0.9, 1.0),
                        double_sided: true,
                        ..Default::default()
                    },
                ],
                ..Default::default()
            };
            let opts =
                PrecomputeOptions { rays: 1 + (r(8) * 200.0) as u32, seed: (r(9) * 1000.0) as u32 };
            case(format!("soup-{k}"), scene, grid, opts)
        })
        .collect()
}
