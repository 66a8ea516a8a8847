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
}

impl Scalar for f64 {
    const ZERO: f64 = 0.0;
    const ONE: f64 = 1.0;
    #[inline]
    fn norm1(self) -> f64 {
        self.abs()
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
