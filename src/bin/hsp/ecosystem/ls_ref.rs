//! The reference results of the default experiment, in the layout of the FMI layered standard
//! for references (FMI-LS-REF 1.0.0-alpha.1) as the Modelica Reference FMUs ship theirs: a
//! folder `extra/org.fmi-standard.fmi-ls-ref/` with the manifest `fmi-ls-manifest.xml`
//! (`<fmiReferences>`, one `<Related>` element per file) and the result
//! `HydraulicSlewingPlate_out.csv`. The presets' parameter sets (`.ssv`, see [`super::ssp`]) sit
//! beside it, listed with the role `parameter`.
//!
//! The result is `hsp run`'s CSV on the packaged FMU (the run that draws the documentation's
//! figure), so it is always this very binary's result; `tests/default_experiment.rs` checks that
//! it is the committed `tests/reference/default_experiment.csv` to the byte. The default
//! experiment has no inputs: `r`, `e_in`, `F1` and `F2` keep their start values (0) and the move
//! comes from the FMU's command generator, so the folder holds no input file.

use std::fmt::Write as _;

use hydraulic_slewing_plate::model::presets::PRESETS;
use hydraulic_slewing_plate::model::variables::MODEL_IDENTIFIER;

use super::{ssp, Entry};
use crate::model_description::{get, ModelDescription};

/// The layered standard's folder in the archive.
pub const FOLDER: &str = "extra/org.fmi-standard.fmi-ls-ref";

/// The name of the result file, as the Reference FMUs name theirs (`<model>_out.csv`).
pub fn result_name() -> String {
    format!("{MODEL_IDENTIFIER}_out.csv")
}

/// The default experiment's settings, read from the model description.
struct Settings {
    stop: f64,
    step: f64,
    tolerance: f64,
}

fn settings(xml: &str) -> Result<Settings, String> {
    let md = ModelDescription::parse(xml)?;
    let de = md
        .default_experiment
        .ok_or("the model description has no <DefaultExperiment>")?;
    let number = |name: &str| -> Result<f64, String> {
        get(&de, name)
            .ok_or_else(|| format!("<DefaultExperiment> has no {name}"))?
            .parse::<f64>()
            .map_err(|e| format!("<DefaultExperiment> {name}: {e}"))
    };
    Ok(Settings {
        stop: number("stopTime")?,
        step: number("stepSize")?,
        tolerance: number("tolerance")?,
    })
}

/// Fails unless the CSV's time column runs from 0 to the default experiment's stop time in its
/// communication steps: the run that made it (`hsp run`'s own defaults) must be the experiment
/// the manifest says it is.
fn check_grid(csv: &[u8], s: &Settings) -> Result<(), String> {
    let text = std::str::from_utf8(csv).map_err(|e| format!("result CSV: {e}"))?;
    let times: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap_or("").parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("result CSV, time column: {e}"))?;
    let expected = (s.stop / s.step).round() as usize + 1;
    let on_grid = times
        .iter()
        .enumerate()
        .all(|(k, t)| (t - k as f64 * s.step).abs() <= 1e-9 * s.stop);
    if times.len() != expected || !on_grid {
        return Err(format!(
            "the result CSV has {} rows, not the {expected} points of the default experiment \
             (0 to {} s every {} s)",
            times.len(),
            s.stop,
            s.step
        ));
    }
    Ok(())
}

/// The comparison a user of the result should make, stated in the manifest (the Python test
/// `tests/python/test_ecosystem.py` reads it from there).
fn tolerance_statement(s: &Settings) -> String {
    format!(
        "Compare each column within a relative tolerance of {:e} of its largest magnitude, the \
         default experiment's tolerance: the FMU's own solver made the result at that \
         tolerance, so smaller differences carry no meaning; an importer that steps the same \
         communication grid in co-simulation reproduces it to rounding.",
        s.tolerance
    )
}

/// The manifest, `fmi-ls-manifest.xml`.
pub fn manifest(xml: &str) -> Result<String, String> {
    let s = settings(xml)?;
    let mut m = String::new();
    m.push_str(concat!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n",
        "<!-- Written by hsp package (src/bin/hsp/ecosystem/ls_ref.rs); docs/ecosystem.md -->\n",
        "<fmiReferences\n",
        "    xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\"\n",
        "    xmlns:fmi-ls=\"http://fmi-standard.org/fmi-ls-manifest\"\n",
        "    fmi-ls:fmi-ls-name=\"org.fmi-standard.fmi-ls-ref\"\n",
        "    fmi-ls:fmi-ls-version=\"1.0.0-alpha.1\">\n",
    ));
    let description = format!(
        "Output of the default experiment: co-simulation from 0 to {} s, communication step {} \
         s, tolerance {:e}, every parameter at its start value, no inputs (r, e_in, F1 and F2 \
         stay 0; the 30 deg move comes from the FMU's command generator). {}",
        s.stop,
        s.step,
        s.tolerance,
        tolerance_statement(&s)
    );
    writeln!(
        m,
        "    <Related type=\"text/csv\" source=\"{}\" role=\"result\" description=\"{}\"/>",
        result_name(),
        ssp::escape(&description)
    )
    .unwrap();
    for p in PRESETS {
        writeln!(
            m,
            "    <Related type=\"application/x-ssp-parameter-set\" source=\"{}\" \
             role=\"parameter\" description=\"{}\"/>",
            ssp::file_name(p),
            ssp::escape(&format!(
                "Preset {} ({}): {}",
                p.name, p.paper, p.description
            ))
        )
        .unwrap();
    }
    m.push_str("</fmiReferences>\n");
    Ok(m)
}

/// The folder's files: the manifest, the result and the parameter sets.
pub fn entries(csv: Vec<u8>, xml: &str) -> Result<Vec<Entry>, String> {
    check_grid(&csv, &settings(xml)?)?;
    let mut files = vec![
        (
            format!("{FOLDER}/fmi-ls-manifest.xml"),
            manifest(xml)?.into_bytes(),
        ),
        (format!("{FOLDER}/{}", result_name()), csv),
    ];
    for p in PRESETS {
        files.push((
            format!("{FOLDER}/{}", ssp::file_name(p)),
            ssp::parameter_set(p)?.into_bytes(),
        ));
    }
    Ok(files)
}
