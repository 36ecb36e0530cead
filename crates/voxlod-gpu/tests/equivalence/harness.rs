//! The suite's machinery: backends, known issues, rows, the table.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use voxlod_gpu::Context;

/// Where a kernel body runs.
pub enum Backend<'a> {
    /// The CPU reference (voxlod-cpu).
    Cpu,
    /// A wgpu adapter.
    Gpu(&'a Context),
}

impl Backend<'_> {
    pub fn name(&self) -> String {
        match self {
            Backend::Cpu => "cpu reference".into(),
            Backend::Gpu(ctx) => ctx.label(),
        }
    }
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

pub struct Suite<'a> {
    issues: &'a [KnownIssue],
    rows: Vec<Row>,
    failures: Vec<String>,
    header: String,
}

impl<'a> Suite<'a> {
    pub fn new(issues: &'a [KnownIssue]) -> Self {
        Self { issues, rows: Vec::new(), failures: Vec::new(), header: String::new() }
    }

    pub fn known(&self, kernel: &str, adapter: &str) -> Option<&KnownIssue> {
        let adapter = adapter.to_lowercase();
        self.issues
            .iter()
            .find(|i| kernel.starts_with(i.kernel) && adapter.contains(&i.adapter.to_lowercase()))
    }

    pub fn say(&mut self, line: &str) {
        println!("{line}");
        self.header.push_str(line);
        self.header.push('\n');
    }

    pub fn fail(&mut self, kernel: &str, backend: &str, why: &str) {
        self.failures.push(format!("{kernel} on {backend}: {why}"));
        self.rows.push(Row {
            kernel: kernel.into(),
            backend: backend.into(),
            max_error: "-".into(),
            bound: "-".into(),
            result: "FAIL".into(),
            seconds: 0.0,
            note: why.into(),
        });
    }

    /// Runs `body` on `backend` and records its row.
    pub fn run(
        &mut self,
        kernel: &str,
        backend: &Backend,
        body: impl FnOnce(&Backend) -> Result<Measure, String>,
    ) {
        let name = backend.name();
        // `VOXLOD_EQUIVALENCE_ONLY=filtered,random`: run only the kernels whose names start
        // with one of the prefixes (for iterating on one kernel); the others are listed as
        // not run, and `finish` says the run was partial.
        let only = std::env::var("VOXLOD_EQUIVALENCE_ONLY").ok();
        if let Some(only) = only.filter(|o| !o.split(',').any(|p| kernel.starts_with(p.trim()))) {
            self.rows.push(Row {
                kernel: kernel.into(),
                backend: name,
                max_error: "-".into(),
                bound: "-".into(),
                result: "not run".into(),
                seconds: 0.0,
                note: format!("VOXLOD_EQUIVALENCE_ONLY={only}"),
            });
            return;
        }
        let known = self.known(kernel, &name).copied();
        if let Some(issue) = known.filter(|i| i.expect == Expect::Skip) {
            self.rows.push(Row {
                kernel: kernel.into(),
                backend: name,
                max_error: "-".into(),
                bound: "-".into(),
                result: "skipped".into(),
                seconds: 0.0,
                note: format!("known issue: {}", issue.reason),
            });
            return;
        }
        let start = Instant::now();
        // A panic (an overflow check in a reference, a driver crash surfacing as a panic) is
        // a failed row, not an aborted suite.
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| body(backend)))
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
            Err(e) => (
                Row {
                    kernel: kernel.into(),
                    backend: name.clone(),
                    max_error: "-".into(),
                    bound: "-".into(),
                    result: "FAIL".into(),
                    seconds,
                    note: format!("error: {e}"),
                },
                false,
            ),
        };
        match (known, pass) {
            (Some(issue), false) => {
                row.result = "expected fail".into();
                row.note = format!("known issue: {}; {}", issue.reason, row.note);
            }
            (Some(issue), true) => {
                row.result = "FAIL".into();
                row.note = format!("passes, but is listed as a known failure ({})", issue.reason);
                self.failures.push(format!("{kernel} on {name}: stale known issue"));
            }
            (None, false) => self.failures.push(format!("{kernel} on {name}: {}", row.note)),
            (None, true) => {}
        }
        println!(
            "{:<22} {:<40} {:>10} {:>10} {:<13} {:>6.2}s {}",
            row.kernel, row.backend, row.max_error, row.bound, row.result, row.seconds, row.note
        );
        self.rows.push(row);
    }

    /// Prints the table, writes it to `target/equivalence.txt`, and fails on any failure.
    pub fn finish(self) {
        let mut t = String::new();
        t.push_str(&self.header);
        let _ = writeln!(
            t,
            "{:<22} {:<40} {:>10} {:>10} {:<13} {:>7}  note",
            "kernel", "backend", "max error", "bound", "result", "time"
        );
        for r in &self.rows {
            let _ = writeln!(
                t,
                "{:<22} {:<40} {:>10} {:>10} {:<13} {:>6.2}s  {}",
                r.kernel, r.backend, r.max_error, r.bound, r.result, r.seconds, r.note
            );
        }
        if self.rows.iter().any(|r| r.result == "not run") {
            t.push_str(
                "equivalence: PARTIAL run (VOXLOD_EQUIVALENCE_ONLY): some kernels not run\n",
            );
        }
        if self.failures.is_empty() {
            t.push_str("equivalence: all kernels within their bounds\n");
        } else {
            let _ = writeln!(t, "equivalence: {} FAILURE(S)", self.failures.len());
            for f in &self.failures {
                let _ = writeln!(t, "  - {f}");
            }
        }
        println!("\n{t}");
        let path = target_dir().join("equivalence.txt");
        if let Err(e) =
            std::fs::create_dir_all(target_dir()).and_then(|_| std::fs::write(&path, &t))
        {
            eprintln!("could not write {}: {e}", path.display());
        }
        assert!(self.failures.is_empty(), "equivalence failures:\n{}", self.failures.join("\n"));
    }
}

/// The workspace's target directory (`CARGO_TARGET_DIR` or `<workspace>/target`).
pub fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target"))
}

/// Opens every adapter, says which were found and which one `Context::new` would pick, and
/// fails loudly when there is none (unless `VOXLOD_ALLOW_NO_GPU=1`).
pub fn contexts(suite: &mut Suite) -> Vec<Context> {
    let found = voxlod_gpu::adapters();
    suite.say(&format!("adapters found: {}", found.len()));
    for a in &found {
        suite.say(&format!("  {a}"));
    }
    let mut out = Vec::new();
    for (i, ctx) in Context::all().into_iter().enumerate() {
        match ctx {
            Ok(ctx) => out.push(ctx),
            Err(e) => suite.fail("open adapter", &format!("adapter {i}"), &e.to_string()),
        }
    }
    if found.is_empty() {
        let allowed = std::env::var("VOXLOD_ALLOW_NO_GPU").is_ok_and(|v| v == "1");
        let banner = "!!!!!!!! NO GPU ADAPTER FOUND: the GPU kernels were NOT checked !!!!!!!!";
        suite.say(banner);
        suite.say("install Mesa's lavapipe (apt-get install mesa-vulkan-drivers) or a GPU driver");
        if !allowed {
            suite.fail("adapters", "none", "no adapter (set VOXLOD_ALLOW_NO_GPU=1 to allow)");
        }
    } else {
        match voxlod_gpu::context::select(
            &found.iter().map(|a| a.info.clone()).collect::<Vec<_>>(),
            voxlod_gpu::context::env_selector().as_deref(),
        ) {
            Ok(i) => suite.say(&format!("default adapter (Context::new): [{i}]")),
            Err(e) => suite.say(&format!("default adapter: {e}")),
        }
    }
    out
}
