//! Rodas5P: an 8-stage, order-5 (embedded order 4), A-stable, stiffly accurate Rosenbrock
//! method with an order-4 dense output.
//!
//! Source of the coefficients: G. Steinebach, "Construction of Rosenbrock–Wanner method Rodas5P
//! and numerical benchmarks within the Julia Differential Equations package", BIT Numer. Math.
//! 63:27 (2023), as tabulated (same numbers, same transformed form) in SciML
//! OrdinaryDiffEq.jl, `Rodas5PTableau` (file `rosenbrock_tableaus.jl`). The tableau's order
//! conditions are checked in `tests/solver_rodas5p_tableau.rs`.
//!
//! # Form of the method
//!
//! The transformed form of Hairer & Wanner II, Sec. IV.7 (eq. 7.4'), which needs only one
//! LU of W = I/(h γ) - J per step and no matrix-vector products:
//!
//! ```text
//! (I/(h γ) - J) U_i = f(t0 + c_i h, y0 + Σ_{j<i} a_ij U_j) + Σ_{j<i} (C_ij / h) U_j + h d_i ∂f/∂t
//! y1 = y0 + Σ m_j U_j,    error estimate = U_8   (y1 - ŷ1, ŷ1 of order 4)
//! ```
//!
//! Relation to the classical form k_i = h f(y0 + Σ α_ij k_j) + h J Σ γ_ij k_j, y1 = y0 + Σ b_j k_j
//! (Γ = (γ_ij) lower triangular, diagonal γ): Γ⁻¹ = I/γ - C, α = A Γ, bᵀ = mᵀ Γ, and
//! d_i = Σ_j γ_ij. Stages 6–8 evaluate f at t0 + h and are "stiffly accurate" stages:
//! Y_7 = Y_6 + U_6, Y_8 = Y_7 + U_7, y1 = Y_8 + U_8, so m = row 8 of A plus e_8.
//!
//! Dense output (same source): with K_r = Σ_j H_rj U_j (r = 1, 2, 3) and θ = (t - t0)/h,
//! y(θ) = (1-θ) y0 + θ (y1 + (1-θ) (K_1 + θ (K_2 + θ K_3))).
//! (`src/solver/rodas5p/dense_output.rs`).
//!
//! # Solves
//!
//! Each stage solves with W (its factorisations: `src/solver/rodas5p/factor.rs`). A varying J is factorised at every step with the structured LU of
//! [`super::linalg`] (by the fixed-step driver, when J varies in at most half its rows, by
//! [`VaryingRows`](super::linalg::VaryingRows): the constant rows eliminated once per step size, the varying rows' Schur
//! complement at every step). A constant J ([`OdeSystem::constant_jacobian`]) keeps its factorisations
//! for the step sizes in use, and for a system of up to 128 states (`step_map::MAX_DIM`) each one
//! comes with W⁻¹ made from it (n solves, once per factorisation): the eight solves of a step
//! are then dense products (`dense::DenseInverse`), which on the LOES with the plate (blocks of one or
//! two states and a border of five) cost a fraction of the structured solve's bookkeeping.

// Index loops over stages and components mirror the formulas they implement.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector};

mod dense_output;
mod factor;
mod state;

pub(crate) use dense_output::dense;
use dense_output::dense_coefficients;
pub(super) use dense_output::interpolate;
use factor::factorise;
pub(crate) use factor::Factor;
pub(crate) use state::check_restored;
pub(crate) use state::{Ahead, Controller};

pub use state::{Rodas5P, State, STATE_VERSION};

use super::common::{
    all_finite, axpy, eval, initial_step, jacobian_here, plan_step, rms, scale_into,
    with_kept_memory, NextStep, Outputs, Workspace,
};
use super::jacobian;
use super::linalg::PatternCache;
use super::method::Stepper;
use super::{OdeSystem, SolverError, SolverErrorKind, SolverOptions};

/// Number of stages.
pub const STAGES: usize = 8;

/// Diagonal coefficient γ of the method.
pub const GAMMA: f64 = 0.21193756319429014;

/// a_ij of the transformed form (row i = stage i+1, columns j < i). Rows 7 and 8 are the
/// stiffly accurate continuation: Y_7 = Y_6 + U_6, Y_8 = Y_7 + U_7.
pub const A: [[f64; STAGES]; STAGES] = {
    const R6: [f64; 5] = [
        -7.502846399306121,
        2.561846144803919,
        -11.627539656261098,
        -0.18268767659942256,
        0.030198172008377946,
    ];
    [
        [0.0; 8],
        [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [
            2.849394379747939,
            0.45842242204463923,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
        [
            -6.954028509809101,
            2.489845061869568,
            -10.358996098473584,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
        [
            2.8029986275628964,
            0.5072464736228206,
            -0.3988312541770524,
            -0.04721187230404641,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
        [R6[0], R6[1], R6[2], R6[3], R6[4], 0.0, 0.0, 0.0],
        [R6[0], R6[1], R6[2], R6[3], R6[4], 1.0, 0.0, 0.0],
        [R6[0], R6[1], R6[2], R6[3], R6[4], 1.0, 1.0, 0.0],
    ]
};

/// Weights m_j of the transformed form: y1 = y0 + Σ m_j U_j (= row 8 of A plus e_8).
pub const M: [f64; STAGES] = [A[7][0], A[7][1], A[7][2], A[7][3], A[7][4], 1.0, 1.0, 1.0];

/// C_ij of the transformed form (strictly lower triangular; sign as in the stage equation
/// in the module documentation).
pub const C: [[f64; STAGES]; STAGES] = [
    [0.0; 8],
    [-14.155112264123755, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [
        -17.97296035885952,
        -2.859693295451294,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        147.12150275711716,
        -1.41221402718213,
        71.68940251302358,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        165.43517024871676,
        -0.4592823456491126,
        42.90938336958603,
        -5.961986721573306,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        24.854864614690072,
        -3.0009227002832186,
        47.4931110020768,
        5.5814197821558125,
        -0.6610691825249471,
        0.0,
        0.0,
        0.0,
    ],
    [
        30.91273214028599,
        -3.1208243349937974,
        77.79954646070892,
        34.28646028294783,
        -19.097331116725623,
        -28.087943162872662,
        0.0,
        0.0,
    ],
    [
        37.80277123390563,
        -3.2571969029072276,
        112.26918849496327,
        66.9347231244047,
        -40.06618937091002,
        -54.66780262877968,
        -9.48861652309627,
        0.0,
    ],
];

/// Stage times c_i (= row sums of α = A Γ; checked in the tableau test).
pub const C_NODES: [f64; STAGES] = [
    0.0,
    0.6358126895828704,
    0.4095798393397535,
    0.9769306725060716,
    0.4288403609558664,
    1.0,
    1.0,
    1.0,
];

/// d_i = γ_i = Σ_j γ_ij, the coefficients of h ∂f/∂t (zero for the stiffly accurate stages).
pub const D: [f64; STAGES] = [
    0.21193756319429014,
    -0.42387512638858027,
    -0.3384627126235924,
    1.8046452872882734,
    2.325825639765069,
    0.0,
    0.0,
    0.0,
];

/// Dense-output coefficients H_rj: K_r = Σ_j H_rj U_j.
pub const H: [[f64; STAGES]; 3] = [
    [
        25.948786856663858,
        -2.5579724845846235,
        10.433815404888879,
        -2.3679251022685204,
        0.524948541321073,
        1.1241088310450404,
        0.4272876194431874,
        -0.17202221070155493,
    ],
    [
        -9.91568850695171,
        -0.9689944594115154,
        3.0438037242978453,
        -24.495224566215796,
        20.176138334709044,
        15.98066361424651,
        -6.789040303419874,
        -6.710236069923372,
    ],
    [
        11.419903575922262,
        2.8879645146136994,
        72.92137995996029,
        80.12511834622643,
        -52.072871366152654,
        -59.78993625266729,
        -0.15582684282751913,
        4.883087185713722,
    ],
];

/// The classical form (α, Γ, b) of the method, computed from the transformed tableau:
/// Γ = (I/γ - C)⁻¹, α = A Γ, bᵀ = mᵀ Γ. Used by the order-condition tests.
pub fn classical_form() -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
    let s = STAGES;
    let ginv = DMatrix::from_fn(s, s, |i, j| if i == j { 1.0 / GAMMA } else { -C[i][j] });
    let gam = ginv.try_inverse().unwrap_or_else(|| DMatrix::zeros(s, s));
    let a = DMatrix::from_fn(s, s, |i, j| A[i][j]);
    let alpha = &a * &gam;
    let m = DMatrix::from_fn(1, s, |_, j| M[j]);
    let b = (&m * &gam).transpose();
    (alpha, gam, DVector::from_column_slice(b.as_slice()))
}

/// Order of the error estimator's local error exponent minus one: err ~ h^5.
const ERR_ORDER: f64 = 5.0;

/// The tunables of the Rodas5P integrator's step-size control, with their defaults, in the
/// manner of the WORK parameters of Hairer's RODAS (its name given where it has one). The
/// integrator uses `Rodas5POptions::default()`; they are not part of
/// [`SolverOptions`], which the integrator saves with its state.
///
/// The step size after an accepted step is that of a PI controller (Hairer & Wanner II,
/// Sec. IV.2 / Gustafsson 1991): h_new = h · safe · err^(-β1) · err_prev^(β2), with
/// β1 = 0.7/k, β2 = 0.4/k, k = 5 (err^(-1/k) on the first step), h_new / h within
/// [fac_min, fac_max] and not above 1 after a rejection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rodas5POptions {
    /// Safety factor of the step-size prediction. RODAS's SAFE, WORK(5). Default 0.9, RODAS's.
    pub safe: f64,
    /// Exponent β1 of the current error in the PI controller. Default 0.7/5 = 0.14.
    pub beta1: f64,
    /// Exponent β2 of the previous accepted step's error in the PI controller. Default
    /// 0.4/5 = 0.08.
    pub beta2: f64,
    /// Smallest h_new / h the step-size prediction gives (also after a rejection by the error
    /// test). RODAS's WORK(3). Default 0.2, RODAS's.
    pub fac_min: f64,
    /// Largest h_new / h. RODAS's WORK(4). Default 6, RODAS's.
    pub fac_max: f64,
    /// Floor of an accepted step's error norm in the controller (and in the error it
    /// remembers), so that err^(-β1) stays finite for a vanishing error estimate.
    /// Default 1e-10.
    pub err_floor: f64,
    /// Factor of h after an attempt whose stages were not finite. Default 0.25.
    pub nonfinite_reject: f64,
    /// Factor of h after an attempt whose iteration matrix was singular. Default 0.5.
    pub singular_reject: f64,
}

impl Default for Rodas5POptions {
    fn default() -> Self {
        Rodas5POptions::for_order(ERR_ORDER)
    }
}

impl Rodas5POptions {
    /// The defaults for an error estimate err ~ h^(k+1) (k = 5 for Rodas5P's pair; another
    /// method with this controller, ROS34PW2, has k = 3): β1 = 0.7/k, β2 = 0.4/k.
    pub fn for_order(k: f64) -> Self {
        Rodas5POptions {
            safe: 0.9,
            beta1: 0.7 / k,
            beta2: 0.4 / k,
            fac_min: 0.2,
            fac_max: 6.0,
            err_floor: 1e-10,
            nonfinite_reject: 0.25,
            singular_reject: 0.5,
        }
    }

    /// h_new / h after a step accepted with error norm `err`, for an error estimate of order
    /// `k` (see [`Rodas5POptions::for_order`]); records the step in `hist`.
    pub(crate) fn accepted(&self, hist: &mut Controller, err: f64, k: f64) -> f64 {
        let e = err.max(self.err_floor);
        let mut fac = if hist.err_prev > 0.0 {
            self.safe
                * crate::math::powf(e, -self.beta1)
                * crate::math::powf(hist.err_prev, self.beta2)
        } else {
            self.safe * crate::math::powf(e, -1.0 / k)
        };
        fac = fac.clamp(self.fac_min, self.fac_max);
        if hist.last_rejected {
            fac = fac.min(1.0);
        }
        hist.err_prev = e;
        hist.last_rejected = false;
        hist.first = false;
        fac
    }

    /// h_new / h after a rejected attempt (`result`: its error norm, or why it failed), for an
    /// error estimate of order `k`; records the rejection in `hist` and in `run` (its count of
    /// consecutive rejections and whether the last failed by non-finite values), with the error
    /// that ends the call if there were too many in a row.
    pub(crate) fn rejected(
        &self,
        hist: &mut Controller,
        run: &mut Rejections,
        result: Result<f64, Reject>,
        k: f64,
        (t, h, max_consecutive): (f64, f64, u32),
    ) -> (f64, Option<SolverError>) {
        run.consecutive += 1;
        hist.last_rejected = true;
        let fac = match result {
            Ok(err) => {
                run.last_nonfinite = false;
                (self.safe * crate::math::powf(err, -1.0 / k)).clamp(self.fac_min, 1.0)
            }
            Err(Reject::NonFinite) => {
                run.last_nonfinite = true;
                self.nonfinite_reject
            }
            Err(Reject::Singular) => self.singular_reject,
        };
        if run.consecutive > max_consecutive {
            let kind = if run.last_nonfinite {
                SolverErrorKind::NonFinite
            } else {
                SolverErrorKind::TooManyRejections
            };
            let n = run.consecutive;
            let message = format!("{n} consecutive step rejections (last h = {h:e})");
            return (fac, Some(SolverError::new(kind, t, message)));
        }
        (fac, None)
    }
}

/// The rejections of one call's step loop: how many in a row, and whether the last attempt
/// failed by non-finite values.
#[derive(Default)]
pub(crate) struct Rejections {
    pub consecutive: u32,
    pub last_nonfinite: bool,
}

impl Rejections {
    /// Why the step size fell below the minimum, from the last rejection.
    pub(crate) fn why_small(&self) -> (SolverErrorKind, &'static str) {
        if self.last_nonfinite {
            (SolverErrorKind::NonFinite, "after non-finite values of f")
        } else {
            (SolverErrorKind::StepTooSmall, "to meet the tolerances")
        }
    }

    /// A step was accepted.
    pub(crate) fn accepted(&mut self) {
        self.consecutive = 0;
        self.last_nonfinite = false;
    }
}

/// Why a step attempt failed.
pub(crate) enum Reject {
    /// A stage produced NaN/inf.
    NonFinite,
    /// W = I/(hγ) - J is singular for this h.
    Singular,
}

/// Workspace of `advance`, kept between calls in the method's cache (no allocation per
/// call); its contents are overwritten before they are read.
pub(crate) struct Work {
    pub(super) f0: Vec<f64>,
    dfdt: Vec<f64>,
    jac: DMatrix<f64>,
    /// The stamp of the constant part of the J that `jac` holds (see
    /// [`OdeSystem::jacobian_constant_part`]), None while it holds none.
    jac_holds: Option<u64>,
    pub(super) u: Vec<Vec<f64>>,
    y: Vec<f64>,
    fy: Vec<f64>,
    pub(super) x1: Vec<f64>,
    sc: Vec<f64>,
    rhs: DVector<f64>,
    /// Scratch of the structured solve.
    scratch: Vec<f64>,
    /// Partition of J into blocks and border (see [`super::linalg`]).
    pattern: PatternCache,
    /// The memory of the last factorisation of a Jacobian that changes from step to step
    /// (its contents are stale): refactorised into, so a step allocates nothing.
    spare: Option<Factor>,
}

impl Workspace for Work {
    type Lu = Factor;
    fn new(n: usize) -> Self {
        Work {
            f0: vec![0.0; n],
            dfdt: vec![0.0; n],
            jac: DMatrix::zeros(n, n),
            jac_holds: None,
            u: vec![vec![0.0; n]; STAGES],
            y: vec![0.0; n],
            fy: vec![0.0; n],
            x1: vec![0.0; n],
            sc: vec![0.0; n],
            rhs: DVector::zeros(n),
            scratch: vec![0.0; n],
            pattern: PatternCache::default(),
            spare: None,
        }
    }
    fn dim(&self) -> usize {
        self.f0.len()
    }
    fn spare(&mut self) -> &mut Option<Factor> {
        &mut self.spare
    }
}

/// J (and, for a non-autonomous system, ∂f/∂t) at the integrator's current point into `w`, with
/// f0 = f(t, x) already in `w.f0`; an error if either is not finite.
pub(super) fn jacobian_at_point<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    stamp: Option<u64>,
    autonomous: bool,
) -> Result<(), SolverError> {
    let t = integ.t;
    let ok = jacobian_here(
        integ,
        |s: &mut State| (&mut s.counted, &mut s.cache),
        sys,
        stamp,
        &w.f0,
        None,
        &mut w.jac,
        &mut w.jac_holds,
    ) && (autonomous
        || jacobian::time_derivative(sys, &mut integ.stats, t, &integ.x, &w.f0, &mut w.dfdt));
    if ok {
        Ok(())
    } else {
        Err(SolverError::new(
            SolverErrorKind::NonFinite,
            t,
            "the Jacobian (or df/dt) is not finite at the current point",
        ))
    }
}

/// One step from the current point, with f0, J (and ∂f/∂t) there already in `w`: W factorised
/// for about `h` (see [`factorise`]; `shorten` lets a constant J's kept LU shorten the step),
/// then the stages. Returns the step size taken and the step's error norm, or why it failed.
/// The adaptive driver and the fixed-step one (`super::fixed`, with `by_rows`: a J varying in
/// few rows factorised by its varying rows' Schur complement) step through this.
#[allow(clippy::too_many_arguments)]
pub(super) fn factorised_step<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    lus: &mut Vec<Factor>,
    stamp: Option<u64>,
    h: f64,
    shorten: bool,
    by_rows: bool,
    autonomous: bool,
) -> (f64, Result<f64, Reject>) {
    let (h, ok) = factorise(integ, sys, w, lus, stamp, h, shorten, by_rows);
    let result = match lus.first() {
        Some(f) if ok => step(integ, sys, w, f, h, autonomous),
        _ => Err(Reject::Singular),
    };
    (h, result)
}

/// One Rodas5P step of size h from (t, x) with f0 = f(t, x), J and (if non-autonomous)
/// ∂f/∂t already in `w`. On success `w.x1` holds y1 and the return value is the error norm.
///
/// On x86-64 processors with AVX2 the step is the same code compiled for 4-wide vectors (its
/// stage sums are vector updates over the states); multiplications and additions stay separate,
/// so the bits are those of the portable code (see [`super::dense`]).
fn step<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    lu: &Factor,
    h: f64,
    autonomous: bool,
) -> Result<f64, Reject> {
    #[cfg(target_arch = "x86_64")]
    {
        #[cfg(test)]
        let portable = tests::PORTABLE_ONLY.with(|p| p.get());
        #[cfg(not(test))]
        let portable = false;
        if !portable && std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { step_avx2(integ, sys, w, lu, h, autonomous) };
        }
    }
    step_body(integ, sys, w, lu, h, autonomous)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn step_avx2<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    lu: &Factor,
    h: f64,
    autonomous: bool,
) -> Result<f64, Reject> {
    step_body(integ, sys, w, lu, h, autonomous)
}

#[inline(always)]
fn step_body<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    lu: &Factor,
    h: f64,
    autonomous: bool,
) -> Result<f64, Reject> {
    let n = integ.x.len();
    let t = integ.t;
    for s in 0..STAGES {
        // Stage argument Y_s and f(Y_s) (stage 1 is f0).
        // The sums run over the stages j in the outer loop, a contiguous axpy per stage (the
        // same additions in the same order as a per-component sum over j, so the same bits).
        if s == 0 {
            w.fy.copy_from_slice(&w.f0);
        } else {
            w.y.copy_from_slice(&integ.x);
            for j in 0..s {
                axpy(A[s][j], &w.u[j], &mut w.y);
            }
            eval(sys, &mut integ.stats, t + C_NODES[s] * h, &w.y, &mut w.fy);
        }
        let rhs = w.rhs.as_mut_slice();
        rhs.copy_from_slice(&w.fy);
        for j in 0..s {
            axpy(C[s][j] / h, &w.u[j], rhs);
        }
        if !autonomous && D[s] != 0.0 {
            for i in 0..n {
                rhs[i] += h * D[s] * w.dfdt[i];
            }
        }
        lu.solve(w.rhs.as_mut_slice(), &mut w.scratch);
        if !all_finite(w.rhs.as_slice()) {
            return Err(Reject::NonFinite);
        }
        w.u[s].copy_from_slice(w.rhs.as_slice());
    }
    w.x1.copy_from_slice(&integ.x);
    for j in 0..STAGES {
        axpy(M[j], &w.u[j], &mut w.x1);
    }
    if !all_finite(&w.x1) {
        return Err(Reject::NonFinite);
    }
    error_norm(&integ.options, &integ.x, &w.x1, &w.u[STAGES - 1], &mut w.sc)
}

/// The weighted RMS norm of a step's error estimate `e` from `x0` to `x1` (`sc` receives the
/// weights), or a rejection if it is not finite.
#[inline]
pub(crate) fn error_norm(
    options: &SolverOptions,
    x0: &[f64],
    x1: &[f64],
    e: &[f64],
    sc: &mut [f64],
) -> Result<f64, Reject> {
    scale_into(&options.atol, options.rtol, x0, x1, sc);
    let err = rms(e, sc);
    if err.is_finite() {
        Ok(err)
    } else {
        Err(Reject::NonFinite)
    }
}

/// Evaluate f0 (and Jacobian/∂f/∂t lazily later) at the current point, failing on NaN/inf.
pub(crate) fn eval_f0<St, S: OdeSystem + ?Sized>(
    integ: &mut Stepper<St>,
    sys: &S,
    f0: &mut [f64],
) -> Result<(), SolverError> {
    eval(sys, &mut integ.stats, integ.t, &integ.x, f0);
    if all_finite(f0) {
        Ok(())
    } else {
        Err(SolverError::new(
            SolverErrorKind::NonFinite,
            integ.t,
            "the right-hand side f(t, x) is not finite at the current point",
        ))
    }
}

/// Advance `integ` to exactly `t_end` with Rodas5P (called through [`OdeMethod::advance`](crate::solver::OdeMethod::advance)), or
/// with steps free to run past it up to `limit` (`Integrator::advance_past`): the step that
/// covers `t_end` is then kept in the state's `ahead` and `t_end`'s state read from its dense output.
pub(crate) fn advance<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    t_end: f64,
    limit: f64,
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
) -> Result<(), SolverError> {
    let opts = Rodas5POptions::default();
    let stamp = sys.constant_jacobian();
    with_memory(integ, stamp, |integ, w, lus| {
        let span = (t_end, limit);
        advance_with(integ, sys, &opts, span, times, out, w, lus, stamp)
    })
}

/// Runs `body` with Rodas5P's workspace and its kept factorisations (see `with_kept_memory`),
/// for the Jacobian `stamp`: the adaptive driver's and the fixed-step driver's (`super::fixed`).
pub(super) fn with_memory<R>(
    integ: &mut Stepper<State>,
    stamp: Option<u64>,
    body: impl FnOnce(&mut Stepper<State>, &mut Work, &mut Vec<Factor>) -> R,
) -> R {
    with_kept_memory(integ, stamp, |s: &mut State| &mut s.cache, body)
}

#[allow(clippy::too_many_arguments)]
fn advance_with<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    opts: &Rodas5POptions,
    (t_end, limit): (f64, f64),
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
    w: &mut Work,
    lus: &mut Vec<Factor>,
    stamp: Option<u64>,
) -> Result<(), SolverError> {
    let n = integ.x.len();
    let autonomous = sys.is_autonomous();
    let mut outputs = Outputs::new(times, integ.t, n);
    eval_f0(integ, sys, &mut w.f0)?;
    if integ.h <= 0.0 {
        integ.h = initial_step(sys, integ, &w.f0, t_end, 4.0);
    }
    let mut jac_ok = false; // J (and ∂f/∂t) evaluated at the current point?
    let mut attempts: u64 = 0;
    let mut rejections = Rejections::default();
    loop {
        let why_small = || rejections.why_small();
        let quantise = stamp.is_some();
        let (h, last, h_proposed) = match plan_step(
            integ,
            t_end,
            limit,
            &w.f0,
            &mut attempts,
            quantise,
            why_small,
        )? {
            NextStep::Done => return Ok(()),
            NextStep::Step { h, last, proposed } => (h, last, proposed),
        };
        let t = integ.t;
        if !jac_ok {
            jacobian_at_point(integ, sys, w, stamp, autonomous)?;
            jac_ok = true;
        }
        // W = I/(h γ) - J, one LU for all 8 stages. A step free to go past t_end that does
        // not end on the limit may be shortened to use a kept LU of a constant J.
        let shorten = limit > t_end && !last;
        let (h, result) = factorised_step(integ, sys, w, lus, stamp, h, shorten, false, autonomous);
        match result {
            Ok(err) if err <= 1.0 => {
                let t1 = if last { limit } else { t + h };
                // Past t_end (only when the caller allows it): keep the step and report t_end.
                let free = limit > t_end;
                let past = free && t1 > t_end;
                let done = last || (free && t1 >= t_end);
                if outputs.pending(t1) {
                    let (x0, x1, u) = (&integ.x, &w.x1, &w.u);
                    outputs.emit(
                        t,
                        h,
                        t1,
                        x1,
                        &mut |th, buf| interpolate(x0, x1, u, th, buf),
                        out,
                    );
                }
                if past {
                    integ.state.ahead.keep(t, t1, h, &integ.x, &w.x1);
                    dense_coefficients(&w.u, &mut integ.state.ahead.coef);
                    let a = &integ.state.ahead;
                    dense(&a.x0, &a.x1, &a.coef, (t_end - t) / h, &mut integ.x);
                    integ.t = t_end;
                } else {
                    integ.x.copy_from_slice(&w.x1);
                    integ.t = t1;
                }
                integ.stats.accepted += 1;
                rejections.accepted();
                // PI step-size controller.
                let fac = opts.accepted(&mut integ.state.hist, err, ERR_ORDER);
                let mut h_new = h * fac;
                if last {
                    // The step was shortened to hit the limit: do not let that shrink the next.
                    h_new = h_new.max(h_proposed);
                }
                integ.h = h_new.min(integ.options.max_step);
                if done {
                    return Ok(());
                }
                eval_f0(integ, sys, &mut w.f0)?;
                jac_ok = false;
            }
            result => {
                integ.stats.rejected += 1;
                let limits = (t, h, integ.options.max_consecutive_rejections);
                let hist = &mut integ.state.hist;
                let (fac, too_many) =
                    opts.rejected(hist, &mut rejections, result, ERR_ORDER, limits);
                integ.h = h * fac;
                if let Some(e) = too_many {
                    return Err(e);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;

    use nalgebra::DMatrix;

    use crate::solver::testset::problem;
    use crate::solver::{Atol, Integrator, Method, OdeSystem, SolverOptions};

    thread_local! {
        /// Steps take the portable code even where AVX2 is available.
        pub(super) static PORTABLE_ONLY: Cell<bool> = const { Cell::new(false) };
    }

    /// A stiff lag driving a lightly damped mode, declared linear with a constant Jacobian.
    struct Linear;

    impl OdeSystem for Linear {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&self, _t: f64, x: &[f64], f: &mut [f64]) {
            f[0] = -1e4 * (x[0] - 1.0);
            f[1] = 300.0 * x[2];
            f[2] = -300.0 * x[1] - 12.0 * x[2] + 300.0 * x[0];
        }
        fn jacobian(&self, _t: f64, _x: &[f64], j: &mut DMatrix<f64>) -> bool {
            j.copy_from_slice(&[-1e4, 0.0, 300.0, 0.0, 0.0, -300.0, 0.0, 300.0, -12.0]);
            true
        }
        fn constant_jacobian(&self) -> Option<u64> {
            Some(7)
        }
        fn is_autonomous(&self) -> bool {
            true
        }
    }

    /// The step compiled for AVX2 gives the portable step's bits: the same run both ways ends in
    /// equal integrators (state, step size, history, counters), on a stiff nonlinear problem
    /// and on a linear one with a constant Jacobian (the explicit inverse's products).
    #[test]
    fn vectorised_step_has_the_portable_bits() {
        let hires = problem("hires").unwrap();
        let cases: [(&str, &dyn OdeSystem, Vec<f64>); 2] = [
            ("hires", hires.as_ref(), hires.y0()),
            ("linear", &Linear, vec![0.0; 3]),
        ];
        for (name, p, y0) in cases {
            let opts = SolverOptions {
                method: Method::Rodas5P,
                rtol: 1e-7,
                atol: Atol::Scalar(1e-9),
                ..Default::default()
            };
            let run = |portable: bool| {
                PORTABLE_ONLY.with(|f| f.set(portable));
                let mut integ = Integrator::new(opts.clone(), 0.0, y0.clone()).unwrap();
                for k in 1..=20 {
                    integ.advance_to(p, k as f64 * 0.05).unwrap();
                }
                PORTABLE_ONLY.with(|f| f.set(false));
                integ
            };
            let (vectorised, portable) = (run(false), run(true));
            assert!(vectorised.stats().accepted > 20, "{name}");
            assert_eq!(vectorised, portable, "{name}");
        }
    }
}
