//! The scalar types the evaluation plan runs in: `f64` for values, forward-mode dual numbers
//! for exact derivatives (one directional derivative per pass), and hyper-dual numbers for the
//! linearisation's derivative along a parameter (`sensitivity.rs`); and how a pass lifts the
//! plan's constants into them ([`Constants`]).

use std::convert::Infallible;
use std::ops::{Add, Div, Mul, Neg, Sub};

use super::element::NonlinearLaw;

/// Scalar type the plan is evaluated in: `f64`, a forward-mode dual number for the exact
/// Jacobian, or a hyper-dual number for the linearisation's parameter derivative.
pub(crate) trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// Why a law cannot be evaluated in this scalar: never for `f64` and [`Dual`]
    /// ([`Infallible`]); a law whose second derivatives a hyper-dual pass lacks.
    type Refusal;
    fn cst(c: f64) -> Self;
    fn scale(self, k: f64) -> Self;
    fn law(law: &NonlinearLaw, x: Self, m: Self) -> Result<Self, Self::Refusal>;
}

/// How a pass lifts the plan's constants into its scalar, each named by where it stands so
/// that a pass can give it a derivative of its own: [`Values`] for the value and Jacobian
/// passes, the constants with their derivatives along a parameter in `sensitivity.rs`.
pub(crate) trait Constants<T> {
    /// The constant `c` that an [`super::plan::Op::Const`] writes into the slot `dst`.
    fn constant(&self, dst: u32, c: f64) -> T;
    /// `x` times the coefficient `k` of the term `t` (its index in the model's terms) of an
    /// [`super::plan::Op::Lin`].
    fn term(&self, t: usize, k: f64, x: T) -> T;
}

/// The plan's constants as their values, without derivatives of their own.
pub(crate) struct Values;

impl<T: Scalar> Constants<T> for Values {
    #[inline(always)]
    fn constant(&self, _dst: u32, c: f64) -> T {
        T::cst(c)
    }
    #[inline(always)]
    fn term(&self, _t: usize, k: f64, x: T) -> T {
        x.scale(k)
    }
}

impl Scalar for f64 {
    type Refusal = Infallible;
    #[inline]
    fn cst(c: f64) -> Self {
        c
    }
    #[inline]
    fn scale(self, k: f64) -> Self {
        self * k
    }
    #[inline]
    fn law(law: &NonlinearLaw, x: Self, m: Self) -> Result<Self, Infallible> {
        Ok((law.value)(x, m))
    }
}

/// The dual number of [`crate::math::dual`]: its arithmetic is the Jacobian passes'.
pub(crate) use crate::math::dual::Dual;

impl Scalar for Dual {
    type Refusal = Infallible;
    #[inline]
    fn cst(c: f64) -> Self {
        Dual { v: c, d: 0.0 }
    }
    #[inline]
    fn scale(self, k: f64) -> Self {
        Dual {
            v: self.v * k,
            d: self.d * k,
        }
    }
    #[inline]
    fn law(law: &NonlinearLaw, x: Self, m: Self) -> Result<Self, Infallible> {
        let (y, dx, dm) = (law.f)(x.v, m.v);
        Ok(Dual {
            v: y,
            d: dx * x.d + dm * m.d,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dual_arithmetic_is_exact() {
        let x = Dual { v: 3.0, d: 1.0 };
        let c = Dual::cst(2.0);
        // f(x) = (x * x - 2) / (x + 2) * (-1) scaled by 0.5
        let f = (-((x * x - c) / (x + c))).scale(0.5);
        let v = -0.5 * (9.0 - 2.0) / 5.0;
        let d = -0.5 * (2.0 * 3.0 * 5.0 - 7.0) / 25.0;
        assert!((f.v - v).abs() < 1e-15 && (f.d - d).abs() < 1e-15);
        let law = NonlinearLaw::modulated("xm", |x, m| (x * m, m, x));
        let m = Dual { v: 4.0, d: 0.5 };
        let Ok(y) = Dual::law(&law, x, m);
        assert_eq!(
            y,
            Dual {
                v: 12.0,
                d: 4.0 + 1.5
            }
        );
        assert_eq!(f64::law(&law, 3.0, 4.0), Ok(12.0));
    }
}
