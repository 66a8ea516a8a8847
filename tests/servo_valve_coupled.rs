//! The position loop with the motor coupled to the hub through the torsion bar
//! (`hydraulics.motor_coupled = true`, default plate, bar and hub): linearised at rest, every
//! eigenvalue must have a negative real part, except the hub angle `hub.theta`, an output
//! integral that nothing feeds back (its column of A is zero, so it contributes an exact 0).

use hydraulic_slewing_plate::fmi2::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::VARIABLES;
use nalgebra::DMatrix;

/// Eigenvalues of the coupled loop at rest with `hub.theta` removed.
fn coupled_eigenvalues(model: &str) -> Vec<nalgebra::Complex<f64>> {
    let mut values = Values::from_start(&VARIABLES);
    set_by_name(&mut values, "hydraulics.model", model).unwrap();
    set_by_name(&mut values, "hydraulics.motor_coupled", "true").unwrap();
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    let sys = Assembled::new(&p).unwrap();
    let lin = sys.compiled().linearize(&sys.initial_state(), sys.inputs());
    let n = lin.a.nrows();
    let k = lin
        .state_names
        .iter()
        .position(|s| s == "hub.theta")
        .expect("hub.theta state");
    assert!(
        lin.a.column(k).iter().all(|v| *v == 0.0),
        "hub.theta is fed back"
    );
    let keep: Vec<usize> = (0..n).filter(|&i| i != k).collect();
    let a = DMatrix::from_fn(n - 1, n - 1, |i, j| lin.a[(keep[i], keep[j])]);
    a.complex_eigenvalues().iter().copied().collect()
}

fn assert_stable(model: &str) {
    let ev = coupled_eigenvalues(model);
    let worst = ev
        .iter()
        .copied()
        .max_by(|a, b| a.re.total_cmp(&b.re))
        .unwrap();
    assert!(
        worst.re < 0.0,
        "model {model}, coupled: eigenvalue {worst} in the right half-plane; all: {ev:?}"
    );
}

#[test]
fn loes_coupled_loop_is_stable() {
    // Slowest pair -0.0069 +- 0.826j (0.13 Hz, README "The heavy hub in the loop").
    assert_stable("1");
}

#[test]
#[ignore = "known limit (README): with the fitted valve the coupled model-2 loop has pairs at \
            +1.19 +- 7.50j and +1.20 +- 33.5j; Kv = 46 1/s exceeds 2 zeta_h omega_h of the hub \
            on the oil spring"]
fn servo_valve_coupled_loop_is_stable() {
    assert_stable("2");
}
