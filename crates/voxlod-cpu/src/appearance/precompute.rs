//! The precompute driver: samples every voxel of a voxelization and fits one record per voxel
//! with any representation's fit function, in parallel over voxels (rayon), deterministically.
//!
//! Rules:
//! - Voxel `i` (the voxelization's Morton order) is sampled with
//!   [`SamplingContext::sample_voxel_seeded`]`(i, opts.seed, 0, opts.rays)`; each rayon worker
//!   reuses one [`VoxelSamples`] buffer (no allocation per voxel once it has grown).
//! - A voxel whose fit returns `None` gets no record; the others keep the voxelization's Morton
//!   order in the result's brick map.
//! - Specular side records are built only when a material of the scene has a specular lobe: the
//!   mean specular level of the voxel's case-(a) hits, and their exponent averaged with the
//!   specular levels as weights (diffuse hits have no lobe, so they lower the level without
//!   diluting the exponent); 0 without any specular hit.
//! - The result depends only on the inputs and `opts`, not on the thread count.

use rayon::prelude::*;
use voxlod_format::BrickMap;
use voxlod_format::morton;
use voxlod_format::records::SpecularRecord;

use super::AppearanceGrid;
use super::line_sampler::SamplingContext;
use super::voxel_samples::VoxelSamples;
use crate::{Error, Result};

/// Options of [`precompute`]. Cost is linear in `rays`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrecomputeOptions {
    /// Sampling lines per voxel, ≥ 1 (150, as in the paper).
    pub rays: u32,
    /// Seed of the lines (another seed gives an independent estimate).
    pub seed: u32,
}

impl Default for PrecomputeOptions {
    fn default() -> Self {
        Self { rays: 150, seed: 0 }
    }
}

/// The specular side record of a voxel's samples (module docs).
pub fn specular_record(samples: &VoxelSamples) -> SpecularRecord {
    let (mut count, mut level, mut weighted) = (0u32, 0.0f64, 0.0f64);
    for s in samples.surfaces() {
        count += 1;
        level += s.specular as f64;
        weighted += (s.specular * s.shininess) as f64;
    }
    if count == 0 || level <= 0.0 {
        return SpecularRecord::new(0.0, 0.0);
    }
    SpecularRecord::new((level / count as f64) as f32, (weighted / level) as f32)
}

/// Samples every voxel of `ctx` with `opts` and fits its record with `fit` (module docs).
/// Errors on `opts.rays = 0`.
pub fn precompute<R: Send>(
    ctx: &SamplingContext,
    opts: &PrecomputeOptions,
    fit: impl Fn(&VoxelSamples) -> Option<R> + Sync,
) -> Result<AppearanceGrid<R>> {
    if opts.rays == 0 {
        return Err(Error::InvalidParameter {
            name: "rays",
            value: "0".into(),
            reason: "at least one sampling line per voxel".into(),
        });
    }
    let specular = ctx.has_specular();
    let fitted: Vec<Option<(R, SpecularRecord)>> = (0..ctx.voxel_count())
        .into_par_iter()
        .map_init(VoxelSamples::default, |buf, i| {
            ctx.sample_voxel_seeded(i, opts.seed, 0, opts.rays, buf);
            let record = fit(buf)?;
            let spec = if specular { specular_record(buf) } else { SpecularRecord::default() };
            Some((record, spec))
        })
        .collect();
    let kept = fitted.iter().filter(|f| f.is_some()).count();
    let mut side = Vec::with_capacity(if specular { kept } else { 0 });
    let mut entries = Vec::with_capacity(kept);
    for (i, f) in fitted.into_iter().enumerate() {
        if let Some((record, spec)) = f {
            entries.push((morton::encode(ctx.coord(i)), record));
            if specular {
                side.push(spec);
            }
        }
    }
    let grid = *ctx.grid();
    let records = BrickMap::from_morton_sorted(grid.dims, entries)?;
    Ok(AppearanceGrid { grid, records, specular: specular.then_some(side) })
}

#[cfg(test)]
mod tests;
