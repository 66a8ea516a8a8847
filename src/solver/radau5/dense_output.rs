//! Dense output: the collocation polynomial of an accepted step (RADAU5's CONT) and its values
//! (CONTR5).

use super::coefficients::nodes;
use super::state::State;
use crate::solver::common::Outputs;
use crate::solver::method::Stepper;

/// The collocation polynomial of an accepted step (CONT(N+1..4N) of RADAU5) from its stage
/// increments, into the integrator's history, and the outputs due within the step from it.
pub(super) fn collocation_polynomial(
    integ: &mut Stepper<State>,
    (z1, z2, z3): (&[f64], &[f64], &[f64]),
    x1: &[f64],
    outputs: &mut Outputs,
    out: &mut dyn FnMut(f64, &[f64]),
    (t, h, t1): (f64, f64, f64),
) {
    let n = x1.len();
    let (c1, c2) = nodes();
    // CONTR5's divided differences, with the divisions by the constant node differences as
    // multiplications by their reciprocals (five divisions per state per step otherwise).
    let (c1m1, c2m1, c1mc2) = (c1 - 1.0, c2 - 1.0, c1 - c2);
    let (r_c1m1, r_c2m1, r_c1mc2, r_c1, r_c2) =
        (1.0 / c1m1, 1.0 / c2m1, 1.0 / c1mc2, 1.0 / c1, 1.0 / c2);
    let mut cont = std::mem::take(&mut integ.state.hist.cont);
    cont.resize(3 * n, 0.0);
    for i in 0..n {
        let k1 = (z2[i] - z3[i]) * r_c2m1;
        let ak = (z1[i] - z2[i]) * r_c1mc2;
        let acont3 = (ak - z1[i] * r_c1) * r_c2;
        let k2 = (ak - k1) * r_c1m1;
        cont[i] = k1;
        cont[n + i] = k2;
        cont[2 * n + i] = k2 - acont3;
    }
    if outputs.pending(t1) {
        outputs.emit(t, h, t1, x1, &mut |th, buf| dense(x1, &cont, th, buf), out);
    }
    integ.state.hist.cont = cont;
}

/// The collocation polynomial of a step at θ ∈ [0, 1] of it (RADAU5's CONTR5, with
/// s = θ - 1 measured back from the step's end), into `buf`, from the end state `x1` and the
/// polynomial's coefficients `cont` (3 n numbers).
fn dense(x1: &[f64], cont: &[f64], theta: f64, buf: &mut [f64]) {
    let n = x1.len();
    let (c1, c2) = nodes();
    let (c1m1, c2m1) = (c1 - 1.0, c2 - 1.0);
    let s = theta - 1.0;
    for i in 0..n {
        buf[i] = x1[i] + s * (cont[i] + (s - c2m1) * (cont[n + i] + (s - c1m1) * cont[2 * n + i]));
    }
}
