//! External control (`controller.external = true`): the input `e_in` drives the valve coil (the
//! LOES's valve command) in place of the analog controller, through the power amplifier's output
//! limit; `r` is not used; `y_pot` stays an output.

use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::VARIABLES;
use hydraulic_slewing_plate::solver::Integrator;

/// The model of a preset with `sets` applied and the inputs set by name.
fn model(preset: &str, sets: &[(&str, &str)], inputs: &[(&str, f64)]) -> (Parameters, Assembled) {
    let mut values = Values::from_start(&VARIABLES);
    presets::apply(&mut values, preset).unwrap();
    for (n, v) in sets {
        set_by_name(&mut values, n, v).unwrap();
    }
    for (n, v) in inputs {
        set_by_name(&mut values, n, &v.to_string()).unwrap();
    }
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    let mut sys = Assembled::new(&p).unwrap();
    sys.set_inputs(&values);
    (p, sys)
}

/// Runs from rest to `t_end`; returns the outputs by name at the end.
fn run(p: &Parameters, sys: &Assembled, t_end: f64) -> impl Fn(&str) -> f64 {
    let mut integ = Integrator::new(p.solver_options(sys), 0.0, sys.initial_state()).unwrap();
    integ.advance_to(sys, t_end).expect("integration");
    let m = sys.compiled().clone();
    let mut y = vec![0.0; m.n_outputs()];
    m.outputs(integ.x(), sys.inputs(), &mut y);
    move |name: &str| {
        y[m.output_index(name)
            .unwrap_or_else(|| panic!("no output {name}"))]
    }
}

const EXTERNAL: (&str, &str) = ("controller.external", "true");

#[test]
fn with_e_in_zero_the_motor_stays_at_rest_whatever_r() {
    for preset in [
        "loes-motor",
        "paper-fig9b",
        "servo-valve-motor",
        "complete",
        "complete-hub-locked",
    ] {
        for r in [-5.0, 0.0, 3.0] {
            let (p, sys) = model(preset, &[EXTERNAL], &[("r", r), ("e_in", 0.0)]);
            let y = run(&p, &sys, 0.5);
            // Exactly zero for the linear LOES (the state never leaves 0); the full servo valve
            // starts at its Newton rest state (steps below 1e-13) and stays there.
            for name in ["theta_motor", "omega_motor", "controller.e_out"] {
                assert!(
                    y(name).abs() < 1e-9,
                    "{preset}, r = {r}: {name} = {}",
                    y(name)
                );
            }
            assert!(y("y_pot").abs() < 1e-9);
        }
    }
}

#[test]
fn the_analog_loop_moves_on_r_and_ignores_e_in() {
    // The converse: without external control r drives the loop and e_in is not used.
    let (p, sys) = model("loes-motor", &[], &[("r", 0.5), ("e_in", 7.0)]);
    let y = run(&p, &sys, 1.0);
    assert!((y("y_pot") - 0.5).abs() < 1e-4, "y_pot = {}", y("y_pot"));
}

#[test]
fn loes_with_constant_e_in_turns_at_k_sv_e_over_d_m() {
    // Motor alone, no position feedback: at steady state the load pressure is zero (no load
    // torque), so the valve flow k_sv e_in all goes into displacement: omega = k_sv e_in / D_m.
    // The transient decays with the hydraulic poles (65 and 753 1/s): after 0.5 s it is below
    // exp(-32) of the step.
    for e_in in [-2.0, 0.5, 3.0] {
        let (p, sys) = model("loes-motor", &[EXTERNAL], &[("r", 1.0), ("e_in", e_in)]);
        let y = run(&p, &sys, 0.5);
        let predicted = p.loes.k_sv * e_in / p.loes.d_m;
        let measured = y("omega_motor");
        assert!(
            (measured - predicted).abs() <= 1e-6 * predicted.abs(),
            "e_in = {e_in}: omega {measured} vs k_sv e / D_m = {predicted}"
        );
        assert_eq!(y("controller.e_out"), e_in);
        // y_pot still reads the potentiometer.
        assert!((y("y_pot") - p.controller.k_pot * y("theta_motor")).abs() < 1e-12);
    }
}

#[test]
fn e_in_passes_the_amplifier_limit() {
    // 30 V asked of a 12 V amplifier: the coil sees the limited voltage, and the motor turns at
    // the rate of that voltage.
    let (p, sys) = model(
        "loes-motor",
        &[EXTERNAL, ("controller.saturation", "true")],
        &[("e_in", 30.0)],
    );
    let y = run(&p, &sys, 0.5);
    let e = y("controller.e_out");
    assert!(
        e < p.controller.e_max && e > 0.99 * p.controller.e_max,
        "{e}"
    );
    let predicted = p.loes.k_sv * e / p.loes.d_m;
    assert!((y("omega_motor") - predicted).abs() <= 1e-6 * predicted);
}

#[test]
fn full_servo_valve_with_constant_e_in_turns_at_the_static_flow_gain() {
    // Motor alone, no position feedback. At steady state the coil carries i = e_in / R_bob (the
    // flapper is still, so no back-EMF), and the spool sits where the feedback wire balances the
    // torque motor with the flapper back at its null: x_v = k_phi i / k_w. (The pilot pressure
    // that holds the spool against its weak centring spring needs a flapper offset of about
    // 1e-9 m, 1e-5 of x_v.) The rotor's seal drag needs the load pressure p_L = b_m omega / D_m
    // (0.06 bar at 0.6 rad/s), which drives the leakage p_L / R_leak across the vanes (0.2 % of
    // the flow of the rig-sized motor) and lowers the metering edges' drop: the four edges pass
    // Q = Cd w sqrt((p_s - p_t - |p_L|) / rho) x_v, and the rotor turns at
    // omega = (Q - p_L / R_leak) / D_m, solved here by fixed-point iteration. What the prediction
    // leaves out, each well below 0.1 %: the orifices' laminar regularisation (dp_cr = 0.05 bar
    // against a 70 bar drop), the end stops and the cavitation floor (far away at these openings).
    // After 1 s the coil lag (64 1/s) has decayed to exp(-64) of the step.
    for e_in in [-1.0, 0.5, 2.0] {
        let (p, sys) = model(
            "servo-valve-motor",
            &[EXTERNAL],
            &[("r", 1.0), ("e_in", e_in)],
        );
        let y = run(&p, &sys, 1.0);
        let v = &p.servo_valve;
        let x_v = v.k_phi * (e_in / v.r_bob) / v.k_w;
        let mut predicted = v.flow_gain() * x_v / v.d_m;
        for _ in 0..50 {
            let p_load = v.b_m * predicted / v.d_m;
            let q = v.cd * v.w * ((v.p_supply - v.p_tank - p_load.abs()) / v.rho).sqrt() * x_v;
            predicted = (q - p_load / v.r_leak) / v.d_m;
        }
        let measured = y("omega_motor");
        assert!(
            (measured - predicted).abs() <= 1e-3 * predicted.abs(),
            "e_in = {e_in}: omega {measured} vs the valve's static flow {predicted}"
        );
        assert!(
            (y("servo_valve.x_v") - x_v).abs() <= 1e-3 * x_v.abs(),
            "e_in = {e_in}: x_v {} vs {x_v}",
            y("servo_valve.x_v")
        );
    }
}
