//! `cargo xtask`: project automation for voxlod.
//!
//! - `cargo xtask test [--no-install] [--allow-no-gpu] [--quick]`: lists the GPU adapters
//!   found and the one used, then formatting, clippy with warnings denied, the documentation
//!   build (missing docs and broken links denied), and every test of the workspace, doc
//!   examples included — among them the CPU↔GPU equivalence suite (voxlod-gpu's
//!   `tests/equivalence`), whose table (kernel, backend, max error, bound, result) is printed at
//!   the end with the step summary.
//!
//! No GPU adapter is a set-up step, not a skip: on a system with apt (Debian, Ubuntu) the
//! command installs Mesa's lavapipe (`mesa-vulkan-drivers`, Vulkan on the CPU), printing each
//! apt command before it runs it, with `sudo -n` when not root, then looks for adapters again.
//! When it cannot install (no apt, not root and sudo wants a password, apt fails) it stops
//! within seconds and prints the command to run by hand. `--no-install` declines the install
//! and stops the same way. `--allow-no-gpu` accepts a machine without an adapter: nothing is
//! installed, and everything but the GPU kernels is checked. `--require-gpu` is accepted as a
//! synonym of the default. CI runs plain `cargo xtask test`.
//!
//! The CPU-GPU equivalence suite is one test per kernel body and adapter
//! (`<kernel> :: <adapter>`): `cargo test -p voxlod-gpu --test equivalence octree` runs the
//! octree rows alone, and its table then says the run was partial.

mod gpu;

use std::process::{Command, ExitCode};
use std::time::Instant;

use anyhow::{Context, Result, bail};

use gpu::Adapters;

const USAGE: &str = "usage: cargo xtask test [--no-install] [--allow-no-gpu] [--quick]

  test            GPU adapters, fmt --check, clippy -D warnings, doc build, all tests (doc
                  examples and the CPU-GPU equivalence suite included), equivalence table.
                  With no GPU adapter and apt present it installs Mesa's lavapipe first:
                  apt-get install -y mesa-vulkan-drivers (apt-get update first when apt does
                  not know the package; through `sudo -n` when not root), printed before it
                  runs. When it cannot, it stops at once and prints the command to run.
  --no-install    do not install lavapipe: with no adapter, stop and print the command
  --allow-no-gpu  with no adapter, install nothing and run everything else (the GPU kernels
                  go unchecked)
  --require-gpu   fail when no GPU adapter is found: the default, accepted for compatibility
  --quick         skip fmt, clippy and the doc build";

struct Step {
    name: String,
    seconds: f64,
    ok: bool,
}

fn main() -> ExitCode {
    match run() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("xtask: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<bool> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("test") => test(&args[1..]),
        Some("-h" | "--help") | None => {
            println!("{USAGE}");
            Ok(true)
        }
        Some(other) => bail!("unknown command '{other}'\n{USAGE}"),
    }
}

fn cargo() -> Command {
    let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    cmd.current_dir(workspace_root());
    // Mesa's device-selection Vulkan layer looks for the display's GPU by connecting to
    // Wayland, which prints "error: XDG_RUNTIME_DIR is invalid" on every adapter enumeration
    // of a machine without a session. With no display there is nothing to select (and voxlod
    // chooses its adapter itself): turn the layer off there.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && std::env::var_os("NODEVICE_SELECT").is_none()
    {
        cmd.env("NODEVICE_SELECT", "1");
    }
    cmd
}

fn workspace_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .into()
}

fn step(steps: &mut Vec<Step>, name: &str, mut cmd: Command) -> Result<bool> {
    println!("\n==> {name}\n    {cmd:?}");
    let start = Instant::now();
    let status = cmd.status().with_context(|| format!("starting {name}"))?;
    let seconds = start.elapsed().as_secs_f64();
    steps.push(Step { name: name.into(), seconds, ok: status.success() });
    if !status.success() {
        eprintln!("==> {name} FAILED ({status})");
    }
    Ok(status.success())
}

fn test(args: &[String]) -> Result<bool> {
    let mut allow_no_gpu = false;
    let mut no_install = false;
    let mut quick = false;
    for a in args {
        match a.as_str() {
            "--require-gpu" => allow_no_gpu = false,
            "--allow-no-gpu" => allow_no_gpu = true,
            "--no-install" => no_install = true,
            "--quick" => quick = true,
            other => bail!("unknown option '{other}'\n{USAGE}"),
        }
    }
    let mut steps = Vec::new();
    let mut ok = true;

    // The adapters first, so that a run without a GPU says so (or gets one) before anything
    // else.
    println!("\n==> GPU adapters");
    let start = Instant::now();
    let mut adapters = gpu::check_adapters(cargo())?;
    let mut installed = false;
    if matches!(adapters, Adapters::None) && !allow_no_gpu {
        match gpu::install(&gpu::LAVAPIPE, no_install)? {
            Ok(()) => {
                println!("==> lavapipe installed; GPU adapters again");
                adapters = gpu::check_adapters(cargo())?;
                installed = true;
            }
            Err(why) => {
                eprintln!("\n==> !!!!!!!! NO GPU ADAPTER !!!!!!!!\n==> {why}");
                eprintln!("==> or pass --allow-no-gpu to run everything but the GPU kernels");
                return Ok(false);
            }
        }
    }
    let found = matches!(adapters, Adapters::Found);
    steps.push(Step {
        name: "GPU adapters".into(),
        seconds: start.elapsed().as_secs_f64(),
        ok: found || allow_no_gpu,
    });
    if !found {
        let why = match adapters {
            Adapters::None if installed => {
                "NO GPU ADAPTER EVEN WITH LAVAPIPE INSTALLED (is the Vulkan loader, libvulkan1, \
                 there? does `VK_ICD_FILENAMES` or `VK_DRIVER_FILES` hide it?)"
            }
            Adapters::None => "NO GPU ADAPTER",
            Adapters::Broken => "THE ADAPTERS EXAMPLE FAILED",
            Adapters::Found => unreachable!("found"),
        };
        eprintln!("\n==> !!!!!!!! {why}: the GPU kernels will NOT be checked !!!!!!!!");
        if allow_no_gpu {
            eprintln!("==> continuing because of --allow-no-gpu");
        } else {
            eprintln!("==> failing (pass --allow-no-gpu to run everything else anyway)");
            return Ok(false);
        }
    }

    // NanoVDB's validator checks the .nvdb files the export tests write; under CI (`CI` set)
    // those tests fail without it.
    if !gpu::have("nanovdb_validate") {
        println!("\n==> NanoVDB tools");
        let start = Instant::now();
        let installed = match gpu::install(&gpu::NANOVDB_TOOLS, no_install)? {
            Ok(()) => gpu::have("nanovdb_validate"),
            Err(why) => {
                eprintln!("==> {why}");
                eprintln!(
                    "==> the .nvdb export tests will say they skipped nanovdb_validate (and \
                     fail when CI is set)"
                );
                false
            }
        };
        let ok_here = installed || std::env::var_os("CI").is_none();
        steps.push(Step {
            name: "NanoVDB tools".into(),
            seconds: start.elapsed().as_secs_f64(),
            ok: ok_here,
        });
        ok &= ok_here;
    }

    if !quick {
        let mut fmt = cargo();
        fmt.args(["fmt", "--all", "--check"]);
        ok &= step(&mut steps, "rustfmt", fmt)?;

        let mut clippy = cargo();
        clippy.args(["clippy", "--workspace", "--all-targets", "--", "-D", "warnings"]);
        ok &= step(&mut steps, "clippy", clippy)?;

        let mut doc = cargo();
        doc.args(["doc", "--workspace", "--no-deps"]).env("RUSTDOCFLAGS", "-D warnings");
        ok &= step(&mut steps, "doc build", doc)?;
    }
    let mut tests = cargo();
    tests.args(["test", "--workspace"]);
    // Property tests: enough cases to find bugs, few enough for 2 CI cores. Set PROPTEST_CASES
    // to search harder.
    if std::env::var_os("PROPTEST_CASES").is_none() {
        tests.env("PROPTEST_CASES", "64");
    }
    if allow_no_gpu {
        tests.env("VOXLOD_ALLOW_NO_GPU", "1");
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("target"));
    let table = target.join("equivalence.txt");
    let _ = std::fs::remove_file(&table);
    ok &= step(&mut steps, "tests (unit, integration, doc examples, CPU-GPU equivalence)", tests)?;

    println!("\n==> CPU-GPU equivalence ({})", table.display());
    match std::fs::read_to_string(&table) {
        Ok(text) => print!("{text}"),
        Err(_) => {
            println!("    no table: the equivalence suite did not run to its end");
            ok = false;
        }
    }

    println!("\n{:<62} {:>9}  result", "step", "seconds");
    for s in &steps {
        println!("{:<62} {:>9.1}  {}", s.name, s.seconds, if s.ok { "ok" } else { "FAILED" });
    }
    println!("\n{}", if ok { "all steps passed" } else { "SOME STEPS FAILED" });
    Ok(ok)
}
