//! The fixed-cost driver for real time, [`Method::Rodas5PFixed`](super::Method::Rodas5PFixed):
//! Rodas5P's step at a step size fixed by the caller's communication step.
//!
//! A hardware-in-the-loop target must finish every communication step within its period, every
//! time. The adaptive drivers cannot promise that: their work per call varies with rejected
//! steps, step-size changes and (Radau5) Newton iterations. This driver takes every call to
//! `t_end` in [`SolverOptions::substeps`](super::SolverOptions::substeps) equal steps
//! h = (t_end − t) / substeps, and each step does the same work whatever the inputs and the
//! solution do:
//!
//! * one f evaluation at the step's start and one Jacobian (for a system with a constant
//!   Jacobian, the kept one: see [`OdeSystem::constant_jacobian`]),
//! * one factorisation of W = I/(hγ) − J (for a constant J, a kept one while h is unchanged;
//!   for a J that varies in at most half its rows, only the varying rows' Schur complement,
//!   the constant rows eliminated once per step size: [`VaryingRows`](super::linalg::VaryingRows)),
//! * seven further f evaluations and eight solves with W (Rodas5P's eight stages),
//!
//! and nothing else: no error test, no rejection, no step-size control, no allocation once warm.
//! The work counters ([`Stats`](super::Stats)) therefore grow by the same amounts at every call
//! with the same `substeps`, which `tests/realtime.rs` asserts.
//!
//! Why Rodas5P's step: it is linearly implicit (no Newton iteration, whose count would vary),
//! L-stable and stiffly accurate, so modes far faster than the step (the servo valve's, at
//! about −4000 ± 60000j s⁻¹) are damped out instead of blowing up, and its stage values are
//! exact for the stiff algebraic limit. What the fixed step gives up is the error control: the
//! error of the slow, accurate part is O(h⁵) but unmonitored, and a mode of frequency ω is
//! resolved only while ω h is well below 1. The step's embedded error estimate is still
//! computed (it comes free with the stages) and the largest of a call is reported by
//! [`Integrator::fixed_step_error`](super::Integrator::fixed_step_error), relative to the tolerances as the adaptive control would
//! judge it (above 1: a step the adaptive driver would have rejected).
//!
//! A step whose stages are not finite, or whose W is singular, ends the call with an error; the
//! integrator stays at the last completed step, as the adaptive drivers do. A call too short for
//! Rodas5P's 1/h terms (below `common::euler_floor`, as an importer's
//! 5e-324 s step is) is one explicit Euler step instead, as in the adaptive drivers.

use super::common::{euler_floor, Outputs};
use super::method::OdeMethod;
use super::method::Stepper;
use super::rodas5p::State;
use super::rodas5p::{self, Reject};
use super::{OdeSystem, SolverError, SolverErrorKind, SolverOptions};

/// Rodas5P's step at a fixed step size, for real time (see the module documentation). Its state
/// is Rodas5P's ([`State`]): the controller's error field holds the largest error estimate of
/// the last call; no step is ever kept past the reported point.
pub struct Rodas5PFixed;

/// The version of the fixed-step driver's saved state (Rodas5P's [`State`]).
pub const STATE_VERSION: u32 = 1;

impl OdeMethod for Rodas5PFixed {
    const NAME: &'static str = "rodas5p-fixed";
    const ALIASES: &'static [&'static str] = &["rodas5pfixed", "fixed"];
    const STATE_VERSION: u32 = STATE_VERSION;
    // h is the communication step over `substeps`, which the maximum step does not bound.
    const H_WITHIN_MAX_STEP: bool = false;
    type State = State;

    fn fresh(_: &SolverOptions, _: usize) -> State {
        State::default()
    }

    /// Real time: the caller's step, in equal substeps, never past t_end (`limit` is ignored).
    fn advance(
        run: &mut Stepper<State>,
        sys: &dyn OdeSystem,
        t_end: f64,
        _limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        advance(run, sys, t_end, times, out)
    }

    fn notify_discontinuity(state: &mut State) {
        <rodas5p::Rodas5P as OdeMethod>::notify_discontinuity(state);
    }

    fn reset(state: &mut State, resized: bool) {
        <rodas5p::Rodas5P as OdeMethod>::reset(state, resized);
    }

    fn after_failure(state: &mut State) {
        <rodas5p::Rodas5P as OdeMethod>::after_failure(state);
    }

    fn check_restored(run: &Stepper<State>, _: Option<&[Vec<u32>]>) -> Result<(), String> {
        rodas5p::check_restored(run)
    }

    fn error_estimate(state: &State) -> f64 {
        state.hist.err_prev
    }
}

/// Advances `integ` to exactly `t_end` in `integ.options.substeps` equal Rodas5P steps (called
/// through [`OdeMethod::advance`] for [`Method::Rodas5PFixed`](super::Method::Rodas5PFixed)).
fn advance<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    t_end: f64,
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
) -> Result<(), SolverError> {
    let stamp = sys.constant_jacobian();
    rodas5p::with_memory(integ, stamp, |integ, w, lus| {
        let n = integ.x.len();
        let autonomous = sys.is_autonomous();
        let substeps = integ.options.substeps.max(1);
        let t0 = integ.t;
        let h = (t_end - t0) / f64::from(substeps);
        let mut outputs = Outputs::new(times, t0, n);
        integ.state.hist.err_prev = 0.0;
        if h <= euler_floor(t0) {
            // A step too short for Rodas5P's 1/h terms (an importer's 5e-324 s): one explicit
            // Euler step over the whole call, as the adaptive drivers take (see `euler_floor`).
            rodas5p::eval_f0(integ, sys, &mut w.f0)?;
            euler_call(integ, &w.f0, &mut w.x1, t_end, &mut outputs, out);
            return Ok(());
        }
        for k in 1..=substeps {
            let t = integ.t;
            rodas5p::eval_f0(integ, sys, &mut w.f0)?;
            rodas5p::jacobian_at_point(integ, sys, w, stamp, autonomous)?;
            // Never shortened: the step is the caller's.
            let (h, result) =
                rodas5p::factorised_step(integ, sys, w, lus, stamp, h, false, true, autonomous);
            let err = result.map_err(|why| fixed_step_failure(why, t, k, substeps, h))?;
            // The last step ends on t_end itself, bit for bit (its size differs from h by
            // the rounding of t only).
            let t1 = if k == substeps {
                t_end
            } else {
                t0 + f64::from(k) * h
            };
            if outputs.pending(t1) {
                let (x0, x1, u) = (&integ.x, &w.x1, &w.u);
                outputs.emit(
                    t,
                    h,
                    t1,
                    x1,
                    &mut |theta, buf| rodas5p::interpolate(x0, x1, u, theta, buf),
                    out,
                );
            }
            integ.x.copy_from_slice(&w.x1);
            integ.t = t1;
            integ.stats.accepted += 1;
            integ.state.hist.err_prev = integ.state.hist.err_prev.max(err);
        }
        integ.h = h;
        Ok(())
    })
}

/// A call too short for a method's 1/h terms (below `common::euler_floor`, as an importer's
/// 5e-324 s step is): one explicit Euler step over the whole call to `t_end`, with f0 = f(t, x)
/// given and `x1` as the buffer of the end state, as the adaptive drivers take (see
/// `euler_floor`).
pub(crate) fn euler_call<St>(
    integ: &mut Stepper<St>,
    f0: &[f64],
    x1: &mut [f64],
    t_end: f64,
    outputs: &mut Outputs<'_>,
    out: &mut dyn FnMut(f64, &[f64]),
) {
    let t0 = integ.t;
    let x0 = &integ.x;
    for ((e, x), f) in x1.iter_mut().zip(x0).zip(f0) {
        *e = x + (t_end - t0) * f;
    }
    if outputs.pending(t_end) {
        let mut linear = |theta: f64, buf: &mut [f64]| {
            for ((b, a), z) in buf.iter_mut().zip(x0).zip(x1.iter()) {
                *b = a + theta * (z - a);
            }
        };
        outputs.emit(t0, t_end - t0, t_end, x1, &mut linear, out);
    }
    integ.x.copy_from_slice(x1);
    integ.t = t_end;
    integ.stats.accepted += 1;
}

/// The error of a fixed step `k` of `substeps` (size `h`, from `t`) that failed for `why`.
pub(crate) fn fixed_step_failure(
    why: Reject,
    t: f64,
    k: u32,
    substeps: u32,
    h: f64,
) -> SolverError {
    let (kind, what) = match why {
        Reject::NonFinite => (SolverErrorKind::NonFinite, "a stage is not finite"),
        Reject::Singular => (
            SolverErrorKind::SingularMatrix,
            "the iteration matrix is singular",
        ),
    };
    SolverError::new(
        kind,
        t,
        format!(
            "fixed step {k} of {substeps} (h = {h:e}): {what}; a fixed-step \
                 method cannot shorten its step: use more substeps, a shorter \
                 communication step or an adaptive method"
        ),
    )
}
