//! `hsp package`: builds the release cdylib and writes the FMU archive: `modelDescription.xml`
//! (verbatim from `modelDescription/`), `binaries/linux64/HydraulicSlewingPlate.so` (glibc 2.17),
//! `binaries/win64/HydraulicSlewingPlate.dll` (where the binaries come from: [`binaries`]) and
//! `documentation/` (the page and its figures, made by [`docpage`] from this very FMU).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::{binaries, docpage};
use hydraulic_slewing_plate::model::variables::MODEL_IDENTIFIER;

pub const DEFAULT_FMU: &str = "fmu/HydraulicSlewingPlate.fmu";

/// The repository root (where Cargo.toml is).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Builds and writes the FMU with every binary the installed toolchains allow; returns its path.
pub fn package(output: &str) -> Result<String, String> {
    package_with(output, false)
}

/// Builds and writes the FMU; with `require_portable`, fails unless both the glibc-2.17 Linux
/// binary and the Windows binary are built (see [`binaries`]). Returns its path.
pub fn package_with(output: &str, require_portable: bool) -> Result<String, String> {
    let binaries = binaries::build(require_portable)?;
    let xml_path = root().join("modelDescription/modelDescription.xml");
    let xml = std::fs::read(&xml_path).map_err(|e| format!("{}: {e}", xml_path.display()))?;
    let mut files = Vec::new();
    for b in &binaries {
        let data = std::fs::read(&b.path).map_err(|e| format!("{}: {e}", b.path.display()))?;
        let name = format!("binaries/{}/{MODEL_IDENTIFIER}.{}", b.platform, b.extension);
        files.push((name, data));
    }
    let out = if Path::new(output).is_absolute() {
        PathBuf::from(output)
    } else {
        root().join(output)
    };
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let xml_text = String::from_utf8_lossy(&xml).into_owned();
    let mut entries: Vec<(String, Vec<u8>)> = vec![("modelDescription.xml".into(), xml)];
    entries.extend(files);
    // Write to a temporary name and rename, so that a reader never sees half an archive. The
    // documentation's figures come from running this very FMU: a first archive without them is
    // run, then the complete one is written.
    let tmp = out.with_extension("fmu.partial");
    write_archive(&tmp, &entries)?;
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
