//! The fixed-step driver of the integrators ([`Method::Rodas5PFixed`]) on problems with closed-form
//! solutions, without FMI or physics: its order, its stop times, its constant work per call and
//! its stability far beyond the step an explicit method could take.

use hydraulic_slewing_plate::solver::testset::Vdpol;
use hydraulic_slewing_plate::solver::{Atol, Integrator, Method, OdeSystem, SolverOptions};
use nalgebra::DMatrix;

/// A harmonic oscillator (x0, x1) of angular frequency `OMEGA` and, apart, the Prothero–Robinson
/// problem x2' = λ (x2 − sin t) + cos t with λ = −1e5 (stiff, with an explicit time dependence):
/// x0 = cos ωt, x1 = −ω sin ωt, x2 = sin t from (1, 0, 0).
struct Problem;

const OMEGA: f64 = 10.0;
const LAMBDA: f64 = -1e5;

impl OdeSystem for Problem {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = -OMEGA * OMEGA * x[0];
        dx[2] = LAMBDA * (x[2] - t.sin()) + t.cos();
    }
    fn jacobian(&self, _t: f64, _x: &[f64], j: &mut DMatrix<f64>) -> bool {
        j.fill(0.0);
        j[(0, 1)] = 1.0;
        j[(1, 0)] = -OMEGA * OMEGA;
        j[(2, 2)] = LAMBDA;
        true
    }
    fn time_derivative(&self, t: f64, _x: &[f64], dfdt: &mut [f64]) -> bool {
        dfdt[0] = 0.0;
        dfdt[1] = 0.0;
        dfdt[2] = -LAMBDA * t.cos() - t.sin();
        true
    }
}

fn fixed(substeps: u32) -> Integrator {
    fixed_from(substeps, vec![1.0, 0.0, 0.0])
}

fn fixed_from(substeps: u32, x0: Vec<f64>) -> Integrator {
    let options = SolverOptions {
        method: Method::Rodas5PFixed,
        rtol: 1e-6,
        atol: Atol::Scalar(1e-9),
        substeps,
        ..SolverOptions::default()
    };
    Integrator::new(options, 0.0, x0).unwrap()
}

/// Van der Pol's oscillator with ε = 1 (nonlinear, not stiff) from (2, 0) to t = 1 in `calls`
/// calls of `substeps` fixed steps: the largest error against a Radau5 solution at 1e-14.
fn vdpol_error(calls: u32, substeps: u32) -> f64 {
    let sys = Vdpol { eps: 1.0 };
    let tight = SolverOptions {
        method: Method::Radau5,
        rtol: 1e-14,
        atol: Atol::Scalar(1e-14),
        max_steps: 10_000_000,
        ..SolverOptions::default()
    };
    let mut reference = Integrator::new(tight, 0.0, vec![2.0, 0.0]).unwrap();
    reference.advance_to(&sys, 1.0).unwrap();
    let mut integ = fixed_from(substeps, vec![2.0, 0.0]);
    for k in 1..=calls {
        let t = f64::from(k) / f64::from(calls);
        integ.advance_to(&sys, t).unwrap();
        assert_eq!(integ.t(), t, "each call ends on its t_end, bit for bit");
    }
    (0..2)
        .map(|i| (integ.x()[i] - reference.x()[i]).abs())
        .fold(0.0, f64::max)
}

/// Halving the step divides the error by about 2^5 on a nonlinear problem: Rodas5P is of order 5
/// (the observed order between 4.5 and 5.5; on a linear problem its stability function is more
/// accurate still, and the oscillator of [`Problem`] shows nearly 6). The same number of steps
/// gives the same error whether taken as more calls or as more substeps per call.
#[test]
fn the_fixed_step_converges_at_order_five() {
    let errors: Vec<f64> = [10, 20, 40].iter().map(|&n| vdpol_error(n, 1)).collect();
    for w in errors.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!(
            (4.5..=5.5).contains(&order),
            "observed order {order:.2} from errors {errors:?}"
        );
    }
    let as_substeps = vdpol_error(5, 4);
    assert!(
        (as_substeps / errors[1] - 1.0).abs() < 1e-6,
        "20 steps as 5 calls of 4 substeps: {as_substeps:e}, as 20 calls: {:e}",
        errors[1]
    );
}

/// Every call adds the same to the counters: `substeps` accepted steps, none rejected, 8 right-hand
/// sides, one Jacobian and one factorisation per step (the Jacobian is not declared constant).
#[test]
fn every_call_does_the_same_work() {
    for substeps in [1, 5] {
        let mut integ = fixed(substeps);
        let mut before = *integ.stats();
        for k in 1..=50 {
            integ.advance_to(&Problem, f64::from(k) * 1e-2).unwrap();
            let s = *integ.stats();
            let grew = [
                s.accepted - before.accepted,
                s.rejected - before.rejected,
                s.f_evals - before.f_evals,
                s.jac_evals - before.jac_evals,
                s.lu_decompositions - before.lu_decompositions,
            ];
            let n = u64::from(substeps);
            assert_eq!(grew, [n, 0, 8 * n, n, n], "call {k}, {substeps} substeps");
            before = s;
        }
    }
}

/// L-stability: a step 1e4 times the stiff mode's time constant (h λ = −1e4), where explicit Euler
/// would grow by a factor 1e4 per step, stays on the smooth solution (sin t), and the error
/// estimate it reports is finite.
#[test]
fn steps_far_beyond_the_stiff_time_constant_stay_stable() {
    let mut integ = fixed(1);
    let h = 0.1;
    for k in 1..=30 {
        integ.advance_to(&Problem, f64::from(k) * h).unwrap();
        assert!(integ.fixed_step_error().is_finite());
    }
    let t: f64 = 3.0;
    assert!(
        (integ.x()[2] - t.sin()).abs() < 1e-6,
        "x2 = {}, sin t = {}",
        integ.x()[2],
        t.sin()
    );
}

/// A substep count outside 1..=MAX_SUBSTEPS is refused, naming the option.
#[test]
fn substeps_out_of_range_are_refused() {
    for substeps in [0, hydraulic_slewing_plate::solver::MAX_SUBSTEPS + 1] {
        let options = SolverOptions {
            method: Method::Rodas5PFixed,
            substeps,
            ..SolverOptions::default()
        };
        let e = Integrator::new(options, 0.0, vec![0.0]).unwrap_err();
        assert!(e.message.contains("substeps"), "{}", e.message);
    }
}
