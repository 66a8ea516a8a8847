//! What a benchmark's timing block says of the machine and the day (CONTRIBUTING.md, "Made by
//! `COMMAND` on YYYY-MM-DD, load L."). Included by the bench binaries with `#[path]`.

/// The 1-minute load average (`/proc/loadavg`), or "unknown".
pub fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into())
}

/// Today's date (UTC) as `date -u +%F` prints it, or "unknown".
pub fn today() -> String {
    std::process::Command::new("date")
        .args(["-u", "+%F"])
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|d| d.trim().to_string())
        .filter(|d| !d.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// The command that runs this binary with the arguments it was given, as `cargo run` would
/// (an argument with a space quoted): the "Made by" of a timing block.
pub fn command(bin: &str) -> String {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .map(|a| {
            if a.contains(' ') {
                format!("\"{a}\"")
            } else {
                a
            }
        })
        .collect();
    let mut command = format!("cargo run --release --bin {bin}");
    if !args.is_empty() {
        command.push_str(" -- ");
        command.push_str(&args.join(" "));
    }
    command
}
