//! Fits constants of the full servo valve to `G_est` (eq. 2 of the paper) and prints the
//! comparison of the linearised direct path with `G_est`, the open-loop poles, and the
//! eigenvalues of the coupled loop (motor driving the hub through the torsion bar) for both plate
//! formulations, hub free and locked. A tool, not a test; the library holds only the model.
//!
//! ```text
//! cargo run --release --bin servo-valve-fit                      # the defaults
//! cargo run --release --bin servo-valve-fit -- --fit L_bob,k_w,k_phi
//! cargo run --release --bin servo-valve-fit -- --set servo_valve.V_1=2e-4 --fit k_phi
//! ```
//!
//! `--set NAME=VALUE` sets any FMU parameter first (as `hsp run --set`); `--fit A,B,...` fits the
//! named `servo_valve.*` constants by Nelder-Mead in their logarithms, minimising
//! [`g_est_cost`] over 40 log-spaced frequencies from 0.5 to 100 Hz, and prints them.

use hydraulic_slewing_plate::eigen;
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::fragments::servo_valve::{
    compare_with_g_est, log_frequencies, open_loop_linearization, GEstPoint,
};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::VARIABLES;
use nalgebra::{Complex, DMatrix};

/// The mismatch measure of the fit: the sum of squared magnitude errors in dB plus squared phase
/// errors in units of 10 degrees, points above 60 Hz weighted by a half (the issue's tolerance
/// there is 3 dB, against 1 dB and 10 degrees below).
fn g_est_cost(points: &[GEstPoint]) -> f64 {
    points
        .iter()
        .map(|q| {
            let w = if q.f_hz > 60.0 { 0.5 } else { 1.0 };
            w * (q.mag_err_db().powi(2) + (q.phase_err_deg() / 10.0).powi(2))
        })
        .sum()
}

/// A plain Nelder-Mead minimiser (reflection 1, expansion 2, contraction 1/2, shrink 1/2).
fn nelder_mead(f: impl Fn(&[f64]) -> f64, x0: &[f64], step: f64, iters: usize) -> Vec<f64> {
    let n = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = (0..=n)
        .map(|i| {
            let mut x = x0.to_vec();
            if i > 0 {
                x[i - 1] += step;
            }
            let v = f(&x);
            (x, v)
        })
        .collect();
    for _ in 0..iters {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let centroid: Vec<f64> = (0..n)
            .map(|j| simplex[..n].iter().map(|s| s.0[j]).sum::<f64>() / n as f64)
            .collect();
        let towards = |t: f64| -> Vec<f64> {
            (0..n)
                .map(|j| centroid[j] + t * (simplex[n].0[j] - centroid[j]))
                .collect()
        };
        let xr = towards(-1.0);
        let fr = f(&xr);
        if fr < simplex[0].1 {
            let xe = towards(-2.0);
            let fe = f(&xe);
            simplex[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[n - 1].1 {
            simplex[n] = (xr, fr);
        } else {
            let xc = towards(0.5);
            let fc = f(&xc);
            if fc < simplex[n].1 {
                simplex[n] = (xc, fc);
            } else {
                let best = simplex[0].0.clone();
                for s in simplex.iter_mut().skip(1) {
                    for (xj, bj) in s.0.iter_mut().zip(&best) {
                        *xj = bj + 0.5 * (*xj - bj);
                    }
                    s.1 = f(&s.0);
                }
            }
        }
        let spread = simplex
            .iter()
            .map(|s| s.1)
            .fold(f64::NEG_INFINITY, f64::max)
            - simplex.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
        if spread < 1e-10 {
            break;
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex.swap_remove(0).0
}

fn parameters(values: &Values) -> Parameters {
    Parameters::from_values(values, &Experiment::default()).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    })
}

/// Eigenvalues of the coupled loop at rest (balanced, [`eigen::eigenvalues`]), sorted by
/// magnitude; states whose column of `A` is zero (output integrals nothing feeds back, e.g.
/// `hub.theta`) are left out and named.
type Mode = (Complex<f64>, String);

fn coupled_eigenvalues(values: &Values) -> Result<(Vec<String>, Vec<Mode>), String> {
    let p = parameters(values);
    let sys = Assembled::new(&p)?;
    let lin = sys.compiled().linearize(&sys.initial_state(), sys.inputs());
    let n = lin.a.nrows();
    let free: Vec<usize> = (0..n)
        .filter(|&j| lin.a.column(j).iter().all(|v| *v == 0.0))
        .collect();
    let keep: Vec<usize> = (0..n).filter(|j| !free.contains(j)).collect();
    let a = DMatrix::from_fn(keep.len(), keep.len(), |i, j| lin.a[(keep[i], keep[j])]);
    // Eigenvectors in nominal units, by inverse iteration on `a` (unbalanced) near each
    // eigenvalue: the three states that move most name the mode.
    let nominal: Vec<f64> = keep.iter().map(|&i| sys.nominal()[i]).collect();
    let m = keep.len();
    let mut ev: Vec<Mode> = eigen::eigenvalues(&a)
        .into_iter()
        .map(|l| {
            let shift = l + Complex::new(1e-9 * (1.0 + l.norm()), 0.0);
            let mat = DMatrix::from_fn(m, m, |i, j| {
                let v = Complex::new(a[(i, j)], 0.0);
                if i == j {
                    v - shift
                } else {
                    v
                }
            });
            let lu = mat.lu();
            let mut v = nalgebra::DVector::from_element(m, Complex::new(1.0, 0.0));
            for _ in 0..3 {
                if let Some(w) = lu.solve(&v) {
                    let n = w.norm();
                    v = w / Complex::new(n, 0.0);
                }
            }
            let mut parts: Vec<(f64, usize)> =
                (0..m).map(|i| (v[i].norm() / nominal[i], i)).collect();
            parts.sort_by(|x, y| y.0.total_cmp(&x.0));
            let top = parts[0].0.max(1e-300);
            let mut label = parts
                .iter()
                .take(3)
                .map(|(w, i)| format!("{} {:.2}", lin.state_names[keep[*i]], w / top))
                .collect::<Vec<_>>()
                .join(", ");
            // How much of the hub's swing the potentiometer sees in this mode: the motor's
            // speed over the hub's (the angles' ratio, both being the speeds over lambda).
            let speed = |name: &str| {
                lin.output_names.iter().position(|n| n == name).map(|o| {
                    (0..m)
                        .map(|i| v[i] * lin.c[(o, keep[i])])
                        .sum::<Complex<f64>>()
                })
            };
            if let (Some(motor), Some(hub)) = (speed("omega_motor"), speed("omega_hub")) {
                if hub.norm() > 0.0 {
                    label += &format!("; motor/hub swing {:.2}", motor.norm() / hub.norm());
                }
            }
            (l, label)
        })
        .collect();
    ev.sort_by(|a, b| a.0.norm().total_cmp(&b.0.norm()));
    Ok((
        free.iter().map(|&i| lin.state_names[i].clone()).collect(),
        ev,
    ))
}

fn main() {
    let mut values = Values::from_start(&VARIABLES);
    set_by_name(&mut values, "hydraulics.model", "2").expect("hydraulics.model");
    // The paper's loop, whose direct path G_est is: the voltage-driven coil, eq. 1's controller.
    set_by_name(&mut values, "servo_valve.drive", "1").expect("servo_valve.drive");
    set_by_name(&mut values, "controller.k_pl", "0").expect("controller.k_pl");
    // The paper's motor has viscous friction only.
    set_by_name(&mut values, "servo_valve.T_c", "0").expect("servo_valve.T_c");
    set_by_name(&mut values, "servo_valve.T_s", "0").expect("servo_valve.T_s");
    let mut fit: Vec<String> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--set" => {
                let s = args.next().expect("--set NAME=VALUE");
                let (n, v) = s.split_once('=').expect("--set NAME=VALUE");
                set_by_name(&mut values, n, v).unwrap_or_else(|e| panic!("{e}"));
            }
            "--fit" => {
                fit = args
                    .next()
                    .expect("--fit NAME,NAME,...")
                    .split(',')
                    .map(|s| format!("servo_valve.{s}"))
                    .collect()
            }
            other => {
                eprintln!("unknown argument '{other}' (use --set NAME=VALUE, --fit A,B,...)");
                std::process::exit(2);
            }
        }
    }
    let ctrl = parameters(&values).controller;
    if !fit.is_empty() {
        let index: Vec<usize> = fit
            .iter()
            .map(|n| {
                VARIABLES
                    .iter()
                    .position(|v| v.name == n)
                    .unwrap_or_else(|| panic!("unknown variable {n}"))
            })
            .collect();
        let start: Vec<f64> = index.iter().map(|&i| values.real(i)).collect();
        let freqs = log_frequencies(0.5, 100.0, 40);
        let apply = |z: &[f64]| {
            let mut v = values.clone();
            for ((&i, s), zi) in index.iter().zip(&start).zip(z) {
                v.set_real(i, s * zi.exp());
            }
            v
        };
        let cost = |z: &[f64]| -> f64 {
            let p = parameters(&apply(z)).servo_valve;
            compare_with_g_est(&p, &ctrl, &freqs)
                .map(|pts| g_est_cost(&pts))
                .unwrap_or(f64::INFINITY)
        };
        let z = nelder_mead(cost, &vec![0.0; fit.len()], 0.2, 600);
        let best = cost(&z);
        values = apply(&z);
        println!("fitted (cost {best:.4e}):");
        for (n, &i) in fit.iter().zip(&index) {
            println!("  {n} = {:.10e}", values.real(i));
        }
    }
    let p = parameters(&values).servo_valve;
    let lin = open_loop_linearization(&p, &ctrl).expect("linearisation");
    let mut ev = eigen::eigenvalues(&lin.a);
    ev.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
    println!("open-loop eigenvalues, motor uncoupled (1/s):");
    for e in ev {
        println!("  {:14.2} {:+14.2}j", e.re, e.im);
    }
    let freqs = [
        0.5, 1.0, 2.0, 5.0, 8.68, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 80.0, 100.0,
    ];
    println!(
        "| f (Hz) | full (dB) | G_est (dB) | diff (dB) | full (deg) | G_est (deg) | diff (deg) |"
    );
    println!("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for q in compare_with_g_est(&p, &ctrl, &freqs).expect("comparison") {
        println!(
            "| {:.2} | {:.2} | {:.2} | {:+.2} | {:.1} | {:.1} | {:+.1} |",
            q.f_hz,
            q.mag_db,
            q.mag_db_est,
            q.mag_err_db(),
            q.phase_deg,
            q.phase_deg_est,
            q.phase_err_deg()
        );
    }
    set_by_name(&mut values, "hydraulics.motor_coupled", "true").expect("motor_coupled");
    for (formulation, fname) in [("1", "paper"), ("2", "consistent")] {
        for (root, rname) in [("1", "hub free"), ("2", "hub locked")] {
            let mut v = values.clone();
            set_by_name(&mut v, "plate.formulation", formulation).expect("formulation");
            set_by_name(&mut v, "plate.root", root).expect("root");
            match coupled_eigenvalues(&v) {
                Ok((free, ev)) => {
                    let worst = ev.iter().map(|e| e.0.re).fold(f64::NEG_INFINITY, f64::max);
                    println!(
                        "coupled, {fname} formulation, {rname}: max Re {worst:.4e} 1/s, \
                         zero columns {free:?}; slowest:"
                    );
                    for (e, label) in ev.iter().filter(|e| e.0.im >= 0.0).take(6) {
                        println!(
                            "  {:12.4} {:+12.4}j   ({:.3} Hz, zeta {:.4})  {label}",
                            e.re,
                            e.im,
                            e.norm() / (2.0 * std::f64::consts::PI),
                            -e.re / e.norm()
                        );
                    }
                }
                Err(e) => println!("coupled, {fname} formulation, {rname}: {e}"),
            }
        }
    }
}
