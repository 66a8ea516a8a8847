//! Forward-mode automatic differentiation: the scalar types the model's parameters can be
//! carried in so that its constants, its linearisation and its right-hand side come with their
//! exact derivatives along one parameter (`hsp identify`'s sensitivities, docs/identify.md).
//!
//! * [`Dual`] `v + d ε` (`ε² = 0`): a value and its derivative along one direction. The compiled
//!   plan's Jacobian passes run in it (the direction a state), and so do the bond graph's
//!   constants (the direction a parameter: [`crate::bond_graph`] keeps each constant with its
//!   derivative).
//! * [`HyperDual`] `v + a ε₁ + b ε₂ + ab ε₁ε₂` (`ε₁² = ε₂² = 0`): two directions and the mixed
//!   second derivative. With `ε₁` along a state and `ε₂` along a parameter, its `ab` part is a
//!   Jacobian entry's derivative with respect to the parameter, `∂²f/∂x∂p`, exact.
//! * [`Real`]: what a function written once, generic in its scalar, may use (arithmetic, with
//!   `f64` constants on the right, and the elementary functions), implemented by `f64`, [`Dual`]
//!   and [`HyperDual`].
//!
//! **The same values to the bit.** In every operation the value part is computed by the very
//! floating-point operation `f64` computes ([`crate::math`]'s portable functions for the
//! transcendental ones), so code run in `Dual` or `HyperDual` gives the doubles it gives in
//! `f64`, whatever the tangents; the tangents only ride along. Tested in this module.

use std::fmt::Debug;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A scalar a function can be written for once and run in `f64` (values), [`Dual`] (one
/// derivative) or [`HyperDual`] (two and their mixed second derivative). Constants multiply,
/// divide, add and subtract on the right (`x * 2.0`); write `S::cst(2.0) / x` for a constant on
/// the left. Call the elementary functions by path, `S::exp(x)` (or `Real::exp(x)`), not as
/// methods: `tests/portable_math.rs` takes a method call `.exp(` for `f64`'s, the platform's.
pub trait Real:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// A constant: its derivatives zero.
    fn cst(c: f64) -> Self;
    /// The value, without its derivatives.
    fn value(self) -> f64;
    /// `e^x` ([`crate::math::exp`]).
    fn exp(self) -> Self;
    /// `ln x` ([`crate::math::ln`]).
    fn ln(self) -> Self;
    /// `ln(1 + x)` ([`crate::math::ln_1p`]).
    fn ln_1p(self) -> Self;
    /// `tanh x` ([`crate::math::tanh`]).
    fn tanh(self) -> Self;
    /// `√x` (IEEE 754's, exact everywhere).
    fn sqrt(self) -> Self;
    /// `|x|`, its derivative `sign(x)` (that of `+0` at `±0`: the side the value's sign bit
    /// names).
    fn abs(self) -> Self;
}

impl Real for f64 {
    #[inline]
    fn cst(c: f64) -> Self {
        c
    }
    #[inline]
    fn value(self) -> f64 {
        self
    }
    #[inline]
    fn exp(self) -> Self {
        super::exp(self)
    }
    #[inline]
    fn ln(self) -> Self {
        super::ln(self)
    }
    #[inline]
    fn ln_1p(self) -> Self {
        super::ln_1p(self)
    }
    #[inline]
    fn tanh(self) -> Self {
        super::tanh(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline]
    fn abs(self) -> Self {
        f64::abs(self)
    }
}

/// A dual number `v + d ε`, `ε² = 0`: a value and its derivative along one direction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dual {
    /// The value.
    pub v: f64,
    /// Its derivative along the direction.
    pub d: f64,
}

impl Dual {
    /// `v` with derivative `d`.
    pub const fn new(v: f64, d: f64) -> Dual {
        Dual { v, d }
    }

    /// `f(v)` with its derivative `f'(v) d`: an elementary function from its value and slope.
    #[inline]
    fn chain(self, f: f64, slope: f64) -> Dual {
        Dual {
            v: f,
            d: slope * self.d,
        }
    }
}

impl From<f64> for Dual {
    /// A constant.
    fn from(v: f64) -> Dual {
        Dual { v, d: 0.0 }
    }
}

impl Add for Dual {
    type Output = Dual;
    #[inline]
    fn add(self, o: Dual) -> Dual {
        Dual {
            v: self.v + o.v,
            d: self.d + o.d,
        }
    }
}
impl Sub for Dual {
    type Output = Dual;
    #[inline]
    fn sub(self, o: Dual) -> Dual {
        Dual {
            v: self.v - o.v,
            d: self.d - o.d,
        }
    }
}
impl Mul for Dual {
    type Output = Dual;
    #[inline]
    fn mul(self, o: Dual) -> Dual {
        Dual {
            v: self.v * o.v,
            d: self.d * o.v + self.v * o.d,
        }
    }
}
impl Div for Dual {
    type Output = Dual;
    #[inline]
    fn div(self, o: Dual) -> Dual {
        let v = self.v / o.v;
        Dual {
            v,
            d: (self.d - v * o.d) / o.v,
        }
    }
}
impl Neg for Dual {
    type Output = Dual;
    #[inline]
    fn neg(self) -> Dual {
        Dual {
            v: -self.v,
            d: -self.d,
        }
    }
}
impl Add<f64> for Dual {
    type Output = Dual;
    #[inline]
    fn add(self, c: f64) -> Dual {
        Dual {
            v: self.v + c,
            d: self.d,
        }
    }
}
impl Sub<f64> for Dual {
    type Output = Dual;
    #[inline]
    fn sub(self, c: f64) -> Dual {
        Dual {
            v: self.v - c,
            d: self.d,
        }
    }
}
impl Mul<f64> for Dual {
    type Output = Dual;
    #[inline]
    fn mul(self, c: f64) -> Dual {
        Dual {
            v: self.v * c,
            d: self.d * c,
        }
    }
}
impl Div<f64> for Dual {
    type Output = Dual;
    #[inline]
    fn div(self, c: f64) -> Dual {
        Dual {
            v: self.v / c,
            d: self.d / c,
        }
    }
}

impl Real for Dual {
    #[inline]
    fn cst(c: f64) -> Self {
        Dual { v: c, d: 0.0 }
    }
    #[inline]
    fn value(self) -> f64 {
        self.v
    }
    fn exp(self) -> Self {
        let e = super::exp(self.v);
        self.chain(e, e)
    }
    fn ln(self) -> Self {
        self.chain(super::ln(self.v), 1.0 / self.v)
    }
    fn ln_1p(self) -> Self {
        self.chain(super::ln_1p(self.v), 1.0 / (1.0 + self.v))
    }
    fn tanh(self) -> Self {
        let t = super::tanh(self.v);
        self.chain(t, 1.0 - t * t)
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s)
    }
    fn abs(self) -> Self {
        self.chain(self.v.abs(), 1f64.copysign(self.v))
    }
}

/// A hyper-dual number `v + a ε₁ + b ε₂ + ab ε₁ε₂`, `ε₁² = ε₂² = 0`: a value, its derivatives
/// along two directions, and the mixed second derivative.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HyperDual {
    /// The value.
    pub v: f64,
    /// Its derivative along the first direction.
    pub a: f64,
    /// Its derivative along the second direction.
    pub b: f64,
    /// The mixed second derivative.
    pub ab: f64,
}

impl HyperDual {
    /// `f(x)` from `f`, `f'` and `f''` at the value: the chain rule to second order.
    #[inline]
    fn chain(self, f: f64, f1: f64, f2: f64) -> HyperDual {
        HyperDual {
            v: f,
            a: f1 * self.a,
            b: f1 * self.b,
            ab: f1 * self.ab + f2 * self.a * self.b,
        }
    }

    /// The number with its first direction's parts only (`b` and `ab` zero).
    pub fn first(self) -> Dual {
        Dual {
            v: self.v,
            d: self.a,
        }
    }

    /// The number with its second direction's parts only (`a` and `ab` zero).
    pub fn second(self) -> Dual {
        Dual {
            v: self.v,
            d: self.b,
        }
    }

    /// `x` along the first direction (`a = x.d`) that is itself `p` along the second: a state
    /// seeded as an input of a Jacobian pass, whose value depends on a parameter.
    pub fn from_parts(v: f64, a: f64, b: f64, ab: f64) -> HyperDual {
        HyperDual { v, a, b, ab }
    }
}

impl From<f64> for HyperDual {
    /// A constant.
    fn from(v: f64) -> HyperDual {
        HyperDual::cst(v)
    }
}

impl From<Dual> for HyperDual {
    /// A number along the second direction only: a parameter's constant.
    fn from(x: Dual) -> HyperDual {
        HyperDual {
            v: x.v,
            a: 0.0,
            b: x.d,
            ab: 0.0,
        }
    }
}

impl Add for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn add(self, o: HyperDual) -> HyperDual {
        HyperDual {
            v: self.v + o.v,
            a: self.a + o.a,
            b: self.b + o.b,
            ab: self.ab + o.ab,
        }
    }
}
impl Sub for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn sub(self, o: HyperDual) -> HyperDual {
        HyperDual {
            v: self.v - o.v,
            a: self.a - o.a,
            b: self.b - o.b,
            ab: self.ab - o.ab,
        }
    }
}
impl Mul for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn mul(self, o: HyperDual) -> HyperDual {
        HyperDual {
            v: self.v * o.v,
            a: self.a * o.v + self.v * o.a,
            b: self.b * o.v + self.v * o.b,
            ab: self.ab * o.v + self.a * o.b + self.b * o.a + self.v * o.ab,
        }
    }
}
impl Div for HyperDual {
    type Output = HyperDual;
    /// `q = x / y` from `x = q y`, part by part.
    #[inline]
    fn div(self, o: HyperDual) -> HyperDual {
        let v = self.v / o.v;
        let a = (self.a - v * o.a) / o.v;
        let b = (self.b - v * o.b) / o.v;
        HyperDual {
            v,
            a,
            b,
            ab: (self.ab - a * o.b - b * o.a - v * o.ab) / o.v,
        }
    }
}
impl Neg for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn neg(self) -> HyperDual {
        HyperDual {
            v: -self.v,
            a: -self.a,
            b: -self.b,
            ab: -self.ab,
        }
    }
}
impl Add<f64> for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn add(self, c: f64) -> HyperDual {
        HyperDual {
            v: self.v + c,
            ..self
        }
    }
}
impl Sub<f64> for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn sub(self, c: f64) -> HyperDual {
        HyperDual {
            v: self.v - c,
            ..self
        }
    }
}
impl Mul<f64> for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn mul(self, c: f64) -> HyperDual {
        HyperDual {
            v: self.v * c,
            a: self.a * c,
            b: self.b * c,
            ab: self.ab * c,
        }
    }
}
impl Div<f64> for HyperDual {
    type Output = HyperDual;
    #[inline]
    fn div(self, c: f64) -> HyperDual {
        HyperDual {
            v: self.v / c,
            a: self.a / c,
            b: self.b / c,
            ab: self.ab / c,
        }
    }
}

impl Real for HyperDual {
    #[inline]
    fn cst(c: f64) -> Self {
        HyperDual {
            v: c,
            a: 0.0,
            b: 0.0,
            ab: 0.0,
        }
    }
    #[inline]
    fn value(self) -> f64 {
        self.v
    }
    fn exp(self) -> Self {
        let e = super::exp(self.v);
        self.chain(e, e, e)
    }
    fn ln(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(super::ln(self.v), r, -r * r)
    }
    fn ln_1p(self) -> Self {
        let r = 1.0 / (1.0 + self.v);
        self.chain(super::ln_1p(self.v), r, -r * r)
    }
    fn tanh(self) -> Self {
        let t = super::tanh(self.v);
        let s = 1.0 - t * t;
        self.chain(t, s, -2.0 * t * s)
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        let f1 = 0.5 / s;
        self.chain(s, f1, -0.5 * f1 / self.v)
    }
    fn abs(self) -> Self {
        self.chain(self.v.abs(), 1f64.copysign(self.v), 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{exp, ln, tanh};

    /// A function written once: `g(x, y) = sqrt(x) tanh(x y) / (1 + |y|) + ln(x) e^(-y) -
    /// ln(1 + x y)`, with constants on the right and on the left.
    fn g<S: Real>(x: S, y: S) -> S {
        x.sqrt() * S::tanh(x * y) / (y.abs() + 1.0) + S::ln(x) * S::exp(-y) - S::ln_1p(x * y)
            + S::cst(2.0) / x * 0.25
            - y * 3.0
    }

    /// `g`'s partial derivatives in closed form, by hand.
    fn g_x(x: f64, y: f64) -> f64 {
        let t = tanh(x * y);
        let n = 1.0 + y.abs();
        (0.5 / x.sqrt() * t + x.sqrt() * (1.0 - t * t) * y) / n + exp(-y) / x
            - y / (1.0 + x * y)
            - 0.5 / (x * x)
    }
    fn g_y(x: f64, y: f64) -> f64 {
        let t = tanh(x * y);
        let n = 1.0 + y.abs();
        x.sqrt() * ((1.0 - t * t) * x / n - t * y.signum() / (n * n))
            - ln(x) * exp(-y)
            - x / (1.0 + x * y)
            - 3.0
    }

    #[test]
    fn each_type_gives_the_doubles_of_f64() {
        for &(x, y) in &[(0.7, 0.3), (2.5, -1.2), (1e-3, 40.0), (9.0, -0.0)] {
            let v = g(x, y);
            let d = g(Dual::new(x, 1.0), Dual::new(y, -2.0));
            let h = g(
                HyperDual::from_parts(x, 1.0, 0.5, 0.0),
                HyperDual::from_parts(y, 0.0, 1.0, 0.0),
            );
            assert_eq!(d.v.to_bits(), v.to_bits());
            assert_eq!(h.v.to_bits(), v.to_bits());
        }
    }

    #[test]
    fn the_derivatives_are_the_closed_forms() {
        for &(x, y) in &[(0.7, 0.3), (2.5, -1.2), (1.3, 0.8)] {
            let d = g(Dual::new(x, 1.0), Dual::new(y, 0.0));
            assert!(
                (d.d - g_x(x, y)).abs() < 1e-13 * (1.0 + g_x(x, y).abs()),
                "{d:?}"
            );
            let d = g(Dual::new(x, 0.0), Dual::new(y, 1.0));
            assert!(
                (d.d - g_y(x, y)).abs() < 1e-13 * (1.0 + g_y(x, y).abs()),
                "{d:?}"
            );
            // ε₁ along x, ε₂ along y: a = g_x, b = g_y, ab = g_xy, checked against the
            // derivative in y of the closed form g_x (the Dual number of g_x's expression
            // would be the same algebra; a central difference of the closed form is
            // independent of it, with its truncation error h² g_xyyy ~ 1e-10 here).
            let h = g(
                HyperDual::from_parts(x, 1.0, 0.0, 0.0),
                HyperDual::from_parts(y, 0.0, 1.0, 0.0),
            );
            assert!((h.a - g_x(x, y)).abs() < 1e-13 * (1.0 + g_x(x, y).abs()));
            assert!((h.b - g_y(x, y)).abs() < 1e-13 * (1.0 + g_y(x, y).abs()));
            let e = 1e-5;
            let g_xy = (g_x(x, y + e) - g_x(x, y - e)) / (2.0 * e);
            assert!(
                (h.ab - g_xy).abs() < 1e-8 * (1.0 + g_xy.abs()),
                "{h:?} {g_xy}"
            );
            // The mixed part is symmetric: the directions swapped give the same.
            let s = g(
                HyperDual::from_parts(x, 0.0, 1.0, 0.0),
                HyperDual::from_parts(y, 1.0, 0.0, 0.0),
            );
            assert!((s.ab - h.ab).abs() < 1e-13 * (1.0 + h.ab.abs()));
        }
    }

    #[test]
    fn the_second_derivative_along_one_direction_is_exact() {
        // Both directions along x: ab = g_xx. g(x) = x^3 / (1 + x) closed form.
        let f = |x: HyperDual| x * x * x / (x + 1.0);
        let x = 1.7;
        let h = f(HyperDual::from_parts(x, 1.0, 1.0, 0.0));
        let exact = (2.0 * x * x * x + 6.0 * x * x + 6.0 * x) / ((1.0 + x) * (1.0 + x) * (1.0 + x));
        assert!((h.ab - exact).abs() < 1e-14 * exact, "{} {exact}", h.ab);
        for (f2, name) in [
            (
                Real::exp(HyperDual::from_parts(x, 1.0, 1.0, 0.0)).ab - exp(x),
                "exp",
            ),
            (
                Real::ln(HyperDual::from_parts(x, 1.0, 1.0, 0.0)).ab + 1.0 / (x * x),
                "ln",
            ),
            (
                HyperDual::from_parts(x, 1.0, 1.0, 0.0).sqrt().ab + 0.25 / (x * x.sqrt()),
                "sqrt",
            ),
            (
                Real::ln_1p(HyperDual::from_parts(x, 1.0, 1.0, 0.0)).ab
                    + 1.0 / ((1.0 + x) * (1.0 + x)),
                "ln_1p",
            ),
            (
                Real::tanh(HyperDual::from_parts(x, 1.0, 1.0, 0.0)).ab
                    + 2.0 * tanh(x) * (1.0 - tanh(x) * tanh(x)),
                "tanh",
            ),
        ] {
            assert!(f2.abs() < 1e-14, "{name}: {f2}");
        }
    }
}
