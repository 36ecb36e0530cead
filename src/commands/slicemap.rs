//! `voxlod slicemap [SCENE]`: what slicemaps miss, and their transmittance shadows and
//! traversed volume, on one scene or the preset's scenes.

use anyhow::{Context, Result};
use voxlod::studies::slicemap::{self, SlicemapConfig};

use super::{Ui, backend, print_json};
use crate::cli::SlicemapArgs;

/// Runs the chosen parts on the scene, writes `<output>/report.md` (+ images, JSON,
/// `slicemap.json`) and prints the tables.
pub fn slicemap(ui: &Ui, args: SlicemapArgs) -> Result<()> {
    let base = if args.full { SlicemapConfig::full() } else { SlicemapConfig::quick() };
    let mut config = match &args.scene {
        Some(scene) => base.for_scene(scene),
        None => base,
    };
    let what = args.scene.as_ref().map_or("the preset's scenes".into(), |s| format!("'{s}'"));
    let wants = |part: &str| args.parts.iter().any(|p| p == part);
    if !wants("holes") {
        config.holes = None;
    }
    if !wants("shadows") {
        config.shadows = None;
    }
    if !wants("refraction") {
        config.refraction = None;
    }
    if !args.slices.is_empty() {
        if let Some(h) = &mut config.holes {
            h.slices = args.slices.clone();
        }
        if let Some(r) = &mut config.refraction {
            r.slices = args.slices.clone();
            r.shown_slices = args.slices[0];
        }
    }
    if let (Some(h), Some(r)) = (&mut config.holes, args.res) {
        h.resolution = r;
    }
    if let (Some(h), Some(n)) = (&mut config.holes, args.map_size) {
        h.map_size = n;
    }
    if let (Some(s), Some(n)) = (&mut config.shadows, args.map_size) {
        let slices = if args.slices.is_empty() { vec![32, 96, 512] } else { args.slices.clone() };
        s.maps = slices.into_iter().map(|k| (n, k)).collect();
    }
    if let Some(s) = &mut config.shadows {
        s.transmissive = args.transmissive.clone();
        s.sigma = args.sigma;
        if let Some(w) = args.image {
            s.height = (w * s.height / s.width).max(1);
            s.width = w;
        }
    }
    if let (Some(r), Some(w)) = (&mut config.refraction, args.image) {
        r.height = (w * r.height / r.width).max(1);
        r.width = w;
    }
    let gpu = backend(args.backend)?;
    let on = super::on(&gpu);
    let spinner = ui.spinner();
    let progress = |msg: &str| spinner.set_message(msg.to_string());
    let result = slicemap::run(&config, on, &progress)
        .with_context(|| format!("measuring the slicemaps of {what}"))?;
    let title = format!("voxlod slicemap {}", args.scene.as_deref().unwrap_or_default());
    let written = super::write_report(title.trim_end(), &args.output, |r| result.add_to_report(r))?;
    let json = serde_json::to_vec_pretty(&result.to_json())?;
    let json_path = args.output.join("slicemap.json");
    voxlod::format::io::write_atomic(&json_path, |w| w.write_all(&json))
        .with_context(|| format!("writing {}", json_path.display()))?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("slicemap", &result.to_json());
    }
    println!("backend: {}", on.describe());
    for table in result.tables()? {
        println!("\n{}", table.to_markdown());
    }
    println!("\nreport written to {}", written.markdown.display());
    Ok(())
}
