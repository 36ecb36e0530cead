//! `voxlod volume <preset>`: the procedural-volume trade of one particle preset.

use anyhow::{Context, Result, ensure};
use voxlod::eval::report::Report;
use voxlod::experiment::volume::{self, PRESETS, VolumeConfig};

use super::{Ui, backend, print_json};
use crate::cli::VolumeArgs;

/// Renders the preset, writes `<output>/report.md` (+ images, JSON) and prints the tables.
pub fn volume(ui: &Ui, args: VolumeArgs) -> Result<()> {
    ensure!(
        PRESETS.contains(&args.preset.as_str()),
        "unknown preset '{}': one of {}",
        args.preset,
        PRESETS.join(", ")
    );
    ensure!((1..=4096).contains(&args.image), "--image {} is out of range 1..=4096", args.image);
    ensure!(args.spp > 0, "--spp must be at least 1");
    ensure!(!args.m.is_empty(), "--m needs at least one metavoxel size");
    let config = VolumeConfig {
        preset: args.preset.clone(),
        particles: args.particles,
        resolution: args.res,
        metavoxel_sizes: args.m.clone(),
        image: args.image,
        mesh_spp: args.spp,
    };
    let (gpu, backend_name) = backend(args.backend)?;
    let spinner = ui.spinner();
    let progress = |msg: &str| spinner.set_message(msg.to_string());
    let result = volume::run_on(&config, gpu.as_ref(), &progress)
        .with_context(|| format!("rendering the volume preset '{}'", args.preset))?;
    let mut report = Report::new(format!("voxlod volume {}", args.preset));
    volume::add_to_report(&mut report, &result)?;
    let written = report
        .write(&args.output)
        .with_context(|| format!("writing the report into {}", args.output.display()))?;
    spinner.finish_and_clear();
    if args.json {
        return print_json(&result);
    }
    println!("backend: {backend_name}");
    if gpu.is_some() {
        println!(
            "(binning, fill, propagation and march on the GPU; the mesh's ground truth on the CPU)"
        );
    }
    for table in result.tables()? {
        println!("\n{}", table.to_markdown());
    }
    println!("\nreport written to {}", written.markdown.display());
    Ok(())
}
