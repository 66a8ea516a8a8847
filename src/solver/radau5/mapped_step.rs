//! Steps as affine maps (see the module documentation of [`super`]): when the step map of a
//! factorisation is built, a step taken by it, and the responses it is built from.

use nalgebra::Complex;

use super::coefficients::{error_weights, T, TI};
use super::decomposition::Lu;
use super::state::State;
use super::workspace::Work;
use super::Radau5Options;
use crate::solver::linalg::Factorisation;
use crate::solver::method::Stepper;

/// Steps taken with one factorisation before its step map is built, ⌈n /
/// [`map_after_divisor`](Radau5Options::map_after_divisor)⌉ (n/2 by default): building costs
/// n + 1 [`map_response`]s of three solves each, about as much as n/2 ordinary steps (see the
/// option for why that many).
pub(super) fn map_after(n: usize, opts: &Radau5Options) -> u32 {
    u32::try_from(n.div_ceil(opts.map_after_divisor)).unwrap_or(u32::MAX)
}

/// A step of size `lu.h` from the integrator's state by the factorisation's step map (built or
/// refitted to the offsets `work.c0` first if need be): the end point into `work.x1`, and the
/// error estimate's norm returned (ESTRAD's, before any refinement). Stands for the simplified
/// Newton iteration converged in one iteration (it has the exact J of an affine f), so the
/// convergence-rate memory ages as in [`newton`](super::newton::newton).
pub(super) fn mapped_step(
    integ: &mut Stepper<State>,
    work: &mut Work,
    lu: &mut Lu,
    opts: &Radau5Options,
) -> f64 {
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
        lu.map.build(2 * n, &integ.state.cache.jac, c0, response);
    } else if !lu.map.fits(c0) {
        lu.map.refit(c0, response);
    }
    integ.state.hist.faccon = crate::math::powf(
        integ.state.hist.faccon.max(f64::EPSILON),
        opts.faccon_exponent,
    );
    lu.map.apply(&integ.x, &mut work.mapped);
    let (z3, e) = work.mapped.split_at(n);
    let mut sum = 0.0;
    for i in 0..n {
        work.x1[i] = integ.x[i] + z3[i];
        sum += (e[i] * work.inv_scal[i]).powi(2);
    }
    (sum / n as f64).sqrt().max(opts.err_floor)
}

/// What a step of size `h` computes when f ≡ v at the three stages and at its start, without
/// the start state: Z3 into `out[..n]` and the vector of the error estimate (ESTRAD's, before
/// its norm) into `out[n..]`. That is one simplified Newton iteration from Z = 0 ([`slvrad`](super::newton::slvrad)
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
