//! The hash of the sources a build of the FMU library comes from: FNV-1a over the library's
//! source files (`src/` without the command-line tools in `src/bin/`: its Rust files and the WIT
//! interfaces the WebAssembly component is generated from; `tools/*.rs`, `build.rs`,
//! `Cargo.toml`, `Cargo.lock` and `modelDescription/modelDescription.xml`), each as its path
//! relative to the checkout and its bytes, in path order.
//!
//! `build.rs` includes this file and writes the hash into the library
//! (`hydraulic_slewing_plate::SOURCE_HASH`, and the marker `hsp-source-hash:<hash>` that the
//! binary carries in its instantiation log line), so that a test holding a packaged FMU can tell
//! whether its binary was built from the sources the test itself was built from. Uses the
//! crate's FNV-1a (`src/fnv1a.rs`, included beside it as `fnv1a`).

use std::path::{Path, PathBuf};

/// The files whose bytes make the library, relative to `root`, in path order.
pub fn library_sources(root: &Path) -> Vec<PathBuf> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            let relative = path.strip_prefix(root).unwrap_or(&path).to_path_buf();
            if path.is_dir() {
                if relative != Path::new("src/bin") {
                    walk(root, &path, out);
                }
            } else if path.extension().is_some_and(|e| e == "rs" || e == "wit") {
                out.push(relative);
            }
        }
    }
    let mut out = Vec::new();
    walk(root, &root.join("src"), &mut out);
    walk(root, &root.join("tools"), &mut out);
    for file in [
        "build.rs",
        "Cargo.toml",
        "Cargo.lock",
        "modelDescription/modelDescription.xml",
    ] {
        out.push(PathBuf::from(file));
    }
    out.sort();
    out
}

/// The hash of the library's sources under `root`, as 16 hexadecimal digits. A file that cannot
/// be read counts as empty.
pub fn source_hash(root: &Path) -> String {
    let mut h = super::fnv1a::OFFSET_BASIS;
    for file in library_sources(root) {
        let name = file.to_string_lossy().replace('\\', "/");
        h = super::fnv1a::fnv1a64_from(h, name.as_bytes());
        h = super::fnv1a::fnv1a64_from(h, &[0]);
        h = super::fnv1a::fnv1a64_from(h, &std::fs::read(root.join(&file)).unwrap_or_default());
        h = super::fnv1a::fnv1a64_from(h, &[0]);
    }
    format!("{h:016x}")
}
