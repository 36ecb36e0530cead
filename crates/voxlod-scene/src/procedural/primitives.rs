//! Small analytic shapes for tests everywhere: closed boxes and spheres with outward normals, a
//! quad, and the Cornell box. Each shape is a [`Mesh`] with material 0 (wrap one in a scene with
//! [`scene_with`]); [`cornell_box`] is a whole [`Scene`].
//!
//! "Closed" means every edge is shared by exactly two triangles that traverse it in opposite
//! directions, comparing vertex positions bit for bit (faces of a box have their own vertices,
//! for flat normals, but corners are the same `f32` values); the tests check it, and that the
//! signed volume is positive (normals point outward).

use glam::{Vec2, Vec3};

use super::builder::MeshBuilder;
use super::rng::{sin_cos_deg, sin_cos_turns};
use crate::{Camera, Light, Material, Mesh, Scene};

/// Bit mask selecting all six faces in [`MeshBuilder::oriented_box`].
const ALL_FACES: u8 = 0b11_1111;

/// The closed axis-aligned box `[min, max]`: 12 triangles, 24 vertices (flat normals), outward.
pub fn cube(min: Vec3, max: Vec3) -> Mesh {
    oriented_box((min + max) * 0.5, [Vec3::X, Vec3::Y, Vec3::Z], (max - min) * 0.5)
}

/// The closed box `center ± axes[k] · half[k]`: 12 triangles, outward normals. `axes` must be
/// orthonormal and right-handed (`axes[0] × axes[1] = axes[2]`), e.g. [`y_rotation`]'s.
pub fn oriented_box(center: Vec3, axes: [Vec3; 3], half: Vec3) -> Mesh {
    let mut b = MeshBuilder::with_capacity(24, 12, false);
    b.oriented_box(center, axes, half, ALL_FACES);
    b.finish("box", 0)
}

/// The right-handed orthonormal axes of a rotation by `deg` degrees about +y.
pub fn y_rotation(deg: f32) -> [Vec3; 3] {
    let (s, c) = sin_cos_deg(deg);
    [Vec3::new(c, 0.0, -s), Vec3::Y, Vec3::new(s, 0.0, c)]
}

/// A closed UV sphere: `segments ≥ 3` around the y axis, `rings ≥ 2` from pole to pole (one
/// vertex per pole), `2 · segments · (rings − 1)` triangles, smooth outward normals. Smaller
/// counts are raised to these minimums.
pub fn uv_sphere(center: Vec3, radius: f32, segments: u32, rings: u32) -> Mesh {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut b = MeshBuilder::with_capacity(
        (segments * (rings - 1) + 2) as usize,
        (2 * segments * (rings - 1)) as usize,
        false,
    );
    let vertex = |b: &mut MeshBuilder, d: Vec3| b.vertex(center + d * radius, d, Vec2::ZERO);
    let north = vertex(&mut b, Vec3::Y);
    for i in 1..rings {
        // Polar angle i/rings half-turns from +y; azimuth runs so that fans wind outward.
        let (sin_t, cos_t) = sin_cos_turns(i as f32 / (2 * rings) as f32);
        for k in 0..segments {
            let (s, c) = sin_cos_turns(k as f32 / segments as f32);
            vertex(&mut b, Vec3::new(sin_t * c, cos_t, -sin_t * s));
        }
    }
    let south = vertex(&mut b, Vec3::NEG_Y);
    let at = |i: u32, k: u32| 1 + (i - 1) * segments + k % segments;
    for k in 0..segments {
        b.triangle(north, at(1, k), at(1, k + 1));
        b.triangle(south, at(rings - 1, k + 1), at(rings - 1, k));
    }
    for i in 1..rings - 1 {
        for k in 0..segments {
            b.quad(at(i, k), at(i + 1, k), at(i + 1, k + 1), at(i, k + 1));
        }
    }
    b.finish("uv_sphere", 0)
}

/// The largest subdivision level [`icosphere`] accepts (20 · 4⁷ = 327 680 triangles).
pub const MAX_ICOSPHERE_SUBDIVISIONS: u32 = 7;

/// A closed icosphere: the icosahedron with each triangle split into four `subdiv` times (capped
/// at [`MAX_ICOSPHERE_SUBDIVISIONS`]), `20 · 4^subdiv` triangles, vertices shared, on the sphere,
/// smooth outward normals.
pub fn icosphere(center: Vec3, radius: f32, subdiv: u32) -> Mesh {
    let t = (1.0 + 5.0f32.sqrt()) * 0.5;
    let mut dirs: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .map(|(x, y, z)| Vec3::new(x, y, z).normalize())
    .to_vec();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdiv.min(MAX_ICOSPHERE_SUBDIVISIONS) {
        // Midpoints keyed by their (ordered) edge: looked up only, never iterated, so the
        // vertex order depends on the face order alone.
        let mut midpoints = std::collections::HashMap::with_capacity(faces.len() * 3 / 2);
        let mut midpoint = |a: u32, b: u32| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                dirs.push((dirs[a as usize] + dirs[b as usize]).normalize());
                dirs.len() as u32 - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (midpoint(a, b), midpoint(b, c), midpoint(c, a));
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    Mesh {
        name: "icosphere".into(),
        positions: dirs.iter().map(|&d| center + d * radius).collect(),
        normals: dirs,
        uvs: Vec::new(),
        indices: faces,
        material: 0,
        skin: None,
        node: None,
    }
}

/// The parallelogram `corner + [0,1]·u + [0,1]·v` as two triangles facing `u × v`, with UVs.
/// With `back_faces`, two more triangles with their own vertices face the other way, for a
/// single-sided material seen from both sides (a `double_sided` material needs no back faces).
pub fn quad(corner: Vec3, u: Vec3, v: Vec3, back_faces: bool) -> Mesh {
    let mut b = MeshBuilder::with_capacity(8, 4, true);
    b.flat_quad(corner, u, v);
    if back_faces {
        b.flat_quad(corner + u, -u, v);
    }
    b.finish("quad", 0)
}

/// A scene holding one mesh (its material index set to 0) with `material`, the default light
/// and a camera framing it.
pub fn scene_with(name: &str, mut mesh: Mesh, material: Material) -> Scene {
    mesh.material = 0;
    let mut scene = Scene {
        name: name.into(),
        meshes: vec![mesh],
        materials: vec![material],
        lights: vec![Light::default()],
        ..Default::default()
    };
    scene.camera = scene.default_camera().ok();
    scene
}

/// The Cornell box in the unit cube, open toward +z: white floor, ceiling and back wall, red left
/// (x = 0) and green right wall, a short and a tall box (rotated ±17°), a point light under the
/// ceiling and a camera in front. 34 triangles; walls are single quads (large triangles).
pub fn cornell_box() -> Scene {
    let white = Material::diffuse("white", Vec3::new(0.73, 0.73, 0.73));
    let red = Material::diffuse("red", Vec3::new(0.65, 0.05, 0.05));
    let green = Material::diffuse("green", Vec3::new(0.12, 0.45, 0.15));
    let mut walls = MeshBuilder::with_capacity(12, 6, true);
    walls.flat_quad(Vec3::Z, Vec3::X, Vec3::NEG_Z); // floor, facing +y
    walls.flat_quad(Vec3::Y, Vec3::X, Vec3::Z); // ceiling, facing −y
    walls.flat_quad(Vec3::ZERO, Vec3::X, Vec3::Y); // back, facing +z
    let mut left = MeshBuilder::with_capacity(4, 2, true);
    left.flat_quad(Vec3::Z, Vec3::NEG_Z, Vec3::Y); // facing +x
    let mut right = MeshBuilder::with_capacity(4, 2, true);
    right.flat_quad(Vec3::X, Vec3::Z, Vec3::Y); // facing −x
    let mut boxes = MeshBuilder::with_capacity(48, 24, false);
    let (short, tall) = (Vec3::splat(0.15), Vec3::new(0.15, 0.3, 0.15));
    boxes.oriented_box(Vec3::new(0.68, 0.15, 0.62), y_rotation(-17.0), short, ALL_FACES);
    boxes.oriented_box(Vec3::new(0.33, 0.3, 0.36), y_rotation(17.0), tall, ALL_FACES);
    Scene {
        name: "cornell".into(),
        meshes: vec![
            walls.finish("cornell/walls", 0),
            boxes.finish("cornell/boxes", 0),
            left.finish("cornell/left", 1),
            right.finish("cornell/right", 2),
        ],
        materials: vec![white, red, green],
        camera: Some(Camera::look_at(
            Vec3::new(0.5, 0.5, 2.35),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::Y,
            38.0,
        )),
        lights: vec![Light::Point {
            position: Vec3::new(0.5, 0.95, 0.55),
            intensity: Vec3::new(1.7, 1.6, 1.4),
        }],
        background: Vec3::ZERO,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{check_closed, signed_volume};
    use super::*;

    #[test]
    fn closed_shapes_are_closed_outward_and_have_the_right_volume() {
        let cube = cube(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 2.5));
        assert_eq!(cube.triangle_count(), 12);
        check_closed(&cube).unwrap();
        let v = signed_volume(&cube);
        assert!((v - 3.0).abs() < 1e-5, "cube volume {v}");
        let r = 0.75f64;
        let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        for subdiv in 0..=3 {
            let s = icosphere(Vec3::new(0.3, -2.0, 1.0), r as f32, subdiv);
            assert_eq!(s.triangle_count(), 20 * 4usize.pow(subdiv));
            check_closed(&s).unwrap();
            let v = signed_volume(&s);
            // An inscribed polyhedron: positive, below the sphere, converging to it.
            assert!(v > 0.6 * exact && v < exact, "subdiv {subdiv}: {v} vs {exact}");
            if subdiv == 3 {
                assert!(v > 0.98 * exact, "{v}");
            }
        }
        for (segments, rings) in [(3, 2), (4, 3), (24, 12)] {
            let s = uv_sphere(Vec3::ONE, r as f32, segments, rings);
            assert_eq!(s.triangle_count() as u32, 2 * segments * (rings - 1));
            check_closed(&s).unwrap();
            assert!(signed_volume(&s) > 0.0);
        }
        let s = uv_sphere(Vec3::ZERO, 1.0, 48, 24);
        assert!((signed_volume(&s) / (4.0 / 3.0 * std::f64::consts::PI) - 1.0).abs() < 0.02);
    }

    #[test]
    fn normals_agree_with_the_winding() {
        let meshes = [
            cube(Vec3::ZERO, Vec3::ONE),
            oriented_box(Vec3::ONE, y_rotation(33.0), Vec3::new(0.1, 0.2, 0.3)),
            icosphere(Vec3::ZERO, 2.0, 2),
            uv_sphere(Vec3::ZERO, 2.0, 8, 5),
            quad(Vec3::ZERO, Vec3::X, Vec3::Z, true),
        ];
        for m in &meshes {
            scene_with("t", m.clone(), Material::default()).validate().unwrap();
            for t in 0..m.triangle_count() {
                let [a, b, c] = m.triangle(t);
                let face = (b - a).cross(c - a).normalize();
                let n: Vec3 = m.indices[t].iter().map(|&i| m.normals[i as usize]).sum();
                assert!(face.dot(n.normalize()) > 0.5, "{} triangle {t}", m.name);
            }
        }
        // The quad faces u × v (−y here), its back faces +y.
        let q = &meshes[4];
        assert_eq!(q.normals[0], Vec3::NEG_Y);
        assert_eq!(q.normals[4], Vec3::Y);
        assert_eq!(quad(Vec3::ZERO, Vec3::X, Vec3::Y, false).triangle_count(), 2);
    }

    #[test]
    fn cornell_box_is_valid_and_its_boxes_are_closed() {
        let s = cornell_box();
        s.validate().unwrap();
        assert_eq!(s.triangle_count(), 34);
        check_closed(&s.meshes[1]).unwrap();
        let v = signed_volume(&s.meshes[1]);
        assert!((v - (0.3f64.powi(3) + 0.3 * 0.6 * 0.3)).abs() < 1e-5, "{v}");
        let (lo, hi) = s.bounds().unwrap();
        assert!(lo.cmpge(Vec3::ZERO).all() && hi.cmple(Vec3::ONE).all(), "{lo} {hi}");
    }
}
