//! ROS34PW2's state ([`State`]: the controller's history, the kept J and the step size of its
//! W, a step kept past the reported point, the buffers) and its registrations as methods: the
//! adaptive [`Ros34pw2`] and the fixed-step [`Ros34pw2Fixed`] for real time.

use serde::{Deserialize, Serialize};

use super::Work;
use crate::solver::method::{check_non_negative, OdeMethod, Stepper};
use crate::solver::rodas5p::{Ahead, Controller};
use crate::solver::{OdeSystem, SolverError, SolverOptions};

/// The adaptive ROS34PW2 (Rang & Angermann 2005) with J and W's LU kept across steps, with
/// steps free to run past a requested point.
pub struct Ros34pw2;

/// ROS34PW2's step at a fixed step size, for real time: every call to `t_end` takes
/// [`SolverOptions::substeps`] equal steps, none rejected; W's LU is kept while the step size
/// stays and J is re-evaluated every `fixed_jacobian_interval` steps
/// ([`Ros34pw2Options`](super::Ros34pw2Options)).
pub struct Ros34pw2Fixed;

/// The version of [`State`]'s saved form (see [`OdeMethod::STATE_VERSION`]), both drivers.
pub const STATE_VERSION: u32 = 1;

/// ROS34PW2's state between calls. Everything but `cache` is saved.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// The step-size controller's history (the fixed-step driver keeps the largest error
    /// estimate of its last call in `err_prev`).
    pub(crate) hist: Controller,
    /// The J in use and the step size of its W.
    pub(crate) kept: Kept,
    /// The step that went past the reported point, if the last call stepped past it.
    #[serde(default, skip_serializing_if = "Ahead::is_idle")]
    pub(crate) ahead: Ahead,
    #[serde(skip)]
    pub(crate) cache: Buffers,
}

/// The J the steps use, kept across steps (see the module documentation of
/// [`ros34pw2`](super)): saved, so that a restored integrator factorises the same W.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct Kept {
    /// J, column by column (n² numbers); empty: evaluate one at the next step.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub jac: Vec<f64>,
    /// ∂f/∂t at the same point (n numbers); empty for an autonomous system.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dfdt: Vec<f64>,
    /// The step size W = I/(h_lu γ) − J was factorised for; 0: none.
    pub h_lu: f64,
    /// Steps accepted (or, fixed-step, taken) since J was evaluated.
    pub age: u32,
    /// J was evaluated at the current point (no step accepted since).
    pub current: bool,
    /// The stamp of a constant Jacobian ([`OdeSystem::constant_jacobian`]) that `jac` is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stamp: Option<u64>,
}

impl Kept {
    /// No J kept: the next step evaluates one (and factorises its W).
    pub(crate) fn drop_jacobian(&mut self) {
        self.jac.clear();
        self.dfdt.clear();
        self.h_lu = 0.0;
    }

    fn forget(&mut self) {
        self.drop_jacobian();
        self.age = 0;
        self.current = false;
        self.stamp = None;
    }
}

/// The buffers and W's factorisation: a clone starts empty, and any two compare equal (they
/// hold nothing that influences results beyond the saved state).
#[derive(Default)]
pub(crate) struct Buffers(pub(super) Option<Box<Work>>);

impl Clone for Buffers {
    fn clone(&self) -> Self {
        Buffers(None)
    }
}

impl PartialEq for Buffers {
    fn eq(&self, _: &Buffers) -> bool {
        true
    }
}

impl std::fmt::Debug for Buffers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Buffers")
    }
}

impl OdeMethod for Ros34pw2 {
    const NAME: &'static str = "ros34pw2";
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
        super::adaptive::advance(run, sys, t_end, limit, times, out)
    }

    /// The controller's history is forgotten and the step kept past the point dropped, as
    /// Rodas5P does; the J is kept (a W-method keeps its order with any J, and a J that no
    /// longer serves shows in a rejected step, which re-evaluates it), but it is no longer the
    /// current point's.
    fn notify_discontinuity(state: &mut State) {
        state.hist = Controller::default();
        state.ahead.active = false;
        state.kept.current = false;
    }

    fn reset(state: &mut State, resized: bool) {
        if resized {
            state.cache = Buffers::default();
        }
        state.kept.forget();
        Self::notify_discontinuity(state);
    }

    fn after_failure(state: &mut State) {
        state.hist = Controller::default();
        state.kept.forget();
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

impl OdeMethod for Ros34pw2Fixed {
    const NAME: &'static str = "ros34pw2-fixed";
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
        super::fixed::advance(run, sys, t_end, times, out)
    }

    /// The J and W are kept (see [`Ros34pw2`]'s): the real-time step's work stays the same.
    fn notify_discontinuity(state: &mut State) {
        <Ros34pw2 as OdeMethod>::notify_discontinuity(state);
    }

    fn reset(state: &mut State, resized: bool) {
        <Ros34pw2 as OdeMethod>::reset(state, resized);
    }

    fn after_failure(state: &mut State) {
        <Ros34pw2 as OdeMethod>::after_failure(state);
    }

    fn check_restored(run: &Stepper<State>, _: Option<&[Vec<u32>]>) -> Result<(), String> {
        check_restored(run)
    }

    fn error_estimate(state: &State) -> f64 {
        state.hist.err_prev
    }
}

/// The checks of a restored state: the controller's error, the kept J (n² finite numbers or
/// none; ∂f/∂t n or none; a W step size only with a J), and a kept step.
fn check_restored(run: &Stepper<State>) -> Result<(), String> {
    let n = run.x.len();
    let kept = &run.state.kept;
    check_non_negative("err_prev", run.state.hist.err_prev)?;
    check_non_negative("W step size h_lu", kept.h_lu)?;
    if !(kept.jac.is_empty() || kept.jac.len() == n * n) {
        return Err(format!(
            "its kept Jacobian holds {} numbers, the model needs {}",
            kept.jac.len(),
            n * n
        ));
    }
    if !(kept.dfdt.is_empty() || (kept.dfdt.len() == n && !kept.jac.is_empty())) {
        return Err(format!(
            "its kept df/dt holds {} numbers, the model needs {n} with a kept Jacobian",
            kept.dfdt.len()
        ));
    }
    if !kept.jac.iter().chain(&kept.dfdt).all(|v| v.is_finite()) {
        return Err("its kept Jacobian holds a non-finite number".into());
    }
    if kept.h_lu > 0.0 && kept.jac.is_empty() {
        return Err(format!(
            "its W step size h_lu = {} comes without a Jacobian",
            kept.h_lu
        ));
    }
    run.state
        .ahead
        .check(n, run.t, &run.x, run.options.max_step)
}
