//! The [`Integrator`]: the whole, serialisable solver state and the public driver API.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::common::check_times;
use super::{Method, OdeSystem, SolverError, SolverErrorKind, SolverOptions, Stats};

/// History that makes later steps depend on earlier ones. Everything here is saved with the
/// integrator; [`Integrator::notify_discontinuity`] resets it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct History {
    /// No step accepted since the start or the last discontinuity.
    pub first: bool,
    /// The last step attempt was rejected (limits the next step's growth).
    pub last_rejected: bool,
    /// Error norm of the previous accepted step (PI controller); 0 = none yet.
    pub err_prev: f64,
    /// Gustafsson's predictive controller (Radau5): previous accepted step and its error.
    pub h_acc: f64,
    pub err_acc: f64,
    /// Radau5: size of the last accepted step and its collocation polynomial (3 n numbers,
    /// RADAU5's CONT(N+1..4N)), used to extrapolate Newton start values. Empty = none.
    pub h_old: f64,
    pub cont: Vec<f64>,
    /// Radau5: Newton convergence-rate estimate carried between steps (RADAU5's FACCON).
    pub faccon: f64,
}

impl History {
    pub fn fresh() -> Self {
        History {
            first: true,
            last_rejected: false,
            err_prev: 0.0,
            h_acc: 0.0,
            err_acc: 0.0,
            h_old: 0.0,
            cont: Vec::new(),
            faccon: 1.0,
        }
    }
}

/// What the counters know about a constant Jacobian (see [`OdeSystem::constant_jacobian`]):
/// the stamp of the one last evaluated and the step size of the last factorisation with it.
/// Saved with the integrator so that a restored copy, which must rebuild J and its LU in memory,
/// counts exactly as the original did (once per stamp and per step size).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct Counted {
    /// Left out of the serialised form while there is none, so that the only `null` a saved
    /// state may hold is `initial_step`'s (any other would be a non-finite number).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jac: Option<u64>,
    /// Step sizes of the factorisations kept with `jac`, most recently used first (at most
    /// [`KEPT_FACTORISATIONS`]).
    pub lu_h: Vec<f64>,
    /// Steps accepted with the front factorisation since it came to the front (made, or taken
    /// up again): Radau5 builds its step map ([`super::step_map`]) for a factorisation once it
    /// has served this many. Saved, so that a restored copy builds it at the same step.
    #[serde(default)]
    pub front_steps: u32,
}

/// How many factorisations of a constant Jacobian (for different step sizes) are kept: a
/// communication step taken in one step, in two, and the odd one after a change.
pub(crate) const KEPT_FACTORISATIONS: usize = 3;

/// A factorisation made for a step size within this relative distance of the step to take is
/// used for it, with the step taken at the factorisation's size: with a constant Jacobian the
/// step to the next communication point, `t_end - t`, differs from the previous one only by the
/// rounding of t (about 1e-12 relative for t up to 10 s), and that must not cost a new LU. The
/// step is then an exact step of the factorisation's size; `t` is set to `t_end` afterwards as
/// always, a shift below 1e-9 of a step.
pub(crate) const SAME_STEP: f64 = 1e-9;

/// A step the controller proposes may be taken shorter, down to 1/SHORTER of it, to use a kept
/// factorisation of a constant Jacobian (RADAU5's QUOT2 = 1.2 plays this part for its step
/// changes): a step somewhat shorter than needed costs less than a new LU.
pub(crate) const SHORTER: f64 = 1.2;

impl Counted {
    /// The step size to factorise for (or use the factorisation of) when the step is `h`: a
    /// kept one within [`SAME_STEP`] of h, or, if `shorten`, the longest kept one between
    /// h / [`SHORTER`] and h (moved to the front); or h itself, counted as a new factorisation
    /// (`count` is added to the LU counter) and kept.
    pub fn factorisation_step(
        &mut self,
        h: f64,
        stats: &mut Stats,
        count: u64,
        shorten: bool,
    ) -> f64 {
        let same = self
            .lu_h
            .iter()
            .position(|&k| (k - h).abs() <= SAME_STEP * h);
        let shorter = || {
            let fits = |k: f64| k <= h && k * SHORTER >= h;
            (0..self.lu_h.len())
                .filter(|&i| fits(self.lu_h[i]))
                .max_by(|&i, &j| self.lu_h[i].total_cmp(&self.lu_h[j]))
        };
        match same.or_else(|| if shorten { shorter() } else { None }) {
            Some(0) => self.lu_h[0],
            Some(i) => {
                self.front_steps = 0;
                let k = self.lu_h.remove(i);
                self.lu_h.insert(0, k);
                k
            }
            None => {
                self.front_steps = 0;
                stats.lu_decompositions += count;
                self.lu_h.insert(0, h);
                self.lu_h.truncate(KEPT_FACTORISATIONS);
                h
            }
        }
    }
}

/// Moves the factorisation for step size `h` to the front of `kept`, making it with `make` if
/// it is not there (rebuilt after a restore: the same bits); keeps at most
/// [`KEPT_FACTORISATIONS`]. `make` is given the oldest one when that many are kept, to
/// refactorise in its memory. False if `make` fails (a singular matrix).
pub(crate) fn front_factorisation<F>(
    kept: &mut Vec<F>,
    h: f64,
    step_of: impl Fn(&F) -> f64,
    make: impl FnOnce(Option<F>) -> Option<F>,
) -> bool {
    match kept.iter().position(|f| step_of(f) == h) {
        Some(i) => {
            // (Already in front at nearly every step: no move of the factorisation's struct.)
            kept[..=i].rotate_right(1);
            true
        }
        None => match make(if kept.len() >= KEPT_FACTORISATIONS {
            kept.pop()
        } else {
            None
        }) {
            Some(f) => {
                kept.insert(0, f);
                kept.truncate(KEPT_FACTORISATIONS);
                true
            }
            None => false,
        },
    }
}

/// Memory kept between `advance_to` calls that changes no result: buffers, and for a system
/// with a constant Jacobian, J and its factorisations (rebuilt identically when absent). Not
/// serialised, not cloned (a clone starts empty), ignored by `==`.
#[derive(Default)]
pub(crate) struct Cache {
    /// Stamp of the constant Jacobian in `jac`, if any.
    pub stamp: Option<u64>,
    pub jac: DMatrix<f64>,
    /// Rodas5P's workspace and its LU of I/(h γ) - J for `stamp` (with its h).
    pub rodas: Option<Box<super::rodas5p::Work>>,
    pub rodas_lu: Vec<super::rodas5p::Factor>,
    /// Radau5's workspace and its real and complex LU for `stamp`.
    pub radau: Option<Box<super::radau5::Work>>,
    pub radau_lu: Vec<super::radau5::Lu>,
}

impl Clone for Cache {
    fn clone(&self) -> Self {
        Cache::default()
    }
}

impl PartialEq for Cache {
    fn eq(&self, _: &Cache) -> bool {
        true
    }
}

impl std::fmt::Debug for Cache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Cache {{ stamp: {:?} }}", self.stamp)
    }
}

impl Cache {
    /// Makes `jac` hold the constant Jacobian `stamp` of `sys` (evaluating it if the cache holds
    /// another or none; the factorisations of another one are dropped). Counts the evaluation
    /// unless `counted` says it was counted already. False if J is not finite.
    pub fn constant_jacobian<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        stamp: u64,
        t: f64,
        x: &[f64],
        stats: &mut Stats,
        counted: &mut Counted,
    ) -> bool {
        if self.stamp != Some(stamp) {
            let n = x.len();
            self.stamp = None;
            self.rodas_lu.clear();
            self.radau_lu.clear();
            if self.jac.shape() != (n, n) {
                self.jac = DMatrix::zeros(n, n);
            }
            if !sys.jacobian(t, x, &mut self.jac) {
                return false; // the stamp promises an analytic Jacobian
            }
            if !self.jac.iter().all(|v| v.is_finite()) {
                return false;
            }
            self.stamp = Some(stamp);
        }
        if counted.jac != Some(stamp) {
            stats.jac_evals += 1;
            counted.jac = Some(stamp);
            counted.lu_h.clear();
        }
        true
    }
}

/// Radau5's Jacobian kept from one call to the next. RADAU5 keeps J for as long as the simplified
/// Newton iteration converges fast (contraction θ ≤ 0.001), and with it the factorisations while
/// the step size stays the same; when every call ends on a communication point, a J evaluated
/// afresh at each call would cost a Jacobian and two LUs per step. The kept J is part of the
/// saved state, so that a restored copy (whose cache starts empty) rebuilds the same matrix and,
/// from it, the same factorisations, and continues bit-identically. Empty while none is kept;
/// never used for a constant Jacobian (the cache keeps that one).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct KeptJacobian {
    /// J's entries: with the system's structural pattern ([`OdeSystem::jacobian_pattern`]) row
    /// by row, the diagonal first and then the pattern's other columns in its order; without
    /// one all n² entries, column by column. Empty: no Jacobian is kept.
    pub entries: Vec<f64>,
    /// Step size of the factorisations made with it (0: none made).
    pub lu_h: f64,
}

impl KeptJacobian {
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn clear(&mut self) {
        self.entries.clear();
        self.lu_h = 0.0;
    }

    /// The positions `(i, j)` of the kept entries of an `n` × `n` Jacobian with structural
    /// pattern `pattern`, in the order of [`KeptJacobian::entries`].
    fn positions(
        n: usize,
        pattern: Option<&[Vec<u32>]>,
    ) -> impl Iterator<Item = (usize, usize)> + '_ {
        let rows = pattern.filter(|rows| rows.len() == n);
        let structural = rows
            .into_iter()
            .flatten()
            .enumerate()
            .flat_map(|(i, cols)| {
                let off_diagonal = cols.iter().map(|&j| j as usize).filter(move |&j| j != i);
                std::iter::once(i).chain(off_diagonal).map(move |j| (i, j))
            });
        let dense = (0..if rows.is_none() { n * n } else { 0 }).map(move |k| (k % n, k / n));
        structural.chain(dense)
    }

    /// The number of entries kept of an `n` × `n` Jacobian with structural pattern `pattern`.
    pub fn len_for(n: usize, pattern: Option<&[Vec<u32>]>) -> usize {
        Self::positions(n, pattern).count()
    }

    /// Keeps `jac`'s entries (see [`KeptJacobian::entries`]), reusing the memory.
    pub fn store(&mut self, jac: &DMatrix<f64>, pattern: Option<&[Vec<u32>]>) {
        self.entries.clear();
        let kept = Self::positions(jac.nrows(), pattern).map(|(i, j)| jac[(i, j)]);
        self.entries.extend(kept);
    }

    /// Rebuilds the kept J into `jac` (n × n; zero outside the pattern, where J is zero by the
    /// pattern's promise). False, leaving `jac` unspecified, if the entries do not fit.
    pub fn rebuild(&self, pattern: Option<&[Vec<u32>]>, jac: &mut DMatrix<f64>) -> bool {
        let n = jac.nrows();
        if jac.ncols() != n || self.entries.len() != Self::len_for(n, pattern) {
            return false;
        }
        jac.fill(0.0);
        for ((i, j), &v) in Self::positions(n, pattern).zip(&self.entries) {
            jac[(i, j)] = v;
        }
        true
    }

    /// Checks a restored one against the system's size and pattern: entries that fit, all finite,
    /// and a finite non-negative step size.
    pub fn check(&self, n: usize, pattern: Option<&[Vec<u32>]>) -> Result<(), String> {
        if self.is_empty() {
            return Ok(());
        }
        let len = Self::len_for(n, pattern);
        if self.entries.len() != len {
            return Err(format!(
                "its kept Jacobian holds {} entries, the model's has {len}",
                self.entries.len()
            ));
        }
        if !(self.entries.iter().all(|v| v.is_finite())
            && self.lu_h.is_finite()
            && self.lu_h >= 0.0)
        {
            return Err("its kept Jacobian holds a non-finite number or a negative step".into());
        }
        Ok(())
    }
}

/// The last accepted step when the integrator has stepped past the point it reports (see
/// [`Integrator::advance_within`]): the step from `t0` to `t1` of size `h`, its end state `x1`
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
    fn is_idle(&self) -> bool {
        !self.active
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
            super::rodas5p::dense(
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

/// A stiff integrator: options, current point, next step size, history and statistics.
///
/// It is `Clone` and serde-serialisable; a restored copy continues bit-identically (see the
/// module documentation). No non-finite number is ever stored in it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Integrator {
    pub(crate) options: SolverOptions,
    pub(crate) t: f64,
    pub(crate) x: Vec<f64>,
    /// Next step size to try; 0 = estimate one at the next `advance_to`.
    pub(crate) h: f64,
    pub(crate) stats: Stats,
    pub(crate) hist: History,
    /// What the counters know about a constant Jacobian.
    #[serde(default)]
    pub(crate) counted: Counted,
    /// The step that went past the reported point, if the last call stepped past it.
    #[serde(default, skip_serializing_if = "Ahead::is_idle")]
    pub(crate) ahead: Ahead,
    /// Radau5's Jacobian kept for the next call, if any.
    #[serde(default, skip_serializing_if = "KeptJacobian::is_empty")]
    pub(crate) kept_jac: KeptJacobian,
    #[serde(skip)]
    pub(crate) cache: Cache,
}

impl Integrator {
    /// A new integrator at (t0, x0). Fails if the options or the initial point are invalid.
    pub fn new(options: SolverOptions, t0: f64, x0: Vec<f64>) -> Result<Self, SolverError> {
        options.validate(x0.len()).map_err(|mut e| {
            e.t = t0;
            e
        })?;
        check_point(t0, &x0)?;
        Ok(Integrator {
            options,
            t: t0,
            x: x0,
            h: 0.0,
            stats: Stats::default(),
            hist: History::fresh(),
            counted: Counted::default(),
            ahead: Ahead::default(),
            kept_jac: KeptJacobian::default(),
            cache: Cache::default(),
        })
    }

    pub fn t(&self) -> f64 {
        self.t
    }
    pub fn x(&self) -> &[f64] {
        &self.x
    }
    pub fn stats(&self) -> &Stats {
        &self.stats
    }
    pub fn options(&self) -> &SolverOptions {
        &self.options
    }
    /// Step size the next step will try (0 before the first step).
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// [`Method::Rodas5PFixed`]: the largest embedded error estimate of the steps of the last
    /// call, as a multiple of the tolerances (the RMS norm the adaptive drivers test against 1:
    /// above 1, a step they would have rejected). 0 before the first call and after a
    /// discontinuity, and always 0 for the adaptive methods (whose step-size controller keeps
    /// another number in the same place).
    pub fn fixed_step_error(&self) -> f64 {
        match self.options.method {
            Method::Rodas5PFixed => self.hist.err_prev,
            Method::Rodas5P | Method::Radau5 => 0.0,
        }
    }

    /// Replace the options (e.g. tolerances) keeping the state. Resets history like
    /// [`Integrator::notify_discontinuity`] since the controller history refers to the old
    /// tolerances.
    pub fn set_options(&mut self, options: SolverOptions) -> Result<(), SolverError> {
        options.validate(self.x.len()).map_err(|mut e| {
            e.t = self.t;
            e
        })?;
        if options.method != self.options.method {
            self.h = 0.0;
            self.counted = Counted::default();
        }
        self.options = options;
        // Radau5's workspace holds its transformed tolerances.
        self.cache.radau = None;
        self.kept_jac.clear();
        self.notify_discontinuity();
        Ok(())
    }

    /// Advance to exactly t_end (t() == t_end bit-exactly afterwards on success). On error the
    /// integrator stays at the last accepted point (t() < t_end) and remains usable.
    pub fn advance_to<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t_end: f64,
    ) -> Result<(), SolverError> {
        self.advance_to_with_output(sys, t_end, &[], &mut |_, _| {})
    }

    /// Same, calling `out(t, x)` at each requested output time in (t(), t_end] via dense
    /// output. `times` must be finite and non-decreasing; times outside (t(), t_end] are
    /// ignored.
    pub fn advance_to_with_output<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t_end: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        self.advance(sys, t_end, t_end, times, out)
    }

    /// Advance to `t_end` without ending a step there: steps keep the size the error control
    /// chooses and may go past `t_end`, though never past `limit` (`t_end <= limit`, `+inf`
    /// for none). Afterwards `t()` is `t_end` bit-exactly and `x()` the state there,
    /// interpolated from the dense output of the step that covers it (Rodas5P's continuous
    /// extension of order 4), which is within the tolerance like the step's end point.
    /// Radau5 ends its steps on `t_end` all the same: its dense output, the collocation
    /// polynomial, is of order 3 only and would spoil the accuracy between its steps.
    ///
    /// The integrator keeps that step: a next call whose `t_end` it also covers only
    /// interpolates, and one beyond it goes on from the step's end, so that a run of short
    /// calls costs about as many steps as one long call. [`Integrator::notify_discontinuity`]
    /// and [`Integrator::reset`] drop the step and go on from the reported point, as after
    /// [`Integrator::advance_to`]. The step is part of the integrator's saved state, so a
    /// restored copy continues bit-identically.
    ///
    /// With `limit == t_end` this is [`Integrator::advance_to`].
    pub fn advance_past<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t_end: f64,
        limit: f64,
    ) -> Result<(), SolverError> {
        self.advance(sys, t_end, limit, &[], &mut |_, _| {})
    }

    /// Is (t(), x()) a point inside the last accepted step, interpolated by
    /// [`Integrator::advance_past`], rather than a step's end?
    pub fn is_past(&self) -> bool {
        self.ahead.active
    }

    /// Where integration has got to: the end of the step kept past `t()` if
    /// [`Integrator::is_past`], else `t()`. Never past the `limit` of [`Integrator::advance_past`].
    pub fn reached(&self) -> f64 {
        if self.ahead.active {
            self.ahead.t1
        } else {
            self.t
        }
    }

    fn advance<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t_end: f64,
        limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        if limit.is_nan() || limit < t_end {
            return Err(SolverError::new(
                SolverErrorKind::InvalidInput,
                self.t,
                format!("the limit {limit} lies before t_end = {t_end}"),
            ));
        }
        if sys.dim() != self.x.len() {
            return Err(SolverError::new(
                SolverErrorKind::InvalidInput,
                self.t,
                format!(
                    "system has {} states but the integrator holds {}",
                    sys.dim(),
                    self.x.len()
                ),
            ));
        }
        if !t_end.is_finite() || t_end < self.t {
            return Err(SolverError::new(
                SolverErrorKind::InvalidInput,
                self.t,
                format!(
                    "t_end must be finite and not before t = {}, got {}",
                    self.t, t_end
                ),
            ));
        }
        check_point(self.t, &self.x)?;
        check_times(times, self.t)?;
        if t_end == self.t {
            return Ok(());
        }
        if self.ahead.active {
            if t_end <= self.ahead.t1 {
                self.emit_ahead(t_end, times, out);
                let mut x = std::mem::take(&mut self.x);
                self.dense_at(t_end, &mut x);
                self.x = x;
                self.t = t_end;
                return Ok(());
            }
            // Go on from the end of the kept step.
            let t1 = self.ahead.t1;
            self.emit_ahead(t1, times, out);
            std::mem::swap(&mut self.x, &mut self.ahead.x1);
            self.t = t1;
            self.ahead.active = false;
        }
        let result = match self.options.method {
            Method::Rodas5P => super::rodas5p::advance(self, sys, t_end, limit, times, out),
            // Radau5 ends its steps on t_end whatever the limit: its dense output, the
            // collocation polynomial, is of order 3 only, and read between the points of free
            // steps it erred by 1e-5 at rtol 1e-6 on the LOES with the plate (6 times the error
            // of steps ending on the points; Rodas5P's order-4 extension: 2e-7).
            Method::Radau5 => super::radau5::advance(self, sys, t_end, times, out),
            // Real time: the caller's step, in equal substeps, never past t_end.
            Method::Rodas5PFixed => super::fixed::advance(self, sys, t_end, times, out),
        };
        if let Err(e) = &result {
            if e.kind != SolverErrorKind::TooManySteps {
                // The step size and history that led into the failure are no guide for the
                // next attempt (typically made after the caller changed something): restart
                // with a fresh step-size estimate.
                self.h = 0.0;
                self.hist = History::fresh();
            }
        }
        result
    }

    /// The state at `t` inside the kept step (t0 <= t <= t1), into `buf`: its end state at t1
    /// itself, else the method's dense output.
    fn dense_at(&self, t: f64, buf: &mut [f64]) {
        let a = &self.ahead;
        if t == a.t1 {
            buf.copy_from_slice(&a.x1);
            return;
        }
        // Only Rodas5P steps past t_end (see `advance`).
        super::rodas5p::dense(&a.x0, &a.x1, &a.coef, (t - a.t0) / a.h, buf);
    }

    /// Calls `out` at the output times in (t(), until] from the kept step.
    fn emit_ahead(&self, until: f64, times: &[f64], out: &mut dyn FnMut(f64, &[f64])) {
        let mut due = times
            .iter()
            .filter(|&&w| w > self.t && w <= until)
            .peekable();
        if due.peek().is_some() {
            let mut buf = vec![0.0; self.x.len()];
            for &w in due {
                self.dense_at(w, &mut buf);
                out(w, &buf);
            }
        }
    }

    /// The inputs of the system jumped (zero-order hold at a communication point): forget
    /// whatever history assumes smoothness across this point (controller history, Newton
    /// start polynomial). Keeps h as a guess, and Radau5's kept Jacobian: the simplified Newton
    /// iteration needs only an approximate one, and its convergence monitor asks for a new J
    /// when the old one no longer serves (RADAU5 knows nothing of jumps either).
    pub fn notify_discontinuity(&mut self) {
        // Keeps the buffer of the collocation polynomial (emptied, so unused): an input jump at
        // every communication point must not cost an allocation.
        let mut cont = std::mem::take(&mut self.hist.cont);
        cont.clear();
        self.hist = History {
            cont,
            ..History::fresh()
        };
        // Go on from the reported point, not from the end of a step taken with the old inputs.
        self.ahead.active = false;
    }

    /// Replace the state (e.g. re-initialisation); resets history like notify_discontinuity.
    /// A non-finite t or x, or a length change, is reported by the next `advance_to`.
    pub fn reset(&mut self, t: f64, x: Vec<f64>) {
        if x.len() != self.x.len() {
            self.cache = Cache::default();
            self.counted = Counted::default();
        }
        self.t = t;
        self.x = x;
        // A Jacobian kept from elsewhere is no guide at the new point.
        self.kept_jac.clear();
        self.notify_discontinuity();
    }

    /// Like [`Integrator::reset`] but validates the new point.
    pub fn try_reset(&mut self, t: f64, x: Vec<f64>) -> Result<(), SolverError> {
        check_point(t, &x)?;
        if x.len() != self.x.len() {
            if let super::Atol::Vector(_) = self.options.atol {
                return Err(SolverError::new(
                    SolverErrorKind::InvalidInput,
                    t,
                    format!(
                        "new state has {} components, atol vector has {}",
                        x.len(),
                        self.x.len()
                    ),
                ));
            }
        }
        self.reset(t, x);
        Ok(())
    }
}

fn check_point(t: f64, x: &[f64]) -> Result<(), SolverError> {
    if !t.is_finite() {
        return Err(SolverError::new(
            SolverErrorKind::InvalidInput,
            0.0,
            format!("t must be finite, got {t}"),
        ));
    }
    if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SolverError::new(
            SolverErrorKind::InvalidInput,
            t,
            format!("state x[{i}] is not finite: {v}"),
        ));
    }
    Ok(())
}
