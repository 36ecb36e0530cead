//! `voxlod report` (the default command): run the default experiment and write the report.

use anyhow::{Context, Result};
use voxlod::experiment::{self, Backend, Config};

use super::{Ui, backend, print_json};
use crate::cli::ReportArgs;

/// Runs the default experiment, writes `<output>/report.md` (+ assets, JSON) and prints the
/// tables.
pub fn report(ui: &Ui, args: ReportArgs) -> Result<()> {
    let start = std::time::Instant::now();
    let config = if args.full { Config::full() } else { Config::quick() };
    // No adapter is an error, never a fall-back to the CPU.
    let (gpu, backend_name) = backend(args.backend)?;
    let on = gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu);
    let spinner = ui.spinner();
    let progress = |msg: &str| spinner.set_message(msg.to_string());
    let mut outcome =
        experiment::run_on(&config, on, &progress).context("running the experiment")?;
    let cone = super::cone::report_outcome(args.full, &progress)
        .context("running the cone-tracing section (builtin:cornell)")?;
    super::cone::add_to_report(&mut outcome.report, &cone)?;
    spinner.set_message(format!("writing {}", args.output.display()));
    let written = outcome
        .report
        .write(&args.output)
        .with_context(|| format!("writing the report into {}", args.output.display()))?;
    spinner.finish_and_clear();
    if args.json {
        return print_json(&outcome.scenes);
    }
    if gpu.is_some() {
        println!("backend: {backend_name} (see each row's backend)");
    }
    for scene in &outcome.scenes {
        println!("\n## {} ({} triangles)\n", scene.label, scene.triangles);
        println!("{}", scene.table()?.to_markdown());
    }
    println!(
        "\nreport written to {} in {:.1} s",
        written.markdown.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
