//! `hsp run --loop-gain K`: the importer closes a proportional loop around the FMU, setting
//! `e_in = K (controller.reference − y_pot)` before every communication step and holding it over
//! the step, as a digital controller with a zero-order hold does (docs/realtime.md, "What a
//! closed loop costs the adaptive solvers").
//!
//! The independent reference is the FMU's own analog loop with the same law: with the pressure
//! feedback off (`controller.k_pl = 0`) it drives the coil with `e_in = A1 A2 (r − y_pot)`,
//! `A1 A2 = 20`, continuously. A hold of length `h` delays the drive by `h / 2` on average, so the
//! digital loop's motor angle differs from the analog loop's by a term of first order in `h`:
//! ten times shorter steps give a difference about ten times smaller.

#[path = "common/packaged.rs"]
mod packaged;

use std::path::Path;
use std::process::Command;

/// Runs `hsp run --no-build` on the packaged FMU, a step of r = 0.25 V for 0.5 s at the
/// communication step `step`, with `extra` arguments; the motor angle at every point.
fn motor_angle(fmu: &Path, step: &str, extra: &[&str]) -> Vec<f64> {
    let run = [
        &[
            "--profile",
            "step",
            "--r",
            "0.25",
            "--stop",
            "0.5",
            "--step",
            step,
        ],
        extra,
    ]
    .concat();
    packaged::csv_columns(&packaged::run_csv(fmu, &run))
        .into_iter()
        .find(|(name, _)| name == "theta_motor")
        .expect("theta_motor column")
        .1
}

/// The largest difference of `a` and `b`, relative to the range of `a`.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let range =
        a.iter().cloned().fold(f64::MIN, f64::max) - a.iter().cloned().fold(f64::MAX, f64::min);
    assert!(range > 0.01, "the motor barely moved: range {range} rad");
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / range
}

#[test]
fn the_digital_loop_converges_to_the_analog_loop_at_first_order() {
    let fmu = packaged::fresh_fmu(packaged::Version::Fmi2);
    let digital = ["--set", "controller.external=true", "--loop-gain", "20"];
    let analog = ["--set", "controller.k_pl=0"];
    let mut differences = Vec::new();
    for step in ["0.001", "0.0001"] {
        let d = motor_angle(&fmu, step, &digital);
        let a = motor_angle(&fmu, step, &analog);
        differences.push(relative_difference(&a, &d));
    }
    let (coarse, fine) = (differences[0], differences[1]);
    assert!(
        fine < 1e-3,
        "at 0.1 ms the digital loop is {fine:e} of the range from the analog one"
    );
    let ratio = coarse / fine;
    assert!(
        (5.0..20.0).contains(&ratio),
        "ten times shorter holds shrink the difference {ratio}x ({coarse:e} -> {fine:e}), \
         not about 10x as a first-order hold delay does"
    );
}

#[test]
fn a_loop_gain_without_the_external_drive_is_refused_by_name() {
    // Refused before the FMU is built or loaded: no packaged FMU needed.
    let out = Command::new(env!("CARGO_BIN_EXE_hsp"))
        .args(["run", "--no-build", "--no-plot", "--loop-gain", "20"])
        .args(["--fmu", "no-such.fmu", "--stop", "0.01"])
        .output()
        .expect("cannot run hsp");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--loop-gain") && err.contains("controller.external=true"),
        "{err}"
    );
}
