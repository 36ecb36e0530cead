//! `voxlod cone <scene>`: voxel cone tracing against ray-traced references (the cone study).

use anyhow::{Context, Result};
use voxlod::studies::cone::{self, ConeConfig, LodConfig};

use super::{Ui, backend, print_json};
use crate::cli::ConeArgs;

/// Runs the cone study, writes `<output>/report.md` (+ JSON, plots, images) and prints the
/// tables.
pub fn cone(ui: &Ui, args: ConeArgs) -> Result<()> {
    let lod = (args.lod_scene != "none").then(|| LodConfig {
        scene: args.lod_scene.clone(),
        resolution: args.lod_res,
        image_size: args.lod_size,
        biases: args.lod_bias.clone(),
        step: args.lod_step,
        zoom_out: args.lod_zoom_out,
        spp: args.lod_spp,
    });
    let config = ConeConfig {
        scene: args.scene.clone(),
        resolutions: args.res.clone(),
        cones: args.cones.clone(),
        apertures_deg: args.apertures.clone(),
        steps: args.steps.clone(),
        image_size: args.size,
        spp: args.spp,
        ao_radius: args.ao_radius,
        lod,
    };
    // No adapter is an error, never a fall-back to the CPU.
    let gpu = backend(args.backend)?;
    let on = super::on(&gpu);
    let spinner = ui.spinner();
    let say = |m: &str| spinner.set_message(m.to_string());
    let result =
        cone::run(&config, on, &say).with_context(|| format!("cone tracing '{}'", args.scene))?;
    let written =
        super::write_report(&format!("voxel cone tracing: {}", result.scene), &args.output, |r| {
            result.add_to_report(r)
        })?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("cone", &result);
    }
    println!("backend: {} (the sweep's cone tracing)", result.backend);
    for t in result.tables()? {
        println!("\n{}", t.to_markdown());
    }
    println!("\nreport written to {}", written.markdown.display());
    Ok(())
}
