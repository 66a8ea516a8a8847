//! `hsp package`: builds the release cdylib and writes the FMU archive: `modelDescription.xml`
//! (verbatim from `modelDescription/`), `binaries/linux64/HydraulicSlewingPlate.so` (glibc 2.17),
//! `binaries/win64/HydraulicSlewingPlate.dll` (where the binaries come from: [`binaries`]) and
//! `documentation/index.html` (generated from the variable table).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::binaries;
use hydraulic_slewing_plate::fmi2::{Causality, Kind, Values};
use hydraulic_slewing_plate::model::variables::{GUID, MODEL_IDENTIFIER, VARIABLES};

pub const DEFAULT_FMU: &str = "fmu/HydraulicSlewingPlate.fmu";

/// The repository root (where Cargo.toml is).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Builds and writes the FMU with every binary the installed toolchains allow; returns its path.
pub fn package(output: &str) -> Result<String, String> {
    package_with(output, false)
}

/// Builds and writes the FMU; with `require_portable`, fails unless both the glibc-2.17 Linux
/// binary and the Windows binary are built (see [`binaries`]). Returns its path.
pub fn package_with(output: &str, require_portable: bool) -> Result<String, String> {
    let binaries = binaries::build(require_portable)?;
    let xml_path = root().join("modelDescription/modelDescription.xml");
    let xml = std::fs::read(&xml_path).map_err(|e| format!("{}: {e}", xml_path.display()))?;
    let mut files = Vec::new();
    for b in &binaries {
        let data = std::fs::read(&b.path).map_err(|e| format!("{}: {e}", b.path.display()))?;
        let name = format!("binaries/{}/{MODEL_IDENTIFIER}.{}", b.platform, b.extension);
        files.push((name, data));
    }
    let out = if Path::new(output).is_absolute() {
        PathBuf::from(output)
    } else {
        root().join(output)
    };
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    // Write to a temporary name and rename, so that a reader never sees half an archive.
    let tmp = out.with_extension("fmu.partial");
    let file = std::fs::File::create(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    let doc = documentation();
    let mut entries: Vec<(&str, &[u8])> = vec![("modelDescription.xml", &xml)];
    entries.extend(
        files
            .iter()
            .map(|(name, data)| (name.as_str(), data.as_slice())),
    );
    entries.push(("documentation/index.html", doc.as_bytes()));
    for (name, data) in entries {
        zip.start_file(name, options)
            .and_then(|_| zip.write_all(data).map_err(Into::into))
            .map_err(|e| format!("writing {name} into {}: {e}", tmp.display()))?;
    }
    zip.finish()
        .map_err(|e| format!("{}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, &out).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(out.display().to_string())
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// `documentation/index.html`: what the model is, where it comes from, and every variable.
pub fn documentation() -> String {
    let start = Values::from_start(&VARIABLES);
    let mut rows = String::new();
    for (section, causalities) in [
        ("Inputs", &[Causality::Input][..]),
        ("Outputs", &[Causality::Output][..]),
        (
            "Parameters",
            &[Causality::Parameter, Causality::CalculatedParameter][..],
        ),
    ] {
        writeln!(rows, "<h2>{section}</h2>\n<table>\n<tr><th>name</th><th>type</th><th>start</th><th>unit</th><th>description</th></tr>").unwrap();
        for (i, v) in VARIABLES.iter().enumerate() {
            if !causalities.contains(&v.causality) {
                continue;
            }
            let start = match (v.kind, start.get(i)) {
                (Kind::Real { start: Some(_), .. }, value)
                | (Kind::Integer { start: Some(_), .. }, value)
                | (Kind::Boolean { start: Some(_) }, value) => format!("{value:?}")
                    .trim_start_matches(|c: char| c.is_alphabetic())
                    .trim_matches(|c| c == '(' || c == ')')
                    .to_string(),
                _ => String::new(),
            };
            writeln!(
                rows,
                "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                escape(v.name),
                v.kind.type_name(),
                start,
                escape(v.unit.unwrap_or("")),
                escape(v.description)
            )
            .unwrap();
        }
        rows.push_str("</table>\n");
    }
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{MODEL_IDENTIFIER}</title>
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto;line-height:1.4}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:.2em .5em;text-align:left;vertical-align:top}}</style>
</head><body>
<h1>{MODEL_IDENTIFIER}</h1>
<p>A flexible aluminium plate on a gas-bearing hub, slewed through a torsion bar by a rotary vane
motor under a two-stage electro-hydraulic servo valve and an analog position loop, after
E. G. Barbosa and L. C. S. G&oacute;es, <em>Modeling system of a flexible structure with hydraulic
actuation using bond-graphs</em>, II National Congress of Mechanical Engineering (CONEM), Jo&atilde;o
Pessoa, 2002. The model is built as in the paper: bond-graph fragments composed into one graph,
from which the state equations are derived.</p>
<h2>What this version simulates</h2>
<p>The hydraulic position loop as the low-order equivalent system (LOES) of the paper's Fig. 3 and
eq. 1: a valve-flow source <code>k_sv A1 A2 (r - k_pot theta_a)</code> into the actuator chambers
(capacitance <code>C3</code>, leakage <code>R7</code>), the vane motor (<code>D_m</code>) and the
rotor inertia <code>I_b</code>. The default parameters fit the identified direct path
<code>G(s) = 2.25e6 / (s (s + 65) (s + 753))</code> of eq. 2 exactly: the paper's printed
<code>R7 = 3.8e7</code> does not (it puts the poles at 135 and 364 rad/s), so
<code>R7 = 1/(818 C3)</code>; <code>D_m</code> and <code>k_sv</code>, which the paper does not print,
follow from the same fit with a potentiometer of 10 V over 150 degrees.</p>
<p>With <code>hydraulics.model = 2</code>, the full servo valve of Fig. 2b instead: torque motor
(BG1: coil, gyrator, flapper), flapper-nozzle stage and spool with a feedback wire (BG2), and the
four-way spool metering into the vane motor's chambers (BG3), with regularised square-root
orifices; its parameters (<code>servo_valve.*</code>) are representative values, three of them
fitted so that its linearised direct path matches <code>G(s)</code> within 0.43 dB and 2.2 degrees
up to 60 Hz. Coupled to the hub through the torsion bar this valve's loop is unstable (its damping
sits in rotor friction, which the heavy hub does not feel); the LOES coupled the same way is stable.
See the project's README.</p>
<p>The flexible plate (sections 2.2 to 4 of the paper): assumed modes (beam functions, any
<code>plate.N</code> x <code>plate.M</code>, default 3 x 5) in the paper's formulation (eqs. 18-21
with errata fixed; reproduces eq. 16) or a consistent Lagrangian one (<code>plate.formulation</code>),
on the hub (<code>hub.I_H</code>) or with the hub locked (<code>plate.root</code>), excited by the
shaker forces <code>F1</code>, <code>F2</code> and, with <code>hydraulics.motor_coupled = true</code>,
by the motor through the torsion bar (<code>torsion_bar.k</code>). With
<code>motor_coupled = false</code> (default) the motor runs alone, as in the paper's identification.
Outputs: hub angle and speed, bar torque, tip deflection and acceleration (eq. 22), twelve
accelerometers; the natural frequencies of the plate model are the calculated parameters
<code>plate.f[1]</code> ... <code>plate.f[20]</code>.</p>
<h2>Solver</h2>
<p>An internal stiff one-step integrator, Rodas5P (default) or Radau IIA of order 5, with relative
tolerance <code>solver.rtol</code> (or the tolerance of <code>fmi2SetupExperiment</code>) and absolute
tolerance <code>solver.atol</code> relative to each state's nominal value. Every communication step
ends exactly on the communication point; FMU states can be saved, restored and serialised, and
restoring gives bit-identical results. A step the solver cannot complete returns
<code>fmi2Discard</code> and keeps the last good state (<code>fmi2LastSuccessfulTime</code>).</p>
<p>GUID <code>{GUID}</code>.</p>
{rows}
</body></html>
"#
    )
}
