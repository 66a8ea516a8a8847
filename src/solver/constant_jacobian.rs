//! What the methods share about a constant Jacobian ([`OdeSystem::constant_jacobian`]): the
//! counters' record of it ([`Counted`], part of a method's saved state), the factorisations
//! kept for a few step sizes, and the [`Cache`] that holds J, the factorisations and a method's
//! buffers in memory between calls.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::common::Workspace;
use super::{OdeSystem, Stats};

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

/// Memory a method keeps between `advance_to` calls that changes no result: its buffers `W`,
/// and for a system with a constant Jacobian, J and its factorisations (rebuilt identically
/// when absent). Not serialised, not cloned (a clone starts empty), ignored by `==`.
pub(crate) struct Cache<W: Workspace> {
    /// Stamp of the constant Jacobian in `jac`, if any.
    pub stamp: Option<u64>,
    pub jac: DMatrix<f64>,
    /// The method's workspace.
    pub work: Option<Box<W>>,
    /// The method's factorisations of its iteration matrices for `stamp` (with their h).
    pub lu: Vec<W::Lu>,
}

impl<W: Workspace> Default for Cache<W> {
    fn default() -> Self {
        Cache {
            stamp: None,
            jac: DMatrix::zeros(0, 0),
            work: None,
            lu: Vec::new(),
        }
    }
}

impl<W: Workspace> Clone for Cache<W> {
    fn clone(&self) -> Self {
        Cache::default()
    }
}

impl<W: Workspace> PartialEq for Cache<W> {
    fn eq(&self, _: &Cache<W>) -> bool {
        true
    }
}

impl<W: Workspace> std::fmt::Debug for Cache<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Cache {{ stamp: {:?} }}", self.stamp)
    }
}

impl<W: Workspace> Cache<W> {
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
            self.lu.clear();
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
