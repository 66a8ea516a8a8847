//! The figures of the documentation that do not depend on the machine's speed are the ones the
//! tools print now: `hsp docs --check` passes on the repository, and fails, naming the file and
//! the block, on a changed figure, a timing table without the line saying what made it, an
//! unknown block and a marker without its end.

#[path = "common/packaged.rs"]
mod packaged;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn hsp_docs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hsp"))
        .arg("docs")
        .args(args)
        .output()
        .expect("hsp runs")
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// A fresh root in the temporary folder with `files` (relative path, text) under `docs/`.
fn temp_root(name: &str, files: &[(&str, String)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hsp-docs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("docs")).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    dir
}

fn check_in(dir: &Path) -> Output {
    hsp_docs(&["--check", "--root", dir.to_str().unwrap()])
}

#[test]
fn the_docs_are_what_hsp_docs_writes() {
    // The size and summary blocks read the packaged FMUs: built from these sources first.
    packaged::fresh_fmu(packaged::Version::Fmi2);
    packaged::fresh_fmu(packaged::Version::Fmi3);
    let out = hsp_docs(&["--check"]);
    assert!(
        out.status.success(),
        "hsp docs --check failed:\n{}",
        text(&out)
    );
}

/// The first generated block of `page`: its start marker and the offset of its text.
fn first_block(page: &str, name: &str) -> (String, usize) {
    let start = page
        .find(&format!("<!-- hsp docs: {name} "))
        .unwrap_or_else(|| panic!("no block {name}"));
    let close = start + page[start..].find("-->").unwrap() + 3;
    let marker = page[start + "<!-- hsp docs: ".len()..close - 3]
        .trim()
        .to_string();
    (marker, close)
}

#[test]
fn a_changed_figure_fails_the_check_naming_file_and_block() {
    let page = std::fs::read_to_string(root().join("docs/model.md")).unwrap();
    let (marker, at) = first_block(&page, "mode-hz");
    // One digit of the figure changed: the first digit after the marker, plus one.
    let offset = at + page[at..].find(|c: char| c.is_ascii_digit()).unwrap();
    let digit = page.as_bytes()[offset] - b'0';
    let mut changed = page.clone();
    changed.replace_range(offset..offset + 1, &((digit + 1) % 10).to_string());
    let dir = temp_root("changed", &[("docs/model.md", changed.clone())]);

    let out = check_in(&dir);
    let said = text(&out);
    assert!(!out.status.success(), "the check passed:\n{said}");
    assert!(said.contains("docs/model.md"), "{said}");
    assert!(
        said.contains(&format!("block '{marker}' differs")),
        "{said}"
    );
    // --check writes nothing; without it the block is written back as the tool gives it.
    let path = dir.join("docs/model.md");
    assert_eq!(std::fs::read_to_string(&path).unwrap(), changed);
    let written = hsp_docs(&["--root", dir.to_str().unwrap()]);
    assert!(written.status.success(), "{}", text(&written));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), page);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_timing_block_without_its_header_fails() {
    let page = std::fs::read_to_string(root().join("docs/benchmarks.md")).unwrap();
    let start = page.find("<!-- hsp timing: ").expect("a timing block");
    let line_end = start + page[start..].find('\n').unwrap() + 1;
    let label = page[start + "<!-- hsp timing: ".len()..line_end]
        .trim_end()
        .trim_end_matches("-->")
        .trim()
        .to_string();
    let header_end = line_end + page[line_end..].find('\n').unwrap() + 1;
    assert!(page[line_end..header_end].starts_with("Made by `"));
    let mut changed = page.clone();
    changed.replace_range(line_end..header_end, "");
    let dir = temp_root("timing", &[("docs/benchmarks.md", changed)]);

    let out = check_in(&dir);
    let said = text(&out);
    assert!(!out.status.success(), "the check passed:\n{said}");
    assert!(
        said.contains("docs/benchmarks.md:") && said.contains(&format!("'{label}'")),
        "{said}"
    );
    assert!(
        said.contains("Made by `COMMAND` on YYYY-MM-DD, load L."),
        "{said}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unknown_block_and_a_marker_without_its_end_fail() {
    let dir = temp_root(
        "markers",
        &[
            (
                "docs/unknown.md",
                "a <!-- hsp docs: no-such-figure -->1<!-- /hsp docs: no-such-figure -->\n".into(),
            ),
            (
                "docs/open.md",
                "<!-- hsp docs: info states -->\n45\n".into(),
            ),
        ],
    );
    let out = check_in(&dir);
    let said = text(&out);
    assert!(!out.status.success(), "the check passed:\n{said}");
    assert!(
        said.contains("docs/unknown.md:1: block 'no-such-figure': unknown block"),
        "{said}"
    );
    assert!(
        said.contains("docs/open.md: line 1: block 'info' has no end marker"),
        "{said}"
    );
    // Nothing is written while a marker is wrong.
    let written = hsp_docs(&["--root", dir.to_str().unwrap()]);
    assert!(!written.status.success(), "{}", text(&written));
    let _ = std::fs::remove_dir_all(&dir);
}
