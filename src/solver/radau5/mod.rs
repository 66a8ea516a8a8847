//! Radau IIA of order 5 (3 stages), implemented in the manner of Hairer's RADAU5
//! (E. Hairer & G. Wanner, Solving ODEs II, Sec. IV.8; Fortran code `radau5.f`, version of
//! 1996/2002). All constants are those of `radau5.f`: the method's coefficients ([`nodes`],
//! [`T`], …) and the tunables ([`Radau5Options`], with their RADAU5 names and defaults).
//!
//! # Method
//!
//! Collocation at c = ((4-√6)/10, (4+√6)/10, 1). With Z_i = Y_i - y0, the stage equations
//! Z = h (A ⊗ I) F(Z) are solved by a simplified Newton iteration whose matrix
//! I - h A ⊗ J is block-diagonalised with the eigen-decomposition T⁻¹ A⁻¹ T = diag(γ, α ± iβ):
//! one real LU of (γ/h) I - J and one complex LU of ((α + iβ)/h) I - J per factorisation
//! (W = T⁻¹ Z are the transformed increments; Hairer & Wanner II, eq. IV.8.16ff).
//!
//! * Jacobian and LU are reused while Newton converges fast (contraction θ ≤ 0.001,
//!   [`Radau5Options::thet`]) and the proposed step changes by less than the factor window
//!   [1, 1.2] ([`Radau5Options::quot1`], [`Radau5Options::quot2`]).
//! * Newton start values: extrapolation of the previous step's collocation polynomial.
//! * Error estimate (Hairer & Wanner II, eq. IV.8.19–8.20): err = ((γ/h) I - J)⁻¹
//!   (f(y0) + (e1 Z1 + e2 Z2 + e3 Z3)/h), the filter (I - h γ0 J)⁻¹ suppresses the stiff
//!   components; after a rejection or on the first step it is refined once with f(y0 + err).
//! * Step control: Gustafsson's predictive controller (eq. IV.8.25) with safety factor
//!   depending on the Newton iteration count.
//! * Tolerances: the relative one is transformed as in RADAU5, rtol' = 0.1 rtol^(2/3), because
//!   the local error estimate is O(h^4) while the method is of order 5. RADAU5 also sets
//!   atol' = rtol' atol/rtol, which assumes the user scales atol with rtol; with a fixed atol
//!   (the FMU's: a fraction of each state's nominal value) it loosens the absolute control by
//!   0.1 rtol^(-1/3) (10x at rtol 1e-6, 215x at 1e-10) as rtol tightens, and the delivered error
//!   grew as the tolerance fell (issue 10). Here atol' = min(1, rtol'/rtol) atol: the absolute
//!   tolerance is never looser than the user's (only for rtol > 1e-3 is it scaled down, as
//!   RADAU5 does).
//! * Dense output: the collocation polynomial (CONTR5).
//! * A system that is affine in x with a constant Jacobian (and autonomous) has every step of a
//!   given size as one affine map of its start (module `step_map`): once a factorisation has
//!   served n/2 steps ([`Radau5Options::map_after_divisor`]), its map is built from it (n + 1 responses of the Newton and ESTRAD solves)
//!   and further steps with it are one dense product, end point and error vector together, in
//!   place of the stage evaluations, the Newton iteration and the error estimate's solve. The
//!   result is the converged Newton iterate, so only rounding differs. An attempt whose error
//!   ESTRAD would refine (on the first step or after a rejection, when ≥ 1), or with output
//!   times inside the step (which need the collocation polynomial), goes the ordinary way.
//!
//! A Jacobian that varies is kept across calls too, as RADAU5 keeps it across steps, while Newton
//! converges fast: a call that ends on every communication point would otherwise evaluate J and
//! factorise twice at every step. Its entries and the step size of its factorisations are part
//! of the saved state (its state's `KeptJacobian`); a restored integrator rebuilds J and the
//! factorisations from them, uncounted, and continues bit-identically. A constant Jacobian
//! ([`OdeSystem::constant_jacobian`]) and its factorisations are kept in the cache instead,
//! rebuilt identically after a restore.
//!
//! # Routines
//!
//! Split by job as RADAU5 is:
//!
//! | file | job | RADAU5 |
//! |---|---|---|
//! | `coefficients` | nodes, eigenvalues of A⁻¹, T and T⁻¹, error weights | prologue of RADCOR |
//! | `options` | the tunables, [`Radau5Options`] | IWORK, WORK |
//! | `tolerances` | transformed tolerances, error weights SCAL | prologue of RADAU5 |
//! | `radcor` | the step loop | RADCOR |
//! | `decomposition` | J, and the real and complex factorisations | label 20, DECOMR, DECOMC |
//! | `newton` | start values, simplified Newton iteration, its solves | RADCOR's loop, SLVRAD |
//! | `estrad` | local error estimate | ESTRAD |
//! | `step_control` | step-size proposal, acceptance of a step | RADCOR, "computation of hnew" |
//! | `dense_output` | collocation polynomial and its values | CONT, CONTR5 |
//! | `mapped_step` | steps as affine maps of a constant J | (none) |
//! | `kept_jacobian` | J kept across calls | (none: RADAU5 keeps J across the steps of its one call) |
//! | `workspace` | buffers kept between calls | WORK arrays |

// Index loops over stages and components mirror the formulas they implement.
#![allow(clippy::needless_range_loop)]

mod coefficients;
mod decomposition;
mod dense_output;
mod estrad;
mod kept_jacobian;
mod mapped_step;
mod newton;
mod options;
mod radcor;
mod state;
mod step_control;
mod tolerances;
mod workspace;

pub use coefficients::{error_weights, inverse_eigenvalues, nodes, T, TI};
pub use options::Radau5Options;
pub use state::{Radau5, State, STATE_VERSION};

use super::common::with_kept_memory;
use super::method::Stepper;
use super::{OdeSystem, SolverError, SolverErrorKind};
use kept_jacobian::{keep_jacobian, resume_kept_jacobian};
use radcor::radcor;

/// Why a step attempt was rejected (to report the right error kind if h gets too small).
#[derive(Clone, Copy, PartialEq)]
enum Why {
    Error,
    Newton,
    NonFinite,
    Singular,
}

impl Why {
    /// The error kind, and the reason for the message, when h falls below the minimum after a
    /// rejection for this reason.
    fn too_small(self) -> (SolverErrorKind, &'static str) {
        match self {
            Why::NonFinite => (SolverErrorKind::NonFinite, "after non-finite values of f"),
            Why::Singular => (
                SolverErrorKind::SingularMatrix,
                "with a singular iteration matrix",
            ),
            Why::Newton => (
                SolverErrorKind::StepTooSmall,
                "because Newton did not converge",
            ),
            Why::Error => (SolverErrorKind::StepTooSmall, "to meet the tolerances"),
        }
    }

    /// The error kind when too many attempts in a row were rejected, the last for this reason.
    fn after_rejections(self) -> SolverErrorKind {
        match self {
            Why::NonFinite => SolverErrorKind::NonFinite,
            Why::Singular => SolverErrorKind::SingularMatrix,
            _ => SolverErrorKind::TooManyRejections,
        }
    }
}

/// Advance `integ` to exactly `t_end` with Radau IIA (called through [`OdeMethod::advance`](crate::solver::OdeMethod::advance)), with
/// the tunables' defaults ([`Radau5Options::default`]).
pub(crate) fn advance<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    t_end: f64,
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
) -> Result<(), SolverError> {
    let opts = Radau5Options::default();
    let stamp = sys.constant_jacobian();
    with_kept_memory(
        integ,
        stamp,
        |s: &mut State| &mut s.cache,
        |integ, w, lus| {
            let mut need_jac = !resume_kept_jacobian(integ, sys, w, lus, stamp);
            let jac_evals = integ.stats.jac_evals;
            let result = radcor(
                integ,
                sys,
                &opts,
                t_end,
                times,
                out,
                w,
                lus,
                stamp,
                &mut need_jac,
            );
            let keep = stamp.is_none() && !need_jac && result.is_ok();
            let evaluated = integ.stats.jac_evals != jac_evals;
            keep_jacobian(integ, sys, w, lus, keep, evaluated);
            result
        },
    )
}

fn nonfinite_here(t: f64) -> SolverError {
    SolverError::new(
        SolverErrorKind::NonFinite,
        t,
        "the right-hand side f(t, x) is not finite at the current point",
    )
}
