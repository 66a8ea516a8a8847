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

/// A benchmark configuration: a name, `--set` assignments, whether the model is linear, and
/// whether scipy runs it too (not for a configuration that differs from another only in how
/// the FMU steps: scipy's runs would be the same).
struct Config {
    name: &'static str,
    sets: &'static [&'static str],
    linear: bool,
    scipy: bool,
}

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
        scipy: true,
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
        scipy: true,
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
        scipy: false,
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
        scipy: false,
    },
    Config {
        name: "servo valve coupled (defaults)",
        sets: &["hydraulics.model=2", "hydraulics.motor_coupled=true"],
        linear: false,
        scipy: false,
    },
    Config {
        name: "servo valve coupled, the default experiment (r = 0)",
        sets: &["hydraulics.model=2", "hydraulics.motor_coupled=true", "r=0"],
        linear: false,
        scipy: false,
    },
    Config {
        name: "servo valve coupled, no drag",
        sets: &[
            "hydraulics.model=2",
            "hydraulics.motor_coupled=true",
            "plate.Cd=0",
        ],
        linear: false,
        scipy: false,
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
        scipy: false,
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
        scipy: false,
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
        scipy: false,
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
        scipy: false,
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
        scipy: true,
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
        scipy: true,
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
        scipy: true,
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
        scipy: false,
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

fn run_once(fmu: &Fmu, method: i32, sets: &[&str]) -> Result<Run, String> {
    let inst = fmu.instantiate("bench-fmu")?;
    inst.setup(Some(RTOL), 0.0, STOP)?;
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
    let first = run_once(fmu, method, sets)?;
    if first.wall > 2.0 {
        return Ok(first);
    }
    let mut runs = vec![
        first,
        run_once(fmu, method, sets)?,
        run_once(fmu, method, sets)?,
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

/// scipy's runs at equal accuracy: per method, the fastest run with error <= `target`.
fn scipy(linear: &Linear, target: f64) -> Result<Vec<(String, String)>, String> {
    // The linearisation's own layout (`hsp linearize`'s), and what the run adds.
    let mut input = linear.lin.to_json();
    input["u"] = serde_json::json!(linear.u);
    input["nominal"] = serde_json::json!(linear.nominal);
    input["stop"] = serde_json::json!(STOP);
    input["step"] = serde_json::json!(STEP);
    let path = std::env::temp_dir().join(format!("bench-fmu-{}.json", std::process::id()));
    std::fs::write(&path, input.to_string()).map_err(|e| e.to_string())?;
    let out = std::process::Command::new(PYTHON)
        .args(["bench/scipy_reference.py", "--linear"])
        .arg(&path)
        .output()
        .map_err(|e| format!("{PYTHON}: {e}"))?;
    let _ = std::fs::remove_file(&path);
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    let runs: serde_json::Value = serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())?;
    let num = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap_or(f64::NAN);
    let cell = |r: &serde_json::Value| {
        format!(
            "{:.1}x (rtol {:.0e}, err {:.1e})",
            STOP / num(r, "wall"),
            num(r, "rtol"),
            num(r, "err")
        )
    };
    let mut best = Vec::new();
    for method in ["Radau", "BDF", "LSODA"] {
        let all: Vec<&serde_json::Value> = runs[method].as_array().into_iter().flatten().collect();
        let fastest = all
            .iter()
            .filter(|r| num(r, "err") <= target)
            .min_by(|a, b| num(a, "wall").total_cmp(&num(b, "wall")));
        let text = match fastest {
            Some(r) => cell(r),
            // Not reached at any rtol down to 1e-10: the most accurate run, marked.
            None => match all
                .iter()
                .min_by(|a, b| num(a, "err").total_cmp(&num(b, "err")))
            {
                Some(r) => format!("not reached; best {}", cell(r)),
                None => "failed".to_string(),
            },
        };
        best.push((method.to_string(), text));
    }
    Ok(best)
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
         discretisation itself (one dense mat-vec per step). scipy: one `solve_ivp` call, the \
         fastest run with error at most Rodas5P's. Shared 2-core machine.\n\n\
         By default (`solver.dense_output = true`) Rodas5P's steps run past the communication \
         points while the inputs are held and the points are read from its dense output; the \
         rows \"steps ending on every point\" set `solver.dense_output = false`, as every run \
         did before. Radau5 always ends its steps on the points.\n"
    )
    .unwrap();
    writeln!(
        md,
        "| configuration | states | method | RTF | steps | f evals | Jacobians | LU | µs/step | error | exact RTF | scipy Radau | scipy BDF | scipy LSODA |"
    )
    .unwrap();
    writeln!(
        md,
        "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- | --- |"
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
        for &(method, name) in &methods {
            let r = match measure(&fmu, method, cfg.sets) {
                Ok(r) => r,
                Err(e) => {
                    eprintln!("{} {name}: {e}", cfg.name);
                    writeln!(md, "| {} | {states} | {name} | failed: {e} |", cfg.name).unwrap();
                    continue;
                }
            };
            let err = reference.as_ref().map(|(y, _)| delivered_error(&r.y, y));
            let scipy_cells = match (method, err, with_scipy && cfg.scipy) {
                (1, Some(e), true) => match scipy(&lin, e) {
                    Ok(cells) => cells.into_iter().map(|c| c.1).collect::<Vec<_>>(),
                    Err(e) => {
                        eprintln!("scipy: {e}");
                        vec!["failed".into(); 3]
                    }
                },
                _ => vec!["".into(); 3],
            };
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
    if let Some(dir) = std::path::Path::new(&out).parent() {
        std::fs::create_dir_all(dir).expect("create output directory");
    }
    std::fs::write(&out, md).expect("write the report");
    eprintln!("wrote {out}");
}
