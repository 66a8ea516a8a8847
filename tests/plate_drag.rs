//! Air drag of the plate (`src/fragments/plate/drag.rs`): a free decay of the plate clamped at
//! the root with drag as its only loss, against an independent quadrature of the drag's work.

use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::fragments::plate::beam_functions::{BeamFunction, BeamKind};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::VARIABLES;
use hydraulic_slewing_plate::solver::{Atol, Integrator, Method, SolverOptions};

/// The paper's plate clamped at the root (hub locked: coordinates are the plain products
/// `phi_n(x/a) psi_m(y/b)` with clamped-free `phi`), no structural damping, drag on; the motor
/// runs alone and idles.
fn system() -> (Parameters, Assembled) {
    let mut values = Values::from_start(&VARIABLES);
    presets::apply(&mut values, "paper-fig10").unwrap();
    for (n, v) in [("plate.zeta", "0"), ("plate.Cd", "1.2")] {
        set_by_name(&mut values, n, v).unwrap();
    }
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    let s = Assembled::new(&p).unwrap();
    (p, s)
}

/// The drag's power at modal rates `rates` (order `j = N (m - 1) + n`), by a 200 x 40 midpoint
/// rule over one arm, times two arms: `2 int int 1/2 rho C_d |v|^3 dA`.
fn drag_power(p: &Parameters, rates: &[f64]) -> f64 {
    let pl = &p.plate;
    let phis = BeamFunction::family(BeamKind::ClampedFree, pl.n);
    let psis = BeamFunction::family(BeamKind::FreeFree, pl.m);
    let (nx, ny) = (200, 40);
    let (dx, dy) = (pl.a / nx as f64, pl.b / ny as f64);
    let mut sum = 0.0;
    for i in 0..nx {
        let xi = (i as f64 + 0.5) / nx as f64;
        let phi: Vec<f64> = phis.iter().map(|f| f.value(xi)).collect();
        for k in 0..ny {
            let eta = (k as f64 + 0.5) / ny as f64;
            let mut v = 0.0;
            for (mi, psi) in psis.iter().enumerate() {
                let s = psi.value(eta);
                for (ni, ph) in phi.iter().enumerate() {
                    v += ph * s * rates[pl.n * mi + ni];
                }
            }
            sum += v.abs().powi(3);
        }
    }
    2.0 * 0.5 * pl.rho_air * pl.cd * sum * dx * dy
}

#[test]
fn free_decay_loses_the_drags_work() {
    let (p, sys) = system();
    let m = sys.compiled();
    let names = m.state_names();
    let at = |name: &str| names.iter().position(|n| n == name).unwrap();
    let modes = p.plate.n * p.plate.m;
    let momentum: Vec<usize> = (1..=modes)
        .map(|j| at(&format!("plate.I[{j}].p")))
        .collect();
    let modal_mass = p.plate.areal_mass() * p.plate.a * p.plate.b;
    // The first bending mode deflected by 0.1 m of modal amplitude (a tip deflection of 0.2 m,
    // w/a 0.14: far for the plate, but what makes drag matter), released at rest.
    let mut x0 = sys.initial_state();
    x0[at("plate.C[1].q")] = 0.1;
    let options = SolverOptions {
        method: Method::Rodas5P,
        rtol: 1e-9,
        atol: Atol::Scalar(1e-12),
        max_step: 1e-3,
        ..SolverOptions::default()
    };
    let mut integ = Integrator::new(options, 0.0, x0.clone()).unwrap();
    let u = sys.inputs().to_vec();
    let rates = |x: &[f64]| -> Vec<f64> { momentum.iter().map(|&i| x[i] / modal_mass).collect() };
    let model_power = |x: &[f64]| {
        m.power_balance(x, &u)
            .elements
            .iter()
            .filter(|(n, _)| n.starts_with("plate.drag["))
            .map(|(_, w)| w)
            .sum::<f64>()
    };
    let e0 = m.stored_energy(&x0);
    let (dt, steps) = (1e-3, 4000);
    let (mut work, mut model_work) = (0.0, 0.0);
    let (mut last, mut last_model) = (0.0, model_power(&x0));
    for k in 1..=steps {
        integ.advance_to(&sys, k as f64 * dt).unwrap();
        let x = integ.x();
        let (pw, pm) = (drag_power(&p, &rates(x)), model_power(x));
        work += 0.5 * (last + pw) * dt;
        model_work += 0.5 * (last_model + pm) * dt;
        (last, last_model) = (pw, pm);
    }
    let lost = e0 - m.stored_energy(integ.x());
    println!(
        "E0 {e0:.6} J, lost {lost:.6} J ({:.2} %); drag's work: independent quadrature {work:.6} J, the model's resistors {model_work:.6} J",
        100.0 * lost / e0
    );
    // Drag is the only loss, and it takes a real share of the energy in 4 s.
    assert!(lost > 0.05 * e0, "{lost} of {e0}");
    // Energy balance of the model: what its drag resistors dissipated is what the plate lost, to
    // the integrator's and the time quadrature's accuracy.
    assert!(
        (lost - model_work).abs() < 1e-4 * lost,
        "{lost} vs {model_work}"
    );
    // Against the independent quadrature of 1/2 rho C_d |v|^3 over the plate: the model's
    // 6 x 3 Gauss rule on the modes it keeps, against a midpoint rule whose own error is about
    // 1e-5 here.
    assert!((lost - work).abs() < 1e-4 * lost, "{lost} vs {work}");
}
