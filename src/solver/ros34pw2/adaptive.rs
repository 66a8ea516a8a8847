//! The adaptive driver of ROS34PW2: Rodas5P's step-size control (a PI controller, steps free to
//! run past the requested point) with the reuse of J and W of the module documentation.

use super::state::State;
use super::{
    constant_kept, eval_f0, evaluate_jacobian, factorised_w, hermite, step, with_work,
    Ros34pw2Options, Work, ERR_ORDER,
};
use crate::solver::common::{all_finite, eval, initial_step, plan_step, NextStep, Outputs};
use crate::solver::method::Stepper;
use crate::solver::rodas5p::{dense, Reject, Rejections};
use crate::solver::{OdeSystem, SolverError};

/// Advances `integ` to exactly `t_end`, or with steps free to run past it up to `limit` (the
/// step that covers `t_end` is then kept in the state's `ahead` and `t_end`'s state read from
/// its dense output), as Rodas5P's driver does.
pub(super) fn advance(
    integ: &mut Stepper<State>,
    sys: &dyn OdeSystem,
    t_end: f64,
    limit: f64,
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
) -> Result<(), SolverError> {
    let opts = Ros34pw2Options::default();
    with_work(integ, |integ, w| {
        advance_with(integ, sys, &opts, (t_end, limit), times, out, w)
    })
}

fn advance_with(
    integ: &mut Stepper<State>,
    sys: &dyn OdeSystem,
    opts: &Ros34pw2Options,
    (t_end, limit): (f64, f64),
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
    w: &mut Work,
) -> Result<(), SolverError> {
    let n = integ.x.len();
    let autonomous = sys.is_autonomous();
    let mut outputs = Outputs::new(times, integ.t, n);
    eval_f0(integ, sys, w)?;
    if integ.h <= 0.0 {
        integ.h = initial_step(sys, integ, &w.f0, t_end, ERR_ORDER);
    }
    let mut attempts: u64 = 0;
    let mut rejections = Rejections::default();
    loop {
        let why_small = || rejections.why_small();
        let step_plan = plan_step(integ, t_end, limit, &w.f0, &mut attempts, false, why_small)?;
        let (h, last, h_proposed) = match step_plan {
            NextStep::Done => return Ok(()),
            NextStep::Step { h, last, proposed } => (h, last, proposed),
        };
        let t = integ.t;
        if integ.state.kept.jac.is_empty() {
            evaluate_jacobian(integ, sys, w, autonomous)?;
        }
        let result = match factorised_w(integ, sys, w, h) {
            true => step(integ, sys, w, h, autonomous),
            false => Err(Reject::Singular),
        };
        // The end point's f: for the dense output of a step that emits output times or is kept
        // past t_end, and as the next step's f0. A step whose end f is not finite is rejected.
        let t1 = if last { limit } else { t + h };
        let done = last || (limit > t_end && t1 >= t_end);
        let result = match result {
            Ok(err) if err <= 1.0 && !(done && t1 <= t_end && !outputs.pending(t1)) => {
                eval(sys, &mut integ.stats, t1, &w.x1, &mut w.f1);
                if all_finite(&w.f1) {
                    Ok(err)
                } else {
                    Err(Reject::NonFinite)
                }
            }
            other => other,
        };
        match result {
            Ok(err) if err <= 1.0 => {
                let past = limit > t_end && t1 > t_end;
                if outputs.pending(t1) || past {
                    hermite(&integ.x, &w.x1, &w.f0, &w.f1, h, &mut w.coef);
                }
                if outputs.pending(t1) {
                    let (x0, x1, coef) = (&integ.x, &w.x1, &w.coef);
                    outputs.emit(
                        t,
                        h,
                        t1,
                        x1,
                        &mut |th, buf| dense(x0, x1, coef, th, buf),
                        out,
                    );
                }
                if past {
                    let a = &mut integ.state.ahead;
                    a.keep(t, t1, h, &integ.x, &w.x1);
                    a.coef.copy_from_slice(&w.coef);
                    dense(&a.x0, &a.x1, &a.coef, (t_end - t) / h, &mut integ.x);
                    integ.t = t_end;
                } else {
                    integ.x.copy_from_slice(&w.x1);
                    integ.t = t1;
                }
                integ.stats.accepted += 1;
                rejections.accepted();
                let fac = opts.control.accepted(&mut integ.state.hist, err, ERR_ORDER);
                let mut h_new = h * fac;
                if last {
                    h_new = h_new.max(h_proposed);
                }
                // Within [quot1, quot2] of the kept W's step size: keep W (RADAU5's rule).
                let h_lu = integ.state.kept.h_lu;
                if h_lu > 0.0 && h_new >= opts.quot1 * h_lu && h_new <= opts.quot2 * h_lu {
                    h_new = h_lu;
                }
                integ.h = h_new.min(integ.options.max_step);
                // The J has served one more step; an old one is re-evaluated at the next.
                integ.state.kept.age += 1;
                integ.state.kept.current = false;
                if integ.state.kept.age >= opts.max_jacobian_age && !constant_kept(integ, sys) {
                    integ.state.kept.drop_jacobian();
                }
                if done {
                    return Ok(());
                }
                std::mem::swap(&mut w.f0, &mut w.f1);
            }
            result => {
                integ.stats.rejected += 1;
                let limits = (t, h, integ.options.max_consecutive_rejections);
                let hist = &mut integ.state.hist;
                let (fac, too_many) =
                    opts.control
                        .rejected(hist, &mut rejections, result, ERR_ORDER, limits);
                integ.h = h * fac;
                // A J of an earlier point may be why: evaluate one here for the next attempt.
                if !integ.state.kept.current && !constant_kept(integ, sys) {
                    integ.state.kept.drop_jacobian();
                }
                if let Some(e) = too_many {
                    return Err(e);
                }
            }
        }
    }
}
