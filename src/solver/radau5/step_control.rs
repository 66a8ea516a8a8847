//! Step-size control (RADCOR, "computation of hnew") and the acceptance of a step (RADCOR,
//! "step is accepted").

use super::dense_output::collocation_polynomial;
use super::state::State;
use super::tolerances::{set_scal, Tolerances};
use super::workspace::Work;
use super::{nonfinite_here, Radau5Options};
use crate::solver::common::{all_finite, Outputs};
use crate::solver::method::Stepper;
use crate::solver::SolverError;

/// The step size proposed after a step of size `h` with error `err` and `newt` Newton
/// iterations (RADCOR, "computation of hnew"; Hairer & Wanner IV.8, "step size selection", with
/// a safety factor that falls with the Newton iterations used): h_new = h / quot, quot within
/// [FACR, FACL]; for an accepted step Gustafsson's predictive controller (eq. 8.25) may shorten
/// it, and its memory (the last accepted h and error) is updated.
pub(super) fn step_size(
    integ: &mut Stepper<State>,
    opts: &Radau5Options,
    err: f64,
    h: f64,
    newt: usize,
) -> f64 {
    let (safe, facl, facr) = (opts.safe, opts.facl, opts.facr);
    let cfac = safe * (1 + 2 * opts.nit) as f64;
    let fac = safe.min(cfac / (newt + 2 * opts.nit) as f64);
    let mut quot = facr.max(facl.min(crate::math::powf(err, 0.25) / fac));
    let mut hnew = h / quot;
    if err < 1.0 {
        if !integ.state.hist.first && integ.state.hist.h_acc > 0.0 {
            let facgus = (integ.state.hist.h_acc / h)
                * crate::math::powf(err * err / integ.state.hist.err_acc, 0.25)
                / safe;
            let facgus = facgus.clamp(facr, facl);
            quot = quot.max(facgus);
            hnew = h / quot;
        }
        integ.state.hist.h_acc = h;
        integ.state.hist.err_acc = err.max(opts.erracc_floor);
    }
    hnew
}

/// Accepts the step from `t` to `t1` (RADCOR, "step is accepted"): y1 = y0 + Z3, the collocation
/// polynomial of the step for dense output and the next Newton start (RADAU5's CONT, evaluated
/// by CONTR5), the outputs due within the step, and the new error weights. A `mapped` step
/// ([`mapped_step`](super::mapped_step::mapped_step)) has its end point in `work.x1` already and leaves no polynomial (the next
/// ordinary step starts Newton from zero, which on the affine system it was made for costs
/// nothing: one iteration converges from anywhere).
pub(super) fn accept(
    integ: &mut Stepper<State>,
    work: &mut Work,
    outputs: &mut Outputs,
    out: &mut dyn FnMut(f64, &[f64]),
    tol: &Tolerances,
    (t, h, t1): (f64, f64, f64),
    mapped: bool,
) -> Result<(), SolverError> {
    let n = integ.x.len();
    let Work {
        z: [z1, z2, z3],
        x1,
        atol,
        inv_scal,
        ..
    } = work;
    if !mapped {
        for i in 0..n {
            x1[i] = integ.x[i] + z3[i];
        }
    }
    if !all_finite(x1) {
        return Err(nonfinite_here(t));
    }
    if mapped {
        integ.state.hist.cont.clear();
    } else {
        collocation_polynomial(integ, (z1, z2, z3), x1, outputs, out, (t, h, t1));
    }
    integ.state.hist.h_old = h;
    integ.state.hist.first = false;
    integ.x.copy_from_slice(x1);
    integ.t = t1;
    integ.stats.accepted += 1;
    set_scal(atol, tol.rtol, &integ.x, inv_scal);
    Ok(())
}
