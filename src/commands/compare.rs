//! `voxlod compare <scene>`: the filtered-appearance trade-off of one scene.

use std::time::Duration;

use anyhow::{Context, Result};
use voxlod::studies::filtered::FilteredConfig;
use voxlod::studies::paper::extras::{self, ExtrasConfig};
use voxlod::studies::paper::{self, PaperConfig};
use voxlod::studies::report::{self, Config, SceneCase};

use super::{Ui, backend, print_json};
use crate::cli::{BackendArg, CompareSceneArgs, SetupArg};

/// Runs the comparison, writes `<output>/report.md` (+ images, plots, JSON) and prints the
/// tables.
pub fn compare(ui: &Ui, args: CompareSceneArgs) -> Result<()> {
    if args.setup == SetupArg::Paper {
        return compare_paper(ui, args);
    }
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
        gt_spp: args.spp.unwrap_or(256),
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

/// `--setup paper`: the paper's conditions on the named scenes (CPU), paired intervals.
fn compare_paper(ui: &Ui, args: CompareSceneArgs) -> Result<()> {
    if args.backend != BackendArg::Cpu {
        anyhow::bail!("--setup paper runs on the CPU (the reference): drop --backend gpu");
    }
    let config = PaperConfig {
        scenes: paper::scenes_named(&args.scene, args.paper.coarse.clone()),
        resolutions: args.res.clone(),
        gt_spp: args.spp.unwrap_or(1024),
        views: args.views,
        seeds: args.paper.seeds,
        rays: args.rays,
        thresholds: args.thresholds.clone(),
        image_thresholds: args.image_thresholds.clone(),
        cache: super::ablation::cache_dir(&args.paper),
        command: super::invocation(),
        ..PaperConfig::full()
    };
    let spinner = ui.spinner();
    let progress = |msg: &str| spinner.set_message(msg.to_string());
    let result = paper::run(&config, &progress)
        .with_context(|| format!("comparing '{}' under the paper's conditions", args.scene))?;
    let extras = if args.extras {
        let e = ExtrasConfig { rays: args.sweep_rays.clone(), ..Default::default() };
        Some(extras::run(&config, &e, &progress).context("measuring the paper setup's extras")?)
    } else {
        None
    };
    let written = super::write_report("voxlod compare --setup paper", &args.output, |r| {
        result.add_to_report(r, &config)?;
        match &extras {
            Some(e) => e.add_to_report(r, &config),
            None => Ok(()),
        }
    })?;
    let json =
        serde_json::to_vec_pretty(&serde_json::json!({ "setup": &result, "extras": &extras }))?;
    let json_path = args.output.join("paper.json");
    voxlod::format::io::write_atomic(&json_path, |w| w.write_all(&json))
        .with_context(|| format!("writing {}", json_path.display()))?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("compare", &result);
    }
    for c in &result.cases {
        println!("\n{}", paper::findings(c));
    }
    for table in result.tables()? {
        println!("\n{}", table.to_markdown());
    }
    if let Some(e) = &extras {
        for table in e.tables(config.rays)? {
            println!("\n{}", table.to_markdown());
        }
    }
    println!("\nreport written to {} in {:.1} s", written.markdown.display(), result.wall_ms / 1e3);
    Ok(())
}
