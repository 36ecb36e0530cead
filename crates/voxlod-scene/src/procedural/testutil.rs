//! Test helpers shared by the procedural modules: an order-sensitive hash of a scene's bits, the
//! closedness check (every edge used once in each direction, positions compared bit for bit),
//! the signed volume, and the heavy-test switch.

use std::collections::BTreeMap;

use crate::{Mesh, Scene};

/// Whether the heavy tests (million-triangle scenes) should run: `VOXLOD_HEAVY_TESTS=1`.
pub fn heavy_tests() -> bool {
    std::env::var("VOXLOD_HEAVY_TESTS").is_ok_and(|v| !v.is_empty() && v != "0")
}

/// FNV-1a over every bit of the geometry (positions, normals, UVs, indices, material indices)
/// and the debug form of materials, camera, lights and background.
pub fn scene_hash(scene: &Scene) -> u64 {
    let mut h = 0xCBF2_9CE4_8422_2325u64;
    let mut eat = |x: u32| {
        for b in x.to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0100_0000_01B3);
        }
    };
    for m in &scene.meshes {
        eat(m.positions.len() as u32);
        eat(m.material as u32);
        for v in m.positions.iter().chain(&m.normals) {
            v.to_array().iter().for_each(|c| eat(c.to_bits()));
        }
        for uv in &m.uvs {
            uv.to_array().iter().for_each(|c| eat(c.to_bits()));
        }
        for t in &m.indices {
            t.iter().for_each(|&i| eat(i));
        }
    }
    let extra = format!(
        "{:?}{:?}{:?}{:?}{:?}",
        scene.materials, scene.textures, scene.camera, scene.lights, scene.background
    );
    for b in extra.bytes() {
        eat(b as u32);
    }
    h
}

/// Checks that `mesh` is closed and consistently oriented: every directed edge (by position
/// bits) occurs exactly once and its reverse occurs exactly once.
pub fn check_closed(mesh: &Mesh) -> Result<(), String> {
    let key = |i: u32| mesh.positions[i as usize].to_array().map(f32::to_bits);
    let mut edges = BTreeMap::new();
    for t in &mesh.indices {
        for e in 0..3 {
            *edges.entry((key(t[e]), key(t[(e + 1) % 3]))).or_insert(0u32) += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        let back = edges.get(&(b, a)).copied().unwrap_or(0);
        if n != 1 || back != 1 {
            return Err(format!(
                "{}: edge {a:?} → {b:?} used {n} times, its reverse {back} times",
                mesh.name
            ));
        }
    }
    Ok(())
}

/// Signed volume of a closed mesh (positive when triangles wind counter-clockwise seen from
/// outside), by the divergence theorem in f64.
pub fn signed_volume(mesh: &Mesh) -> f64 {
    (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}
