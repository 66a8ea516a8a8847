//! The entries of the iteration matrices: real or complex.

use std::ops::{Add, Div, Mul, Neg, Sub};

use nalgebra::Complex;

/// The scalars the iteration matrices have: f64 (Rodas5P, Radau5's real system) and
/// `Complex<f64>` (Radau5's complex system).
pub trait Scalar:
    Copy
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + std::fmt::Debug
{
    const ZERO: Self;
    const ONE: Self;
    /// |re| + |im|, the pivot size LAPACK's `izamax` uses.
    fn norm1(self) -> f64;
    /// The entries as f64s if they are (`Some` for f64 only): the dense solve's AVX2 kernel
    /// for small real blocks is written for them, the other scalars take the loops.
    #[doc(hidden)]
    fn as_reals(s: &[Self]) -> Option<&[f64]> {
        let _ = s;
        None
    }
    /// [`Scalar::as_reals`], mutable.
    #[doc(hidden)]
    fn as_reals_mut(s: &mut [Self]) -> Option<&mut [f64]> {
        let _ = s;
        None
    }
}

impl Scalar for f64 {
    const ZERO: f64 = 0.0;
    const ONE: f64 = 1.0;
    #[inline]
    fn norm1(self) -> f64 {
        self.abs()
    }
    #[inline]
    fn as_reals(s: &[f64]) -> Option<&[f64]> {
        Some(s)
    }
    #[inline]
    fn as_reals_mut(s: &mut [f64]) -> Option<&mut [f64]> {
        Some(s)
    }
}

impl Scalar for Complex<f64> {
    const ZERO: Complex<f64> = Complex { re: 0.0, im: 0.0 };
    const ONE: Complex<f64> = Complex { re: 1.0, im: 0.0 };
    #[inline]
    fn norm1(self) -> f64 {
        self.re.abs() + self.im.abs()
    }
}
