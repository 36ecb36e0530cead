//! `voxlod volume <preset>`: the procedural-volume trade of one particle preset.

use anyhow::{Context, Result};
use voxlod::studies::volume::{self, VolumeConfig};

use super::{Ui, backend, print_json};
use crate::cli::VolumeArgs;

/// Renders the preset, writes `<output>/report.md` (+ images, JSON) and prints the tables.
pub fn volume(ui: &Ui, args: VolumeArgs) -> Result<()> {
    let config = VolumeConfig {
        preset: args.preset.clone(),
        particles: args.particles,
        resolution: args.res,
        metavoxel_sizes: args.m.clone(),
        image: args.image,
        mesh_spp: args.spp,
    };
    let gpu = backend(args.backend)?;
    let on = super::on(&gpu);
    let spinner = ui.spinner();
    let progress = |msg: &str| spinner.set_message(msg.to_string());
    let result = volume::run(&config, on, &progress)
        .with_context(|| format!("rendering the volume preset '{}'", args.preset))?;
    let written =
        super::write_report(&format!("voxlod volume {}", args.preset), &args.output, |r| {
            result.add_to_report(r)
        })?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("volume", &result);
    }
    println!("backend: {}", on.describe());
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
