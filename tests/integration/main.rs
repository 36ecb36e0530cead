//! End-to-end and cross-crate tests of voxlod, in one test binary (one link on 2-core CI).

use std::process::{Command, Output};

mod cli;
mod cone;
mod dynamic;
mod export;
mod far_from_origin;
mod heitz_neyret;
mod import;
mod scene_files;
mod slicemap;
mod volume;

/// The `result` of a `--json` output, after checking the envelope every command shares
/// (`schema_version`, `command`; docs/json.md).
pub fn json_result(stdout: &[u8], command: &str) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(stdout).expect("valid JSON on stdout");
    assert_eq!(v["schema_version"], 1, "{v}");
    assert_eq!(v["command"], command, "{v}");
    v["result"].take()
}

/// Runs the voxlod binary with `args` and `--quiet`.
pub fn voxlod(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_voxlod"))
        .args(args)
        .arg("--quiet")
        .output()
        .expect("the voxlod binary runs")
}
