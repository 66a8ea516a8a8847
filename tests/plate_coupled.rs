//! The plate in the assembled model: FRFs against Table 1 and the experiment (Fig. 10), energy
//! conservation of the consistent formulation, power balance.

use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::frf::frequency_response;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::VARIABLES;
use hydraulic_slewing_plate::solver::{Atol, Integrator, Method, SolverOptions};

/// The model with `sets` applied over the LOES on the motor alone (preset `loes-motor`, the
/// configuration these tests were written for; they couple the motor or lock the hub themselves).
fn system(sets: &[(&str, &str)]) -> (Parameters, Assembled) {
    let mut values = Values::from_start(&VARIABLES);
    presets::apply(&mut values, "loes-motor").unwrap();
    for (n, v) in sets {
        set_by_name(&mut values, n, v).unwrap();
    }
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    let s = Assembled::new(&p).unwrap();
    (p, s)
}

fn peaks(sets: &[(&str, &str)], input: &str, output: &str) -> Vec<f64> {
    let (_, s) = system(sets);
    let lin = s.compiled().linearize(&s.initial_state(), s.inputs());
    let h = frequency_response(&lin, input, output, 0.5, 120.0, 2000).unwrap();
    h.peaks.iter().map(|p| p.0).collect()
}

/// Table 1, second column: peaks of the paper's FRF of Fig. 9b (r to the tip).
use hydraulic_slewing_plate::model::paper::TABLE1_FRF_HZ as TABLE1_FRF;

#[test]
fn coupled_paper_frf_peaks_against_table_1() {
    let coupled = [("hydraulics.motor_coupled", "true")];
    let acc = peaks(&coupled, "r", "acc_tip");
    let w = peaks(&coupled, "r", "w_tip");
    println!("r -> acc_tip peaks: {acc:.3?}");
    println!("r -> w_tip peaks:   {w:.3?}");
    println!("Table 1 (Fig. 9b):  {TABLE1_FRF:?}");
    // The three bending peaks within 5 % (the issue's tolerance): the LOES and torsion bar
    // shift the pinned-free frequencies 4.914 / 15.926 / 33.228 by under 1 % here; the paper's
    // CAMP-G model (unknown bar stiffness and coupling details) shows 4.98 / 16.0 / 33.3.
    assert_eq!(acc.len(), 3, "{acc:?}");
    for (got, want) in acc.iter().zip(&TABLE1_FRF[..3]) {
        assert!((got - want).abs() <= 0.05 * want, "{got} vs {want}");
    }
    for (got, want) in w.iter().zip(&TABLE1_FRF[..3]) {
        assert!((got - want).abs() <= 0.05 * want, "{got} vs {want}");
    }
    // Not reproduced (docs/model-notes.md, item 9): the (n,3) peaks 66, 73, 84 Hz. In eqs. 18-21
    // the hub torque cannot excite m >= 3 (int psi_m dy = 0), so this FRF has no peak above 40 Hz.
    assert!(acc.iter().all(|&f| f < 40.0));
}

#[test]
fn locked_hub_frf_from_f1_against_the_experiment() {
    // Fig. 10: hub locked, shaker; the experiment's peaks 5.0, 19.0, 33.0 Hz. A clamped root
    // puts the bending modes at 1.12, 7.02, 19.67 Hz (both formulations, docs/model-notes.md,
    // item 10): only 19.0 has a neighbour (19.7). Reported, not asserted against the experiment;
    // the clamped-plate values are asserted.
    let locked = [("plate.root", "2")];
    let p = peaks(&locked, "F1", "acc[11]");
    println!("paper, hub locked, F1 -> acc[11]: {p:.3?} (experiment 5.0, 19.0, 33.0)");
    for (got, want) in p.iter().zip([1.1207, 7.0233, 19.6653]) {
        assert!((got - want).abs() <= 2e-3 * want, "{got} vs {want}");
    }
    let pc = peaks(
        &[("plate.root", "2"), ("plate.formulation", "2")],
        "F1",
        "acc[11]",
    );
    println!("consistent, hub locked, F1 -> acc[11]: {pc:.3?}");
}

#[test]
fn consistent_free_vibration_conserves_energy() {
    // Zero damping, plate free on its hub (motor uncoupled, F = 0): a Hamiltonian system. 10 s of
    // free vibration at rtol 1e-10; stored energy constant to 1e-8 relative.
    let (p, s) = system(&[
        ("plate.formulation", "2"),
        ("plate.zeta", "0"),
        ("plate.N", "2"),
        ("plate.M", "3"),
    ]);
    let names = s.compiled().state_names().to_vec();
    let mut x0 = vec![0.0; s.dim()];
    for (i, n) in names.iter().enumerate() {
        if n.starts_with("plate.C[") {
            x0[i] = 1e-3 / (i as f64);
        } else if n.starts_with("plate.I[") {
            x0[i] = 0.05 * (-1f64).powi(i as i32);
        }
    }
    let e0 = s.compiled().stored_energy(&x0);
    assert!(e0 > 0.0);
    let opts = SolverOptions {
        method: Method::Rodas5P,
        rtol: 1e-10,
        atol: Atol::Vector(s.nominal().iter().map(|n| n * 1e-12).collect()),
        max_step: 0.1,
        max_steps: 10_000_000,
        ..SolverOptions::default()
    };
    let _ = p;
    let mut integ = Integrator::new(opts, 0.0, x0).unwrap();
    integ.advance_to(&s, 10.0).unwrap();
    let e1 = s.compiled().stored_energy(integ.x());
    println!(
        "E(0) = {e0:e} J, E(10) = {e1:e} J, relative change {:e}, {} steps",
        (e1 - e0) / e0,
        integ.stats().accepted
    );
    assert!(((e1 - e0) / e0).abs() <= 1e-8);
}

#[test]
fn power_balance_with_damping_and_forcing() {
    for sets in [
        vec![
            ("plate.formulation", "2"),
            ("hydraulics.motor_coupled", "true"),
        ],
        vec![
            ("plate.formulation", "1"),
            ("hydraulics.motor_coupled", "true"),
        ],
        vec![("plate.formulation", "2")],
        vec![("plate.formulation", "2"), ("plate.root", "2")],
    ] {
        let (_, s) = system(&sets);
        let m = s.compiled();
        // the LOES at rest so that the plate's power terms are not swamped by the hydraulics
        let x: Vec<f64> = (0..m.n_states())
            .map(|i| {
                if m.state_names()[i].starts_with("loes.") {
                    0.0
                } else {
                    s.nominal()[i] * ((i as f64 * 0.7).sin() + 0.3)
                }
            })
            .collect();
        let u: Vec<f64> = m
            .input_names()
            .iter()
            .map(|n| match n.as_str() {
                "r" => 0.8,
                "F1" => 3.0,
                "F2" => -2.0,
                _ => 0.0,
            })
            .collect();
        let pb = m.power_balance(&x, &u);
        let scale = pb.source_power.abs() + pb.dissipated_power.abs() + pb.stored_rate.abs();
        println!(
            "{sets:?}: {pb:?}",
            pb = (pb.stored_rate, pb.source_power, pb.dissipated_power)
        );
        assert!(pb.dissipated_power > 0.0 && pb.source_power != 0.0);
        assert!(
            pb.residual.abs() <= 1e-12 * scale,
            "residual {} of {scale}",
            pb.residual
        );
    }
}

/// The consistent formulation's mass matrix couples the hub to every mode, yet its bond graph
/// (inertias on the modes' absolute rates, `plate::AbsoluteRates`) keeps each mode's rate a
/// function of its own momentum and the hub's: the complete default with a 20 × 20 plate
/// (816 states) has a Jacobian whose modes form blocks of their own joined by a small border,
/// and its iteration matrix `c I - J` (`c = 1/(h γ)`, from 0.1 s to 0.1 µs) is factorised with
/// that structure, not the dense LU, and solves as the dense LU does.
#[test]
fn a_20x20_plate_keeps_its_modes_in_blocks() {
    use hydraulic_slewing_plate::solver::linalg::{Factorisation, Partition, Shifted};
    use std::sync::Arc;
    let mut values = Values::from_start(&VARIABLES);
    for n in ["plate.N", "plate.M"] {
        set_by_name(&mut values, n, "20").unwrap();
    }
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    let s = Assembled::new(&p).unwrap();
    let jac = s.compiled().linearize(&s.initial_state(), s.inputs()).a;
    let n = jac.nrows();
    assert_eq!(n, 816);
    let part = Arc::new(Partition::of_matrix(&jac));
    println!(
        "{} blocks, largest {}, border {}",
        part.blocks(),
        part.largest_block(),
        part.border()
    );
    assert!(part.blocks() >= 400 && part.largest_block() <= 4 && part.border() <= 32);
    let b: Vec<f64> = (0..n)
        .map(|i| ((i * 37 % 101) as f64 - 50.0) / 50.0)
        .collect();
    for c in [1e1, 1e3, 1e5, 1e7] {
        let mut f = Factorisation::new(Arc::clone(&part));
        assert!(
            f.factor(&part, Shifted { c, jac: &jac }),
            "refused at c = {c}"
        );
        let mut x = b.clone();
        f.solve(&mut x, &mut vec![0.0; n]);
        let m = nalgebra::DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                c - jac[(i, j)]
            } else {
                -jac[(i, j)]
            }
        });
        let dense = m
            .lu()
            .solve(&nalgebra::DVector::from_vec(b.clone()))
            .unwrap();
        let worst = (0..n)
            .map(|i| (x[i] - dense[i]).abs() / dense.amax())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "c = {c}: {worst:e} from the dense LU");
    }
}
