//! The figures of the documentation page: the sketch of the rig, the model's bond graph, the
//! default experiment run on the packaged FMU and the Bode plot of the linearised model.

use std::path::{Path, PathBuf};
use std::process::Command;

use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::frf::frequency_response;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::VARIABLES;
use hydraulic_slewing_plate::model::{assembly::Assembled, compose::bond_graph};

use super::bond_graph;
use crate::plot;

/// The hand-drawn sketch of the rig.
pub const SKETCH: &str = include_str!("../../../../docs/img/sketch.svg");

/// Settings of the bond-graph figure: the full servo valve (the FMU's start value, pinned here
/// because the caption says so) with a two-mode plate, so that the picture stays readable (each
/// further plate mode adds the same pattern).
pub const BOND_GRAPH_FIGURE: &[(&str, &str)] = &[
    ("hydraulics.model", "2"),
    ("plate.N", "2"),
    ("plate.M", "1"),
    ("plate.Cd", "0"),
];

/// The model's bond graph at the FMU's start values (and [`BOND_GRAPH_FIGURE`]), grouped as the
/// paper draws it and laid out by [`bond_graph::svg`], with the causal strokes of the compiled
/// model.
pub fn bond_graph_svg() -> Result<String, String> {
    let graph = bond_graph(&figure_parameters(&[])?)?;
    let compiled = graph
        .compile()
        .map_err(|e| format!("bond graph figure: {e}"))?;
    Ok(bond_graph::svg(&graph, Some(compiled.causal_strokes())))
}

/// The parameters of the bond-graph figure: the FMU's start values with [`BOND_GRAPH_FIGURE`],
/// then `more`.
pub fn figure_parameters(more: &[(&str, &str)]) -> Result<Parameters, String> {
    let mut values = Values::from_start(&VARIABLES);
    for (name, value) in BOND_GRAPH_FIGURE.iter().chain(more) {
        set_by_name(&mut values, name, value)?;
    }
    Parameters::from_values(&values, &Experiment::default())
}

/// Runs `hsp run` with its defaults (no `--set`) on the FMU in a child process: its summary, the
/// figure files.
pub fn default_experiment(fmu: &Path, work: &Path) -> Result<(String, Vec<PathBuf>), String> {
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

/// The Bode plot's files and its caption.
pub struct BodeFigure {
    pub paths: Vec<PathBuf>,
    pub caption: String,
}

/// The preset of the Bode plot: the paper's Fig. 9b, whose peaks Table 1 lists.
const BODE_PRESET: &str = "paper-fig9b";

/// The Bode plot of the model linearised at rest in the preset [`BODE_PRESET`]: from `r` to the
/// tip deflection when the motor drives the plate, else to the potentiometer.
pub fn bode(work: &Path) -> Result<BodeFigure, String> {
    let mut values = Values::from_start(&VARIABLES);
    hydraulic_slewing_plate::model::presets::apply(&mut values, BODE_PRESET)?;
    let parameters = Parameters::from_values(&values, &Experiment::default())?;
    let system = Assembled::new(&parameters.sliding())?;
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
