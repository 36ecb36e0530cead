//! The baseline's per-voxel record, [`BaselineVoxel`], and [`build`], which computes it from a
//! voxelization's triangle lists.
//!
//! # The average colour of a voxel
//! The mean albedo of the surface inside the voxel, weighted by area and coverage:
//! each triangle of the voxel's list is clipped to the voxel's closed box (Sutherland–Hodgman,
//! in `f64`, in voxel-local coordinates); the clipped polygon is fanned into triangles, and
//! each fan triangle is sampled at the 4 centroids of its midpoint subdivision, each standing
//! for a quarter of its area. At each sample the material is evaluated at the interpolated UV
//! (bilinear texture), and the sample weighs `area · alpha` (alpha 1 for opaque materials,
//! 0 or 1 after the cutoff for masked ones, the alpha value for blended ones).
//!
//! Fallbacks, in order: if every weight is 0 (everything masked out), the area alone weighs;
//! if the clipped area is 0 too (triangles only touching the voxel's boundary along an edge or
//! corner), each listed triangle's albedo at its centroid counts equally; a voxel with an empty
//! list (the interior of a solid voxelization, never visible from outside) gets
//! [`INTERIOR_ALBEDO`]. Specular colour is not kept: the baseline is diffuse.

use bytemuck::{Pod, Zeroable};
use glam::{DVec2, DVec3, UVec3, Vec3};
use rayon::prelude::*;
use voxlod_format::BrickMap;
use voxlod_scene::texture::{linear_to_srgb, srgb_to_linear_table};
use voxlod_scene::{Geometry, Scene};

use crate::render::surface::check_geometry;
use crate::voxelize::Voxelization;
use crate::{Error, Result};

/// Albedo of voxels whose triangle list is empty (solid interiors): linear mid-grey.
pub const INTERIOR_ALBEDO: f32 = 0.5;

/// One voxel of the baseline: an opaque cube of one diffuse colour. 4 bytes per voxel:
/// the mean albedo quantized to 8-bit sRGB (what the metrics see, so the quantization costs
/// less than the 8-bit output already does), plus a zero byte that aligns the record to a
/// `u32` for GPU buffers (`unpack4x8unorm` in WGSL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
#[repr(C)]
pub struct BaselineVoxel {
    /// Mean albedo, sRGB-encoded bytes.
    pub albedo_srgb: [u8; 3],
    /// Zero.
    pub _pad: u8,
}

impl BaselineVoxel {
    /// Encodes a linear albedo (clamped to [0, 1], rounded to the nearest byte).
    pub fn from_linear(albedo: Vec3) -> Self {
        let enc = |c: f32| (linear_to_srgb(c) * 255.0 + 0.5) as u8;
        Self { albedo_srgb: [enc(albedo.x), enc(albedo.y), enc(albedo.z)], _pad: 0 }
    }

    /// The linear albedo.
    #[inline]
    pub fn albedo(&self) -> Vec3 {
        let lut = srgb_to_linear_table();
        Vec3::from_array(self.albedo_srgb.map(|c| lut[c as usize]))
    }
}

/// Computes every occupied voxel's [`BaselineVoxel`] (see the module docs), in parallel.
///
/// Errors when the voxelization kept no triangle lists, refers to triangles the geometry does
/// not have, or the geometry's attributes or materials do not match the scene.
pub fn build(
    scene: &Scene,
    geometry: &Geometry,
    voxelization: &Voxelization,
) -> Result<BrickMap<BaselineVoxel>> {
    check_geometry(scene, geometry)?;
    let v = voxelization;
    if v.voxels.dims() != v.grid.dims {
        return Err(Error::InvalidParameter {
            name: "voxelization",
            value: format!("brick map of {} voxels", v.voxels.dims()),
            reason: format!("its grid has {} voxels", v.grid.dims),
        });
    }
    if v.triangles.is_empty() && !v.voxels.is_empty() {
        return Err(Error::InvalidParameter {
            name: "voxelization",
            value: format!("{} voxels without triangle lists", v.voxels.len()),
            reason: "the baseline needs triangle lists (voxelize with triangle_lists: true)".into(),
        });
    }
    let n = geometry.triangle_count();
    if let Some(&t) = v.triangles.iter().find(|&&t| t as usize >= n) {
        return Err(Error::InvalidParameter {
            name: "voxelization",
            value: format!("triangle {t}"),
            reason: format!("the geometry has {n} triangles"),
        });
    }
    if let Some(r) = v
        .voxels
        .values()
        .iter()
        .find(|r| r.first as u64 + r.count as u64 > v.triangles.len() as u64)
    {
        return Err(Error::InvalidParameter {
            name: "voxelization",
            value: format!("triangle range {r:?}"),
            reason: format!("the list holds {} entries", v.triangles.len()),
        });
    }
    let coords: Vec<UVec3> = v.voxels.coords().collect();
    let size = v.grid.voxel_size;
    let values: Vec<BaselineVoxel> = coords
        .par_iter()
        .enumerate()
        .map(|(i, &c)| {
            let min = v.grid.voxel_min(c);
            BaselineVoxel::from_linear(mean_albedo(scene, geometry, v.triangles_of(i), min, size))
        })
        .collect();
    Ok(v.voxels.with_values(values)?)
}

/// A polygon vertex: voxel-local position and barycentrics `(u, v)` on its triangle.
#[derive(Clone, Copy, Debug, Default)]
struct PolyVertex {
    p: DVec3,
    b: DVec2,
}

/// The most vertices a triangle clipped by 6 planes can have.
const MAX_POLY: usize = 9;

/// The mean albedo of `triangles` inside the voxel whose min corner is `min` (see the module
/// docs).
fn mean_albedo(scene: &Scene, g: &Geometry, triangles: &[u32], min: DVec3, size: f64) -> Vec3 {
    if triangles.is_empty() {
        return Vec3::splat(INTERIOR_ALBEDO);
    }
    let (mut weighted, mut weight) = (Vec3::ZERO, 0.0f64);
    let (mut by_area, mut area) = (Vec3::ZERO, 0.0f64);
    let mut at_centroids = Vec3::ZERO;
    for &t in triangles {
        let ti = t as usize;
        let material = g.materials[ti];
        let [u0, u1, u2] = g.indices[ti].map(|i| g.uvs[i as usize]);
        let sample = |b: DVec2| {
            let uv = u0 * (1.0 - b.x - b.y) as f32 + u1 * b.x as f32 + u2 * b.y as f32;
            scene.material_sample(material, uv)
        };
        at_centroids += sample(DVec2::splat(1.0 / 3.0)).albedo;
        let corners = g.triangle(ti).map(|p| (p.as_dvec3() - min) / size);
        let (poly, len) = clip_to_unit_box(corners);
        for k in 1..len.saturating_sub(1) {
            let (a, b, c) = (poly[0], poly[k], poly[k + 1]);
            let fan_area = 0.5 * (b.p - a.p).cross(c.p - a.p).length();
            if fan_area <= 0.0 {
                continue;
            }
            // Centroids of the 4 children of the midpoint subdivision.
            for w in [[4.0, 1.0, 1.0], [1.0, 4.0, 1.0], [1.0, 1.0, 4.0], [2.0, 2.0, 2.0]] {
                let bary = (a.b * w[0] + b.b * w[1] + c.b * w[2]) / 6.0;
                let m = sample(bary);
                let quarter = fan_area * 0.25;
                weighted += m.albedo * (quarter * m.alpha as f64) as f32;
                weight += quarter * m.alpha as f64;
                by_area += m.albedo * quarter as f32;
                area += quarter;
            }
        }
    }
    if weight > 0.0 {
        weighted / weight as f32
    } else if area > 0.0 {
        by_area / area as f32
    } else {
        at_centroids / triangles.len() as f32
    }
}

/// Clips the triangle `corners` (voxel-local) to the closed unit box, carrying barycentrics.
fn clip_to_unit_box(corners: [DVec3; 3]) -> ([PolyVertex; MAX_POLY], usize) {
    let mut poly = [PolyVertex::default(); MAX_POLY];
    let bary = [DVec2::ZERO, DVec2::X, DVec2::Y];
    for i in 0..3 {
        poly[i] = PolyVertex { p: corners[i], b: bary[i] };
    }
    let mut len = 3;
    for axis in 0..3 {
        for (side, bound) in [(1.0, 0.0), (-1.0, 1.0)] {
            // Keep side · (p[axis] − bound) ≥ 0.
            let dist = |v: &PolyVertex| side * (v.p[axis] - bound);
            let mut out = [PolyVertex::default(); MAX_POLY];
            let mut n = 0;
            for i in 0..len {
                let (cur, next) = (poly[i], poly[(i + 1) % len]);
                let (dc, dn) = (dist(&cur), dist(&next));
                if dc >= 0.0 && n < MAX_POLY {
                    out[n] = cur;
                    n += 1;
                }
                if (dc >= 0.0) != (dn >= 0.0) && n < MAX_POLY {
                    let s = dc / (dc - dn);
                    out[n] = PolyVertex { p: cur.p.lerp(next.p, s), b: cur.b.lerp(next.b, s) };
                    n += 1;
                }
            }
            poly = out;
            len = n;
            if len < 3 {
                return (poly, 0);
            }
        }
    }
    (poly, len)
}
