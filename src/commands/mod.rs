//! The `voxlod` subcommands. Each prints a human summary (or JSON with `--json`), writes its
//! outputs atomically, and returns errors with context for `main` to print.

mod compare;
mod cone;
mod cone_primary;
mod info;
mod render;
mod report;
mod volume;
mod voxelize;

use std::path::Path;
use std::time::Duration;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

pub use compare::compare;
pub use cone::cone;
pub use info::info;
pub use render::render;
pub use report::report;
pub use volume::volume;
pub use voxelize::voxelize;

use crate::cli::{BackendArg, CompareArgs};

/// The GPU context for `--backend gpu` (an error if there is no adapter: never a fall-back),
/// and the line naming the backend that every command prints.
fn backend(choice: BackendArg) -> Result<(Option<voxlod::gpu::Context>, String)> {
    match choice {
        BackendArg::Cpu => Ok((None, "cpu (rayon)".into())),
        BackendArg::Gpu => {
            let ctx = voxlod::gpu::Context::new().context("opening the GPU backend")?;
            // The summary says when the adapter is a CPU implementation (CPU timings).
            let name = format!("gpu: {}", ctx.summary());
            Ok((Some(ctx), name))
        }
    }
}

/// How to talk to the user.
pub struct Ui {
    /// No progress bars.
    pub quiet: bool,
}

impl Ui {
    /// A spinner showing stage messages on stderr (hidden when quiet or not a terminal).
    pub fn spinner(&self) -> ProgressBar {
        if self.quiet {
            return ProgressBar::hidden();
        }
        let bar = ProgressBar::new_spinner();
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {msg}")
                .expect("static template"),
        );
        bar.enable_steady_tick(Duration::from_millis(120));
        bar
    }
}

/// Loads a scene spec, naming it in the error.
pub fn load_scene(spec: &str) -> Result<voxlod::scene::Scene> {
    voxlod::scenes::load(spec).with_context(|| format!("loading scene '{spec}'"))
}

/// Prints `value` as pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> Result<()> {
    println!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}

/// `voxlod compare-images a b`.
pub fn compare_images(args: CompareArgs) -> Result<()> {
    let load = |p: &Path| {
        voxlod::scene::Srgb8Image::load(p).with_context(|| format!("reading image {}", p.display()))
    };
    let (a, b) = (load(&args.a)?, load(&args.b)?);
    let m = voxlod::eval::compare(&b, &a)
        .with_context(|| format!("comparing {} with {}", args.b.display(), args.a.display()))?;
    if args.json {
        return print_json(&m);
    }
    println!("reference  {}", args.a.display());
    println!("test       {}", args.b.display());
    println!("MSE        {:.6}  (8-bit sRGB scaled to [0,1])", m.mse);
    println!("PSNR       {:.3} dB", m.psnr);
    println!("SSIM       {:.6}  (Gaussian σ=1.5, 11×11, K1=0.01, K2=0.03)", m.ssim);
    Ok(())
}

/// `voxlod scenes`.
pub fn scenes() -> Result<()> {
    println!("Builtin scenes (use as builtin:NAME or builtin:NAME?KEY=VALUE&KEY=VALUE):\n");
    for (name, description) in voxlod::scenes::builtin_names() {
        println!("  {name:<14} {description}");
        if let Ok(params) = voxlod::scene::procedural::builtin_params(name) {
            for p in params {
                let default = p.default.map_or(String::new(), |d| format!(" (default {d})"));
                println!("      {:<12} {}{default}", p.name, p.description);
            }
        }
    }
    Ok(())
}
