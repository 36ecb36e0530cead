//! `voxlod import`: MagicaVoxel `.vox` or Mitsuba 3 `.vol` into a `.vxl` of Averages records
//! (or of four `f32` per voxel with `--f32`), through `voxlod_format::import`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use voxlod::format::{GridSpec, import, vol, vox, vxl};

use super::{Ui, print_json};
use crate::cli::{ImportArgs, ImportFormat};

#[derive(serde::Serialize)]
struct Summary {
    input: String,
    format: &'static str,
    /// `.vox`: models and shape instances in the file.
    #[serde(skip_serializing_if = "Option::is_none")]
    models: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    instances: Option<usize>,
    /// `.vol`: the albedo grid read, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    albedo: Option<String>,
    records: &'static str,
    dims: [u32; 3],
    voxel_size: f64,
    origin: [f64; 3],
    voxels: usize,
    seconds: f64,
    output: String,
}

/// Imports a `.vox` or `.vol` file into a `.vxl` file.
pub fn import(ui: &Ui, args: ImportArgs) -> Result<()> {
    let spinner = ui.spinner();
    let input = &args.input.path;
    spinner.set_message(format!("reading {}", input.display()));
    let start = Instant::now();
    let source = input.display().to_string();
    let mut meta = vec![
        ("source".to_string(), source.clone()),
        ("generator".to_string(), format!("voxlod {}", env!("CARGO_PKG_VERSION"))),
    ];
    let write_err = || format!("writing {}", args.output.display());
    let (mut models, mut instances, mut albedo_used) = (None, None, None);
    let (format, grid, voxels, records): (_, GridSpec, usize, _) = match args.input.format {
        ImportFormat::Vox => {
            if args.f32 || args.albedo.is_some() {
                bail!("--f32 and --albedo apply to .vol inputs; {} is a .vox file", source);
            }
            let file = vox::read(input)?;
            models = Some(file.models.len());
            instances = Some(file.instances.len());
            let size = args.voxel_size.unwrap_or(1.0);
            let (grid, map) = import::vox_to_averages(&file, size, input)
                .with_context(|| format!("importing {source}"))?;
            meta.push(("format".into(), "MagicaVoxel .vox".into()));
            vxl::write(&args.output, &grid, &map, &meta).with_context(write_err)?;
            ("vox", grid, map.len(), "averages")
        }
        ImportFormat::Vol => {
            if args.voxel_size.is_some() {
                bail!("--voxel-size applies to .vox inputs: a .vol's box and cells set its voxels");
            }
            let density = vol::read(input)?;
            let albedo_path = match &args.albedo {
                Some(p) => Some(p.clone()),
                None => Some(albedo_beside(input)).filter(|p| p.exists()),
            };
            let albedo = match &albedo_path {
                Some(p) => Some(
                    vol::read(p).with_context(|| format!("reading the albedo {}", p.display()))?,
                ),
                None => None,
            };
            albedo_used = albedo_path.map(|p| p.display().to_string());
            meta.push((
                "format".into(),
                "Mitsuba 3 .vol (density → opacity 1 − exp(−σ·size))".into(),
            ));
            if let Some(a) = &albedo_used {
                meta.push(("albedo".into(), a.clone()));
            }
            let context = || format!("importing {source}");
            if args.f32 {
                let (grid, map) = import::vol_to_rgba_f32(&density, albedo.as_ref(), input)
                    .with_context(context)?;
                vxl::write(&args.output, &grid, &map, &meta).with_context(write_err)?;
                ("vol", grid, map.len(), "rgba-f32")
            } else {
                let (grid, map) = import::vol_to_averages(&density, albedo.as_ref(), input)
                    .with_context(context)?;
                vxl::write(&args.output, &grid, &map, &meta).with_context(write_err)?;
                ("vol", grid, map.len(), "averages")
            }
        }
    };
    spinner.finish_and_clear();
    let summary = Summary {
        input: source,
        format,
        models,
        instances,
        albedo: albedo_used,
        records,
        dims: grid.dims.to_array(),
        voxel_size: grid.voxel_size,
        origin: grid.origin.to_array(),
        voxels,
        seconds: start.elapsed().as_secs_f64(),
        output: args.output.display().to_string(),
    };
    if args.json {
        return print_json("import", &summary);
    }
    println!(
        "{} ({}) → {} voxels of {} records in a {}×{}×{} grid (voxel size {}), {:.3} s → {}",
        summary.input,
        summary.format,
        summary.voxels,
        summary.records,
        summary.dims[0],
        summary.dims[1],
        summary.dims[2],
        summary.voxel_size,
        summary.seconds,
        summary.output
    );
    if let (Some(m), Some(i)) = (summary.models, summary.instances) {
        println!("  {m} model(s) placed {i} time(s) by the scene graph");
    }
    if let Some(a) = &summary.albedo {
        println!("  albedo from {a}");
    }
    Ok(())
}

/// `NAME.albedo.vol` beside `NAME.vol` (what `voxlod export` writes).
fn albedo_beside(density: &Path) -> PathBuf {
    let stem = density.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    density.with_file_name(format!("{stem}.albedo.vol"))
}
