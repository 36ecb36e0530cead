//! Finding a GPU adapter, and installing the system packages the tests need when the system has
//! apt: Mesa's lavapipe (a Vulkan driver that runs on the CPU) when there is no adapter, and
//! NanoVDB's command-line tools, which check the `.nvdb` files voxlod writes.
//!
//! An install is one apt transaction, printed before it runs: `apt-get update` only when the
//! package lists do not know the package, then a non-interactive `apt-get install -y PACKAGE`;
//! prefixed with `sudo -n` when not root. Every reason it cannot run (no apt, not root and no
//! password-less sudo) is found before apt starts, so the run fails within seconds and names
//! the command to run by hand.

use std::ffi::OsStr;
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{Context, Result};

/// A Debian/Ubuntu package the tests need, and why.
#[derive(Clone, Copy, Debug)]
pub struct Package {
    /// The package name.
    pub name: &'static str,
    /// What it is, for messages ("Mesa's lavapipe").
    pub what: &'static str,
    /// Why it is installed, the start of a message ("no GPU adapter").
    pub why: &'static str,
    /// How to install it elsewhere (several lines when apt is absent).
    pub no_apt: &'static str,
}

/// The package that holds lavapipe.
pub const LAVAPIPE: Package = Package {
    name: "mesa-vulkan-drivers",
    what: "Mesa's lavapipe",
    why: "no GPU adapter",
    no_apt: NO_APT_BY_HAND,
};

/// The package that holds `nanovdb_validate` (OpenVDB 10's NanoVDB tools).
pub const NANOVDB_TOOLS: Package = Package {
    name: "libnanovdb-tools",
    what: "NanoVDB's tools (nanovdb_validate)",
    why: "no nanovdb_validate on PATH",
    no_apt: "install OpenVDB 10's NanoVDB tools (nanovdb_validate) from your distribution",
};

/// Whether `name` is an executable on PATH.
pub fn have(name: &str) -> bool {
    on_path(name).is_some()
}

/// What the adapters example reported.
pub enum Adapters {
    /// At least one adapter, and `Context::new` opened the one it picked.
    Found,
    /// The example ran and found no adapter.
    None,
    /// The example did not build, or found adapters but could not open the selected one.
    Broken,
}

/// Runs voxlod-gpu's `adapters` example (its output goes to the terminal) and classifies it.
pub fn check_adapters(mut cargo: Command) -> Result<Adapters> {
    cargo
        .args(["run", "--quiet", "--package", "voxlod-gpu", "--example", "adapters"])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit());
    println!("    {cargo:?}");
    let out = cargo.output().context("starting the adapters example")?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    print!("{stdout}");
    let count = stdout
        .lines()
        .find_map(|l| l.strip_prefix("GPU adapters found: "))
        .and_then(|n| n.trim().parse::<usize>().ok());
    Ok(match count {
        Some(_) if out.status.success() => Adapters::Found,
        Some(0) => Adapters::None,
        _ => Adapters::Broken,
    })
}

/// A command line, shown exactly as it runs (the environment assignment in shell syntax).
pub struct CommandLine {
    env: Option<(&'static str, &'static str)>,
    argv: Vec<String>,
}

impl CommandLine {
    fn new(argv: &[&str]) -> Self {
        Self { env: None, argv: argv.iter().map(|s| s.to_string()).collect() }
    }

    fn run(&self) -> Result<bool> {
        println!("    $ {self}");
        let mut cmd = Command::new(&self.argv[0]);
        cmd.args(&self.argv[1..]).stdin(Stdio::null());
        if let Some((k, v)) = self.env {
            cmd.env(k, v);
        }
        let status = cmd.status().with_context(|| format!("starting `{self}`"))?;
        if !status.success() {
            eprintln!("    `{self}` failed ({status})");
        }
        Ok(status.success())
    }
}

impl fmt::Display for CommandLine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some((k, v)) = self.env {
            write!(f, "{k}={v} ")?;
        }
        write!(f, "{}", self.argv.join(" "))
    }
}

/// Why a package was not installed; `Display` says what to do by hand.
pub struct NotInstalled {
    /// The reason, one sentence.
    pub reason: String,
    /// What the package is.
    pub what: &'static str,
    /// The command a user runs to install it (several lines when the OS is unknown).
    pub by_hand: String,
}

impl fmt::Display for NotInstalled {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}\n==> to install {} by hand, run:\n      {}",
            self.reason, self.what, self.by_hand
        )
    }
}

/// The install command a user types in a shell (sudo may ask for a password there).
fn by_hand(package: &Package, sudo: bool, update: bool) -> String {
    let s = if sudo { "sudo " } else { "" };
    let install = format!("{s}apt-get install -y {}", package.name);
    if update { format!("{s}apt-get update && {install}") } else { install }
}

const NO_APT_BY_HAND: &str = "Debian/Ubuntu: sudo apt-get install -y mesa-vulkan-drivers
      Fedora:        sudo dnf install -y mesa-vulkan-drivers
      Arch:          sudo pacman -S vulkan-swrast
      (or any Vulkan, Metal or DX12 driver for your GPU)";

/// Installs `package` with apt, or says (within seconds, before apt runs) why it cannot.
/// `decline` (`--no-install`) only reports the command.
pub fn install(package: &Package, decline: bool) -> Result<std::result::Result<(), NotInstalled>> {
    let (why, what) = (package.why, package.what);
    if on_path("apt-get").is_none() {
        return Ok(Err(NotInstalled {
            reason: format!("{why}, and no apt-get on PATH to install {what}"),
            what,
            by_hand: package.no_apt.into(),
        }));
    }
    let root = is_root();
    let update = !apt_knows(package.name);
    let hand = by_hand(package, !root, update);
    if decline {
        return Ok(Err(NotInstalled {
            reason: format!("{why}, and --no-install declines installing {what}"),
            what,
            by_hand: hand,
        }));
    }
    let mut prefix: Vec<String> = Vec::new();
    if !root {
        let Some(sudo) = on_path("sudo") else {
            return Ok(Err(NotInstalled {
                reason: format!(
                    "{why}; installing {what} needs root, and there is no sudo on PATH"
                ),
                what,
                by_hand: by_hand(package, false, update) + "   (as root)",
            }));
        };
        let ok = Command::new(&sudo)
            .args(["-n", "true"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            return Ok(Err(NotInstalled {
                reason: format!(
                    "{why}; installing {what} needs root, and sudo wants a password \
                     (`sudo -n true` failed)"
                ),
                what,
                by_hand: hand,
            }));
        }
        prefix = vec!["sudo".into(), "-n".into()];
    }
    let apt = String::from("apt-get");
    let mut commands = Vec::new();
    if update {
        let mut argv = prefix.clone();
        argv.extend([apt.clone(), "update".into()]);
        commands.push(CommandLine { env: None, argv });
    }
    let mut install = CommandLine::new(&[]);
    if root {
        install.env = Some(("DEBIAN_FRONTEND", "noninteractive"));
    } else {
        // sudo resets the environment: pass the variable through env(1).
        install.argv.extend(prefix.iter().cloned());
        install.argv.extend(["env".into(), "DEBIAN_FRONTEND=noninteractive".into()]);
    }
    install.argv.extend([apt, "install".into(), "-y".into(), package.name.into()]);
    commands.push(install);

    println!("==> {why}: installing {what} with apt");
    for c in &commands {
        if !c.run()? {
            return Ok(Err(NotInstalled {
                reason: format!("installing {what} failed: `{c}` did not succeed"),
                what,
                by_hand: hand,
            }));
        }
    }
    Ok(Ok(()))
}

/// Whether apt's package lists have a candidate version of `package`.
fn apt_knows(package: &str) -> bool {
    let Ok(out) = Command::new("apt-cache").args(["policy", package]).stdin(Stdio::null()).output()
    else {
        return false;
    };
    String::from_utf8_lossy(&out.stdout).lines().any(|l| {
        l.trim()
            .strip_prefix("Candidate:")
            .is_some_and(|v| !v.trim().is_empty() && v.trim() != "(none)")
    })
}

/// Whether this process runs as root (`id -u` is 0).
fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// The first executable file called `name` in the directories of PATH.
fn on_path(name: impl AsRef<OsStr>) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name.as_ref())).find(|p| is_executable(p))
}

#[cfg(unix)]
fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    p.metadata().is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

#[cfg(not(unix))]
fn is_executable(p: &Path) -> bool {
    p.is_file()
}
