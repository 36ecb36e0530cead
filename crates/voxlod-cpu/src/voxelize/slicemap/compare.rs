//! Slicemaps measured against exact voxelizations: what they miss and what they add.
//!
//! # Aligned with a grid
//! An orthographic uniform map from [`SliceCamera::aligned`] has one column per voxel column
//! of a [`GridSpec`] and one slice per voxel along the axis, so its cells are the grid's voxels
//! and [`aligned_voxels`] reads it as a voxel set ([`DenseBits`]) to compare with the exact
//! conservative and thin voxelizations of [`crate::voxelize`]. [`merged_voxels`] ORs the maps
//! along the three axes (an extension of ours: a triangle steep along one axis is shallow along
//! another).
//!
//! # Perspective and local maps
//! Their cells are frustum pieces (a pixel's pyramid cut by two planes of constant eye-space
//! z), which no grid voxel fits. Instead of resampling a fine exact voxelization into them (a
//! cell would count as occupied when some fine voxel's centre falls in it, an approximation that
//! both adds and misses cells), the reference is computed in the map's own cells with the same
//! rule the conservative voxelizer uses for boxes: a cell is occupied when the triangle meets
//! it. That is the conservative map ([`super::Coverage::Conservative`]) sliced over the same
//! column ranges ([`super::build_in_ranges`] with the tested map's ranges): coverage of the
//! closed pixel square exact on the snapped triangle, depth range per column from the exact
//! extreme candidates, rounded to `f32` only in the depth values. [`cell_agreement`] counts the
//! cells of one map missing from or added to another. In the aligned case, this reference
//! reproduces the conservative voxelizer (tested), which is what makes it the exact one.

use glam::UVec3;
use voxlod_format::GridSpec;
use voxlod_scene::Geometry;

use super::{Coverage, Options, SliceCamera, Slicemap, Slicing, build};
use crate::voxelize::Voxelization;
use crate::{Error, Result};

/// A dense set of voxels of a grid: one bit per voxel, x fastest, then y, then z.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DenseBits {
    /// Grid dimensions.
    pub dims: UVec3,
    /// Bit `i % 64` of word `i / 64` for linear index `i`.
    pub words: Vec<u64>,
}

impl DenseBits {
    /// The empty set over `dims`.
    pub fn new(dims: UVec3) -> Self {
        let n = dims.x as u64 * dims.y as u64 * dims.z as u64;
        DenseBits { dims, words: vec![0; n.div_ceil(64) as usize] }
    }

    #[inline]
    fn index(&self, c: UVec3) -> usize {
        c.x as usize + self.dims.x as usize * (c.y as usize + self.dims.y as usize * c.z as usize)
    }

    /// Adds voxel `c` (inside the grid).
    #[inline]
    pub fn insert(&mut self, c: UVec3) {
        let i = self.index(c);
        self.words[i / 64] |= 1 << (i % 64);
    }

    /// Whether voxel `c` is in the set.
    #[inline]
    pub fn contains(&self, c: UVec3) -> bool {
        let i = self.index(c);
        self.words[i / 64] >> (i % 64) & 1 == 1
    }

    /// Number of voxels in the set.
    pub fn len(&self) -> u64 {
        self.words.iter().map(|w| w.count_ones() as u64).sum()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.words.iter().all(|&w| w == 0)
    }

    /// The union with `other` (same dims).
    pub fn union_with(&mut self, other: &DenseBits) {
        for (a, b) in self.words.iter_mut().zip(&other.words) {
            *a |= b;
        }
    }

    /// The occupied voxels of a voxelization.
    pub fn from_voxelization(v: &Voxelization) -> Self {
        let mut out = DenseBits::new(v.grid.dims);
        for (c, _) in v.voxels.iter() {
            out.insert(c);
        }
        out
    }

    /// Voxels in `self` and not in `other`, and voxels in `other` and not in `self`.
    pub fn difference_counts(&self, other: &DenseBits) -> (u64, u64) {
        self.words.iter().zip(&other.words).fold((0, 0), |(a, b), (x, y)| {
            (a + (x & !y).count_ones() as u64, b + (y & !x).count_ones() as u64)
        })
    }
}

/// How a tested set of cells agrees with a reference set.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Agreement {
    /// Cells in the reference.
    pub reference: u64,
    /// Cells in the tested set.
    pub tested: u64,
    /// Reference cells the tested set misses (holes).
    pub missed: u64,
    /// Tested cells not in the reference.
    pub extra: u64,
}

impl Agreement {
    /// `tested` against `reference`.
    pub fn of(tested: &DenseBits, reference: &DenseBits) -> Self {
        let (extra, missed) = tested.difference_counts(reference);
        Agreement { reference: reference.len(), tested: tested.len(), missed, extra }
    }

    /// Missed cells as a fraction of the reference's (0 for an empty reference).
    pub fn missed_fraction(&self) -> f64 {
        if self.reference == 0 { 0.0 } else { self.missed as f64 / self.reference as f64 }
    }
}

/// Cells of `tested` missing from or added to `reference`, two maps with the same camera,
/// slice count and layers (their ranges are the caller's business, see the module docs).
pub fn cell_agreement(tested: &Slicemap, reference: &Slicemap) -> Result<Agreement> {
    if tested.bits.len() != reference.bits.len() || tested.camera != reference.camera {
        return Err(Error::InvalidParameter {
            name: "slicemaps",
            value: format!("{} and {} words", tested.bits.len(), reference.bits.len()),
            reason: "cells compare only between maps of the same camera and layout".into(),
        });
    }
    let (mut missed, mut extra) = (0, 0);
    for (&t, &r) in tested.bits.iter().zip(&reference.bits) {
        missed += (r & !t).count_ones() as u64;
        extra += (t & !r).count_ones() as u64;
    }
    Ok(Agreement { reference: reference.occupied(), tested: tested.occupied(), missed, extra })
}

/// The map of [`SliceCamera::aligned`] along `axis` with one slice per voxel, uniform.
pub fn aligned_map(
    geometry: &Geometry,
    grid: &GridSpec,
    axis: usize,
    coverage: Coverage,
) -> Result<Slicemap> {
    let camera = SliceCamera::aligned(grid, axis)?;
    let slices = grid.dims[axis.min(2)];
    let options = Options { slices, slicing: Slicing::Uniform, coverage, ..Options::default() };
    build(geometry, &camera, &options)
}

/// Reads an aligned map (built by [`aligned_map`] along `axis` for `grid`) as voxels.
pub fn map_voxels(map: &Slicemap, grid: &GridSpec, axis: usize) -> DenseBits {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut out = DenseBits::new(grid.dims);
    for y in 0..map.camera.height {
        for x in 0..map.camera.width {
            for (w, &word) in map.column(0, x, y).iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let s = w as u32 * 32 + bits.trailing_zeros();
                    bits &= bits - 1;
                    let mut c = UVec3::ZERO;
                    c[axis] = s;
                    c[u] = x;
                    c[v] = y;
                    out.insert(c);
                }
            }
        }
    }
    out
}

/// The voxels of `grid` an aligned map along `axis` sets (module docs). Errors as
/// [`build`] (a grid side over the map's limits, more than [`super::MAX_SLICES`] voxels along
/// `axis`).
pub fn aligned_voxels(
    geometry: &Geometry,
    grid: &GridSpec,
    axis: usize,
    coverage: Coverage,
) -> Result<DenseBits> {
    Ok(map_voxels(&aligned_map(geometry, grid, axis, coverage)?, grid, axis))
}

/// The union of the aligned maps along x, y and z (module docs): three passes.
pub fn merged_voxels(
    geometry: &Geometry,
    grid: &GridSpec,
    coverage: Coverage,
) -> Result<DenseBits> {
    let mut out = aligned_voxels(geometry, grid, 0, coverage)?;
    for axis in 1..3 {
        out.union_with(&aligned_voxels(geometry, grid, axis, coverage)?);
    }
    Ok(out)
}
