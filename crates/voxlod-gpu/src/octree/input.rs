//! Host-side input checks: the CPU builds' checks in their order (grid, plan, then per voxel
//! bounds and payload), so bad input gets voxlod-octree's own errors, and the naming of a
//! duplicate voxel the GPU found.

use glam::UVec3;
use voxlod_format::{GridSpec, morton};
use voxlod_octree::{AveragePayload, BuildOptions, Payload};

use crate::Error;
use crate::Result;

/// The host's plan and input, checked.
pub(super) struct Input<'v> {
    pub(super) depth: u32,
    pub(super) first_dense: u32,
    pub(super) coords: Vec<u32>,
    pub(super) voxels: usize,
    pub(super) payload: Option<&'v [AveragePayload]>,
    /// Input already on the device (coordinates, payloads), instead of `coords` and `payload`.
    pub(super) device: Option<(&'v wgpu::Buffer, &'v wgpu::Buffer)>,
}

/// The CPU builds' input checks, in their order (grid, plan, then per voxel: inside the grid,
/// then an acceptable payload). Duplicates are found on the GPU.
pub(super) fn check_input<'v>(
    grid: &GridSpec,
    coords: impl ExactSizeIterator<Item = UVec3>,
    payload: Option<&'v [AveragePayload]>,
    options: &BuildOptions,
) -> Result<Input<'v>> {
    grid.validate().map_err(voxlod_octree::Error::from)?;
    let (depth, first_dense) = voxlod_octree::plan(grid.dims, options)?;
    let voxels = coords.len();
    let mut flat = Vec::with_capacity(3 * voxels);
    for (i, c) in coords.enumerate() {
        if !c.cmplt(grid.dims).all() {
            return Err(voxlod_octree::Error::OutOfBounds { coord: c, dims: grid.dims }.into());
        }
        if let Some(reason) = payload.and_then(|p| p[i].check()) {
            return Err(voxlod_octree::Error::InvalidPayload { coord: c, reason }.into());
        }
        flat.extend_from_slice(&c.to_array());
    }
    Ok(Input { depth, first_dense, coords: flat, voxels, payload, device: None })
}

/// The first duplicate in Morton order, as the CPU build names it (error path only).
pub(super) fn first_duplicate(coords: &[u32]) -> Error {
    let mut codes: Vec<u64> =
        coords.chunks_exact(3).map(|c| morton::encode(UVec3::new(c[0], c[1], c[2]))).collect();
    codes.sort_unstable();
    match codes.windows(2).find(|w| w[0] == w[1]) {
        Some(w) => voxlod_octree::Error::DuplicateVoxel { coord: morton::decode(w[0]) }.into(),
        None => Error::Device {
            adapter: String::new(),
            during: "building an octree",
            message: "the leaves kernel reported a duplicate voxel, but there is none".into(),
        },
    }
}

#[cfg(test)]
mod tests {
    use voxlod_octree::FlatOctree;

    use super::*;

    #[test]
    fn bad_input_gets_the_cpu_error_before_any_gpu_work() {
        use glam::{DVec3, Vec3};
        let grid = GridSpec::new(DVec3::ZERO, 1.0, UVec3::splat(4)).unwrap();
        let ok = AveragePayload::new(Vec3::ONE, Vec3::Z, 0.5);
        let nan = AveragePayload::new(Vec3::ONE, Vec3::Z, f32::NAN);
        let opts = BuildOptions::default();
        let cases: [(Vec<(UVec3, AveragePayload)>, BuildOptions); 4] = [
            (vec![(UVec3::ZERO, ok), (UVec3::new(0, 4, 0), ok)], opts),
            (vec![(UVec3::ZERO, ok), (UVec3::new(1, 2, 3), nan), (UVec3::splat(9), ok)], opts),
            (vec![(UVec3::ZERO, ok)], BuildOptions { depth: Some(1), dense_log2: 1 }),
            (vec![(UVec3::ZERO, ok)], BuildOptions { depth: None, dense_log2: 30 }),
        ];
        for (voxels, opts) in cases {
            let coords = voxels.iter().map(|v| v.0);
            let payload: Vec<_> = voxels.iter().map(|v| v.1).collect();
            let gpu = check_input(&grid, coords, Some(&payload), &opts).err().unwrap().to_string();
            let cpu =
                FlatOctree::build_level_by_level(grid, &voxels, &opts).unwrap_err().to_string();
            assert_eq!(gpu, cpu);
        }
        // Duplicates: named as the CPU names them (the smallest repeated Morton code).
        let coords = [3, 1, 0, 1, 1, 1, 3, 1, 0, 1, 1, 1];
        let voxels: Vec<_> = coords.chunks(3).map(|c| (UVec3::from_slice(c), ok)).collect();
        let cpu = FlatOctree::build_level_by_level(grid, &voxels, &opts).unwrap_err().to_string();
        assert_eq!(first_duplicate(&coords).to_string(), cpu);
    }
}
