//! `voxlod compare <scene>`: the filtered-appearance trade-off of one scene.

use std::time::Duration;

use anyhow::{Context, Result};
use voxlod::studies::filtered::FilteredConfig;
use voxlod::studies::report::{self, Config, SceneCase};

use super::{Ui, backend, print_json};
use crate::cli::CompareSceneArgs;

/// Runs the comparison, writes `<output>/report.md` (+ images, plots, JSON) and prints the
/// tables.
pub fn compare(ui: &Ui, args: CompareSceneArgs) -> Result<()> {
    let filtered = FilteredConfig {
        resolutions: args.res.clone(),
        higher_image: (args.image > 0).then_some(args.image),
        rays: args.rays,
        thresholds: args.thresholds.clone(),
        ..FilteredConfig::quick()
    };
    let config = Config {
        scenes: vec![SceneCase::new(&args.scene, "scene")],
        resolutions: args.res.clone(),
        image_size: args.res[0],
        gt_spp: args.spp,
        views: args.views,
        section_budget: Duration::MAX,
        filtered: Some(filtered),
        volume: None,
        cone: None,
        command: super::invocation(),
        ..Config::quick()
    };
    // No adapter is an error, never a fall-back to the CPU.
    let gpu = backend(args.backend)?;
    let on = super::on(&gpu);
    let spinner = ui.spinner();
    let progress = |msg: &str| spinner.set_message(msg.to_string());
    let outcome = report::run(&config, on, &progress)
        .with_context(|| format!("comparing representations of '{}'", args.scene))?;
    let written = outcome
        .report
        .write(&args.output)
        .with_context(|| format!("writing the report into {}", args.output.display()))?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("compare", &outcome.scenes);
    }
    if gpu.is_some() {
        // The CPU run prints what it always did; a GPU run says which adapter rendered what.
        println!("backend: {}", on.describe());
        println!(
            "(ground truth and every representation rendered on the GPU, Averages also \
             precomputed there: see each row's backend and 'precompute on')"
        );
    }
    for scene in &outcome.scenes {
        if let Some(f) = &scene.filtered {
            for table in f.tables(&scene.label)? {
                println!("\n{}", table.to_markdown());
            }
        }
    }
    println!(
        "\nreport written to {} in {:.1} s",
        written.markdown.display(),
        outcome.elapsed.as_secs_f64()
    );
    Ok(())
}
