//! `voxlod ablation SCENE`: the paper setup of the filtered-appearance comparison and one
//! deviation at a time, with paired intervals.

use anyhow::{Context, Result};
use voxlod::studies::paper::ablation::{self, Toggle};
use voxlod::studies::paper::{self, PaperConfig};

use super::{Ui, print_json};
use crate::cli::{AblationArgs, PaperArgs, ToggleArg};

/// The cache directory the options name (None: no cache).
pub(super) fn cache_dir(args: &PaperArgs) -> Option<std::path::PathBuf> {
    if args.no_cache {
        return None;
    }
    if let Some(dir) = &args.cache {
        return Some(dir.clone());
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(std::path::PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| std::path::PathBuf::from(h).join(".cache")))?;
    Some(base.join("voxlod").join("ground-truth"))
}

/// Runs the ablation, writes `<output>/report.md` (+ JSON) and prints the tables.
pub fn ablation(ui: &Ui, args: AblationArgs) -> Result<()> {
    let toggles: Vec<Toggle> = if args.toggles.is_empty() {
        Toggle::ALL.to_vec()
    } else {
        args.toggles
            .iter()
            .map(|t| match t {
                ToggleArg::CoarseMesh => Toggle::CoarseMesh,
                ToggleArg::RedBackground => Toggle::RedBackground,
                ToggleArg::SceneBackground => Toggle::SceneBackground,
                ToggleArg::SunOnly => Toggle::SunOnly,
                ToggleArg::LinesOpacity => Toggle::LinesOpacityRule,
                ToggleArg::CirclesOpacity => Toggle::CirclesOpacityRule,
                ToggleArg::FixedFaceSamples => Toggle::FixedFaceSamples,
                ToggleArg::StoredNormalsFallback => Toggle::StoredNormalsFallback,
                ToggleArg::PerRayChord => Toggle::PerRayChord,
                ToggleArg::FlippedAveragesNormal => Toggle::FlippedAveragesNormal,
                ToggleArg::FixedPixelPattern => Toggle::FixedPixelPattern,
                ToggleArg::AllOurs => Toggle::AllOurs,
                ToggleArg::Crop => Toggle::Crop,
            })
            .collect()
    };
    let config = PaperConfig {
        scenes: paper::scenes_named(&args.scene, args.paper.coarse.clone()),
        resolutions: args.res.clone(),
        gt_spp: args.spp,
        views: args.views,
        seeds: args.paper.seeds,
        rays: args.rays,
        thresholds: args.thresholds.clone(),
        image_thresholds: args.image_thresholds.clone(),
        cache: cache_dir(&args.paper),
        command: super::invocation(),
        ..PaperConfig::full()
    };
    let spinner = ui.spinner();
    let progress = |msg: &str| spinner.set_message(msg.to_string());
    let result = ablation::run(&config, &toggles, &progress)
        .with_context(|| format!("ablating the paper setup on '{}'", args.scene))?;
    let written =
        super::write_report("voxlod ablation", &args.output, |r| result.add_to_report(r, &config))?;
    let json = serde_json::to_vec_pretty(&result)?;
    let json_path = args.output.join("ablation.json");
    voxlod::format::io::write_atomic(&json_path, |w| w.write_all(&json))
        .with_context(|| format!("writing {}", json_path.display()))?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("ablation", &result);
    }
    for table in result.tables()? {
        println!("\n{}", table.to_markdown());
    }
    println!(
        "\nreport written to {} in {:.1} s",
        written.markdown.display(),
        result.result.wall_ms / 1e3
    );
    Ok(())
}
