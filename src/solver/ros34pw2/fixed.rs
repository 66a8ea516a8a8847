//! The fixed-step driver of ROS34PW2 for real time ([`Ros34pw2Fixed`](super::Ros34pw2Fixed)):
//! every call to `t_end` takes [`SolverOptions::substeps`](crate::solver::SolverOptions::substeps)
//! equal steps h = (t_end − t) / substeps, none rejected, as Rodas5P's fixed-step driver
//! (`solver::fixed`) does, with the W-method's reuse: W's LU is kept while the step size stays
//! (to within `SAME_STEP`, the rounding of t), and J is re-evaluated, with a new LU, every
//! `fixed_jacobian_interval` steps ([`Ros34pw2Options`](super::Ros34pw2Options)). A step
//! therefore costs one f evaluation at its start, three more and four solves with W, plus, at
//! every `fixed_jacobian_interval`-th step, a Jacobian and an LU: the work of every step is
//! bounded, and that of most steps is a fraction of Rodas5P's (eight stages, a Jacobian and an
//! LU at every step).
//!
//! No error control: the embedded error estimate is still computed, and the largest of a call
//! is reported ([`Integrator::fixed_step_error`](crate::solver::Integrator::fixed_step_error)).
//! A step whose stages are not finite, or whose W is singular, ends the call with an error; a
//! call too short for the method's 1/h terms is one explicit Euler step, as Rodas5P's driver
//! takes.

use super::state::State;
use super::{
    constant_kept, eval_f0, evaluate_jacobian, factorised_w, step, with_work, Ros34pw2Options,
};
use crate::solver::common::{euler_floor, Outputs};
use crate::solver::fixed::{euler_call, fixed_step_failure};
use crate::solver::method::Stepper;
use crate::solver::rodas5p::{dense, Reject};
use crate::solver::{OdeSystem, SolverError};

/// Advances `integ` to exactly `t_end` in `integ.options.substeps` equal steps.
pub(super) fn advance(
    integ: &mut Stepper<State>,
    sys: &dyn OdeSystem,
    t_end: f64,
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
) -> Result<(), SolverError> {
    let opts = Ros34pw2Options::default();
    with_work(integ, |integ, w| {
        let n = integ.x.len();
        let autonomous = sys.is_autonomous();
        let substeps = integ.options.substeps.max(1);
        let t0 = integ.t;
        let h = (t_end - t0) / f64::from(substeps);
        let mut outputs = Outputs::new(times, t0, n);
        integ.state.hist.err_prev = 0.0;
        if h <= euler_floor(t0) {
            eval_f0(integ, sys, w)?;
            euler_call(integ, &w.f0, &mut w.x1, t_end, &mut outputs, out);
            return Ok(());
        }
        for k in 1..=substeps {
            let t = integ.t;
            eval_f0(integ, sys, w)?;
            let kept = &integ.state.kept;
            let old = kept.age >= opts.fixed_jacobian_interval && !constant_kept(integ, sys);
            if kept.jac.is_empty() || old {
                evaluate_jacobian(integ, sys, w, autonomous)?;
            }
            let result = match factorised_w(integ, sys, w, h) {
                true => step(integ, sys, w, h, autonomous),
                false => Err(Reject::Singular),
            };
            let err = result.map_err(|why| fixed_step_failure(why, t, k, substeps, h))?;
            let t1 = if k == substeps {
                t_end
            } else {
                t0 + f64::from(k) * h
            };
            if outputs.pending(t1) {
                // The dense output needs f at the step's end.
                crate::solver::common::eval(sys, &mut integ.stats, t1, &w.x1, &mut w.f1);
                super::hermite(&integ.x, &w.x1, &w.f0, &w.f1, h, &mut w.coef);
                let (x0, x1, coef) = (&integ.x, &w.x1, &w.coef);
                outputs.emit(
                    t,
                    h,
                    t1,
                    x1,
                    &mut |theta, buf| dense(x0, x1, coef, theta, buf),
                    out,
                );
            }
            integ.x.copy_from_slice(&w.x1);
            integ.t = t1;
            integ.stats.accepted += 1;
            integ.state.kept.age += 1;
            integ.state.kept.current = false;
            integ.state.hist.err_prev = integ.state.hist.err_prev.max(err);
        }
        integ.h = h;
        Ok(())
    })
}
