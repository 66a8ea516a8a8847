//! The scalar types the evaluation plan runs in: `f64` for values, and forward-mode dual numbers
//! for exact derivatives (one directional derivative per pass).

use std::ops::{Add, Div, Mul, Neg, Sub};

use super::element::NonlinearLaw;

/// Scalar type the plan is evaluated in: `f64`, or a forward-mode dual number for the exact
/// Jacobian.
pub(crate) trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    fn cst(c: f64) -> Self;
    fn scale(self, k: f64) -> Self;
    fn law(law: &NonlinearLaw, x: Self, m: Self) -> Self;
}

impl Scalar for f64 {
    #[inline]
    fn cst(c: f64) -> Self {
        c
    }
    #[inline]
    fn scale(self, k: f64) -> Self {
        self * k
    }
    #[inline]
    fn law(law: &NonlinearLaw, x: Self, m: Self) -> Self {
        (law.value)(x, m)
    }
}

/// The dual number of [`crate::math::dual`]: its arithmetic is the Jacobian passes'.
pub(crate) use crate::math::dual::Dual;

impl Scalar for Dual {
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
    fn law(law: &NonlinearLaw, x: Self, m: Self) -> Self {
        let (y, dx, dm) = (law.f)(x.v, m.v);
        Dual {
            v: y,
            d: dx * x.d + dm * m.d,
        }
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
        let y = Dual::law(&law, x, m);
        assert_eq!(
            y,
            Dual {
                v: 12.0,
                d: 4.0 + 1.5
            }
        );
        assert_eq!(f64::law(&law, 3.0, 4.0), 12.0);
    }
}
