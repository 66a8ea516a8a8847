//! Fits the full servo valve's `D_m`, `b_m`, `k_phi` to `G_est` (eq. 2) and prints the
//! comparison of the linearised direct path with `G_est` (issue 6). Not a test.
//!
//! ```text
//! cargo run --release --bin servo-valve-fit            # compare the defaults
//! cargo run --release --bin servo-valve-fit -- --fit   # fit, print the new constants as JSON
//! cargo run --release --bin servo-valve-fit -- --r-leak 4e8 --fit   # refit with a bypass
//! ```

use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::servo_valve::{
    compare_with_g_est, fit_to_g_est, open_loop_linearization, ServoValveParameters,
};

fn main() {
    let ctrl = ControllerParameters::default();
    let mut p = ServoValveParameters::default();
    let args: Vec<String> = std::env::args().collect();
    // `--r-leak VALUE`: start from another cross-port resistance (N s/m^5), to study the
    // trade-off between the bypass and the fit.
    if let Some(i) = args.iter().position(|a| a == "--r-leak") {
        p.r_leak = args
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .expect("--r-leak needs a number");
    }
    if args.iter().any(|a| a == "--fit") {
        p = fit_to_g_est(&p, &ctrl).expect("fit");
        println!(
            "{}",
            serde_json::json!({"r_leak": p.r_leak, "d_m": p.d_m, "b_m": p.b_m, "k_phi": p.k_phi})
        );
    }
    let lin = open_loop_linearization(&p, &ctrl).expect("linearisation");
    let eig = lin.a.complex_eigenvalues();
    let mut ev: Vec<_> = eig.iter().copied().collect();
    ev.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
    println!("open-loop eigenvalues (1/s):");
    for e in ev {
        println!("  {:12.1} {:+12.1}j", e.re, e.im);
    }
    // Static spool position per volt of valve command: the DC solution of the linearisation with
    // the rotor held (its angle and momentum pinned to zero); the spool does not feel the load.
    let mut a = lin.a.clone();
    let mut b = lin.b.column(0).clone_owned();
    for (i, name) in lin.state_names.iter().enumerate() {
        if name.ends_with("theta_a") || name.ends_with("I_m.p") {
            a.row_mut(i).fill(0.0);
            a[(i, i)] = 1.0;
            b[i] = 0.0;
        }
    }
    let x = a.lu().solve(&(-b)).expect("DC solve");
    let ixv = lin
        .state_names
        .iter()
        .position(|n| n.ends_with("springs.q[2]"))
        .expect("x_v state");
    let a12 = ctrl.a1 * ctrl.a2;
    let xv_per_volt = x[ixv] / a12; // input e is the error; the valve sees A1 A2 e
    println!(
        "static spool position {:.4e} m/V of valve command ({:.3} mm at 10 V), flow gain K_q {:.4} m^2/s, \
         k_sv = {:.4e} m^3/(s V) ({:.1} L/min at 10 V), k_sv/D_m = {:.4} (LOES {:.4})",
        xv_per_volt,
        xv_per_volt * 10.0 * 1e3,
        p.flow_gain(),
        xv_per_volt * p.flow_gain(),
        xv_per_volt * p.flow_gain() * 10.0 * 60_000.0,
        xv_per_volt * p.flow_gain() / p.d_m,
        {
            let l = hydraulic_slewing_plate::fragments::loes::LoesParameters::default();
            l.k_sv / l.d_m
        }
    );
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
}
