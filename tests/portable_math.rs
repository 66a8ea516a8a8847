//! The library computes the same doubles on every platform (src/math.rs): no call of a
//! transcendental function of `f64` (which goes to the platform's C library) outside
//! `src/math.rs`, whose functions come from the `libm` crate. The command-line tools
//! (`src/bin/`) are not part of the FMU and may use the platform's.

use std::path::Path;

/// The `f64` methods that call the platform's libm (sqrt is exact everywhere and allowed).
const PLATFORM_FUNCTIONS: [&str; 21] = [
    "exp", "exp2", "exp_m1", "ln", "ln_1p", "log2", "log10", "powf", "cbrt", "hypot", "sin", "cos",
    "tan", "sin_cos", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
];

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "bin") {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") && !path.ends_with("src/math.rs") {
            out.push(path);
        }
    }
}

/// Method calls `.NAME(` and paths `f64::NAME(` of the platform functions in code (not in
/// comments). A line whose comment says `nalgebra` calls nalgebra's function of a matrix (its
/// scalar functions come from libm too: Cargo.toml's `libm-force`).
fn platform_calls(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let (code, comment) = line.split_once("//").unwrap_or((line, ""));
        if comment.contains("nalgebra") {
            continue;
        }
        for name in PLATFORM_FUNCTIONS {
            for pattern in [format!(".{name}("), format!("f64::{name}(")] {
                if code.contains(&pattern) && !code.contains(&format!("math::{name}(")) {
                    found.push(format!("line {}: {}", number + 1, line.trim()));
                }
            }
        }
    }
    found
}

#[test]
fn the_library_calls_no_platform_math_function() {
    let mut files = Vec::new();
    rust_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut files,
    );
    assert!(files.len() > 50, "{} files", files.len());
    let mut offenders = Vec::new();
    for f in &files {
        for call in platform_calls(&std::fs::read_to_string(f).unwrap()) {
            offenders.push(format!("{}: {call}", f.display()));
        }
    }
    assert!(
        offenders.is_empty(),
        "use crate::math instead (the same bits on every platform):\n{}",
        offenders.join("\n")
    );
}

#[test]
fn the_scan_finds_what_it_looks_for() {
    assert_eq!(platform_calls("let y = x.tanh();").len(), 1);
    assert_eq!(platform_calls("let y = f64::exp(x);").len(), 1);
    assert!(platform_calls("let y = crate::math::tanh(x);").is_empty());
    assert!(platform_calls("// x.exp() in a comment").is_empty());
    assert!(platform_calls("let y = x.sqrt();").is_empty());
    assert!(platform_calls("let e = m.exp(); // nalgebra's matrix exponential").is_empty());
}
