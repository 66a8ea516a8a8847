//! The full servo valve (issues 6 and 9): null pressures, orifice characteristics, power balance
//! (valve alone and coupled to the hub and plate), the fit to G_est, flow reversal and parameter
//! rejection.

use hydraulic_slewing_plate::bond_graph::CompiledModel;
use hydraulic_slewing_plate::fmu::{Experiment, Value, Values};
use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::orifice::{regularised_sqrt, smooth_ramp};
use hydraulic_slewing_plate::fragments::servo_valve::{
    self, compare_with_g_est, log_frequencies, open_loop_linearization, rest_state, CoilDrive,
    ServoValveParameters,
};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::frf::response_at;
use hydraulic_slewing_plate::model::parameters::{check, set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::{idx, VARIABLES};
use hydraulic_slewing_plate::solver::Integrator;
use nalgebra::{Complex, DMatrix};

const P: &str = "servo_valve";

/// The closed loop at rest, with each state's nominal magnitude.
fn closed_loop(p: &ServoValveParameters) -> (CompiledModel, Vec<f64>, Vec<f64>) {
    let g = servo_valve::build_loop(p, &ControllerParameters::default()).unwrap();
    let nominal = servo_valve::nominals(&g);
    let m = g.compile().unwrap();
    let x = rest_state(&m, &[0.0], P, p, &nominal).unwrap();
    (m, x, nominal)
}

fn state(m: &CompiledModel, name: &str) -> usize {
    m.state_index(&format!("{P}.{name}"))
        .unwrap_or_else(|| panic!("no state {name}: {:?}", m.state_names()))
}

fn output(m: &CompiledModel, x: &[f64], name: &str) -> f64 {
    let mut y = vec![0.0; m.n_outputs()];
    m.outputs(x, &[0.0], &mut y);
    y[m.output_index(name)
        .unwrap_or_else(|| panic!("no output {name}"))]
}

#[test]
fn null_pressures_are_symmetric() {
    let p = ServoValveParameters::default();
    let (m, x, nominal) = closed_loop(&p);
    let (pa, pb) = (
        output(&m, &x, "servo_valve.p_a"),
        output(&m, &x, "servo_valve.p_b"),
    );
    let (p1, p2) = (
        output(&m, &x, "servo_valve.p_1"),
        output(&m, &x, "servo_valve.p_2"),
    );
    let half = 0.5 * p.p_supply;
    // Exact symmetry of the two sides.
    assert!((pa - pb).abs() <= 1e-9 * half, "p_a {pa} p_b {pb}");
    assert!((p1 - p2).abs() <= 1e-9 * half, "p_1 {p1} p_2 {p2}");
    // Main stage: edges P->A and A->T equally open at null, so p_1 = p_s / 2 exactly.
    assert!((p1 - half).abs() <= 1e-9 * half, "p_1 {p1}");
    // Pilot stage: inlet and nozzle areas equal by the choice of x_f0, up to the gap rounding
    // (ramp(x_f0, 0.01 x_f0) = x_f0 (1 + 2.5e-5)): p_a = p_s / (1 + (A_n/A_0)^2).
    let ratio = smooth_ramp(p.x_f0, 0.01 * p.x_f0).0 * p.d_n * 4.0 / (p.d_0 * p.d_0);
    let want = p.p_supply / (1.0 + ratio * ratio);
    assert!((pa - want).abs() <= 1e-6 * half, "p_a {pa} want {want}");
    // Spool, flapper, current, rotor at rest.
    for name in [
        "servo_valve.x_v",
        "servo_valve.x_f",
        "servo_valve.i_coil",
        "omega_motor",
    ] {
        assert!(output(&m, &x, name).abs() < 1e-15, "{name}");
    }
    let mut dx = vec![0.0; m.n_states()];
    m.derivatives(&x, &[0.0], &mut dx);
    for (i, d) in dx.iter().enumerate() {
        assert!(d.abs() <= 1e-9 * nominal[i], "{}: {d}", m.state_names()[i]);
    }
}

/// Textbook critical-centre four-way valve: flow into chamber 1 for spool `x` with chamber
/// pressures `p1`, `p2` (turbulent law, no clearance).
fn textbook_q1(p: &ServoValveParameters, x: f64, p1: f64) -> f64 {
    let k = p.cd * p.w * (2.0 / p.rho).sqrt();
    if x >= 0.0 {
        k * x * (p.p_supply - p1).sqrt()
    } else {
        -k * (-x) * (p1 - p.p_tank).sqrt()
    }
}

#[test]
fn flow_characteristic_matches_orifice_law() {
    let p = ServoValveParameters::default();
    let (m, rest, _) = closed_loop(&p);
    let c = p.v_1 / p.beta;
    for &x in &[-4e-4, -1e-4, -2e-5, 2e-5, 1e-4, 4e-4] {
        for &pl in &[-60e5, 0.0, 30e5, 90e5] {
            let p1 = 0.5 * (p.p_supply + pl);
            let p2 = 0.5 * (p.p_supply - pl);
            let mut s = rest.clone();
            s[state(&m, "springs.q[2]")] = x;
            s[state(&m, "C_1.q")] = c * p1;
            s[state(&m, "C_2.q")] = c * p2;
            let q = output(&m, &s, "q_valve");
            let want = textbook_q1(&p, x, p1);
            // Regularisation: the clearance widens the open edge by w c^2/(4|x|) (relative
            // c^2/(4 x^2)) and leaves w c^2/(4|x|) open on the closed edge, whose pressure drop is
            // at most 115/25 times the open edge's here (relative at most sqrt(4.6) c^2/(4 x^2));
            // together below 0.79 c^2/x^2. The laminar term adds dp_cr^2/(4 dp^2) < 1e-6.
            let tol = p.c_r * p.c_r / (x * x) + 1e-6;
            assert!(
                (q - want).abs() <= tol * want.abs(),
                "x {x} p_L {pl}: {q} vs {want} (rel {:e})",
                (q / want - 1.0).abs()
            );
        }
    }
}

#[test]
fn flow_and_pressure_gains_at_null() {
    // Remove the leakage so that the chamber pressure sensitivity is the valve's alone.
    let p = ServoValveParameters {
        r_leak: 1e30,
        ..ServoValveParameters::default()
    };
    let (m, x, _) = closed_loop(&p);
    let mut jac = DMatrix::zeros(m.n_states(), m.n_states());
    m.jacobian(&x, &[0.0], &mut jac);
    let (i1, ixv) = (state(&m, "C_1.q"), state(&m, "springs.q[2]"));
    let c = p.v_1 / p.beta;
    // Flow gain dQ_1/dx_v = Cd w sqrt(2/rho) g(p_s/2) (g the regularised square root): exact at
    // null because ramp(x) - ramp(-x) = x; g(p_s/2) = sqrt(p_s/2) (1 - dp_cr^2/(4 (p_s/2)^2) ...).
    let k = p.cd * p.w * (2.0 / p.rho).sqrt();
    let (g, dg) = regularised_sqrt(0.5 * p.p_supply, p.dp_cr);
    let kq = k * g;
    assert!(
        (jac[(i1, ixv)] / kq - 1.0).abs() < 1e-9,
        "{} vs {kq}",
        jac[(i1, ixv)]
    );
    let kq_textbook = p.cd * p.w * (p.p_supply / p.rho).sqrt();
    assert!((kq / kq_textbook - 1.0).abs() < 1e-6);
    // Flow-pressure coefficient of one chamber: two edges, each open c_r/2, at p_s/2:
    // K_c = 2 k (c_r/2) g'(p_s/2), textbook Cd w c_r / sqrt(rho p_s).
    let kc = k * p.c_r * dg;
    let kc_textbook = p.cd * p.w * p.c_r / (p.rho * p.p_supply).sqrt();
    assert!((kc / kc_textbook - 1.0).abs() < 1e-6);
    let dq_dp1 = jac[(i1, i1)] * c; // d(dq1/dt)/dp1
    assert!((-dq_dp1 / kc - 1.0).abs() < 1e-9, "{dq_dp1} vs {kc}");
    // Blocked load: the load pressure gain is 2 K_q / K_c, textbook 2 p_s / c_r.
    let gain = 2.0 * jac[(i1, ixv)] / -dq_dp1;
    assert!((gain / (2.0 * p.p_supply / p.c_r) - 1.0).abs() < 1e-6);

    // Pilot stage: blocked-spool pressure gain dp_a/dx_f = p_s / (2 x_f0) (inlet and nozzle at
    // equal area), up to the gap rounding.
    let (ia, ixf) = (state(&m, "C_Ha.q"), state(&m, "springs.q[1]"));
    let ch = p.v_h / p.beta;
    let dpa_dxf = -jac[(ia, ixf)] / (jac[(ia, ia)] * ch);
    let want = p.p_supply / (2.0 * p.x_f0);
    assert!(
        (dpa_dxf / want - 1.0).abs() < 1e-3,
        "{dpa_dxf:e} vs {want:e}"
    );
}

#[test]
fn orifice_law_is_odd_monotonic_and_dissipative() {
    let mut last = f64::NEG_INFINITY;
    for i in -2000..=2000 {
        let dp = i as f64 * 1e2;
        let (q, dq) = regularised_sqrt(dp, 5e3);
        assert!(q > last && dq > 0.0 && q * dp >= 0.0);
        assert_eq!(regularised_sqrt(-dp, 5e3).0, -q);
        last = q;
    }
}

/// A small deterministic generator (no dependency): uniform in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

#[test]
fn power_balance_at_random_states() {
    let p = ServoValveParameters::default();
    let (m, rest, nominal) = closed_loop(&p);
    let mut rng = Lcg(6);
    for _ in 0..200 {
        let x: Vec<f64> = rest
            .iter()
            .zip(&nominal)
            .map(|(x0, &nom)| {
                // Pressures anywhere from -0.5 p_s to 1.5 p_s, positions and speeds +-2 nominal.
                x0 + 2.0 * nom * rng.next()
            })
            .collect();
        let r = 2.0 * rng.next();
        let b = m.power_balance(&x, &[r]);
        let scale: f64 = b.elements.iter().map(|(_, w)| w.abs()).sum();
        assert!(
            b.residual.abs() <= 1e-12 * scale,
            "residual {} of {scale}: {:?}",
            b.residual,
            b
        );
        // Supply power = stored + dissipated + delivered (to the coil source, tank): the
        // residual says it; every orifice and damper only dissipates.
        for (name, w) in &b.elements {
            let is_r = name.contains(".R")
                || name.ends_with(".spool_stop")
                || name.ends_with(".b_f")
                || name.ends_with(".b_v")
                || name.ends_with(".b_m");
            if is_r {
                assert!(*w >= -1e-12 * scale, "{name} generates {w}");
            }
        }
    }
}

#[test]
fn coupled_power_balance_at_random_states() {
    for (formulation, root) in [("1", "1"), ("2", "1"), ("1", "2"), ("2", "2")] {
        let p = fmu_parameters(&[
            ("hydraulics.model", "2"),
            ("hydraulics.motor_coupled", "true"),
            ("plate.formulation", formulation),
            ("plate.root", root),
            ("plate.Cd", "1.2"),
            ("plate.Ca", "1"),
        ]);
        let sys = Assembled::new(&p).unwrap();
        let m = sys.compiled();
        let rest = sys.initial_state();
        let mut rng = Lcg(9);
        let (mut drag_power, mut stop_rate, mut friction_power) = (0.0f64, 0.0f64, 0.0f64);
        let rotor = m
            .state_index("servo_valve.I_m.p")
            .expect("the rotor's momentum");
        let i_m = p.servo_valve.i_m;
        for k in 0..100 {
            // Every state within +-2 nominal of rest: pressures from -0.5 to 1.5 p_s (some chambers
            // in cavitation), spool and flapper past their stops, the bar twisted, the plate bent.
            let mut x: Vec<f64> = rest
                .iter()
                .zip(sys.nominal())
                .map(|(x0, nom)| x0 + 2.0 * nom * rng.next())
                .collect();
            // Every other state turns the rotor within twice the friction's Stribeck speed.
            if k % 2 == 1 {
                x[rotor] = 2.0 * p.servo_valve.omega_s * i_m * rng.next();
            }
            let u: Vec<f64> = (0..m.input_names().len())
                .map(|_| 2.0 * rng.next())
                .collect();
            let b = m.power_balance(&x, &u);
            let scale: f64 = b.elements.iter().map(|(_, w)| w.abs()).sum();
            assert!(
                b.residual.abs() <= 1e-12 * scale,
                "formulation {formulation}, root {root}: residual {} of {scale}",
                b.residual
            );
            // Every orifice and damper only dissipates, the spool stop's contact damping too (its
            // spring is stored energy, a law of the spring field).
            for (name, w) in &b.elements {
                let dissipative = name.contains(".R")
                    || name.ends_with(".spool_stop")
                    || name.ends_with(".b_f")
                    || name.ends_with(".b_v")
                    || name.ends_with(".b_m")
                    || name.ends_with(".friction")
                    || name == "torsion_bar.c";
                if dissipative {
                    assert!(*w >= -1e-12 * scale, "{name} generates {w}");
                }
                if name.starts_with("plate.drag[") {
                    drag_power += w;
                }
                if name == "servo_valve.friction" {
                    friction_power += w;
                }
                if name == "servo_valve.springs.law[2]" {
                    stop_rate = stop_rate.max(w.abs());
                }
            }
        }
        // The balance above holds with the drag dissipating and the stop spring storing.
        assert!(drag_power > 0.0, "formulation {formulation}: no drag");
        assert!(stop_rate > 0.0, "formulation {formulation}: no stop spring");
        assert!(
            friction_power > 0.0,
            "formulation {formulation}: no seal friction"
        );
    }
}

#[test]
fn linearisation_matches_g_est() {
    // The paper's loop: the voltage-driven coil and eq. 1's controller (no pressure feedback).
    let p = ServoValveParameters::voltage_driven();
    let ctrl = ControllerParameters::paper();
    let pts = compare_with_g_est(&p, &ctrl, &log_frequencies(0.5, 100.0, 60)).unwrap();
    let mut report = String::new();
    for q in &pts {
        report += &format!(
            "{:7.2} Hz  {:+6.2} dB  {:+6.2} deg\n",
            q.f_hz,
            q.mag_err_db(),
            q.phase_err_deg()
        );
        if q.f_hz <= 60.0 {
            assert!(q.mag_err_db().abs() <= 1.0, "{report}");
            assert!(q.phase_err_deg().abs() <= 10.0, "{report}");
        } else {
            assert!(q.mag_err_db().abs() <= 3.0, "{report}");
        }
    }
    eprintln!("{report}");
}

/// The current-feedback amplifier replaces the coil's lag `R_bob/L_bob` by the current loop's:
/// the direct path with current drive over the one with voltage drive is, from the coil's two
/// current laws alone, `G_i K_i (R_bob + L_bob s) / (R_bob + K_i + L_bob s)`. The two
/// linearisations of the whole valve agree with it to 1e-4 in magnitude and 0.01 deg (measured:
/// 3e-5 and 0.002 deg at 100 Hz): what is left is the flapper's back-EMF `k_phi v_f`, which the
/// closed form leaves out. With the current drive the valve no
/// longer follows G_est: the test asserts that it leaves the 1 dB / 10 deg band.
#[test]
fn current_drive_replaces_the_coil_lag_by_the_current_loop() {
    let ctrl = ControllerParameters::linear();
    let volt = ServoValveParameters::voltage_driven();
    let cur = ServoValveParameters {
        drive: CoilDrive::Current,
        ..volt.clone()
    };
    // the default valve and motor, without the seal friction the paper's motor lacks
    assert_eq!(cur, ServoValveParameters::default().sliding());
    let lin_v = open_loop_linearization(&volt, &ctrl).unwrap();
    let lin_c = open_loop_linearization(&cur, &ctrl).unwrap();
    let y = lin_v
        .output_names
        .iter()
        .position(|n| n == "y_pot")
        .unwrap();
    let mut report = String::new();
    for f in log_frequencies(0.5, 100.0, 25) {
        let s = Complex::new(0.0, 2.0 * std::f64::consts::PI * f);
        let ratio = response_at(&lin_c, 0, y, f).unwrap() / response_at(&lin_v, 0, y, f).unwrap();
        let expected = (s * cur.l_bob + cur.r_bob) * (cur.g_i * cur.k_i)
            / (s * cur.l_bob + cur.r_bob + cur.k_i);
        let err = ratio / expected;
        report += &format!(
            "{f:7.2} Hz  |ratio| {:.5}  expected {:.5}  err {:+.4} %  {:+.3} deg\n",
            ratio.norm(),
            expected.norm(),
            100.0 * (err.norm() - 1.0),
            err.arg().to_degrees()
        );
        assert!((err.norm() - 1.0).abs() < 1e-4, "{report}");
        assert!(err.arg().to_degrees().abs() < 0.01, "{report}");
    }
    eprintln!("{report}");
    let fit = compare_with_g_est(&cur, &ctrl, &log_frequencies(0.5, 60.0, 30)).unwrap();
    let worst = fit
        .iter()
        .map(|q| q.mag_err_db().abs().max(q.phase_err_deg().abs() / 10.0))
        .fold(0.0, f64::max);
    assert!(worst > 1.0, "the current drive still fits G_est ({worst})");
}

fn fmu_parameters(sets: &[(&str, &str)]) -> Parameters {
    let mut values = Values::from_start(&VARIABLES);
    for (n, v) in sets {
        set_by_name(&mut values, n, v).unwrap();
    }
    Parameters::from_values(&values, &Experiment::default()).unwrap()
}

#[test]
fn flow_reversal_and_zero_pressure_drop_stay_finite() {
    // A square wave of +-0.5 V at 2 Hz, a 10 bar supply and a heavy, nearly frictionless rotor (3.5 kg m^2, the
    // hub inertia I_H; b_m = 0.01 N m s/rad): when the command reverses, the coasting rotor
    // drives the motor as a pump against the closing valve, the chamber pressures swing past the
    // supply and tank pressures (metering edges see their pressure drop cross zero and their
    // flow reverse) and the spool crosses null. (Chamber pressures may fall below the tank's,
    // down to the cavitation floor, limits::CAVITATION_PRESSURE.)
    let params = fmu_parameters(&[
        ("hydraulics.model", "2"),
        ("servo_valve.I_m", "3.5"),
        ("servo_valve.b_m", "0.01"),
        ("servo_valve.p_supply", "10e5"),
    ]);
    let mut sys = Assembled::new(&params).unwrap();
    let m = sys.compiled().clone();
    let mut integ = Integrator::new(params.solver_options(&sys), 0.0, sys.initial_state()).unwrap();
    let (mut p1_max, mut p1_min, mut pl_min, mut pl_max) = (f64::MIN, f64::MAX, f64::MAX, f64::MIN);
    let (mut xv_min, mut xv_max) = (f64::MAX, f64::MIN);
    let mut t = 0.0;
    // The model's inputs are r, F1 and F2 (the shakers stay off).
    let r_index = m.input_names().iter().position(|n| n == "r").unwrap();
    let mut u = vec![0.0; m.input_names().len()];
    for k in 0..1000 {
        let r = if (k / 250) % 2 == 0 { 0.5 } else { -0.5 };
        u[r_index] = r;
        sys.restore_inputs(&u);
        integ.notify_discontinuity();
        t += 1e-3;
        integ.advance_to(&sys, t).expect("step");
        let x = integ.x();
        assert!(x.iter().all(|v| v.is_finite()));
        let mut y = vec![0.0; m.n_outputs()];
        m.outputs(x, &u, &mut y);
        let get = |n: &str| y[m.output_index(n).unwrap()];
        p1_max = p1_max.max(get("servo_valve.p_1"));
        p1_min = p1_min.min(get("servo_valve.p_1"));
        pl_min = pl_min.min(get("p_load"));
        pl_max = pl_max.max(get("p_load"));
        xv_min = xv_min.min(get("servo_valve.x_v"));
        xv_max = xv_max.max(get("servo_valve.x_v"));
    }
    eprintln!("p_1 in [{p1_min:e}, {p1_max:e}], p_L in [{pl_min:e}, {pl_max:e}], x_v in [{xv_min:e}, {xv_max:e}]");
    assert!(pl_min < 0.0 && pl_max > 0.0, "load pressure reverses");
    assert!(xv_min < 0.0 && xv_max > 0.0, "spool crosses null");
    assert!(
        p1_max > params.servo_valve.p_supply || p1_min < params.servo_valve.p_tank,
        "an edge sees its pressure drop reverse: p_1 in [{p1_min}, {p1_max}]"
    );
}

#[test]
fn non_positive_supply_pressure_is_rejected() {
    for v in [0.0, -1e5] {
        let e = check(idx::SERVO_VALVE_P_SUPPLY, &Value::Real(v)).unwrap_err();
        assert!(e.contains("servo_valve.p_supply"), "{e}");
        let p = ServoValveParameters {
            p_supply: v,
            ..ServoValveParameters::default()
        };
        let e = servo_valve::build_loop(&p, &ControllerParameters::default()).unwrap_err();
        assert!(e.contains("servo_valve.p_supply"), "{e}");
    }
    let mut values = Values::from_start(&VARIABLES);
    assert!(set_by_name(&mut values, "servo_valve.p_supply", "0").is_err());
}
