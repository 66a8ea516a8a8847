//! A method behind one trait, each with its own state ([`OdeMethod`]), as diffsol's
//! `OdeSolverMethod` and Hairer's codes (each its own WORK arrays) keep theirs.
//!
//! The driver ([`Integrator`](super::Integrator)) owns what every method shares, the
//! [`Stepper`]'s point (options, t, x, the next step size h, the work counters), and checks the
//! arguments of every call; the method owns the rest (its controller's history, its kept
//! Jacobian, its buffers) in its [`OdeMethod::State`] and takes the steps. A method is one
//! module (or folder) with a type implementing [`OdeMethod`], plus one registration: a line of
//! the `built_in!` list of `registry.rs` for the methods of the crate, or [`register`](super::register)
//! at run time (how a test adds one). See CONTRIBUTING.md, "Adding a solver method".
//!
//! The saved state of an integrator is the shared point and the method's state in the format
//! the method writes, tagged with its version ([`OdeMethod::STATE_VERSION`]); a saved state of
//! another version is refused when read, naming both versions.

use std::fmt::Debug;

use serde::de::DeserializeOwned;
use serde::Serialize;

use super::{OdeSystem, SolverError, SolverOptions, Stats};

/// The point every method advances, and the counters: what the driver keeps and checks, shared
/// by all methods; `state` is the method's own.
#[derive(Clone, Debug, PartialEq)]
pub struct Stepper<S> {
    pub options: SolverOptions,
    /// The current time (bit-exactly a requested `t_end` after a successful call).
    pub t: f64,
    /// The state at `t`.
    pub x: Vec<f64>,
    /// Next step size to try; 0 = estimate one at the next call.
    pub h: f64,
    /// Work counters, cumulative.
    pub stats: Stats,
    /// The method's own state.
    pub state: S,
}

/// One integration method: its name, the version of its saved state, and its steps. The
/// methods are types (usually without values: the state lives in [`OdeMethod::State`]); the
/// driver calls them through this trait only.
pub trait OdeMethod: 'static {
    /// Lower-case name, as on command lines, in [`SolverOptions::method`] and in saved states.
    const NAME: &'static str;
    /// Other names [`Method`](super::Method)'s `from_str` accepts.
    const ALIASES: &'static [&'static str] = &[];
    /// Version of the saved form of [`OdeMethod::State`]: raise it with any change of the
    /// state's serialised fields or of their meaning. A saved state of another version is
    /// refused on restore.
    const STATE_VERSION: u32;
    /// Does [`SolverOptions::max_step`] bound the next step size h of a saved state? False for
    /// a method whose h is the caller's (the fixed-step one).
    const H_WITHIN_MAX_STEP: bool = true;
    /// Everything the method keeps between calls: what influences later results (saved with
    /// the integrator; no non-finite number) and buffers (`#[serde(skip)]`).
    type State: Clone + Debug + PartialEq + Send + Serialize + DeserializeOwned + 'static;

    /// The state of a fresh start with `options` and `n` states.
    fn fresh(options: &SolverOptions, n: usize) -> Self::State;

    /// Advances `run` to exactly `t_end` (`run.t == t_end` bit-exactly on success), or, for a
    /// method that may step past it (`limit > t_end`), reports `t_end` from a step that ends
    /// beyond, never past `limit`. Calls `out(t, x)` at each of the `times` in (t, t_end].
    /// The driver has checked the arguments and the current point. On error the point stays
    /// at the last accepted step.
    fn advance(
        run: &mut Stepper<Self::State>,
        sys: &dyn OdeSystem,
        t_end: f64,
        limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError>;

    /// The inputs jumped: forget what assumes smoothness across this point, and go on from
    /// the reported point (drop a step kept past it).
    fn notify_discontinuity(state: &mut Self::State);

    /// The point was replaced (`resized`: by one of another length): by default as after a
    /// discontinuity.
    fn reset(state: &mut Self::State, resized: bool) {
        let _ = resized;
        Self::notify_discontinuity(state);
    }

    /// The options changed (the method stayed): by default as after a discontinuity.
    fn options_changed(state: &mut Self::State) {
        Self::notify_discontinuity(state);
    }

    /// A call failed (other than by too many steps): the history that led into the failure is
    /// no guide for the next attempt. (The driver sets h to 0, a fresh estimate.)
    fn after_failure(state: &mut Self::State);

    /// Checks a restored state against the system's size and Jacobian pattern, beyond what the
    /// driver checks of the shared point; the message completes "the FMU state is refused:".
    fn check_restored(
        run: &Stepper<Self::State>,
        pattern: Option<&[Vec<u32>]>,
    ) -> Result<(), String> {
        let _ = (run, pattern);
        Ok(())
    }

    /// Is the reported point inside a step kept past it? Default false.
    fn is_past(state: &Self::State) -> bool {
        let _ = state;
        false
    }

    /// Where integration has got to: the end of a step kept past `run.t`, else `run.t`.
    fn reached(run: &Stepper<Self::State>) -> f64 {
        run.t
    }

    /// A fixed-step method's largest error estimate of the last call, relative to the
    /// tolerances; 0 for an adaptive one (the default).
    fn error_estimate(state: &Self::State) -> f64 {
        let _ = state;
        0.0
    }
}

/// A restored number that must be finite and not negative: the message if it is not.
pub(crate) fn check_non_negative(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!(
            "its integrator's {name} = {v} is not a finite non-negative number"
        ))
    }
}
