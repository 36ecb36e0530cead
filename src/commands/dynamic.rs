//! `voxlod dynamic <scene>`: dynamic scenes by voxel transformation against re-voxelization
//! (the dynamic study), and a frame sequence through the pipeline on either backend.

use anyhow::{Context, Result};
use voxlod::studies::dynamic::{self, DynamicConfig};

use super::{Ui, backend, print_json};
use crate::cli::DynamicArgs;

/// Runs the dynamic study, writes `<output>/report.md` (+ JSON, plot, images) and prints the
/// tables.
pub fn dynamic(ui: &Ui, args: DynamicArgs) -> Result<()> {
    let preset = if args.full { DynamicConfig::full() } else { DynamicConfig::quick() };
    let mut config = DynamicConfig { scene: args.scene.clone(), voxel_size: args.voxel, ..preset };
    if !args.times.is_empty() {
        config.times = args.times.clone();
    }
    if args.walkers == [0] {
        config.scaling = None;
    } else if let (false, Some(s)) = (args.walkers.is_empty(), config.scaling.as_mut()) {
        s.walkers = args.walkers.clone();
    }
    if let Some(f) = args.frames {
        config.frames = f;
    }
    if let Some(w) = args.width {
        config.image_width = w;
    }
    if let Some(s) = args.spp {
        config.spp = s;
    }
    if args.no_extras {
        config.rotations = false;
        config.stability = None;
    }
    // No adapter is an error, never a fall-back to the CPU.
    let gpu = backend(args.backend)?;
    let on = super::on(&gpu);
    let spinner = ui.spinner();
    let say = |m: &str| spinner.set_message(m.to_string());
    let result = dynamic::run(&config, on, &say)
        .with_context(|| format!("dynamic scene '{}'", args.scene))?;
    let written =
        super::write_report(&format!("dynamic scenes: {}", result.scene), &args.output, |r| {
            result.add_to_report(r)
        })?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("dynamic", &result);
    }
    println!("backend: {} (the frame sequence)", result.backend);
    for t in result.tables()? {
        println!("\n{}", t.to_markdown());
    }
    println!("\nreport written to {}", written.markdown.display());
    Ok(())
}
