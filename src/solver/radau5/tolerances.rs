//! The tolerances the step control works with (RADAU5's prologue) and the error weights of the
//! weighted RMS norm (RADCOR's SCAL).

use super::state::State;
use super::workspace::Work;
use super::Radau5Options;
use crate::solver::method::Stepper;
use crate::solver::Atol;

/// The tolerances the step control works with (RADAU5's prologue and RADCOR's FNEWT).
#[derive(Clone, Copy)]
pub(super) struct Tolerances {
    /// Transformed relative tolerance rtol' = 0.1 rtol^(2/3).
    pub(super) rtol: f64,
    /// Newton stopping criterion κ·Tol (RADAU5 FNEWT default; Hairer & Wanner IV.8, "stopping
    /// criterion" of the simplified Newton iteration).
    pub(super) fnewt: f64,
}

/// RADAU5's tolerance transformation: rtol' = 0.1 rtol^(2/3) for the relative part (the local
/// error estimate is O(h⁴), the method of order 5); the absolute part `work.atol` is the user's,
/// scaled down with rtol'/rtol but never up (see the module docs for why this departs from
/// RADAU5's atol' = rtol' atol/rtol).
pub(super) fn transformed_tolerances(
    integ: &Stepper<State>,
    work: &mut Work,
    opts: &Radau5Options,
) -> Tolerances {
    if let Some(tol) = work.tolerances {
        return tol;
    }
    let rtol_user = integ.options.rtol;
    let rtol = 0.1 * crate::math::powf(rtol_user, 2.0 / 3.0);
    let atol_factor = (rtol / rtol_user).min(1.0);
    for (i, a) in work.atol.iter_mut().enumerate() {
        *a = atol_factor * integ.options.atol.get(i);
    }
    if let Atol::Vector(v) = &mut work.atol_for_fd {
        v.copy_from_slice(&work.atol);
    }
    let fnewt = (10.0 * f64::EPSILON / rtol).max(opts.fnewt_cap.min(rtol.sqrt()));
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
pub(super) fn set_scal(atol: &[f64], rtol: f64, x: &[f64], inv_scal: &mut [f64]) {
    for i in 0..inv_scal.len() {
        inv_scal[i] = 1.0 / (atol[i] + rtol * x[i].abs()).max(f64::MIN_POSITIVE);
    }
}
