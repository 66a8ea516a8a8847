//! ROS34PW2: a 4-stage Rosenbrock-W method of order 3 (embedded order 2), L-stable and stiffly
//! accurate (Rang & Angermann, BIT Numer. Math. 45 (2005) 761–787), which keeps the Jacobian
//! and the factorisation of W across steps.
//!
//! # Why a W-method
//!
//! A Rosenbrock method such as Rodas5P keeps its order only with the exact Jacobian at every
//! step, so a nonlinear plant costs a Jacobian and an LU of W = I/(h γ) − J at every step. A
//! W-method keeps its order with *any* matrix in place of J (Hairer & Wanner II, Sec. IV.7,
//! "W-methods"; ROS34PW2's coefficients meet the W-method order conditions of order 3, checked in
//! `tests/solver_ros34pw2.rs`): J is only an approximation that keeps the stiff modes stable,
//! and it may be old. W's LU made for a step size h_lu also serves a step h ≠ h_lu: it is the W
//! of the matrix J + (1/(h γ) − 1/(h_lu γ)) I, again just another approximation. So both are kept
//! while they serve (the reuse policy, [`Ros34pw2Options`]):
//!
//! * J (and ∂f/∂t) is evaluated at the first step, after a rejected step taken with a J of an
//!   earlier point (an old J may be why), after a failure, and after `max_jacobian_age` accepted
//!   steps (the fixed-step driver: every `fixed_jacobian_interval` steps);
//! * W is refactorised with a new J, or when the step size changes; the step size is frozen while
//!   the controller's proposal stays within [QUOT1, QUOT2] = [1, 1.2] of it, as RADAU5 does.
//!
//! The kept J is part of the saved state (it influences later results), so that a restored
//! integrator refactorises the same W and continues bit for bit; the LU is rebuilt from it
//! without being counted again (the original did not count it either).
//!
//! # Form of the method
//!
//! The transformed form of Hairer & Wanner II, eq. IV.7.4', with one LU of W per step size:
//!
//! ```text
//! (I/(h_lu γ) − J) U_i = f(t0 + c_i h, y0 + Σ_{j<i} a_ij U_j) + Σ_{j<i} (C_ij / h) U_j + h d_i ∂f/∂t
//! y1 = y0 + Σ m_j U_j,    error estimate = Σ (m_j − m̂_j) U_j   (ŷ1 of order 2)
//! ```
//!
//! Dense output (between the points of a step, and for a step kept past the reported point): the
//! cubic Hermite interpolant of y0, y1, f(y0), f(y1), of order 3 like the method, written in the
//! form of Rodas5P's extension so that the same code evaluates it (`hermite`).

// Index loops over stages and components mirror the formulas they implement.
#![allow(clippy::needless_range_loop)]

mod adaptive;
mod fixed;
mod state;
mod tableau;

use std::sync::Arc;

use nalgebra::DMatrix;

pub use state::{Ros34pw2, Ros34pw2Fixed, State, STATE_VERSION};
pub use tableau::{classical_form, A, C, C_NODES, D, E, GAMMA, M, M_HAT, STAGES};

use super::common::{all_finite, axpy, eval};
use super::constant_jacobian::SAME_STEP;
use super::jacobian;
use super::linalg::{factor_with_fallback, Factorisation, PatternCache, Shifted};
use super::method::Stepper;
use super::rodas5p::{error_norm, Reject, Rodas5POptions};
use super::{OdeSystem, SolverError, SolverErrorKind};

/// Order of the error estimator's local error exponent minus one: err ~ h^3.
const ERR_ORDER: f64 = 3.0;

/// The tunables of ROS34PW2: its step-size control, Rodas5P's (a PI controller, see
/// [`Rodas5POptions`]) with the exponents of its order-3 pair, and its reuse of J and W, with
/// their defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ros34pw2Options {
    /// The step-size control. Default `Rodas5POptions::for_order(3)`: RODAS's SAFE 0.9,
    /// WORK(3) 0.2 and WORK(4) 6, β1 = 0.7/3, β2 = 0.4/3.
    pub control: Rodas5POptions,
    /// RADAU5's QUOT1 (WORK(3) there): W's LU is kept, and the step size frozen at the one it
    /// was made for, h_lu, while the step size the controller proposes, h_new, stays within
    /// [quot1 · h_lu, quot2 · h_lu]. Default 1, RADAU5's. (A factorisation made for h_lu is the
    /// W of the matrix J + (1/h − 1/h_lu)/γ · I for a step h: a W-method's order holds for any
    /// fixed matrix, but this one differs from J by O(1/h), so its error is not of the method's
    /// order; the stiff test set's orego lost two digits with h within a factor 2 of h_lu.)
    pub quot1: f64,
    /// RADAU5's QUOT2 (WORK(4)): see `quot1`. Default 1.2, RADAU5's: a step up to 20 % shorter
    /// than the controller dares costs less than an LU.
    pub quot2: f64,
    /// A J is re-evaluated after this many accepted steps, however well it serves. Default 5:
    /// an old J keeps the order but not the error constant, and on the default plant (its valve
    /// and drag nonlinear) the controller's steps shrink as J ages: 10 s of the default
    /// experiment took 15 733 steps with a J at every step, 17 708 with one every 3, 18 893
    /// every 5, 20 748 every 8 and 31 714 every 25 (rtol 1e-6, `bench-fmu`, measured while
    /// choosing this default); every 5 steps paid the fewest Jacobians and LUs together for
    /// the steps it took.
    pub max_jacobian_age: u32,
    /// The fixed-step driver ([`Ros34pw2Fixed`]) re-evaluates J (and refactorises W) every this
    /// many steps. Default 10: 10 ms of a 1 ms real-time step, shorter than the plant's slowest
    /// nonlinear change (the valve's opening over a move), and the step's work is bounded by
    /// one Jacobian, one LU and four stages whichever step it is.
    pub fixed_jacobian_interval: u32,
}

impl Default for Ros34pw2Options {
    fn default() -> Self {
        Ros34pw2Options {
            control: Rodas5POptions::for_order(ERR_ORDER),
            quot1: 1.0,
            quot2: 1.2,
            max_jacobian_age: 5,
            fixed_jacobian_interval: 10,
        }
    }
}

/// The method's buffers and W's factorisation, kept between calls in the state's cache (no
/// allocation per call); rebuilt empty in a clone or a restored state.
pub(crate) struct Work {
    f0: Vec<f64>,
    f1: Vec<f64>,
    dfdt: Vec<f64>,
    jac: DMatrix<f64>,
    /// The stamp of the constant part of the J that `jac` holds (see
    /// [`OdeSystem::jacobian_constant_part`]), None while it holds none.
    jac_holds: Option<u64>,
    u: Vec<Vec<f64>>,
    y: Vec<f64>,
    fy: Vec<f64>,
    x1: Vec<f64>,
    sc: Vec<f64>,
    rhs: Vec<f64>,
    /// The dense output's coefficients of the last step (3 n).
    coef: Vec<f64>,
    scratch: Vec<f64>,
    pattern: PatternCache,
    lu: Option<Factorisation<f64>>,
    /// The step size W's factorisation in `lu` was made for with the kept J; None while `lu`
    /// holds none of the kept J (a fresh or restored workspace).
    lu_h: Option<f64>,
    /// `jac` and `dfdt` hold the state's kept J (false in a fresh workspace until copied).
    synced: bool,
}

impl Work {
    fn new(n: usize) -> Self {
        Work {
            f0: vec![0.0; n],
            f1: vec![0.0; n],
            dfdt: vec![0.0; n],
            jac: DMatrix::zeros(n, n),
            jac_holds: None,
            u: vec![vec![0.0; n]; STAGES],
            y: vec![0.0; n],
            fy: vec![0.0; n],
            x1: vec![0.0; n],
            sc: vec![0.0; n],
            rhs: vec![0.0; n],
            coef: vec![0.0; 3 * n],
            scratch: vec![0.0; n],
            pattern: PatternCache::default(),
            lu: None,
            lu_h: None,
            synced: false,
        }
    }
}

/// Runs `body` with the workspace taken out of the state's cache (made for `n` states if it
/// holds none or one of another size) and puts it back after, whatever the outcome. A fresh
/// workspace takes the kept J from the state.
fn with_work<R>(
    integ: &mut Stepper<State>,
    body: impl FnOnce(&mut Stepper<State>, &mut Work) -> R,
) -> R {
    let n = integ.x.len();
    let mut w = match integ.state.cache.0.take() {
        Some(w) if w.f0.len() == n => w,
        _ => Box::new(Work::new(n)),
    };
    if !w.synced {
        let kept = &integ.state.kept;
        if kept.jac.len() == n * n {
            w.jac.copy_from_slice(&kept.jac);
        }
        if kept.dfdt.len() == n {
            w.dfdt.copy_from_slice(&kept.dfdt);
        }
        w.jac_holds = None;
        w.lu_h = None;
        w.synced = true;
    }
    let result = body(integ, &mut w);
    integ.state.cache.0 = Some(w);
    result
}

/// f0 = f(t, x) at the current point into `w.f0`; an error if not finite.
fn eval_f0<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
) -> Result<(), SolverError> {
    super::rodas5p::eval_f0(integ, sys, &mut w.f0)
}

/// Is the kept J a constant Jacobian of this system ([`OdeSystem::constant_jacobian`], the same
/// stamp)? It then serves for ever: no rejection or age makes it re-evaluated.
fn constant_kept<S: OdeSystem + ?Sized>(integ: &Stepper<State>, sys: &S) -> bool {
    let kept = &integ.state.kept;
    kept.stamp.is_some() && kept.stamp == sys.constant_jacobian() && !kept.jac.is_empty()
}

/// Evaluates J (and ∂f/∂t for a non-autonomous system) at the current point, with f0 in
/// `w.f0`, and keeps it in the state: W must then be refactorised.
fn evaluate_jacobian<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    autonomous: bool,
) -> Result<(), SolverError> {
    let Stepper {
        t,
        x,
        stats,
        state,
        options,
        ..
    } = integ;
    let ok = jacobian::evaluate(
        sys,
        stats,
        *t,
        x,
        &w.f0,
        &options.atol,
        options.rtol,
        &mut w.jac,
        &mut w.jac_holds,
    ) && (autonomous || jacobian::time_derivative(sys, stats, *t, x, &w.f0, &mut w.dfdt));
    let kept = &mut state.kept;
    kept.jac.clear();
    kept.dfdt.clear();
    kept.h_lu = 0.0;
    w.lu_h = None;
    if !ok {
        return Err(SolverError::new(
            SolverErrorKind::NonFinite,
            *t,
            "the Jacobian (or df/dt) is not finite at the current point",
        ));
    }
    kept.jac.extend_from_slice(w.jac.as_slice());
    if !autonomous {
        kept.dfdt.extend_from_slice(&w.dfdt);
    }
    kept.age = 0;
    kept.current = true;
    kept.stamp = sys.constant_jacobian();
    Ok(())
}

/// W = I/(h_lu γ) − J of the kept J for a step of size `h`: the kept factorisation if it was
/// made for h to within [`SAME_STEP`] (the steps to successive communication points differ by
/// the rounding of t), rebuilt, uncounted, in a fresh workspace; else a new one for h. Returns
/// false if W is singular.
fn factorised_w<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    h: f64,
) -> bool {
    let kept = &mut integ.state.kept;
    let h_kept = kept.h_lu;
    let serves = h_kept > 0.0 && (h - h_kept).abs() <= SAME_STEP * h;
    let h_lu = if serves { h_kept } else { h };
    if serves && w.lu_h == Some(h_kept) {
        return true;
    }
    if !serves {
        integ.stats.lu_decompositions += 1;
    }
    let part = w.pattern.partition_within(&w.jac, sys.jacobian_pattern());
    let lu =
        w.lu.get_or_insert_with(|| Factorisation::new(Arc::clone(part)));
    let c = 1.0 / (h_lu * GAMMA);
    let ok = factor_with_fallback(lu, part, Shifted { c, jac: &w.jac });
    if ok {
        kept.h_lu = h_lu;
        w.lu_h = Some(h_lu);
    } else {
        kept.h_lu = 0.0;
        w.lu_h = None;
    }
    ok
}

/// One ROS34PW2 step of size h from (t, x), with f0 = f(t, x) in `w.f0` and W factorised (for
/// the kept J and some h_lu) in `w.lu`. On success `w.x1` holds y1 and the return value is the
/// error norm.
fn step<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    h: f64,
    autonomous: bool,
) -> Result<f64, Reject> {
    let Some(lu) = w.lu.as_ref() else {
        return Err(Reject::Singular);
    };
    let t = integ.t;
    for s in 0..STAGES {
        if s == 0 {
            w.fy.copy_from_slice(&w.f0);
        } else {
            w.y.copy_from_slice(&integ.x);
            for j in 0..s {
                axpy(A[s][j], &w.u[j], &mut w.y);
            }
            eval(sys, &mut integ.stats, t + C_NODES[s] * h, &w.y, &mut w.fy);
        }
        w.rhs.copy_from_slice(&w.fy);
        for j in 0..s {
            axpy(C[s][j] / h, &w.u[j], &mut w.rhs);
        }
        if !autonomous && D[s] != 0.0 {
            axpy(h * D[s], &w.dfdt, &mut w.rhs);
        }
        lu.solve(&mut w.rhs, &mut w.scratch);
        if !all_finite(&w.rhs) {
            return Err(Reject::NonFinite);
        }
        w.u[s].copy_from_slice(&w.rhs);
    }
    w.x1.copy_from_slice(&integ.x);
    for j in 0..STAGES {
        axpy(M[j], &w.u[j], &mut w.x1);
    }
    if !all_finite(&w.x1) {
        return Err(Reject::NonFinite);
    }
    // The error estimate Σ e_j U_j into the (free) stage argument buffer.
    w.y.fill(0.0);
    for j in 0..STAGES {
        axpy(E[j], &w.u[j], &mut w.y);
    }
    error_norm(&integ.options, &integ.x, &w.x1, &w.y, &mut w.sc)
}

/// The cubic Hermite interpolant of a step of size h from (y0, f0) to (y1, f1), as the
/// coefficients of Rodas5P's extension y(θ) = (1 − θ) y0 + θ (y1 + (1 − θ) (K1 + θ (K2 + θ K3)))
/// ([`dense`](super::rodas5p::dense)): K1 = h f0 − Δ, K2 = 2Δ − h (f0 + f1), K3 = 0 with
/// Δ = y1 − y0. Into `coef` (K1 of every component, then K2, then K3).
pub(crate) fn hermite(y0: &[f64], y1: &[f64], f0: &[f64], f1: &[f64], h: f64, coef: &mut [f64]) {
    let n = y0.len();
    for i in 0..n {
        let delta = y1[i] - y0[i];
        coef[i] = h * f0[i] - delta;
        coef[n + i] = 2.0 * delta - h * (f0[i] + f1[i]);
        coef[2 * n + i] = 0.0;
    }
}
