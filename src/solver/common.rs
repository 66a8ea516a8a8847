//! Pieces shared by both methods: scaling, norms, the starting step, the step-size floor,
//! dense-output bookkeeping and non-finite checks.

// Index loops over stages and components mirror the formulas they implement.
#![allow(clippy::needless_range_loop)]

use nalgebra::DMatrix;

use super::constant_jacobian::{Cache, Counted};
use super::method::Stepper;
use super::{Atol, OdeSystem, SolverError, SolverErrorKind, SolverOptions, Stats};

/// Error weights `atol_i + rtol * max(|a_i|, |b_i|)`, floored at the smallest normal number so
/// that a component with atol = 0 sitting at 0 cannot divide by zero.
pub(crate) fn scale_into(atol: &Atol, rtol: f64, a: &[f64], b: &[f64], sc: &mut [f64]) {
    for i in 0..sc.len() {
        let s = atol.get(i) + rtol * a[i].abs().max(b[i].abs());
        sc[i] = s.max(f64::MIN_POSITIVE);
    }
}

/// Weighted RMS norm sqrt(mean((v_i / sc_i)^2)) (Hairer & Wanner II, eq. IV.8.20).
pub(crate) fn rms(v: &[f64], sc: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let s: f64 = v.iter().zip(sc).map(|(x, s)| (x / s) * (x / s)).sum();
    (s / v.len() as f64).sqrt()
}

/// `y += a x`.
#[inline]
pub(crate) fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// Whether every entry of `v` is finite: without an early exit, so that the loop has no branch
/// and vectorises (the stages of a step are finite but for a failure; a stage of the complete
/// system is tested in a few vector operations instead of a branch per entry).
pub(crate) fn all_finite(v: &[f64]) -> bool {
    v.iter().fold(true, |all, x| all & x.is_finite())
}

/// The method's factorisations kept in `slot` from the last call, for a call with Jacobian stamp
/// `stamp`: they survive only while the Jacobian is constant and the same (`cached` is the stamp
/// they were made with); otherwise the call starts with none.
fn take_factorisations<L>(slot: &mut Vec<L>, cached: Option<u64>, stamp: Option<u64>) -> Vec<L> {
    let mut lus = std::mem::take(slot);
    if stamp.is_none() || cached != stamp {
        lus.clear();
    }
    lus
}

/// Puts the factorisations back into `slot` after a call: those of a constant Jacobian are kept
/// for the next call, any other lived for this call only.
fn keep_factorisations<L>(slot: &mut Vec<L>, mut lus: Vec<L>, stamp: Option<u64>) {
    if stamp.is_none() {
        lus.clear();
    }
    *slot = lus;
}

/// A method's buffers, kept between `advance` calls in the method's cache so that a call
/// allocates nothing once they exist.
pub(crate) trait Workspace {
    /// The method's factorisations of its iteration matrices.
    type Lu;
    /// Buffers for `n` states.
    fn new(n: usize) -> Self;
    /// The number of states the buffers are for.
    fn dim(&self) -> usize;
    /// The memory of the last factorisations of a Jacobian that changes from step to step.
    fn spare(&mut self) -> &mut Option<Self::Lu>;
}

/// Runs one method's `advance` body `run` with the method's buffers and factorisations taken out
/// of its cache (`cache` picks it in the method's state) and puts them back after, whatever the
/// outcome: the buffers always, the factorisations of a constant Jacobian for the next call, and
/// otherwise the memory of the last one as the buffers' spare.
pub(crate) fn with_kept_memory<St, W: Workspace, R>(
    integ: &mut Stepper<St>,
    stamp: Option<u64>,
    cache: fn(&mut St) -> &mut Cache<W>,
    run: impl FnOnce(&mut Stepper<St>, &mut W, &mut Vec<W::Lu>) -> R,
) -> R {
    let n = integ.x.len();
    let c = cache(&mut integ.state);
    let mut w = match c.work.take() {
        Some(w) if w.dim() == n => w,
        _ => Box::new(W::new(n)),
    };
    let cached = c.stamp;
    let mut lus = take_factorisations(&mut c.lu, cached, stamp);
    let result = run(integ, &mut w, &mut lus);
    if stamp.is_none() {
        let spare = w.spare();
        *spare = lus.pop().or(spare.take());
    }
    let c = cache(&mut integ.state);
    c.work = Some(w);
    keep_factorisations(&mut c.lu, lus, stamp);
    result
}

/// J = ∂f/∂x at the integrator's current point, into `jac`, or, for a constant Jacobian
/// (`stamp`, [`OdeSystem::constant_jacobian`]), the one kept in the method's cache
/// (evaluated once per stamp). `fd_tolerances` are the (atol, rtol) of a finite-difference
/// Jacobian (None: the integrator's own). `holds` is the stamp of the constant part of the J
/// that `jac` holds ([`OdeSystem::jacobian_constant_part`]), None when it holds none: with it,
/// only the varying entries are written. False if J is not finite.
#[allow(clippy::too_many_arguments)]
pub(crate) fn jacobian_here<St, W: Workspace, S: OdeSystem + ?Sized>(
    integ: &mut Stepper<St>,
    kept: fn(&mut St) -> (&mut Counted, &mut Cache<W>),
    sys: &S,
    stamp: Option<u64>,
    f0: &[f64],
    fd_tolerances: Option<(&Atol, f64)>,
    jac: &mut DMatrix<f64>,
    holds: &mut Option<u64>,
) -> bool {
    let Stepper {
        t,
        x,
        stats,
        state,
        options,
        ..
    } = integ;
    match stamp {
        Some(stamp) => {
            let (counted, cache) = kept(state);
            cache.constant_jacobian(sys, stamp, *t, x, stats, counted)
        }
        None => {
            let (atol, rtol) = fd_tolerances.unwrap_or((&options.atol, options.rtol));
            super::jacobian::evaluate(sys, stats, *t, x, f0, atol, rtol, jac, holds)
        }
    }
}

/// Evaluate f, counting it.
#[inline]
pub(crate) fn eval<S: OdeSystem + ?Sized>(
    sys: &S,
    stats: &mut Stats,
    t: f64,
    x: &[f64],
    out: &mut [f64],
) {
    stats.f_evals += 1;
    sys.rhs(t, x, out);
}

/// 16 ulp of t: a step this small would not change t reliably. A remainder up to t_end below
/// this (only possible through rounding in the caller's times) is covered by explicit Euler.
pub(crate) fn rounding_floor(t: f64) -> f64 {
    16.0 * f64::EPSILON * t.abs()
}

/// Below this a step is explicit Euler's, not the method's: 16 ulp of t (the step would not
/// change t reliably), or √(smallest normal double) ≈ 1.5e-154 (the methods' terms in 1/h and
/// its square would overflow; a communication step of 5e-324 s is one an importer may ask for).
/// Euler's local error, O(h² |f'|), is far below any tolerance at such a size, and it is stable
/// while h |λ| < 2, which such a step meets for any eigenvalue λ of a model.
pub(crate) fn euler_floor(t: f64) -> f64 {
    rounding_floor(t).max(f64::MIN_POSITIVE.sqrt())
}

/// Smallest admissible step at time t chosen by error control: the user's `min_step`, but
/// never below [`rounding_floor`].
pub(crate) fn h_min(opts: &SolverOptions, t: f64) -> f64 {
    opts.min_step.max(rounding_floor(t))
}

/// Starting step size, Hairer, Nørsett & Wanner I, Sec. II.4 ("Starting step size"), with the
/// weights of the error norm: h0 from |x|/|f|, then one explicit Euler probe estimates the
/// second derivative, and h = (0.01 / max(|f|, |f'|))^(1/(p+1)). The controller corrects it.
/// From the integrator's current point, with its options; `f0` is f there, `order` is p.
pub(crate) fn initial_step<St, S: OdeSystem + ?Sized>(
    sys: &S,
    integ: &mut Stepper<St>,
    f0: &[f64],
    t_end: f64,
    order: f64,
) -> f64 {
    let Stepper {
        options: opts,
        stats,
        t,
        x,
        ..
    } = integ;
    let (t, x) = (*t, x.as_slice());
    let span = (t_end - t).abs();
    let cap = span.min(opts.max_step);
    if let Some(h0) = opts.initial_step {
        return h0.min(cap);
    }
    let n = x.len();
    let mut sc = vec![0.0; n];
    scale_into(&opts.atol, opts.rtol, x, x, &mut sc);
    let d0 = rms(x, &sc);
    let d1 = rms(f0, &sc);
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(cap);
    let x1: Vec<f64> = x.iter().zip(f0).map(|(xi, fi)| xi + h0 * fi).collect();
    let mut f1 = vec![0.0; n];
    eval(sys, stats, t + h0, &x1, &mut f1);
    if !all_finite(&f1) {
        return (h0 * 1e-3).max(h_min(opts, t));
    }
    let diff: Vec<f64> = f1.iter().zip(f0).map(|(a, b)| a - b).collect();
    let d2 = rms(&diff, &sc) / h0;
    let dm = d1.max(d2);
    let h1 = if dm <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        crate::math::powf(0.01 / dm, 1.0 / (order + 1.0))
    };
    let h = (100.0 * h0).min(h1).min(cap);
    if h.is_finite() && h > 0.0 {
        h
    } else {
        h0
    }
}

/// Requested output times, validated: finite and non-decreasing. Times outside
/// (t, t_end] are skipped by the caller.
pub(crate) fn check_times(times: &[f64], t: f64) -> Result<(), SolverError> {
    for (i, w) in times.iter().enumerate() {
        if !w.is_finite() {
            return Err(SolverError::new(
                SolverErrorKind::InvalidInput,
                t,
                format!("output time times[{i}] is not finite: {w}"),
            ));
        }
        if i > 0 && *w < times[i - 1] {
            return Err(SolverError::new(
                SolverErrorKind::InvalidInput,
                t,
                format!(
                    "output times must be non-decreasing; times[{i}] = {w} < times[{}]",
                    i - 1
                ),
            ));
        }
    }
    Ok(())
}

/// Cursor over the requested output times of one `advance_to` call.
pub(crate) struct Outputs<'a> {
    pub times: &'a [f64],
    pub next: usize,
    pub buf: Vec<f64>,
}

impl<'a> Outputs<'a> {
    pub fn new(times: &'a [f64], t: f64, n: usize) -> Self {
        let next = times.iter().position(|&w| w > t).unwrap_or(times.len());
        Outputs {
            times,
            next,
            // No allocation when there are no output times (the FMU's case).
            buf: if times.is_empty() {
                Vec::new()
            } else {
                vec![0.0; n]
            },
        }
    }

    /// Is there an output time in (t0, t1]?
    pub fn pending(&self, t1: f64) -> bool {
        self.next < self.times.len() && self.times[self.next] <= t1
    }

    /// Emit every output time in (t0, t1] of the step just accepted. `interp(theta, buf)`
    /// evaluates the dense output at t0 + theta * h; at t1 itself x1 is reported exactly.
    pub fn emit(
        &mut self,
        t0: f64,
        h: f64,
        t1: f64,
        x1: &[f64],
        interp: &mut dyn FnMut(f64, &mut [f64]),
        out: &mut dyn FnMut(f64, &[f64]),
    ) {
        while self.pending(t1) {
            let w = self.times[self.next];
            if w == t1 {
                out(w, x1);
            } else {
                let theta = ((w - t0) / h).clamp(0.0, 1.0);
                interp(theta, &mut self.buf);
                out(w, &self.buf);
            }
            self.next += 1;
        }
    }
}

/// What the step loop of `advance_to` does next.
pub(crate) enum NextStep {
    /// `t_end` is reached.
    Done,
    /// Attempt a step of size `h`; `last` if it ends on the limit (`t_end`, unless the caller
    /// lets steps go past it). `proposed` is the step the controller asked for, kept as the
    /// next call's guess when the limit cut it short.
    Step { h: f64, last: bool, proposed: f64 },
}

/// Plans the next step attempt, the same way for both methods (with `quantise`, a step shorter
/// than what is left before `t_end` is an equal share of it, see below): covers a remnant before
/// `t_end` below [`euler_floor`] (a few ulp of t, or a denormal step) with an explicit Euler
/// step, error O(remaining^2); counts the attempt
/// against `max_steps`; clips h to `max_step` and to `limit` (`t_end`, or beyond it when the
/// caller lets steps go past `t_end`: [`Integrator::advance_past`](super::Integrator::advance_past)); and fails when h has fallen below
/// the minimum step, with the kind and reason `why_small` gives. A final step shorter than the
/// minimum is fine: its size is dictated by `t_end`, not by error control.
pub(crate) fn plan_step<St>(
    integ: &mut Stepper<St>,
    t_end: f64,
    limit: f64,
    f0: &[f64],
    attempts: &mut u64,
    quantise: bool,
    why_small: impl FnOnce() -> (SolverErrorKind, &'static str),
) -> Result<NextStep, SolverError> {
    let t = integ.t;
    let remaining = t_end - t;
    if remaining <= euler_floor(t) {
        for (x, f) in integ.x.iter_mut().zip(f0) {
            *x += remaining * f;
        }
        integ.t = t_end;
        return Ok(NextStep::Done);
    }
    *attempts += 1;
    if *attempts > integ.options.max_steps {
        return Err(SolverError::new(
            SolverErrorKind::TooManySteps,
            t,
            format!(
                "more than max_steps = {} step attempts in one call",
                integ.options.max_steps
            ),
        ));
    }
    let h_proposed = integ.h.min(integ.options.max_step);
    // Room before the limit: `remaining` itself unless the caller lets steps go past t_end.
    let room = if limit > t_end { limit - t } else { remaining };
    let (h, last) = if h_proposed >= room {
        (room, true)
    } else if quantise && limit == t_end && h_proposed * 64.0 >= remaining {
        // An equal share of what is left, not larger than proposed: the same few step sizes
        // recur from one communication step to the next, and so do their factorisations (with
        // a constant Jacobian, which is when this is asked for).
        let k = (remaining / h_proposed).ceil();
        (remaining / k, false)
    } else {
        (h_proposed, false)
    };
    let hmin = h_min(&integ.options, t);
    // A step that reaches t_end may be short: its size came from t_end (a short communication
    // step), not from error control.
    if h < hmin && !last && h < remaining {
        let (kind, reason) = why_small();
        return Err(SolverError::new(
            kind,
            t,
            format!("step size {h:e} fell below the minimum {hmin:e} {reason}"),
        ));
    }
    Ok(NextStep::Step {
        h,
        last,
        proposed: h_proposed,
    })
}
