//! Arithmetic that gives the same doubles on every platform and every CPU.
//!
//! **Transcendental functions**, for the model, its integrators and its tools: the `libm` crate (Rust's port of musl's libm), compiled into the library, in place
//! of `f64::exp` and its siblings, which call the platform's C library (glibc on Linux, the
//! Windows CRT, Apple's libm) or, in WebAssembly, Rust's own copy. Those differ in the last bit
//! of some results, and a last bit can tip an adaptive step-size decision, after which two
//! platforms' runs differ at the tolerance's level (1e-7 of an output's range at rtol 1e-6,
//! measured between the browser and Linux). With these, the FMU on every platform and the
//! browser build compute the same doubles (`tests/python/test_portable.py`,
//! `tests/python/test_web.py`). `sqrt` stays `f64::sqrt`: IEEE 754 rounds it exactly everywhere.
//!
//! **Products of matrices** ([`product`]): nalgebra multiplies dynamic matrices larger than 5 x 5
//! with the `matrixmultiply` crate, whose kernels use fused multiply-adds where the CPU has them
//! (chosen at run time on x86-64): the same FMU would compute other last bits on another
//! machine. The model's own products of matrices go through [`product`].
//!
//! `tests/portable_math.rs` checks that the library calls no platform function but `sqrt`.

pub mod dual;
pub mod lanes;

use nalgebra::DMatrix;

/// `a b`, each entry summed in order of the inner index with separately rounded products and
/// sums, whatever the CPU.
pub fn product(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    assert_eq!(a.ncols(), b.nrows(), "product: inner dimensions differ");
    DMatrix::from_fn(a.nrows(), b.ncols(), |i, j| {
        (0..a.ncols()).fold(0.0, |sum, k| sum + a[(i, k)] * b[(k, j)])
    })
}

/// `e^x`.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// `e^x - 1`, accurate near 0.
#[inline]
pub fn exp_m1(x: f64) -> f64 {
    libm::expm1(x)
}

/// Natural logarithm.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// `ln(1 + x)`, accurate near 0.
#[inline]
pub fn ln_1p(x: f64) -> f64 {
    libm::log1p(x)
}

/// Decimal logarithm.
#[inline]
pub fn log10(x: f64) -> f64 {
    libm::log10(x)
}

/// `x^y`.
#[inline]
pub fn powf(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// Cube root.
#[inline]
pub fn cbrt(x: f64) -> f64 {
    libm::cbrt(x)
}

#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

#[inline]
pub fn sinh(x: f64) -> f64 {
    libm::sinh(x)
}

#[inline]
pub fn cosh(x: f64) -> f64 {
    libm::cosh(x)
}

#[inline]
pub fn tanh(x: f64) -> f64 {
    libm::tanh(x)
}

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}
