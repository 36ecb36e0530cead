//! Small hand-built meshes and scenes for the ray-casting and renderer tests (test builds only).

use glam::{Vec2, Vec3};
use voxlod_scene::{Camera, Geometry, Light, Material, Mesh, Scene};

/// A mesh from triangles given by their corners, with flat normals and UVs `(0,0), (1,0),
/// (0,1)` per triangle.
pub(crate) fn soup(name: &str, tris: &[[Vec3; 3]], material: usize) -> Mesh {
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    for t in tris {
        let base = m.positions.len() as u32;
        let n = (t[1] - t[0]).cross(t[2] - t[0]).try_normalize().unwrap_or(Vec3::Z);
        m.positions.extend_from_slice(t);
        m.normals.extend([n; 3]);
        m.uvs.extend([Vec2::ZERO, Vec2::X, Vec2::Y]);
        m.indices.push([base, base + 1, base + 2]);
    }
    m
}

/// A quad `corner + s·a + t·b` for `s, t ∈ [0, 1]`, front face toward `a × b`, UV `(s, t)`.
pub(crate) fn quad(name: &str, corner: Vec3, a: Vec3, b: Vec3, material: usize) -> Mesh {
    let n = a.cross(b).normalize();
    Mesh {
        name: name.into(),
        positions: vec![corner, corner + a, corner + a + b, corner + b],
        normals: vec![n; 4],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material,
        skin: None,
        node: None,
    }
}

/// An axis-aligned box `[lo, hi]` with flat faces (24 vertices), outward normals.
pub(crate) fn cuboid(name: &str, lo: Vec3, hi: Vec3, material: usize) -> Mesh {
    let e = hi - lo;
    let faces = [
        (Vec3::new(hi.x, lo.y, hi.z), Vec3::NEG_Z * e.z, Vec3::Y * e.y), // +x
        (lo, Vec3::Z * e.z, Vec3::Y * e.y),                              // −x
        (Vec3::new(lo.x, hi.y, hi.z), Vec3::X * e.x, Vec3::NEG_Z * e.z), // +y
        (lo, Vec3::X * e.x, Vec3::Z * e.z),                              // −y
        (Vec3::new(lo.x, lo.y, hi.z), Vec3::X * e.x, Vec3::Y * e.y),     // +z
        (Vec3::new(hi.x, lo.y, lo.z), Vec3::NEG_X * e.x, Vec3::Y * e.y), // −z
    ];
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    for (corner, a, b) in faces {
        let q = quad(name, corner, a, b, material);
        let base = m.positions.len() as u32;
        m.positions.extend(q.positions);
        m.normals.extend(q.normals);
        m.uvs.extend(q.uvs);
        m.indices.extend(q.indices.iter().map(|t| t.map(|i| i + base)));
    }
    m
}

/// An icosphere subdivided `levels` times (20·4^levels triangles), closed, with shared
/// vertices and smooth normals: the scene crate's primitive, renamed.
pub(crate) fn icosphere(name: &str, levels: u32, center: Vec3, radius: f32) -> Mesh {
    let mut m = voxlod_scene::procedural::primitives::icosphere(center, radius, levels);
    m.name = name.into();
    m
}

/// A scene of `meshes` with `materials`, a directional light and black background.
pub(crate) fn scene(meshes: Vec<Mesh>, materials: Vec<Material>, light: Light) -> Scene {
    Scene {
        name: "test".into(),
        meshes,
        materials,
        lights: vec![light],
        background: Vec3::ZERO,
        ..Default::default()
    }
}

/// A directional light toward `to_light` with irradiance `e` in every channel.
pub(crate) fn sun(to_light: Vec3, e: f32) -> Light {
    Light::Directional { to_light: to_light.normalize(), irradiance: Vec3::splat(e) }
}

/// A camera at `eye` looking at `target` with a 40° vertical field of view.
pub(crate) fn camera(eye: Vec3, target: Vec3) -> Camera {
    let up = if (target - eye).normalize().y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    Camera::look_at(eye, target, up, 40.0)
}

/// A geometry made of one mesh (material 0).
pub(crate) fn geometry(mesh: Mesh) -> Geometry {
    scene(vec![mesh], vec![Material::default()], sun(Vec3::Y, 1.0)).geometry()
}
