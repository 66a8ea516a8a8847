//! Rodas5P's own state ([`State`], shared by the fixed-step driver of its step) and its
//! registration as a method ([`Rodas5P`]): the PI controller's history, the counters' record of
//! a constant Jacobian, the step kept past the reported point, and the buffers.

use serde::{Deserialize, Serialize};

use super::{advance, dense, Work};
use crate::solver::constant_jacobian::{Cache, Counted};
use crate::solver::method::{check_non_negative, OdeMethod, Stepper};
use crate::solver::{OdeSystem, SolverError, SolverOptions};

/// The adaptive Rodas5P method (Steinebach 2023), with steps free to run past a requested
/// point ([`Integrator::advance_past`](crate::solver::Integrator::advance_past)).
pub struct Rodas5P;

/// The version of [`State`]'s saved form (see [`OdeMethod::STATE_VERSION`]).
pub const STATE_VERSION: u32 = 1;

impl OdeMethod for Rodas5P {
    const NAME: &'static str = "rodas5p";
    const STATE_VERSION: u32 = STATE_VERSION;
    type State = State;

    fn fresh(_: &SolverOptions, _: usize) -> State {
        State::default()
    }

    fn advance(
        run: &mut Stepper<State>,
        sys: &dyn OdeSystem,
        t_end: f64,
        limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        if run
            .state
            .ahead
            .resume(&mut run.t, &mut run.x, t_end, times, out)
        {
            return Ok(());
        }
        advance(run, sys, t_end, limit, times, out)
    }

    fn notify_discontinuity(state: &mut State) {
        state.hist = Controller::default();
        // Go on from the reported point, not from the end of a step taken with the old inputs.
        state.ahead.active = false;
    }

    fn reset(state: &mut State, resized: bool) {
        if resized {
            state.cache = Cache::default();
            state.counted = Counted::default();
        }
        Self::notify_discontinuity(state);
    }

    fn after_failure(state: &mut State) {
        state.hist = Controller::default();
    }

    fn check_restored(run: &Stepper<State>, _: Option<&[Vec<u32>]>) -> Result<(), String> {
        check_restored(run)
    }

    fn is_past(state: &State) -> bool {
        state.ahead.active
    }

    fn reached(run: &Stepper<State>) -> f64 {
        if run.state.ahead.active {
            run.state.ahead.t1
        } else {
            run.t
        }
    }
}

/// The checks of a restored Rodas5P state (also the fixed-step driver's): the controller's
/// error finite and non-negative, a kept step sound.
pub(crate) fn check_restored(run: &Stepper<State>) -> Result<(), String> {
    check_non_negative("err_prev", run.state.hist.err_prev)?;
    run.state
        .ahead
        .check(run.x.len(), run.t, &run.x, run.options.max_step)
}

/// Rodas5P's state between calls. Everything but `cache` is saved.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// The step-size controller's history.
    pub(crate) hist: Controller,
    /// What the counters know about a constant Jacobian.
    pub(crate) counted: Counted,
    /// The step that went past the reported point, if the last call stepped past it.
    #[serde(default, skip_serializing_if = "Ahead::is_idle")]
    pub(crate) ahead: Ahead,
    /// Buffers, and a constant Jacobian with its factorisations.
    #[serde(skip)]
    pub(crate) cache: Cache<Work>,
}

/// The PI controller's history (Hairer & Wanner II, IV.8, eq. 8.21 for the PI form). Reset by
/// a discontinuity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Controller {
    /// No step accepted since the start or the last discontinuity.
    pub first: bool,
    /// The last step attempt was rejected (limits the next step's growth).
    pub last_rejected: bool,
    /// Error norm of the previous accepted step; 0 = none yet. The fixed-step driver keeps the
    /// largest error estimate of its last call here.
    pub err_prev: f64,
}

impl Default for Controller {
    fn default() -> Self {
        Controller {
            first: true,
            last_rejected: false,
            err_prev: 0.0,
        }
    }
}

/// The last accepted step when the integrator has stepped past the point it reports (see
/// [`Integrator::advance_past`](crate::solver::Integrator::advance_past)): the step from `t0` to `t1` of size `h`, its end state `x1`
/// (where integration goes on), its start state `x0` and the coefficients of its dense output,
/// from which the reported point `(t, x)` inside the step was interpolated.
///
/// The buffers are kept while it is idle, so that stepping past points allocates nothing once
/// warm; only an active one is saved (an idle one serialises to nothing and compares equal to
/// any other idle one).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub(crate) struct Ahead {
    /// True while the integrator's (t, x) is an interpolated point inside this step.
    pub active: bool,
    pub t0: f64,
    pub t1: f64,
    pub h: f64,
    pub x0: Vec<f64>,
    pub x1: Vec<f64>,
    /// Dense-output coefficients, 3 n numbers: Rodas5P's three correction vectors of its
    /// order-4 interpolant.
    pub coef: Vec<f64>,
}

impl Ahead {
    pub(crate) fn is_idle(&self) -> bool {
        !self.active
    }

    /// The start of a call to `t_end` from the reported point (t, x) while this step is active:
    /// calls `out` at the output times in (t, min(t_end, t1)] from its dense output, and either
    /// moves (t, x) to t_end inside the step (true: the call is done), or to the step's end t1,
    /// where integration goes on (false; the step is then no longer kept).
    pub(crate) fn resume(
        &mut self,
        t: &mut f64,
        x: &mut Vec<f64>,
        t_end: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> bool {
        if !self.active {
            return false;
        }
        if t_end <= self.t1 {
            self.emit(*t, t_end, times, out);
            self.at(t_end, x);
            *t = t_end;
            return true;
        }
        let t1 = self.t1;
        self.emit(*t, t1, times, out);
        std::mem::swap(x, &mut self.x1);
        *t = t1;
        self.active = false;
        false
    }

    /// The state at `t` inside the step (t0 <= t <= t1), into `buf`: its end state at t1
    /// itself, else the dense output.
    fn at(&self, t: f64, buf: &mut [f64]) {
        if t == self.t1 {
            buf.copy_from_slice(&self.x1);
            return;
        }
        dense(&self.x0, &self.x1, &self.coef, (t - self.t0) / self.h, buf);
    }

    /// Calls `out` at the output times in (t, until] from the step.
    fn emit(&self, t: f64, until: f64, times: &[f64], out: &mut dyn FnMut(f64, &[f64])) {
        let mut due = times.iter().filter(|&&w| w > t && w <= until).peekable();
        if due.peek().is_some() {
            let mut buf = vec![0.0; self.x0.len()];
            for &w in due {
                self.at(w, &mut buf);
                out(w, &buf);
            }
        }
    }

    /// Makes the buffers hold a step from `t0` (state `x0`) to `t1` (state `x1`) of size `h`,
    /// active; the method fills `coef` (resized to 3 n).
    pub fn keep(&mut self, t0: f64, t1: f64, h: f64, x0: &[f64], x1: &[f64]) {
        self.active = true;
        self.t0 = t0;
        self.t1 = t1;
        self.h = h;
        self.x0.clear();
        self.x0.extend_from_slice(x0);
        self.x1.clear();
        self.x1.extend_from_slice(x1);
        self.coef.resize(3 * x0.len(), 0.0);
    }

    /// Checks a restored step: finite, of the right sizes, covering `t`, as long as its step
    /// `h` (to rounding) and no longer than `max_step`, and agreeing with the state `x` at `t`
    /// (bit for bit: `x` was read from this step's dense output). A crafted step stretched over
    /// a longer window would otherwise hand out its interpolant far outside the step it was
    /// fitted to (issue 24, N3).
    pub fn check(&self, n: usize, t: f64, x: &[f64], max_step: f64) -> Result<(), String> {
        if !self.active {
            return Ok(());
        }
        if self.x0.len() != n || self.x1.len() != n || self.coef.len() != 3 * n {
            return Err(format!(
                "its step past the communication point holds {}, {} and {} numbers, the model needs {n}, {n} and {}",
                self.x0.len(),
                self.x1.len(),
                self.coef.len(),
                3 * n
            ));
        }
        let numbers = [self.t0, self.t1, self.h].into_iter();
        if !numbers
            .chain(self.x0.iter().copied())
            .chain(self.x1.iter().copied())
            .chain(self.coef.iter().copied())
            .all(f64::is_finite)
        {
            return Err("its step past the communication point holds a non-finite number".into());
        }
        if !(self.h > 0.0 && self.t0 <= t && t <= self.t1) {
            return Err(format!(
                "its step past the communication point, from t = {} to {}, does not cover t = {t}",
                self.t0, self.t1
            ));
        }
        // t1 is t0 + h, or the limit the step was cut to with h = limit - t0: equal to h but
        // for the rounding of one addition.
        let rounding = 4.0 * f64::EPSILON * self.t0.abs().max(self.t1.abs());
        if ((self.t1 - self.t0) - self.h).abs() > rounding || self.h > max_step {
            return Err(format!(
                "its step past the communication point, from t = {:e} to {:e}, is not its step size h = {:e} long, or h is above the maximum step {:e}",
                self.t0, self.t1, self.h, max_step
            ));
        }
        let mut at_t = vec![0.0; n];
        if t == self.t1 {
            at_t.copy_from_slice(&self.x1);
        } else {
            dense(
                &self.x0,
                &self.x1,
                &self.coef,
                (t - self.t0) / self.h,
                &mut at_t,
            );
        }
        if let Some(i) = (0..n).find(|&i| at_t[i].to_bits() != x[i].to_bits()) {
            return Err(format!(
                "its state x[{i}] = {:e} at t = {t:e} is not its step's dense output there ({:e})",
                x[i], at_t[i]
            ));
        }
        Ok(())
    }
}

impl PartialEq for Ahead {
    fn eq(&self, other: &Ahead) -> bool {
        match (self.active, other.active) {
            (false, false) => true,
            (true, true) => {
                (self.t0, self.t1, self.h) == (other.t0, other.t1, other.h)
                    && self.x0 == other.x0
                    && self.x1 == other.x1
                    && self.coef == other.coef
            }
            _ => false,
        }
    }
}
