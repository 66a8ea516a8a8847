//! Radau IIA with the full servo valve, through the exported `fmi2*` functions: the Jacobian is
//! kept from one `fmi2DoStep` to the next while Newton converges fast (as RADAU5 keeps it from
//! step to step), it travels with the FMU state, and a restored instance, which rebuilds it
//! and its factorisations, goes on with the same bits and the same counters. A hand-edited
//! kept Jacobian that does not fit the model is refused by name.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::{find_key, Fmu};
use hydraulic_slewing_plate::fmi2::ffi::*;

const STEP: f64 = 1e-3;

/// The default configuration (complete system: full servo valve coupled to hub and plate) with
/// Radau IIA.
fn radau5() -> Fmu {
    let f = Fmu::new();
    assert_eq!(f.set_integer("solver.method", 2), Fmi2Status::Ok);
    assert_eq!(f.init(0.0), Fmi2Status::Ok, "{}", f.last());
    f
}

/// Steps from point k0 to k1 with `r(k)` set before each step; `y_pot` and the spool position
/// at each point.
fn run(f: &Fmu, k0: usize, k1: usize, r: impl Fn(usize) -> f64) -> Vec<f64> {
    let mut out = Vec::new();
    for k in k0..k1 {
        assert_eq!(f.set_real("r", r(k)), Fmi2Status::Ok);
        assert_eq!(
            f.step(k as f64 * STEP, STEP),
            Fmi2Status::Ok,
            "{}",
            f.last()
        );
        out.push(f.get_real("y_pot").1);
        out.push(f.get_real("servo_valve.x_v").1);
    }
    out
}

fn counter(f: &Fmu, name: &str) -> i32 {
    let (s, n) = f.get_integer(name);
    assert_eq!(s, Fmi2Status::Ok);
    n
}

fn counters(f: &Fmu) -> Vec<i32> {
    [
        "solver.steps",
        "solver.f_evals",
        "solver.jac_evals",
        "solver.lu",
    ]
    .iter()
    .map(|n| counter(f, n))
    .collect()
}

/// Steps on from point `k` (r = 2 V) until the FMU state holds a kept Jacobian: the point
/// reached, the state and its payload.
fn until_kept(f: &Fmu, k: usize) -> (usize, Fmi2FmuState, serde_json::Value) {
    fmu::until_state_holds(f, k, "kept_jac", 1000, |k| {
        run(f, k, k + 1, |_| 2.0);
    })
}

#[test]
fn the_jacobian_is_kept_across_points_and_restored_with_the_state() {
    let f = radau5();
    // A 2 V step of r: the valve opens, the motor slews; 300 points of 1 ms.
    run(&f, 0, 300, |_| 2.0);
    let (steps, jacobians) = (counter(&f, "solver.steps"), counter(&f, "solver.jac_evals"));
    // Radau IIA ends a step on every point; J was evaluated at the start of each (300 calls)
    // before it was kept across points. In the slewing transient (amplifier at its limit,
    // spool on its stops) Newton slows now and then and asks for a new one.
    assert!(steps >= 300, "{steps} steps");
    assert!(jacobians < 200, "{jacobians} Jacobians in {steps} steps");

    let (k, saved, mut payload) = until_kept(&f, 300);
    let bytes = f.serialize(saved);
    let kept = find_key(&mut payload, "kept_jac").expect("the state holds the kept Jacobian");
    assert!(kept["entries"].as_array().is_some_and(|e| !e.is_empty()));

    // Go on with r held, then a jump back: the same bits from the state in memory and from its
    // serialised form in another instance, and the same counters (the rebuilt J and LUs are
    // not counted again).
    let r = |k: usize| if k < 450 { 2.0 } else { 0.5 };
    let first = run(&f, k, 600, r);
    let first_counters = counters(&f);
    assert_eq!(f.set_state(saved), Fmi2Status::Ok);
    let again = run(&f, k, 600, r);
    let other = radau5();
    let (s, restored) = other.deserialize(&bytes);
    assert_eq!(s, Fmi2Status::Ok, "{}", other.last());
    assert_eq!(
        other.set_state(restored),
        Fmi2Status::Ok,
        "{}",
        other.last()
    );
    let elsewhere = run(&other, k, 600, r);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&first), bits(&again));
    assert_eq!(bits(&first), bits(&elsewhere));
    assert_eq!(first_counters, counters(&f));
    assert_eq!(first_counters, counters(&other));
    f.free_state(saved);
    other.free_state(restored);
}

#[test]
fn a_kept_jacobian_that_does_not_fit_is_refused_by_name() {
    let f = radau5();
    run(&f, 0, 50, |_| 2.0);
    let (_, saved, mut payload) = until_kept(&f, 50);
    let kept = find_key(&mut payload, "kept_jac").expect("kept_jac");
    kept["entries"].as_array_mut().unwrap().pop();
    let (s, edited) = f.deserialize(&fmu::blob(&payload));
    if s == Fmi2Status::Ok {
        assert_eq!(f.set_state(edited), Fmi2Status::Error);
        f.free_state(edited);
    }
    assert!(f.last().contains("kept Jacobian"), "{}", f.last());
    f.free_state(saved);
}
