//! The simplified Newton iteration for the stage increments (RADCOR's Newton loop): its start
//! values, the iteration with its convergence monitor, and its linear solves (RADAU5's SLVRAD).

use nalgebra::Complex;

use super::coefficients::{inverse_eigenvalues, nodes, T, TI};
use super::decomposition::Lu;
use super::state::State;
use super::tolerances::Tolerances;
use super::workspace::Work;
use super::{Radau5Options, Why};
use crate::solver::common::{all_finite, eval};
use crate::solver::method::Stepper;
use crate::solver::OdeSystem;

/// Starting values of the simplified Newton iteration (RADCOR, "starting values for Newton
/// iteration"; Hairer & Wanner IV.8, "starting values"): Z_i⁰ = q(c_i h), the previous step's collocation
/// polynomial q extrapolated, and W⁰ = T⁻¹ Z⁰; zero on the first step or when there is no
/// polynomial.
pub(super) fn start_values(integ: &Stepper<State>, work: &mut Work, h: f64) {
    let n = integ.x.len();
    let Work {
        z: [z1, z2, z3],
        w: [w1, w2, w3],
        ..
    } = work;
    if integ.state.hist.first
        || integ.state.hist.cont.len() != 3 * n
        || integ.state.hist.h_old <= 0.0
    {
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
    let c3q = h / integ.state.hist.h_old;
    let (c1q, c2q) = (c1 * c3q, c2 * c3q);
    let cont = &integ.state.hist.cont;
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
pub(super) struct Newton {
    /// Iterations used.
    pub(super) iterations: usize,
    /// Last contraction estimate θ (J is kept while θ ≤ THET).
    pub(super) theta: f64,
}

/// The simplified Newton iteration for the stage increments (RADCOR, "loop for the simplified
/// Newton iteration"; Hairer & Wanner IV.8, "simplified Newton iterations", in the transformed
/// form of eq. 8.16ff), with the convergence monitor of the "stopping criterion": contraction θ_k = ‖ΔW^k‖/‖ΔW^{k-1}‖, stop when
/// η_k ‖ΔW^k‖ ≤ κ Tol, η_k = θ_k/(1 - θ_k); give up early (with a factor for h) when the
/// predicted error after NIT iterations is too large. Leaves Z and W in `work`.
pub(super) fn newton<S: OdeSystem + ?Sized>(
    integ: &mut Stepper<State>,
    sys: &S,
    work: &mut Work,
    lu: &Lu,
    tol: &Tolerances,
    opts: &Radau5Options,
    h: f64,
) -> Result<Newton, (Why, f64)> {
    let n = integ.x.len();
    let t = integ.t;
    let (c1, c2) = nodes();
    let (u1, alph, beta) = inverse_eigenvalues();
    let fac1 = u1 / h;
    let (alphn, betan) = (alph / h, beta / h);
    integ.state.hist.faccon = crate::math::powf(
        integ.state.hist.faccon.max(f64::EPSILON),
        opts.faccon_exponent,
    );
    let mut theta = opts.thet;
    let mut newt = 0;
    let nit = opts.nit;
    let mut dynold = 0.0;
    let mut thqold = 0.0;
    loop {
        if newt >= nit {
            return Err((Why::Newton, opts.unexpected_reject));
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
            return Err((Why::NonFinite, opts.unexpected_reject));
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
            return Err((Why::NonFinite, opts.unexpected_reject));
        }
        // Convergence monitor: contraction θ and predicted remaining error.
        if newt > 1 && newt < nit {
            let thq = dyno / dynold;
            theta = if newt == 2 {
                thq
            } else {
                (thq * thqold).sqrt()
            };
            thqold = thq;
            if theta < opts.theta_diverge {
                integ.state.hist.faccon = theta / (1.0 - theta);
                let dyth = integ.state.hist.faccon * dyno * theta.powi((nit - 1 - newt) as i32)
                    / tol.fnewt;
                if dyth >= 1.0 {
                    // Would not converge within NIT iterations: smaller step.
                    let qnewt = dyth.clamp(opts.qnewt_min, opts.qnewt_max);
                    let hhfac = opts.hhfac_safety
                        * crate::math::powf(qnewt, -1.0 / (4.0 + (nit - 1 - newt) as f64));
                    return Err((Why::Newton, hhfac));
                }
            } else {
                return Err((Why::Newton, opts.unexpected_reject));
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
        if integ.state.hist.faccon * dyno <= tol.fnewt {
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
