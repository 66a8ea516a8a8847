//! The real-time W-method (`solver.method = 4`: ROS34PW2 at a fixed step, its LU kept and its
//! Jacobian renewed every 10 steps) on the complete default plant, through the exported `fmi2*`
//! functions: the default experiment's own move, 6 s at 1 ms communication steps with one step
//! each, against the adaptive Rodas5P at rtol 1e-10 (`solver.atol` 1e-12), the reference of
//! `bench-latency --accuracy`. The bar is issue 40's accuracy test: every output within 1e-6 of
//! its range of an rtol 1e-10 reference.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::*;

const STEP: f64 = 1e-3;
const POINTS: usize = 6000;
const OUTPUTS: [&str; 5] = ["y_pot", "theta_motor", "theta_hub", "w_tip", "p_load"];

/// The outputs at every point of the default experiment with `method` (and its tolerances).
fn run(method: i32, tolerances: Option<(f64, f64)>) -> Vec<[f64; 5]> {
    let f = Fmu::new();
    assert_eq!(f.set_integer("solver.method", method), Fmi2Status::Ok);
    if let Some((rtol, atol)) = tolerances {
        assert_eq!(f.set_real("solver.rtol", rtol), Fmi2Status::Ok);
        assert_eq!(f.set_real("solver.atol", atol), Fmi2Status::Ok);
    }
    assert_eq!(f.init(0.0), Fmi2Status::Ok, "{}", f.last());
    (0..POINTS)
        .map(|k| {
            let status = f.step(k as f64 * STEP, STEP);
            assert_eq!(status, Fmi2Status::Ok, "{}", f.last());
            OUTPUTS.map(|name| f.get_real(name).1)
        })
        .collect()
}

#[test]
fn real_time_w_method_meets_the_reference_within_1e_6_of_each_range() {
    let reference = run(1, Some((1e-10, 1e-12)));
    let real_time = run(4, None);
    for (i, name) in OUTPUTS.iter().enumerate() {
        let (lo, hi) = reference
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
                (lo.min(y[i]), hi.max(y[i]))
            });
        let range = hi - lo;
        assert!(range > 0.0, "{name} does not move");
        let worst = real_time
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a[i] - b[i]).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-6 * range,
            "{name}: largest deviation {worst:e} is {:.2e} of its range {range:e}",
            worst / range
        );
    }
}
