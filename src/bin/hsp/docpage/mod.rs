//! The FMU's documentation page, `documentation/index.html`, and its figures, made at package time.
//!
//! The page stands alone (the reader has neither the paper nor this repository) and loads nothing
//! from the network: every figure is a file in `documentation/` beside it.
//! - `sketch.svg`: a hand-drawn sketch of the rig (`docs/img/sketch.svg`, embedded in `hsp`);
//! - `bond_graph.svg`: the model's own bond graph (its elements, bonds and causal strokes, the
//!   graph `hsp graph` prints), grouped as the paper draws it and laid out by `bond_graph.rs`, so
//!   packaging needs no Graphviz;
//! - `default_experiment.svg`/`.png`: `hsp run` with its defaults on the packaged FMU itself (run
//!   as a child process of `hsp`, through the FMU's C ABI), its summary printed on the page as the
//!   expected result;
//! - `bode.svg`/`.png`: the frequency response of the model linearised at rest with the FMU's
//!   start values.
//!
//! The variable tables are read from the archive's `modelDescription.xml` (the single source of
//! truth, read by the project's one reader, `tools/model_description.rs`): causality,
//! variability, start, min, max, unit and display unit, values printed short.
//!
//! One job a file: `figures.rs` makes the figures (`bond_graph.rs` draws the bond graph),
//! `tables.rs` the tables, `page.rs` fills the page template `page.html` with them; `text.rs` has
//! the number and HTML formatting they share.

mod bond_graph;
mod figures;
mod page;
mod tables;
pub mod text;

use std::path::Path;

use crate::model_description::ModelDescription;

/// A file of the documentation folder: its name inside `documentation/` and its bytes.
pub type DocFile = (String, Vec<u8>);

/// The documentation of the packaged FMU `fmu` (without documentation: the default experiment is
/// run on it), `xml` its model description, `platforms2` and `platforms3` the `binaries/` folders
/// of the FMI 2.0 and the FMI 3.0 FMU (both carry this documentation).
pub fn documentation(
    fmu: &Path,
    xml: &str,
    platforms2: &[String],
    platforms3: &[String],
    web: bool,
) -> Result<Vec<DocFile>, String> {
    let work = std::env::temp_dir().join(format!("hsp-doc-{}", std::process::id()));
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    let result = make(fmu, xml, [platforms2, platforms3], web, &work);
    let _ = std::fs::remove_dir_all(&work);
    result
}

fn make(
    fmu: &Path,
    xml: &str,
    platforms: [&[String]; 2],
    web: bool,
    work: &Path,
) -> Result<Vec<DocFile>, String> {
    let md = ModelDescription::parse(xml)?;
    let mut files: Vec<DocFile> = vec![
        ("sketch.svg".into(), figures::SKETCH.as_bytes().to_vec()),
        (
            "bond_graph.svg".into(),
            figures::bond_graph_svg()?.into_bytes(),
        ),
    ];
    let (summary, experiment) = figures::default_experiment(fmu, work)?;
    let bode = figures::bode(work)?;
    for path in experiment.iter().chain(&bode.paths) {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| format!("{}: no file name", path.display()))?
            .to_string();
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        files.push((name, bytes));
    }
    let page = page::page(&md, platforms, &summary, &bode.caption, web)?;
    files.insert(0, ("index.html".into(), page.into_bytes()));
    Ok(files)
}

/// The figures of a packaged FMU's `documentation/` copied into `dir` (`hsp doc-figures`, which
/// refreshes the README's pictures in `docs/img/`); returns the paths written.
pub fn copy_figures(fmu: &Path, dir: &Path) -> Result<Vec<std::path::PathBuf>, String> {
    let file = std::fs::File::open(fmu).map_err(|e| format!("{}: {e}", fmu.display()))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| format!("{}: {e}", fmu.display()))?;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut written = Vec::new();
    for i in 0..zip.len() {
        let mut entry = zip
            .by_index(i)
            .map_err(|e| format!("{}: {e}", fmu.display()))?;
        let Some(name) = entry
            .name()
            .strip_prefix("documentation/")
            .map(str::to_string)
        else {
            continue;
        };
        if !(name.ends_with(".svg") || name.ends_with(".png")) || name.contains('/') {
            continue;
        }
        let path = dir.join(&name);
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(&mut entry, &mut bytes)
            .map_err(|e| format!("{}: {name}: {e}", fmu.display()))?;
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(path);
    }
    if written.is_empty() {
        return Err(format!("{}: no figures in documentation/", fmu.display()));
    }
    Ok(written)
}
