//! `voxlod export`: a scene (voxelized, then filtered with the Averages fit) or a `.vxl` file
//! out to MagicaVoxel `.vox` or Mitsuba 3 `.vol`.
//!
//! Coordinates: a `.vol` bounding box is `f32`, which cannot place a grid of 10⁻³ voxels at
//! 10⁷. It is written relative to the scene's origin (`world = box + scene_origin`, printed and
//! in the JSON summary): for a scene that reaches near the world origin the origin is 0 and the
//! box is the world box; a far one keeps its own precision, the same box at any offset. A `.vxl`
//! input is re-centred by the same rule on its grid's box. `.vox` models carry no origin.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::DVec3;
use voxlod::cpu::appearance::averages;
use voxlod::cpu::appearance::line_sampler::SamplingContext;
use voxlod::cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod::cpu::voxelize;
use voxlod::format::origin::recentring_origin;
use voxlod::format::records::AverageRecord;
use voxlod::format::{BrickMap, GridSpec, Occupancy, VxlRecord, vol, vox, vxl};

use super::{Ui, load_scene, print_json};
use crate::cli::{ExportArgs, ExportFormat};

/// The sRGB8 colour given to every voxel of an occupancy-only input in a `.vox` file.
const OCCUPANCY_COLOR: [u8; 3] = [204, 204, 204];

/// What was exported (`--json`; fields in docs/json.md).
#[derive(serde::Serialize)]
struct Summary {
    input: String,
    input_kind: &'static str,
    records: &'static str,
    format: &'static str,
    dims: [u32; 3],
    voxel_size: f64,
    origin: [f64; 3],
    scene_origin: [f64; 3],
    voxels: usize,
    files: Vec<FileSummary>,
    models: Option<usize>,
    palette: Option<PaletteSummary>,
    prepare_s: f64,
    write_s: f64,
}

#[derive(serde::Serialize)]
struct FileSummary {
    path: String,
    content: &'static str,
    bytes: u64,
}

#[derive(serde::Serialize)]
struct PaletteSummary {
    method: &'static str,
    colors: usize,
    distinct_colors: usize,
    rms_error_srgb8: f64,
    max_error_srgb8: u8,
    rms_error_median_cut_srgb8: f64,
}

/// The voxels to export: Averages records, or occupancy only.
enum Voxels {
    Averages(BrickMap<AverageRecord>),
    Occupancy(BrickMap<Occupancy>),
}

/// Exports a scene or a `.vxl` file.
pub fn export(ui: &Ui, args: ExportArgs) -> Result<()> {
    let spinner = ui.spinner();
    let start = Instant::now();
    let is_vxl = Path::new(&args.input).extension().is_some_and(|e| e.eq_ignore_ascii_case("vxl"));
    let (grid, scene_origin, voxels) = if is_vxl {
        spinner.set_message(format!("reading {}", args.input));
        read_vxl(Path::new(&args.input))?
    } else {
        spinner.set_message(format!("loading {}", args.input));
        filter_scene(&args, |m| spinner.set_message(m))?
    };
    let prepare_s = start.elapsed().as_secs_f64();
    let out = &args.output.path;
    spinner.set_message(format!("writing {}", out.display()));
    let start = Instant::now();
    let (mut files, mut models, mut palette) = (Vec::new(), None, None);
    // A .vol box is f32: written relative to the scene's origin (see the module docs).
    let local = GridSpec { origin: grid.origin - scene_origin, ..grid };
    let write_err = || format!("exporting to {}", out.display());
    match args.output.format {
        ExportFormat::Vox => {
            let export = match &voxels {
                Voxels::Averages(map) => vox::write(out, map, |r| r.color),
                Voxels::Occupancy(map) => vox::write(out, map, |_| OCCUPANCY_COLOR),
            }
            .with_context(write_err)?;
            let e = export.palette.error;
            files.push(file(out, "occupancy and palette colours")?);
            models = Some(export.models);
            palette = Some(PaletteSummary {
                method: "median cut + k-means (Lloyd), sRGB8, weighted by voxel count",
                colors: export.palette.colors.len(),
                distinct_colors: e.distinct_colors,
                rms_error_srgb8: e.rms,
                max_error_srgb8: e.max,
                rms_error_median_cut_srgb8: e.rms_median_cut,
            });
        }
        ExportFormat::Vol => match &voxels {
            Voxels::Averages(map) => {
                let (density, albedo) =
                    vol::density_and_albedo(&local, map).with_context(write_err)?;
                let albedo_path = albedo_path(out);
                vol::write(out, &density).with_context(write_err)?;
                vol::write(&albedo_path, &albedo)
                    .with_context(|| format!("exporting to {}", albedo_path.display()))?;
                files.push(file(out, "density: extinction per world unit, 1 channel")?);
                files.push(file(&albedo_path, "albedo: linear RGB, 3 channels")?);
            }
            Voxels::Occupancy(map) => {
                let density = vol::occupancy_density(&local, map).with_context(write_err)?;
                vol::write(out, &density).with_context(write_err)?;
                files.push(file(out, "density: extinction per world unit, 1 channel")?);
            }
        },
    }
    let write_s = start.elapsed().as_secs_f64();
    spinner.finish_and_clear();
    let (records, count) = match &voxels {
        Voxels::Averages(m) => ("averages", m.len()),
        Voxels::Occupancy(m) => ("occupancy", m.len()),
    };
    let summary = Summary {
        input: args.input,
        input_kind: if is_vxl { "vxl" } else { "scene" },
        records,
        format: match args.output.format {
            ExportFormat::Vox => "vox",
            ExportFormat::Vol => "vol",
        },
        dims: grid.dims.to_array(),
        voxel_size: grid.voxel_size,
        origin: grid.origin.to_array(),
        scene_origin: scene_origin.to_array(),
        voxels: count,
        files,
        models,
        palette,
        prepare_s,
        write_s,
    };
    if args.json {
        return print_json("export", &summary);
    }
    println!(
        "{} ({}, {} records) → {} voxels in a {}×{}×{} grid, prepared in {:.3} s, written in {:.3} s",
        summary.input,
        summary.input_kind,
        summary.records,
        summary.voxels,
        summary.dims[0],
        summary.dims[1],
        summary.dims[2],
        summary.prepare_s,
        summary.write_s
    );
    if scene_origin != DVec3::ZERO {
        println!(
            "  scene origin {scene_origin} (world = local + origin); .vol boxes are local, .vox \
             models origin-free"
        );
    }
    for f in &summary.files {
        println!("  {} ({} bytes): {}", f.path, f.bytes, f.content);
    }
    if let (Some(m), Some(p)) = (summary.models, &summary.palette) {
        println!(
            "  {m} model(s); palette of {} colours from {} distinct, {}: RMS error {:.2}, max {} (sRGB8 units)",
            p.colors, p.distinct_colors, p.method, p.rms_error_srgb8, p.max_error_srgb8
        );
    }
    Ok(())
}

/// Where the albedo grid of `density.vol` goes: `density.albedo.vol`.
fn albedo_path(density: &Path) -> PathBuf {
    let stem = density.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    density.with_file_name(format!("{stem}.albedo.vol"))
}

fn file(path: &Path, content: &'static str) -> Result<FileSummary> {
    let bytes = std::fs::metadata(path)
        .with_context(|| format!("reading the size of {}", path.display()))?
        .len();
    Ok(FileSummary { path: path.display().to_string(), content, bytes })
}

/// A `.vxl` file of Averages or occupancy records: its (world) grid, the re-centring origin of
/// the grid's box, and its records.
fn read_vxl(path: &Path) -> Result<(GridSpec, DVec3, Voxels)> {
    let info = vxl::read_info(path)?;
    let origin = |g: &GridSpec| recentring_origin(g.origin, g.max_corner()).unwrap_or(DVec3::ZERO);
    if info.record_tag == AverageRecord::TAG {
        let f = vxl::read::<AverageRecord>(path)?;
        Ok((f.grid, origin(&f.grid), Voxels::Averages(f.map)))
    } else if info.record_tag == Occupancy::TAG {
        let f = vxl::read::<Occupancy>(path)?;
        Ok((f.grid, origin(&f.grid), Voxels::Occupancy(f.map)))
    } else {
        bail!(
            "{} holds {} records; export reads Averages ({}) or occupancy ({}) records",
            path.display(),
            vxl::tag_name(info.record_tag),
            vxl::tag_name(AverageRecord::TAG),
            vxl::tag_name(Occupancy::TAG)
        )
    }
}

/// Voxelizes a scene and fits an Averages record per voxel: the grid in world coordinates, the
/// scene's origin, the records.
fn filter_scene(args: &ExportArgs, say: impl Fn(String)) -> Result<(GridSpec, DVec3, Voxels)> {
    let scene = load_scene(&args.input)?;
    let geometry = scene.geometry();
    let (lo, hi) = scene.bounds()?;
    let grid = GridSpec::fit(lo.as_dvec3(), hi.as_dvec3(), args.res)
        .with_context(|| format!("fitting a {}³ grid to the scene", args.res))?;
    say(format!("voxelizing {} triangles into {}", geometry.triangle_count(), grid.dims));
    let vox = voxelize::voxelize(&geometry, &grid, &voxelize::Options::default())
        .context("voxelizing")?;
    say(format!(
        "fitting Averages records to {} voxels ({} rays each)",
        vox.voxels.len(),
        args.rays
    ));
    let ctx = SamplingContext::new(&scene, &geometry, &vox).context("preparing the sampling")?;
    let opts = PrecomputeOptions { rays: args.rays, seed: 0 };
    let fitted = precompute(&ctx, &opts, averages::fit).context("fitting Averages records")?;
    let world = GridSpec { origin: fitted.grid.origin + scene.origin, ..fitted.grid };
    Ok((world, scene.origin, Voxels::Averages(fitted.records)))
}
