//! The suite's machinery: executors, known issues, one test per (kernel body × executor), the
//! table.
//!
//! The test binary is a libtest-mimic harness: the standard command-line interface (a name
//! filter, `--exact`, `--skip`, `--list`, `--test-threads`), one trial per row, named
//! `<kernel body> :: <executor>` so that a filter on a kernel's name runs that kernel only and
//! a failure names the kernel and the adapter.
//!
//! # Threads
//! Trials run on libtest-mimic's threads (one per core by default). Every adapter's
//! [`Context`] is opened once, by the first trial that needs it, and shared; the trials of one
//! adapter run one at a time (a lock per adapter), the CPU-reference trials beside them.
//! Serial per adapter because a device's uncaptured-error and device-lost reports are per
//! device, not per trial: two trials on one device at once could each see the other's error,
//! and a wait for one trial's submission would also wait for the other's work (and count it in
//! its time). Nothing is lost on a CPU adapter such as Mesa's lavapipe, which already spreads
//! each dispatch over every core; the CPU-reference trial running beside it fills the gaps
//! where the driver is single-threaded (shader compilation, readback).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use libtest_mimic::{Arguments, Completion, Failed, Trial};
use voxlod_gpu::Context;

/// Where a kernel body runs.
pub enum Executor<'a> {
    /// The CPU reference (voxlod-cpu).
    Cpu,
    /// A wgpu adapter.
    Gpu(&'a Context),
}

impl Executor<'_> {
    pub fn name(&self) -> String {
        match self {
            Executor::Cpu => CPU_NAME.into(),
            Executor::Gpu(ctx) => ctx.label(),
        }
    }
}

const CPU_NAME: &str = "cpu reference";

/// A kernel body: runs one kernel's checks on an executor and measures the worst error.
pub type Body = fn(&Executor) -> Result<Measure, String>;

/// One kernel body of the suite.
pub struct Kernel {
    /// The row's name; every test of this body starts with it.
    pub name: &'static str,
    /// The checks.
    pub body: Body,
}

/// What a known issue expects.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expect {
    /// Do not run (the body would hang or crash the driver).
    #[allow(dead_code)]
    Skip,
    /// Runs and fails; the row shows the failure but the suite passes.
    Fail,
}

/// A known driver problem.
#[derive(Clone, Copy, Debug)]
pub struct KnownIssue {
    /// Kernel name prefix (`"raycast"` matches `"raycast (scenes)"`).
    pub kernel: &'static str,
    /// Case-insensitive substring of the adapter label.
    pub adapter: &'static str,
    /// What to expect.
    pub expect: Expect,
    /// Why.
    pub reason: &'static str,
}

/// The known issue that applies to `kernel` on the executor labelled `adapter`, if any.
pub fn known<'a>(issues: &'a [KnownIssue], kernel: &str, adapter: &str) -> Option<&'a KnownIssue> {
    let adapter = adapter.to_lowercase();
    issues
        .iter()
        .find(|i| kernel.starts_with(i.kernel) && adapter.contains(&i.adapter.to_lowercase()))
}

/// One comparison's result: the largest error seen and the bound it must stay within.
#[derive(Clone, Debug)]
pub struct Measure {
    pub max_error: f64,
    pub bound: f64,
    pub pass: bool,
    pub note: String,
}

impl Measure {
    /// One row from several comparisons (none empty): the worst error, the first one's
    /// bound, a pass only if every one passes, and their notes joined.
    pub fn combine(measures: &[Measure]) -> Measure {
        Measure {
            max_error: measures.iter().map(|m| m.max_error).fold(0.0, f64::max),
            bound: measures[0].bound,
            pass: measures.iter().all(|m| m.pass),
            note: measures.iter().map(|m| m.note.as_str()).collect::<Vec<_>>().join(" | "),
        }
    }
}

struct Row {
    kernel: String,
    backend: String,
    max_error: String,
    bound: String,
    result: String,
    seconds: f64,
    note: String,
}

impl Row {
    fn empty(kernel: &str, backend: &str, result: &str, note: String) -> Self {
        Row {
            kernel: kernel.into(),
            backend: backend.into(),
            max_error: "-".into(),
            bound: "-".into(),
            result: result.into(),
            seconds: 0.0,
            note,
        }
    }

    fn line(&self) -> String {
        format!(
            "{:<34} {:<40} {:>10} {:>10} {:<13} {:>7.2}s  {}",
            self.kernel,
            self.backend,
            self.max_error,
            self.bound,
            self.result,
            self.seconds,
            self.note
        )
    }
}

/// Rows by trial position, so that the table keeps the suite's order whatever the threads do.
type Rows = Arc<Mutex<BTreeMap<usize, Row>>>;

/// One adapter: found at start, opened by the first trial that needs it, used by one trial at
/// a time (module docs).
struct Adapter {
    index: usize,
    label: String,
    context: OnceLock<Result<Context, String>>,
    turn: Mutex<()>,
}

/// Runs `body` on `executor` (a panic is a failed row, not an aborted suite), applies the
/// known issues and records the row; the trial's outcome.
fn evaluate(
    kernel: &str,
    executor: &Executor,
    body: Body,
    issues: &[KnownIssue],
) -> (Row, Result<Completion, Failed>) {
    let name = executor.name();
    let known = known(issues, kernel, &name).copied();
    if let Some(issue) = known.filter(|i| i.expect == Expect::Skip) {
        let note = format!("known issue: {}", issue.reason);
        return (
            Row::empty(kernel, &name, "skipped", note.clone()),
            Ok(Completion::ignored_with(note)),
        );
    }
    let start = Instant::now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| body(executor)))
        .unwrap_or_else(|p| {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(format!("panicked: {msg}"))
        });
    let seconds = start.elapsed().as_secs_f64();
    let (mut row, pass) = match outcome {
        Ok(m) => (
            Row {
                kernel: kernel.into(),
                backend: name.clone(),
                max_error: format!("{:.3e}", m.max_error),
                bound: format!("{:.3e}", m.bound),
                result: if m.pass { "pass" } else { "FAIL" }.into(),
                seconds,
                note: m.note,
            },
            m.pass,
        ),
        Err(e) => {
            let mut row = Row::empty(kernel, &name, "FAIL", format!("error: {e}"));
            row.seconds = seconds;
            (row, false)
        }
    };
    let outcome = match (known, pass) {
        (Some(issue), false) => {
            row.result = "expected fail".into();
            row.note = format!("known issue: {}; {}", issue.reason, row.note);
            Ok(Completion::Completed)
        }
        (Some(issue), true) => {
            row.result = "FAIL".into();
            row.note = format!("passes, but is listed as a known failure ({})", issue.reason);
            Err(format!("{kernel} on {name}: stale known issue ({}): remove it", issue.reason)
                .into())
        }
        (None, false) => Err(format!(
            "{kernel} on {name}: max error {} (bound {}): {}",
            row.max_error, row.bound, row.note
        )
        .into()),
        (None, true) => Ok(Completion::Completed),
    };
    (row, outcome)
}

fn record(
    rows: &Rows,
    position: usize,
    row: Row,
    outcome: Result<Completion, Failed>,
) -> Result<Completion, Failed> {
    println!("{}", row.line());
    rows.lock().unwrap_or_else(|e| e.into_inner()).insert(position, row);
    outcome
}

/// The suite's entry point: one trial per (kernel × executor), plus `extra` trials (tests of
/// the harness itself); then the table, written to `target/equivalence.txt`.
///
/// No adapter at all makes every kernel's GPU trial fail (named `<kernel> :: no GPU adapter`),
/// so that a filtered run fails as loudly as a full one; with `VOXLOD_ALLOW_NO_GPU=1` those
/// trials are ignored (counted and listed as not checked) instead.
pub fn main(
    kernels: &'static [Kernel],
    issues: &'static [KnownIssue],
    extra: Vec<Trial>,
) -> ExitCode {
    let args = Arguments::from_args();
    let mut header = String::new();
    let found = voxlod_gpu::adapters();
    let mut say = |line: String| {
        if !args.list {
            println!("{line}");
        }
        header.push_str(&line);
        header.push('\n');
    };
    say(format!("adapters found: {}", found.len()));
    for a in &found {
        say(format!("  {a}"));
    }
    let allowed = std::env::var("VOXLOD_ALLOW_NO_GPU").is_ok_and(|v| v == "1");
    if found.is_empty() {
        say("!!!!!!!! NO GPU ADAPTER FOUND: the GPU kernels are NOT checked !!!!!!!!".into());
        say("install Mesa's lavapipe (apt-get install mesa-vulkan-drivers) or a GPU driver".into());
    } else {
        let infos: Vec<_> = found.iter().map(|a| a.info.clone()).collect();
        match voxlod_gpu::context::select(&infos, voxlod_gpu::context::env_selector().as_deref()) {
            Ok(i) => say(format!("default adapter (Context::new): [{i}]")),
            Err(e) => say(format!("default adapter: {e}")),
        }
    }

    // Adapter labels name the trials; two identical adapters get their index appended.
    let labels: Vec<String> =
        found.iter().map(|a| format!("{} ({:?})", a.info.name, a.info.backend)).collect();
    let adapters: Vec<Arc<Adapter>> = found
        .iter()
        .zip(&labels)
        .map(|(a, label)| {
            let twins = labels.iter().filter(|l| *l == label).count() > 1;
            Arc::new(Adapter {
                index: a.index,
                label: if twins { format!("{label} #{}", a.index) } else { label.clone() },
                context: OnceLock::new(),
                turn: Mutex::new(()),
            })
        })
        .collect();

    let rows: Rows = Arc::default();
    let mut trials = Vec::new();
    for kernel in kernels {
        let (name, body) = (kernel.name, kernel.body);
        let position = trials.len();
        let r = rows.clone();
        trials.push(Trial::ignorable_test(format!("{name} :: {CPU_NAME}"), move || {
            let (row, outcome) = evaluate(name, &Executor::Cpu, body, issues);
            record(&r, position, row, outcome)
        }));
        for adapter in &adapters {
            let position = trials.len();
            let (r, adapter) = (rows.clone(), adapter.clone());
            trials.push(Trial::ignorable_test(format!("{name} :: {}", adapter.label), move || {
                let _turn = adapter.turn.lock().unwrap_or_else(|e| e.into_inner());
                let opened = adapter.context.get_or_init(|| {
                    Context::with_selector(Some(&adapter.index.to_string()))
                        .map_err(|e| e.to_string())
                });
                let (row, outcome) = match opened {
                    Ok(ctx) => evaluate(name, &Executor::Gpu(ctx), body, issues),
                    Err(e) => {
                        let why = format!("cannot open adapter [{}]: {e}", adapter.index);
                        let fail = Err(format!("{name} on {}: {why}", adapter.label).into());
                        (Row::empty(name, &adapter.label, "FAIL", why), fail)
                    }
                };
                record(&r, position, row, outcome)
            }));
        }
        if adapters.is_empty() {
            let position = trials.len();
            let r = rows.clone();
            trials.push(Trial::ignorable_test(format!("{name} :: no GPU adapter"), move || {
                let (row, outcome) = if allowed {
                    let why = "no GPU adapter: NOT checked (VOXLOD_ALLOW_NO_GPU=1)";
                    (
                        Row::empty(name, "none", "not checked", why.into()),
                        Ok(Completion::ignored_with(why)),
                    )
                } else {
                    let why = "no GPU adapter found: install Mesa's lavapipe (apt-get install \
                               mesa-vulkan-drivers) or a GPU driver, or set VOXLOD_ALLOW_NO_GPU=1";
                    (
                        Row::empty(name, "none", "FAIL", why.into()),
                        Err(format!("{name}: {why}").into()),
                    )
                };
                record(&r, position, row, outcome)
            }));
        }
    }
    let kernel_trials = trials.len();
    trials.extend(extra);

    let conclusion = libtest_mimic::run(&args, trials);
    if args.list {
        return conclusion.exit_code();
    }

    let rows = rows.lock().unwrap_or_else(|e| e.into_inner());
    let mut t = header;
    let _ = writeln!(
        t,
        "{:<34} {:<40} {:>10} {:>10} {:<13} {:>8}  note",
        "kernel", "backend", "max error", "bound", "result", "time"
    );
    for r in rows.values() {
        let _ = writeln!(t, "{}", r.line());
    }
    if rows.len() < kernel_trials {
        let _ = writeln!(
            t,
            "equivalence: PARTIAL run: {} of {kernel_trials} kernel tests run (name filter)",
            rows.len()
        );
    }
    let failures: Vec<&Row> = rows.values().filter(|r| r.result == "FAIL").collect();
    if failures.is_empty() {
        t.push_str("equivalence: all kernels run are within their bounds\n");
    } else {
        let _ = writeln!(t, "equivalence: {} FAILURE(S)", failures.len());
        for r in failures {
            let _ = writeln!(t, "  - {} on {}: {}", r.kernel, r.backend, r.note);
        }
    }
    println!("\n{t}");
    let path = target_dir().join("equivalence.txt");
    if let Err(e) = voxlod_format::io::write_atomic(&path, |w| w.write_all(t.as_bytes())) {
        eprintln!("could not write {}: {e}", path.display());
    }
    conclusion.exit_code()
}

/// The workspace's target directory (`CARGO_TARGET_DIR` or `<workspace>/target`).
pub fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target"))
}
