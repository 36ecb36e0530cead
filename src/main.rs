//! The `voxlod` command-line tool. With no arguments it runs the default experiment on the
//! embedded scenes and writes `out/report.md`.

mod cli;
mod commands;

use std::process::ExitCode;

use clap::Parser;

#[global_allocator]
static ALLOC: voxlod::studies::alloc::TrackingAllocator = voxlod::studies::alloc::TrackingAllocator;

fn main() -> ExitCode {
    let cli = cli::Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One clear line, then the cause chain.
            eprintln!("error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}

fn run(cli: cli::Cli) -> anyhow::Result<()> {
    if let Some(n) = cli.threads {
        anyhow::ensure!(n > 0, "--threads must be at least 1");
        rayon::ThreadPoolBuilder::new().num_threads(n).build_global()?;
    }
    let ui = commands::Ui { quiet: cli.quiet };
    match cli.command.unwrap_or(cli::Command::Report(Default::default())) {
        cli::Command::Report(a) => commands::report(&ui, a),
        cli::Command::Voxelize(a) => commands::voxelize(&ui, a),
        cli::Command::Export(a) => commands::export(&ui, a),
        cli::Command::Render(a) => commands::render(&ui, a),
        cli::Command::CompareImages(a) => commands::compare_images(a),
        cli::Command::Compare(a) => commands::compare(&ui, a),
        cli::Command::Ablation(a) => commands::ablation(&ui, a),
        cli::Command::Cone(a) => commands::cone(&ui, a),
        cli::Command::Dynamic(a) => commands::dynamic(&ui, a),
        cli::Command::HeitzNeyret(a) => commands::heitz_neyret(&ui, a),
        cli::Command::Info(a) => commands::info(a),
        cli::Command::Import(a) => commands::import(&ui, a),
        cli::Command::Volume(a) => commands::volume(&ui, a),
        cli::Command::Slicemap(a) => commands::slicemap(&ui, a),
        cli::Command::Scenes => commands::scenes(),
    }
}
