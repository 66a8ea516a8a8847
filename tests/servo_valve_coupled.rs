//! The position loop with the motor coupled to the hub through the torsion bar
//! (`hydraulics.motor_coupled = true`), for both hydraulic models, both plate formulations, hub
//! free and locked: linearised at rest, every eigenvalue has a negative real part except the
//! exact zeros of conserved quantities, which are named and checked:
//!
//! * hub free: the hub angle `hub.theta`, an output integral that nothing feeds back (its column
//!   of A is zero);
//! * hub locked: the rotor angle and the bar twist integrate the same speed (the bar's far end
//!   is fixed), so `theta_a - twist` is conserved: their rows of A are equal, and A has one
//!   exact zero eigenvalue (the bar held twisted by a chamber pressure difference is at rest too).

use hydraulic_slewing_plate::eigen;
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::VARIABLES;
use nalgebra::{Complex, DMatrix};

struct Coupled {
    names: Vec<String>,
    a: DMatrix<f64>,
}

fn coupled(model: &str, formulation: &str, root: &str) -> Coupled {
    let mut values = Values::from_start(&VARIABLES);
    set_by_name(&mut values, "hydraulics.model", model).unwrap();
    set_by_name(&mut values, "hydraulics.motor_coupled", "true").unwrap();
    set_by_name(&mut values, "plate.formulation", formulation).unwrap();
    set_by_name(&mut values, "plate.root", root).unwrap();
    // The loop at rest, without the command generator: its clock integrates a constant and is
    // no part of the loop (an exact zero eigenvalue that round-off may put on either side).
    set_by_name(&mut values, "reference.angle", "0").unwrap();
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    let sys = Assembled::new(&p).unwrap();
    let lin = sys.compiled().linearize(&sys.initial_state(), sys.inputs());
    Coupled {
        names: lin.state_names.clone(),
        a: lin.a,
    }
}

/// The eigenvalues of `A` after the named conserved quantity is taken out, checked to be stable.
fn assert_stable(model: &str, formulation: &str, root: &str) -> Vec<Complex<f64>> {
    let c = coupled(model, formulation, root);
    let n = c.a.nrows();
    let label = format!("model {model}, formulation {formulation}, root {root}");
    let index = |s: &str| {
        c.names
            .iter()
            .position(|x| x == s)
            .unwrap_or_else(|| panic!("{label}: no state {s}"))
    };
    let rotor = if model == "1" {
        "loes.theta_a"
    } else {
        "servo_valve.theta_a"
    };
    let (keep, zero) = if root == "1" {
        let k = index("hub.theta");
        assert!(
            c.a.column(k).iter().all(|v| *v == 0.0),
            "{label}: hub.theta is fed back"
        );
        ((0..n).filter(|&i| i != k).collect::<Vec<_>>(), 0)
    } else {
        ((0..n).collect(), 1)
    };
    let a = DMatrix::from_fn(keep.len(), keep.len(), |i, j| c.a[(keep[i], keep[j])]);
    if zero == 1 {
        // The left null vector: the rows of the rotor angle and of the bar twist are the same
        // (both integrate the rotor speed; the bar's far end is fixed), so their difference is
        // conserved.
        let (it, iq) = (index(rotor), index("torsion_bar.k.q"));
        let diff = (a.row(it) - a.row(iq)).norm();
        assert!(
            diff <= 1e-14 * a.row(it).norm(),
            "{label}: rows differ by {diff}: {} vs {}",
            a.row(it),
            a.row(iq)
        );
    }
    let mut ev = eigen::eigenvalues(&a);
    ev.sort_by(|x, y| x.norm().total_cmp(&y.norm()));
    let scale = ev.last().unwrap().norm();
    // The conserved quantity's exact zero comes out at round-off of the largest eigenvalue.
    assert!(
        ev.iter().take(zero).all(|e| e.norm() <= 1e-9 * scale),
        "{label}: {:?}",
        &ev[..zero]
    );
    let rest = &ev[zero..];
    let worst = rest
        .iter()
        .copied()
        .max_by(|x, y| x.re.total_cmp(&y.re))
        .unwrap();
    assert!(
        worst.re < 0.0,
        "{label}: eigenvalue {worst} in the right half-plane; all: {rest:?}"
    );
    rest.to_vec()
}

#[test]
fn loes_coupled_loop_is_stable() {
    // Slowest pair -0.0069 +- 0.826j (0.13 Hz, docs/model-notes.md, item 11).
    assert_stable("1", "1", "1");
}

#[test]
fn servo_valve_coupled_loop_is_stable_paper_hub_free() {
    assert_stable("2", "1", "1");
}

#[test]
fn servo_valve_coupled_loop_is_stable_paper_hub_locked() {
    assert_stable("2", "1", "2");
}

#[test]
fn servo_valve_coupled_loop_is_stable_consistent_hub_free() {
    assert_stable("2", "2", "1");
}

#[test]
fn servo_valve_coupled_loop_is_stable_consistent_hub_locked() {
    assert_stable("2", "2", "2");
}
