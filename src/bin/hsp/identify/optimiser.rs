//! A Levenberg–Marquardt least-squares solver (Moré, "The Levenberg-Marquardt algorithm:
//! implementation and theory", 1978, with Nielsen's damping update, 1999), short and
//! unconstrained: the fit's box bounds are a change of variables (the logistic map of
//! [`super::data::Fitted::z_of_t`]), so the solver sees none.
//!
//! Why not a crate: `levenberg-marquardt` 0.15 (rust-cv, the well-kept one on crates.io) is
//! built on nalgebra 0.34, which would put a second nalgebra beside the project's 0.35 into the
//! tool, and has no bounds either.
//!
//! Each iteration solves `(J^T J + mu D) dt = -J^T r` with `D` the largest diagonal of `J^T J`
//! seen so far (Moré's scaling, invariant to the parameters' units), tries `t + dt`, and accepts
//! it if the cost `|r|^2` falls. The gain ratio `rho` = actual / predicted decrease sets the
//! damping: accepted, `mu *= max(1/3, 1 - (2 rho - 1)^3)`; refused, `mu *= nu`, `nu *= 2`. A
//! trial point where the model fails (a parameter it refuses) counts as refused.

use nalgebra::{DMatrix, DVector};

/// A least-squares problem in unconstrained coordinates `t`.
pub trait LeastSquares {
    /// The residuals at `t`.
    fn residuals(&self, t: &[f64]) -> Result<DVector<f64>, String>;
    /// Their Jacobian at `t`, a column per coordinate.
    fn jacobian(&self, t: &[f64]) -> Result<DMatrix<f64>, String>;
}

/// When to stop.
#[derive(Clone, Copy, Debug)]
pub struct Tolerances {
    /// An accepted step that lowers the cost by less than this fraction of it.
    pub f_rel: f64,
    /// A step shorter than this times `|t| + f_rel`.
    pub t_rel: f64,
    /// The gradient's largest entry, relative to the cost, below this.
    pub gradient: f64,
    /// At most this many iterations (steps tried).
    pub iterations: usize,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            f_rel: 1e-10,
            t_rel: 1e-9,
            gradient: 1e-12,
            iterations: 200,
        }
    }
}

/// Why the solver stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    Cost,
    Step,
    Gradient,
    /// The iteration limit: not converged.
    Iterations,
}

/// The solver's result.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub t: Vec<f64>,
    /// `|r|^2` at `t`.
    pub cost: f64,
    /// Steps tried (accepted or not).
    pub iterations: usize,
    pub stop: Stop,
}

/// Minimises `|r(t)|^2` from `t0`.
pub fn levenberg_marquardt(
    problem: &impl LeastSquares,
    t0: &[f64],
    tol: Tolerances,
) -> Result<Outcome, String> {
    let k = t0.len();
    let mut t = DVector::from_column_slice(t0);
    let mut r = problem.residuals(t.as_slice())?;
    let mut cost = r.norm_squared();
    let mut jac = problem.jacobian(t.as_slice())?;
    let mut d = DVector::<f64>::zeros(k);
    let mut mu = f64::NAN;
    let mut nu = 2.0;
    let mut iterations = 0;
    let stop = loop {
        let a = jac.tr_mul(&jac);
        let g = jac.tr_mul(&r);
        for i in 0..k {
            d[i] = d[i].max(a[(i, i)]);
        }
        if mu.is_nan() {
            mu = 1e-3;
        }
        if g.amax() <= tol.gradient * cost.max(f64::MIN_POSITIVE) {
            break Stop::Gradient;
        }
        if iterations >= tol.iterations {
            break Stop::Iterations;
        }
        iterations += 1;
        // A floor for the scaling of a coordinate the data do not see (a zero column).
        let floor = 1e-12 * d.max().max(f64::MIN_POSITIVE);
        let mut m = a.clone();
        for i in 0..k {
            m[(i, i)] += mu * d[i].max(floor);
        }
        let Some(step) = m.cholesky().map(|c| c.solve(&(-&g))) else {
            mu *= nu;
            nu *= 2.0;
            continue;
        };
        if step.norm() <= tol.t_rel * (t.norm() + tol.t_rel) {
            break Stop::Step;
        }
        let trial = &t + &step;
        let predicted = cost - (&r + &jac * &step).norm_squared();
        let accepted = match problem.residuals(trial.as_slice()) {
            Ok(r_new) => {
                let c_new = r_new.norm_squared();
                let rho = (cost - c_new) / predicted;
                if c_new < cost && rho > 0.0 {
                    let decrease = cost - c_new;
                    t = trial;
                    r = r_new;
                    cost = c_new;
                    mu *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                    nu = 2.0;
                    if decrease <= tol.f_rel * cost {
                        break Stop::Cost;
                    }
                    true
                } else {
                    false
                }
            }
            Err(_) => false,
        };
        if accepted {
            jac = problem.jacobian(t.as_slice())?;
        } else {
            mu *= nu;
            nu *= 2.0;
        }
    };
    Ok(Outcome {
        t: t.as_slice().to_vec(),
        cost,
        iterations,
        stop,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock's function as least squares, `r = (10 (t2 - t1^2), 1 - t1)`: its minimum 0 at
    /// (1, 1), reached from the classic start (-1.2, 1) along the curved valley.
    struct Rosenbrock;
    impl LeastSquares for Rosenbrock {
        fn residuals(&self, t: &[f64]) -> Result<DVector<f64>, String> {
            Ok(DVector::from_vec(vec![
                10.0 * (t[1] - t[0] * t[0]),
                1.0 - t[0],
            ]))
        }
        fn jacobian(&self, t: &[f64]) -> Result<DMatrix<f64>, String> {
            Ok(DMatrix::from_row_slice(
                2,
                2,
                &[-20.0 * t[0], 10.0, -1.0, 0.0],
            ))
        }
    }

    #[test]
    fn levenberg_marquardt_finds_rosenbrocks_minimum() {
        let out = levenberg_marquardt(&Rosenbrock, &[-1.2, 1.0], Tolerances::default()).unwrap();
        assert_ne!(out.stop, Stop::Iterations, "{out:?}");
        assert!(
            (out.t[0] - 1.0).abs() < 1e-8 && (out.t[1] - 1.0).abs() < 1e-8,
            "{out:?}"
        );
        assert!(out.cost < 1e-20, "{out:?}");
    }

    /// An exponential decay `y = a e^(-b x)` fitted to exact data: the least-squares answer is
    /// the generating (a, b) = (2, 0.7); a trial point whose model fails is refused, not fatal.
    struct Decay;
    impl LeastSquares for Decay {
        fn residuals(&self, t: &[f64]) -> Result<DVector<f64>, String> {
            if t[1] < -1.0 {
                return Err("b below -1".into());
            }
            Ok(DVector::from_fn(20, |i, _| {
                let x = i as f64 * 0.25;
                t[0] * (-t[1] * x).exp() - 2.0 * (-0.7 * x).exp()
            }))
        }
        fn jacobian(&self, t: &[f64]) -> Result<DMatrix<f64>, String> {
            Ok(DMatrix::from_fn(20, 2, |i, j| {
                let x = i as f64 * 0.25;
                let e = (-t[1] * x).exp();
                if j == 0 {
                    e
                } else {
                    -t[0] * x * e
                }
            }))
        }
    }

    #[test]
    fn levenberg_marquardt_fits_an_exponential_decay() {
        let out = levenberg_marquardt(&Decay, &[1.0, 0.1], Tolerances::default()).unwrap();
        assert!(
            (out.t[0] - 2.0).abs() < 1e-8 && (out.t[1] - 0.7).abs() < 1e-8,
            "{out:?}"
        );
    }
}
