//! `voxlod report` (the default command): run the default report and write it.

use anyhow::{Context, Result};
use voxlod::studies::report::{self, Config};

use super::{Ui, backend, print_json};
use crate::cli::ReportArgs;

/// Runs the default report, writes `<output>/report.md` (+ assets, JSON) and prints the
/// tables.
pub fn report(ui: &Ui, args: ReportArgs) -> Result<()> {
    let preset = if args.full { Config::full() } else { Config::quick() };
    let mut config = Config { command: super::invocation(), ..preset };
    if let Some(frames) = args.turntable {
        config = config.with_turntable(frames as usize);
    }
    // No adapter is an error, never a fall-back to the CPU.
    let gpu = backend(args.backend)?;
    let on = super::on(&gpu);
    let spinner = ui.spinner();
    let progress = |msg: &str| spinner.set_message(msg.to_string());
    let outcome = report::run(&config, on, &progress).context("running the report")?;
    spinner.set_message(format!("writing {}", args.output.display()));
    let written = outcome
        .report
        .write(&args.output)
        .with_context(|| format!("writing the report into {}", args.output.display()))?;
    spinner.finish_and_clear();
    if args.json {
        return print_json("report", &outcome.scenes);
    }
    if gpu.is_some() {
        println!("backend: {} (see each row's backend)", on.describe());
    }
    for scene in &outcome.scenes {
        println!("\n## {} ({} triangles)\n", scene.label, scene.triangles);
        println!("{}", scene.table()?.to_markdown());
    }
    println!(
        "\nreport written to {} in {:.1} s",
        written.markdown.display(),
        outcome.elapsed.as_secs_f64()
    );
    Ok(())
}
