//! `voxlod export`: a scene (voxelized, then filtered with the Averages fit), a `.vxl` file or
//! a procedural volume's density out to MagicaVoxel `.vox`, Mitsuba 3 `.vol` or NanoVDB
//! `.nvdb`.
//!
//! Coordinates: a `.vol` bounding box is `f32`, which cannot place a grid of 10⁻³ voxels at
//! 10⁷. It is written relative to the scene's origin (`world = box + scene_origin`, printed and
//! in the JSON summary): for a scene that reaches near the world origin the origin is 0 and the
//! box is the world box; a far one keeps its own precision, the same box at any offset. A `.vxl`
//! input is re-centred by the same rule on its grid's box. `.nvdb` keeps the world grid (its map
//! is `f64`); `.vox` models carry no origin.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::DVec3;
use voxlod::cpu::appearance::averages;
use voxlod::cpu::appearance::line_sampler::SamplingContext;
use voxlod::cpu::appearance::precompute::{PrecomputeOptions, precompute};
use voxlod::cpu::volume::{self, BuildSettings, VolumeSpec};
use voxlod::cpu::voxelize;
use voxlod::format::nvdb::{self, GridClass, NvdbGrid};
use voxlod::format::origin::recentring_origin;
use voxlod::format::records::AverageRecord;
use voxlod::format::{BrickMap, GridSpec, Occupancy, VxlRecord, vol, vox, vxl};

use super::{Ui, load_scene, print_json};
use crate::cli::{ExportArgs, ExportFormat};

/// The prefix of a procedural volume input (`volume:smoke`).
const VOLUME_PREFIX: &str = "volume:";
/// Largest `--res` of a volume input: 128 metavoxels of 32³ voxels per axis.
const MAX_VOLUME_RES: u32 = 4096;

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
    grids: Option<Vec<NvdbGridSummary>>,
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
struct NvdbGridSummary {
    name: String,
    value_type: &'static str,
    grid_class: &'static str,
    active_voxels: u64,
    leaf_nodes: u32,
    lower_nodes: u32,
    upper_nodes: u32,
    bytes: u64,
    checksum: String,
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

/// The voxels to export: Averages records, occupancy only, or a density (extinction per world
/// unit).
enum Voxels {
    Averages(BrickMap<AverageRecord>),
    Occupancy(BrickMap<Occupancy>),
    Density(BrickMap<f32>),
}

/// Exports a scene or a `.vxl` file.
pub fn export(ui: &Ui, args: ExportArgs) -> Result<()> {
    let spinner = ui.spinner();
    let start = Instant::now();
    let is_vxl = Path::new(&args.input).extension().is_some_and(|e| e.eq_ignore_ascii_case("vxl"));
    let volume_preset = args.input.strip_prefix(VOLUME_PREFIX);
    let (grid, scene_origin, voxels) = if is_vxl {
        spinner.set_message(format!("reading {}", args.input));
        read_vxl(Path::new(&args.input))?
    } else if let Some(preset) = volume_preset {
        if args.output.format == ExportFormat::Vox {
            bail!(
                "{} is a density: export it to .vol (Mitsuba 3) or .nvdb (NanoVDB), not .vox",
                args.input
            );
        }
        spinner.set_message(format!("building the {preset} volume"));
        let (grid, voxels) = volume_density(preset, args.res)?;
        (grid, DVec3::ZERO, voxels)
    } else {
        spinner.set_message(format!("loading {}", args.input));
        filter_scene(&args, |m| spinner.set_message(m))?
    };
    let prepare_s = start.elapsed().as_secs_f64();
    let out = &args.output.path;
    spinner.set_message(format!("writing {}", out.display()));
    let start = Instant::now();
    let (mut files, mut models, mut palette, mut grids) = (Vec::new(), None, None, None);
    // A .vol box is f32: written relative to the scene's origin (see the module docs).
    let local = GridSpec { origin: grid.origin - scene_origin, ..grid };
    let write_err = || format!("exporting to {}", out.display());
    match args.output.format {
        ExportFormat::Vox => {
            let export = match &voxels {
                Voxels::Averages(map) => vox::write(out, map, |r| r.color),
                Voxels::Occupancy(map) => vox::write(out, map, |_| OCCUPANCY_COLOR),
                Voxels::Density(map) => vox::write(out, map, |_| OCCUPANCY_COLOR),
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
            Voxels::Density(map) => {
                let density = vol::VolGrid::from_brick_map(&local, map, [0.0], |&d| [d])
                    .with_context(write_err)?;
                vol::write(out, &density).with_context(write_err)?;
                files.push(file(out, "density: extinction per world unit, 1 channel")?);
            }
        },
        ExportFormat::Nvdb => {
            let (written, content) = match &voxels {
                Voxels::Averages(map) => {
                    let (density, color) =
                        nvdb::density_and_color(&grid, map).with_context(write_err)?;
                    let grids = [density.into(), color.into()];
                    let content = "grids `density` (float fog volume: extinction per world unit) \
                                   and `color` (Vec3f: linear RGB)";
                    (nvdb::write(out, &grids), content)
                }
                Voxels::Occupancy(map) => {
                    let density = nvdb::occupancy_density(&grid, map).with_context(write_err)?;
                    let content = "grid `density` (float fog volume: extinction per world unit)";
                    (nvdb::write(out, &[density.into()]), content)
                }
                Voxels::Density(map) => {
                    let density = NvdbGrid::from_brick_map(
                        "density",
                        GridClass::FogVolume,
                        &grid,
                        map,
                        |&d| d,
                    )
                    .with_context(write_err)?;
                    let content = "grid `density` (float fog volume: extinction per world unit)";
                    (nvdb::write(out, &[density.into()]), content)
                }
            };
            let written = written.with_context(write_err)?;
            files.push(file(out, content)?);
            grids = Some(written.iter().map(grid_summary).collect());
        }
    }
    let write_s = start.elapsed().as_secs_f64();
    spinner.finish_and_clear();
    let (records, count) = match &voxels {
        Voxels::Averages(m) => ("averages", m.len()),
        Voxels::Occupancy(m) => ("occupancy", m.len()),
        Voxels::Density(m) => ("density", m.len()),
    };
    let input_kind = match (is_vxl, volume_preset) {
        (true, _) => "vxl",
        (false, Some(_)) => "volume",
        (false, None) => "scene",
    };
    let summary = Summary {
        input: args.input,
        input_kind,
        records,
        format: match args.output.format {
            ExportFormat::Vox => "vox",
            ExportFormat::Vol => "vol",
            ExportFormat::Nvdb => "nvdb",
        },
        dims: grid.dims.to_array(),
        voxel_size: grid.voxel_size,
        origin: grid.origin.to_array(),
        scene_origin: scene_origin.to_array(),
        voxels: count,
        files,
        models,
        palette,
        grids,
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
    for g in summary.grids.iter().flatten() {
        println!(
            "  grid {:?}: {} {}, {} active voxels in {} leaves, {} lower and {} upper nodes, \
             {} bytes, checksum {}",
            g.name,
            g.value_type,
            g.grid_class,
            g.active_voxels,
            g.leaf_nodes,
            g.lower_nodes,
            g.upper_nodes,
            g.bytes,
            g.checksum
        );
    }
    if let (Some(m), Some(p)) = (summary.models, &summary.palette) {
        println!(
            "  {m} model(s); palette of {} colours from {} distinct, {}: RMS error {:.2}, max {} (sRGB8 units)",
            p.colors, p.distinct_colors, p.method, p.rms_error_srgb8, p.max_error_srgb8
        );
    }
    Ok(())
}

fn grid_summary(g: &nvdb::GridSummary) -> NvdbGridSummary {
    let (value_type, grid_class) = match g.grid_type {
        nvdb::GridType::Float => ("float", "fog volume"),
        _ => ("Vec3f", "unknown"),
    };
    NvdbGridSummary {
        name: g.name.clone(),
        value_type,
        grid_class,
        active_voxels: g.voxels,
        leaf_nodes: g.nodes[0],
        lower_nodes: g.nodes[1],
        upper_nodes: g.nodes[2],
        bytes: g.bytes,
        checksum: format!("{:#018x}", g.checksum),
    }
}

/// The density of the particles of volume preset `preset` (its default particle count, at the
/// time the preset shows), sampled at the voxel centres of a world-aligned cube of `res³`
/// voxels around them: extinction per world unit, voxels of zero density left out.
///
/// The volume is built with the light straight above, which makes the metavoxel frame
/// axis-aligned (the density does not depend on the light, only the frame does); the voxels
/// are then re-indexed onto world axes.
fn volume_density(preset: &str, res: u32) -> Result<(GridSpec, Voxels)> {
    if res > MAX_VOLUME_RES {
        bail!("--res {res}: a volume export has at most {MAX_VOLUME_RES} voxels per axis");
    }
    let system = voxlod::studies::volume::preset(preset, 0)
        .with_context(|| format!("the volume preset '{preset}'"))?;
    let spheres = system.at(system.time);
    let Some((lo, hi)) = voxlod::scene::particles::bounds(&spheres) else {
        bail!("the volume preset '{preset}' has no particle alive");
    };
    // M: the largest power of two up to 32 dividing res; K = res / M ≤ 128.
    let m = (0..=5).rev().map(|p| 1u32 << p).find(|&m| res.is_multiple_of(m)).unwrap_or(1);
    if res / m > volume::MAX_METAVOXELS_PER_AXIS {
        bail!(
            "--res {res}: the volume is split into {} metavoxels of {m}³ per axis, over the {} \
             its index holds; use a multiple of 32",
            res / m,
            volume::MAX_METAVOXELS_PER_AXIS
        );
    }
    let spec = VolumeSpec::fit(lo, hi, glam::Vec3::Y, res / m, m)?;
    let built = volume::build(
        &spheres,
        &system.displacement,
        &spec,
        &BuildSettings::default(),
        None,
        None,
    )?;
    let f = spec.frame;
    let axes = [f.u, f.v, f.w];
    if axes.iter().any(|a| (a.abs().max_element() - 1.0).abs() > 1e-6) {
        bail!("the volume frame {axes:?} is not axis-aligned");
    }
    // World-aligned grid: the frame's cube, its minimum corner as origin.
    let size = f.voxel_size as f64;
    let n = res as f64;
    let world = |q: DVec3| {
        f.origin.as_dvec3()
            + (f.u.as_dvec3() * q.x + f.v.as_dvec3() * q.y + f.w.as_dvec3() * q.z) * size
    };
    let origin = (0..8)
        .map(|c| world(DVec3::new((c & 1) as f64, (c >> 1 & 1) as f64, (c >> 2) as f64) * n))
        .fold(DVec3::INFINITY, DVec3::min);
    let grid = GridSpec::new(origin, size, glam::UVec3::splat(res))?;
    let edge = spec.metavoxel_edge;
    let mut voxels = Vec::new();
    for mv in &built.metavoxels {
        let base = glam::UVec3::from_array(mv.coord) * edge;
        for (i, v) in mv.voxels.iter().enumerate() {
            if v.w <= 0.0 {
                continue;
            }
            let i = i as u32;
            let local = glam::UVec3::new(i % edge, i / edge % edge, i / (edge * edge));
            let centre = world((base + local).as_dvec3() + 0.5);
            let cell = ((centre - origin) / size - 0.5).round();
            if cell.min_element() < 0.0 || cell.max_element() >= n {
                bail!("volume voxel {} re-indexed outside the grid at {cell}", base + local);
            }
            voxels.push((cell.as_uvec3(), v.w));
        }
    }
    let map = BrickMap::from_voxels(grid.dims, voxels)
        .context("re-indexing the volume's voxels onto world axes")?;
    Ok((grid, Voxels::Density(map)))
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

/// A `.vxl` file of Averages or occupancy records.
fn read_vxl(path: &Path) -> Result<(GridSpec, DVec3, Voxels)> {
    let origin = |g: &GridSpec| recentring_origin(g.origin, g.max_corner()).unwrap_or(DVec3::ZERO);
    let info = vxl::read_info(path)?;
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

/// Voxelizes a scene and fits an Averages record per voxel.
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
