//! Radau5's own state ([`State`]) and its registration as a method ([`Radau5`]): the
//! controller's history and the Newton start polynomial, the counters' record of a constant
//! Jacobian, the Jacobian kept across calls, and the buffers.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::workspace::Work;
use crate::solver::constant_jacobian::{Cache, Counted};
use crate::solver::method::{check_non_negative, OdeMethod, Stepper};
use crate::solver::{OdeSystem, SolverError, SolverOptions};

/// Radau IIA of order 5 in the manner of RADAU5 (see the module documentation of [`super`]).
pub struct Radau5;

/// The version of [`State`]'s saved form (see [`OdeMethod::STATE_VERSION`]).
pub const STATE_VERSION: u32 = 1;

impl OdeMethod for Radau5 {
    const NAME: &'static str = "radau5";
    const ALIASES: &'static [&'static str] = &["radau", "radauiia5"];
    const STATE_VERSION: u32 = STATE_VERSION;
    type State = State;

    fn fresh(_: &SolverOptions, _: usize) -> State {
        State::default()
    }

    /// Radau5 ends its steps on t_end whatever the limit: its dense output, the collocation
    /// polynomial, is of order 3 only, and read between the points of free steps it erred by
    /// 1e-5 at rtol 1e-6 on the LOES with the plate (6 times the error of steps ending on the
    /// points; Rodas5P's order-4 extension: 2e-7).
    fn advance(
        run: &mut Stepper<State>,
        sys: &dyn OdeSystem,
        t_end: f64,
        _limit: f64,
        times: &[f64],
        out: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), SolverError> {
        super::advance(run, sys, t_end, times, out)
    }

    /// Keeps the buffer of the collocation polynomial (emptied, so unused): an input jump at
    /// every communication point must not cost an allocation. Keeps the kept Jacobian: the
    /// simplified Newton iteration needs only an approximate one, and its convergence monitor
    /// asks for a new J when the old one no longer serves (RADAU5 knows nothing of jumps
    /// either).
    fn notify_discontinuity(state: &mut State) {
        let mut cont = std::mem::take(&mut state.hist.cont);
        cont.clear();
        state.hist = History {
            cont,
            ..History::fresh()
        };
    }

    fn reset(state: &mut State, resized: bool) {
        if resized {
            state.cache = Cache::default();
            state.counted = Counted::default();
        }
        // A Jacobian kept from elsewhere is no guide at the new point.
        state.kept_jac.clear();
        Self::notify_discontinuity(state);
    }

    fn options_changed(state: &mut State) {
        // The workspace holds the transformed tolerances.
        state.cache.work = None;
        state.kept_jac.clear();
        Self::notify_discontinuity(state);
    }

    fn after_failure(state: &mut State) {
        state.hist = History::fresh();
    }

    fn check_restored(run: &Stepper<State>, pattern: Option<&[Vec<u32>]>) -> Result<(), String> {
        let (h, dim) = (&run.state.hist, run.x.len());
        check_non_negative("h_acc", h.h_acc)?;
        check_non_negative("err_acc", h.err_acc)?;
        check_non_negative("h_old", h.h_old)?;
        check_non_negative("faccon", h.faccon)?;
        if !(h.cont.is_empty() || h.cont.len() == 3 * dim) || h.cont.iter().any(|c| !c.is_finite())
        {
            return Err(format!(
                "its integrator's interpolation history has {} entries, not 0 or {}, or a non-finite one",
                h.cont.len(),
                3 * dim
            ));
        }
        run.state.kept_jac.check(dim, pattern)
    }
}

/// Radau5's state between calls. Everything but `cache` is saved.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct State {
    pub(crate) hist: History,
    /// What the counters know about a constant Jacobian.
    pub(crate) counted: Counted,
    /// The Jacobian kept for the next call, if any.
    #[serde(default, skip_serializing_if = "KeptJacobian::is_empty")]
    pub(crate) kept_jac: KeptJacobian,
    /// Buffers, and a constant Jacobian with its factorisations.
    #[serde(skip)]
    pub(crate) cache: Cache<Work>,
}

impl Default for State {
    fn default() -> Self {
        State {
            hist: History::fresh(),
            counted: Counted::default(),
            kept_jac: KeptJacobian::default(),
            cache: Cache::default(),
        }
    }
}

/// History that makes later steps depend on earlier ones. Everything here is saved with the
/// integrator; [`Integrator::notify_discontinuity`](crate::solver::Integrator::notify_discontinuity) resets it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct History {
    /// No step accepted since the start or the last discontinuity.
    pub first: bool,
    /// The last step attempt was rejected (limits the next step's growth).
    pub last_rejected: bool,
    /// Gustafsson's predictive controller: previous accepted step and its error.
    pub h_acc: f64,
    pub err_acc: f64,
    /// Size of the last accepted step and its collocation polynomial (3 n numbers,
    /// RADAU5's CONT(N+1..4N)), used to extrapolate Newton start values. Empty = none.
    pub h_old: f64,
    pub cont: Vec<f64>,
    /// Newton convergence-rate estimate carried between steps (RADAU5's FACCON).
    pub faccon: f64,
}

impl History {
    pub fn fresh() -> Self {
        History {
            first: true,
            last_rejected: false,
            h_acc: 0.0,
            err_acc: 0.0,
            h_old: 0.0,
            cont: Vec::new(),
            faccon: 1.0,
        }
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
