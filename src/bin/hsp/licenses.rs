//! The licences both FMUs carry in `documentation/licenses/` (`hsp package`), the folder FMI 3.0
//! reserves for them (FMI 3.0, section 2.5, "documentation/licenses": `license.txt` is the entry
//! point); the FMI 2.0 FMU carries the same folder.
//!
//! - `license.txt`: this project's licence (MIT OR Apache-2.0), then what else is in the FMU and
//!   under which licence: every crate compiled into the binaries, Rust's standard library, and,
//!   when the FMU has the Windows binary, the runtime libraries the mingw-w64 linker adds to it.
//! - `LICENSE-MIT`, `LICENSE-APACHE`: this project's licence texts (from the repository's root).
//! - `third-party/NAME-VERSION/`: each crate's own licence files, as its package on crates.io ships
//!   them (the MIT licence asks for its notice in every copy, binaries included).
//!
//! The crates are those `cargo tree` lists for the library as `hsp package` builds it: normal
//! dependencies only (no build or dev dependencies), without the `cli` feature's tool-only crates,
//! without procedural macros (they run in the compiler and leave no code in the binary), on the
//! targets of the binaries built (the WebAssembly component's `wit-bindgen`, for one, only when
//! the FMU has the component). Their licence files are read from cargo's registry sources (`$CARGO_HOME/registry/src`),
//! where the build found them.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use super::binaries::cargo;
use super::ecosystem::Entry;
use super::package::root;

/// Where the licences go in both FMUs.
pub const DIR: &str = "documentation/licenses";

/// The project's licence texts, at the repository's root.
const OWN: [&str; 2] = ["LICENSE-MIT", "LICENSE-APACHE"];

/// One crate compiled into the binaries.
#[derive(Debug, PartialEq)]
pub struct Crate {
    pub name: String,
    pub version: String,
    /// Its licence as its manifest states it (an SPDX expression, or the older `A/B` form).
    pub license: String,
}

/// The crates of the FMU's library built for `targets` (Rust target triples), from `cargo tree`
/// (see the module's documentation); the project's own package is left out.
pub fn crates(targets: &[&str]) -> Result<Vec<Crate>, String> {
    let output = Command::new(cargo())
        .args(["tree", "--no-default-features"])
        .args(targets.iter().flat_map(|t| ["--target", t]))
        .args(["-e", "normal,no-proc-macro", "--prefix", "none"])
        .args(["--format", "{p}|{l}"])
        .current_dir(root())
        .output()
        .map_err(|e| format!("cannot run cargo tree: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "cargo tree failed ({}): {}",
            output.status,
            String::from_utf8_lossy(&output.stderr).trim()
        ));
    }
    let own = env!("CARGO_PKG_NAME");
    let mut list = parse_tree(&String::from_utf8_lossy(&output.stdout))?;
    list.retain(|c| c.name != own);
    Ok(list)
}

/// The crates of `cargo tree --prefix none --format "{p}|{l}"`'s lines (`name vX.Y.Z[ (…)]|licence[
/// (*)]`), each once, sorted by name and version.
fn parse_tree(text: &str) -> Result<Vec<Crate>, String> {
    let mut list = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let (package, license) = line
            .split_once('|')
            .ok_or_else(|| format!("cargo tree: unexpected line {line:?}"))?;
        let mut words = package.split_whitespace();
        let (Some(name), Some(version)) = (words.next(), words.next()) else {
            return Err(format!("cargo tree: unexpected line {line:?}"));
        };
        let version = version
            .strip_prefix('v')
            .ok_or_else(|| format!("cargo tree: no version in {line:?}"))?;
        let license = license.trim().trim_end_matches("(*)").trim();
        list.push(Crate {
            name: name.to_string(),
            version: version.to_string(),
            license: if license.is_empty() {
                "not stated".to_string()
            } else {
                license.to_string()
            },
        });
    }
    list.sort_by(|a, b| (&a.name, &a.version).cmp(&(&b.name, &b.version)));
    list.dedup();
    Ok(list)
}

/// Whether a file of a crate's package is one of its licence files.
fn is_license_file(name: &str) -> bool {
    let upper = name.to_ascii_uppercase();
    ["LICENSE", "LICENCE", "COPYING", "UNLICENSE", "NOTICE"]
        .iter()
        .any(|p| upper.starts_with(p))
}

/// The folder of `krate`'s sources in cargo's registry.
fn source_dir(krate: &Crate) -> Result<PathBuf, String> {
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")))
        .ok_or("neither CARGO_HOME nor HOME is set")?;
    let registry = home.join("registry/src");
    let folder = format!("{}-{}", krate.name, krate.version);
    std::fs::read_dir(&registry)
        .map_err(|e| format!("{}: {e}", registry.display()))?
        .filter_map(Result::ok)
        .map(|index| index.path().join(&folder))
        .find(|dir| dir.join("Cargo.toml").is_file())
        .ok_or_else(|| {
            format!(
                "the sources of {folder} are not under {} (its licence files are read there)",
                registry.display()
            )
        })
}

/// `krate`'s licence files, `(file name, bytes)`, sorted by name; an error if it has none.
fn license_files(krate: &Crate) -> Result<Vec<(String, Vec<u8>)>, String> {
    let dir = source_dir(krate)?;
    let mut files = Vec::new();
    for entry in std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))? {
        let path = entry.map_err(|e| format!("{}: {e}", dir.display()))?.path();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if path.is_file() && is_license_file(&name) {
            let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
            files.push((name, bytes));
        }
    }
    if files.is_empty() {
        return Err(format!(
            "{} {} ({}) ships no licence file in {}",
            krate.name,
            krate.version,
            krate.license,
            dir.display()
        ));
    }
    files.sort();
    Ok(files)
}

/// The runtime libraries mingw-w64 links into the Windows binary, and their licences.
const WINDOWS_RUNTIME: &str = "The Windows binary (binaries/win64, binaries/x86_64-windows) is \
linked by mingw-w64's GCC, which adds static parts of its runtime: GCC's support library libgcc \
and unwinder libgcc_eh (GPL-3.0 with the GCC Runtime Library Exception, which sets no condition \
on the binary made with them) and the mingw-w64 runtime's libmingw32 and libmingwex (public \
domain and ZPL-2.1 notices; Debian's copyright file of mingw-w64 lists them).";

/// Where the WebAssembly component's interface comes from.
const WIT_INTERFACES: &str = "The WebAssembly component of the FMI 3.0 FMU \
(binaries/wasm32-wasip2) implements the interfaces of the draft FMI layered standard for \
WebAssembly, fmi-ls-wasm (https://github.com/modelica/fmi-ls-wasm, 2-Clause BSD License, copyright \
the Modelica Association Project FMI), whose declarations it carries as its component type.";

/// Everything of [`DIR`], `(name inside the FMU, bytes)`, for the binaries built for `targets`
/// (Rust target triples).
pub fn entries(targets: &[&str]) -> Result<Vec<Entry>, String> {
    let windows = targets.iter().any(|t| t.contains("windows"));
    let crates = crates(targets)?;
    let mut text = String::new();
    let own = env!("CARGO_PKG_NAME");
    writeln!(
        text,
        "{own} {}: licences\n\n\
         This FMU, its model, binaries, documentation, figures and icon are licensed under \
         either of the Apache License, Version 2.0 (LICENSE-APACHE) or the MIT license \
         (LICENSE-MIT), at your option (SPDX: {}).\n",
        env!("CARGO_PKG_VERSION"),
        env!("CARGO_PKG_LICENSE")
    )
    .unwrap();
    writeln!(
        text,
        "The binaries are compiled from the project's library and these Rust crates, each under \
         its own licence; each one's licence files are in third-party/NAME-VERSION/:\n"
    )
    .unwrap();
    for c in &crates {
        writeln!(text, "  {:<14} {:<10} {}", c.name, c.version, c.license).unwrap();
    }
    writeln!(
        text,
        "\nand with Rust's standard library (core, alloc, std; MIT OR Apache-2.0, copyright the \
         Rust project's contributors: https://github.com/rust-lang/rust, whose licence texts \
         are the same as LICENSE-MIT and LICENSE-APACHE here).\n\n\
         The figures of documentation/ are drawn by the project's tools; their text is set in \
         the DejaVu fonts (Bitstream Vera licence, which sets no condition on pictures made with \
         them); no font file is in the FMU."
    )
    .unwrap();
    if windows {
        writeln!(text, "\n{WINDOWS_RUNTIME}").unwrap();
    }
    if targets.contains(&super::binaries::WASI_TARGET) {
        writeln!(text, "\n{WIT_INTERFACES}").unwrap();
    }
    let mut entries: Vec<Entry> = vec![(format!("{DIR}/license.txt"), text.into_bytes())];
    for name in OWN {
        let path = root().join(name);
        let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        entries.push((format!("{DIR}/{name}"), bytes));
    }
    for c in &crates {
        for (file, bytes) in license_files(c)? {
            entries.push((
                format!("{DIR}/third-party/{}-{}/{file}", c.name, c.version),
                bytes,
            ));
        }
    }
    Ok(entries)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cargo_tree_lines_become_crates_once_each() {
        let text = "hydraulic-slewing-plate v0.1.0 (/x)|MIT OR Apache-2.0\n\
                    nalgebra v0.35.0|Apache-2.0\n\
                    approx v0.5.1|Apache-2.0\n\
                    approx v0.5.1|Apache-2.0 (*)\n\
                    odd v1.0.0|\n";
        let list = parse_tree(text).unwrap();
        let names: Vec<_> = list
            .iter()
            .map(|c| (c.name.as_str(), c.version.as_str()))
            .collect();
        assert_eq!(
            names,
            [
                ("approx", "0.5.1"),
                ("hydraulic-slewing-plate", "0.1.0"),
                ("nalgebra", "0.35.0"),
                ("odd", "1.0.0")
            ]
        );
        assert_eq!(list[0].license, "Apache-2.0");
        assert_eq!(list[3].license, "not stated");
        assert!(parse_tree("no bar here").is_err());
        assert!(parse_tree("name 1.0|MIT").is_err());
    }

    #[test]
    fn licence_files_are_recognised_by_name() {
        for name in [
            "LICENSE",
            "LICENSE-MIT",
            "LICENSE-APACHE.md",
            "COPYING",
            "UNLICENSE",
        ] {
            assert!(is_license_file(name), "{name}");
        }
        for name in ["Cargo.toml", "README.md", "src"] {
            assert!(!is_license_file(name), "{name}");
        }
    }
}
