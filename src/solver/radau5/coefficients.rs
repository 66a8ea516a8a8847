//! The method's constants (RADAU5's prologue of RADCOR): the collocation nodes, the eigenvalues
//! of A⁻¹ and the transformation T that block-diagonalises it, and the weights of the error
//! estimate. All as in `radau5.f`; the comments say what each is.

/// √6.
fn sq6() -> f64 {
    6f64.sqrt()
}

/// Collocation nodes c1 = (4-√6)/10 and c2 = (4+√6)/10 (c3 = 1).
pub fn nodes() -> (f64, f64) {
    ((4.0 - sq6()) / 10.0, (4.0 + sq6()) / 10.0)
}

/// Eigenvalues of A⁻¹ (A the Radau IIA matrix): a real one γ and a complex pair α ± iβ.
/// RADAU5: U1 = 1/((6 + 81^(1/3) - 9^(1/3))/30), ALPH, BETA = (…)/(ALPH² + BETA²).
pub fn inverse_eigenvalues() -> (f64, f64, f64) {
    let c81 = crate::math::cbrt(81f64);
    let c9 = crate::math::cbrt(9f64);
    let u1 = (6.0 + c81 - c9) / 30.0; // real eigenvalue of A
    let alph = (12.0 - c81 + c9) / 60.0; // real part of the complex pair of A
    let beta = (c81 + c9) * 3f64.sqrt() / 60.0; // imaginary part
    let cno = alph * alph + beta * beta;
    (1.0 / u1, alph / cno, beta / cno)
}

/// Error-estimate weights (DD1, DD2, DD3) of RADAU5: the embedded combination
/// e = γ0 h f(y0) + Σ e_i Z_i (eq. IV.8.19) written with e_i = DD_i / γ (DD_i below).
pub fn error_weights() -> (f64, f64, f64) {
    (
        -(13.0 + 7.0 * sq6()) / 3.0,
        (-13.0 + 7.0 * sq6()) / 3.0,
        -1.0 / 3.0,
    )
}

/// T with `T⁻¹ A⁻¹ T = [[γ,0,0],[0,α,-β],[0,β,α]]` (RADAU5's T11…T33; T32 = 1, T33 = 0).
#[allow(clippy::excessive_precision)] // digits as published in radau5.f
pub const T: [[f64; 3]; 3] = [
    [
        9.1232394870892942792e-02,
        -0.14125529502095420843,
        -3.0029194105147424492e-02,
    ],
    [
        0.24171793270710701896,
        0.20412935229379993199,
        0.38294211275726193779,
    ],
    [0.96604818261509293619, 1.0, 0.0],
];
/// T⁻¹ (RADAU5's TI11…TI33).
#[allow(clippy::excessive_precision)] // digits as published in radau5.f
pub const TI: [[f64; 3]; 3] = [
    [
        4.3255798900631553510,
        0.33919925181580986954,
        0.54177053993587487119,
    ],
    [
        -4.1787185915519047273,
        -0.32768282076106238708,
        0.47662355450055045196,
    ],
    [
        -0.50287263494578687595,
        2.5719269498556054292,
        -0.59603920482822492497,
    ],
];
