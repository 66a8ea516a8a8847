//! The local error estimate (RADAU5's ESTRAD).

use nalgebra::DVector;

use super::coefficients::error_weights;
use super::decomposition::Lu;
use super::state::State;
use super::workspace::Work;
use super::{Radau5Options, Why};
use crate::solver::common::{all_finite, eval};
use crate::solver::method::Stepper;
use crate::solver::OdeSystem;

/// The local error estimate (RADAU5's ESTRAD; Hairer & Wanner IV.8, eqs. 8.19–8.20):
/// err = ((γ/h) I - J)⁻¹ (f(y0) + (e1 Z1 + e2 Z2 + e3 Z3)/h) in the weighted RMS norm, the
/// filter suppressing the stiff components. On the first step or after a rejection an estimate
/// ≥ 1 is refined once with f(y0 + err) in place of f(y0), as ESTRAD does.
pub(super) fn estrad<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    work: &mut Work,
    lu: &Lu,
    h: f64,
    opts: &Radau5Options,
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
        (s / n as f64).sqrt().max(opts.err_floor)
    };
    let mut err = norm(rr);
    if err >= 1.0 && (integ.state.hist.first || integ.state.hist.last_rejected) {
        // Refined estimate with one more f evaluation (stiff components).
        for i in 0..n {
            ytmp[i] = integ.x[i] + rr[i];
        }
        eval(sys, &mut integ.stats, integ.t, ytmp, a1);
        if !all_finite(a1) {
            return Err((Why::NonFinite, opts.unexpected_reject));
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
        Err((Why::NonFinite, opts.unexpected_reject))
    }
}
