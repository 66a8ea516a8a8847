//! The iteration matrix W = I/(h γ) − J of a Rodas5P step and its factorisations: a kept LU
//! (and, for a small system, its explicit inverse) for each step size in use when J is
//! constant; a new LU in the memory of the last when J changes from step to step; and for the
//! fixed-step driver, the elimination of J's constant rows kept across steps with only the
//! varying rows' Schur complement factorised per step ([`VaryingRows`]).

use std::sync::Arc;

use nalgebra::DMatrix;

use super::State;
use super::{Work, GAMMA};
use crate::solver::constant_jacobian::front_factorisation;
use crate::solver::dense::DenseInverse;
use crate::solver::linalg::{factor_with_fallback, Factorisation, Partition, Shifted, VaryingRows};
use crate::solver::method::Stepper;
use crate::solver::step_map;
use crate::solver::OdeSystem;

/// The LU of W = I/(h γ) - J for the step size `h`, and for a constant J of a small system
/// (n ≤ [`step_map::MAX_DIM`]) its explicit inverse, with which the step's eight solves are
/// dense products ([`DenseInverse`]).
pub(crate) struct Factor {
    h: f64,
    lu: Factorisation<f64>,
    inverse: DenseInverse,
    /// For the fixed-step driver, a J whose constant rows are kept: their elimination (see
    /// [`KeptRows`]), which the solves use while `by_rows` (else `lu` or `inverse`).
    rows: Option<KeptRows>,
    by_rows: bool,
}

/// The elimination of a J's constant rows for one shift c = 1/(h γ) ([`VaryingRows`]), kept
/// across the steps of the fixed-step driver: the constant part `stamp`
/// ([`OdeSystem::jacobian_constant_part`]) and c it was made for, and None if its constant
/// block was singular (the general LU then serves, without retrying at every step).
struct KeptRows {
    stamp: u64,
    c: f64,
    elimination: Option<VaryingRows>,
}

impl Factor {
    /// Refactorises for step size `h` in this factorisation's memory (its inverse, made from
    /// the old factors, is dropped); false if W is singular.
    fn refactor(&mut self, part: &Arc<Partition>, jac: &DMatrix<f64>, h: f64) -> bool {
        self.h = h;
        self.inverse.clear();
        self.by_rows = false;
        factor_into(&mut self.lu, part, jac, h)
    }

    /// Solves W x = rhs in place.
    pub(super) fn solve(&self, rhs: &mut [f64], scratch: &mut [f64]) {
        let rows = self.rows.as_ref().and_then(|k| k.elimination.as_ref());
        if let (true, Some(rows)) = (self.by_rows, rows) {
            rows.solve(rhs, scratch);
        } else if self.inverse.is_built() {
            self.inverse.solve(rhs, scratch);
        } else {
            self.lu.solve(rhs, scratch);
        }
    }
}

/// Factorises W = I/(h γ) - J into `lu` (reusing its memory) with the partition `part` of J;
/// false if W is singular.
fn factor_into(
    lu: &mut Factorisation<f64>,
    part: &Arc<Partition>,
    jac: &DMatrix<f64>,
    h: f64,
) -> bool {
    let c = 1.0 / (h * GAMMA);
    factor_with_fallback(lu, part, Shifted { c, jac })
}

/// A factorisation of W for step size `h` (in the memory of `old` if given); None if W is
/// singular.
fn factor(
    jac: &DMatrix<f64>,
    part: &Arc<Partition>,
    h: f64,
    old: Option<Factor>,
) -> Option<Factor> {
    let mut f = old.unwrap_or_else(|| Factor {
        h,
        lu: Factorisation::new(Arc::clone(part)),
        inverse: DenseInverse::default(),
        rows: None,
        by_rows: false,
    });
    f.refactor(part, jac, h).then_some(f)
}

/// W = I/(h γ) - J for the step size `h`, at the front of `lus`, with the J that `w.jac` (or,
/// for a constant Jacobian `stamp`, the method's cache) holds: for a constant J a kept
/// factorisation if one was made for this step size (to within `SAME_STEP`) or, if `shorten`,
/// for a step up to `SHORTER` times shorter, else a new one; for a J that changes from step to
/// step a new one in the memory of the last (with `by_rows`, the fixed-step driver's, by its
/// varying rows where that applies: [`factorise_by_rows`]). Returns the step size to take (that of the
/// factorisation) and false if W is singular.
#[allow(clippy::too_many_arguments)]
pub(super) fn factorise<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    lus: &mut Vec<Factor>,
    stamp: Option<u64>,
    h: f64,
    shorten: bool,
    by_rows: bool,
) -> (f64, bool) {
    match stamp {
        Some(_) => {
            let h_lu = integ
                .state
                .counted
                .factorisation_step(h, &mut integ.stats, 1, shorten);
            let jac = &integ.state.cache.jac;
            let pattern = &mut w.pattern;
            let ok = front_factorisation(
                lus,
                h_lu,
                |f| f.h,
                |old| {
                    let mut f = factor(jac, pattern.partition(jac, stamp), h_lu, old)?;
                    let n = jac.nrows();
                    if n <= step_map::MAX_DIM {
                        f.inverse.build(&f.lu, n, &mut w.scratch);
                    }
                    Some(f)
                },
            );
            (h_lu, ok)
        }
        None => {
            integ.stats.lu_decompositions += 1;
            if lus.is_empty() {
                lus.extend(w.spare.take());
            }
            lus.truncate(1);
            if by_rows {
                if let Some(done) = factorise_by_rows(integ, sys, w, lus, h) {
                    return done;
                }
            }
            let part = w.pattern.partition_within(&w.jac, sys.jacobian_pattern());
            let ok = match lus.first_mut() {
                Some(f) => f.refactor(part, &w.jac, h),
                None => {
                    lus.extend(factor(&w.jac, part, h, None));
                    !lus.is_empty()
                }
            };
            (h, ok)
        }
    }
}

/// For the fixed-step driver, W = I/(h γ) − J for a J that varies in at most half its rows,
/// at the front of `lus`, by the elimination of J's constant rows kept across steps
/// ([`VaryingRows`]): per step only the varying rows' Schur complement is factorised. The step
/// size is a kept one within `SAME_STEP` of `h` (the integrator's saved list, so that a
/// restored integrator rebuilds the same elimination, bit for bit). Returns the step size and
/// false if W is singular, or None where this does not apply (no constant part held in
/// `w.jac`, no varying pattern, too many varying rows, more than `step_map::MAX_DIM` states,
/// or a singular constant block): the general LU then factorises.
fn factorise_by_rows<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    w: &mut Work,
    lus: &mut Vec<Factor>,
    h: f64,
) -> Option<(f64, bool)> {
    let stamp = sys.jacobian_constant_part()?;
    let varying = sys.jacobian_varying_pattern()?;
    let n = w.jac.nrows();
    let r = varying.iter().filter(|v| !v.is_empty()).count();
    if w.jac_holds != Some(stamp) || n > step_map::MAX_DIM || 2 * r > n {
        return None;
    }
    let h_lu = integ
        .state
        .counted
        .factorisation_step(h, &mut integ.stats, 0, false);
    let c = 1.0 / (h_lu * GAMMA);
    if lus.is_empty() {
        lus.push(Factor {
            h: h_lu,
            lu: Factorisation::new(Arc::new(Partition::dense(n))),
            inverse: DenseInverse::default(),
            rows: None,
            by_rows: false,
        });
    }
    let f = &mut lus[0];
    if !f
        .rows
        .as_ref()
        .is_some_and(|k| k.stamp == stamp && k.c == c)
    {
        f.rows = Some(KeptRows {
            stamp,
            c,
            elimination: VaryingRows::new(&w.jac, c, varying, sys.jacobian_pattern()),
        });
    }
    let elimination = f.rows.as_mut()?.elimination.as_mut()?;
    let ok = elimination.factor(&w.jac);
    f.h = h_lu;
    f.inverse.clear();
    f.by_rows = true;
    Some((h_lu, ok))
}
