//! Building an object's [`VoxelCache`] from its meshes ([`build_cache`]), and the records of a
//! voxelization ([`voxel_records`]): Averages by ray sampling, or fragment averages over the
//! voxel's triangle pieces.

use glam::{DVec3, UVec3};
use rayon::prelude::*;
use voxlod_format::records::{AverageRecord, SkinnedRecord, VoxelSkin};
use voxlod_format::{BrickMap, GridSpec};
use voxlod_octree::dynamic::{MAX_CACHE_DIM, VoxelCache};
use voxlod_scene::{Geometry, Scene};

use super::pieces::{barycentric, clip};
use super::scene::{DynamicScene, ObjectKind, bounds};
use crate::appearance::averages;
use crate::appearance::line_sampler::SamplingContext;
use crate::appearance::precompute::{PrecomputeOptions, precompute};
use crate::voxelize::{self, Mode, Voxelization};
use crate::{Error, Result};

/// Where a voxel's Averages record comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RecordSource {
    /// The Averages fit of `rays` lines sampled through the voxel (voxlod-cpu's appearance
    /// precompute): opacity = occluded lines / lines. A voxel no line hits from outside gets no
    /// record (and is dropped).
    Rays {
        /// Lines per voxel.
        rays: u32,
        /// Their seed.
        seed: u32,
    },
    /// Fragment averages, what a rasterizing voxelizer computes: the mean albedo and normal of
    /// the voxel's triangle pieces at their centroids, weighted by the pieces' areas, and
    /// opacity 1. Cheap enough to run every frame.
    Pieces,
}

impl Default for RecordSource {
    fn default() -> Self {
        Self::Rays { rays: 32, seed: 0 }
    }
}

/// How an object's cache is built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheOptions {
    /// The voxelizer (conservative by default; thin for the paper's 6-separating surfaces).
    pub mode: Mode,
    /// Where the records come from.
    pub records: RecordSource,
}

/// The area-weighted pieces of voxel `index`'s triangles: `(triangle, area, centroid)`; when all
/// pieces have zero area (degenerate triangles), each gets area 1. The voxelizer decides
/// overlap on vertices snapped to its lattice, so a triangle it lists may miss the exact box by
/// a hair: then the box grown by a thousandth of a voxel is tried, and failing that each listed
/// triangle counts once at its point nearest the voxel's centre (its clamped barycentric
/// projection).
fn voxel_pieces(geometry: &Geometry, vox: &Voxelization, index: usize) -> Vec<(u32, f64, DVec3)> {
    let c = vox.voxels.coord_of(index);
    let size = vox.grid.voxel_size;
    let lo = vox.grid.voxel_min(c);
    let hi = lo + DVec3::splat(size);
    let tris = vox.triangles_of(index);
    let clip_all = |grow: f64| -> Vec<(u32, f64, DVec3)> {
        tris.iter()
            .filter_map(|&t| {
                let tri = geometry.triangle(t as usize).map(|p| p.as_dvec3());
                clip(tri, lo - grow, hi + grow).map(|p| (t, p.area, p.centroid))
            })
            .collect()
    };
    let mut out = clip_all(0.0);
    if out.is_empty() {
        out = clip_all(1e-3 * size);
    }
    if out.is_empty() {
        let centre = lo + DVec3::splat(0.5 * size);
        out = tris
            .iter()
            .map(|&t| {
                let tri = geometry.triangle(t as usize).map(|p| p.as_dvec3());
                let b = barycentric(tri, centre);
                (t, 1.0, tri[0] * b[0] + tri[1] * b[1] + tri[2] * b[2])
            })
            .collect();
    }
    if out.iter().all(|p| p.1 <= 0.0) {
        out.iter_mut().for_each(|p| p.1 = 1.0);
    }
    out
}

/// Fragment averages of every voxel of `vox` ([`RecordSource::Pieces`]).
pub fn fragment_records(
    scene: &Scene,
    geometry: &Geometry,
    vox: &Voxelization,
) -> Result<BrickMap<AverageRecord>> {
    if vox.triangles.is_empty() && !vox.voxels.is_empty() {
        return Err(Error::InvalidParameter {
            name: "voxelization",
            value: format!("{} voxels without triangle lists", vox.voxels.len()),
            reason: "fragment averages need triangle lists".into(),
        });
    }
    crate::render::surface::check_geometry(scene, geometry)?;
    let records: Vec<AverageRecord> = (0..vox.voxels.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            let (mut area, mut albedo, mut normal) = (0.0f64, DVec3::ZERO, DVec3::ZERO);
            for (t, a, centroid) in voxel_pieces(geometry, vox, i) {
                let tri = geometry.triangle(t as usize).map(|p| p.as_dvec3());
                let b = barycentric(tri, centroid);
                let (n, uv) = geometry.interpolate(t as usize, b[1] as f32, b[2] as f32);
                let m = scene.material_sample(geometry.materials[t as usize], uv);
                area += a;
                albedo += m.albedo.as_dvec3() * a;
                normal += n.as_dvec3() * a;
            }
            let n = normal.normalize_or_zero().as_vec3();
            AverageRecord::new((albedo / area.max(f64::MIN_POSITIVE)).as_vec3(), n, 1.0)
        })
        .collect();
    Ok(vox.voxels.with_values(records)?)
}

/// The Averages records of a voxelization from `source` (voxels without a record dropped).
pub fn voxel_records(
    scene: &Scene,
    geometry: &Geometry,
    vox: &Voxelization,
    source: RecordSource,
) -> Result<BrickMap<AverageRecord>> {
    match source {
        RecordSource::Pieces => fragment_records(scene, geometry, vox),
        RecordSource::Rays { rays, seed } => {
            let ctx = SamplingContext::new(scene, geometry, vox)?;
            Ok(precompute(&ctx, &PrecomputeOptions { rays, seed }, averages::fit)?.records)
        }
    }
}

/// The skin of every voxel at `coords` of `vox` (module docs of the parent: the vertex weights
/// of the voxel's triangles interpolated at its pieces' centroids, weighted by the pieces'
/// areas, the four largest kept and renormalized). `influences` has one entry per vertex of
/// `geometry`.
pub fn voxel_skins(
    geometry: &Geometry,
    influences: &[([u16; 4], [f32; 4])],
    vox: &Voxelization,
    coords: &[UVec3],
) -> Result<Vec<VoxelSkin>> {
    coords
        .par_iter()
        .map(|&c| {
            let index = vox.voxels.index_of(c).ok_or_else(|| Error::InvalidParameter {
                name: "voxel",
                value: c.to_string(),
                reason: "not in the voxelization".into(),
            })?;
            let mut acc: Vec<(u32, f32)> = Vec::new();
            for (t, area, centroid) in voxel_pieces(geometry, vox, index) {
                let tri_v = geometry.indices[t as usize];
                let tri = tri_v.map(|v| geometry.positions[v as usize].as_dvec3());
                let b = barycentric(tri, centroid);
                for (corner, &v) in tri_v.iter().enumerate() {
                    let (j, w) = influences[v as usize];
                    for k in 0..4 {
                        if w[k] > 0.0 {
                            acc.push((j[k] as u32, (area * b[corner] * w[k] as f64) as f32));
                        }
                    }
                }
            }
            VoxelSkin::from_influences(&acc).ok_or_else(|| Error::Dynamic {
                object: format!("voxel {c}"),
                reason: format!(
                    "its interpolated joint weights cannot be normalized (zero sum or a joint ≥ {})",
                    VoxelSkin::MAX_JOINTS
                ),
            })
        })
        .collect()
}

/// Voxelizes object `object` of `ds` once, in its own space, at the world voxel size
/// `world_voxel` (so a cached voxel is a world voxel), with `options`: the object grid starts
/// half a voxel below the corner of its bounds and ends at least half a voxel past the other
/// corner, at most [`MAX_CACHE_DIM`] voxels per axis.
pub fn build_cache(
    ds: &DynamicScene,
    object: usize,
    world_voxel: f64,
    options: &CacheOptions,
) -> Result<VoxelCache> {
    let o = ds.objects.get(object).ok_or_else(|| Error::InvalidParameter {
        name: "object",
        value: object.to_string(),
        reason: format!("the scene has {} moving objects", ds.objects.len()),
    })?;
    if !(world_voxel.is_finite() && world_voxel > 0.0) {
        return Err(Error::InvalidParameter {
            name: "world_voxel",
            value: world_voxel.to_string(),
            reason: "a positive finite voxel size".into(),
        });
    }
    let (geometry, scale) = ds.object_geometry(o)?;
    let (lo, hi) = bounds(&geometry)
        .ok_or_else(|| Error::Dynamic { object: o.name.clone(), reason: "no triangles".into() })?;
    let dxo = world_voxel / scale;
    // Half a voxel of margin: faces at the bounds lie inside voxels, not on grid faces, where
    // the conservative tie rule would set one side only.
    let lo = lo - DVec3::splat(0.5 * dxo);
    let dims = ((hi - lo) / dxo + 0.5).floor() + 1.0;
    if dims.max_element() > MAX_CACHE_DIM as f64 {
        return Err(voxlod_octree::Error::CacheTooLarge {
            object: o.name.clone(),
            dims: [dims.x as u64, dims.y as u64, dims.z as u64],
            max: MAX_CACHE_DIM,
        }
        .into());
    }
    let grid = GridSpec::new(lo, dxo, dims.as_uvec3())?;
    let vopts =
        voxelize::Options { mode: options.mode, triangle_lists: true, ..Default::default() };
    let vox = voxelize::voxelize(&geometry, &grid, &vopts)?;
    let records = voxel_records(&ds.scene, &geometry, &vox, options.records)?;
    match o.kind {
        ObjectKind::Rigid { .. } => Ok(VoxelCache::rigid(&o.name, grid, scale, &records)?),
        ObjectKind::Skinned { skin } => {
            let joints = ds.scene.skins[skin].joints.len();
            if joints as u32 > VoxelSkin::MAX_JOINTS {
                return Err(Error::Dynamic {
                    object: o.name.clone(),
                    reason: format!(
                        "its skin has {joints} joints; cached voxels index at most {}",
                        VoxelSkin::MAX_JOINTS
                    ),
                });
            }
            let coords: Vec<UVec3> = records.coords().collect();
            let influences = ds.object_skin(o);
            let skins =
                voxel_skins(&geometry, &influences, &vox, &coords).map_err(|e| match e {
                    Error::Dynamic { object, reason } => Error::Dynamic {
                        object: o.name.clone(),
                        reason: format!("{object}: {reason}"),
                    },
                    other => other,
                })?;
            let map = records.with_values(
                records
                    .values()
                    .iter()
                    .zip(skins)
                    .map(|(&average, skin)| SkinnedRecord { average, skin })
                    .collect(),
            )?;
            Ok(VoxelCache::skinned(&o.name, grid, scale, skin, joints as u32, &map)?)
        }
    }
}

/// The world voxels of the static meshes of `ds` in `grid`, with their records.
pub fn static_voxels(
    ds: &DynamicScene,
    grid: &GridSpec,
    options: &CacheOptions,
) -> Result<Vec<(UVec3, AverageRecord)>> {
    let geometry = ds.static_geometry();
    if geometry.indices.is_empty() {
        return Ok(Vec::new());
    }
    let vopts =
        voxelize::Options { mode: options.mode, triangle_lists: true, ..Default::default() };
    let vox = voxelize::voxelize(&geometry, grid, &vopts)?;
    let records = voxel_records(&ds.scene, &geometry, &vox, options.records)?;
    Ok(records.iter().map(|(c, r)| (c, *r)).collect())
}
