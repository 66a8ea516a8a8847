//! The Jacobian kept across calls (see the module documentation of [`super`]): taken up at the
//! start of a call, kept (or dropped) at its end.

use super::decomposition::{factor, Lu};
use super::state::State;
use super::workspace::Work;
use crate::solver::method::Stepper;
use crate::solver::OdeSystem;

/// Takes up the Jacobian the last call kept (see
/// [`KeptJacobian`](super::state::KeptJacobian)): from the workspace if it
/// still holds it with its factorisations, else rebuilt from the saved entries, and its
/// factorisations made again for their saved step size, uncounted (they were counted when first
/// made, so a restored copy counts as the original does). False if there is none to take up (a
/// constant Jacobian, nothing kept, or entries that do not fit the system).
pub(super) fn resume_kept_jacobian<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    work: &mut Work,
    lus: &mut Vec<Lu>,
    stamp: Option<u64>,
) -> bool {
    let kept = &integ.state.kept_jac;
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
        integ.state.kept_jac.clear();
        return false;
    }
    if kept.lu_h > 0.0 {
        let part = work.pattern.partition_within(&work.jac, pattern);
        let Some(lu) = factor(&work.jac, part, kept.lu_h, work.spare.take()) else {
            integ.state.kept_jac.clear();
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
pub(super) fn keep_jacobian<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    work: &mut Work,
    lus: &[Lu],
    keep: bool,
    evaluated: bool,
) {
    if !keep {
        integ.state.kept_jac.clear();
        work.kept_synced = false;
        return;
    }
    if evaluated || integ.state.kept_jac.is_empty() {
        integ
            .state
            .kept_jac
            .store(&work.jac, sys.jacobian_pattern());
    }
    // The factorisation in use is the front one; `with_kept_memory` moves it into `spare`.
    integ.state.kept_jac.lu_h = lus.first().map_or(0.0, |lu| lu.h);
    work.kept_synced = true;
}
