//! `cargo xtask`: project automation for voxlod.
//!
//! - `cargo xtask test [--require-gpu] [--quick]`: formatting, clippy with warnings denied, the
//!   documentation build (missing docs and broken links denied), and every test of the
//!   workspace, doc examples included; a summary table at the end.

use std::process::{Command, ExitCode};
use std::time::Instant;

use anyhow::{Context, Result, bail};

const USAGE: &str = "usage: cargo xtask test [--require-gpu] [--quick]

  test           fmt --check, clippy -D warnings, doc build, all tests (doc examples included)
  --require-gpu  fail when no GPU adapter is found (CI passes this)
  --quick        skip fmt, clippy and the doc build";

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
    let mut require_gpu = false;
    let mut quick = false;
    for a in args {
        match a.as_str() {
            "--require-gpu" => require_gpu = true,
            "--quick" => quick = true,
            other => bail!("unknown option '{other}'\n{USAGE}"),
        }
    }
    let mut steps = Vec::new();
    let mut ok = true;
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
    if require_gpu {
        tests.env("VOXLOD_REQUIRE_GPU", "1");
    }
    ok &= step(&mut steps, "tests (unit, integration, doc examples)", tests)?;

    println!("\n{:<42} {:>9}  result", "step", "seconds");
    for s in &steps {
        println!("{:<42} {:>9.1}  {}", s.name, s.seconds, if s.ok { "ok" } else { "FAILED" });
    }
    println!("\n{}", if ok { "all steps passed" } else { "SOME STEPS FAILED" });
    Ok(ok)
}
