//! The rest state of the full servo valve: every pressure at its null value.

use nalgebra::{DMatrix, DVector};

use crate::bond_graph::CompiledModel;

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
pub fn rest_state(
    model: &CompiledModel,
    u: &[f64],
    prefix: &str,
    p: &ServoValveParameters,
    scale: &[f64],
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
        // A state whose rate depends on no state (a clock) has no rest: it stays at its guess.
        for (i, fi) in f.iter_mut().enumerate() {
            if jac.row(i).iter().all(|&v| v == 0.0) {
                *fi = 0.0;
            }
        }
        // Solve in scaled variables x = S z: (S^-1 J S) dz = -S^-1 f, a matrix of rates (1/s).
        let js = DMatrix::from_fn(n, n, |i, j| jac[(i, j)] * scale[j] / scale[i]);
        let rhs = DVector::from_iterator(n, (0..n).map(|i| -f[i] / scale[i]));
        let svd = js.svd(true, true);
        let eps = 1e-13 * svd.singular_values.max();
        let dz = svd
            .solve(&rhs, eps)
            .map_err(|e| format!("servo valve rest state: {e}"))?;
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
