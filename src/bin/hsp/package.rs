//! `hsp package`: builds the release cdylib and writes the FMU archive: `modelDescription.xml`
//! (verbatim from `modelDescription/`), `binaries/linux64/HydraulicSlewingPlate.so` (glibc 2.17),
//! `binaries/win64/HydraulicSlewingPlate.dll`, `binaries/darwin64/HydraulicSlewingPlate.dylib` (one
//! universal binary for x86-64 and arm64 Macs; where the binaries come from: [`binaries`]) and
//! `documentation/` (the page and its figures, made by [`docpage`] from this very FMU, and the
//! interactive page with the browser build in `documentation/web/`, see [`web`], when the
//! toolchain has the WebAssembly target), and the
//! ecosystem's formats ([`ecosystem`]): `extra/org.fmi-standard.fmi-ls-ref/` (the default
//! experiment's result, the presets as SSP parameter sets) and the icon `model.png`, and the
//! licences of the FMU and of everything compiled into it in `documentation/licenses/`
//! ([`licenses`]).
//!
//! Beside it, in `fmi3/` of the same folder, the FMI 3.0 FMU: the same binaries (they export the
//! `fmi3*` functions too) under FMI 3.0's platform names (`x86_64-linux`, `x86_64-windows`), with
//! the aarch64 Linux binary (`aarch64-linux`, a folder FMI 2.0 has no name for) and the macOS one
//! per processor (`x86_64-darwin`, `aarch64-darwin`) in place of the universal one, the
//! WebAssembly component (`wasm32-wasip2`, with `extra/org.modelica.fmi-ls-wasm/manifest.xml`), the
//! FMI 3.0 `modelDescription.xml` written by `modelDescription/fmi3.py`, the same documentation
//! and `extra/`, and `terminalsAndIcons/` (the icon and the terminals) in place of `model.png`.
//!
//! Beside them, `HydraulicSlewingPlate.ssp`: the example SSP system with the FMI 2.0 FMU (see
//! [`ecosystem::ssp`]).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::binaries::{self, Portability};
use super::{docpage, ecosystem, licenses, web};
use hydraulic_slewing_plate::model::variables::MODEL_IDENTIFIER;

pub const DEFAULT_FMU: &str = "fmu/HydraulicSlewingPlate.fmu";

/// The repository root (where Cargo.toml is).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Builds and writes the FMUs with every binary the installed toolchains allow; returns the FMI 2.0
/// one's path.
pub fn package(output: &str) -> Result<String, String> {
    package_with(output, Portability::IfInstalled).map(|[fmi2, _, _, _]| fmi2)
}

/// Where the FMI 3.0 FMU goes: `fmi3/` beside the FMI 2.0 one.
pub fn fmi3_path(fmi2: &Path) -> PathBuf {
    let name = fmi2.file_name().unwrap_or_default();
    fmi2.with_file_name("fmi3").join(name)
}

/// Where the example SSP system goes: beside the FMI 2.0 FMU, with the extension `.ssp`; its
/// form for libcosim and ecos with `-osp` added to the name ([`ecosystem::ssp::Form`]).
pub fn ssp_path(fmi2: &Path, form: ecosystem::ssp::Form) -> PathBuf {
    match form {
        ecosystem::ssp::Form::Exposed => fmi2.with_extension("ssp"),
        ecosystem::ssp::Form::Osp => {
            let stem = fmi2.file_stem().unwrap_or_default().to_string_lossy();
            fmi2.with_file_name(format!("{stem}-osp.ssp"))
        }
    }
}

/// Builds and writes the FMI 2.0 FMU at `output`, the FMI 3.0 FMU beside it (see
/// [`fmi3_path`]) and the example SSP system (see [`ssp_path`]), with the binaries `portability`
/// asks for (see [`binaries`]).
/// Returns the three paths.
///
/// The browser page is optional like the cross binaries: without the WebAssembly target (and
/// without `--require-portable`) it is skipped with one warning, the FMUs carry no
/// `documentation/web/` and `docs/web/` keeps what it has. Nothing half-written is left behind:
/// the archives are written under temporary names, renamed when all three are complete, and
/// removed when anything fails.
pub fn package_with(output: &str, portability: Portability) -> Result<[String; 4], String> {
    let out = if Path::new(output).is_absolute() {
        PathBuf::from(output)
    } else {
        root().join(output)
    };
    let partial = [
        out.with_extension("fmu.partial"),
        fmi3_path(&out).with_extension("fmu.partial"),
        ssp_path(&out, ecosystem::ssp::Form::Exposed).with_extension("ssp.partial"),
        ssp_path(&out, ecosystem::ssp::Form::Osp).with_extension("ssp.partial"),
    ];
    let result = write_all(&out, &partial, portability);
    if result.is_err() {
        for path in &partial {
            let _ = std::fs::remove_file(path);
        }
    }
    result
}

/// [`package_with`]'s work: `partial` holds the temporary names of the FMI 2.0 FMU, the FMI 3.0
/// FMU and the SSP files (SSP's form, libcosim's and ecos's).
fn write_all(
    out: &Path,
    partial: &[PathBuf; 4],
    portability: Portability,
) -> Result<[String; 4], String> {
    let with_web = portability == Portability::Required || web::available();
    if !with_web {
        let consequence = format!(
            "the FMUs carry no browser page (documentation/web/) and {} is not rebuilt",
            web::PAGE_DIR
        );
        eprintln!("warning: {}", web::missing_target(&consequence));
    }
    let binaries = binaries::build(portability)?;
    let xml_path = root().join("modelDescription/modelDescription.xml");
    let xml = std::fs::read(&xml_path).map_err(|e| format!("{}: {e}", xml_path.display()))?;
    // Each binary under its folder in each FMU that has one for it (see `binaries`).
    let (mut files2, mut files3) = (Vec::new(), Vec::new());
    for b in &binaries {
        let data = std::fs::read(&b.path).map_err(|e| format!("{}: {e}", b.path.display()))?;
        let name = |platform| format!("binaries/{platform}/{MODEL_IDENTIFIER}.{}", b.extension);
        if let Some(platform) = b.fmi2 {
            files2.push((name(platform), data.clone()));
        }
        if let Some(platform) = b.fmi3 {
            files3.push((name(platform), data));
        }
    }
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let xml_text = String::from_utf8_lossy(&xml).into_owned();
    let mut entries: Vec<(String, Vec<u8>)> = vec![("modelDescription.xml".into(), xml)];
    entries.extend(files2);
    // Write to a temporary name and rename, so that a reader never sees half an archive. The
    // documentation's figures come from running this very FMU: a first archive without them is
    // run, then the complete one is written.
    let [tmp, tmp3, tmp_ssp, tmp_osp] = partial;
    write_archive(tmp, &entries)?;
    let docs = docpage::documentation(
        tmp,
        &xml_text,
        &platforms(&entries),
        &platforms(&files3),
        with_web,
    )?;
    // What both FMUs carry besides the model description and the binaries.
    let mut shared: Vec<(String, Vec<u8>)> = docs
        .into_iter()
        .map(|(name, bytes)| (format!("documentation/{name}"), bytes))
        .collect();
    shared.extend(ecosystem::extra(&xml_text)?);
    // The reference result: this very FMU run in its default experiment.
    let recorded = ecosystem::result::run_default_experiment(tmp, &xml_text)?;
    let targets: Vec<&str> = binaries.iter().map(|b| b.target).collect();
    shared.extend(licenses::entries(&targets)?);
    // The interactive page with the browser build, in the FMUs and beside its sources.
    if with_web {
        let page = web::page_files()?;
        web::write(&page, &root().join(web::PAGE_DIR))?;
        shared.extend(
            page.into_iter()
                .map(|(name, bytes)| (format!("documentation/web/{name}"), bytes)),
        );
    }
    entries.extend(shared.iter().cloned());

    // FMI 3.0: its own model description, the binaries under its platform names, the same
    // documentation and extra/, and terminalsAndIcons/.
    let xml3_path = root().join("modelDescription/fmi3/modelDescription.xml");
    let xml3 = std::fs::read(&xml3_path).map_err(|e| format!("{}: {e}", xml3_path.display()))?;
    let terminals_and_icons = ecosystem::fmi3_only(&String::from_utf8_lossy(&xml3), &recorded)?;
    // The WebAssembly component comes with the manifest of its layered standard.
    let wasm = binaries
        .iter()
        .any(|b| b.fmi3 == Some(binaries::WASI_TARGET));
    let ls_wasm = if wasm {
        ecosystem::ls_wasm::entries()
    } else {
        Vec::new()
    };
    let entries3: Vec<(String, Vec<u8>)> = std::iter::once(("modelDescription.xml".into(), xml3))
        .chain(files3)
        .chain(shared)
        .chain(terminals_and_icons)
        .chain(ls_wasm)
        .collect();
    entries.extend(ecosystem::fmi2_only(&recorded)?);
    write_archive(tmp, &entries)?;
    let out3 = fmi3_path(out);
    if let Some(dir) = out3.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    write_archive(tmp3, &entries3)?;
    let fmu2 = std::fs::read(tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let ssp = ssp_path(out, ecosystem::ssp::Form::Exposed);
    let osp = ssp_path(out, ecosystem::ssp::Form::Osp);
    write_archive(
        tmp_ssp,
        &ecosystem::ssp::archive(fmu2.clone(), ecosystem::ssp::Form::Exposed)?,
    )?;
    write_archive(
        tmp_osp,
        &ecosystem::ssp::archive(fmu2, ecosystem::ssp::Form::Osp)?,
    )?;
    std::fs::rename(tmp, out).map_err(|e| format!("{}: {e}", out.display()))?;
    std::fs::rename(tmp3, &out3).map_err(|e| format!("{}: {e}", out3.display()))?;
    std::fs::rename(tmp_ssp, &ssp).map_err(|e| format!("{}: {e}", ssp.display()))?;
    std::fs::rename(tmp_osp, &osp).map_err(|e| format!("{}: {e}", osp.display()))?;
    Ok([
        out.display().to_string(),
        out3.display().to_string(),
        ssp.display().to_string(),
        osp.display().to_string(),
    ])
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
