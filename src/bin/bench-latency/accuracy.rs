//! `bench-latency --accuracy`: what the real-time method's fixed step costs in accuracy, and
//! where it stops being stable. Writes `bench/realtime_accuracy.md`.
//!
//! Each run goes through the packaged FMU's FMI 2.0 entry points at a fixed communication step
//! and is compared, at every communication point, with the adaptive Rodas5P at rtol 1e-10 and
//! `solver.atol` 1e-12 run the same way (at the FMU's default tolerances tightened to rtol 1e-8
//! only, the reference's own error, 7.5e-8 of `p_load`'s range, hid the real-time method's on
//! the default experiment). The real-time runs keep the FMU's default tolerances, which only
//! scale their error estimate. The deviation of an output
//! is its largest difference over the run relative to its range in the reference run; the table
//! gives the largest over [`COMPARED`] and the output it comes from.
//!
//! Two scenarios, 6 s each: the default experiment (the complete system and its own 30 deg
//! minimum-jerk move, inputs untouched) and the closed loop of the latency benchmark (the
//! importer's proportional controller on `e_in` following a square wave of `r`, so the inputs
//! change at every step; there the two runs' inputs differ too, as each follows its own
//! outputs). The stability scan runs the default experiment with one fixed step per
//! communication step at ever longer communication steps.

use std::fmt::Write as _;

use hydraulic_slewing_plate::model::variables::vr;

use crate::loader::Fmu;
use crate::{reference, GAIN};

/// The outputs compared.
const COMPARED: [(&str, u32); 5] = [
    ("y_pot", vr::Y_POT),
    ("theta_motor", vr::THETA_MOTOR),
    ("theta_hub", vr::THETA_HUB),
    ("w_tip", vr::W_TIP),
    ("p_load", vr::P_LOAD),
];
const STOP: f64 = 6.0;
/// The real-time methods compared: `solver.method` and a name.
const REAL_TIME: [(i32, &str); 2] = [(3, "Rodas5P fixed"), (4, "ROS34PW2 fixed")];
const REFERENCE_RTOL: f64 = 1e-10;
/// `solver.atol` of the reference (a fraction of each state's nominal value).
const REFERENCE_ATOL: f64 = 1e-12;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Scenario {
    DefaultExperiment,
    ClosedLoop,
}

impl Scenario {
    fn name(self) -> &'static str {
        match self {
            Scenario::DefaultExperiment => "default experiment",
            Scenario::ClosedLoop => "closed loop (square wave)",
        }
    }
}

/// A run's outputs at the communication points and its largest error estimate; Err with the
/// FMU's message if a step failed.
struct Trajectory {
    y: Vec<[f64; 5]>,
    largest_estimate: f64,
}

fn simulate(
    fmu: &Fmu,
    scenario: Scenario,
    h: f64,
    method: Option<(i32, i32)>,
) -> Result<Trajectory, String> {
    let inst = fmu.instantiate("bench-latency-accuracy")?;
    match method {
        Some((method, substeps)) => {
            inst.setup(None, 0.0, STOP)?;
            inst.set_integer(vr::SOLVER_METHOD, method)?;
            inst.set_integer(vr::SOLVER_SUBSTEPS, substeps)?;
        }
        None => {
            inst.setup(Some(REFERENCE_RTOL), 0.0, STOP)?;
            inst.set_real(vr::SOLVER_ATOL, REFERENCE_ATOL)?;
        }
    }
    if scenario == Scenario::ClosedLoop {
        inst.set_boolean(vr::CONTROLLER_EXTERNAL, true)?;
    }
    inst.enter_initialization()?;
    inst.exit_initialization()?;
    let n = (STOP / h).round() as usize;
    let refs = COMPARED.map(|(_, r)| r);
    let mut y = Vec::with_capacity(n);
    let mut largest_estimate: f64 = 0.0;
    let mut v = [0.0; 5];
    for k in 0..n {
        let t = k as f64 * h;
        if scenario == Scenario::ClosedLoop {
            let y_pot = inst.get_reals(&[vr::Y_POT])?[0];
            inst.set_real(vr::E_IN, GAIN * (reference(t) - y_pot))?;
        }
        inst.do_step(t, h)?;
        inst.get_reals_into(&refs, &mut v)?;
        if v.iter().any(|x| !x.is_finite()) {
            return Err(format!("non-finite output at t = {}", t + h));
        }
        y.push(v);
        largest_estimate = largest_estimate.max(inst.get_reals(&[vr::SOLVER_ERROR_ESTIMATE])?[0]);
    }
    inst.terminate()?;
    Ok(Trajectory {
        y,
        largest_estimate,
    })
}

/// The largest deviation relative to the reference's range, and the output it is of.
fn deviation(run: &Trajectory, reference: &Trajectory) -> (f64, &'static str) {
    let mut worst = (0.0, COMPARED[0].0);
    for (i, (name, _)) in COMPARED.iter().enumerate() {
        let (lo, hi) = reference
            .y
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
                (lo.min(y[i]), hi.max(y[i]))
            });
        let d = run
            .y
            .iter()
            .zip(&reference.y)
            .map(|(a, b)| (a[i] - b[i]).abs())
            .fold(0.0, f64::max)
            / (hi - lo);
        if d > worst.0 {
            worst = (d, name);
        }
    }
    worst
}

/// Runs the comparison and the stability scan; returns the Markdown.
pub fn report(fmu: &Fmu) -> Result<String, String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Accuracy of the real-time method\n\n\
         Written by `cargo run --release --bin bench-latency -- --accuracy` (see \
         `src/bin/bench-latency/accuracy.rs` for the method). The real-time methods \
         (`solver.method = 3`: Rodas5P's step; 4: ROS34PW2's, its LU kept and its Jacobian \
         renewed every 10 steps) against the adaptive Rodas5P at rtol {REFERENCE_RTOL:e} and `solver.atol` {REFERENCE_ATOL:e}, both \
         through the packaged FMU's FMI 2.0 entry points at the same communication step, {STOP} s. \
         Deviation: the largest difference over the run of y_pot, theta_motor, theta_hub, w_tip \
         and p_load, each relative to its range, and the output where it is largest. Estimate: \
         the largest `solver.error_estimate` of the run: the embedded error estimate of a step \
         relative to the FMU's default tolerances (rtol 1e-6, atol 1e-8 of each state's \
         nominal value; above 1, a step the adaptive method would have rejected).\n"
    );
    let _ = writeln!(
        md,
        "| scenario | communication step | method | substeps | step h | deviation / range | worst output | estimate |\n\
         | --- | ---: | --- | ---: | ---: | ---: | --- | ---: |"
    );
    for scenario in [Scenario::DefaultExperiment, Scenario::ClosedLoop] {
        for (h, substeps) in [(1e-3, &[1, 2, 4, 10][..]), (1e-4, &[1, 2][..])] {
            let reference = simulate(fmu, scenario, h, None)?;
            for (&s, &(method, method_name)) in substeps
                .iter()
                .flat_map(|s| REAL_TIME.iter().map(move |m| (s, m)))
            {
                let row = match simulate(fmu, scenario, h, Some((method, s))) {
                    Ok(run) => {
                        let (d, name) = deviation(&run, &reference);
                        format!("{d:.1e} | {name} | {:.1e}", run.largest_estimate)
                    }
                    Err(e) => format!("failed: {e} | | "),
                };
                eprintln!(
                    "{} at {h} s, {method_name}, {s} substeps: {row}",
                    scenario.name()
                );
                let _ = writeln!(
                    md,
                    "| {} | {} ms | {method_name} | {s} | {} µs | {row} |",
                    scenario.name(),
                    h * 1e3,
                    h / f64::from(s) * 1e6
                );
            }
        }
    }
    let _ = writeln!(
        md,
        "\n## Stability: one fixed step per communication step\n\n\
         Both scenarios with `solver.substeps = 1` at longer communication steps, against the \
         adaptive solver at the same points. In the closed loop the importer's controller is \
         sampled at the communication step, so there the loop itself, not the integrator, may \
         go unstable: then both runs fail or diverge together.\n\n\
         | scenario | communication step | method | deviation / range | worst output | estimate |\n\
         | --- | ---: | --- | ---: | --- | ---: |"
    );
    for scenario in [Scenario::DefaultExperiment, Scenario::ClosedLoop] {
        for (h, &(method, method_name)) in [1e-3, 5e-3, 1e-2, 2e-2, 5e-2, 0.1, 0.5]
            .into_iter()
            .flat_map(|h| REAL_TIME.iter().map(move |m| (h, m)))
        {
            let row = match simulate(fmu, scenario, h, None) {
                Err(e) => format!("adaptive failed too: {e} | | "),
                Ok(reference) => match simulate(fmu, scenario, h, Some((method, 1))) {
                    Ok(run) => {
                        let (d, name) = deviation(&run, &reference);
                        format!("{d:.1e} | {name} | {:.1e}", run.largest_estimate)
                    }
                    Err(e) => format!("failed: {e} | | "),
                },
            };
            eprintln!(
                "stability, {} at {h} s, {method_name}: {row}",
                scenario.name()
            );
            let _ = writeln!(
                md,
                "| {} | {} ms | {method_name} | {row} |",
                scenario.name(),
                h * 1e3
            );
        }
    }
    Ok(md)
}
