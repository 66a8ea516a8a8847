//! The layering of the crate, checked on its sources: the version-neutral FMU core (`src/fmu/`)
//! names no FMI version in its code (no `fmi2`/`fmi3` path, no `Fmi2*`/`Fmi3*` type, no function
//! name of either version in a string), the FMI 2.0 and FMI 3.0 layers do not import each other,
//! and the physics (`bond_graph`, `fragments`, `model`, `solver`) imports neither FMI layer.
//! Comments are left out: the core's documentation may cite the standard's function names.

use std::path::{Path, PathBuf};

/// The `.rs` files under `dir`, recursively.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(sources(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out.sort();
    out
}

/// `line` up to its comment: the first `//` outside a string literal (a URI, say).
fn without_comment(line: &str) -> &str {
    line.match_indices("//")
        .find(|(at, _)| line[..*at].matches('"').count().is_multiple_of(2))
        .map_or(line, |(at, _)| &line[..at])
}

/// The code of a file without its comments (line comments and doc comments; the crate uses no
/// block comments), with line numbers.
fn code_lines(path: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .enumerate()
        .filter_map(|(i, line)| {
            let code = without_comment(line);
            (!code.trim().is_empty()).then(|| (i + 1, code.to_string()))
        })
        .collect()
}

/// Every line of code under `dir` that contains one of `needles`, as "file:line: code".
fn offending(dir: &str, needles: &[&str]) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut out = Vec::new();
    for path in sources(&root) {
        for (n, code) in code_lines(&path) {
            if needles.iter().any(|needle| code.contains(needle)) {
                out.push(format!("{}:{n}: {}", path.display(), code.trim()));
            }
        }
    }
    out
}

#[test]
fn the_core_names_no_fmi_version() {
    let found = offending(
        "src/fmu",
        &["fmi2", "fmi3", "Fmi2", "Fmi3", "FMI2_", "FMI3_"],
    );
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn the_fmi_layers_do_not_import_each_other() {
    let found = offending("src/fmi2", &["crate::fmi3", "fmi3::"]);
    assert!(found.is_empty(), "{}", found.join("\n"));
    let found = offending("src/fmi3", &["crate::fmi2", "fmi2::"]);
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn the_physics_and_the_solver_import_no_fmi_layer() {
    for dir in ["src/bond_graph", "src/fragments", "src/model", "src/solver"] {
        let found = offending(dir, &["crate::fmi2", "crate::fmi3", "fmi2::", "fmi3::"]);
        assert!(found.is_empty(), "{}", found.join("\n"));
    }
}

/// The scan sees what it looks for: a line of code with a needle is found, the same in a
/// comment is not.
#[test]
fn the_scan_finds_code_and_skips_comments() {
    let dir = std::env::temp_dir().join(format!("layering-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("a.rs"),
        "use crate::fmi2::ffi; // fmi3\n/// fmi3 in a doc comment\nlet u = \"file://x\"; // Fmi3\n",
    )
    .unwrap();
    let lines = code_lines(&dir.join("a.rs"));
    assert_eq!(lines.len(), 2);
    assert!(lines[0].1.contains("fmi2") && !lines[0].1.contains("fmi3"));
    assert!(lines[1].1.contains("file://x") && !lines[1].1.contains("Fmi3"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every `unsafe` block and `unsafe impl` in the sources has a `SAFETY:` comment saying why it
/// is sound, on the lines just before it or on its own line (and `unsafe_op_in_unsafe_fn` is
/// denied in the library and `hsp`, so an unsafe function's body needs the blocks too).
#[test]
fn every_unsafe_block_says_why_it_is_sound() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut missing = Vec::new();
    for path in sources(&root) {
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let code = without_comment(line);
            let block = code.contains("unsafe {") || code.contains("unsafe impl");
            if block
                && !lines[i.saturating_sub(4)..=i]
                    .iter()
                    .any(|l| l.contains("SAFETY:"))
            {
                missing.push(format!("{}:{}: {}", path.display(), i + 1, line.trim()));
            }
        }
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
    for file in ["src/lib.rs", "src/bin/hsp/main.rs"] {
        let text =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(file)).unwrap();
        assert!(text.contains("#![deny(unsafe_op_in_unsafe_fn)]"), "{file}");
    }
}
