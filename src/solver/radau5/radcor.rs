//! RADCOR, RADAU5's step loop ([`radcor`]), and the state it keeps across the attempts of one
//! call ([`StepLoop`]): its prologue, the planning of each attempt, the attempt itself, and the
//! bookkeeping after an accepted or a rejected one.

use std::ops::ControlFlow;

use super::decomposition::{decompose, jacobian_at, Lu};
use super::estrad::estrad;
use super::mapped_step::{map_after, mapped_step};
use super::newton::{newton, start_values, Newton};
use super::state::State;
use super::step_control::{accept, step_size};
use super::tolerances::{set_scal, transformed_tolerances, Tolerances};
use super::workspace::Work;
use super::{nonfinite_here, Radau5Options, Why};
use crate::solver::common::{
    all_finite, euler_floor, eval, initial_step, plan_step, NextStep, Outputs,
};
use crate::solver::method::Stepper;
use crate::solver::{OdeSystem, SolverError, SolverErrorKind};

/// Step loop of RADAU5 (subroutine RADCOR): plans each step, computes J where needed (RADCOR
/// label 20), factorises ([`decompose`]), sets the Newton start ([`start_values`]), iterates
/// ([`newton`]), estimates the error ([`estrad`]), then accepts ([`accept`]) or rejects, and
/// chooses the next step size ([`step_size`]). A step that can be an affine map is taken by it
/// ([`mapped_step`]) in place of the Newton iteration and the error estimate.
#[allow(clippy::too_many_arguments)]
pub(super) fn radcor<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    opts: &Radau5Options,
    t_end: f64,
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
    work: &mut Work,
    lus: &mut Vec<Lu>,
    stamp: Option<u64>,
    need_jac: &mut bool,
) -> Result<(), SolverError> {
    let mut run = StepLoop::start(integ, sys, opts, work, stamp, (t_end, times, out), need_jac)?;
    loop {
        let Some((h, last, h_proposed)) = run.plan(integ, work, t_end)? else {
            return Ok(());
        };
        let t = integ.t;
        if *run.need_jac {
            run.jacobian(integ, work, lus)?;
        }
        let t1 = if last { t_end } else { t + h };
        // A rejected attempt gives the next h and why it was rejected.
        let (h_next, why) = match run.attempt(integ, work, lus, h, t1)? {
            Ok(step) => {
                let hnew = step_size(integ, opts, step.err, h, step.newton.iterations);
                if step.err < 1.0 {
                    let next = (hnew, h_proposed, last);
                    let flow = run.accepted(integ, work, &step, (t, h, t1), next)?;
                    if flow.is_break() {
                        return Ok(());
                    }
                    continue;
                }
                // Rejected by the error test.
                let first = integ.state.hist.first;
                (if first { h * opts.first_reject } else { hnew }, Why::Error)
            }
            Err((why, fac)) => (h * fac, why),
        };
        run.rejected(integ, (t, h, h_next), why)?;
    }
}

/// What an attempt that got through the Newton iteration (or the step map) and the error
/// estimate leaves for the step-size choice.
struct Attempt {
    newton: Newton,
    /// The error estimate's norm.
    err: f64,
    /// The step was taken by the step map (no collocation polynomial to keep).
    mapped: bool,
}

/// The receiver of the outputs at the requested times, `out(t, x)`.
type Out<'a> = &'a mut dyn FnMut(f64, &[f64]);

/// RADCOR's state across the step attempts of one call.
struct StepLoop<'a, S: ?Sized> {
    sys: &'a S,
    opts: &'a Radau5Options,
    /// Receives the outputs at the requested times.
    out: Out<'a>,
    /// J is to be evaluated before the next attempt (and, when the call ends, whether the next
    /// call must evaluate it afresh).
    need_jac: &'a mut bool,
    /// The stamp of a constant Jacobian ([`OdeSystem::constant_jacobian`]).
    stamp: Option<u64>,
    tol: Tolerances,
    /// A constant J of an autonomous system: f = J x + c, and a step can be a step map.
    mappable: bool,
    /// `work.f0` holds f at the integrator's current point. RADAU5 evaluates it at the start and
    /// after every accepted step; a system that may take mapped steps, which do not need it, has
    /// it evaluated only when an ordinary step, the initial step size or the last tiny remainder
    /// does ([`StepLoop::f0_here`]).
    f0_fresh: bool,
    /// f(t, 0) = c for the step map, evaluated when first wanted in this call: None until then,
    /// then whether it is finite.
    offsets: Option<bool>,
    /// J evaluated at the current point?
    jac_fresh: bool,
    attempts: u64,
    consecutive_rejections: u32,
    /// Singular iteration matrices in this call (RADAU5's NSING; see [`Radau5Options::nsing`]).
    singular: u32,
    /// Why the last attempt was rejected.
    why: Why,
    outputs: Outputs<'a>,
}

impl<'a, S: OdeSystem + ?Sized> StepLoop<'a, S> {
    /// RADCOR's prologue: the transformed tolerances and the error weights, f at the start
    /// (unless the steps may be mapped and there is a step size) and the initial step size if
    /// there is none.
    fn start(
        integ: &mut Stepper<State>,
        sys: &'a S,
        opts: &'a Radau5Options,
        work: &mut Work,
        stamp: Option<u64>,
        (t_end, times, out): (f64, &'a [f64], Out<'a>),
        need_jac: &'a mut bool,
    ) -> Result<Self, SolverError> {
        let n = integ.x.len();
        let tol = transformed_tolerances(integ, work, opts);
        set_scal(&work.atol, tol.rtol, &integ.x, &mut work.inv_scal);
        let mut run = StepLoop {
            sys,
            opts,
            out,
            need_jac,
            stamp,
            tol,
            mappable: stamp.is_some() && n <= opts.map_max_dim && sys.is_autonomous(),
            f0_fresh: false,
            offsets: None,
            jac_fresh: false,
            attempts: 0,
            consecutive_rejections: 0,
            singular: 0,
            why: Why::Error,
            outputs: Outputs::new(times, integ.t, n),
        };
        if !run.mappable || integ.h <= 0.0 {
            run.f0_here(integ, work)?;
        }
        if integ.h <= 0.0 {
            integ.h = initial_step(sys, integ, &work.f0, t_end, 3.0);
        }
        Ok(run)
    }

    /// f at the integrator's current point into `work.f0`, unless it is there already.
    fn f0_here(&mut self, integ: &mut Stepper<State>, work: &mut Work) -> Result<(), SolverError> {
        if !self.f0_fresh {
            eval(self.sys, &mut integ.stats, integ.t, &integ.x, &mut work.f0);
            if !all_finite(&work.f0) {
                return Err(nonfinite_here(integ.t));
            }
            self.f0_fresh = true;
        }
        Ok(())
    }

    /// The next attempt's (h, last, proposed) from [`plan_step`], or None when `t_end` is
    /// reached (a remnant before it below [`euler_floor`] covered by an Euler step from f0).
    fn plan(
        &mut self,
        integ: &mut Stepper<State>,
        work: &mut Work,
        t_end: f64,
    ) -> Result<Option<(f64, bool, f64)>, SolverError> {
        if t_end - integ.t <= euler_floor(integ.t) {
            // plan_step finishes with an Euler step from f0.
            self.f0_here(integ, work)?;
        }
        let why = self.why;
        let quantise = self.stamp.is_some();
        let f0 = &work.f0;
        match plan_step(
            integ,
            t_end,
            t_end,
            f0,
            &mut self.attempts,
            quantise,
            || why.too_small(),
        )? {
            NextStep::Done => Ok(None),
            NextStep::Step { h, last, proposed } => Ok(Some((h, last, proposed))),
        }
    }

    /// J at the current point ([`jacobian_at`]), no longer needed; an error if it is not
    /// finite.
    fn jacobian(
        &mut self,
        integ: &mut Stepper<State>,
        work: &mut Work,
        lus: &mut Vec<Lu>,
    ) -> Result<(), SolverError> {
        // (f0 is fresh here unless the system is mappable, whose J is analytic and constant:
        // jacobian_at then needs no f0 for finite differences.)
        if !jacobian_at(integ, self.sys, work, lus, self.stamp, self.tol.rtol) {
            return Err(SolverError::new(
                SolverErrorKind::NonFinite,
                integ.t,
                "the Jacobian is not finite at the current point",
            ));
        }
        *self.need_jac = false;
        self.jac_fresh = true;
        Ok(())
    }

    /// One attempt of a step of size `h` to `t1`: the factorisations ([`decompose`]), then the
    /// step map's step where it serves ([`StepLoop::may_map`], [`mapped_step`]), else the
    /// Newton start ([`start_values`]), the iteration ([`newton`]) and the error estimate
    /// ([`estrad`]). Its outcome, or a rejection reason with the factor for h; an error if f is
    /// not finite at the step's start.
    fn attempt(
        &mut self,
        integ: &mut Stepper<State>,
        work: &mut Work,
        lus: &mut Vec<Lu>,
        h: f64,
        t1: f64,
    ) -> Result<Result<Attempt, (Why, f64)>, SolverError> {
        let opts = self.opts;
        let singular = Err((Why::Singular, opts.unexpected_reject));
        let structure = self.sys.jacobian_pattern();
        if !decompose(integ, work, lus, (self.stamp, structure), h, opts) {
            return Ok(singular);
        }
        let Some(lu) = lus.first_mut() else {
            return Ok(singular);
        };
        if self.may_map(integ, work, t1) {
            let err = mapped_step(integ, work, lu, opts);
            // ESTRAD's refinement after a rejection or on the first step needs f at a
            // point off the map: such an attempt goes the ordinary way.
            if err.is_finite()
                && (err < 1.0 || !(integ.state.hist.first || integ.state.hist.last_rejected))
            {
                let newton = Newton {
                    iterations: 1,
                    theta: opts.thet,
                };
                return Ok(Ok(Attempt {
                    newton,
                    err,
                    mapped: true,
                }));
            }
        }
        let lu = &*lu;
        self.f0_here(integ, work)?;
        start_values(integ, work, h);
        let newton = match newton(integ, self.sys, work, lu, &self.tol, opts, h) {
            Ok(newton) => newton,
            Err(e) => return Ok(Err(e)),
        };
        Ok(
            estrad(integ, self.sys, work, lu, h, opts).map(|err| Attempt {
                newton,
                err,
                mapped: false,
            }),
        )
    }

    /// May the attempt ending at `t1` be a mapped step? For a mappable system, with no output
    /// time within the step, once the front factorisation has served [`map_after`] steps, and
    /// with finite offsets f(t, 0) (evaluated when first asked in this call).
    fn may_map(&mut self, integ: &mut Stepper<State>, work: &mut Work, t1: f64) -> bool {
        let sys = self.sys;
        self.mappable
            && !self.outputs.pending(t1)
            && integ.state.counted.front_steps >= map_after(integ.x.len(), self.opts)
            && *self.offsets.get_or_insert_with(|| {
                work.ytmp.fill(0.0);
                eval(sys, &mut integ.stats, integ.t, &work.ytmp, &mut work.c0);
                all_finite(&work.c0)
            })
    }

    /// Takes the `step` of size `h` from `t` to `t1` (RADCOR, "step is accepted"; [`accept`])
    /// and sets the next step size from the proposal `hnew` (not above h after a rejection, nor
    /// above `max_step`). At the call's `last` step it is kept for the next call, with J if
    /// Newton converged fast, and the loop breaks. Otherwise f at the new point, and h with J
    /// and its factorisations kept while θ ≤ THET and h_new / h lies in [QUOT1, QUOT2], J alone
    /// while θ ≤ THET.
    fn accepted(
        &mut self,
        integ: &mut Stepper<State>,
        work: &mut Work,
        step: &Attempt,
        (t, h, t1): (f64, f64, f64),
        (mut hnew, h_proposed, last): (f64, f64, bool),
    ) -> Result<ControlFlow<()>, SolverError> {
        let (opts, theta) = (self.opts, step.newton.theta);
        let (outputs, tol) = (&mut self.outputs, &self.tol);
        accept(integ, work, outputs, self.out, tol, (t, h, t1), step.mapped)?;
        if self.stamp.is_some() {
            integ.state.counted.front_steps = integ.state.counted.front_steps.saturating_add(1);
        }
        self.consecutive_rejections = 0;
        self.why = Why::Error;
        if integ.state.hist.last_rejected {
            hnew = hnew.min(h);
        }
        integ.state.hist.last_rejected = false;
        hnew = hnew.min(integ.options.max_step);
        if last {
            integ.h = hnew.max(h_proposed);
            // The next call goes on with this J only while Newton converges fast.
            *self.need_jac = theta > opts.thet;
            return Ok(ControlFlow::Break(()));
        }
        self.f0_fresh = false;
        if !self.mappable {
            if let Err(e) = self.f0_here(integ, work) {
                integ.h = hnew;
                return Err(e);
            }
        }
        self.jac_fresh = false;
        let qt = hnew / h;
        if theta <= opts.thet && (opts.quot1..=opts.quot2).contains(&qt) {
            // Keep h, J and LU.
            integ.h = h;
        } else {
            integ.h = hnew;
            // Reuse J (new LU) only while Newton converges very fast.
            *self.need_jac = theta > opts.thet;
        }
        Ok(ControlFlow::Continue(()))
    }

    /// After a rejected attempt of size `h` from `t` (RADCOR, "step is rejected" and label 78):
    /// the next attempt's size `h_next`; RADAU5 recomputes J unless it is already current. An
    /// error at the [`Radau5Options::nsing`]-th singular matrix of the call, or after more than
    /// `max_consecutive_rejections` in a row.
    fn rejected(
        &mut self,
        integ: &mut Stepper<State>,
        (t, h, h_next): (f64, f64, f64),
        why: Why,
    ) -> Result<(), SolverError> {
        integ.h = h_next;
        self.why = why;
        integ.stats.rejected += 1;
        integ.state.hist.last_rejected = true;
        self.consecutive_rejections += 1;
        if !self.jac_fresh {
            *self.need_jac = true;
        }
        if why == Why::Singular {
            self.singular += 1;
            if self.singular >= self.opts.nsing {
                return Err(SolverError::new(
                    SolverErrorKind::SingularMatrix,
                    t,
                    format!(
                        "the iteration matrix was singular {} times in this call (RADAU5's NSING = {}; last h = {h:e})",
                        self.singular, self.opts.nsing
                    ),
                ));
            }
        }
        let rejections = self.consecutive_rejections;
        if rejections > integ.options.max_consecutive_rejections {
            return Err(SolverError::new(
                why.after_rejections(),
                t,
                format!("{rejections} consecutive step rejections (last h = {h:e})"),
            ));
        }
        Ok(())
    }
}
