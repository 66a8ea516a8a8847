//! `hsp`: the project's command-line tool.
//!
//! - `hsp package`: builds the release library and writes `fmu/HydraulicSlewingPlate.fmu`.
//! - `hsp run`: builds the FMU if needed, loads it through its C ABI, runs the default experiment
//!   (a step in the reference `r`), prints a summary and writes the results as CSV.
//! - `hsp linearize --json [--set NAME=VALUE ...]`: A, B, C, D of the assembled model at rest.
//! - `hsp graph [--set ...]`: the model's bond graph as Graphviz DOT, with causal strokes.

mod loader;
mod package;
mod run;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use hydraulic_slewing_plate::fmi2::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::{bond_graph, Assembled};
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
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

#[derive(Subcommand)]
enum Command {
    /// Build the release library and package fmu/HydraulicSlewingPlate.fmu
    Package {
        /// Where to write the FMU
        #[arg(long, default_value = package::DEFAULT_FMU)]
        output: String,
    },
    /// Run the default experiment through the FMU's C ABI and summarise it
    Run(run::RunArgs),
    /// Linearise the assembled model at rest: A, B, C, D
    Linearize {
        /// Print JSON (the only format)
        #[arg(long)]
        json: bool,
        /// Set a parameter, NAME=VALUE (repeatable); names are the FMU's variable names
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<String>,
    },
    /// Print the model's bond graph as Graphviz DOT
    Graph {
        #[arg(long = "set", value_name = "NAME=VALUE")]
        set: Vec<String>,
    },
}

/// The FMU's start values with `--set` applied.
fn values_with(sets: &[String]) -> Result<Values, String> {
    let mut values = Values::from_start(&VARIABLES);
    for s in sets {
        let (name, value) = s
            .split_once('=')
            .ok_or_else(|| format!("--set '{s}': expected NAME=VALUE"))?;
        set_by_name(&mut values, name.trim(), value.trim())?;
    }
    Ok(values)
}

fn linearize(sets: &[String]) -> Result<String, String> {
    let values = values_with(sets)?;
    let parameters = Parameters::from_values(&values, &Experiment::default())?;
    let system = Assembled::new(&parameters)?;
    let x = system.initial_state();
    let lin = system.compiled().linearize(&x, system.inputs());
    let rows = |m: &nalgebra::DMatrix<f64>| -> Vec<Vec<f64>> {
        (0..m.nrows())
            .map(|i| m.row(i).iter().copied().collect())
            .collect()
    };
    let json = serde_json::json!({
        "states": lin.state_names,
        "inputs": lin.input_names,
        "outputs": lin.output_names,
        "A": rows(&lin.a),
        "B": rows(&lin.b),
        "C": rows(&lin.c),
        "D": rows(&lin.d),
    });
    Ok(json.to_string())
}

fn graph(sets: &[String]) -> Result<String, String> {
    let values = values_with(sets)?;
    let parameters = Parameters::from_values(&values, &Experiment::default())?;
    Ok(bond_graph(&parameters)?.to_dot())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Package { output } => package::package(&output).map(|path| {
            println!("wrote {path}");
        }),
        Command::Run(args) => run::run(&args),
        Command::Linearize { json: _, set } => linearize(&set).map(|s| println!("{s}")),
        Command::Graph { set } => graph(&set).map(|s| println!("{s}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hsp: error: {e}");
            ExitCode::FAILURE
        }
    }
}
