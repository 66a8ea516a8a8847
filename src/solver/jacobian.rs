//! Jacobian evaluation: the model's analytic Jacobian if it has one, else forward differences.

// Index loops over stages and components mirror the formulas they implement.
#![allow(clippy::needless_range_loop)]

use nalgebra::DMatrix;

use super::common::{all_finite, eval};
use super::{OdeSystem, Stats};

/// Forward-difference increment for component j: sqrt(eps) times the component's scale,
/// where the scale is max(|x_j|, floor_j) (the floor is atol_j / rtol inside the solver: a
/// component is "significant" from that size on) and at least 1e-8. The increment is then
/// made exactly representable, (x_j + d) - x_j, so the divided difference has no
/// representation error in the denominator (Dennis & Schnabel, Sec. 5.4).
fn increment(xj: f64, floor: f64) -> f64 {
    let d = f64::EPSILON.sqrt() * xj.abs().max(floor).max(1e-8);
    let xp = xj + d;
    xp - xj
}

/// Forward-difference Jacobian of `sys` at (t, x), given f0 = f(t, x); `floor[j]` is the
/// lower bound of the scale of component j (see [`increment`]). Returns the number of f
/// evaluations used (= dim).
pub(crate) fn fd_jacobian_with<S: OdeSystem + ?Sized>(
    sys: &S,
    t: f64,
    x: &[f64],
    f0: &[f64],
    floor: &dyn Fn(usize) -> f64,
    jac: &mut DMatrix<f64>,
) -> u64 {
    let n = x.len();
    let mut xp = x.to_vec();
    let mut f1 = vec![0.0; n];
    for j in 0..n {
        let d = increment(x[j], floor(j));
        xp[j] = x[j] + d;
        sys.rhs(t, &xp, &mut f1);
        for i in 0..n {
            jac[(i, j)] = (f1[i] - f0[i]) / d;
        }
        xp[j] = x[j];
    }
    n as u64
}

/// Central-difference Jacobian, meant for *checking* a model's analytic Jacobian (the solver
/// itself uses forward differences with increment sqrt(eps) · max(|x_j|, atol_j/rtol)).
/// Increment ε^(1/3) · max(|x_j|, 1e-3), made exactly representable; truncation error O(δ²)
/// (exact for quadratic f), rounding error O(ε |f| / δ). Costs 2 dim evaluations of f.
pub fn finite_difference_jacobian<S: OdeSystem + ?Sized>(
    sys: &S,
    t: f64,
    x: &[f64],
) -> DMatrix<f64> {
    let n = sys.dim();
    let mut jac = DMatrix::zeros(n, n);
    let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    for j in 0..n {
        let d0 = crate::math::cbrt(f64::EPSILON) * x[j].abs().max(1e-3);
        xp[j] = x[j] + d0;
        xm[j] = x[j] - d0;
        let d = xp[j] - xm[j];
        sys.rhs(t, &xp, &mut fp);
        sys.rhs(t, &xm, &mut fm);
        for i in 0..n {
            jac[(i, j)] = (fp[i] - fm[i]) / d;
        }
        xp[j] = x[j];
        xm[j] = x[j];
    }
    jac
}

/// Solver-internal Jacobian: analytic if the model provides one, else forward differences
/// with floors atol_j / rtol. Counts the evaluation. Returns false if the result is not finite.
#[allow(clippy::too_many_arguments)]
pub(crate) fn evaluate<S: OdeSystem + ?Sized>(
    sys: &S,
    stats: &mut Stats,
    t: f64,
    x: &[f64],
    f0: &[f64],
    atol: &super::Atol,
    rtol: f64,
    jac: &mut DMatrix<f64>,
    holds: &mut Option<u64>,
) -> bool {
    stats.jac_evals += 1;
    let n = x.len();
    let part = sys.jacobian_constant_part();
    if part.is_some() && *holds == part && jac.shape() == (n, n) {
        // `jac` holds a J of this system under the same constant part: only the rest varies.
        return sys.jacobian_varying(t, x, jac);
    }
    *holds = None;
    if jac.nrows() != n || jac.ncols() != n {
        *jac = DMatrix::zeros(n, n);
    }
    let analytic = sys.jacobian(t, x, jac);
    if !analytic {
        stats.f_evals += fd_jacobian_with(sys, t, x, f0, &|j| atol.get(j) / rtol, jac);
    }
    let finite = all_finite(jac.as_slice());
    if analytic && finite {
        *holds = part;
    }
    finite
}

/// df/dt at (t, x) for non-autonomous systems: the model's, else a forward difference with
/// increment sqrt(eps) * max(|t|, 1e-5). Returns false if not finite.
pub(crate) fn time_derivative<S: OdeSystem + ?Sized>(
    sys: &S,
    stats: &mut Stats,
    t: f64,
    x: &[f64],
    f0: &[f64],
    dfdt: &mut [f64],
) -> bool {
    if sys.time_derivative(t, x, dfdt) {
        return all_finite(dfdt);
    }
    let d = {
        let d = f64::EPSILON.sqrt() * t.abs().max(1e-5);
        (t + d) - t
    };
    let mut f1 = vec![0.0; x.len()];
    eval(sys, stats, t + d, x, &mut f1);
    for i in 0..x.len() {
        dfdt[i] = (f1[i] - f0[i]) / d;
    }
    all_finite(dfdt)
}
