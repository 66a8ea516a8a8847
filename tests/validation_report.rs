//! docs/validation.md, the model against the paper: the committed report and its figures are what
//! `hsp validate` writes from the current library, every row is within its tolerance, and every
//! test it names exists.

use std::path::Path;
use std::process::Command;

#[test]
fn committed_report_is_what_hsp_validate_writes() {
    // `--check` writes nothing; it fails on a stale report or figure, on a figure it does not
    // write, and on a row outside its tolerance.
    let out = Command::new(env!("CARGO_BIN_EXE_hsp"))
        .args(["validate", "--check"])
        .output()
        .expect("hsp runs");
    assert!(
        out.status.success(),
        "hsp validate --check failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `tests/FILE.rs::NAME` references in a text.
fn test_references(text: &str) -> Vec<(String, String)> {
    let mut refs = Vec::new();
    for (i, _) in text.match_indices("tests/") {
        let rest = &text[i..];
        let Some(sep) = rest.find("::") else { continue };
        let file = &rest[..sep];
        if !file.ends_with(".rs") || file.contains(char::is_whitespace) {
            continue;
        }
        let name: String = rest[sep + 2..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        refs.push((file.to_string(), name));
    }
    refs
}

#[test]
fn every_test_the_report_names_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let report = std::fs::read_to_string(root.join("docs/validation.md")).unwrap();
    let refs = test_references(&report);
    assert!(refs.len() >= 5, "{refs:?}");
    for (file, name) in refs {
        let source = std::fs::read_to_string(root.join(&file))
            .unwrap_or_else(|e| panic!("{file}, named by docs/validation.md: {e}"));
        assert!(
            source.contains(&format!("#[test]\nfn {name}()")),
            "docs/validation.md names {file}::{name}, which is not a test there"
        );
    }
}
