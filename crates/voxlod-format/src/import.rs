//! Voxels from other tools into voxlod's grids: MagicaVoxel `.vox` scenes ([`crate::vox`]) and
//! Mitsuba 3 `.vol` density grids ([`crate::vol`]) as Averages records
//! ([`AverageRecord`]: colour, opacity, no normal) over a [`GridSpec`], ready for
//! [`crate::vxl::write`].
//!
//! - **`.vox`**: every voxel of every shape (rotations and translations applied, see
//!   [`crate::vox`]) becomes an opaque voxel of its palette colour (sRGB8 kept as is; palette
//!   alpha and materials are not read). The file stores whole voxels only, so the grid's origin
//!   is the voxels' bounding-box minimum in voxlod's axes times the voxel size given: a scene
//!   exported by [`crate::vox::encode`] comes back with the same occupancy, translated by whole
//!   voxels.
//! - **`.vol`**: a one-channel grid is read as extinction σ per world unit (what
//!   [`crate::vol::density_and_albedo`] writes); each cell of σ > 0 becomes a voxel of opacity
//!   `α = 1 − exp(−σ·size)` (the exponential transmittance across one voxel; the inverse of
//!   [`extinction_from_opacity`](crate::records::extinction_from_opacity) below its cap). The
//!   colour is a three-channel albedo grid of the same cells and box when given (linear RGB,
//!   clamped to [0, 1]), else [`GREY`]. Cells must be cubes: voxlod's voxels are.
//!
//! Errors name the file and what is wrong: an empty scene, a grid wider than
//! [`GridSpec::MAX_DIM`], two shapes setting the same voxel, a `.vol` of another channel count
//! than expected, non-cubic cells, a negative or non-finite density, no cell of positive density.

use std::path::Path;

use glam::{DVec3, UVec3, Vec3};

use crate::records::AverageRecord;
use crate::vol::VolGrid;
use crate::vox::VoxFile;
use crate::{BrickMap, Error, GridSpec, Result};

/// The colour of imported `.vol` voxels without an albedo grid: sRGB 204 (linear ≈ 0.604), the
/// grey `voxlod export` gives occupancy-only voxels.
pub const GREY: [u8; 3] = [204, 204, 204];

/// Largest relative difference between a `.vol` grid's cell edges along x, y and z for the cells
/// to count as cubes (f32 bounding boxes round their corners).
pub const CUBE_TOLERANCE: f64 = 1e-5;

/// A `.vox` scene as Averages records on a grid of `voxel_size` (see the [module docs](self));
/// `path` names the source in errors. Returns the grid and the records.
///
/// ```
/// use std::path::Path;
/// use glam::UVec3;
/// use voxlod_format::{BrickMap, import, vox};
/// let map = BrickMap::from_voxels(UVec3::new(3, 2, 2), [(UVec3::new(2, 1, 0), [90u8, 20, 10])])
///     .unwrap();
/// let file = vox::decode(&vox::encode(&map, |&c| c).unwrap().bytes, Path::new("a.vox")).unwrap();
/// let (grid, records) = import::vox_to_averages(&file, 0.5, Path::new("a.vox")).unwrap();
/// assert_eq!((grid.dims, grid.voxel_size, records.len()), (UVec3::ONE, 0.5, 1));
/// let r = records.get(UVec3::ZERO).unwrap();
/// assert_eq!((r.color, r.opacity), ([90, 20, 10], 255));
/// ```
pub fn vox_to_averages(
    file: &VoxFile,
    voxel_size: f64,
    path: &Path,
) -> Result<(GridSpec, BrickMap<AverageRecord>)> {
    let named = |e: Error| match e {
        Error::InvalidGrid { reason } => {
            Error::InvalidGrid { reason: format!("{}: {reason}", path.display()) }
        }
        other => other,
    };
    let (min, indices) = file.to_brick_map().map_err(named)?;
    let grid = GridSpec::new(min.as_dvec3() * voxel_size, voxel_size, indices.dims())?;
    let records = indices.map(|&i| {
        let [r, g, b, _] = file.palette[i as usize];
        AverageRecord { color: [r, g, b], opacity: 255, normal: [0; 3], _pad: 0 }
    });
    Ok((grid, records))
}

/// A `.vol` density grid (and optional albedo grid) as Averages records (see the
/// [module docs](self)); `path` names the density file in errors.
///
/// ```
/// use std::path::Path;
/// use glam::{UVec3, Vec3};
/// use voxlod_format::{import, vol::VolGrid};
/// let density = VolGrid {
///     dims: UVec3::new(2, 1, 1),
///     channels: 1,
///     bbox_min: Vec3::ZERO,
///     bbox_max: Vec3::new(1.0, 0.5, 0.5),
///     data: vec![0.0, 2.0],
/// };
/// let (grid, records) = import::vol_to_averages(&density, None, Path::new("d.vol")).unwrap();
/// assert_eq!((grid.voxel_size, records.len()), (0.5, 1));
/// // α = 1 − exp(−2 · 0.5) ≈ 0.632 → unorm8 161.
/// assert_eq!(records.get(UVec3::new(1, 0, 0)).unwrap().opacity, 161);
/// ```
pub fn vol_to_averages(
    density: &VolGrid,
    albedo: Option<&VolGrid>,
    path: &Path,
) -> Result<(GridSpec, BrickMap<AverageRecord>)> {
    let (grid, cells) = vol_cells(density, albedo, path)?;
    let grey = crate::records::quant::decode_srgb8(GREY);
    let records = BrickMap::from_voxels(
        grid.dims,
        cells
            .into_iter()
            .map(|(c, alpha, rgb)| (c, AverageRecord::new(rgb.unwrap_or(grey), Vec3::ZERO, alpha))),
    )?;
    Ok((grid, records))
}

/// [`vol_to_averages`] at full precision: per voxel `[r, g, b, α]` in `f32` (linear albedo,
/// [`GREY`] without an albedo grid; opacity unquantized).
pub fn vol_to_rgba_f32(
    density: &VolGrid,
    albedo: Option<&VolGrid>,
    path: &Path,
) -> Result<(GridSpec, BrickMap<[f32; 4]>)> {
    let (grid, cells) = vol_cells(density, albedo, path)?;
    let grey = crate::records::quant::decode_srgb8(GREY);
    let records = BrickMap::from_voxels(
        grid.dims,
        cells.into_iter().map(|(c, alpha, rgb)| (c, rgb.unwrap_or(grey).extend(alpha).to_array())),
    )?;
    Ok((grid, records))
}

/// Opacity `1 − exp(−σ·size)` of a voxel of extinction `sigma` (per world unit) and edge
/// `size`, in `f64` then rounded to `f32`.
pub fn opacity_from_extinction(sigma: f32, size: f64) -> f32 {
    (-(-(sigma as f64) * size).exp_m1()) as f32
}

/// The grid of a `.vol` density and its non-empty cells: `(cell, α, albedo)`.
#[allow(clippy::type_complexity)]
fn vol_cells(
    density: &VolGrid,
    albedo: Option<&VolGrid>,
    path: &Path,
) -> Result<(GridSpec, Vec<(UVec3, f32, Option<Vec3>)>)> {
    let bad =
        |reason: String| Error::InvalidGrid { reason: format!("{}: {reason}", path.display()) };
    density.validate()?;
    if density.channels != 1 {
        return Err(bad(format!(
            "{} channels: a density grid has 1 (a 3-channel grid is an albedo or colour grid)",
            density.channels
        )));
    }
    if let Some(a) = albedo {
        a.validate()?;
        if a.channels != 3 {
            return Err(bad(format!("its albedo grid has {} channels, not 3", a.channels)));
        }
        if (a.dims, a.bbox_min, a.bbox_max) != (density.dims, density.bbox_min, density.bbox_max) {
            return Err(bad(format!(
                "its albedo grid ({} cells over {} … {}) is not the density's ({} cells over {} \
                 … {})",
                a.dims, a.bbox_min, a.bbox_max, density.dims, density.bbox_min, density.bbox_max
            )));
        }
    }
    let edges =
        (density.bbox_max.as_dvec3() - density.bbox_min.as_dvec3()) / density.dims.as_dvec3();
    let size = edges.x;
    if (edges - DVec3::splat(size)).abs().max_element() > CUBE_TOLERANCE * size {
        return Err(bad(format!(
            "its cells are {} × {} × {} (not cubes): voxlod's voxels are cubes",
            edges.x, edges.y, edges.z
        )));
    }
    let grid = GridSpec::new(density.bbox_min.as_dvec3(), size, density.dims)
        .map_err(|e| bad(e.to_string()))?;
    let mut cells = Vec::new();
    let d = density.dims;
    for z in 0..d.z {
        for y in 0..d.y {
            for x in 0..d.x {
                let c = UVec3::new(x, y, z);
                let sigma = density.data[density.index(c)];
                if sigma < 0.0 {
                    return Err(bad(format!("negative density {sigma} at cell {c}")));
                }
                if sigma == 0.0 {
                    continue;
                }
                let rgb = albedo.map(|a| {
                    let at = a.index(c);
                    Vec3::from_slice(&a.data[at..at + 3]).clamp(Vec3::ZERO, Vec3::ONE)
                });
                cells.push((c, opacity_from_extinction(sigma, size), rgb));
            }
        }
    }
    if cells.is_empty() {
        return Err(bad("no cell has a density above 0: nothing to import".into()));
    }
    Ok((grid, cells))
}

#[cfg(test)]
mod tests;
