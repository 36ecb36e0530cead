//! Re-voxelizing the posed moving meshes into the world grid: what voxel transformation
//! replaces, and the reference it is measured against.

use voxlod_format::BrickMap;
use voxlod_format::GridSpec;
use voxlod_format::records::AverageRecord;
use voxlod_scene::{Geometry, Scene};

use super::cache::{RecordSource, voxel_records};
use crate::Result;
use crate::voxelize::{self, Mode, Voxelization};

/// The meshes `meshes` of `scene` as one geometry.
pub fn geometry_of(scene: &Scene, meshes: &[usize]) -> Geometry {
    let mut s = Scene { meshes: Vec::with_capacity(meshes.len()), ..Scene::default() };
    s.meshes.extend(meshes.iter().map(|&i| scene.meshes[i].clone()));
    s.geometry()
}

/// One re-voxelization of moved meshes.
#[derive(Clone, Debug)]
pub struct Revoxelized {
    /// The voxelization (occupancy and triangle lists).
    pub voxelization: Voxelization,
    /// Its records (voxels without one dropped).
    pub records: BrickMap<AverageRecord>,
}

/// Voxelizes `geometry` (posed moving meshes of `scene`, world space) into `grid` with `mode`
/// and gives every voxel a record from `source`.
pub fn revoxelize(
    scene: &Scene,
    geometry: &Geometry,
    grid: &GridSpec,
    mode: Mode,
    source: RecordSource,
) -> Result<Revoxelized> {
    let opts = voxelize::Options { mode, triangle_lists: true, ..Default::default() };
    let voxelization = voxelize::voxelize(geometry, grid, &opts)?;
    let records = voxel_records(scene, geometry, &voxelization, source)?;
    Ok(Revoxelized { voxelization, records })
}
