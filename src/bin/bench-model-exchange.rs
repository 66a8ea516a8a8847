//! Cost of a Model Exchange evaluation through the FMU's C ABI, FMUs side by side. Not a test.
//!
//! ```text
//! cargo run --release --bin hsp -- package                 # build fmu/HydraulicSlewingPlate.fmu
//! cargo run --release --bin bench-model-exchange           # writes bench/model_exchange.md
//! cargo run --release --bin bench-model-exchange -- --fmu OLD.fmu --fmu NEW.fmu --rounds 5
//! ```
//!
//! An importer's solver in Model Exchange calls, at every stage of every step,
//! `fmi2SetTime`, `fmi2SetContinuousStates` and `fmi2GetDerivatives`, and reads a few outputs
//! with `fmi2GetReal` at its communication points. This benchmark makes those calls along a real
//! trajectory: the states of the default experiment (the complete system's 30 deg move, rtol
//! 1e-6), recorded every 5 ms over its 6 s by a co-simulation instance of the last FMU given
//! ([`POINTS`] points). At each point a Model Exchange instance of each FMU is evaluated
//! [`STAGES`] times (an 8-stage Rosenbrock step's count; the states are set anew each time, so
//! each is a full evaluation) and then `y_pot` and `w_tip` are read, as a recorder does.
//!
//! Each round runs every FMU once over all the points, the FMUs interleaved; the figure is the
//! calling thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`) of the whole loop per evaluation, in µs,
//! the median over `--rounds` (default 5) with the range, and the ratio of each FMU's median to
//! the first FMU's. With one FMU (the default, `fmu/HydraulicSlewingPlate.fmu`) it reports that
//! one alone. The table goes to `--out` (default `bench/model_exchange.md`; `-` prints it only)
//! with the timing block's first line: the command, the date and the load.

#[allow(dead_code)]
#[path = "hsp/loader.rs"]
mod loader;
#[path = "bench-common/machine.rs"]
mod machine;
#[path = "bench-common/measure.rs"]
mod measure;

use std::fmt::Write as _;
use std::os::raw::c_int;

use hydraulic_slewing_plate::fmi2::ffi::{Fmi2Component, Fmi2EventInfo, Fmi2Status};
use hydraulic_slewing_plate::model::variables::{vr, CONTINUOUS_STATES, VARIABLES};
use loader::{check, Fmu};
use measure::{median_range, now};

/// Communication points of the recorded trajectory: the default experiment's 6 s at 5 ms.
const POINTS: usize = 1200;
/// Its communication step, s.
const STEP: f64 = 5e-3;
/// Evaluations per point.
const STAGES: usize = 8;

type SetTime = unsafe extern "C" fn(Fmi2Component, f64) -> Fmi2Status;
type SetStates = unsafe extern "C" fn(Fmi2Component, *const f64, usize) -> Fmi2Status;
type GetDerivatives = unsafe extern "C" fn(Fmi2Component, *mut f64, usize) -> Fmi2Status;
type Simple = unsafe extern "C" fn(Fmi2Component) -> Fmi2Status;
type NewDiscreteStates = unsafe extern "C" fn(Fmi2Component, *mut Fmi2EventInfo) -> Fmi2Status;

/// The value references of the declared continuous states.
fn state_vrs() -> Vec<u32> {
    CONTINUOUS_STATES
        .iter()
        .map(|&(x, _)| VARIABLES[x].value_reference)
        .collect()
}

/// The states of the default experiment at its communication points, from a co-simulation
/// instance of `fmu`.
fn trajectory(fmu: &Fmu) -> Result<Vec<Vec<f64>>, String> {
    let inst = fmu.instantiate("bench-model-exchange-trajectory")?;
    inst.setup(None, 0.0, POINTS as f64 * STEP)?;
    inst.enter_initialization()?;
    inst.exit_initialization()?;
    let vrs = state_vrs();
    let mut points = vec![inst.get_reals(&vrs)?];
    for k in 0..POINTS - 1 {
        inst.do_step(k as f64 * STEP, STEP)?;
        points.push(inst.get_reals(&vrs)?);
    }
    inst.terminate()?;
    Ok(points)
}

/// One round of `fmu`: the thread CPU time per evaluation, µs.
fn round(fmu: &Fmu, points: &[Vec<f64>]) -> Result<f64, String> {
    // SAFETY: the FMI 2.0 functions of these names have these signatures.
    let (set_time, set_states, get_derivatives, enter_ct, new_discrete) = unsafe {
        (
            fmu.symbol::<SetTime>("fmi2SetTime")?,
            fmu.symbol::<SetStates>("fmi2SetContinuousStates")?,
            fmu.symbol::<GetDerivatives>("fmi2GetDerivatives")?,
            fmu.symbol::<Simple>("fmi2EnterContinuousTimeMode")?,
            fmu.symbol::<NewDiscreteStates>("fmi2NewDiscreteStates")?,
        )
    };
    let inst = fmu.instantiate_model_exchange("bench-model-exchange")?;
    let c = inst.component();
    inst.setup(None, 0.0, POINTS as f64 * STEP)?;
    inst.enter_initialization()?;
    inst.exit_initialization()?;
    let mut info = Fmi2EventInfo::default();
    // SAFETY: functions of the loaded FMU, its live instance, arguments that outlive the calls.
    unsafe {
        check(new_discrete(c, &mut info), "fmi2NewDiscreteStates")?;
        check(enter_ct(c), "fmi2EnterContinuousTimeMode")?;
    }
    let n = CONTINUOUS_STATES.len();
    let mut dx = vec![0.0; n];
    let mut y = [0.0; 2];
    let mut failed: c_int = 0;
    let start = now(libc::CLOCK_THREAD_CPUTIME_ID);
    for (k, x) in points.iter().enumerate() {
        // SAFETY: as above; `x` and `dx` hold n values.
        unsafe {
            failed |= (set_time(c, k as f64 * STEP) > Fmi2Status::Warning) as c_int;
            for _ in 0..STAGES {
                failed |= (set_states(c, x.as_ptr(), n) > Fmi2Status::Warning) as c_int;
                failed |= (get_derivatives(c, dx.as_mut_ptr(), n) > Fmi2Status::Warning) as c_int;
            }
        }
        inst.get_reals_into(&[vr::Y_POT, vr::W_TIP], &mut y)?;
    }
    let elapsed = now(libc::CLOCK_THREAD_CPUTIME_ID) - start;
    if failed != 0 {
        return Err("a Model Exchange call failed".into());
    }
    Ok(elapsed as f64 / 1e3 / (points.len() * STAGES) as f64)
}

fn main() {
    if let Err(e) = run() {
        eprintln!("bench-model-exchange: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let mut paths: Vec<String> = Vec::new();
    let mut rounds = 5usize;
    let mut out = "bench/model_exchange.md".to_string();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |what: &str| args.next().ok_or(format!("{a} needs {what}"));
        match a.as_str() {
            "--fmu" => paths.push(value("a path")?),
            "--rounds" => {
                rounds = value("a number")?
                    .parse()
                    .map_err(|e| format!("--rounds: {e}"))?
            }
            "--out" => out = value("a path or -")?,
            _ => return Err(format!("unknown argument {a}")),
        }
    }
    if paths.is_empty() {
        paths.push("fmu/HydraulicSlewingPlate.fmu".into());
    }
    if rounds == 0 {
        return Err("--rounds must be at least 1".into());
    }
    let load_start = machine::load();
    let fmus = paths
        .iter()
        .map(|p| Fmu::load(std::path::Path::new(p)))
        .collect::<Result<Vec<_>, _>>()?;
    let points = trajectory(fmus.last().expect("one FMU at least"))?;
    let mut times = vec![Vec::new(); fmus.len()];
    for r in 0..rounds {
        for (i, fmu) in fmus.iter().enumerate() {
            let t = round(fmu, &points)?;
            eprintln!("round {}: {}: {t:.3} µs per evaluation", r + 1, paths[i]);
            times[i].push(t);
        }
    }
    let load_end = machine::load();
    let mut table = String::new();
    writeln!(
        table,
        "Made by `{}` on {}, load {load_start} at the start and {load_end} at the end.\n",
        machine::command("bench-model-exchange"),
        machine::today()
    )
    .unwrap();
    writeln!(
        table,
        "| FMU | µs per evaluation | against the first |\n| --- | ---: | ---: |"
    )
    .unwrap();
    let first = median_range(&times[0]).0;
    for (path, t) in paths.iter().zip(&times) {
        let (m, lo, hi) = median_range(t);
        writeln!(
            table,
            "| `{path}` | {m:.2} ({lo:.2}–{hi:.2}) | {:.2}× |",
            m / first
        )
        .unwrap();
    }
    let text = format!(
        "# Model Exchange: the cost of an evaluation\n\n\
         Written by `cargo run --release --bin bench-model-exchange` (the method is in that \
         file's header): the calling thread's CPU time per `fmi2SetContinuousStates` + \
         `fmi2GetDerivatives`, {STAGES} evaluations at each of the default experiment's {POINTS} \
         points (5 ms apart) and `y_pot`, `w_tip` read at each point, the median over {rounds} \
         interleaved rounds with the range.\n\n\
         <!-- hsp timing: model-exchange -->\n{table}<!-- /hsp timing: model-exchange -->\n"
    );
    print!("{text}");
    if out != "-" {
        std::fs::write(&out, &text).map_err(|e| format!("{out}: {e}"))?;
    }
    Ok(())
}
