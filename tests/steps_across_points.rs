//! Co-simulation steps across communication points (`solver.dense_output`), through the exported
//! `fmi2*` functions: while the inputs are held, Rodas5P's steps run past the points and the
//! points are read from its dense output; an input change takes effect at the communication
//! point where it is set, not at the end of the step that ran past it; and a saved FMU state
//! holding such a step restores bit-exactly.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::{find_key, Fmu};
use hydraulic_slewing_plate::fmi2::ffi::*;

/// The LOES coupled to the plate (linear: a jump's timing shows plainly), 1 ms points.
const STEP: f64 = 1e-3;

fn fmu(dense_output: bool) -> Fmu {
    let f = Fmu::new();
    assert_eq!(f.set_integer("hydraulics.model", 1), Fmi2Status::Ok);
    assert_eq!(
        f.set_boolean("controller.saturation", false),
        Fmi2Status::Ok
    );
    assert_eq!(
        f.set_boolean("hydraulics.motor_coupled", true),
        Fmi2Status::Ok
    );
    assert_eq!(
        f.set_boolean("solver.dense_output", dense_output),
        Fmi2Status::Ok
    );
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    f
}

/// Steps from point k0 to k1 with `r(k)` set before each step; `y_pot` at each point.
fn run(f: &Fmu, k0: usize, k1: usize, r: impl Fn(usize) -> f64) -> Vec<f64> {
    (k0..k1)
        .map(|k| {
            assert_eq!(f.set_real("r", r(k)), Fmi2Status::Ok);
            assert_eq!(
                f.step(k as f64 * STEP, STEP),
                Fmi2Status::Ok,
                "{}",
                f.last()
            );
            f.get_real("y_pot").1
        })
        .collect()
}

fn steps(f: &Fmu) -> i32 {
    let (s, n) = f.get_integer("solver.steps");
    assert_eq!(s, Fmi2Status::Ok);
    n
}

/// Largest difference of two trajectories relative to the largest magnitude of the second.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

#[test]
fn held_inputs_cost_fewer_steps_than_points_at_the_same_accuracy() {
    let (free, ending) = (fmu(true), fmu(false));
    let r = |_| 1.0;
    let (a, b) = (run(&free, 0, 2000, r), run(&ending, 0, 2000, r));
    // Steps ending on every point take at least one per point; running past them, the steps
    // grow to what rtol 1e-6 allows (measured: 1203 against 4018 over these 2 s).
    assert!(steps(&ending) >= 2000, "{}", steps(&ending));
    assert!(
        2 * steps(&free) < steps(&ending),
        "{} against {}",
        steps(&free),
        steps(&ending)
    );
    // Both well within the tolerance (rtol 1e-6) of each other: measured 1.6e-10 of y_pot's
    // swing (the motor angle is slow beside the steps' error control, which watches the
    // plate's fast states).
    let d = relative_difference(&a, &b);
    assert!(d < 1e-8, "{d:e}");
}

#[test]
fn an_input_change_acts_at_its_communication_point() {
    // r steps up at point 0 and back down at point 700, when the free run has a step kept past
    // the point. Had the jump been applied at the end of that step (5 to 25 ms later), y_pot
    // would differ by a good fraction of its swing; at the point itself, the two runs agree
    // as closely as with held inputs (measured 3.6e-10).
    let r = |k: usize| if k < 700 { 1.0 } else { 0.0 };
    let (free, ending) = (fmu(true), fmu(false));
    let a = run(&free, 0, 700, r);
    assert!(
        steps(&free) < 700,
        "{}: no step kept past the points",
        steps(&free)
    );
    let b = run(&ending, 0, 700, r);
    let (a2, b2) = (run(&free, 700, 1400, r), run(&ending, 700, 1400, r));
    let d = relative_difference(&[a, a2].concat(), &[b, b2].concat());
    assert!(d < 1e-8, "{d:e}");
}

#[test]
fn a_kept_step_is_saved_with_the_fmu_state() {
    let f = fmu(true);
    run(&f, 0, 500, |_| 1.0);
    let (k, saved, _) = until_kept(&f, 500);
    let bytes = f.serialize(saved);
    // Go on with held inputs, then with a jump: both continuations restore bit for bit, from
    // the state in memory and from its serialised form in another instance.
    let r = |k: usize| if k < 800 { 1.0 } else { -0.5 };
    let first = run(&f, k, 1000, r);
    assert_eq!(f.set_state(saved), Fmi2Status::Ok);
    let again = run(&f, k, 1000, r);
    let other = fmu(true);
    let (s, restored) = other.deserialize(&bytes);
    assert_eq!(s, Fmi2Status::Ok, "{}", other.last());
    assert_eq!(
        other.set_state(restored),
        Fmi2Status::Ok,
        "{}",
        other.last()
    );
    let elsewhere = run(&other, k, 1000, r);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&first), bits(&again));
    assert_eq!(bits(&first), bits(&elsewhere));
    assert_eq!(steps(&f), steps(&other));
    f.free_state(saved);
    other.free_state(restored);
}

#[test]
fn a_restored_kept_step_must_cover_the_fmu_time() {
    // A hand-edited state whose kept step ends before the FMU's time is refused by name.
    let f = fmu(true);
    run(&f, 0, 500, |_| 1.0);
    let (_, saved, mut p) = until_kept(&f, 500);
    let ahead = find_key(&mut p, "ahead").expect("ahead");
    ahead["t1"] = serde_json::json!(0.25);
    let (s, edited) = f.deserialize(&fmu::blob(&p));
    if s == Fmi2Status::Ok {
        assert_eq!(f.set_state(edited), Fmi2Status::Error);
        f.free_state(edited);
    }
    assert!(f.last().contains("does not cover"), "{}", f.last());
    f.free_state(saved);
}

/// Steps on from point `k` (r = 1) until the FMU's time falls inside a step kept past it (the
/// steps are a few points long here): the point reached, the FMU state there and its payload.
fn until_kept(f: &Fmu, k: usize) -> (usize, Fmi2FmuState, serde_json::Value) {
    fmu::until_state_holds(f, k, "ahead", 600, |k| {
        run(f, k, k + 1, |_| 1.0);
    })
}
