//! The reference files of the FMUs in the layout of the FMI layered standard for references
//! (FMI-LS-REF 1.0.0-alpha.1): a folder `extra/org.fmi-standard.fmi-ls-ref/` with the manifest
//! `fmi-ls-manifest.xml` (`<fmiReferences>`, one `<Related>` element per file), the default
//! experiment's result `HydraulicSlewingPlate_out.csv` (see [`super::result`]) and the presets'
//! parameter sets (`.ssv`, see [`super::ssp`]); and `documentation/fmi-ls-ref.html`, the page
//! the standard recommends ("further information to the importer": what the files are, how to
//! compare, the deviations to expect).
//!
//! The default experiment has no inputs: `r`, `e_in`, `F1` and `F2` keep their start values (0)
//! and the move comes from the FMU's command generator, so the folder holds no input file.

use std::fmt::Write as _;

use hydraulic_slewing_plate::model::presets::PRESETS;
use hydraulic_slewing_plate::model::variables::MODEL_IDENTIFIER;

use super::result::DefaultExperiment;
use super::ssp::{self, escape};
use super::Entry;

/// The layered standard's folder in the archive.
pub const FOLDER: &str = "extra/org.fmi-standard.fmi-ls-ref";

/// The page with what the importer should know of the folder, in `documentation/`.
pub const DOCUMENTATION: &str = "fmi-ls-ref.html";

/// The root element's `fmi-ls:fmi-ls-description`, which the standard's schema fixes to this text.
const LS_DESCRIPTION: &str =
    "Layered Standard providing information on related files included in an FMU.";

/// The largest deviation from the result, relative to each column's largest magnitude, of an
/// importer that passes no stop time and steps the default experiment's grid: a regression
/// bound on the value measured with libcosim and with fmpy's low-level API, 4.5e-8 (in
/// `servo_valve.x_f`, at the last points; the dense output's error at those points, within the
/// solver's tolerance, so that it moves with the solver's steps: 2.4e-8 before the hub's
/// inertias were put on the modes' absolute rates):
/// `tests/python/test_ecosystem.py::test_the_stated_reproduction_holds_with_and_without_a_stop_time`
/// and `test_libcosim_without_a_stop_time_reproduces_the_result_as_stated` print it and fail
/// above the bound.
const WITHOUT_STOP_TIME: f64 = 5e-8;

/// The same bound before the last [`DIFFERING_POINTS`] communication points: fmpy without a stop
/// time reproduces those to the bit; libcosim, whose communication points are whole nanoseconds
/// (steps of 0.004999999999999893 s), within 7.1e-14 (a regression bound, the same tests).
const BEFORE_THE_LAST: f64 = 1e-13;

/// How many communication points at the end differ by more than [`BEFORE_THE_LAST`] when the
/// importer passes no stop time: the FMU's solver steps run past communication points up to the
/// stop time (`solver.dense_output`); without one its last step runs past the end, and these
/// points come from its dense output: as many as the last step spans (a regression value, 3
/// since the hub's inertias were put on the modes' absolute rates, 2 before).
const DIFFERING_POINTS: usize = 3;

/// The name of the result file, as the Reference FMUs name theirs (`<model>_out.csv`).
pub fn result_name() -> String {
    format!("{MODEL_IDENTIFIER}_out.csv")
}

/// A file the manifest lists: its MIME type, name, role and description.
struct Related {
    mime: &'static str,
    source: String,
    role: &'static str,
    description: String,
}

/// The experiment the result is of, in words.
fn experiment_text(de: &DefaultExperiment) -> String {
    format!(
        "co-simulation from {} to {} s, communication step {} s, tolerance {:e}, every \
         parameter at its start value, no inputs (r, e_in, F1 and F2 stay 0; the 30 deg move \
         comes from the FMU's command generator)",
        de.start, de.stop, de.step, de.tolerance
    )
}

/// How to compare with the result and what an importer reproduces (the Python tests read the
/// tolerance and the bound from the manifest).
fn comparison_text(de: &DefaultExperiment) -> String {
    format!(
        "Compare each column within a relative tolerance of {:e} of its largest magnitude, the \
         default experiment's tolerance: the FMU's own solver made the result at that \
         tolerance, so smaller differences carry no meaning. Measured: an importer that passes \
         the stop time and steps this grid in co-simulation (fmpy) reproduces every column to \
         the bit; one that passes no stop time (libcosim) reproduces the values within {:e} of \
         each column's largest magnitude, and within {:e} but at the last {DIFFERING_POINTS} \
         communication points (the FMU's solver steps run past communication points up to the \
         stop time; without one its last step runs past the end, and those points come from \
         its dense output; before them only the rounding of the importer's communication \
         points remains).",
        de.tolerance, WITHOUT_STOP_TIME, BEFORE_THE_LAST
    )
}

/// The files of the folder, the manifest aside, in the manifest's order.
fn related(de: &DefaultExperiment) -> Vec<Related> {
    let mut files = vec![Related {
        mime: "text/csv",
        source: result_name(),
        role: "result",
        description: format!(
            "Output of the default experiment: {}. Every output of the model description, one \
             column each (an FMI 3.0 array one column, its elements separated by spaces). {}",
            experiment_text(de),
            comparison_text(de)
        ),
    }];
    for p in PRESETS {
        files.push(Related {
            mime: "application/x-ssp-parameter-set",
            source: ssp::file_name(p),
            role: "parameter",
            description: format!("Preset {} ({}): {}", p.name, p.paper, p.description),
        });
    }
    files
}

/// The manifest, `fmi-ls-manifest.xml`, for the FMI 2.0 model description `xml`.
pub fn manifest(xml: &str) -> Result<String, String> {
    let de = DefaultExperiment::read(xml)?;
    let mut m = String::new();
    m.push_str(concat!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n",
        "<!-- Written by hsp package (src/bin/hsp/ecosystem/ls_ref.rs); docs/ecosystem.md -->\n",
        "<fmiReferences\n",
        "    xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\"\n",
        "    xmlns:fmi-ls=\"http://fmi-standard.org/fmi-ls-manifest\"\n",
        "    fmi-ls:fmi-ls-name=\"org.fmi-standard.fmi-ls-ref\"\n",
        "    fmi-ls:fmi-ls-version=\"1.0.0-alpha.1\"\n",
    ));
    writeln!(m, "    fmi-ls:fmi-ls-description=\"{LS_DESCRIPTION}\">").unwrap();
    for r in related(&de) {
        writeln!(
            m,
            "    <Related type=\"{}\" source=\"{}\" role=\"{}\" description=\"{}\"/>",
            r.mime,
            escape(&r.source),
            r.role,
            escape(&r.description)
        )
        .unwrap();
    }
    m.push_str("</fmiReferences>\n");
    Ok(m)
}

/// `documentation/fmi-ls-ref.html`: the folder's files and how to use the result.
pub fn documentation(xml: &str) -> Result<String, String> {
    let de = DefaultExperiment::read(xml)?;
    let mut rows = String::new();
    for r in related(&de) {
        writeln!(
            rows,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td></tr>",
            escape(&r.source),
            r.role,
            escape(&r.description)
        )
        .unwrap();
    }
    Ok(format!(
        "<!DOCTYPE html>\n\
         <html lang=\"en\"><head><meta charset=\"utf-8\"><title>{MODEL_IDENTIFIER}: reference \
         files (FMI-LS-REF)</title></head><body>\n\
         <!-- Written by hsp package (src/bin/hsp/ecosystem/ls_ref.rs); docs/ecosystem.md -->\n\
         <h1>Reference files (FMI-LS-REF)</h1>\n\
         <p>The folder <code>{FOLDER}/</code> holds the files below, listed with their roles in \
         its <code>fmi-ls-manifest.xml</code>. The <a href=\"index.html\">FMU's documentation</a> \
         describes the model.</p>\n\
         <table border=\"1\"><tr><th>file</th><th>role</th><th>what</th></tr>\n{rows}</table>\n\
         <h2>The result</h2>\n\
         <p><code>{}</code> is the default experiment ({}) as the Modelica Reference FMUs lay out \
         theirs: a column <code>time</code> and one column per output, in the model \
         description's order. The FMI 2.0 FMU's file has one column per scalar \
         (<code>acc[1]</code> .. <code>acc[12]</code>); the FMI 3.0 FMU's has one column per \
         variable, an array's elements separated by spaces in one cell (<code>acc</code>), \
         as fmusim writes it and fmpy's <code>read_csv</code> reads it.</p>\n\
         <p>{}</p>\n\
         </body></html>\n",
        result_name(),
        escape(&experiment_text(&de)),
        escape(&comparison_text(&de)),
    ))
}

/// The folder's files but the result (the manifest and the parameter sets), and the page in
/// `documentation/`: the same in both FMUs.
pub fn entries(xml: &str) -> Result<Vec<Entry>, String> {
    let mut files = vec![
        (
            format!("{FOLDER}/fmi-ls-manifest.xml"),
            manifest(xml)?.into_bytes(),
        ),
        (
            format!("documentation/{DOCUMENTATION}"),
            documentation(xml)?.into_bytes(),
        ),
    ];
    for p in PRESETS {
        files.push((
            format!("{FOLDER}/{}", ssp::file_name(p)),
            ssp::parameter_set(p)?.into_bytes(),
        ));
    }
    Ok(files)
}

/// The result file's entry with the bytes `csv`.
pub fn result_entry(csv: String) -> Entry {
    (format!("{FOLDER}/{}", result_name()), csv.into_bytes())
}
