//! `hsp package`: builds the release cdylib and writes the FMU archive: `modelDescription.xml`
//! (verbatim from `modelDescription/`), `binaries/linux64/HydraulicSlewingPlate.so` and
//! `documentation/` (the page and its figures, made by [`docpage`] from this very FMU).

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use hydraulic_slewing_plate::model::variables::MODEL_IDENTIFIER;

use super::docpage;

pub const DEFAULT_FMU: &str = "fmu/HydraulicSlewingPlate.fmu";

/// The repository root (where Cargo.toml is).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"))
}

/// Builds the release library and returns the path of the shared object.
fn build_library() -> Result<PathBuf, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(&cargo)
        .args(["build", "--release", "--lib", "--quiet"])
        .current_dir(root())
        .status()
        .map_err(|e| format!("cannot run {cargo}: {e}"))?;
    if !status.success() {
        return Err(format!("cargo build --release --lib failed ({status})"));
    }
    let so = target_dir()
        .join("release")
        .join("libhydraulic_slewing_plate.so");
    if !so.exists() {
        return Err(format!("{} was not built", so.display()));
    }
    Ok(so)
}

/// Builds and writes the FMU; returns its path.
pub fn package(output: &str) -> Result<String, String> {
    let so = build_library()?;
    let xml_path = root().join("modelDescription/modelDescription.xml");
    let xml = std::fs::read(&xml_path).map_err(|e| format!("{}: {e}", xml_path.display()))?;
    let binary = std::fs::read(&so).map_err(|e| format!("{}: {e}", so.display()))?;
    let out = if Path::new(output).is_absolute() {
        PathBuf::from(output)
    } else {
        root().join(output)
    };
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let mut entries: Vec<(String, Vec<u8>)> = vec![
        ("modelDescription.xml".into(), xml),
        (format!("binaries/linux64/{MODEL_IDENTIFIER}.so"), binary),
    ];
    // Write to a temporary name and rename, so that a reader never sees half an archive. The
    // documentation's figures come from running this very FMU: a first archive without them is
    // run, then the complete one is written.
    let tmp = out.with_extension("fmu.partial");
    write_archive(&tmp, &entries)?;
    let xml_text = String::from_utf8_lossy(&entries[0].1).into_owned();
    let platforms = platforms(&entries);
    let docs = docpage::documentation(&tmp, &xml_text, &platforms)?;
    entries.extend(
        docs.into_iter()
            .map(|(name, bytes)| (format!("documentation/{name}"), bytes)),
    );
    write_archive(&tmp, &entries)?;
    std::fs::rename(&tmp, &out).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(out.display().to_string())
}

/// The platform folders under `binaries/` of an archive's entries.
fn platforms(entries: &[(String, Vec<u8>)]) -> Vec<String> {
    let mut list: Vec<String> = entries
        .iter()
        .filter_map(|(name, _)| name.strip_prefix("binaries/")?.split_once('/'))
        .map(|(platform, _)| platform.to_string())
        .collect();
    list.dedup();
    list
}

/// Writes a zip archive of `(name, bytes)` entries.
fn write_archive(path: &Path, entries: &[(String, Vec<u8>)]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    for (name, data) in entries {
        zip.start_file(name.as_str(), options)
            .and_then(|_| zip.write_all(data).map_err(Into::into))
            .map_err(|e| format!("writing {name} into {}: {e}", path.display()))?;
    }
    zip.finish()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(())
}
