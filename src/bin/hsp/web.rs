//! `hsp web`: the browser build. Compiles the library for `wasm32-unknown-unknown` (the model,
//! its integrators and `src/web/`, without the FMI layers) in Cargo.toml's `wasm` profile, and
//! puts the module beside the page's sources in `docs/web/`: `hsp.wasm`, and `hsp.wasm.js`, the
//! same bytes as base64 in a script, which the page loads when it is opened from the disk
//! (browsers refuse `fetch()` on `file://` URLs). `hsp package` does the same and puts the
//! whole page into both FMUs' `documentation/web/`.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::binaries::{built, cargo, has_rust_target, not_installed, run, target_dir, timed};
use super::package::root;

/// The Rust target of the browser build.
pub const TARGET: &str = "wasm32-unknown-unknown";

/// Where the page's sources are, in the repository.
pub const PAGE_DIR: &str = "docs/web";

/// The page's sources (in [`PAGE_DIR`]).
const SOURCES: [&str; 10] = [
    "index.html",
    "page.css",
    "hsp.js",
    "worker.js",
    "controls.js",
    "plots.js",
    "plate.js",
    "status.js",
    "export.js",
    "page.js",
];

/// What is missing when the browser build cannot be made, what that means (`consequence`), and
/// how to add it.
pub fn missing_target(consequence: &str) -> String {
    format!(
        "{}, so {consequence}; `bash tests/setup.sh` installs it",
        not_installed(&[TARGET])
    )
}

/// Whether this toolchain can make the browser build.
pub fn available() -> bool {
    has_rust_target(TARGET)
}

/// Builds the `.wasm` and returns its bytes.
pub fn build_wasm() -> Result<Vec<u8>, String> {
    if !available() {
        return Err(missing_target("the browser page cannot be built"));
    }
    let path = timed("browser build (wasm32)", || {
        let mut command = Command::new(cargo());
        command.args([
            "build",
            "--quiet",
            "--lib",
            "--no-default-features",
            "--profile",
            "wasm",
            "--target",
            TARGET,
        ]);
        run(command, "cargo build --target wasm32-unknown-unknown")?;
        built(
            target_dir()
                .join(TARGET)
                .join("wasm")
                .join("hydraulic_slewing_plate.wasm"),
        )
    })?;
    std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))
}

/// The files the page is made of besides its sources: the module and its script form.
fn module_files(wasm: &[u8]) -> [(String, Vec<u8>); 2] {
    let script = format!(
        "// hsp.wasm as base64, for pages opened from the disk (written by `hsp web`).\n\
         globalThis.HSP_WASM_BASE64 = \"{}\";\n",
        base64(wasm)
    );
    [
        ("hsp.wasm".into(), wasm.to_vec()),
        ("hsp.wasm.js".into(), script.into_bytes()),
    ]
}

/// The whole page, `(file name, bytes)`: its sources and the module built from this tree.
pub fn page_files() -> Result<Vec<(String, Vec<u8>)>, String> {
    let wasm = build_wasm()?;
    let dir = root().join(PAGE_DIR);
    let mut files = Vec::new();
    for name in SOURCES {
        let path = dir.join(name);
        files.push((
            name.to_string(),
            std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?,
        ));
    }
    files.extend(module_files(&wasm));
    Ok(files)
}

/// Writes the page's files into `out`; in the repository's own [`PAGE_DIR`] only the built
/// ones (the sources are already there). Returns the paths written.
pub fn write(files: &[(String, Vec<u8>)], out: &Path) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let in_place = out.canonicalize().ok() == root().join(PAGE_DIR).canonicalize().ok();
    let mut written = Vec::new();
    for (name, bytes) in files {
        if in_place && SOURCES.contains(&name.as_str()) {
            continue;
        }
        let path = out.join(name);
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}

/// Standard base64 (RFC 4648, with padding).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::base64;

    #[test]
    fn base64_matches_rfc_4648_test_vectors() {
        // RFC 4648, section 10.
        for (text, encoded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(text.as_bytes()), encoded, "{text:?}");
        }
    }
}
