//! Speed benchmark of the FMU through its C ABI. Not a test.
//!
//! ```text
//! cargo run --release --bin hsp -- package           # build fmu/HydraulicSlewingPlate.fmu
//! cargo run --release --bin bench-fmu                # writes bench/fmu_speed.md
//! cargo run --release --bin bench-fmu -- --only "LOES coupled 3x5" --method Radau5 --no-scipy
//! ```
//!
//! Loads the packaged FMU as an importer does, and for each configuration and both methods runs
//! 10 s at 1 ms communication steps (10 000 `fmi2DoStep` calls) with rtol 1e-6 (through
//! `fmi2SetupExperiment`) after a unit step of the reference `r` at t = 0 (none in a
//! configuration that sets `r=0`: the default experiment's own move). It reports the
//! real-time factor (simulated time over wall time, median of 3 runs when a run takes under 2 s),
//! the solver's counters (accepted steps, f evaluations, Jacobians, LU factorisations), the wall
//! time per communication step (the `fmi2DoStep` and the `fmi2GetReal` of the two outputs it
//! records, as an importer's recorder does: the FMU computes some outputs only when they are
//! read), and the delivered error.
//!
//! **Delivered error.** For the configurations that are linear (the LOES with the plate) the
//! exact solution at the communication points is the exact discretisation
//! `x_{k+1} = expm(A h) x_k + ∫_0^h expm(A s) ds B u` of the model linearised by
//! [`CompiledModel::linearize`](hydraulic_slewing_plate::bond_graph::CompiledModel::linearize)
//! (what `hsp linearize` prints; exact for a linear model). The error is the largest deviation
//! of `y_pot` and `w_tip` over the run, relative to the largest magnitude of that output.
//! The time of that exact discretisation itself (one dense mat-vec per step, compiled) is the
//! floor reported in the last column.
//!
//! **scipy side by side** (unless `--no-scipy`): `bench/scipy_reference.py --linear` gets A, B,
//! the output rows and the state nominals, integrates the same 10 s with one `solve_ivp` call per
//! method (Radau, BDF, LSODA; constant Jacobian A) over a range of rtol (atol = 1e-2 rtol times
//! each state's nominal value, as the FMU does), measures each run's delivered error the same way
//! and its wall time. The table shows, per method, the fastest run whose error is at most the
//! FMU's (Rodas5P's) error: "equal accuracy".

#[allow(dead_code)]
#[path = "hsp/loader.rs"]
mod loader;
#[path = "bench-common/machine.rs"]
mod machine;

use std::fmt::Write as _;
use std::time::Instant;

use hydraulic_slewing_plate::bond_graph::{ExactDiscretisation, Linearization};
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::{vr, VARIABLES};
use loader::Fmu;
use nalgebra::{DMatrix, DVector};

const STOP: f64 = 10.0;
const STEP: f64 = 1e-3;
const RTOL: f64 = 1e-6;
/// The project's virtual environment (made by `tests/setup.sh`), which has scipy.
const PYTHON: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/.venv/bin/python");

/// A benchmark configuration: a name, `--set` assignments (after `r` = 1, so a set of `r`
/// wins), whether the model is linear, and how scipy runs it too (not for a configuration that
/// differs from another only in how the FMU steps: scipy's runs would be the same).
struct Config {
    name: &'static str,
    sets: &'static [&'static str],
    linear: bool,
    scipy: Scipy,
}

/// How the competitors run a configuration.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Scipy {
    /// Not at all.
    No,
    /// scipy on the exported linear model (`bench/scipy_reference.py --linear`), the error
    /// against the exact discretisation.
    Linear,
    /// scipy and CVODE on the FMU's Model Exchange interface
    /// (`bench/model_exchange_solvers.py`), the error against the FMU at rtol [`REFERENCE_RTOL`].
    ModelExchange,
}

/// The rtol of the reference runs of the nonlinear configurations: Radau IIA (the reference)
/// and Rodas5P (its check).
const REFERENCE_RTOL: f64 = 1e-10;

const CONFIGS: &[Config] = &[
    Config {
        name: "LOES motor alone (preset loes-motor)",
        sets: &[
            "hydraulics.model=1",
            "controller.saturation=false",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
            "hydraulics.motor_coupled=false",
        ],
        linear: true,
        scipy: Scipy::Linear,
    },
    Config {
        name: "LOES coupled 3x5",
        sets: &[
            "hydraulics.model=1",
            "controller.saturation=false",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
            "hydraulics.motor_coupled=true",
        ],
        linear: true,
        scipy: Scipy::Linear,
    },
    Config {
        name: "LOES coupled 3x5, steps ending on every point",
        sets: &[
            "hydraulics.model=1",
            "controller.saturation=false",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
            "hydraulics.motor_coupled=true",
            "solver.dense_output=false",
        ],
        linear: true,
        scipy: Scipy::No,
    },
    Config {
        name: "servo valve uncoupled",
        sets: &[
            "hydraulics.model=2",
            "hydraulics.motor_coupled=false",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
        ],
        linear: false,
        scipy: Scipy::No,
    },
    Config {
        name: "servo valve coupled (defaults)",
        sets: &["hydraulics.model=2", "hydraulics.motor_coupled=true"],
        linear: false,
        scipy: Scipy::ModelExchange,
    },
    Config {
        name: "defaults, the default experiment's input (r = 0)",
        sets: &["hydraulics.model=2", "hydraulics.motor_coupled=true", "r=0"],
        linear: false,
        scipy: Scipy::ModelExchange,
    },
    Config {
        name: "servo valve coupled, no drag",
        sets: &[
            "hydraulics.model=2",
            "hydraulics.motor_coupled=true",
            "plate.Cd=0",
        ],
        linear: false,
        scipy: Scipy::No,
    },
    Config {
        name: "servo valve coupled, paper plate, no move, no drag",
        sets: &[
            "hydraulics.model=2",
            "hydraulics.motor_coupled=true",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
        ],
        linear: false,
        scipy: Scipy::No,
    },
    Config {
        name: "servo valve coupled, identified motor (D_m 8.04e-5)",
        sets: &[
            "hydraulics.model=2",
            "hydraulics.motor_coupled=true",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
            "servo_valve.D_m=8.04e-5",
            "servo_valve.V_1=1.5e-4",
            "servo_valve.w=0.015707963267948967",
            "servo_valve.I_m=0.0025",
        ],
        linear: false,
        scipy: Scipy::No,
    },
    Config {
        name: "servo valve coupled, consistent plate, no move, no drag",
        sets: &[
            "hydraulics.model=2",
            "hydraulics.motor_coupled=true",
            "reference.angle=0",
            "plate.Cd=0",
        ],
        linear: false,
        scipy: Scipy::No,
    },
    Config {
        name: "servo valve coupled, steps ending on every point",
        sets: &[
            "hydraulics.model=2",
            "hydraulics.motor_coupled=true",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
            "solver.dense_output=false",
        ],
        linear: false,
        scipy: Scipy::No,
    },
    Config {
        name: "LOES coupled 6x6",
        sets: &[
            "hydraulics.model=1",
            "controller.saturation=false",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
            "hydraulics.motor_coupled=true",
            "plate.N=6",
            "plate.M=6",
        ],
        linear: true,
        scipy: Scipy::Linear,
    },
    Config {
        name: "LOES coupled 12x12",
        sets: &[
            "hydraulics.model=1",
            "controller.saturation=false",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
            "hydraulics.motor_coupled=true",
            "plate.N=12",
            "plate.M=12",
        ],
        linear: true,
        scipy: Scipy::Linear,
    },
    Config {
        name: "LOES coupled 20x20",
        sets: &[
            "hydraulics.model=1",
            "controller.saturation=false",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=0",
            "plate.zeta=0.01",
            "hydraulics.motor_coupled=true",
            "plate.N=20",
            "plate.M=20",
        ],
        linear: true,
        scipy: Scipy::Linear,
    },
    Config {
        name: "LOES coupled 20x20 with drag",
        sets: &[
            "hydraulics.model=1",
            "controller.saturation=false",
            "hydraulics.motor_coupled=true",
            "plate.formulation=1",
            "reference.angle=0",
            "plate.Cd=1.2",
            "plate.zeta=0.01",
            "plate.N=20",
            "plate.M=20",
        ],
        linear: false,
        scipy: Scipy::No,
    },
];

/// The outputs whose delivered error is measured.
const ERR_OUTPUTS: [(&str, u32); 2] = [("y_pot", vr::Y_POT), ("w_tip", vr::W_TIP)];

struct Run {
    wall: f64,
    stats: Vec<i32>,
    /// Trajectories of [`ERR_OUTPUTS`] at the communication points 1..=n.
    y: Vec<[f64; 2]>,
}

fn run_once(fmu: &Fmu, method: i32, sets: &[&str], rtol: f64) -> Result<Run, String> {
    let inst = fmu.instantiate("bench-fmu")?;
    inst.setup(Some(rtol), 0.0, STOP)?;
    inst.set_integer(vr::SOLVER_METHOD, method)?;
    // The unit step of r first, so that a configuration's `r=0` takes it back.
    inst.set_real(vr::R, 1.0)?;
    for s in sets {
        inst.set_from_text(s)?;
    }
    inst.enter_initialization()?;
    inst.exit_initialization()?;
    let n = (STOP / STEP).round() as usize;
    let refs = [ERR_OUTPUTS[0].1, ERR_OUTPUTS[1].1];
    let mut y = Vec::with_capacity(n);
    let mut wall = 0.0;
    for k in 0..n {
        let t = k as f64 * STEP;
        // Timed: the step and the reading of the outputs an importer records (the FMU computes
        // some outputs only when they are read).
        let start = Instant::now();
        inst.do_step(t, (k + 1) as f64 * STEP - t)?;
        let mut v = [0.0; 2];
        inst.get_reals_into(&refs, &mut v)?;
        wall += start.elapsed().as_secs_f64();
        y.push([v[0], v[1]]);
    }
    let stats = inst.solver_stats()?;
    inst.terminate()?;
    Ok(Run { wall, stats, y })
}

/// The median run (3 runs if one takes under 2 s, else 1).
fn measure(fmu: &Fmu, method: i32, sets: &[&str]) -> Result<Run, String> {
    let first = run_once(fmu, method, sets, RTOL)?;
    if first.wall > 2.0 {
        return Ok(first);
    }
    let mut runs = vec![
        first,
        run_once(fmu, method, sets, RTOL)?,
        run_once(fmu, method, sets, RTOL)?,
    ];
    runs.sort_by(|a, b| a.wall.total_cmp(&b.wall));
    Ok(runs.swap_remove(1))
}

/// The linearised model of a configuration (exact for the linear ones) at its start state.
struct Linear {
    /// Its outputs cut to [`ERR_OUTPUTS`] (the rows of C and D, the names).
    lin: Linearization,
    /// The input held over the run: `r` = 1, the others 0.
    u: Vec<f64>,
    /// The states' nominal values.
    nominal: Vec<f64>,
}

fn linear_model(sets: &[&str]) -> Result<Linear, String> {
    let mut values = Values::from_start(&VARIABLES);
    for s in sets {
        let (name, value) = s.split_once('=').ok_or("NAME=VALUE")?;
        set_by_name(&mut values, name, value)?;
    }
    let parameters = Parameters::from_values(&values, &Experiment::default())?;
    let system = Assembled::new(&parameters)?;
    let x0 = system.initial_state();
    let mut lin = system.compiled().linearize(&x0, system.inputs());
    let rows: Vec<usize> = ERR_OUTPUTS
        .iter()
        .map(|(name, _)| lin.output_names.iter().position(|o| o == name).unwrap())
        .collect();
    let c = DMatrix::from_fn(rows.len(), lin.a.ncols(), |i, j| lin.c[(rows[i], j)]);
    let d = DMatrix::from_fn(rows.len(), lin.b.ncols(), |i, j| lin.d[(rows[i], j)]);
    let u = lin
        .input_names
        .iter()
        .map(|n| if n == "r" { 1.0 } else { 0.0 })
        .collect();
    (lin.c, lin.d) = (c, d);
    lin.output_names = ERR_OUTPUTS.iter().map(|(n, _)| n.to_string()).collect();
    Ok(Linear {
        lin,
        u,
        nominal: system.nominal().to_vec(),
    })
}

/// The exact discretisation: the output trajectories at 1..=n communication points and the
/// wall time per step of the propagation (one dense mat-vec).
fn exact(linear: &Linear, n: usize) -> (Vec<[f64; 2]>, f64) {
    let lin = &linear.lin;
    let disc = ExactDiscretisation::new(&lin.a, &lin.b, STEP);
    let gu = disc.input_term(&linear.u);
    let du = &lin.d * DVector::from_column_slice(&linear.u);
    let mut x = DVector::from_column_slice(&lin.x0);
    let mut x1 = DVector::zeros(x.len());
    let mut y = Vec::with_capacity(n);
    let start = Instant::now();
    for _ in 0..n {
        disc.step(&x, &gu, &mut x1);
        std::mem::swap(&mut x, &mut x1);
        let yo = &lin.c * &x + &du;
        y.push([yo[0], yo[1]]);
    }
    let wall = start.elapsed().as_secs_f64();
    (y, wall / n as f64)
}

/// Largest deviation of each output relative to the largest magnitude of the exact output
/// (outputs that stay zero are left out); the worst of them.
fn delivered_error(y: &[[f64; 2]], reference: &[[f64; 2]]) -> f64 {
    let mut worst: f64 = 0.0;
    for o in 0..2 {
        let scale = reference.iter().fold(0.0_f64, |m, r| m.max(r[o].abs()));
        if scale == 0.0 {
            continue;
        }
        let dev = y
            .iter()
            .zip(reference)
            .fold(0.0_f64, |m, (a, b)| m.max((a[o] - b[o]).abs()));
        worst = worst.max(dev / scale);
    }
    worst
}

/// The competitors' methods, in the table's order (CVODE on Model Exchange only).
const COMPETITORS: [&str; 4] = ["Radau", "BDF", "LSODA", "CVODE"];

/// Runs `script` (with `flags` before the input file) on `input`, written to a temporary file,
/// and returns what it prints: the runs of each method (rtol, err, wall, ...).
fn python(
    script: &str,
    flags: &[&str],
    input: &serde_json::Value,
) -> Result<serde_json::Value, String> {
    let path = std::env::temp_dir().join(format!("bench-fmu-{}.json", std::process::id()));
    std::fs::write(&path, input.to_string()).map_err(|e| e.to_string())?;
    let out = std::process::Command::new(PYTHON)
        .arg(script)
        .args(flags)
        .arg(&path)
        .stderr(std::process::Stdio::inherit())
        .output()
        .map_err(|e| format!("{PYTHON}: {e}"))?;
    let _ = std::fs::remove_file(&path);
    if !out.status.success() {
        return Err(format!("{script} failed"));
    }
    serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())
}

fn num(r: &serde_json::Value, k: &str) -> f64 {
    r[k].as_f64().unwrap_or(f64::NAN)
}

/// Per method of [`COMPETITORS`], the fastest of its `runs` with error <= `target` ("equal
/// accuracy"), or where none reached it (at any rtol down to 1e-10) the most accurate, marked;
/// `None` for a method that did not run.
fn equal_accuracy(runs: &serde_json::Value, target: f64) -> Vec<Option<(bool, serde_json::Value)>> {
    COMPETITORS
        .iter()
        .map(|method| {
            let all: Vec<&serde_json::Value> = runs.get(method)?.as_array()?.iter().collect();
            let fastest = all
                .iter()
                .filter(|r| num(r, "err") <= target)
                .min_by(|a, b| num(a, "wall").total_cmp(&num(b, "wall")));
            match fastest {
                Some(r) => Some((true, (*r).clone())),
                None => all
                    .iter()
                    .min_by(|a, b| num(a, "err").total_cmp(&num(b, "err")))
                    .map(|r| (false, (*r).clone())),
            }
        })
        .collect()
}

/// The table's cell of a competitor's run: "12.3x (rtol 1e-7, err 2.1e-8, 1234 steps)".
fn cell(run: &Option<(bool, serde_json::Value)>, ran: bool) -> String {
    let Some((reached, r)) = run else {
        return if ran { "failed".into() } else { String::new() };
    };
    let steps = r["steps"]
        .as_u64()
        .map_or(String::new(), |s| format!(", {s} steps"));
    format!(
        "{}{:.1}x (rtol {:.0e}, err {:.1e}{steps})",
        if *reached { "" } else { "not reached; best " },
        STOP / num(r, "wall"),
        num(r, "rtol"),
        num(r, "err")
    )
}

/// scipy's runs of a linear configuration (its exported matrices), at equal accuracy.
fn scipy_linear(linear: &Linear, target: f64) -> Result<Vec<String>, String> {
    // The linearisation's own layout (`hsp linearize`'s), and what the run adds.
    let mut input = linear.lin.to_json();
    input["u"] = serde_json::json!(linear.u);
    input["nominal"] = serde_json::json!(linear.nominal);
    input["stop"] = serde_json::json!(STOP);
    input["step"] = serde_json::json!(STEP);
    let runs = python("bench/scipy_reference.py", &["--linear"], &input)?;
    Ok(equal_accuracy(&runs, target)
        .iter()
        .zip(COMPETITORS)
        .map(|(r, m)| cell(r, m != "CVODE"))
        .collect())
}

/// A nonlinear configuration's reference: the outputs of Radau IIA at [`REFERENCE_RTOL`], and
/// the error of Rodas5P's run at the same rtol against it (the reference's own uncertainty).
fn reference_run(fmu: &Fmu, sets: &[&str]) -> Result<(Vec<[f64; 2]>, f64), String> {
    let reference = run_once(fmu, 2, sets, REFERENCE_RTOL)?.y;
    let check = run_once(fmu, 1, sets, REFERENCE_RTOL)?.y;
    let uncertainty = delivered_error(&check, &reference);
    Ok((reference, uncertainty))
}

/// scipy and CVODE on the FMU's Model Exchange interface (`bench/model_exchange_solvers.py`), at
/// equal accuracy: the table's cells, the rows of the section on the interface, and its note
/// on the reference and the cost of a call.
fn model_exchange(
    fmu_path: &str,
    cfg: &Config,
    reference: &(Vec<[f64; 2]>, f64),
    fmu_row: (f64, f64),
) -> Result<(Vec<String>, Vec<String>, String), String> {
    let (target, fmu_rtf) = fmu_row;
    let input = serde_json::json!({
        "fmu": fmu_path,
        "sets": cfg.sets,
        "stop": STOP,
        "step": STEP,
        "outputs": ERR_OUTPUTS.map(|(name, _)| name),
        "reference": reference.0,
        "target": target,
    });
    let runs = python("bench/model_exchange_solvers.py", &[], &input)?;
    let best = equal_accuracy(&runs, target);
    let stopped = |method: &str| {
        runs["stopped"]
            .as_array()
            .is_some_and(|s| s.iter().any(|m| m == method))
    };
    let cells = best
        .iter()
        .zip(COMPETITORS)
        .map(|(r, method)| match r {
            Some((false, _)) if stopped(method) => {
                format!("stopped by a run over 60 s; {}", cell(r, true))
            }
            _ => cell(r, true),
        })
        .collect();
    let f_us = num(&runs, "f_us");
    let cs = &runs["cs_fmpy"];
    let mut lines = vec![
        format!(
            "| {} | FMU, Rodas5P through the C ABI (the table's row) | {RTOL:.0e} | {fmu_rtf:.1}x | | | | | {target:.1e} | |",
            cfg.name
        ),
        format!(
            "| {} | FMU, Rodas5P driven from Python through fmpy | {RTOL:.0e} | {:.1}x | | | | | {:.1e} | |",
            cfg.name,
            STOP / num(cs, "wall"),
            num(cs, "err")
        ),
    ];
    for (method, run) in COMPETITORS.iter().zip(&best) {
        let Some((reached, r)) = run else {
            lines.push(format!(
                "| {} | {method} | failed | | | | | | | |",
                cfg.name
            ));
            continue;
        };
        let share = num(r, "nfev") * f_us * 1e-6 / num(r, "wall");
        lines.push(format!(
            "| {} | {method}{} | {:.0e} | {:.1}x | {} | {} | {} | {} | {:.1e} | {:.0} % |",
            cfg.name,
            match (*reached, stopped(method)) {
                (true, _) => "",
                (false, true) =>
                    " (stopped by a run over 60 s before the target; its most accurate run)",
                (false, false) => " (target not reached; its most accurate run)",
            },
            num(r, "rtol"),
            STOP / num(r, "wall"),
            r["steps"],
            r["nfev"],
            r["njev"],
            r["nlu"],
            num(r, "err"),
            100.0 * share
        ));
    }
    let note = format!(
        "- \"{}\": the reference, Radau IIA at rtol {REFERENCE_RTOL:.0e}, and Rodas5P at the same \
         rtol differ by {:.1e}; one right-hand side through fmpy (`fmi2SetTime`, \
         `fmi2SetContinuousStates`, `fmi2GetDerivatives` from Python) took {f_us:.1} µs (the \
         least of 10 batches of 200 calls).",
        cfg.name, reference.1
    );
    Ok((cells, lines, note))
}

fn main() {
    let mut fmu_path = "fmu/HydraulicSlewingPlate.fmu".to_string();
    let mut out = "bench/fmu_speed.md".to_string();
    let mut only: Vec<String> = Vec::new();
    let mut with_scipy = true;
    let mut methods: Vec<(i32, &str)> = vec![(1, "Rodas5P"), (2, "Radau5")];
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--fmu" => fmu_path = args.next().expect("--fmu PATH"),
            "--out" => out = args.next().expect("--out PATH"),
            "--only" => only.push(args.next().expect("--only NAME")),
            "--no-scipy" => with_scipy = false,
            "--method" => {
                let name = args.next().expect("--method Rodas5P|Radau5");
                methods.retain(|&(_, m)| m.eq_ignore_ascii_case(&name));
            }
            other => {
                eprintln!(
                    "unknown argument '{other}' (use --fmu PATH, --out PATH, --only NAME, --method NAME, --no-scipy)"
                );
                std::process::exit(2);
            }
        }
    }
    if with_scipy && !std::path::Path::new(PYTHON).exists() {
        eprintln!(
            "{PYTHON} does not exist: `bash tests/setup.sh` makes the virtual environment with \
             scipy (or pass --no-scipy)"
        );
        std::process::exit(2);
    }
    let fmu = Fmu::load(std::path::Path::new(&fmu_path)).unwrap_or_else(|e| {
        eprintln!("{e} (build it with: cargo run --release --bin hsp -- package)");
        std::process::exit(1)
    });
    let n = (STOP / STEP).round() as usize;
    let label = std::path::Path::new(&out)
        .file_stem()
        .map_or("fmu-speed".into(), |s| {
            s.to_string_lossy().replace('_', "-")
        });
    let command = machine::command("bench-fmu");
    let mut me_lines: Vec<String> = Vec::new();
    let mut me_notes: Vec<String> = Vec::new();
    let mut md = String::new();
    writeln!(
        md,
        "# FMU speed\n\n`cargo run --release --bin bench-fmu`: {STOP} s at {STEP} s \
         communication steps (10 000 `fmi2DoStep` calls through the C ABI), rtol {RTOL:e} (atol \
         1e-8 of each state's nominal value), unit step of `r` at t = 0 (none with r = 0). RTF = real-time factor \
         (median of 3 runs if a run is under 2 s); µs/step = wall time per `fmi2DoStep` and the \
         `fmi2GetReal` of `y_pot` and `w_tip` after it; error = \
         largest deviation of `y_pot` and `w_tip` from the exact discretisation, relative to the \
         output's largest magnitude (linear configurations only); exact = RTF of the exact \
         discretisation itself (one dense mat-vec per step). scipy: one `solve_ivp` call on the \
         linear configurations, the fastest run with error at most Rodas5P's. Shared 2-core machine.\n\n\
         By default (`solver.dense_output = true`) Rodas5P's steps run past the communication \
         points while the inputs are held and the points are read from its dense output; the \
         rows \"steps ending on every point\" set `solver.dense_output = false`, as every run \
         did before. Radau5 always ends its steps on the points.\n\n\
         The complete default plant (\"servo valve coupled (defaults)\", and the same with the \
         default experiment's input, r = 0) is nonlinear: its error is against Radau IIA at \
         rtol {REFERENCE_RTOL:.0e}, and its competitors are scipy's `solve_ivp` methods and \
         SUNDIALS CVODE (fmpy's) on the FMU's Model Exchange interface \
         (`bench/model_exchange_solvers.py`, whose header gives the method), with the same \
         error and the same rule (the fastest run at most the FMU's error). The section \"On \
         the Model Exchange interface\" gives their counts and what Python costs them.\n\n\
         <!-- hsp timing: {label} -->\n\
         Made by `{command}` on {}, load {} at the start (`/proc/loadavg`, the 1-minute \
         average; the end's is below the tables).\n",
        machine::today(),
        machine::load()
    )
    .unwrap();
    writeln!(
        md,
        "| configuration | states | method | RTF | steps | f evals | Jacobians | LU | µs/step | error | exact RTF | scipy Radau | scipy BDF | scipy LSODA | CVODE (fmpy) |"
    )
    .unwrap();
    writeln!(
        md,
        "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- | --- | --- |"
    )
    .unwrap();
    for cfg in CONFIGS {
        if !only.is_empty() && !only.iter().any(|o| o == cfg.name) {
            continue;
        }
        let lin = match linear_model(cfg.sets) {
            Ok(l) => l,
            Err(e) => {
                eprintln!("{}: skipped ({e})", cfg.name);
                writeln!(md, "| {} | – | – | not supported: {e} |", cfg.name).unwrap();
                continue;
            }
        };
        let states = lin.lin.a.nrows();
        let reference = cfg.linear.then(|| exact(&lin, n));
        let me_reference = match (cfg.scipy, with_scipy) {
            (Scipy::ModelExchange, true) => match reference_run(&fmu, cfg.sets) {
                Ok(r) => Some(r),
                Err(e) => {
                    eprintln!("{}: the reference run failed: {e}", cfg.name);
                    None
                }
            },
            _ => None,
        };
        for &(method, name) in &methods {
            let r = match measure(&fmu, method, cfg.sets) {
                Ok(r) => r,
                Err(e) => {
                    eprintln!("{} {name}: {e}", cfg.name);
                    writeln!(md, "| {} | {states} | {name} | failed: {e} |", cfg.name).unwrap();
                    continue;
                }
            };
            let err = reference
                .as_ref()
                .or(me_reference.as_ref())
                .map(|(y, _)| delivered_error(&r.y, y));
            let mut scipy_cells = vec![String::new(); COMPETITORS.len()];
            match (method, err, cfg.scipy, &me_reference) {
                (1, Some(e), Scipy::Linear, _) if with_scipy => match scipy_linear(&lin, e) {
                    Ok(cells) => scipy_cells = cells,
                    Err(e) => eprintln!("scipy: {e}"),
                },
                (1, Some(e), Scipy::ModelExchange, Some(me)) => {
                    match model_exchange(&fmu_path, cfg, me, (e, STOP / r.wall)) {
                        Ok((cells, lines, note)) => {
                            scipy_cells = cells;
                            me_lines.extend(lines);
                            me_notes.push(note);
                        }
                        Err(e) => eprintln!("Model Exchange: {e}"),
                    }
                }
                _ => {}
            }
            let line = format!(
                "| {} | {states} | {name} | {:.1} | {} | {} | {} | {} | {:.1} | {} | {} | {} |",
                cfg.name,
                STOP / r.wall,
                r.stats[0],
                r.stats[2],
                r.stats[3],
                r.stats[4],
                r.wall / n as f64 * 1e6,
                err.map_or("–".into(), |e| format!("{e:.1e}")),
                match (&reference, method) {
                    (Some((_, t)), 1) => format!("{:.0}", STEP / t),
                    _ => "".into(),
                },
                scipy_cells.join(" | ")
            );
            println!("{line}");
            writeln!(md, "{line}").unwrap();
        }
    }
    if !me_lines.is_empty() {
        writeln!(
            md,
            "\n## On the Model Exchange interface\n\n\
             The FMU's row of the table, the FMU at the same rtol driven from Python (fmpy's \
             `FMU2Slave`: `fmi2DoStep` and `fmi2GetReal` at every point), and the competitors' \
             runs of the table (the fastest at most the FMU's error), with their counts (scipy: \
             Jacobians from `fmi2GetDirectionalDerivative`, LU factorisations; CVODE: \
             difference-quotient Jacobians, whose right-hand sides are in its f evals, and \
             linear-solver setups). \"f share\": the f evals times the cost of one right-hand \
             side through fmpy, over the run's time: about what the calls through Python take of it \
             (the cost measured apart, under the load of its moment).\n\n\
             | configuration | solver | rtol | RTF | steps | f evals | Jacobians | LU | error | f share |\n\
             | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
        )
        .unwrap();
        for line in &me_lines {
            writeln!(md, "{line}").unwrap();
        }
        writeln!(md).unwrap();
        for note in &me_notes {
            writeln!(md, "{note}").unwrap();
        }
    }
    writeln!(
        md,
        "\nLoad at the end: {} (`/proc/loadavg`, the 1-minute average).\n<!-- /hsp timing: {label} -->",
        machine::load()
    )
    .unwrap();
    if let Some(dir) = std::path::Path::new(&out).parent() {
        std::fs::create_dir_all(dir).expect("create output directory");
    }
    std::fs::write(&out, md).expect("write the report");
    eprintln!("wrote {out}");
}
