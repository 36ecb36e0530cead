//! What machine a report ran on, for the report's header: the CPU model, its logical cores, the
//! operating system and the worker threads used. Read from `/proc/cpuinfo` and
//! `/etc/os-release` where they exist (Linux); "unknown" elsewhere.

/// One line describing this machine, e.g. `Intel(R) Xeon(R) … (2 logical cores), Debian GNU/Linux
/// 12 (bookworm), 2 worker threads`.
pub fn describe() -> String {
    let cpu = read_key("/proc/cpuinfo", "model name", ':').unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let os = read_key("/etc/os-release", "PRETTY_NAME", '=')
        .map(|s| s.trim_matches('"').to_string())
        .unwrap_or_else(|| std::env::consts::OS.into());
    format!("{cpu} ({cores} logical cores), {os}, {} worker threads", rayon::current_num_threads())
}

/// The value of the first line `key<sep>value` of a text file, trimmed.
fn read_key(path: &str, key: &str, sep: char) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    text.lines().find_map(|line| {
        let (k, v) = line.split_once(sep)?;
        (k.trim() == key).then(|| v.trim().to_string())
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn describes_cores_and_threads() {
        let d = super::describe();
        let threads = rayon::current_num_threads();
        assert!(d.ends_with(&format!("{threads} worker threads")), "{d}");
        assert!(d.contains("logical cores"), "{d}");
    }
}
