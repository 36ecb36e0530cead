//! Host-side preparation: each voxel's triangles set up in voxel-local coordinates in `f64`,
//! exactly as the CPU sampler sets them up, then rounded to the kernel's `f32` records.

use glam::{DVec3, Vec3};
use voxlod_cpu::appearance::line_sampler::SamplingContext;
use voxlod_scene::{AlphaMode, Geometry, Scene};

use super::params::{ALPHA_FLAG, GpuLocalTri, GpuVoxel};
use crate::{Error, Result};

/// The kernel's voxels and their local triangles, set up as the CPU sampler's
/// `load_triangles` does (in `f64` from the grid's origin and voxel size, then rounded), with
/// [`ALPHA_FLAG`] on triangles of `scene`'s non-`Opaque` materials.
pub fn prepare(
    sampling: &SamplingContext,
    scene: &Scene,
    geometry: &Geometry,
) -> Result<(Vec<GpuVoxel>, Vec<GpuLocalTri>)> {
    let alpha: Vec<bool> =
        scene.materials.iter().map(|m| m.alpha_mode != AlphaMode::Opaque).collect();
    let vox = sampling.voxelization();
    let grid = sampling.grid();
    let inv = 1.0 / grid.voxel_size;
    let mut voxels = Vec::with_capacity(sampling.voxel_count());
    let mut tris = Vec::new();
    for i in 0..sampling.voxel_count() {
        let min = grid.voxel_min(sampling.coord(i));
        let local = |p: Vec3| (p.as_dvec3() - min) * inv;
        let first = tris.len();
        for &t in vox.triangles_of(i) {
            let [a, b, c] = geometry.triangle(t as usize);
            let (la, lb, lc) = (local(a), local(b), local(c));
            let (e1, e2) = (lb - la, lc - la);
            let big_n = e1.cross(e2);
            let area2 = big_n.length_squared();
            if area2.is_nan() || area2 <= 0.0 {
                continue; // degenerate: never hit
            }
            let bu = e2.cross(big_n) / area2;
            let bv = big_n.cross(e1) / area2;
            let n = big_n / area2.sqrt();
            let (fa, fb, fc) = (la.as_vec3(), lb.as_vec3(), lc.as_vec3());
            let mut flat =
                (0..3).filter(|&j| fa[j] == fb[j] && fa[j] == fc[j]).fold(0u32, |m, j| m | 1 << j);
            // Indices checked by SamplingContext::new.
            if alpha[geometry.materials[t as usize] as usize] {
                flat |= ALPHA_FLAG;
            }
            let w = |v: DVec3, w: f32| v.as_vec3().extend(w).to_array();
            tris.push(GpuLocalTri {
                a: fa.extend(f32::from_bits(flat)).to_array(),
                n: w(n, n.dot(la) as f32),
                bu: w(bu, -bu.dot(la) as f32),
                bv: w(bv, -bv.dot(la) as f32),
                ng: (b - a).cross(c - a).extend(f32::from_bits(t)).to_array(),
            });
        }
        let count = tris.len() - first;
        if first > u32::MAX as usize || count > u32::MAX as usize {
            return Err(Error::TooLarge {
                what: "(voxel, triangle) pairs (32-bit indices)",
                requested: tris.len() as u64,
                limit: u32::MAX as u64,
            });
        }
        voxels.push(GpuVoxel {
            first: first as u32,
            count: count as u32,
            id: sampling.voxel_id(i),
            pad: 0,
        });
    }
    Ok((voxels, tris))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `prepare` flags the triangles of non-`Opaque` materials (their hits pass the alpha
    /// test in the kernel) next to the flat-axis bits, and no others.
    #[test]
    fn prepare_flags_the_triangles_whose_alpha_filters_hits() {
        use voxlod_cpu::voxelize::{Options, voxelize};
        use voxlod_format::GridSpec;
        use voxlod_scene::{Material, Mesh};
        let tri = |z: f32, material| Mesh {
            name: "t".into(),
            positions: vec![Vec3::new(0.1, 0.1, z), Vec3::new(0.9, 0.1, z), Vec3::new(0.1, 0.9, z)],
            normals: vec![Vec3::Z; 3],
            uvs: vec![glam::Vec2::ZERO; 3],
            indices: vec![[0, 1, 2]],
            material,
            ..Default::default()
        };
        let blend = Material { alpha_mode: AlphaMode::Blend, ..Default::default() };
        let scene = Scene {
            meshes: vec![tri(0.3, 0), tri(0.6, 1)],
            materials: vec![Material::default(), blend],
            ..Default::default()
        };
        let geometry = scene.geometry();
        let grid = GridSpec::new(DVec3::ZERO, 1.0, glam::UVec3::ONE).unwrap();
        let vox = voxelize(&geometry, &grid, &Options::default()).unwrap();
        let sampling = SamplingContext::new(&scene, &geometry, &vox).unwrap();
        let (_, tris) = prepare(&sampling, &scene, &geometry).unwrap();
        let flags: Vec<u32> = tris.iter().map(|t| t.a[3].to_bits()).collect();
        // Both lie in a z plane (flat-axis bit 2); only the blended one is alpha-filtered.
        assert_eq!(flags, [4, 4 | ALPHA_FLAG]);
    }
}
