//! The packaged FMUs, checked to be built from the sources these tests were built from: each
//! binary carries the marker `hsp-source-hash:<hash>` of its sources (`tools/source_hash.rs`),
//! and a test that loads a packaged FMU first looks for this build's marker in the FMU's Linux
//! binary. A missing or stale FMU is rebuilt with `hsp package` (as `tests/run_all.sh` does before
//! `cargo test`); one still stale after that fails the test, naming both hashes.

#![allow(dead_code)]

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

use hydraulic_slewing_plate::model::variables::MODEL_IDENTIFIER;
use hydraulic_slewing_plate::SOURCE_HASH;

/// The FMI version of a packaged FMU: its path in `fmu/` and its Linux binary's path inside.
#[derive(Clone, Copy, Debug)]
pub enum Version {
    Fmi2,
    Fmi3,
}

impl Version {
    fn archive(self) -> PathBuf {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fmu");
        let dir = match self {
            Version::Fmi2 => root,
            Version::Fmi3 => root.join("fmi3"),
        };
        dir.join(format!("{MODEL_IDENTIFIER}.fmu"))
    }

    fn binary(self) -> String {
        let platform = match self {
            Version::Fmi2 => "linux64",
            Version::Fmi3 => "x86_64-linux",
        };
        format!("binaries/{platform}/{MODEL_IDENTIFIER}.so")
    }
}

/// The source hash the packaged FMU's Linux binary carries, `None` if there is no FMU, no binary
/// or no marker.
pub fn packaged_hash(version: Version) -> Option<String> {
    let file = std::fs::File::open(version.archive()).ok()?;
    let mut zip = zip::ZipArchive::new(file).ok()?;
    let mut binary = Vec::new();
    zip.by_name(&version.binary())
        .ok()?
        .read_to_end(&mut binary)
        .ok()?;
    let prefix = b"hsp-source-hash:";
    let at = binary.windows(prefix.len()).position(|w| w == prefix)?;
    let hash = binary.get(at + prefix.len()..at + prefix.len() + 16)?;
    Some(String::from_utf8_lossy(hash).into_owned())
}

/// One check-and-package at a time: the tests of a binary run on threads, and two `hsp package`
/// runs writing the same archives at once leave a corrupt one ("corrupt deflate stream" in the
/// next test that opens it).
static PACKAGING: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The packaged FMU of `version`, built from this build's sources: rebuilt with `hsp package`
/// when missing or stale.
pub fn fresh_fmu(version: Version) -> PathBuf {
    // A test that failed while holding the lock leaves it poisoned; the archives are checked
    // again below all the same.
    let _one = PACKAGING.lock().unwrap_or_else(|e| e.into_inner());
    let this = SOURCE_HASH;
    if packaged_hash(version).as_deref() != Some(this) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let status = Command::new(env!("CARGO"))
            .args([
                "run",
                "--release",
                "--quiet",
                "--bin",
                "hsp",
                "--",
                "package",
            ])
            .current_dir(root)
            .status()
            .expect("cannot run cargo to build the FMUs");
        assert!(status.success(), "hsp package failed: {status}");
    }
    let packaged = packaged_hash(version);
    assert_eq!(
        packaged.as_deref(),
        Some(this),
        "{} is not built from these sources even after hsp package",
        version.archive().display()
    );
    version.archive()
}

/// The CSV `hsp run --no-build --no-plot` writes for the packaged FMU `fmu` with the arguments
/// `args`, read back (its file deleted). The run must succeed; its error output is the message
/// when it does not.
pub fn run_csv(fmu: &Path, args: &[&str]) -> Vec<u8> {
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let csv = std::env::temp_dir().join(format!("hsp-run-{}-{n}.csv", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_hsp"))
        .args(["run", "--no-build", "--no-plot", "--fmu"])
        .arg(fmu)
        .args(args)
        .arg("--csv")
        .arg(&csv)
        .output()
        .expect("cannot run hsp");
    assert!(
        out.status.success(),
        "hsp run {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got = std::fs::read(&csv).unwrap();
    let _ = std::fs::remove_file(&csv);
    got
}

/// The columns of a CSV that `hsp run` wrote: each header name with its values.
pub fn csv_columns(csv: &[u8]) -> Vec<(String, Vec<f64>)> {
    let text = std::str::from_utf8(csv).expect("the CSV is UTF-8");
    let mut lines = text.lines();
    let mut columns: Vec<(String, Vec<f64>)> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(|name| (name.to_string(), Vec::new()))
        .collect();
    for line in lines {
        for ((_, values), v) in columns.iter_mut().zip(line.split(',')) {
            values.push(v.parse().expect("a number"));
        }
    }
    columns
}
