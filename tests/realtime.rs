//! The real-time method (`solver.method = 3`, Rodas5P at a fixed step, `solver.substeps` steps
//! per communication step) through the FMI 2.0 entry points: its accuracy against the adaptive
//! solver on the default experiment, the same work at every communication step whatever the
//! input does (from the solver's counters), and its error estimate.
//! Its zero allocation per step is in `tests/zero_allocation.rs`; the latency it buys is measured
//! by `cargo run --release --bin bench-latency` (bench/latency.md), not here.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;
use hydraulic_slewing_plate::fmu::Kind;
use hydraulic_slewing_plate::model::variables::VARIABLES;
use hydraulic_slewing_plate::solver::MAX_SUBSTEPS;

/// The outputs compared with the adaptive solver.
const COMPARED: [&str; 5] = ["y_pot", "theta_motor", "theta_hub", "w_tip", "p_load"];
/// The solver's counters, in the order of [`Run::counters`].
const COUNTERS: [&str; 5] = [
    "solver.steps",
    "solver.rejected",
    "solver.f_evals",
    "solver.jac_evals",
    "solver.lu",
];

struct Run {
    /// The compared outputs at every communication point.
    y: Vec<[f64; 5]>,
    /// The counters after every communication step.
    counters: Vec<[i32; 5]>,
    /// `solver.error_estimate` after every communication step.
    error: Vec<f64>,
}

/// Runs the FMU from 0 to `stop` in communication steps `h` with `sets` (name, value as text
/// parsed by type below), calling `input(t, y_pot)` before each step for the value of `e_in`
/// (None: leave the inputs alone).
fn run(sets: &[(&str, &str)], h: f64, stop: f64, input: impl Fn(f64, f64) -> Option<f64>) -> Run {
    let fmu = initialised(sets);
    steps(&fmu, 0, (stop / h).round() as usize, h, input)
}

/// An instance with `sets` (see [`run`]), initialised at t = 0.
fn initialised(sets: &[(&str, &str)]) -> Fmu {
    let fmu = Fmu::new();
    for &(name, value) in sets {
        let status = match name {
            "solver.rtol" | "solver.atol" => fmu.set_real(name, value.parse().unwrap()),
            "controller.external" | "controller.saturation" => {
                fmu.set_boolean(name, value == "true")
            }
            _ => fmu.set_integer(name, value.parse().unwrap()),
        };
        assert_eq!(status, Fmi2Status::Ok, "setting {name} = {value}");
    }
    assert_eq!(fmu.init(0.0), Fmi2Status::Ok);
    fmu
}

/// Communication steps `k0..k1` of size `h` (see [`run`]).
fn steps(fmu: &Fmu, k0: usize, k1: usize, h: f64, input: impl Fn(f64, f64) -> Option<f64>) -> Run {
    let n = k1 - k0;
    let mut out = Run {
        y: Vec::with_capacity(n),
        counters: Vec::with_capacity(n),
        error: Vec::with_capacity(n),
    };
    for k in k0..k1 {
        let t = k as f64 * h;
        let y_pot = fmu.get_real("y_pot").1;
        if let Some(e) = input(t, y_pot) {
            assert_eq!(fmu.set_real("e_in", e), Fmi2Status::Ok);
        }
        assert_eq!(fmu.step(t, h), Fmi2Status::Ok, "step at t = {t}");
        out.y.push(COMPARED.map(|name| fmu.get_real(name).1));
        out.counters
            .push(COUNTERS.map(|name| fmu.get_integer(name).1));
        out.error.push(fmu.get_real("solver.error_estimate").1);
    }
    out
}

/// The largest deviation of each compared output over the run, relative to that output's range
/// in the reference run.
fn deviations(run: &Run, reference: &Run) -> [f64; 5] {
    let mut dev = [0.0; 5];
    for (i, d) in dev.iter_mut().enumerate() {
        let (lo, hi) = reference
            .y
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
                (lo.min(y[i]), hi.max(y[i]))
            });
        let worst = run
            .y
            .iter()
            .zip(&reference.y)
            .map(|(a, b)| (a[i] - b[i]).abs())
            .fold(0.0, f64::max);
        *d = worst / (hi - lo);
    }
    dev
}

/// The default experiment (the complete system and its own 30 deg move, 6 s) at 1 ms
/// communication steps: the real-time method, with one fixed step per communication step and
/// with four, agrees with the adaptive Rodas5P at rtol 1e-10 (`solver.atol` 1e-12) to within
/// 1e-10 of each compared output's range.
///
/// The bound is the one docs/realtime.md states; `bench-latency --accuracy` measured 4.0e-12 and
/// 5.6e-12 (bench/realtime_accuracy.md; `--nocapture` prints this run's). The reference's own
/// error is of the order of 1e-12 of the ranges: at the FMU's default tolerances tightened to
/// rtol 1e-8 alone it was 7.5e-8 of `p_load`'s range and hid the method's error.
#[test]
fn the_default_experiment_at_1_ms_agrees_with_the_adaptive_solver() {
    let tight = [("solver.rtol", "1e-10"), ("solver.atol", "1e-12")];
    let reference = run(&tight, 1e-3, 6.0, |_, _| None);
    for substeps in ["1", "4"] {
        let fixed = run(
            &[("solver.method", "3"), ("solver.substeps", substeps)],
            1e-3,
            6.0,
            |_, _| None,
        );
        let dev = deviations(&fixed, &reference);
        println!("{substeps} substeps: deviation / range of {COMPARED:?} = {dev:?}");
        for (name, d) in COMPARED.iter().zip(dev) {
            assert!(
                d <= 1e-10,
                "{substeps} substeps: {name} deviates by {d:.2e} of its range (bound 1e-10)"
            );
        }
    }
}

/// With an input that changes at every communication point (a proportional controller closing
/// the loop on `y_pot`, following a square wave), every communication step of the real-time
/// method adds the same amounts to the solver's counters: `substeps` steps, no rejection, 8
/// right-hand sides, one Jacobian and one factorisation per step. The adaptive Rodas5P, run the
/// same way, does not (the check can fail).
#[test]
fn every_step_does_the_same_work_whatever_the_input() {
    let square = |t: f64| if t % 0.2 < 0.1 { 0.25 } else { 0.0 };
    let controller = move |t: f64, y_pot: f64| Some(20.0 * (square(t) - y_pot));
    let external = ("controller.external", "true");
    let increments = |run: &Run| -> Vec<[i32; 5]> {
        run.counters
            .windows(2)
            .map(|w| std::array::from_fn(|i| w[1][i] - w[0][i]))
            .collect()
    };
    for substeps in [1, 3] {
        let s = substeps.to_string();
        let fixed = run(
            &[external, ("solver.method", "3"), ("solver.substeps", &s)],
            1e-3,
            1.0,
            controller,
        );
        let expected = [substeps, 0, 8 * substeps, substeps, substeps];
        for (k, inc) in increments(&fixed).iter().enumerate() {
            assert_eq!(
                *inc,
                expected,
                "{substeps} substeps, communication step {}: counters grew by {inc:?} \
                 (steps, rejected, f, J, LU)",
                k + 1
            );
        }
    }
    let adaptive = run(&[external], 1e-3, 1.0, controller);
    let inc = increments(&adaptive);
    assert!(
        inc.iter().any(|i| *i != inc[0]),
        "the adaptive solver did the same work at every step too: the check proves nothing"
    );
}

/// The W-method's real-time step (`solver.method = 4`, ROS34PW2) in the same closed loop: every
/// communication step adds one step, no rejection and four right-hand sides, and a Jacobian
/// with its factorisation comes every 10 steps exactly (`Ros34pw2Options::fixed_jacobian_interval`),
/// whatever the input does: each run of 10 communication steps adds the same work.
#[test]
fn the_w_method_renews_its_jacobian_every_ten_steps_whatever_the_input() {
    let square = |t: f64| if t % 0.2 < 0.1 { 0.25 } else { 0.0 };
    let controller = move |t: f64, y_pot: f64| Some(20.0 * (square(t) - y_pot));
    let sets = [("controller.external", "true"), ("solver.method", "4")];
    let w = run(&sets, 1e-3, 1.0, controller);
    let increments: Vec<[i32; 5]> = w
        .counters
        .windows(2)
        .map(|w| std::array::from_fn(|i| w[1][i] - w[0][i]))
        .collect();
    assert_eq!(increments.len(), 999);
    // Increment k is communication step k + 2's; the Jacobians come at steps 1, 11, 21, ...
    for (k, inc) in increments.iter().enumerate() {
        let renewed = i32::from((k + 1) % 10 == 0);
        assert_eq!(
            *inc,
            [1, 0, 4, renewed, renewed],
            "communication step {}: counters grew by {inc:?} (steps, rejected, f, J, LU)",
            k + 2
        );
    }
}

/// The error estimate the real-time method reports (`solver.error_estimate`) grows with its step
/// (order 5: much more than tenfold for a tenfold step) in the closed loop of
/// [`every_step_does_the_same_work_whatever_the_input`], whose steps of `r` the fixed step must
/// cross; the adaptive method reports 0.
#[test]
fn the_error_estimate_follows_the_step() {
    let closed_loop = |sets: &[(&str, &str)]| {
        let mut all = vec![("controller.external", "true")];
        all.extend_from_slice(sets);
        run(&all, 1e-3, 1.0, |t, y_pot| {
            Some(20.0 * (if t % 0.2 < 0.1 { 0.25 } else { 0.0 } - y_pot))
        })
    };
    let at = |substeps| closed_loop(&[("solver.method", "3"), ("solver.substeps", substeps)]);
    let largest = |r: &Run| r.error.iter().copied().fold(0.0, f64::max);
    let (e1, e10) = (largest(&at("1")), largest(&at("10")));
    println!("largest error estimate: 1 substep {e1:.3e}, 10 substeps {e10:.3e}");
    assert!(e10 > 0.0);
    assert!(e1 > 30.0 * e10, "1 substep {e1:e}, 10 substeps {e10:e}");
    assert_eq!(largest(&closed_loop(&[])), 0.0);
}

/// A run of the real-time method restored from an FMU state continues bit for bit, from the
/// state in memory and from its serialised form in another instance: the kept elimination of
/// the Jacobian's constant rows (`solver::linalg::VaryingRows`), rebuilt after the restore, is
/// made for the step size saved with the integrator, not for the restored call's own
/// `t_end − t` (which differs from it in the last bits).
#[test]
fn a_restored_run_continues_bit_for_bit() {
    let sets = [
        ("controller.external", "true"),
        ("solver.method", "3"),
        ("solver.substeps", "2"),
    ];
    let controller =
        |t: f64, y_pot: f64| Some(20.0 * (if t % 0.2 < 0.1 { 0.25 } else { 0.0 } - y_pot));
    let h = 1e-3;
    let f = initialised(&sets);
    steps(&f, 0, 150, h, controller);
    let (status, saved) = f.get_state();
    assert_eq!(status, Fmi2Status::Ok);
    let bytes = f.serialize(saved);
    let first = steps(&f, 150, 450, h, controller);
    assert_eq!(f.set_state(saved), Fmi2Status::Ok);
    let again = steps(&f, 150, 450, h, controller);
    let other = initialised(&sets);
    let (status, restored) = other.deserialize(&bytes);
    assert_eq!(status, Fmi2Status::Ok);
    assert_eq!(other.set_state(restored), Fmi2Status::Ok);
    let elsewhere = steps(&other, 150, 450, h, controller);
    let bits = |r: &Run| -> Vec<u64> { r.y.iter().flatten().map(|v| v.to_bits()).collect() };
    assert_eq!(bits(&first), bits(&again));
    assert_eq!(bits(&first), bits(&elsewhere));
    assert_eq!(first.counters, elsewhere.counters);
    f.free_state(saved);
    other.free_state(restored);
}

/// `solver.substeps` outside 1..=10000 is refused with a message that names it, and that range
/// in the model description is the solver's own (`MAX_SUBSTEPS`).
#[test]
fn substeps_out_of_range_are_refused() {
    let declared = VARIABLES
        .iter()
        .find(|v| v.name == "solver.substeps")
        .map(|v| v.kind);
    match declared {
        Some(Kind::Integer { min, max, .. }) => {
            assert_eq!((min, max), (Some(1), Some(MAX_SUBSTEPS as i32)));
        }
        other => panic!("solver.substeps is declared as {other:?}"),
    }
    for bad in [0, -3, 10_001] {
        let fmu = Fmu::new();
        let status = fmu.set_integer("solver.substeps", bad);
        let log = fmu.log();
        assert_eq!(status, Fmi2Status::Error, "substeps = {bad}");
        assert!(
            log.iter().any(|(_, m)| m.contains("solver.substeps")),
            "substeps = {bad}: {log:?}"
        );
    }
}
