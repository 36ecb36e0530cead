//! What slicemaps miss: holes against the exact voxelizers, per scene.
//!
//! - **Aligned with a grid**: orthographic uniform maps from [`SliceCamera::aligned`] along x,
//!   y and z (one column per voxel column, one slice per voxel), read as voxels and compared
//!   with the exact conservative and thin voxelizations of the same grid; their union (the
//!   three-axis merge); and the emulated conservative rasterization along z.
//! - **Local maps' exact cells** are those of the standard map's column ranges; a column it
//!   misses entirely has no range, no cells, and counts among the missed columns (columns the
//!   conservative map reaches and the standard one does not).
//! - **Perspective, uniform and local**: a map from the scene's camera, compared with the exact
//!   cells of the same map (the conservative map in the same column ranges: every cell a
//!   triangle meets; [`voxlod_cpu::voxelize::slicemap::compare`] says why this is the exact
//!   voxelization of those cells rather than a resampled grid).
//!
//! Every figure comes with the time of the CPU reference (and of the GPU path on the adapter
//! given; on lavapipe these are CPU timings of the GPU path).

use serde::Serialize;
use voxlod_cpu::voxelize::slicemap::compare::{
    Agreement, DenseBits, aligned_map, cell_agreement, map_voxels,
};
use voxlod_cpu::voxelize::slicemap::{
    self as sm, Coverage, Options, SliceCamera, Slicemap, Slicing, build_in_ranges,
};
use voxlod_cpu::voxelize::{self as vox, Mode};
use voxlod_eval::heatmap::colour_ramp;
use voxlod_format::GridSpec;
use voxlod_gpu::slicemap::SlicemapRenderer;
use voxlod_scene::{Geometry, Scene, Srgb8Image};

use super::{Timing, framing_camera, time};
use crate::Error;

/// What the holes part measures.
#[derive(Clone, Debug, PartialEq)]
pub struct HolesConfig {
    /// Scene specs ([`crate::scenes::load`]).
    pub scenes: Vec<String>,
    /// Voxels along the longest side of the aligned grid fitted to each scene (≤ 512: one
    /// slice per voxel).
    pub resolution: u32,
    /// Columns per side of the perspective maps.
    pub map_size: u32,
    /// Slice counts of the perspective maps.
    pub slices: Vec<u32>,
    /// Timed runs per figure (the spread is reported).
    pub repeats: u32,
}

/// One aligned method on one scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AlignedRow {
    /// Scene spec.
    pub scene: String,
    /// Method.
    pub method: String,
    /// Voxels it sets.
    pub voxels: u64,
    /// Conservative voxels it misses.
    pub missed_conservative: u64,
    /// Thin (6-separating) voxels it misses.
    pub missed_thin: u64,
    /// Voxels it sets outside the conservative voxelization.
    pub extra: u64,
    /// CPU time in ms.
    pub cpu_ms: Timing,
    /// GPU-path time in ms (slicemap methods, with an adapter).
    pub gpu_ms: Option<Timing>,
}

/// Cells of a tested map against the exact cells of the same map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Cells {
    /// Exact cells (the geometry meets them).
    pub exact: u64,
    /// Cells the tested map sets.
    pub set: u64,
    /// Exact cells it misses.
    pub missed: u64,
    /// Cells it sets that are not exact.
    pub extra: u64,
    /// Columns with exact cells.
    pub columns: u64,
    /// Columns with exact cells where the tested map sets none (a triangle seen edge-on or
    /// between pixel centres).
    pub columns_missed: u64,
}

/// Columns with a cell in `reference`, and those of them empty in `tested`.
fn columns(tested: &Slicemap, reference: &Slicemap) -> (u64, u64) {
    let (mut all, mut missed) = (0, 0);
    for y in 0..reference.camera.height {
        for x in 0..reference.camera.width {
            if reference.column(0, x, y).iter().any(|&w| w != 0) {
                all += 1;
                missed += tested.column(0, x, y).iter().all(|&w| w == 0) as u64;
            }
        }
    }
    (all, missed)
}

/// One perspective map against its exact cells.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CellRow {
    /// Scene spec.
    pub scene: String,
    /// Uniform or local slicing.
    pub slicing: String,
    /// Slices per column.
    pub slices: u32,
    /// The standard (hardware-rule) map against the exact cells.
    pub cells: Cells,
    /// CPU time of the standard map, ms.
    pub standard_ms: Timing,
    /// CPU time of the exact (conservative) map, ms.
    pub exact_ms: Timing,
    /// GPU-path time of the standard map, ms.
    pub gpu_standard_ms: Option<Timing>,
    /// GPU-path time of the conservative map (emulated), ms.
    pub gpu_conservative_ms: Option<Timing>,
}

/// The holes part's results.
#[derive(Clone, Debug)]
pub struct HolesResult {
    /// Aligned rows, per scene and method.
    pub aligned: Vec<AlignedRow>,
    /// Perspective rows, per scene, slicing and slice count.
    pub cells: Vec<CellRow>,
    /// Per scene: label and image of the exact cells per column and the standard map's missed
    /// cells per column.
    pub images: Vec<(String, Srgb8Image, Srgb8Image)>,
}

fn exact(g: &Geometry, grid: &GridSpec, mode: Mode) -> Result<vox::Voxelization, Error> {
    let o = vox::Options { mode, triangle_lists: false, ..Default::default() };
    Ok(vox::voxelize(g, grid, &o)?)
}

/// Per column of `reference`: its occupied cells (grey) and the fraction of them `tested`
/// misses (heat).
fn column_images(tested: &Slicemap, reference: &Slicemap) -> (Srgb8Image, Srgb8Image) {
    let (w, h) = (reference.camera.width, reference.camera.height);
    let count = |m: &Slicemap, x, y| m.column(0, x, y).iter().map(|v| v.count_ones()).sum::<u32>();
    let max = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| count(reference, x, y));
    let max = max.max().unwrap_or(0).max(1) as f64;
    let mut cells = Srgb8Image::new(w, h, [0, 0, 0]);
    let mut missed = Srgb8Image::new(w, h, [0, 0, 0]);
    for y in 0..h {
        for x in 0..w {
            let r = count(reference, x, y);
            if r == 0 {
                continue;
            }
            let g = (40.0 + 215.0 * r as f64 / max) as u8;
            let i = (y * w + x) as usize;
            cells.pixels[i] = [g, g, g];
            let miss: u32 = reference
                .column(0, x, y)
                .iter()
                .zip(tested.column(0, x, y))
                .map(|(a, b)| (a & !b).count_ones())
                .sum();
            missed.pixels[i] = colour_ramp(miss as f64 / r as f64);
        }
    }
    (cells, missed)
}

/// Runs the holes part (module docs).
pub fn run(
    config: &HolesConfig,
    gpu: Option<&SlicemapRenderer>,
    progress: &dyn Fn(&str),
) -> Result<HolesResult, Error> {
    if config.resolution == 0 || config.resolution > sm::MAX_SLICES {
        return Err(Error::InvalidConfig {
            study: "slicemap",
            field: "holes.resolution",
            value: config.resolution.to_string(),
            expected: "1..=512 voxels (one slice per voxel along the view axis)",
        });
    }
    let mut out = HolesResult { aligned: Vec::new(), cells: Vec::new(), images: Vec::new() };
    let repeats = config.repeats.max(1);
    for spec in &config.scenes {
        progress(&format!("slicemap holes: {spec}"));
        let scene: Scene = crate::scenes::load(spec)?;
        let g = scene.geometry();
        let (lo, hi) = scene.bounds()?;
        let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), config.resolution)?;
        let (cons, cons_ms) = time(repeats, || exact(&g, &grid, Mode::Conservative))?;
        let (thin, thin_ms) = time(repeats, || exact(&g, &grid, Mode::Thin))?;
        let (cons, thin) =
            (DenseBits::from_voxelization(&cons), DenseBits::from_voxelization(&thin));
        let mut push = |method: &str, v: &DenseBits, cpu_ms, gpu_ms| {
            let c = Agreement::of(v, &cons);
            let t = Agreement::of(v, &thin);
            out.aligned.push(AlignedRow {
                scene: spec.clone(),
                method: method.into(),
                voxels: v.len(),
                missed_conservative: c.missed,
                missed_thin: t.missed,
                extra: c.extra,
                cpu_ms,
                gpu_ms,
            });
        };
        push("exact conservative voxelizer", &cons, cons_ms, None);
        push("exact thin voxelizer", &thin, thin_ms, None);
        // One map per axis, standard rasterization (the paper), then their union; and the
        // emulated conservative map along z.
        let mut merged = DenseBits::new(grid.dims);
        let (mut merged_ms, mut merged_gpu_ms) = (Vec::new(), Vec::new());
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            let (map, ms) =
                time(repeats, || Ok(aligned_map(&g, &grid, axis, Coverage::Standard)?))?;
            let gpu_ms = match gpu {
                Some(r) => {
                    let cam = SliceCamera::aligned(&grid, axis)?;
                    let o = Options { slices: grid.dims[axis], ..Options::default() };
                    Some(time(repeats, || Ok(r.build(&g, &cam, &o)?))?.1)
                }
                None => None,
            };
            merged_ms.push(ms);
            merged_gpu_ms.extend(gpu_ms);
            let v = map_voxels(&map, &grid, axis);
            merged.union_with(&v);
            push(&format!("slicemap along {name}, standard"), &v, ms, gpu_ms);
        }
        let sum = |t: &[Timing]| Timing {
            median_ms: t.iter().map(|t| t.median_ms).sum(),
            min_ms: t.iter().map(|t| t.min_ms).sum(),
            max_ms: t.iter().map(|t| t.max_ms).sum(),
        };
        let gpu_sum = (merged_gpu_ms.len() == 3).then(|| sum(&merged_gpu_ms));
        push("x, y and z maps merged (sum of the three)", &merged, sum(&merged_ms), gpu_sum);
        let (map, ms) = time(repeats, || Ok(aligned_map(&g, &grid, 2, Coverage::Conservative)?))?;
        let gpu_ms = match gpu {
            Some(r) => {
                let cam = SliceCamera::aligned(&grid, 2)?;
                let o = Options {
                    slices: grid.dims.z,
                    coverage: Coverage::Conservative,
                    ..Options::default()
                };
                Some(time(repeats, || Ok(r.build(&g, &cam, &o)?))?.1)
            }
            None => None,
        };
        push("slicemap along z, conservative (emulated)", &map_voxels(&map, &grid, 2), ms, gpu_ms);

        // Perspective maps from the scene's camera.
        let cam = framing_camera(&scene, config.map_size, config.map_size)?;
        let prepared = sm::prepare(&g, &cam)?;
        let mut image_done = false;
        for &slices in &config.slices {
            for slicing in [Slicing::Uniform, Slicing::Local] {
                let o = Options { slices, slicing, ..Options::default() };
                o.validate(&cam)?;
                let (standard, standard_ms) =
                    time(repeats, || Ok(sm::build_prepared(&prepared.triangles, &cam, &o)))?;
                let co = Options { coverage: Coverage::Conservative, ..o };
                // The exact cells of the standard map: in its own column ranges.
                let (reference, exact_ms) = time(repeats, || match &standard.ranges {
                    Some(r) => Ok(build_in_ranges(&prepared.triangles, &cam, &co, r)?),
                    None => Ok(sm::build_prepared(&prepared.triangles, &cam, &co)),
                })?;
                // The conservative map with its own ranges: every column the geometry reaches.
                let own = match standard.ranges {
                    Some(_) => sm::build_prepared(&prepared.triangles, &cam, &co),
                    None => reference.clone(),
                };
                let a = cell_agreement(&standard, &reference)?;
                let (columns, columns_missed) = columns(&standard, &own);
                let cells = Cells {
                    exact: a.reference,
                    set: a.tested,
                    missed: a.missed,
                    extra: a.extra,
                    columns,
                    columns_missed,
                };
                let (gpu_standard_ms, gpu_conservative_ms) = match gpu {
                    Some(r) => (
                        Some(
                            time(repeats, || {
                                Ok(r.build_prepared(&prepared.triangles, &cam, &o)?)
                            })?
                            .1,
                        ),
                        Some(
                            time(repeats, || {
                                let c = Options { coverage: Coverage::Conservative, ..o };
                                Ok(r.build_prepared(&prepared.triangles, &cam, &c)?)
                            })?
                            .1,
                        ),
                    ),
                    None => (None, None),
                };
                if !image_done && slicing == Slicing::Uniform {
                    let (cells, missed) = column_images(&standard, &reference);
                    out.images.push((format!("{slices} slices"), cells, missed));
                    image_done = true;
                }
                out.cells.push(CellRow {
                    scene: spec.clone(),
                    slicing: format!("{slicing:?}").to_lowercase(),
                    slices,
                    cells,
                    standard_ms,
                    exact_ms,
                    gpu_standard_ms,
                    gpu_conservative_ms,
                });
            }
        }
    }
    Ok(out)
}
