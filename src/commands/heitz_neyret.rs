//! `voxlod heitz-neyret`: Heitz–Neyret surface statistics with coverage masks against alpha
//! blending over distance (the study of `voxlod_studies::heitz_neyret`).

use anyhow::{Context, Result};
use voxlod::studies::heitz_neyret::{self, HeitzNeyretConfig, SceneCase};

use super::{Ui, backend, print_json};
use crate::cli::HeitzNeyretArgs;

/// A scene given on the command line, with the flags its spec implies (see the argument's
/// help).
fn case(spec: &str) -> SceneCase {
    let name = spec.strip_prefix("builtin:").unwrap_or(spec).split('?').next().unwrap_or("");
    SceneCase {
        spec: spec.to_string(),
        label: name.to_string(),
        in_domain: !matches!(name, "forest" | "island" | "blinds"),
        radial: name.starts_with("bumpy-"),
    }
}

/// Runs the study, writes `<output>/report.md` (+ JSON, plot, images) and prints the tables.
pub fn heitz_neyret(ui: &Ui, args: HeitzNeyretArgs) -> Result<()> {
    let preset = if args.full { HeitzNeyretConfig::full() } else { HeitzNeyretConfig::quick() };
    let config = HeitzNeyretConfig {
        scenes: if args.scenes.is_empty() {
            preset.scenes.clone()
        } else {
            args.scenes.iter().map(|s| case(s)).collect()
        },
        resolution: args.res.unwrap_or(preset.resolution),
        image_size: args.size.unwrap_or(preset.image_size),
        zooms: if args.zooms.is_empty() { preset.zooms.clone() } else { args.zooms.clone() },
        spp: args.spp.unwrap_or(preset.spp),
        rays: args.rays.unwrap_or(preset.rays),
        repeats: args.repeats.unwrap_or(preset.repeats),
        depth_of_field: !args.no_dof,
    };
    let gpu = backend(args.backend)?;
    let on = super::on(&gpu);
    let spinner = ui.spinner();
    let say = |m: &str| spinner.set_message(m.to_string());
    let result = heitz_neyret::run(&config, on, &say).context("the Heitz–Neyret study")?;
    let written = super::write_report(
        "Heitz–Neyret: surface statistics and coverage masks",
        &args.output,
        |r| result.add_to_report(r),
    )?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("heitz-neyret", &result);
    }
    println!("backend: {}", result.backend);
    for t in result.tables()? {
        println!("\n{}", t.to_markdown());
    }
    println!("\nreport written to {}", written.markdown.display());
    Ok(())
}
