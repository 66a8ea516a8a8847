//! Stiff one-step integrators: Rodas5P (default) and Radau IIA of order 5.
//!
//! This module knows numbers only: no FMI, no physics. A model implements [`OdeSystem`]
//! (right-hand side, optionally an analytic dense Jacobian), and an [`Integrator`] advances
//! it to requested times.
//!
//! What a newcomer needs to know:
//!
//! * **Methods behind one trait.** Each method is a module with its own state behind
//!   [`OdeMethod`] (as diffsol's `OdeSolverMethod`, and as each of Hairer's codes keeps its own
//!   WORK arrays): [`rodas5p`], [`radau5`], [`fixed`], [`ros34pw2`]. The [`Integrator`] is the driver they
//!   share: it checks every call's arguments, keeps the point every method advances (a
//!   [`Stepper`]: options, t, x, the next step size, the counters) and hands the steps to the
//!   method named by [`SolverOptions::method`]. A method is registered once ([`Method`]'s
//!   constants for the crate's, [`register`] for one added at run time); see CONTRIBUTING.md,
//!   "Adding a solver method".
//! * **Methods.** [`Method::Rodas5P`] is the linearly implicit Rosenbrock method of
//!   Steinebach (BIT Numer. Math. 63:27, 2023), 8 stages, order 5 with an embedded order-4
//!   estimate, stiffly accurate, with an order-4 dense output; see [`rodas5p`].
//!   [`Method::Radau5`] is the 3-stage Radau IIA collocation method (order 5) implemented the
//!   way Hairer's `RADAU5` does it (simplified Newton, Jacobian/LU reuse, Gustafsson step
//!   control); see [`radau5`].
//!   [`Method::Rodas5PFixed`] is Rodas5P's step without error control, for real time: a fixed
//!   number of equal substeps per call ([`SolverOptions::substeps`]), each with one Jacobian,
//!   one factorisation, eight right-hand sides and eight solves, whatever the solution does;
//!   see [`fixed`].
//!   [`Method::Ros34pw2`] is the Rosenbrock-W method ROS34PW2 (Rang & Angermann 2005), 4
//!   stages, order 3 with an embedded order-2 estimate, which keeps its order with an old
//!   Jacobian and so keeps J and W's LU across steps; [`Method::Ros34pw2Fixed`] its step at a
//!   fixed step size for real time, the LU kept and J renewed every 10 steps; see
//!   [`ros34pw2`].
//! * **Exact stop times.** [`Integrator::advance_to`] ends bit-exactly on `t_end`: the last
//!   step is shortened to `t_end - t` and `t` is then *set* to `t_end` (no summing drift).
//! * **Stepping past requested points.** [`Integrator::advance_past`] reports `t_end` too, but
//!   lets Rodas5P's steps run past it (up to a limit) and reads the state at `t_end` from the
//!   step's dense output; the step is kept, so that a run of closely spaced points costs about
//!   the steps of one long call. A kept step is part of the saved state and is dropped by
//!   [`Integrator::notify_discontinuity`]. (ROS34PW2 does the same, with a cubic Hermite dense
//!   output.) Radau5 ends its steps on `t_end` all the same (its
//!   dense output is of order 3 only).
//! * **Failure is an error, not a panic.** Non-finite values, a step below the minimum, too
//!   many steps or rejections return a [`SolverError`] carrying the time reached; the
//!   integrator stays at the last accepted point and can continue (e.g. after the caller
//!   changes the inputs or tolerances).
//! * **Checkpointing.** [`Integrator`] is `Clone + Serialize + Deserialize` and holds
//!   everything that influences later results (t, x, h, controller history, Radau's Newton
//!   start polynomial, statistics, and the Jacobian Radau5 goes on with). Its saved form is the
//!   shared point (`options`, `t`, `x`, `h`, `stats`) and the method's own state (`state`) in
//!   the method's format, with that format's version (`state_version`,
//!   [`OdeMethod::STATE_VERSION`]); a saved state of another version is refused when read,
//!   with a message naming both versions. LU factors are *not*
//!   saved: every `advance_to` call evaluates f afresh at its start (the inputs may have changed
//!   since); Rodas5P evaluates J at every step, Radau5 keeps a varying J across calls while
//!   Newton converges fast, as RADAU5 keeps it across steps, with its entries and the step size
//!   of its LUs in the saved state, from which a restored copy rebuilds J and the LUs
//!   bit-identically and uncounted. A system with a constant Jacobian
//!   ([`OdeSystem::constant_jacobian`]) has J and its factorisations kept in memory while the
//!   step size is unchanged and rebuilt, bit-identically, by a restored copy. The work counters
//!   count a factorisation once per (Jacobian, step size) in that case, so they too agree between
//!   a restored copy and the original. Serialise with
//!   `serde_json` (the crate enables `float_roundtrip`, so every f64 round-trips exactly); no
//!   non-finite f64 is ever stored.
//! * **Linear algebra.** The iteration matrices are factorised by [`linalg`]: bordered
//!   block-diagonal elimination with the blocks and the border found from J's nonzero pattern
//!   (the dense LU when there is no such structure), so a model of loosely coupled parts costs
//!   about linearly in its size. Once warm, a call to `advance_to` without output times
//!   allocates nothing for an autonomous system with an analytic Jacobian (the FMU's case;
//!   finite differences and the starting-step estimate use temporary vectors).
//! * **Zero-order-hold input jumps.** Call [`Integrator::notify_discontinuity`] after the
//!   inputs jump: step-size history and Newton start values that assume smoothness are dropped.
//! * **Error control.** Mixed: component i is scaled by `atol_i + rtol * |x_i|`, RMS norm.
//!   For Radau5 the tolerances are transformed as in RADAU5 (`rtol' = 0.1 rtol^(2/3)`),
//!   because its embedded estimate is only of order 3; the user-facing meaning of `rtol`
//!   is thereby the same for both methods (≈ global relative accuracy reached).
//! * **Test problems** of the Mazzia–Magherini IVP test set live in [`testset`], with analytic
//!   Jacobians and reference solutions; the `stiff-testset` and `work-precision` binaries and
//!   the `tests/solver_*.rs` tests use them.
//! * **Work-precision** of both methods against scipy's Radau and LSODA: `bench/work_precision.md`
//!   (regenerate with `cargo run --release --bin work-precision`, see that file's header).
//!
//! # Example: a co-simulation loop
//!
//! ```
//! use hydraulic_slewing_plate::solver::{Atol, Integrator, Method, OdeSystem, SolverOptions};
//! use std::cell::Cell;
//!
//! /// A stiff lag x' = -1e5 (x - u) with a zero-order-held input u.
//! struct Lag { u: Cell<f64> }
//! impl OdeSystem for Lag {
//!     fn dim(&self) -> usize { 1 }
//!     fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) { dx[0] = -1e5 * (x[0] - self.u.get()); }
//!     fn jacobian(&self, _t: f64, _x: &[f64], j: &mut nalgebra::DMatrix<f64>) -> bool {
//!         j[(0, 0)] = -1e5;
//!         true
//!     }
//!     fn is_autonomous(&self) -> bool { true }
//! }
//!
//! let sys = Lag { u: Cell::new(0.0) };
//! let opts = SolverOptions { method: Method::Rodas5P, rtol: 1e-6, atol: Atol::Scalar(1e-9), ..Default::default() };
//! let mut integ = Integrator::new(opts, 0.0, vec![0.0]).unwrap();
//! let mut saved = None;
//! for k in 0..10 {
//!     sys.u.set(1.0 + k as f64);          // input jump at the communication point
//!     integ.notify_discontinuity();
//!     let t_end = (k + 1) as f64 * 1e-3;
//!     integ.advance_to(&sys, t_end).unwrap();
//!     assert_eq!(integ.t(), t_end);       // bit-exact stop
//!     if k == 4 {
//!         saved = Some(serde_json::to_string(&integ).unwrap()); // fmi2GetFMUstate + serialise
//!     }
//! }
//! assert!((integ.x()[0] - 10.0).abs() < 1e-6);
//! let restored: Integrator = serde_json::from_str(&saved.unwrap()).unwrap();
//! assert_eq!(restored.t(), 5e-3);
//! ```

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

mod common;
mod constant_jacobian;
mod dense;
pub mod fixed;
mod integrator;
pub mod jacobian;
pub mod linalg;
mod method;
pub mod radau5;
mod registry;
pub mod rodas5p;
pub mod ros34pw2;
mod step_map;
#[cfg(any(test, feature = "analysis"))]
pub mod testset;

pub use integrator::Integrator;
pub use jacobian::finite_difference_jacobian;
pub use method::{OdeMethod, Stepper};
pub use registry::{methods, register, Method};

/// An ODE system x' = f(t, x). Inputs (e.g. zero-order-held FMU inputs) are held by the model
/// itself; the solver only sees f.
pub trait OdeSystem {
    /// Number of states.
    fn dim(&self) -> usize;
    /// dx/dt = f(t, x), written into `dxdt` (length `dim`).
    fn rhs(&self, t: f64, x: &[f64], dxdt: &mut [f64]);
    /// Dense Jacobian df/dx into `jac` (dim x dim, already sized). Return false if the system
    /// has none; the solver then uses finite differences.
    fn jacobian(&self, _t: f64, _x: &[f64], _jac: &mut DMatrix<f64>) -> bool {
        false
    }
    /// `Some(stamp)` if the Jacobian is the same at every (t, x) (a linear system with constant
    /// coefficients, whatever its inputs), `stamp` identifying that matrix (a hash of its bits,
    /// say). The integrator then evaluates J once, and keeps J and its factorisations across
    /// steps and [`Integrator::advance_to`] calls for as long as the stamp and the step size stay
    /// the same. `jacobian` must give bit-identical values under one stamp, so that a restored
    /// integrator (which rebuilds them) continues bit-identically. With
    /// [`OdeSystem::is_autonomous`] as well, f is `J x + f(t, 0)`, and Radau5 may take its steps
    /// as affine maps built from J (see `step_map`). Default `None`: Rodas5P
    /// evaluates J at every step; Radau5 keeps it across steps and calls while Newton converges
    /// fast (saved with the integrator) and evaluates it afresh when not.
    fn constant_jacobian(&self) -> Option<u64> {
        None
    }
    /// `Some(stamp)` if part of J is the same at every (t, x) and the system can write the rest
    /// alone ([`OdeSystem::jacobian_varying`]); `stamp` identifies the constant part (its pattern
    /// and values). An integrator whose J buffer holds a J this system wrote under the same
    /// stamp then updates only the varying entries instead of writing the whole matrix (for a
    /// large model with a few nonlinear terms, the dense copy was most of the cost of a step).
    /// Default `None`.
    fn jacobian_constant_part(&self) -> Option<u64> {
        None
    }
    /// Overwrites the entries of `jac` that vary with (t, x), leaving the constant ones, which
    /// `jac` must already hold: it holds a J that [`OdeSystem::jacobian`] wrote under the stamp
    /// [`OdeSystem::jacobian_constant_part`] gives now. The result has the bits `jacobian` would
    /// give. Returns false if a varying entry is not finite (the constant ones were checked when
    /// `jac` was written) or if the system cannot (the default).
    fn jacobian_varying(&self, _t: f64, _x: &[f64], _jac: &mut DMatrix<f64>) -> bool {
        false
    }
    /// For each row i, the columns j whose entry may vary with (t, x) under the stamp of
    /// [`OdeSystem::jacobian_constant_part`] (the others are the constant part); a row with
    /// none is constant. With it the fixed-step driver ([`Method::Rodas5PFixed`]) eliminates
    /// the constant rows of its iteration matrix once and factorises only the varying rows'
    /// Schur complement at every step ([`linalg::VaryingRows`]). Default `None`.
    fn jacobian_varying_pattern(&self) -> Option<&[Vec<u32>]> {
        None
    }
    /// Where J may be nonzero: for each row i, the columns j for which ∂f_i/∂x_j is not zero
    /// at some point (a structural pattern, such as a compiled model knows; the diagonal need
    /// not be listed). With it, the block partition of the iteration matrices ([`linalg`]) is
    /// found once from this pattern instead of from J's nonzero entries at every evaluation,
    /// which for a J evaluated at every step costs a scan of J each time. Default `None`.
    fn jacobian_pattern(&self) -> Option<&[Vec<u32>]> {
        None
    }
    /// True if f does not depend on t explicitly (lets Rosenbrock skip df/dt). Default false.
    fn is_autonomous(&self) -> bool {
        false
    }
    /// Partial derivative df/dt into `dfdt`. Return false if not available; Rodas5P then uses
    /// a forward difference in t (only for non-autonomous systems). Extension beyond the
    /// minimal API; the default keeps existing implementors unchanged.
    fn time_derivative(&self, _t: f64, _x: &[f64], _dfdt: &mut [f64]) -> bool {
        false
    }
}

/// Absolute tolerance: one value for all components or one per component.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Atol {
    Scalar(f64),
    Vector(Vec<f64>),
}

impl Atol {
    /// Tolerance of component `i` (callers validate the length first).
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        match self {
            Atol::Scalar(a) => *a,
            Atol::Vector(v) => v[i],
        }
    }
}

/// Solver options. All fields are finite so that the struct serialises to JSON.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverOptions {
    pub method: Method,
    /// Relative tolerance (> 0).
    pub rtol: f64,
    /// Absolute tolerance(s) (>= 0).
    pub atol: Atol,
    /// Largest internal step. Default `f64::MAX` (finite, i.e. "no limit").
    pub max_step: f64,
    /// Smallest internal step (absolute); a step that must shrink below
    /// `max(min_step, 16 ulp(t))` makes the solver fail with `StepTooSmall`.
    pub min_step: f64,
    /// First step of a fresh start (after `new`, `reset`); `None` = automatic estimate.
    pub initial_step: Option<f64>,
    /// Maximum number of step attempts (accepted + rejected) per `advance_to` call.
    pub max_steps: u64,
    /// Maximum number of consecutive rejected step attempts before `TooManyRejections`.
    pub max_consecutive_rejections: u32,
    /// The fixed-step methods ([`Method::Rodas5PFixed`], [`Method::Ros34pw2Fixed`]) only: the
    /// number of equal steps each call to `t_end` takes
    /// (at least 1, at most [`MAX_SUBSTEPS`]). Default 1. The adaptive methods ignore it.
    #[serde(default = "one_substep")]
    pub substeps: u32,
}

/// The most substeps [`SolverOptions::substeps`] allows: a fixed-cost step of more would be a
/// communication step too long for real time.
pub const MAX_SUBSTEPS: u32 = 10_000;

fn one_substep() -> u32 {
    1
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            method: Method::Rodas5P,
            rtol: 1e-6,
            atol: Atol::Scalar(1e-9),
            max_step: f64::MAX,
            min_step: 1e-14,
            initial_step: None,
            max_steps: 100_000,
            max_consecutive_rejections: 50,
            substeps: 1,
        }
    }
}

impl SolverOptions {
    /// Check every option; the error message names the bad one.
    pub fn validate(&self, dim: usize) -> Result<(), SolverError> {
        let bad = |msg: String| Err(SolverError::new(SolverErrorKind::InvalidOptions, 0.0, msg));
        if !(self.rtol.is_finite() && self.rtol > 0.0) {
            return bad(format!(
                "rtol must be positive and finite, got {}",
                self.rtol
            ));
        }
        if self.rtol < 1e-15 {
            return bad(format!(
                "rtol must be at least 1e-15 (double precision), got {}",
                self.rtol
            ));
        }
        match &self.atol {
            Atol::Scalar(a) => {
                if !(a.is_finite() && *a >= 0.0) {
                    return bad(format!("atol must be non-negative and finite, got {a}"));
                }
            }
            Atol::Vector(v) => {
                if v.len() != dim {
                    return bad(format!(
                        "atol vector has length {}, but the system has {} states",
                        v.len(),
                        dim
                    ));
                }
                if let Some((i, a)) = v
                    .iter()
                    .enumerate()
                    .find(|(_, a)| !(a.is_finite() && **a >= 0.0))
                {
                    return bad(format!(
                        "atol[{i}] must be non-negative and finite, got {a}"
                    ));
                }
            }
        }
        if !(self.max_step.is_finite() && self.max_step > 0.0) {
            return bad(format!(
                "max_step must be positive and finite, got {}",
                self.max_step
            ));
        }
        if !(self.min_step.is_finite() && self.min_step >= 0.0) {
            return bad(format!(
                "min_step must be non-negative and finite, got {}",
                self.min_step
            ));
        }
        if self.min_step >= self.max_step {
            return bad(format!(
                "min_step ({}) must be smaller than max_step ({})",
                self.min_step, self.max_step
            ));
        }
        if let Some(h0) = self.initial_step {
            if !(h0.is_finite() && h0 > 0.0) {
                return bad(format!(
                    "initial_step must be positive and finite, got {h0}"
                ));
            }
        }
        if self.max_steps == 0 {
            return bad("max_steps must be positive, got 0".to_string());
        }
        if self.max_consecutive_rejections == 0 {
            return bad("max_consecutive_rejections must be positive, got 0".to_string());
        }
        if !(1..=MAX_SUBSTEPS).contains(&self.substeps) {
            return bad(format!(
                "substeps must be in 1..={MAX_SUBSTEPS}, got {}",
                self.substeps
            ));
        }
        Ok(())
    }
}

/// Work counters, cumulative over the life of an [`Integrator`] (part of its saved state).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub accepted: u64,
    pub rejected: u64,
    /// Right-hand-side evaluations, including those for finite-difference Jacobians.
    pub f_evals: u64,
    pub jac_evals: u64,
    pub lu_decompositions: u64,
}

/// What went wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SolverErrorKind {
    /// An option is invalid (message names it).
    InvalidOptions,
    /// A call argument is invalid: dimension mismatch, non-finite or backwards `t_end`,
    /// unsorted output times, non-finite initial state.
    InvalidInput,
    /// f (or the Jacobian) produced NaN/inf at the current point, or kept producing them
    /// until the step size fell below the minimum.
    NonFinite,
    /// The step size fell below the minimum step.
    StepTooSmall,
    /// More than `max_steps` step attempts in one `advance_to` call.
    TooManySteps,
    /// More than `max_consecutive_rejections` rejected attempts in a row.
    TooManyRejections,
    /// The iteration matrix stayed singular although the step size was reduced.
    SingularMatrix,
}

/// A solver failure: what, where (time reached, the last accepted point) and a message.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverError {
    pub kind: SolverErrorKind,
    /// Time of the last accepted point (the integrator's `t()` after the failure).
    pub t: f64,
    pub message: String,
}

impl SolverError {
    pub fn new(kind: SolverErrorKind, t: f64, message: impl Into<String>) -> Self {
        SolverError {
            kind,
            t,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for SolverError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "solver error ({:?}) at t = {}: {}",
            self.kind, self.t, self.message
        )
    }
}

impl std::error::Error for SolverError {}
