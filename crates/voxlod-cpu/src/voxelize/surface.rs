//! The surface voxelizers — conservative and 6-separating thin — over a whole scene: survey and
//! memory guard, parallel rasterization of every triangle ([`super::raster`]), and assembly of
//! the sparse result ([`super::pairs`]).
//!
//! With triangle lists, every (voxel, triangle) overlap becomes one sort key; the sorted keys
//! are the CSR directly. Without them only occupancy is kept: on grids whose brick bitset is
//! small (up to 16 MiB, or no larger than the pairs it replaces) triangles set bits of a dense
//! atomic bitset — no pair is stored, no sort runs — and the set voxels are read back in
//! Morton order; larger, sparser grids sort and deduplicate Morton codes instead.

use rayon::prelude::*;
use voxlod_format::BrickMap;
use voxlod_scene::Geometry;

use super::budget::{self, result_bytes};
use super::lattice::{Lattice, Reach};
use super::pairs::{self, BrickBits, bits_for, code_bits};
use super::sort::Key;
use super::{Mode, Options, TriangleRange, Voxelization};
use crate::Result;

/// Largest brick bitset always used for occupancy-only voxelization (16 MiB: a 2048²×512 grid).
const DENSE_BYTES: u64 = 16 << 20;

/// How a surface voxelization will be carried out, chosen from the survey.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plan {
    /// Occupancy through a dense brick bitset.
    DenseOccupancy,
    /// Occupancy through sorted unique codes.
    SparseOccupancy,
    /// Triangle lists with 64-bit keys.
    Lists64,
    /// Triangle lists with 128-bit keys (Morton code and triangle id do not fit 64 bits).
    Lists128,
}

/// Chooses the plan and returns it with its estimated peak bytes (including the lattice), for
/// at most `pairs` (voxel, triangle) pairs.
pub fn plan(lattice: &Lattice, triangles: u64, pairs: u64, lists: bool) -> (Plan, u64) {
    let dims = lattice.grid().dims;
    let voxels = pairs.min(lattice.grid().voxel_count());
    let base = lattice.memory_bytes() as u64 + result_bytes(voxels, dims);
    let tri_bits = bits_for(triangles);
    let (plan, working) = if lists {
        let (plan, key) = if code_bits(dims) + tri_bits <= 64 {
            (Plan::Lists64, 8)
        } else {
            (Plan::Lists128, 16)
        };
        // Chunk buffers and their concatenation, then the triangle ids.
        (plan, pairs.saturating_mul(2 * key + 4))
    } else {
        let dense = BrickBits::bytes(dims);
        let sparse = pairs.saturating_mul(16);
        if dense <= DENSE_BYTES.max(sparse) {
            (Plan::DenseOccupancy, dense)
        } else {
            (Plan::SparseOccupancy, sparse)
        }
    };
    (plan, base.saturating_add(working))
}

/// Conservative or thin voxelization of `geometry` on `lattice`.
///
/// Occupancy on a grid whose brick bitset is small skips the survey when even a completely
/// full grid would fit the memory limit: the emission pass validates the triangles itself.
pub fn voxelize(geometry: &Geometry, lattice: &Lattice, options: &Options) -> Result<Voxelization> {
    let thin = options.mode == Mode::Thin;
    let grid = *lattice.grid();
    let triangles = geometry.indices.len() as u64;
    let full = plan(lattice, triangles, grid.voxel_count(), false);
    let (plan, bytes) = if !options.triangle_lists
        && full.0 == Plan::DenseOccupancy
        && full.1 <= options.memory_limit_bytes
    {
        full
    } else {
        let survey = budget::survey(geometry, lattice, Reach::Surface, thin)?;
        plan(lattice, triangles, survey.pairs, options.triangle_lists)
    };
    budget::check(grid.dims, bytes, options.memory_limit_bytes)?;
    let tri_bits = bits_for(triangles);
    let (voxels, triangles) = match plan {
        Plan::DenseOccupancy => {
            let bits = pairs::dense_bits(geometry, lattice, thin)?;
            (brick_map(grid.dims, bits.codes().map(|c| (c, TriangleRange::default())))?, Vec::new())
        }
        Plan::SparseOccupancy => {
            let codes = pairs::sorted_codes(geometry, lattice, thin)?;
            (
                brick_map(grid.dims, codes.into_iter().map(|c| (c, TriangleRange::default())))?,
                Vec::new(),
            )
        }
        Plan::Lists64 => lists::<u64>(geometry, lattice, thin, tri_bits)?,
        Plan::Lists128 => lists::<u128>(geometry, lattice, thin, tri_bits)?,
    };
    Ok(Voxelization { grid, mode: options.mode, voxels, triangles, boundary_edges: None })
}

fn lists<K: Key>(
    geometry: &Geometry,
    lattice: &Lattice,
    thin: bool,
    tri_bits: u32,
) -> Result<(BrickMap<TriangleRange>, Vec<u32>)> {
    let keys = pairs::sorted_keys::<K>(geometry, lattice, thin, tri_bits)?;
    let triangles = keys.par_iter().map(|k| k.tri(tri_bits)).collect();
    let voxels = brick_map(lattice.grid().dims, pairs::runs(&keys, tri_bits))?;
    Ok((voxels, triangles))
}

/// The brick map of voxels given in Morton order.
pub fn brick_map(
    dims: glam::UVec3,
    voxels: impl IntoIterator<Item = (u64, TriangleRange)>,
) -> Result<BrickMap<TriangleRange>> {
    Ok(BrickMap::from_morton_sorted(dims, voxels)?)
}
