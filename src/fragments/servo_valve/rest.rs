//! The rest state of the full servo valve: every pressure at its null value.

use std::sync::Arc;

use nalgebra::{DMatrix, DVector};

use crate::bond_graph::CompiledModel;
use crate::solver::linalg::{Factorisation, Partition};

use super::ServoValveParameters;

/// The rest state of a model containing the actuator under `prefix`: every pressure state at its
/// null value, found by Newton's method on `f(x, u) = 0` from the guess "control and actuator
/// chambers at `(p_s + p_t)/2`, everything else zero", in variables scaled by `scale` (each
/// state's nominal magnitude).
///
/// The equilibrium need not be isolated: where the Jacobian is singular (the open loop's free
/// rotor angle; with the hub locked, the rotor angle and the bar twist, which integrate the
/// same speed) each Newton step is the least-norm one (SVD), which leaves the free directions
/// at their guess, 0. A state whose rate depends on no state (the command generator's clock)
/// has no rest value: it stays at its guess too.
///
/// Each step is first solved by the solver's LU with partial pivoting ([`Factorisation`]) on
/// the states whose rate depends on some state, the others' steps 0, and a free angle's step 0
/// (see `lu_step`): for a model of hundreds of states (816 with a 20 × 20 plate) tens of
/// milliseconds where the SVD of its Jacobian takes seconds. Where a pivot is small in the
/// equilibrated matrix (a Jacobian singular otherwise, as with the hub locked) or the step does
/// not solve the system to a backward error of 1e-9, the step is the least-norm one by SVD.
pub fn rest_state(
    model: &CompiledModel,
    u: &[f64],
    prefix: &str,
    p: &ServoValveParameters,
    scale: &[f64],
) -> Result<Vec<f64>, String> {
    newton(model, u, prefix, p, scale, true)
}

/// [`rest_state`] with every step the least-norm one by SVD: the reference its LU steps are
/// tested against.
#[doc(hidden)]
pub fn rest_state_least_norm(
    model: &CompiledModel,
    u: &[f64],
    prefix: &str,
    p: &ServoValveParameters,
    scale: &[f64],
) -> Result<Vec<f64>, String> {
    newton(model, u, prefix, p, scale, false)
}

fn newton(
    model: &CompiledModel,
    u: &[f64],
    prefix: &str,
    p: &ServoValveParameters,
    scale: &[f64],
    by_lu: bool,
) -> Result<Vec<f64>, String> {
    let n = model.n_states();
    let names = model.state_names();
    let mid = 0.5 * (p.p_supply + p.p_tank);
    let mut x = vec![0.0; n];
    for (i, name) in names.iter().enumerate() {
        let local = name.strip_prefix(prefix).and_then(|s| s.strip_prefix('.'));
        match local {
            Some("C_Ha.q") | Some("C_Hb.q") => x[i] = p.v_h / p.beta * mid,
            Some("C_1.q") | Some("C_2.q") => x[i] = p.v_1 / p.beta * mid,
            _ => {}
        }
    }
    let mut f = vec![0.0; n];
    let mut jac = DMatrix::zeros(n, n);
    for _ in 0..50 {
        model.derivatives(&x, u, &mut f);
        model.jacobian(&x, u, &mut jac);
        let dz = newton_step(&jac, &f, scale, by_lu)?;
        let mut step = 0.0f64;
        for i in 0..n {
            x[i] += scale[i] * dz[i];
            step = step.max(dz[i].abs());
        }
        if step < 1e-13 {
            return Ok(x);
        }
    }
    Err("servo valve rest state: Newton's method did not converge".into())
}

/// The derivative of the rest state `x0` ([`rest_state`]) along a parameter whose partial
/// derivative of the rates at `x0` is `f_p` (`∂f/∂p`): differentiating `f(x0(p), p) = 0` on the
/// equations the rest state solves, `J dx0/dp = -∂f/∂p`, solved as a Newton step is (the same
/// rows void, the same free directions held: their derivative 0). Exact: the step is the
/// implicit function's derivative. `scale` as [`rest_state`]'s.
pub fn rest_state_derivative(
    model: &CompiledModel,
    x0: &[f64],
    u: &[f64],
    f_p: &[f64],
    scale: &[f64],
) -> Result<Vec<f64>, String> {
    let n = model.n_states();
    let mut jac = DMatrix::zeros(n, n);
    model.jacobian(x0, u, &mut jac);
    let dz = newton_step(&jac, f_p, scale, true)?;
    Ok((0..n).map(|i| scale[i] * dz[i]).collect())
}

/// The Newton step `dz` (in the scaled variables `x = S z`) for the rates `f` with the Jacobian
/// `jac` (see [`rest_state`]): a rate whose row of `jac` is zero (a clock) is left out, and the
/// step is the LU one where it applies (`by_lu`), the least-norm one by SVD elsewhere.
fn newton_step(
    jac: &DMatrix<f64>,
    f: &[f64],
    scale: &[f64],
    by_lu: bool,
) -> Result<DVector<f64>, String> {
    let n = f.len();
    // A state whose rate depends on no state (a clock) has no rest: it stays at its guess.
    let f: Vec<f64> = (0..n)
        .map(|i| {
            if jac.row(i).iter().all(|&v| v == 0.0) {
                0.0
            } else {
                f[i]
            }
        })
        .collect();
    // Solve in scaled variables x = S z: (S^-1 J S) dz = -S^-1 f, a matrix of rates (1/s).
    let js = DMatrix::from_fn(n, n, |i, j| jac[(i, j)] * scale[j] / scale[i]);
    let rhs = DVector::from_iterator(n, (0..n).map(|i| -f[i] / scale[i]));
    match by_lu.then(|| lu_step(&js, &rhs)).flatten() {
        Some(dz) => Ok(dz),
        None => {
            let svd = js.svd(true, true);
            let eps = 1e-13 * svd.singular_values.max();
            svd.solve(&rhs, eps)
                .map_err(|e| format!("servo valve rest state: {e}"))
        }
    }
}

/// The Newton step `js dz = rhs` by LU with partial pivoting, if it applies (see
/// [`rest_state`]): on the states whose row of `js` is not zero (the others' steps 0, as the
/// least-norm step gives them: their equations are void), with the row of a state whose
/// column is zero (a free angle, which no rate reads) replaced by `dz_j = 0`, the least-norm
/// step's value there. Its own equation (the angle's rate, a speed, zero) is left to the other
/// equations, which bring every speed to rest: the rest state is the least-norm iteration's
/// (test `the_lu_rest_state_is_the_least_norm_one`, on every preset), the path to it
/// differs. `None` where a pivot is small in the equilibrated matrix
/// ([`Factorisation::judging_pivots`]: a Jacobian singular otherwise, as with the hub locked,
/// where the rotor angle and the bar's twist integrate the same speed) or the step's residual
/// in the other rows is above 1e-9 of `‖js‖ ‖dz‖ + ‖rhs‖` (max norms over those rows: its
/// normwise backward error, near 1e-16 for an LU that went right).
fn lu_step(js: &DMatrix<f64>, rhs: &DVector<f64>) -> Option<DVector<f64>> {
    let n = js.nrows();
    let live: Vec<usize> = (0..n)
        .filter(|&i| js.row(i).iter().any(|&v| v != 0.0))
        .collect();
    let free: Vec<bool> = (0..n)
        .map(|j| js.column(j).iter().all(|&v| v == 0.0))
        .collect();
    let m = live.len();
    let entry = |i: usize, j: usize| {
        let (r, c) = (live[i], live[j]);
        match free[r] {
            true => f64::from(u8::from(r == c)),
            false => js[(r, c)],
        }
    };
    let part = Arc::new(Partition::dense(m));
    let mut lu = Factorisation::judging_pivots(Arc::clone(&part));
    if !lu.factor(&part, entry) {
        return None;
    }
    let mut x: Vec<f64> = live
        .iter()
        .map(|&i| if free[i] { 0.0 } else { rhs[i] })
        .collect();
    lu.solve(&mut x, &mut vec![0.0; m]);
    let mut dz = DVector::zeros(n);
    for (&i, &v) in live.iter().zip(&x) {
        dz[i] = v;
    }
    let residual = js * &dz - rhs;
    let kept = |v: &DVector<f64>| {
        (0..n)
            .filter(|&i| !free[i])
            .fold(0.0f64, |m, i| m.max(v[i].abs()))
    };
    let size = kept(&(js.abs() * DVector::repeat(n, dz.amax()))) + kept(rhs);
    let fine = kept(&residual) <= 1e-9 * size;
    (fine && dz.iter().all(|v| v.is_finite())).then_some(dz)
}
