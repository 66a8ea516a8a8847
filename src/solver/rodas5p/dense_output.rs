//! Rodas5P's dense output (Steinebach 2023, as tabulated in OrdinaryDiffEq.jl): with
//! K_r = Σ_j H_rj U_j (r = 1, 2, 3) and θ = (t − t0)/h,
//! y(θ) = (1 − θ) y0 + θ (y1 + (1 − θ) (K_1 + θ (K_2 + θ K_3))), of order 4: at output times
//! inside a step, and for a step kept past the reported point.

use super::{H, STAGES};

/// The dense output's three correction terms of component `i`: k_r = Σ_j H_rj U_j.
fn corrections(u: &[Vec<f64>], i: usize) -> [f64; 3] {
    let mut k = [0.0; 3];
    for (r, kr) in k.iter_mut().enumerate() {
        for j in 0..STAGES {
            *kr += H[r][j] * u[j][i];
        }
    }
    k
}

/// The order-4 continuous extension at θ ∈ [0, 1] of one component, from its values at the
/// step's ends and its corrections.
#[inline]
fn extension(y0: f64, y1: f64, k: [f64; 3], theta: f64) -> f64 {
    let t1 = 1.0 - theta;
    t1 * y0 + theta * (y1 + t1 * (k[0] + theta * (k[1] + theta * k[2])))
}

/// Evaluate the dense output at θ into `buf` from y0, y1 and the stage vectors.
pub(in crate::solver) fn interpolate(
    y0: &[f64],
    y1: &[f64],
    u: &[Vec<f64>],
    theta: f64,
    buf: &mut [f64],
) {
    for i in 0..y0.len() {
        buf[i] = extension(y0[i], y1[i], corrections(u, i), theta);
    }
}

/// The corrections of every component into `coef` (k_0 for all components, then k_1, then
/// k_2): the dense output of a step kept past the reported point.
pub(super) fn dense_coefficients(u: &[Vec<f64>], coef: &mut [f64]) {
    let n = u[0].len();
    for i in 0..n {
        let k = corrections(u, i);
        coef[i] = k[0];
        coef[n + i] = k[1];
        coef[2 * n + i] = k[2];
    }
}

/// The dense output at θ of a kept step (see [`dense_coefficients`]) into `buf`: the same
/// numbers as the output times of [`Integrator::advance_to_with_output`] get.
pub(crate) fn dense(y0: &[f64], y1: &[f64], coef: &[f64], theta: f64, buf: &mut [f64]) {
    let n = y0.len();
    for i in 0..n {
        let k = [coef[i], coef[n + i], coef[2 * n + i]];
        buf[i] = extension(y0[i], y1[i], k, theta);
    }
}
