//! The FMU's documentation page, `documentation/index.html`, and its figures, made at package time.
//!
//! The page stands alone (the reader has neither the paper nor this repository) and loads nothing
//! from the network: every figure is a file in `documentation/` beside it.
//! - `sketch.svg`: a hand-drawn sketch of the rig (`docs/img/sketch.svg`, embedded in `hsp`);
//! - `bond_graph.svg`: the model's own bond graph (the DOT of `hsp graph`) laid out by the
//!   pure-Rust `layout-rs`, so packaging needs no Graphviz;
//! - `default_experiment.svg`/`.png`: `hsp run` with its defaults on the packaged FMU itself (run
//!   as a child process of `hsp`, through the FMU's C ABI), its summary printed on the page as the
//!   expected result;
//! - `bode.svg`/`.png`: the frequency response of the model linearised at rest with the FMU's
//!   start values.
//!
//! The variable tables are read from the archive's `modelDescription.xml` (the single source of
//! truth): causality, variability, start, min, max, unit and display unit, values printed short.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::{bond_graph, Assembled};
use hydraulic_slewing_plate::model::frf::frequency_response;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::presets::PRESETS;
use hydraulic_slewing_plate::model::variables::VARIABLES;

use super::plot;

/// The hand-drawn sketch of the rig.
const SKETCH: &str = include_str!("../../../docs/img/sketch.svg");

/// The paper the model reproduces, in full.
pub const PAPER: &str = "E. G. Barbosa and L. C. S. G&oacute;es, <em>Modeling system of a \
    flexible structure with hydraulic actuation using bond-graphs</em>, Proceedings of the II \
    National Congress of Mechanical Engineering (CONEM 2002), Jo&atilde;o Pessoa, Brazil, \
    August 2002. Instituto Tecnol&oacute;gico de Aeron&aacute;utica (ITA), S&atilde;o Jos&eacute; \
    dos Campos.";

/// A file of the documentation folder: its name inside `documentation/` and its bytes.
pub type DocFile = (String, Vec<u8>);

/// Everything of `documentation/`: the page and its figures. `fmu` is the packaged FMU without
/// documentation (the default experiment is run on it), `xml` its model description,
/// `platforms` the `binaries/` folders it carries.
pub fn documentation(fmu: &Path, xml: &str, platforms: &[String]) -> Result<Vec<DocFile>, String> {
    let work = std::env::temp_dir().join(format!("hsp-doc-{}", std::process::id()));
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    let result = make(fmu, xml, platforms, &work);
    let _ = std::fs::remove_dir_all(&work);
    result
}

fn make(fmu: &Path, xml: &str, platforms: &[String], work: &Path) -> Result<Vec<DocFile>, String> {
    let md = ModelDescription::parse(xml)?;
    let mut files: Vec<DocFile> = vec![
        ("sketch.svg".into(), SKETCH.as_bytes().to_vec()),
        ("bond_graph.svg".into(), bond_graph_svg()?.into_bytes()),
    ];
    let (summary, experiment) = default_experiment(fmu, work)?;
    let bode = bode(work)?;
    for path in experiment.iter().chain(&bode.paths) {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| format!("{}: no file name", path.display()))?
            .to_string();
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        files.push((name, bytes));
    }
    let page = page(&md, platforms, &summary, &bode.caption);
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

/// Settings of the bond-graph figure: the FMU's start values with a two-mode plate, so that the
/// picture stays readable (each further plate mode adds the same pattern).
pub const BOND_GRAPH_FIGURE: &[(&str, &str)] =
    &[("plate.N", "2"), ("plate.M", "1"), ("plate.Cd", "0")];

/// The model's bond graph at the FMU's start values (and [`BOND_GRAPH_FIGURE`]), its power part
/// laid out and drawn as SVG by `layout-rs`.
pub fn bond_graph_svg() -> Result<String, String> {
    use layout::backends::svg::SVGWriter;
    use layout::gv::{DotParser, GraphBuilder};

    let mut values = Values::from_start(&VARIABLES);
    for (name, value) in BOND_GRAPH_FIGURE {
        set_by_name(&mut values, name, value)?;
    }
    let parameters = Parameters::from_values(&values, &Experiment::default())?;
    let dot = power_part(&bond_graph(&parameters)?.to_dot());
    let mut parser = DotParser::new(&dot);
    let graph = parser
        .process()
        .map_err(|e| format!("bond graph: layout-rs cannot read the DOT: {e}"))?;
    let mut builder = GraphBuilder::new();
    builder.visit_graph(&graph);
    let mut visual = builder.get();
    let mut svg = SVGWriter::new();
    visual.do_it(false, false, false, &mut svg);
    Ok(svg.finalize())
}

/// Whether a DOT statement names a signal block (`s12`).
fn names_signal(statement: &str) -> bool {
    statement
        .split(|c: char| c.is_whitespace() || c == '[' || c == ';')
        .take(3)
        .any(|w| w.len() > 1 && w.starts_with('s') && w[1..].chars().all(|c| c.is_ascii_digit()))
}

/// The power part of `hsp graph`'s DOT, restyled for `layout-rs` (which draws plain arrows and
/// boxes or circles): signal blocks dropped; elements as boxes, junctions as circles; each bond
/// an arrow in the power direction, black when the causal stroke is at its head (the element
/// there receives the effort), blue when it is at its tail. The bond names ("a->b") repeat the
/// element names and are dropped.
fn power_part(dot: &str) -> String {
    let mut out = String::new();
    for l in dot.lines() {
        let t = l.trim_start();
        if names_signal(t) || t.starts_with("node ") || t.starts_with("label=") {
            continue;
        }
        if let Some((ends, attrs)) = t.split_once(" [").filter(|(e, _)| e.contains(" -> ")) {
            let color = if attrs.contains("arrowhead=teelnormal") {
                "black"
            } else {
                "blue"
            };
            writeln!(out, "  {ends} [color=\"{color}\"];").unwrap();
        } else if t.starts_with('e') && t.contains("[label=") {
            let junction = t.contains("[label=\"0\"") || t.contains("[label=\"1\"");
            if junction {
                writeln!(out, "  {t}").unwrap();
            } else {
                writeln!(out, "  {}", t.replacen("[label=", "[shape=box, label=", 1)).unwrap();
            }
        } else {
            writeln!(out, "{l}").unwrap();
        }
    }
    out
}

/// Runs `hsp run` with its defaults (no `--set`) on the FMU in a child process: its summary and
/// the figure files.
fn default_experiment(
    fmu: &Path,
    work: &Path,
) -> Result<(String, Vec<std::path::PathBuf>), String> {
    let exe = std::env::current_exe().map_err(|e| format!("hsp's own path: {e}"))?;
    let csv = work.join("default_experiment.csv");
    let out = Command::new(&exe)
        .args(["run", "--no-build", "--no-plot", "--fmu"])
        .arg(fmu)
        .arg("--csv")
        .arg(&csv)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    if !out.status.success() {
        return Err(format!(
            "the default experiment failed on the packaged FMU ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let summary = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.trim_start().starts_with("results"))
        .collect::<Vec<_>>()
        .join("\n");
    let paths = plot::experiment(&csv, "Default experiment (hsp run)")?;
    Ok((summary, paths))
}

struct BodeFigure {
    paths: Vec<std::path::PathBuf>,
    caption: String,
}

/// The preset of the Bode plot: the paper's Fig. 9b, whose peaks Table 1 lists.
const BODE_PRESET: &str = "paper-fig9b";

/// The Bode plot of the model linearised at rest in the preset [`BODE_PRESET`]: from `r` to the
/// tip deflection when the motor drives the plate, else to the potentiometer.
fn bode(work: &Path) -> Result<BodeFigure, String> {
    let mut values = Values::from_start(&VARIABLES);
    hydraulic_slewing_plate::model::presets::apply(&mut values, BODE_PRESET)?;
    let parameters = Parameters::from_values(&values, &Experiment::default())?;
    let system = Assembled::new(&parameters)?;
    let lin = system
        .compiled()
        .linearize(&system.initial_state(), system.inputs());
    let mut h = frequency_response(&lin, "r", "w_tip", 0.5, 120.0, 2000)?;
    let plate = h.magnitude.iter().any(|m| *m > 1e-12);
    if !plate {
        h = frequency_response(&lin, "r", "y_pot", 0.5, 120.0, 2000)?;
    }
    let paths = plot::bode(
        &work.join("bode"),
        &plot::Bode {
            title: format!(
                "Frequency response {} -> {}, preset {BODE_PRESET} (linearised at rest)",
                h.input, h.output
            ),
            f_hz: &h.f_hz,
            magnitude: &h.magnitude,
            phase_deg: &h.phase_deg,
            peaks: &h.peaks,
            reference: plate.then_some(("Table 1 of the paper", &plot::TABLE1_FRF_HZ[..])),
        },
    )?;
    let peaks: Vec<String> = h.peaks.iter().map(|(f, _)| format!("{f:.2} Hz")).collect();
    let caption = format!(
        "Frequency response from the reference <code>r</code> [V] to <code>{}</code> [{}], the \
         model linearised at rest in the preset <code>{BODE_PRESET}</code> (the paper's Fig. 9b: \
         the LOES driving the hub and the paper's plate formulation; <code>hsp frf --preset \
         {BODE_PRESET} --output {} --plot FILE</code>). Resonance peaks: {}.{}",
        h.output,
        if plate { "m" } else { "V" },
        h.output,
        if peaks.is_empty() {
            "none".to_string()
        } else {
            peaks.join(", ")
        },
        if plate {
            " Dashed: the peaks the paper measured (its Table 1: 4.98, 16.0, 33.3, 66, 73, 84 Hz); \
             the model's hub torque cannot excite the modes above 40 Hz, see below."
        } else {
            ""
        }
    );
    Ok(BodeFigure { paths, caption })
}

/// A variable as the model description declares it.
struct Var {
    name: String,
    causality: String,
    variability: String,
    kind: String,
    start: Option<String>,
    min: Option<String>,
    max: Option<String>,
    unit: Option<String>,
    display_unit: Option<String>,
    description: String,
}

/// A display unit: name, factor, offset (display = factor * SI + offset).
type DisplayUnit = (String, f64, f64);

/// What the page needs from `modelDescription.xml`.
struct ModelDescription {
    attributes: Vec<(String, String)>,
    co_simulation: Vec<(String, String)>,
    model_exchange: bool,
    default_experiment: Vec<(String, String)>,
    /// unit -> its display units
    display_units: Vec<(String, Vec<DisplayUnit>)>,
    variables: Vec<Var>,
}

fn attributes(node: roxmltree::Node) -> Vec<(String, String)> {
    node.attributes()
        .map(|a| (a.name().to_string(), a.value().to_string()))
        .collect()
}

fn get<'a>(attrs: &'a [(String, String)], name: &str) -> Option<&'a str> {
    attrs
        .iter()
        .find(|(k, _)| k == name)
        .map(|(_, v)| v.as_str())
}

impl ModelDescription {
    fn parse(xml: &str) -> Result<Self, String> {
        let doc =
            roxmltree::Document::parse(xml).map_err(|e| format!("modelDescription.xml: {e}"))?;
        let root = doc.root_element();
        let child = |name: &str| root.children().find(|n| n.has_tag_name(name));
        let mut display_units = Vec::new();
        if let Some(defs) = child("UnitDefinitions") {
            for unit in defs.children().filter(|n| n.has_tag_name("Unit")) {
                let list = unit
                    .children()
                    .filter(|n| n.has_tag_name("DisplayUnit"))
                    .map(|d| {
                        let num = |k: &str, default: f64| {
                            d.attribute(k)
                                .and_then(|v| v.parse().ok())
                                .unwrap_or(default)
                        };
                        (
                            d.attribute("name").unwrap_or("").to_string(),
                            num("factor", 1.0),
                            num("offset", 0.0),
                        )
                    })
                    .collect();
                display_units.push((unit.attribute("name").unwrap_or("").to_string(), list));
            }
        }
        let mut variables = Vec::new();
        if let Some(list) = child("ModelVariables") {
            for sv in list.children().filter(|n| n.has_tag_name("ScalarVariable")) {
                let Some(ty) = sv.children().find(|n| n.is_element()) else {
                    continue;
                };
                let a = |k: &str| ty.attribute(k).map(str::to_string);
                variables.push(Var {
                    name: sv.attribute("name").unwrap_or("").to_string(),
                    causality: sv.attribute("causality").unwrap_or("local").to_string(),
                    variability: sv
                        .attribute("variability")
                        .unwrap_or("continuous")
                        .to_string(),
                    kind: ty.tag_name().name().to_string(),
                    start: a("start"),
                    min: a("min"),
                    max: a("max"),
                    unit: a("unit"),
                    display_unit: a("displayUnit"),
                    description: sv.attribute("description").unwrap_or("").to_string(),
                });
            }
        }
        Ok(ModelDescription {
            attributes: attributes(root),
            co_simulation: child("CoSimulation").map(attributes).unwrap_or_default(),
            model_exchange: child("ModelExchange").is_some(),
            default_experiment: child("DefaultExperiment")
                .map(attributes)
                .unwrap_or_default(),
            display_units,
            variables,
        })
    }

    /// The display unit of a variable: its `displayUnit`, else the unit's first display unit.
    fn display(&self, v: &Var) -> Option<DisplayUnit> {
        let unit = v.unit.as_deref()?;
        let list = &self.display_units.iter().find(|(u, _)| u == unit)?.1;
        match &v.display_unit {
            Some(d) => list.iter().find(|(n, _, _)| n == d).cloned(),
            None => list.first().cloned(),
        }
    }
}

/// A number printed short: four significant digits, no trailing zeros, scientific notation
/// outside 1e-3 to 1e5 (`23153293.32444247` -> `2.315e7`, `3.9062499999999994e-5` -> `3.906e-5`).
pub fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{v:.3e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exponent}")
    }
}

/// A number from the XML printed short (non-numbers as they are).
fn short_text(s: &str) -> String {
    s.parse::<f64>()
        .map(short)
        .unwrap_or_else(|_| s.to_string())
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// When a variable may be set, in words.
fn settable(v: &Var) -> &'static str {
    match (v.causality.as_str(), v.variability.as_str()) {
        ("input", _) => "any time (input)",
        ("parameter", "fixed") => "before initialisation only",
        ("parameter", "tunable") => "any time",
        ("calculatedParameter", _) | ("output", _) | ("local", _) => "read-only",
        (_, "constant") => "read-only",
        _ => "see the FMI standard",
    }
}

fn variable_table(md: &ModelDescription, causalities: &[&str], s: &mut String) {
    s.push_str(
        "<table>\n<tr><th>name</th><th>type</th><th>causality / variability</th><th>settable</th>\
         <th>start</th><th>min</th><th>max</th><th>unit</th><th>start in display unit</th>\
         <th>description</th></tr>\n",
    );
    for v in md
        .variables
        .iter()
        .filter(|v| causalities.contains(&v.causality.as_str()))
    {
        let display = match (md.display(v), v.start.as_deref().map(str::parse::<f64>)) {
            (Some((unit, factor, offset)), Some(Ok(x))) => {
                format!("{} {}", short(x * factor + offset), escape(&unit))
            }
            (Some((unit, _, _)), _) => escape(&unit),
            _ => String::new(),
        };
        let opt = |o: &Option<String>| o.as_deref().map(short_text).unwrap_or_default();
        writeln!(
            s,
            "<tr><td><code>{}</code></td><td>{}</td><td>{} / {}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&v.name),
            v.kind,
            v.causality,
            v.variability,
            settable(v),
            opt(&v.start),
            opt(&v.min),
            opt(&v.max),
            escape(v.unit.as_deref().unwrap_or("")),
            display,
            escape(&v.description)
        )
        .unwrap();
    }
    s.push_str("</table>\n");
}

/// Today's date (UTC), or that of `SOURCE_DATE_EPOCH` for reproducible packages.
fn date() -> String {
    let secs = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.parse::<i64>().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_secs() as i64)
                .unwrap_or(0)
        });
    // Days to civil date (H. Hinnant's algorithm).
    let z = secs.div_euclid(86_400) + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

fn has(md: &ModelDescription, name: &str) -> bool {
    md.variables.iter().any(|v| v.name == name)
}

/// The page.
fn page(md: &ModelDescription, platforms: &[String], summary: &str, bode_caption: &str) -> String {
    let attr = |k: &str| escape(get(&md.attributes, k).unwrap_or("?"));
    let model = attr("modelName");
    let mut capabilities = String::new();
    for (k, v) in &md.co_simulation {
        if k != "modelIdentifier" {
            write!(capabilities, "<code>{k}=\"{}\"</code> ", escape(v)).unwrap();
        }
    }
    // The plate modes Model Exchange declares states for (x.plate.I[k].p, k = 1, 2, ...).
    let me_plate_modes = md
        .variables
        .iter()
        .filter(|v| v.name.starts_with("x.plate.I["))
        .count();
    let interfaces = if md.model_exchange {
        "Co-Simulation and Model Exchange"
    } else {
        "Co-Simulation only (the FMU carries its own stiff solver)"
    };
    let platform_list: Vec<String> = platforms
        .iter()
        .map(|p| match p.as_str() {
            "linux64" => "<code>linux64</code> (x86-64 Linux)".to_string(),
            "win64" => "<code>win64</code> (x86-64 Windows 10 or later)".to_string(),
            "darwin64" => "<code>darwin64</code> (x86-64 macOS)".to_string(),
            other => format!("<code>{}</code>", escape(other)),
        })
        .collect();
    let de = |k: &str| get(&md.default_experiment, k).map(short_text);
    let default_experiment = format!(
        "start {} s, stop {} s, step {} s, tolerance {}",
        de("startTime").unwrap_or_else(|| "0".into()),
        de("stopTime").unwrap_or_else(|| "?".into()),
        de("stepSize").unwrap_or_else(|| "?".into()),
        de("tolerance").unwrap_or_else(|| "?".into()),
    );
    let external = if has(md, "e_in") {
        "<h3>External control</h3>\n<p>Set the parameter <code>controller.external = true</code> \
         before initialisation and the input <code>e_in</code> [V] drives the servo valve's coil \
         in place of the built-in analog controller, so that your own controller (Simulink, \
         Modelica, Python) closes the loop on the outputs <code>y_pot</code>, \
         <code>theta_hub</code>, the torsion-bar torque and the accelerometers.</p>\n"
    } else {
        ""
    };
    let mut tables = String::new();
    for (title, causalities, note) in [
        (
            "Inputs",
            &["input"][..],
            "Set them between communication steps.",
        ),
        ("Outputs", &["output"][..], "Read-only."),
        (
            "Parameters",
            &["parameter"][..],
            "<em>fixed</em> parameters can be set only before initialisation (between \
             <code>fmi2Instantiate</code> and <code>fmi2ExitInitializationMode</code>); \
             <em>tunable</em> ones at any time. A value outside min/max is refused by \
             <code>fmi2SetReal</code>/<code>fmi2SetInteger</code> with a message naming the \
             variable.",
        ),
        (
            "Calculated parameters",
            &["calculatedParameter"][..],
            "Read-only: computed at initialisation from the parameters (for example the plate's \
             natural frequencies <code>plate.f[i]</code>).",
        ),
        (
            "Continuous states and their derivatives",
            &["local"][..],
            "Model Exchange integrates these: the storages' momenta <code>p</code> and \
             displacements <code>q</code> of the bond graph, set through \
             <code>fmi2SetContinuousStates</code>; a state the chosen configuration does not \
             have keeps its value with derivative 0. Co-Simulation reports them after each step.",
        ),
    ] {
        if !md
            .variables
            .iter()
            .any(|v| causalities.contains(&v.causality.as_str()))
        {
            continue;
        }
        writeln!(tables, "<h3>{title}</h3>\n<p>{note}</p>").unwrap();
        variable_table(md, causalities, &mut tables);
    }
    let fmu_version = attr("version");
    let guid = attr("guid");
    let fmi_version = attr("fmiVersion");
    let generation_tool = attr("generationTool");
    let today = date();
    let summary = escape(summary);
    let mut presets = String::from(
        "<table>\n<tr><th>name</th><th>in the paper</th><th>what</th><th>settings</th></tr>\n",
    );
    for p in PRESETS {
        let settings: Vec<String> = p
            .settings
            .iter()
            .map(|(k, v)| format!("<code>{k} = {}</code>", short_text(v)))
            .collect();
        writeln!(
            presets,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td></tr>",
            p.name,
            escape(p.paper),
            escape(p.description),
            settings.join(", ")
        )
        .unwrap();
    }
    presets.push_str("</table>\n");
    let bond_graph_settings = BOND_GRAPH_FIGURE
        .iter()
        .map(|(k, v)| format!("<code>{k} = {v}</code>"))
        .collect::<Vec<_>>()
        .join(", ");
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{model}</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
body{{font-family:"DejaVu Sans",Verdana,sans-serif;max-width:66em;margin:2em auto;padding:0 1em;line-height:1.45;color:#222}}
table{{border-collapse:collapse;font-size:.85em;margin-bottom:1em}}
td,th{{border:1px solid #ccc;padding:.2em .45em;text-align:left;vertical-align:top}}
th{{background:#f2f2f2}} code{{font-size:.95em}} pre{{background:#f6f6f6;padding:.6em;overflow-x:auto}}
figure{{margin:1em 0}} figure img{{max-width:100%;border:1px solid #ddd}} figcaption{{font-size:.9em;color:#444}}
.meta td:first-child{{font-weight:bold}}
</style>
</head><body>
<h1>{model}</h1>
<p>A flexible aluminium plate on a hub, slewed through a torsion bar by a rotary vane motor under a
two-stage electro-hydraulic servo valve and an analog position loop: an FMI {fmi_version}
FMU ({interfaces}), reproducing the model of {PAPER}</p>

<table class="meta">
<tr><td>FMU version</td><td>{fmu_version} (packaged {today})</td></tr>
<tr><td>FMI version and interfaces</td><td>FMI {fmi_version}, {interfaces}</td></tr>
<tr><td>FMI 2.0 and 3.0</td><td>The model is packaged twice from the same binaries, with this page in
both: <code>HydraulicSlewingPlate.fmu</code> (FMI 2.0) and <code>fmi3/HydraulicSlewingPlate.fmu</code>
(FMI 3.0). The variables below carry their FMI 2.0 names; in the FMI 3.0 FMU the accelerometers
<code>acc[1]</code> to <code>acc[12]</code> are one array variable <code>acc</code> and the
frequencies <code>plate.f[k]</code> the array <code>plate.f</code> (value reference of the first
element), and <code>time</code> is value reference 0.</td></tr>
<tr><td>Capabilities</td><td>{capabilities}</td></tr>
<tr><td>Platforms (binaries in this FMU)</td><td>{platforms}</td></tr>
<tr><td>Default experiment</td><td>{default_experiment}</td></tr>
<tr><td>GUID</td><td><code>{guid}</code></td></tr>
<tr><td>Generated by</td><td>{generation_tool}</td></tr>
</table>

<h2>The system</h2>
<figure><img src="sketch.svg" alt="Sketch of the rig: servo valve, vane motor, torsion bar, hub, plate, sensors" width="900">
<figcaption>The rig. The position controller compares the reference <code>r</code> with the
motor potentiometer <code>y_pot</code> (10 V over 150 degrees) and drives the coil of the servo
valve's torque motor; the valve meters oil into the two chambers of the vane motor; the motor
turns the hub through a torsion bar; the hub carries the flexible plate, excited by the slewing
and by two shaker forces <code>F1</code>, <code>F2</code>, and instrumented with accelerometers
and a tip-deflection output <code>w_tip</code>.</figcaption></figure>

<p>How it is modelled. The paper builds the model from <em>bond graphs</em>: each physical part (the
torque motor, the flapper-nozzle stage, the spool, the vane motor, the torsion bar, the hub, the
plate) is a small graph of energy storages (I: inertias, C: compliances), dissipators (R),
transformers (TF), gyrators (GY) and sources, and the parts are joined at power ports; the state
equations follow from the joined graph. This FMU does the same at initialisation, from the
parameters you set, and integrates the result with its own stiff solver (Rodas5P or Radau IIA of
order 5; <code>solver.*</code> parameters). The plate is an assumed-modes model (products of beam
functions along and across the plate, <code>plate.N</code> x <code>plate.M</code>); its natural
frequencies are the read-only <code>plate.f[i]</code>. The hydraulics is either the full servo valve
(<code>hydraulics.model = 2</code>) or the paper's identified low-order equivalent system
(<code>hydraulics.model = 1</code>, a third-order transfer function from command to motor angle,
<code>2.25e6 / (s (s + 65) (s + 753))</code> from the potentiometer's point of view).</p>

<figure><img src="bond_graph.svg" alt="The model's bond graph" style="max-height:60em">
<figcaption>The power part of the bond graph this FMU builds from its start values, drawn at
package time from the model's own graph, with a two-mode plate ({bond_graph_settings}) so that it
stays readable: each further plate mode adds one more 1-junction with its I, C, R and the
transformers from the forces. Boxes: elements (I inertia, C compliance, R resistance, TF
transformer, GY gyrator, MSe/MSf modulated sources), with their parameter; circles: 0- and
1-junctions. Each arrow is a bond in the direction of positive power; black when the causal stroke
is at the arrow's head (the element there receives the effort), blue when it is at the tail. The
signal part (sensors, controller) is left out; <code>hsp graph</code> prints the whole graph as
Graphviz DOT.</figcaption></figure>

<h2>Expected result of the default experiment</h2>
<figure><img src="default_experiment.svg" alt="Time histories of the default experiment" width="1000">
<figcaption>The default experiment, run at package time on this FMU through its C ABI
(<code>hsp run</code> with its defaults; <code>default_experiment.png</code> is the same picture as a
bitmap).</figcaption></figure>
<p>What <code>hsp run</code> printed for it (your importer should reproduce these numbers to the
solver tolerance):</p>
<pre>{summary}</pre>

<figure><img src="bode.svg" alt="Bode plot" width="1000">
<figcaption>{bode_caption}</figcaption></figure>

<h2>How to use</h2>
<h3>Python (fmpy)</h3>
<pre>from fmpy import simulate_fmu
result = simulate_fmu("HydraulicSlewingPlate.fmu",  # the default experiment: a 30 degree move
                      output=["controller.reference", "y_pot", "theta_hub", "w_tip", "plate.stress"])
# result is a NumPy structured array: result["time"], result["y_pot"], ...
# the paper's 2 V step instead (it leaves the linear model's range, and the FMU warns):
# start_values={{"reference.angle": 0.0, "r": 2.0}}</pre>
<p>Parameters are set the same way (<code>start_values={{"plate.zeta": 0.01}}</code>); fixed
parameters only take effect when given before initialisation, which <code>simulate_fmu</code>
does.</p>
<h3>Modelica and Simulink</h3>
<p>Dymola: <em>File &gt; Import &gt; FMU</em>; OpenModelica: <em>File &gt; Import &gt; FMI</em>
(or <code>importFMU("HydraulicSlewingPlate.fmu")</code>); both give a block with the inputs and
outputs below and the parameters as block parameters. Simulink: the <em>FMU Import</em> block
(Simulink &gt; Simulink Extras, or the FMU block of R2017b and later) in co-simulation mode; set
the block's sample time to your communication step (1 ms is a good start: the FMU takes its own
internal steps). Connect a signal to <code>r</code> (the position reference, V; 10 V is 150
degrees of motor angle) and read <code>y_pot</code>, <code>theta_hub</code>, <code>w_tip</code> and
the accelerometers.</p>
<h3>Co-Simulation or Model Exchange</h3>
<p>One binary offers both interfaces. In <em>Co-Simulation</em> the FMU integrates itself with
its stiff solver and delivers the state at each communication point (while the inputs are
unchanged its steps run past the points, which are read from the solver's dense output within the
tolerance; <code>solver.dense_output = false</code> ends a step on every point): the choice for co-simulation
masters, Simulink's FMU block and fixed-step importers. In <em>Model Exchange</em> the importer's
solver integrates the continuous states <code>x.*</code> from their derivatives
<code>der(x.*)</code>: the choice for Modelica tools, which prefer it, and for coupling the model
tightly with other equations. Pick a stiff (implicit) solver there: the servo valve's pilot stage
is fast. Both interfaces give exact directional derivatives
(<code>fmi2GetDirectionalDerivative</code>, from dual numbers through the bond graph's equations)
and the sparsity of the Jacobian (<code>ModelStructure/Derivatives</code>). The number of states
of FMI 2.0 Model Exchange is fixed by this file, while the model's states depend on the structural
parameters: the file declares the states of every configuration with up to {me_plate_modes} plate modes
(<code>plate.N</code> x <code>plate.M</code>); a state the chosen configuration does not have keeps
its value and has derivative 0, and a larger plate is refused at initialisation in Model Exchange
(Co-Simulation takes up to 20 x 20). The model has no events: its limits are smooth laws.</p>
<h3>Configurations of the paper</h3>
<p>The paper's configurations are parameter sets: set these parameters before initialisation (the
others keep their start values). The first is the FMU's default. The repository's command-line
tool selects them by name (<code>hsp run --preset NAME</code>).</p>
{presets}
{external}
<h3>Limits</h3>
<p>The paper's frequency response (its Table 1) also shows peaks at 66, 73 and 84 Hz. In the plate
equations the hub torque cannot excite the modes (n, m) with m &ge; 3 (the elastic beam functions
across the plate, whose integral over the width is zero), so this model shows no peak above 40 Hz
from <code>r</code>; the shakers <code>F1</code>, <code>F2</code> do excite those modes. A step the solver cannot complete returns <code>fmi2Discard</code> and keeps the last
good state (<code>fmi2LastSuccessfulTime</code>); FMU states can be saved, restored and
serialised.</p>

<h2>Variables</h2>
<p>Values in SI units as the FMI standard transmits them; the display unit is what importing tools
show.</p>
{tables}
<h2>Reference</h2>
<p>{PAPER}</p>
</body></html>
"#,
        platforms = platform_list.join(", "),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_printed_short() {
        assert_eq!(short(23153293.32444247), "2.315e7");
        assert_eq!(short(3.9062499999999994e-5), "3.906e-5");
        assert_eq!(short(0.0025), "0.0025");
        assert_eq!(short(2.0), "2");
        assert_eq!(short(-150.0), "-150");
        assert_eq!(short(57.29577951308232), "57.3");
        assert_eq!(short(1e-6), "1e-6");
        assert_eq!(short(0.0), "0");
    }

    #[test]
    fn power_part_keeps_elements_and_bonds_only() {
        let dot = "digraph \"g\" {\n  rankdir=LR;\n  node [shape=plaintext];\n  \
                   e0 [label=\"1\", tooltip=\"j\"];\n  e1 [label=\"I: m\\n2\", tooltip=\"m\"];\n  \
                   s0 [shape=box, label=\"sensor\"];\n  \
                   e0 -> e1 [dir=both, arrowhead=teelnormal, arrowtail=none, label=\"j->m\"];\n  \
                   e1 -> s0 [style=dashed];\n}";
        let p = power_part(dot);
        assert!(p.contains("e0 [label=\"1\""), "{p}");
        assert!(p.contains("e1 [shape=box, label="), "{p}");
        assert!(p.contains("e0 -> e1 [color=\"black\"];"), "{p}");
        assert!(
            !p.contains("s0") && !p.contains("j->m") && !p.contains("plaintext"),
            "{p}"
        );
    }

    #[test]
    fn dates_are_civil() {
        std::env::set_var("SOURCE_DATE_EPOCH", "951782400"); // 2000-02-29
        assert_eq!(date(), "2000-02-29");
        std::env::remove_var("SOURCE_DATE_EPOCH");
    }
}
