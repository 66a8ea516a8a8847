//! `hsp`: the project's command-line tool.
//!
//! - `hsp package`: builds the release library and writes `fmu/HydraulicSlewingPlate.fmu` (FMI 2.0),
//!   `fmu/fmi3/HydraulicSlewingPlate.fmu` (FMI 3.0) and the example SSP system
//!   `fmu/HydraulicSlewingPlate.ssp`.
//! - `hsp ssp [--out ssp]`: the presets as SSP 1.0 parameter sets and the example system's
//!   `SystemStructure.ssd`, the repository's `ssp/` (docs/ecosystem.md).
//! - `hsp run [--preset NAME]`: builds the FMU if needed, loads it through its C ABI, runs the
//!   default experiment (a slewing manoeuvre of the complete system: a step in the reference `r`),
//!   prints a summary and writes the results as CSV.
//! - `hsp identify --frf INPUT:OUTPUT:FILE.csv --fit NAME[:LOW:HIGH] [--out FILE.ssv] [--json]`:
//!   fits parameters to measured frequency responses, with confidence intervals
//!   (docs/identify.md).
//! - `hsp fastest-move [hsp run arguments]`: the fastest minimum-jerk move whose peak `w_tip/a`
//!   stays within 0.1, bisected over `reference.duration`, and its torque budget.
//! - `hsp presets [--json]`: the named parameter sets (the paper's configurations).
//! - `hsp linearize --json [--set NAME=VALUE ...]`: A, B, C, D of the assembled model at rest, in
//!   the layout of `Linearization::to_json` (names, operating point `x0`, `u0`, matrices by rows),
//!   and A's `eigenvalues` as `[re, im]` (balanced, `hydraulic_slewing_plate::eigen`).
//! - `hsp graph [--set ...]`: the model's bond graph as Graphviz DOT, with causal strokes.
//! - `hsp modes --json [--set ...]`: natural frequencies of the plate model (eq. 14); `--plot FILE`
//!   draws the first mode shapes.
//! - `hsp frf --input r --output acc_tip --from 0.5 --to 120 [--json] [--set ...]`: frequency
//!   response of the linearised model and its resonance peaks; `--plot FILE` draws its Bode plot.
//! - `hsp info [--json] [--preset NAME] [--set ...]`: size and structure of the assembled model:
//!   states, plan, the Jacobian's pattern, its varying entries and passes per evaluation.
//! - `hsp validate [--check]`: writes docs/validation.md and its figures, the model against the
//!   paper (`--check` compares instead).
//! - `hsp web [--out docs/web]`: the browser build, the `.wasm` beside the interactive page's
//!   sources (docs/web.md).
//! - `hsp docs [--check] [--root DIR]`: the generated figures of the markdown files, rewritten
//!   (`--check` compares instead).
//! - `hsp doc-figures [--fmu F] [--out docs/img]`: the packaged FMU's documentation figures,
//!   copied for the README.

#![deny(unsafe_op_in_unsafe_fn)]

mod binaries;
mod docpage;
mod docs;
mod ecosystem;
mod fastest;
mod identify;
mod info;
mod licenses;
mod loader;
mod manoeuvre;
// The one reader of modelDescription.xml, shared with build.rs.
#[path = "../../../tools/model_description.rs"]
#[allow(dead_code)]
mod model_description;
mod modeshape;
mod package;
mod plot;
mod progress;
mod results;
mod run;
mod validate;
mod web;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use hydraulic_slewing_plate::bond_graph::Linearization;
use hydraulic_slewing_plate::eigen;
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::compose::{bond_graph, plate_modes};
use hydraulic_slewing_plate::model::frf::frequency_response;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::VARIABLES;

#[derive(Parser)]
#[command(
    name = "hsp",
    version,
    about = "Hydraulic slewing plate (Barbosa & Goes, 2002): FMU tools"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The parameter set a command works on: the FMU's start values, a preset, then `--set`.
#[derive(clap::Args)]
struct ModelArgs {
    /// Set a parameter, NAME=VALUE (repeatable); names are the FMU's variable names
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Start from a named parameter set (`hsp presets`); --set applies after it
    #[arg(long)]
    preset: Option<String>,
}

impl ModelArgs {
    /// The FMU's values: the start values, the preset, then `--set`.
    fn values(&self) -> Result<Values, String> {
        values_with(self.preset.as_deref(), &self.set)
    }
    fn parameters(&self) -> Result<Parameters, String> {
        Parameters::from_values(&self.values()?, &Experiment::default())
    }
    /// The model to linearise: the vane motor sliding ([`Parameters::sliding`]).
    fn assembled(&self) -> Result<Assembled, String> {
        Assembled::new(&self.parameters()?.sliding())
    }
}

#[derive(Subcommand)]
enum Command {
    /// Build the release library and package the FMI 2.0 FMU fmu/HydraulicSlewingPlate.fmu and
    /// the FMI 3.0 FMU fmu/fmi3/HydraulicSlewingPlate.fmu
    Package {
        /// Where to write the FMU
        #[arg(long, default_value = package::DEFAULT_FMU)]
        output: String,
        /// Fail unless every binary is built: Linux (x86-64 and aarch64, glibc 2.17), Windows and
        /// macOS (without it, a missing toolchain gives a warning and the FMU lacks that platform;
        /// without zig, the Linux binary is built for this machine's glibc only)
        #[arg(long)]
        require_portable: bool,
        /// Build only the Linux binary for this machine (no glibc-2.17 or other cross build):
        /// the quick test loop's FMU
        #[arg(long, conflicts_with = "require_portable")]
        host_only: bool,
    },
    /// Write the presets as SSP 1.0 parameter sets (resources/*.ssv) and the example system
    /// (SystemStructure.ssd) into a folder, the repository's ssp/
    Ssp {
        /// Where to write them
        #[arg(long, default_value = "ssp")]
        out: String,
    },
    /// Build the browser build (WebAssembly) and put it beside the interactive page: open
    /// docs/web/index.html
    Web {
        /// Where to write the page (its sources are copied there too unless it is docs/web)
        #[arg(long, default_value = web::PAGE_DIR)]
        out: String,
    },
    /// Run the default experiment (a slewing manoeuvre) through the FMU's C ABI and summarise it
    Run(run::RunArgs),
    /// Fit parameters to measured frequency responses, with 95 % confidence intervals and a
    /// warning naming what the data cannot determine; write the fitted configuration as an SSP
    /// parameter set (docs/identify.md)
    Identify(identify::IdentifyArgs),
    /// The torque budget: the fastest minimum-jerk move (bisected to 1 ms over
    /// reference.duration) whose peak |w_tip|/a stays within the validity monitor's limit, with
    /// its peak bar torque, load pressure, hub overshoot and the motor's margin
    FastestMove(fastest::FastestArgs),
    /// Print the hash of the sources this build is made from; a packaged FMU's binary carries it
    /// as `hsp-source-hash:<hash>`, so a test can tell a stale FMU from a fresh one
    SourceHash,
    /// List the named parameter sets (the paper's configurations) for --preset
    Presets {
        /// Print JSON: [{"name", "paper", "description", "settings": {NAME: value}}]
        #[arg(long)]
        json: bool,
    },
    /// Linearise the assembled model at rest: {"states", "inputs", "outputs", "x0", "u0", "A", "B",
    /// "C", "D", "eigenvalues"}, the matrices as arrays of rows, A's eigenvalues as [re, im] pairs
    /// (balanced first, as LAPACK's dgeev), the largest real part first
    Linearize {
        /// Print JSON (the only format)
        #[arg(long)]
        json: bool,
        /// Linearise the model as the integrators see it, the vane motor's seal friction with
        /// its regularised slope at rest included (a stiff real pole, T_s / (omega_t I_m)); by
        /// default the motor is sliding (docs/model-notes.md, item 31)
        #[arg(long)]
        as_integrated: bool,
        #[command(flatten)]
        model: ModelArgs,
    },
    /// Size and structure of the assembled model: states, plan, Jacobian pattern and passes
    Info {
        /// Print JSON instead of text
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        model: ModelArgs,
    },
    /// Print the model's bond graph as Graphviz DOT
    Graph {
        #[command(flatten)]
        model: ModelArgs,
    },
    /// Natural frequencies of the plate model (eq. 14): {"f_hz": [...], "labels": ["(n,m)", ...]}
    Modes {
        /// Print JSON (the only format)
        #[arg(long)]
        json: bool,
        /// Also draw the first mode shapes into FILE.png and FILE.svg
        #[arg(long, value_name = "FILE")]
        plot: Option<String>,
        /// How many mode shapes --plot draws
        #[arg(long, default_value_t = 6)]
        count: usize,
        #[command(flatten)]
        model: ModelArgs,
    },
    /// Copy the packaged FMU's documentation figures into a folder (the README's docs/img)
    DocFigures {
        /// The FMU to read (built by `hsp package`)
        #[arg(long, default_value = package::DEFAULT_FMU)]
        fmu: String,
        /// Where to write the figures
        #[arg(long, default_value = "docs/img")]
        out: String,
    },
    /// Write docs/validation.md and its figures: the model's numbers against the paper's
    Validate {
        /// Write nothing; fail when the committed report or a figure differs from what the
        /// command writes, or when a row is outside its tolerance
        #[arg(long)]
        check: bool,
    },
    /// Rewrite the generated figures of the markdown files (`<!-- hsp docs: NAME -->` blocks)
    Docs {
        /// Write nothing; fail when a block differs from what its generator gives, names no
        /// generator or lacks its end, or a timing block lacks its header
        #[arg(long)]
        check: bool,
        /// The repository whose README.md, CONTRIBUTING.md, docs/*.md and bench/*.md are read
        #[arg(long, value_name = "DIR")]
        root: Option<std::path::PathBuf>,
        /// Print the generators a block can name, with their arguments, and nothing else
        #[arg(long)]
        list: bool,
    },
    /// Frequency response of the linearised model, with its resonance peaks
    Frf {
        /// Input name (r, F1, F2)
        #[arg(long, default_value = "r")]
        input: String,
        /// Output name (acc_tip, w_tip, `acc[k]`, theta_hub, y_pot, ...)
        #[arg(long, default_value = "acc_tip")]
        output: String,
        /// Lowest frequency, Hz
        #[arg(long, default_value_t = 0.5)]
        from: f64,
        /// Highest frequency, Hz
        #[arg(long, default_value_t = 120.0)]
        to: f64,
        /// Number of log-spaced frequencies
        #[arg(long, default_value_t = 2000)]
        points: usize,
        /// Print JSON (frequencies, magnitude, phase, peaks) instead of the peak table
        #[arg(long)]
        json: bool,
        /// Also draw the Bode plot into FILE.png and FILE.svg (a .png/.svg extension is dropped)
        #[arg(long, value_name = "FILE")]
        plot: Option<String>,
        #[command(flatten)]
        model: ModelArgs,
    },
}

/// The linearisation whose responses the paper's FRFs are (`hsp frf`, `hsp identify`): the
/// assembled model of `p` at rest (zero inputs; the full servo valve at its null pressures),
/// with the vane motor sliding ([`Parameters::sliding`]: its seal friction's regularised slope
/// at rest left out).
fn linearization_at_rest(p: &Parameters) -> Result<Linearization, String> {
    Ok(Assembled::with_linearization_at_rest(&p.sliding())?.1)
}

/// The FMU's start values with the preset, then `--set`, applied.
fn values_with(preset: Option<&str>, sets: &[String]) -> Result<Values, String> {
    let mut values = Values::from_start(&VARIABLES);
    if let Some(name) = preset {
        presets::apply(&mut values, name)?;
    }
    for s in sets {
        let (name, value) = s
            .split_once('=')
            .ok_or_else(|| format!("--set '{s}': expected NAME=VALUE"))?;
        set_by_name(&mut values, name.trim(), value.trim())?;
    }
    Ok(values)
}

fn presets_text(json: bool) -> String {
    if json {
        return presets::presets_json().to_string();
    }
    let mut s = String::new();
    for p in presets::PRESETS {
        let settings: Vec<String> = p.settings.iter().map(|(n, v)| format!("{n}={v}")).collect();
        s.push_str(&format!(
            "{:<20} {}: {}\n{:<20} {}\n",
            p.name,
            p.paper,
            p.description,
            "",
            settings.join(" ")
        ));
    }
    s.trim_end().to_string()
}

fn linearize(model: &ModelArgs, as_integrated: bool) -> Result<String, String> {
    let system = if as_integrated {
        Assembled::new(&model.parameters()?)?
    } else {
        model.assembled()?
    };
    let x = system.initial_state();
    let lin = system.compiled().linearize(&x, system.inputs());
    let mut json = lin.to_json();
    let eigenvalues: Vec<[f64; 2]> = eigen::eigenvalues(&lin.a)
        .iter()
        .map(|z| [z.re, z.im])
        .collect();
    json["eigenvalues"] = serde_json::json!(eigenvalues);
    Ok(json.to_string())
}

fn model_info(model: &ModelArgs, json: bool) -> Result<String, String> {
    let system = model.assembled()?;
    Ok(if json {
        info::facts(&system).to_string()
    } else {
        info::text(&system)
    })
}

fn graph(model: &ModelArgs) -> Result<String, String> {
    let parameters = model.parameters()?;
    Ok(bond_graph(&parameters)?.to_dot())
}

fn modes(model: &ModelArgs, plot_file: Option<&str>, count: usize) -> Result<String, String> {
    let parameters = model.parameters()?;
    let modes = plate_modes(&parameters)?;
    if let Some(file) = plot_file {
        let shapes = modeshape::mode_shapes(&parameters.plate, count, 41, 17)?;
        for p in plot::mode_shapes(
            &plot::stem_of(file),
            "Plate mode shapes (deflection relative to the hub; white: nodal lines)",
            &shapes,
        )? {
            eprintln!("wrote {}", p.display());
        }
    }
    let json = serde_json::json!({
        "f_hz": modes.iter().map(|m| m.f_hz).collect::<Vec<_>>(),
        "labels": modes.iter().map(|m| format!("({},{})", m.label.0, m.label.1)).collect::<Vec<_>>(),
    });
    Ok(json.to_string())
}

struct FrfArgs<'a> {
    input: &'a str,
    output: &'a str,
    from: f64,
    to: f64,
    points: usize,
    json: bool,
    plot: Option<&'a str>,
}

/// Whether an output is a plate signal (its FRF from r is the paper's Fig. 9b, Table 1).
fn is_plate_signal(output: &str) -> bool {
    output.starts_with("acc") || output.starts_with("w_tip") || output.starts_with("plate.")
}

fn frf(a: &FrfArgs, model: &ModelArgs) -> Result<String, String> {
    let lin = linearization_at_rest(&model.parameters()?)?;
    let h = frequency_response(&lin, a.input, a.output, a.from, a.to, a.points)?;
    let mut written = Vec::new();
    if let Some(file) = a.plot {
        let reference = (a.input == "r" && is_plate_signal(a.output))
            .then_some(("Table 1 of the paper (Fig. 9b)", &plot::TABLE1_FRF_HZ[..]));
        written = plot::bode(
            &plot::stem_of(file),
            &plot::Bode {
                title: format!("Frequency response {} -> {}", h.input, h.output),
                f_hz: &h.f_hz,
                magnitude: &h.magnitude,
                phase_deg: &h.phase_deg,
                peaks: &h.peaks,
                reference,
            },
        )?;
    }
    if a.json {
        return serde_json::to_string(&h).map_err(|e| e.to_string());
    }
    let mut s = format!(
        "FRF {} -> {}, {} to {} Hz: {} resonance peaks\n    f [Hz]        |H|\n",
        h.input,
        h.output,
        a.from,
        a.to,
        h.peaks.len()
    );
    for (f, m) in &h.peaks {
        s.push_str(&format!("{f:10.4} {m:12.5e}\n"));
    }
    for p in written {
        s.push_str(&format!("wrote {}\n", p.display()));
    }
    Ok(s.trim_end().to_string())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Package {
            output,
            require_portable,
            host_only,
        } => {
            let portability = match (require_portable, host_only) {
                (true, _) => binaries::Portability::Required,
                (false, true) => binaries::Portability::HostOnly,
                (false, false) => binaries::Portability::IfInstalled,
            };
            package::package_with(&output, portability)
        }
        .map(|paths| {
            for path in paths {
                println!("wrote {path}");
            }
        }),
        Command::Run(args) => run::run(&args),
        Command::Identify(args) => identify::main(&args),
        Command::FastestMove(args) => fastest::main(&args),
        Command::Web { out } => web::page_files()
            .and_then(|files| web::write(&files, &package::root().join(out)))
            .map(|paths| {
                for p in paths {
                    println!("wrote {}", p.display());
                }
            }),
        Command::Ssp { out } => ecosystem::ssp::write(&package::root().join(out)).map(|paths| {
            for p in paths {
                println!("wrote {}", p.display());
            }
        }),
        Command::DocFigures { fmu, out } => {
            let root = package::root();
            docpage::copy_figures(&root.join(fmu), &root.join(out)).map(|paths| {
                for p in paths {
                    println!("wrote {}", p.display());
                }
            })
        }
        Command::Validate { check } => validate::run(&package::root(), check).map(|paths| {
            let verb = if check { "checked" } else { "wrote" };
            paths
                .iter()
                .for_each(|p| println!("{verb} {}", p.display()));
        }),
        Command::Docs { check, root, list } => {
            docs::run(&root.unwrap_or_else(package::root), check, list)
                .map(|lines| lines.iter().for_each(|l| println!("{l}")))
        }
        Command::SourceHash => {
            println!("{}", hydraulic_slewing_plate::SOURCE_HASH);
            Ok(())
        }
        Command::Presets { json } => {
            println!("{}", presets_text(json));
            Ok(())
        }
        Command::Linearize {
            json: _,
            as_integrated,
            model,
        } => linearize(&model, as_integrated).map(|s| println!("{s}")),
        Command::Graph { model } => graph(&model).map(|s| println!("{s}")),
        Command::Info { json, model } => model_info(&model, json).map(|s| println!("{s}")),
        Command::Modes {
            json: _,
            plot,
            count,
            model,
        } => modes(&model, plot.as_deref(), count).map(|s| println!("{s}")),
        Command::Frf {
            input,
            output,
            from,
            to,
            points,
            json,
            plot,
            model,
        } => frf(
            &FrfArgs {
                input: &input,
                output: &output,
                from,
                to,
                points,
                json,
                plot: plot.as_deref(),
            },
            &model,
        )
        .map(|s| println!("{s}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hsp: error: {e}");
            ExitCode::FAILURE
        }
    }
}
