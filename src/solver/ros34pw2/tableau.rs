//! The coefficients of ROS34PW2 (Rang & Angermann, BIT Numer. Math. 45 (2005) 761–787: the
//! classical form α, Γ, b, b̂), and their transformed form, which the step uses.
//!
//! The published classical form (as also tabulated in PETSc's `TSROSWRA34PW2` and in MATLODE's
//! `Coefficients_ROS34PW2.m`, the same digits): γ = 0.435866521508459,
//! α21 = 2γ, α31, α32, α43 = 1 (α41 = α42 = 0), the strictly lower γ_ij, b (= row 4 of α + Γ:
//! stiffly accurate) and b̂. The transformed form (Hairer & Wanner II, IV.7, eq. 7.4') was
//! computed from them in 40-digit arithmetic: a = α Γ⁻¹, C = diag(1/γ) − Γ⁻¹, mᵀ = bᵀ Γ⁻¹
//! (= row 4 of a plus e_4), m̂ᵀ = b̂ᵀ Γ⁻¹; `classical_form` inverts this and
//! `tests/solver_ros34pw2.rs` checks that it gives back the published numbers and that they meet
//! the order conditions of a W-method of order 3 (embedded order 2).

use nalgebra::{DMatrix, DVector};

/// Number of stages.
pub const STAGES: usize = 4;

/// Diagonal coefficient γ (Rang & Angermann: γ = 0.435866521508459, L-stable).
pub const GAMMA: f64 = 0.435866521508459;

/// a_ij of the transformed form (row i = stage i+1, columns j < i).
pub const A: [[f64; STAGES]; STAGES] = [
    [0.0; 4],
    [2.0, 0.0, 0.0, 0.0],
    [1.4192173174557647, -0.2592322116729697, 0.0, 0.0],
    [
        4.18476048231916,
        -0.28519201735549593,
        2.294280360279042,
        0.0,
    ],
];

/// C_ij of the transformed form (strictly lower triangular; C = diag(1/γ) − Γ⁻¹).
pub const C: [[f64; STAGES]; STAGES] = [
    [0.0; 4],
    [-4.588560720558084, 0.0, 0.0, 0.0],
    [-4.18476048231916, 0.28519201735549593, 0.0, 0.0],
    [
        -6.368179200128358,
        -6.795620944466836,
        2.870098604331056,
        0.0,
    ],
];

/// Weights m_j: y1 = y0 + Σ m_j U_j (stiffly accurate: row 4 of `A` plus e_4).
pub const M: [f64; STAGES] = [A[3][0], A[3][1], A[3][2], 1.0];

/// Weights m̂_j of the embedded order-2 solution ŷ1 = y0 + Σ m̂_j U_j.
pub const M_HAT: [f64; STAGES] = [
    3.907010534671192,
    1.1180478778205032,
    0.5216502326114907,
    0.5,
];

/// Weights of the error estimate y1 − ŷ1 = Σ (m_j − m̂_j) U_j.
pub const E: [f64; STAGES] = [
    M[0] - M_HAT[0],
    M[1] - M_HAT[1],
    M[2] - M_HAT[2],
    M[3] - M_HAT[3],
];

/// Stage times c_i = α_i = Σ_j α_ij.
pub const C_NODES: [f64; STAGES] = [0.0, 0.871733043016918, 0.7315799577888524, 1.0];

/// d_i = γ_i = Σ_j γ_ij, the coefficients of h ∂f/∂t. γ_4 is 0 by the method's design (the
/// last stage is the stiffly accurate one; the published 17 digits sum to −1e-16).
pub const D: [f64; STAGES] = [
    0.435866521508459,
    -0.435866521508459,
    -0.4133333762338865,
    0.0,
];

/// The classical form (α, Γ, b, b̂) computed from the transformed tableau: Γ = (diag(1/γ) −
/// C)⁻¹, α = a Γ, bᵀ = mᵀ Γ, b̂ᵀ = m̂ᵀ Γ. For the order-condition tests.
pub fn classical_form() -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>, DVector<f64>) {
    let s = STAGES;
    let ginv = DMatrix::from_fn(s, s, |i, j| if i == j { 1.0 / GAMMA } else { -C[i][j] });
    let gam = ginv.try_inverse().unwrap_or_else(|| DMatrix::zeros(s, s));
    let a = DMatrix::from_fn(s, s, |i, j| A[i][j]);
    let alpha = &a * &gam;
    let weights = |w: &[f64; STAGES]| {
        let row = DMatrix::from_fn(1, s, |_, j| w[j]);
        DVector::from_column_slice((&row * &gam).transpose().as_slice())
    };
    let (b, b_hat) = (weights(&M), weights(&M_HAT));
    (alpha, gam, b, b_hat)
}
