//! The `voxlod` subcommands. Each prints a human summary (or JSON with `--json`), writes its
//! outputs atomically, and returns errors with context for `main` to print.

mod compare;
mod cone;
mod dynamic;
mod export;
mod heitz_neyret;
mod info;
mod render;
mod report;
mod slicemap;
mod volume;
mod voxelize;

use std::path::Path;
use std::time::Duration;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

pub use compare::compare;
pub use cone::cone;
pub use dynamic::dynamic;
pub use export::export;
pub use heitz_neyret::heitz_neyret;
pub use info::info;
pub use render::render;
pub use report::report;
pub use slicemap::slicemap;
pub use volume::volume;
pub use voxelize::voxelize;

use voxlod::studies::backend::Backend;

use crate::cli::{BackendArg, CompareArgs};

/// The GPU context for `--backend gpu` (an error if there is no adapter: never a fall-back).
fn backend(choice: BackendArg) -> Result<Option<voxlod::gpu::Context>> {
    match choice {
        BackendArg::Cpu => Ok(None),
        BackendArg::Gpu => {
            Ok(Some(voxlod::gpu::Context::new().context("opening the GPU backend")?))
        }
    }
}

/// How to run this invocation again from the repository: `cargo run --release` and this
/// process's arguments (named at the top of the reports).
fn invocation() -> String {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() {
        "cargo run --release".into()
    } else {
        format!("cargo run --release -- {}", args.join(" "))
    }
}

/// The studies' backend for an opened context (or none).
fn on(gpu: &Option<voxlod::gpu::Context>) -> Backend<'_> {
    gpu.as_ref().map_or(Backend::Cpu, Backend::Gpu)
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
    voxlod::studies::scenes::load(spec).with_context(|| format!("loading scene '{spec}'"))
}

/// The version of every `--json` output's layout (docs/json.md): raised whenever a field is
/// renamed, removed or changes meaning.
pub const JSON_SCHEMA_VERSION: u32 = 1;

/// Prints `result` as pretty JSON on stdout, in the envelope every `--json` output shares:
/// `{"schema_version": …, "command": …, "result": …}` (docs/json.md).
pub fn print_json(command: &str, result: &impl serde::Serialize) -> Result<()> {
    #[derive(serde::Serialize)]
    struct Envelope<'a, T> {
        schema_version: u32,
        command: &'a str,
        result: &'a T,
    }
    let out = Envelope { schema_version: JSON_SCHEMA_VERSION, command, result };
    println!("{}", serde_json::to_string_pretty(&out)?);
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
        return print_json("compare-images", &m);
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
    for (name, description) in voxlod::studies::scenes::builtin_names() {
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
