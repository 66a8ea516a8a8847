//! Radau IIA of order 5 (3 stages), implemented in the manner of Hairer's RADAU5
//! (E. Hairer & G. Wanner, Solving ODEs II, Sec. IV.8; Fortran code `radau5.f`, version of
//! 1996/2002). All constants below are those of `radau5.f`; the comments say what each is.
//!
//! # Method
//!
//! Collocation at c = ((4-√6)/10, (4+√6)/10, 1). With Z_i = Y_i - y0, the stage equations
//! Z = h (A ⊗ I) F(Z) are solved by a simplified Newton iteration whose matrix
//! I - h A ⊗ J is block-diagonalised with the eigen-decomposition T⁻¹ A⁻¹ T = diag(γ, α ± iβ):
//! one real LU of (γ/h) I - J and one complex LU of ((α + iβ)/h) I - J per factorisation
//! (W = T⁻¹ Z are the transformed increments; Hairer & Wanner II, eq. IV.8.16ff).
//!
//! * Jacobian and LU are reused while Newton converges fast (contraction θ ≤ 0.001) and the
//!   proposed step changes by less than the factor window [1, 1.2].
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
//!   served n/2 steps, its map is built from it (n + 1 responses of the Newton and ESTRAD solves)
//!   and further steps with it are one dense product, end point and error vector together, in
//!   place of the stage evaluations, the Newton iteration and the error estimate's solve. The
//!   result is the converged Newton iterate, so only rounding differs. An attempt whose error
//!   ESTRAD would refine (on the first step or after a rejection, when ≥ 1), or with output
//!   times inside the step (which need the collocation polynomial), goes the ordinary way.
//!
//! A Jacobian that varies is kept across calls too, as RADAU5 keeps it across steps, while Newton
//! converges fast: a call that ends on every communication point would otherwise evaluate J and
//! factorise twice at every step. Its entries and the step size of its factorisations are part
//! of the saved state (the integrator's `KeptJacobian`); a restored integrator rebuilds J and the
//! factorisations from them, uncounted, and continues bit-identically. A constant Jacobian
//! ([`OdeSystem::constant_jacobian`]) and its factorisations are kept in the cache instead,
//! rebuilt identically after a restore.

// Index loops over stages and components mirror the formulas they implement.
#![allow(clippy::needless_range_loop)]

use std::sync::Arc;

use nalgebra::{Complex, DMatrix, DVector};

use super::common::{
    all_finite, eval, initial_step, jacobian_here, plan_step, rounding_floor, with_kept_memory,
    NextStep, Outputs, Workspace,
};
use super::integrator::Integrator;
use super::integrator::{front_factorisation, SAME_STEP};
use super::linalg::{factor_with_fallback, Factorisation, Partition, PatternCache};
use super::step_map::{self, StepMap};
use super::{Atol, OdeSystem, SolverError, SolverErrorKind};

/// √6.
fn sq6() -> f64 {
    6f64.sqrt()
}

/// Collocation nodes c1 = (4-√6)/10 and c2 = (4+√6)/10 (c3 = 1).
pub fn nodes() -> (f64, f64) {
    ((4.0 - sq6()) / 10.0, (4.0 + sq6()) / 10.0)
}

/// Eigenvalues of A⁻¹ (A the Radau IIA matrix): a real one γ and a complex pair α ± iβ.
/// RADAU5: U1 = 1/((6 + 81^(1/3) - 9^(1/3))/30), ALPH, BETA = (…)/(ALPH² + BETA²).
pub fn inverse_eigenvalues() -> (f64, f64, f64) {
    let c81 = 81f64.cbrt();
    let c9 = 9f64.cbrt();
    let u1 = (6.0 + c81 - c9) / 30.0; // real eigenvalue of A
    let alph = (12.0 - c81 + c9) / 60.0; // real part of the complex pair of A
    let beta = (c81 + c9) * 3f64.sqrt() / 60.0; // imaginary part
    let cno = alph * alph + beta * beta;
    (1.0 / u1, alph / cno, beta / cno)
}

/// Error-estimate weights (DD1, DD2, DD3) of RADAU5: the embedded combination
/// e = γ0 h f(y0) + Σ e_i Z_i (eq. IV.8.19) written with e_i = DD_i / γ (DD_i below).
pub fn error_weights() -> (f64, f64, f64) {
    (
        -(13.0 + 7.0 * sq6()) / 3.0,
        (-13.0 + 7.0 * sq6()) / 3.0,
        -1.0 / 3.0,
    )
}

/// T with `T⁻¹ A⁻¹ T = [[γ,0,0],[0,α,-β],[0,β,α]]` (RADAU5's T11…T33; T32 = 1, T33 = 0).
#[allow(clippy::excessive_precision)] // digits as published in radau5.f
pub const T: [[f64; 3]; 3] = [
    [
        9.1232394870892942792e-02,
        -0.14125529502095420843,
        -3.0029194105147424492e-02,
    ],
    [
        0.24171793270710701896,
        0.20412935229379993199,
        0.38294211275726193779,
    ],
    [0.96604818261509293619, 1.0, 0.0],
];
/// T⁻¹ (RADAU5's TI11…TI33).
#[allow(clippy::excessive_precision)] // digits as published in radau5.f
pub const TI: [[f64; 3]; 3] = [
    [
        4.3255798900631553510,
        0.33919925181580986954,
        0.54177053993587487119,
    ],
    [
        -4.1787185915519047273,
        -0.32768282076106238708,
        0.47662355450055045196,
    ],
    [
        -0.50287263494578687595,
        2.5719269498556054292,
        -0.59603920482822492497,
    ],
];

/// Maximum number of Newton iterations (RADAU5 NIT default).
const NIT: usize = 7;
/// Jacobian is kept if the Newton contraction rate θ stays below this (RADAU5 WORK(3)).
const THET: f64 = 0.001;
/// Keep h (and the LU) if h_new/h lies in [QUOT1, QUOT2] (RADAU5 WORK(5), WORK(6)).
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;
/// Safety factor (WORK(2)) and step ratio limits 1/FACL ≤ h_new/h ≤ 1/FACR (WORK(8), WORK(9)).
const SAFE: f64 = 0.9;
const FACL: f64 = 5.0;
const FACR: f64 = 0.125;

/// Why a step attempt was rejected (to report the right error kind if h gets too small).
#[derive(Clone, Copy, PartialEq)]
enum Why {
    Error,
    Newton,
    NonFinite,
    Singular,
}

/// The real LU of (γ/h) I - J and the complex LU of ((α + iβ)/h) I - J for the step size `h`.
pub(crate) struct Lu {
    real: Factorisation<f64>,
    complex: Factorisation<Complex<f64>>,
    h: f64,
    /// A step of size `h` as one affine map, for a system affine in x (see [`StepMap`]); made
    /// from these factorisations, cleared when they are remade.
    map: StepMap,
}

/// Factorises both iteration matrices for step size `h` into `lu` (reusing its memory) with the
/// partition `part` of J; false if either is singular.
fn factor_into(lu: &mut Lu, part: &Arc<Partition>, jac: &DMatrix<f64>, h: f64) -> bool {
    let (u1, alph, beta) = inverse_eigenvalues();
    let fac1 = u1 / h;
    let (alphn, betan) = (alph / h, beta / h);
    lu.h = h;
    lu.map.clear();
    factor_with_fallback(&mut lu.real, part, |i, j| {
        if i == j {
            fac1 - jac[(i, j)]
        } else {
            -jac[(i, j)]
        }
    }) && factor_with_fallback(&mut lu.complex, part, |i, j| {
        if i == j {
            Complex::new(alphn - jac[(i, j)], betan)
        } else {
            Complex::new(-jac[(i, j)], 0.0)
        }
    })
}

/// Factorisations of both iteration matrices for step size `h` (in the memory of `old` if
/// given); None if either is singular.
fn factor(jac: &DMatrix<f64>, part: &Arc<Partition>, h: f64, old: Option<Lu>) -> Option<Lu> {
    let mut lu = old.unwrap_or_else(|| Lu {
        real: Factorisation::new(Arc::clone(part)),
        complex: Factorisation::new(Arc::clone(part)),
        h,
        map: StepMap::default(),
    });
    factor_into(&mut lu, part, jac, h).then_some(lu)
}

/// Buffers of `advance`, kept between calls in the integrator's cache (no allocation per call);
/// overwritten before they are read.
pub(crate) struct Work {
    jac: DMatrix<f64>,
    /// The stamp of the constant part of the J that `jac` holds (see
    /// [`OdeSystem::jacobian_constant_part`]), None while it holds none.
    jac_holds: Option<u64>,
    f0: Vec<f64>,
    /// 1/SCAL (see [`set_scal`]).
    inv_scal: Vec<f64>,
    /// Stage increments Z_i = Y_i - y0.
    z: [Vec<f64>; 3],
    /// Transformed increments W = T⁻¹ Z.
    w: [Vec<f64>; 3],
    /// f at the stages.
    a: [Vec<f64>; 3],
    ytmp: Vec<f64>,
    f2: Vec<f64>,
    x1: Vec<f64>,
    /// f(t, 0), the constant part of an affine f, for the step map (evaluated once per call).
    c0: Vec<f64>,
    /// The step map's result: Z3 (rows 0..n) and the error estimate's vector (n..2n).
    mapped: Vec<f64>,
    /// [`transformed_tolerances`], with `atol` and `atol_for_fd`, once made (the options do
    /// not change under a workspace: `set_options` drops it).
    tolerances: Option<Tolerances>,
    atol: Vec<f64>,
    /// `atol` again, in the form the finite-difference Jacobian takes.
    atol_for_fd: Atol,
    rr: DVector<f64>,
    rc: DVector<Complex<f64>>,
    /// Scratch of the structured solves.
    scratch_r: Vec<f64>,
    scratch_c: Vec<Complex<f64>>,
    /// Partition of J into blocks and border (see [`super::linalg`]).
    pattern: PatternCache,
    /// The memory of the last factorisations of a Jacobian that changes from step to step:
    /// refactorised into, so a step allocates nothing. Their contents are stale unless
    /// `kept_synced` says otherwise.
    spare: Option<Lu>,
    /// `jac` holds the integrator's [`KeptJacobian`](super::integrator::KeptJacobian), and if
    /// that has factorisations, `spare` holds them (set when a call ends keeping J; a new
    /// workspace, as after a restore, starts without).
    kept_synced: bool,
}

impl Workspace for Work {
    type Lu = Lu;
    fn new(n: usize) -> Self {
        let v = || vec![0.0; n];
        Work {
            jac: DMatrix::zeros(n, n),
            jac_holds: None,
            f0: v(),
            inv_scal: v(),
            z: [v(), v(), v()],
            w: [v(), v(), v()],
            a: [v(), v(), v()],
            ytmp: v(),
            f2: v(),
            x1: v(),
            c0: v(),
            mapped: vec![0.0; 2 * n],
            tolerances: None,
            atol: v(),
            atol_for_fd: Atol::Vector(v()),
            rr: DVector::zeros(n),
            rc: DVector::zeros(n),
            scratch_r: v(),
            scratch_c: vec![Complex::new(0.0, 0.0); n],
            pattern: PatternCache::default(),
            spare: None,
            kept_synced: false,
        }
    }
    fn dim(&self) -> usize {
        self.f0.len()
    }
    fn spare(&mut self) -> &mut Option<Lu> {
        &mut self.spare
    }
}

/// Advance `integ` to exactly `t_end` with Radau IIA (called by `Integrator::advance_to*`).
pub(crate) fn advance<S: OdeSystem + ?Sized>(
    integ: &mut Integrator,
    sys: &S,
    t_end: f64,
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
) -> Result<(), SolverError> {
    let stamp = sys.constant_jacobian();
    with_kept_memory(
        integ,
        stamp,
        |c| (&mut c.radau, &mut c.radau_lu),
        |integ, w, lus| {
            let mut need_jac = !resume_kept_jacobian(integ, sys, w, lus, stamp);
            let jac_evals = integ.stats.jac_evals;
            let result = radcor(integ, sys, t_end, times, out, w, lus, stamp, &mut need_jac);
            let keep = stamp.is_none() && !need_jac && result.is_ok();
            let evaluated = integ.stats.jac_evals != jac_evals;
            keep_jacobian(integ, sys, w, lus, keep, evaluated);
            result
        },
    )
}

/// Takes up the Jacobian the last call kept (see
/// [`KeptJacobian`](super::integrator::KeptJacobian)): from the workspace if it
/// still holds it with its factorisations, else rebuilt from the saved entries, and its
/// factorisations made again for their saved step size, uncounted (they were counted when first
/// made, so a restored copy counts as the original does). False if there is none to take up (a
/// constant Jacobian, nothing kept, or entries that do not fit the system).
fn resume_kept_jacobian<S: OdeSystem + ?Sized>(
    integ: &mut Integrator,
    sys: &S,
    work: &mut Work,
    lus: &mut Vec<Lu>,
    stamp: Option<u64>,
) -> bool {
    let kept = &integ.kept_jac;
    if stamp.is_some() || kept.is_empty() {
        return false;
    }
    if work.kept_synced {
        if kept.lu_h == 0.0 {
            return true;
        }
        match work.spare.take() {
            Some(lu) if lu.h == kept.lu_h => {
                lus.push(lu);
                return true;
            }
            // Not the factorisation expected: rebuild as after a restore.
            other => work.spare = other,
        }
    }
    let pattern = sys.jacobian_pattern();
    // The rebuilt J is one the system wrote, but restored from a saved state: claim nothing.
    work.jac_holds = None;
    if !kept.rebuild(pattern, &mut work.jac) {
        integ.kept_jac.clear();
        return false;
    }
    if kept.lu_h > 0.0 {
        let part = work.pattern.partition_within(&work.jac, pattern);
        let Some(lu) = factor(&work.jac, part, kept.lu_h, work.spare.take()) else {
            integ.kept_jac.clear();
            return false;
        };
        lus.push(lu);
    }
    work.kept_synced = true;
    true
}

/// After a call: keeps J (and notes the step size of its factorisation) for the next call if
/// the step control would go on with it (`keep`), storing its entries in the saved state when
/// it was `evaluated` in this call; otherwise keeps nothing.
fn keep_jacobian<S: OdeSystem + ?Sized>(
    integ: &mut Integrator,
    sys: &S,
    work: &mut Work,
    lus: &[Lu],
    keep: bool,
    evaluated: bool,
) {
    if !keep {
        integ.kept_jac.clear();
        work.kept_synced = false;
        return;
    }
    if evaluated || integ.kept_jac.is_empty() {
        integ.kept_jac.store(&work.jac, sys.jacobian_pattern());
    }
    // The factorisation in use is the front one; `with_kept_memory` moves it into `spare`.
    integ.kept_jac.lu_h = lus.first().map_or(0.0, |lu| lu.h);
    work.kept_synced = true;
}

/// The tolerances the step control works with (RADAU5's prologue and RADCOR's FNEWT).
#[derive(Clone, Copy)]
struct Tolerances {
    /// Transformed relative tolerance rtol' = 0.1 rtol^(2/3).
    rtol: f64,
    /// Newton stopping criterion κ·Tol (RADAU5 FNEWT default; Hairer & Wanner IV.8, "stopping
    /// criterion" of the simplified Newton iteration).
    fnewt: f64,
}

/// RADAU5's tolerance transformation: rtol' = 0.1 rtol^(2/3) for the relative part (the local
/// error estimate is O(h⁴), the method of order 5); the absolute part `work.atol` is the user's,
/// scaled down with rtol'/rtol but never up (see the module docs for why this departs from
/// RADAU5's atol' = rtol' atol/rtol).
fn transformed_tolerances(integ: &Integrator, work: &mut Work) -> Tolerances {
    if let Some(tol) = work.tolerances {
        return tol;
    }
    let rtol_user = integ.options.rtol;
    let rtol = 0.1 * rtol_user.powf(2.0 / 3.0);
    let atol_factor = (rtol / rtol_user).min(1.0);
    for (i, a) in work.atol.iter_mut().enumerate() {
        *a = atol_factor * integ.options.atol.get(i);
    }
    if let Atol::Vector(v) = &mut work.atol_for_fd {
        v.copy_from_slice(&work.atol);
    }
    let fnewt = (10.0 * f64::EPSILON / rtol).max(0.03f64.min(rtol.sqrt()));
    let tol = Tolerances { rtol, fnewt };
    work.tolerances = Some(tol);
    tol
}

/// Reciprocal error weights 1/sc_i, sc_i = atol'_i + rtol' |x_i|, of the weighted RMS norm
/// (RADCOR's SCAL; Hairer & Wanner IV.8, the norm under eq. 8.20), sc_i floored at the smallest
/// normal number. RADAU5 divides by SCAL in every norm (three divisions per state per Newton
/// iteration, one in the error estimate); with the reciprocals made once per step they are
/// multiplications (about 3 % of a step at 806 states). The norms differ from RADAU5's by
/// rounding only.
fn set_scal(atol: &[f64], rtol: f64, x: &[f64], inv_scal: &mut [f64]) {
    for i in 0..inv_scal.len() {
        inv_scal[i] = 1.0 / (atol[i] + rtol * x[i].abs()).max(f64::MIN_POSITIVE);
    }
}

/// Step loop of RADAU5 (subroutine RADCOR): plans each step, computes J where needed (RADCOR
/// label 20), factorises ([`decompose`]), sets the Newton start ([`start_values`]), iterates
/// ([`newton`]), estimates the error ([`estrad`]), then accepts ([`accept`]) or rejects, and
/// chooses the next step size ([`step_size`]).
#[allow(clippy::too_many_arguments)]
fn radcor<S: OdeSystem + ?Sized>(
    integ: &mut Integrator,
    sys: &S,
    t_end: f64,
    times: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
    work: &mut Work,
    lus: &mut Vec<Lu>,
    stamp: Option<u64>,
    need_jac: &mut bool,
) -> Result<(), SolverError> {
    let n = integ.x.len();
    let tol = transformed_tolerances(integ, work);
    set_scal(&work.atol, tol.rtol, &integ.x, &mut work.inv_scal);

    // A constant J of an autonomous system: f = J x + c, and a step can be a step map.
    let mappable = stamp.is_some() && n <= step_map::MAX_DIM && sys.is_autonomous();
    // `work.f0` holds f at the integrator's current point. RADAU5 evaluates it at the start and
    // after every accepted step; a system that may take mapped steps, which do not need it, has
    // it evaluated only when an ordinary step, the initial step size or the last tiny remainder
    // does (`f0_here`).
    let mut f0_fresh = false;
    let f0_here = |integ: &mut Integrator, work: &mut Work, fresh: &mut bool| {
        if !*fresh {
            eval(sys, &mut integ.stats, integ.t, &integ.x, &mut work.f0);
            if !all_finite(&work.f0) {
                return Err(nonfinite_here(integ.t));
            }
            *fresh = true;
        }
        Ok(())
    };
    if !mappable || integ.h <= 0.0 {
        f0_here(integ, work, &mut f0_fresh)?;
    }
    if integ.h <= 0.0 {
        let opts = integ.options.clone();
        integ.h = initial_step(
            sys,
            &opts,
            &mut integ.stats,
            integ.t,
            &integ.x,
            &work.f0,
            t_end,
            3.0,
        );
    }
    let mut outputs = Outputs::new(times, integ.t, n);
    // f(t, 0) = c for the step map, evaluated when first wanted in this call: None until then,
    // then whether it is finite.
    let mut offsets: Option<bool> = None;

    let mut jac_fresh = false; // J evaluated at the current point?
    let mut attempts: u64 = 0;
    let mut consecutive_rejections: u32 = 0;
    let mut why = Why::Error;

    loop {
        let why_small = || match why {
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
        };
        let quantise = stamp.is_some();
        if t_end - integ.t <= rounding_floor(integ.t) {
            // plan_step finishes with an Euler step from f0.
            f0_here(integ, work, &mut f0_fresh)?;
        }
        let (h, last, h_proposed) = match plan_step(
            integ,
            t_end,
            t_end,
            &work.f0,
            &mut attempts,
            quantise,
            why_small,
        )? {
            NextStep::Done => return Ok(()),
            NextStep::Step { h, last, proposed } => (h, last, proposed),
        };
        let t = integ.t;
        if *need_jac {
            // (f0 is fresh here unless the system is mappable, whose J is analytic and constant:
            // jacobian_at then needs no f0 for finite differences.)
            if !jacobian_at(integ, sys, work, lus, stamp, tol.rtol) {
                return Err(SolverError::new(
                    SolverErrorKind::NonFinite,
                    t,
                    "the Jacobian is not finite at the current point",
                ));
            }
            *need_jac = false;
            jac_fresh = true;
        }

        // Outcome of this attempt: the Newton result and the error, or a rejection reason with
        // the factor for h.
        let t1 = if last { t_end } else { t + h };
        // The step was taken by the step map (no collocation polynomial to keep).
        let mut mapped = false;
        let attempt: Result<(Newton, f64), (Why, f64)> = 'attempt: {
            if !decompose(integ, work, lus, (stamp, sys.jacobian_pattern()), h) {
                break 'attempt Err((Why::Singular, 0.5));
            }
            let Some(lu) = lus.first_mut() else {
                break 'attempt Err((Why::Singular, 0.5));
            };
            if mappable
                && !outputs.pending(t1)
                && integ.counted.front_steps >= map_after(n)
                && *offsets.get_or_insert_with(|| {
                    work.ytmp.fill(0.0);
                    eval(sys, &mut integ.stats, t, &work.ytmp, &mut work.c0);
                    all_finite(&work.c0)
                })
            {
                let err = mapped_step(integ, work, lu);
                // ESTRAD's refinement after a rejection or on the first step needs f at a
                // point off the map: such an attempt goes the ordinary way.
                if err.is_finite() && (err < 1.0 || !(integ.hist.first || integ.hist.last_rejected))
                {
                    mapped = true;
                    break 'attempt Ok((
                        Newton {
                            iterations: 1,
                            theta: THET,
                        },
                        err,
                    ));
                }
            }
            let lu = &*lu;
            f0_here(integ, work, &mut f0_fresh)?;
            start_values(integ, work, h);
            let newton = match newton(integ, sys, work, lu, &tol, h) {
                Ok(newton) => newton,
                Err(e) => break 'attempt Err(e),
            };
            match estrad(integ, sys, work, lu, h) {
                Ok(err) => Ok((newton, err)),
                Err(e) => Err(e),
            }
        };

        match attempt {
            Ok((newton, err)) => {
                let mut hnew = step_size(integ, err, h, newton.iterations);
                if err < 1.0 {
                    accept(integ, work, &mut outputs, out, &tol, (t, h, t1), mapped)?;
                    if stamp.is_some() {
                        integ.counted.front_steps = integ.counted.front_steps.saturating_add(1);
                    }
                    consecutive_rejections = 0;
                    why = Why::Error;
                    if integ.hist.last_rejected {
                        hnew = hnew.min(h);
                    }
                    integ.hist.last_rejected = false;
                    hnew = hnew.min(integ.options.max_step);
                    if last {
                        integ.h = hnew.max(h_proposed);
                        // The next call goes on with this J only while Newton converges fast.
                        *need_jac = newton.theta > THET;
                        return Ok(());
                    }
                    f0_fresh = false;
                    if !mappable {
                        if let Err(e) = f0_here(integ, work, &mut f0_fresh) {
                            integ.h = hnew;
                            return Err(e);
                        }
                    }
                    jac_fresh = false;
                    let qt = hnew / h;
                    if newton.theta <= THET && (QUOT1..=QUOT2).contains(&qt) {
                        // Keep h, J and LU.
                        integ.h = h;
                    } else {
                        integ.h = hnew;
                        // Reuse J (new LU) only while Newton converges very fast.
                        *need_jac = newton.theta > THET;
                    }
                    continue;
                }
                // Rejected by the error test.
                integ.h = if integ.hist.first { h * 0.1 } else { hnew };
                why = Why::Error;
            }
            Err((reason, fac)) => {
                integ.h = h * fac;
                why = reason;
            }
        }
        // Common rejection bookkeeping: RADAU5 recomputes J unless it is already current.
        integ.stats.rejected += 1;
        integ.hist.last_rejected = true;
        consecutive_rejections += 1;
        if !jac_fresh {
            *need_jac = true;
        }
        if consecutive_rejections > integ.options.max_consecutive_rejections {
            let kind = match why {
                Why::NonFinite => SolverErrorKind::NonFinite,
                Why::Singular => SolverErrorKind::SingularMatrix,
                _ => SolverErrorKind::TooManyRejections,
            };
            return Err(SolverError::new(
                kind,
                t,
                format!("{consecutive_rejections} consecutive step rejections (last h = {h:e})"),
            ));
        }
    }
}

/// The Jacobian J = ∂f/∂y at the current point (RADCOR label 20: analytic or by finite
/// differences). A constant J ([`OdeSystem::constant_jacobian`]) is the same everywhere and is
/// kept in the integrator's cache with its factorisations; otherwise J goes into `work.jac` and
/// the factorisations of the old J are dropped (their memory kept as the spare). False if J is
/// not finite.
fn jacobian_at<S: OdeSystem + ?Sized>(
    integ: &mut Integrator,
    sys: &S,
    work: &mut Work,
    lus: &mut Vec<Lu>,
    stamp: Option<u64>,
    rtol: f64,
) -> bool {
    if stamp.is_none() {
        if let Some(lu) = lus.pop() {
            work.spare = Some(lu);
        }
        lus.clear();
    }
    let fd = Some((&work.atol_for_fd, rtol));
    jacobian_here(
        integ,
        sys,
        stamp,
        &work.f0,
        fd,
        &mut work.jac,
        &mut work.jac_holds,
    )
}

/// Makes `lus[0]` the factorisations for step size `h` (RADAU5's DECOMR and DECOMC: the real LU
/// of (γ/h) I - J and the complex LU of ((α + iβ)/h) I - J, the blocks of the transformed
/// Newton matrix, Hairer & Wanner IV.8, eq. 8.16ff), reusing those in `lus` where they fit.
/// False if a matrix is singular.
///
/// The simplified Newton iteration converges with factorisations for a step size within
/// SAME_STEP of h as with exact ones (the difference is rounding in t_end - t); with a constant J
/// the factorisation in use is the one counted (also after a restore, which rebuilds it with the
/// same bits). A changing J is refactorised in the memory of its last factorisation, with the
/// partition of the system's structural pattern (`structure`) if it has one.
fn decompose(
    integ: &mut Integrator,
    work: &mut Work,
    lus: &mut Vec<Lu>,
    (stamp, structure): (Option<u64>, Option<&[Vec<u32>]>),
    h: f64,
) -> bool {
    let Work {
        jac,
        pattern,
        spare,
        ..
    } = work;
    match stamp {
        Some(_) => {
            let lu_h = integ
                .counted
                .factorisation_step(h, &mut integ.stats, 2, false);
            let jac = &integ.cache.jac;
            front_factorisation(
                lus,
                lu_h,
                |l| l.h,
                |old| {
                    let fresh = old.is_none();
                    let mut lu = factor(jac, pattern.partition(jac, stamp), lu_h, old)?;
                    let n = jac.nrows();
                    if fresh && n <= step_map::MAX_DIM {
                        // Its step map is built later, mid-run: take its memory with the rest.
                        lu.map.reserve(2 * n, n);
                    }
                    Some(lu)
                },
            )
        }
        None => {
            if lus.first().is_none_or(|l| (l.h - h).abs() > SAME_STEP * h) {
                integ.stats.lu_decompositions += 2;
                if lus.is_empty() {
                    lus.extend(spare.take());
                }
                lus.truncate(1);
                let part = pattern.partition_within(jac, structure);
                match lus.first_mut() {
                    Some(lu) => {
                        if !factor_into(lu, part, jac, h) {
                            *spare = lus.pop();
                        }
                    }
                    None => lus.extend(factor(jac, part, h, None)),
                }
            }
            !lus.is_empty()
        }
    }
}

/// Starting values of the simplified Newton iteration (RADCOR, "starting values for Newton
/// iteration"; Hairer & Wanner IV.8, "starting values"): Z_i⁰ = q(c_i h), the previous step's collocation
/// polynomial q extrapolated, and W⁰ = T⁻¹ Z⁰; zero on the first step or when there is no
/// polynomial.
fn start_values(integ: &Integrator, work: &mut Work, h: f64) {
    let n = integ.x.len();
    let Work {
        z: [z1, z2, z3],
        w: [w1, w2, w3],
        ..
    } = work;
    if integ.hist.first || integ.hist.cont.len() != 3 * n || integ.hist.h_old <= 0.0 {
        z1.fill(0.0);
        z2.fill(0.0);
        z3.fill(0.0);
        w1.fill(0.0);
        w2.fill(0.0);
        w3.fill(0.0);
        return;
    }
    let (c1, c2) = nodes();
    let (c1m1, c2m1) = (c1 - 1.0, c2 - 1.0);
    let c3q = h / integ.hist.h_old;
    let (c1q, c2q) = (c1 * c3q, c2 * c3q);
    let cont = &integ.hist.cont;
    for i in 0..n {
        let (k1, k2, k3) = (cont[i], cont[n + i], cont[2 * n + i]);
        let p = |q: f64| q * (k1 + (q - c2m1) * (k2 + (q - c1m1) * k3));
        z1[i] = p(c1q);
        z2[i] = p(c2q);
        z3[i] = p(c3q);
        w1[i] = TI[0][0] * z1[i] + TI[0][1] * z2[i] + TI[0][2] * z3[i];
        w2[i] = TI[1][0] * z1[i] + TI[1][1] * z2[i] + TI[1][2] * z3[i];
        w3[i] = TI[2][0] * z1[i] + TI[2][1] * z2[i] + TI[2][2] * z3[i];
    }
}

/// What a converged Newton iteration leaves for the step-size choice.
struct Newton {
    /// Iterations used.
    iterations: usize,
    /// Last contraction estimate θ (J is kept while θ ≤ THET).
    theta: f64,
}

/// The simplified Newton iteration for the stage increments (RADCOR, "loop for the simplified
/// Newton iteration"; Hairer & Wanner IV.8, "simplified Newton iterations", in the transformed
/// form of eq. 8.16ff), with the convergence monitor of the "stopping criterion": contraction θ_k = ‖ΔW^k‖/‖ΔW^{k-1}‖, stop when
/// η_k ‖ΔW^k‖ ≤ κ Tol, η_k = θ_k/(1 - θ_k); give up early (with a factor for h) when the
/// predicted error after NIT iterations is too large. Leaves Z and W in `work`.
fn newton<S: OdeSystem + ?Sized>(
    integ: &mut Integrator,
    sys: &S,
    work: &mut Work,
    lu: &Lu,
    tol: &Tolerances,
    h: f64,
) -> Result<Newton, (Why, f64)> {
    let n = integ.x.len();
    let t = integ.t;
    let (c1, c2) = nodes();
    let (u1, alph, beta) = inverse_eigenvalues();
    let fac1 = u1 / h;
    let (alphn, betan) = (alph / h, beta / h);
    integ.hist.faccon = integ.hist.faccon.max(f64::EPSILON).powf(0.8);
    let mut theta = THET;
    let mut newt = 0;
    let mut dynold = 0.0;
    let mut thqold = 0.0;
    loop {
        if newt >= NIT {
            return Err((Why::Newton, 0.5));
        }
        let Work {
            z: [z1, z2, z3],
            a: [a1, a2, a3],
            ytmp,
            ..
        } = &mut *work;
        for i in 0..n {
            ytmp[i] = integ.x[i] + z1[i];
        }
        eval(sys, &mut integ.stats, t + c1 * h, ytmp, a1);
        for i in 0..n {
            ytmp[i] = integ.x[i] + z2[i];
        }
        eval(sys, &mut integ.stats, t + c2 * h, ytmp, a2);
        for i in 0..n {
            ytmp[i] = integ.x[i] + z3[i];
        }
        eval(sys, &mut integ.stats, t + h, ytmp, a3);
        if !(all_finite(a1) && all_finite(a2) && all_finite(a3)) {
            return Err((Why::NonFinite, 0.5));
        }
        slvrad(work, lu, fac1, alphn, betan);
        let Work {
            z: [z1, z2, z3],
            w: [w1, w2, w3],
            inv_scal,
            rr,
            rc,
            ..
        } = &mut *work;
        newt += 1;
        let mut dyno = 0.0;
        for i in 0..n {
            let w = inv_scal[i];
            dyno += (rr[i] * w).powi(2) + (rc[i].re * w).powi(2) + (rc[i].im * w).powi(2);
        }
        let dyno = (dyno / (3 * n) as f64).sqrt();
        if !dyno.is_finite() {
            return Err((Why::NonFinite, 0.5));
        }
        // Convergence monitor: contraction θ and predicted remaining error.
        if newt > 1 && newt < NIT {
            let thq = dyno / dynold;
            theta = if newt == 2 {
                thq
            } else {
                (thq * thqold).sqrt()
            };
            thqold = thq;
            if theta < 0.99 {
                integ.hist.faccon = theta / (1.0 - theta);
                let dyth =
                    integ.hist.faccon * dyno * theta.powi((NIT - 1 - newt) as i32) / tol.fnewt;
                if dyth >= 1.0 {
                    // Would not converge within NIT iterations: smaller step.
                    let qnewt = dyth.clamp(1e-4, 20.0);
                    let hhfac = 0.8 * qnewt.powf(-1.0 / (4.0 + (NIT - 1 - newt) as f64));
                    return Err((Why::Newton, hhfac));
                }
            } else {
                return Err((Why::Newton, 0.5));
            }
        }
        dynold = dyno.max(f64::EPSILON);
        for i in 0..n {
            w1[i] += rr[i];
            w2[i] += rc[i].re;
            w3[i] += rc[i].im;
            z1[i] = T[0][0] * w1[i] + T[0][1] * w2[i] + T[0][2] * w3[i];
            z2[i] = T[1][0] * w1[i] + T[1][1] * w2[i] + T[1][2] * w3[i];
            z3[i] = T[2][0] * w1[i] + w2[i];
        }
        if integ.hist.faccon * dyno <= tol.fnewt {
            return Ok(Newton {
                iterations: newt,
                theta,
            });
        }
    }
}

/// The linear solves of one simplified Newton iteration (RADAU5's SLVRAD; Hairer & Wanner IV.8,
/// eq. 8.16ff): the residual of the stage equations transformed with T⁻¹, from f at the stages in
/// `work.a` and W in `work.w`, then the increments ΔW₁ of the real block (γ/h) I - J into
/// `work.rr` and ΔW₂ + iΔW₃ of the complex block ((α + iβ)/h) I - J into `work.rc`.
fn slvrad(work: &mut Work, lu: &Lu, fac1: f64, alphn: f64, betan: f64) {
    let Work {
        w: [w1, w2, w3],
        a: [a1, a2, a3],
        rr,
        rc,
        scratch_r,
        scratch_c,
        ..
    } = work;
    for i in 0..rr.len() {
        let r1 = TI[0][0] * a1[i] + TI[0][1] * a2[i] + TI[0][2] * a3[i];
        let r2 = TI[1][0] * a1[i] + TI[1][1] * a2[i] + TI[1][2] * a3[i];
        let r3 = TI[2][0] * a1[i] + TI[2][1] * a2[i] + TI[2][2] * a3[i];
        rr[i] = r1 - fac1 * w1[i];
        rc[i] = Complex::new(
            r2 - alphn * w2[i] + betan * w3[i],
            r3 - betan * w2[i] - alphn * w3[i],
        );
    }
    lu.real.solve(rr.as_mut_slice(), scratch_r);
    lu.complex.solve(rc.as_mut_slice(), scratch_c);
}

/// The local error estimate (RADAU5's ESTRAD; Hairer & Wanner IV.8, eqs. 8.19–8.20):
/// err = ((γ/h) I - J)⁻¹ (f(y0) + (e1 Z1 + e2 Z2 + e3 Z3)/h) in the weighted RMS norm, the
/// filter suppressing the stiff components. On the first step or after a rejection an estimate
/// ≥ 1 is refined once with f(y0 + err) in place of f(y0), as ESTRAD does.
fn estrad<S: OdeSystem + ?Sized>(
    integ: &mut Integrator,
    sys: &S,
    work: &mut Work,
    lu: &Lu,
    h: f64,
) -> Result<f64, (Why, f64)> {
    let n = integ.x.len();
    let (dd1, dd2, dd3) = error_weights();
    let Work {
        z: [z1, z2, z3],
        a: [a1, ..],
        f0,
        f2,
        ytmp,
        inv_scal,
        rr,
        scratch_r,
        ..
    } = work;
    let (hee1, hee2, hee3) = (dd1 / h, dd2 / h, dd3 / h);
    for i in 0..n {
        f2[i] = hee1 * z1[i] + hee2 * z2[i] + hee3 * z3[i];
        rr[i] = f2[i] + f0[i];
    }
    lu.real.solve(rr.as_mut_slice(), scratch_r);
    let norm = |v: &DVector<f64>| {
        let s: f64 = (0..n).map(|i| (v[i] * inv_scal[i]).powi(2)).sum();
        (s / n as f64).sqrt().max(1e-10)
    };
    let mut err = norm(rr);
    if err >= 1.0 && (integ.hist.first || integ.hist.last_rejected) {
        // Refined estimate with one more f evaluation (stiff components).
        for i in 0..n {
            ytmp[i] = integ.x[i] + rr[i];
        }
        eval(sys, &mut integ.stats, integ.t, ytmp, a1);
        if !all_finite(a1) {
            return Err((Why::NonFinite, 0.5));
        }
        for i in 0..n {
            rr[i] = a1[i] + f2[i];
        }
        lu.real.solve(rr.as_mut_slice(), scratch_r);
        err = norm(rr);
    }
    if err.is_finite() {
        Ok(err)
    } else {
        Err((Why::NonFinite, 0.5))
    }
}

/// The step size proposed after a step of size `h` with error `err` and `newt` Newton
/// iterations (RADCOR, "computation of hnew"; Hairer & Wanner IV.8, "step size selection", with
/// a safety factor that falls with the Newton iterations used): h_new = h / quot, quot within
/// [FACR, FACL]; for an accepted step Gustafsson's predictive controller (eq. 8.25) may shorten
/// it, and its memory (the last accepted h and error) is updated.
fn step_size(integ: &mut Integrator, err: f64, h: f64, newt: usize) -> f64 {
    let cfac = SAFE * (1 + 2 * NIT) as f64;
    let fac = SAFE.min(cfac / (newt + 2 * NIT) as f64);
    let mut quot = FACR.max(FACL.min(err.powf(0.25) / fac));
    let mut hnew = h / quot;
    if err < 1.0 {
        if !integ.hist.first && integ.hist.h_acc > 0.0 {
            let facgus =
                (integ.hist.h_acc / h) * (err * err / integ.hist.err_acc).powf(0.25) / SAFE;
            let facgus = facgus.clamp(FACR, FACL);
            quot = quot.max(facgus);
            hnew = h / quot;
        }
        integ.hist.h_acc = h;
        integ.hist.err_acc = err.max(1e-2);
    }
    hnew
}

/// Steps taken with one factorisation before its step map is built: building costs n + 1
/// [`map_response`]s of three solves each, about as much as n/2 ordinary steps (each a few f
/// evaluations and three solves), so a factorisation that has already served that many is
/// likely to serve as many more (the cost of building never exceeds that of the steps taken
/// without the map by much, whatever the run of steps at one size).
fn map_after(n: usize) -> u32 {
    u32::try_from(n.div_ceil(2)).unwrap_or(u32::MAX)
}

/// A step of size `lu.h` from the integrator's state by the factorisation's step map (built or
/// refitted to the offsets `work.c0` first if need be): the end point into `work.x1`, and the
/// error estimate's norm returned (ESTRAD's, before any refinement). Stands for the simplified
/// Newton iteration converged in one iteration (it has the exact J of an affine f), so the
/// convergence-rate memory ages as in [`newton`].
fn mapped_step(integ: &mut Integrator, work: &mut Work, lu: &mut Lu) -> f64 {
    let n = integ.x.len();
    let Work {
        c0,
        rr,
        rc,
        scratch_r,
        scratch_c,
        ..
    } = work;
    let solves = (&lu.real, &lu.complex, lu.h);
    let response = |v: &[f64], out: &mut [f64]| {
        map_response(
            solves,
            v,
            out,
            (rr.as_mut_slice(), rc.as_mut_slice()),
            (scratch_r, scratch_c),
        )
    };
    if !lu.map.is_built() {
        lu.map.build(2 * n, &integ.cache.jac, c0, response);
    } else if !lu.map.fits(c0) {
        lu.map.refit(c0, response);
    }
    integ.hist.faccon = integ.hist.faccon.max(f64::EPSILON).powf(0.8);
    lu.map.apply(&integ.x, &mut work.mapped);
    let (z3, e) = work.mapped.split_at(n);
    let mut sum = 0.0;
    for i in 0..n {
        work.x1[i] = integ.x[i] + z3[i];
        sum += (e[i] * work.inv_scal[i]).powi(2);
    }
    (sum / n as f64).sqrt().max(1e-10)
}

/// What a step of size `h` computes when f ≡ v at the three stages and at its start, without
/// the start state: Z3 into `out[..n]` and the vector of the error estimate (ESTRAD's, before
/// its norm) into `out[n..]`. That is one simplified Newton iteration from Z = 0 ([`slvrad`]
/// with W = 0, then Z = T W), followed by ESTRAD's solve with f(y0) = v; for f = J x + c and
/// the factorisations of this J, the iteration's first result is its converged one.
fn map_response(
    (real, complex, h): (&Factorisation<f64>, &Factorisation<Complex<f64>>, f64),
    v: &[f64],
    out: &mut [f64],
    (rr, rc): (&mut [f64], &mut [Complex<f64>]),
    (scratch_r, scratch_c): (&mut [f64], &mut [Complex<f64>]),
) {
    let n = v.len();
    let (dd1, dd2, dd3) = error_weights();
    let (hee1, hee2, hee3) = (dd1 / h, dd2 / h, dd3 / h);
    for i in 0..n {
        let (a1, a2, a3) = (v[i], v[i], v[i]);
        rr[i] = TI[0][0] * a1 + TI[0][1] * a2 + TI[0][2] * a3;
        rc[i] = Complex::new(
            TI[1][0] * a1 + TI[1][1] * a2 + TI[1][2] * a3,
            TI[2][0] * a1 + TI[2][1] * a2 + TI[2][2] * a3,
        );
    }
    real.solve(rr, scratch_r);
    complex.solve(rc, scratch_c);
    let (z3, e) = out.split_at_mut(n);
    for i in 0..n {
        let (w1, w2, w3) = (rr[i], rc[i].re, rc[i].im);
        let z1 = T[0][0] * w1 + T[0][1] * w2 + T[0][2] * w3;
        let z2 = T[1][0] * w1 + T[1][1] * w2 + T[1][2] * w3;
        z3[i] = T[2][0] * w1 + w2;
        e[i] = hee1 * z1 + hee2 * z2 + hee3 * z3[i] + v[i];
    }
    real.solve(e, scratch_r);
}

/// Accepts the step from `t` to `t1` (RADCOR, "step is accepted"): y1 = y0 + Z3, the collocation
/// polynomial of the step for dense output and the next Newton start (RADAU5's CONT, evaluated
/// by CONTR5), the outputs due within the step, and the new error weights. A `mapped` step
/// ([`mapped_step`]) has its end point in `work.x1` already and leaves no polynomial (the next
/// ordinary step starts Newton from zero, which on the affine system it was made for costs
/// nothing: one iteration converges from anywhere).
fn accept(
    integ: &mut Integrator,
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
        integ.hist.cont.clear();
    } else {
        collocation_polynomial(integ, (z1, z2, z3), x1, outputs, out, (t, h, t1));
    }
    integ.hist.h_old = h;
    integ.hist.first = false;
    integ.x.copy_from_slice(x1);
    integ.t = t1;
    integ.stats.accepted += 1;
    set_scal(atol, tol.rtol, &integ.x, inv_scal);
    Ok(())
}

/// The collocation polynomial of an accepted step (CONT(N+1..4N) of RADAU5) from its stage
/// increments, into the integrator's history, and the outputs due within the step from it.
fn collocation_polynomial(
    integ: &mut Integrator,
    (z1, z2, z3): (&[f64], &[f64], &[f64]),
    x1: &[f64],
    outputs: &mut Outputs,
    out: &mut dyn FnMut(f64, &[f64]),
    (t, h, t1): (f64, f64, f64),
) {
    let n = x1.len();
    let (c1, c2) = nodes();
    // CONTR5's divided differences, with the divisions by the constant node differences as
    // multiplications by their reciprocals (five divisions per state per step otherwise).
    let (c1m1, c2m1, c1mc2) = (c1 - 1.0, c2 - 1.0, c1 - c2);
    let (r_c1m1, r_c2m1, r_c1mc2, r_c1, r_c2) =
        (1.0 / c1m1, 1.0 / c2m1, 1.0 / c1mc2, 1.0 / c1, 1.0 / c2);
    let mut cont = std::mem::take(&mut integ.hist.cont);
    cont.resize(3 * n, 0.0);
    for i in 0..n {
        let k1 = (z2[i] - z3[i]) * r_c2m1;
        let ak = (z1[i] - z2[i]) * r_c1mc2;
        let acont3 = (ak - z1[i] * r_c1) * r_c2;
        let k2 = (ak - k1) * r_c1m1;
        cont[i] = k1;
        cont[n + i] = k2;
        cont[2 * n + i] = k2 - acont3;
    }
    if outputs.pending(t1) {
        outputs.emit(t, h, t1, x1, &mut |th, buf| dense(x1, &cont, th, buf), out);
    }
    integ.hist.cont = cont;
}

/// The collocation polynomial of a step at θ ∈ [0, 1] of it (RADAU5's CONTR5, with
/// s = θ - 1 measured back from the step's end), into `buf`, from the end state `x1` and the
/// polynomial's coefficients `cont` (3 n numbers).
fn dense(x1: &[f64], cont: &[f64], theta: f64, buf: &mut [f64]) {
    let n = x1.len();
    let (c1, c2) = nodes();
    let (c1m1, c2m1) = (c1 - 1.0, c2 - 1.0);
    let s = theta - 1.0;
    for i in 0..n {
        buf[i] = x1[i] + s * (cont[i] + (s - c2m1) * (cont[n + i] + (s - c1m1) * cont[2 * n + i]));
    }
}

fn nonfinite_here(t: f64) -> SolverError {
    SolverError::new(
        SolverErrorKind::NonFinite,
        t,
        "the right-hand side f(t, x) is not finite at the current point",
    )
}
