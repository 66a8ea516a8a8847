//! The regularised orifice law shared by every restriction of the full servo valve (BG2: inlet
//! orifices R1, R2 and the flapper-controlled nozzles R(x_f); BG3: the four metering edges of
//! the spool).
//!
//! # The law
//!
//! The textbook turbulent orifice, `Q = Cd A sqrt(2 |dp| / rho) sgn(dp)`, has an infinite slope at
//! `dp = 0`, which breaks the Newton iterations of Radau and the Jacobian of Rosenbrock methods
//! every time a pressure drop crosses zero (flow reversal). As the Modelica libraries do
//! (docs/model-notes.md, item 16), the law is regularised with a laminar region around zero:
//!
//! ```text
//! Q = Cd A sqrt(2/rho) dp / (dp^2 + dp_cr^2)^(1/4)
//! dQ/d(dp) = Cd A sqrt(2/rho) (dp^2/2 + dp_cr^2) / (dp^2 + dp_cr^2)^(5/4)
//! ```
//!
//! * for `|dp| >> dp_cr` it is the square-root law (relative error `dp_cr^2 / (4 dp^2)`);
//! * for `|dp| << dp_cr` it is laminar, `Q = Cd A sqrt(2/rho) dp / sqrt(dp_cr)`;
//! * it is odd, analytic (C-infinity) everywhere, strictly increasing, and `Q dp >= 0`: the
//!   orifice only dissipates, also through flow reversal.
//!
//! `dp_cr` follows from a critical Reynolds number: the mean jet velocity
//! `v = Cd sqrt(2 dp / rho)` reaches `Re_cr nu / d_h` at `dp_cr = rho/2 (Re_cr nu / (Cd d_h))^2`
//! ([`critical_pressure`]). With `Re_cr` = 10, `nu` = 32 cSt, `d_h` = 0.25 mm (the inlet orifice)
//! and `Cd` = 0.61 that is about 0.02 bar; the default `servo_valve.dp_cr` = 0.05 bar rounds it up
//! (the smaller pilot passages and the spool clearance are more laminar still). Every pressure
//! drop of interest is 10 to 1000 bar times larger, so the choice does not show in the response;
//! it only bounds the Jacobian (`dQ/d(dp)` at zero is finite).
//!
//! # Openings
//!
//! The opening area of a spool edge is `w x` for `x > 0` and zero for a critically centred spool
//! at `x <= 0`: a kink at null. It is replaced by the smooth ramp
//! `(x + sqrt(x^2 + c^2)) / 2` ([`smooth_ramp`]) where `c` is the radial clearance: at null each
//! edge is open by `c/2`, which is the clearance leakage of a real critically centred valve, and the
//! ramps of two opposite edges differ by exactly `x` (`ramp(x) - ramp(-x) = x`), so the null flow
//! gain of a four-way valve is exactly `Cd w sqrt(p_s/rho)`, unchanged by the regularisation. The
//! same ramp keeps the nozzle gap of the flapper positive when the flapper touches a nozzle.
//!
//! No branch depends on the sign of `dp` or `x`: flow reversal and spool null need no special
//! case at run time.

use crate::bond_graph::{Law, NonlinearLaw};
use crate::math::dual::{Dual, HyperDual, Real};

/// `Q/K` of the regularised law, per unit of `K = Cd A sqrt(2/rho)`:
/// `dp / (dp^2 + dp_cr^2)^(1/4)`, in any [`Real`] (the value of [`regularised_sqrt`], the same
/// operations).
#[inline]
pub fn regularised_sqrt_value<S: Real>(dp: S, dp_cr: S) -> S {
    let s = dp * dp + dp_cr * dp_cr;
    dp / s.sqrt().sqrt() // s^(1/4)
}

/// `(Q/K, d(Q/K)/d(dp))` of the regularised law, per unit of `K = Cd A sqrt(2/rho)`:
/// [`regularised_sqrt_value`] and its derivative.
#[inline]
pub fn regularised_sqrt(dp: f64, dp_cr: f64) -> (f64, f64) {
    let s = dp * dp + dp_cr * dp_cr;
    let q = s.sqrt().sqrt(); // s^(1/4)
    let dy = (0.5 * dp * dp + dp_cr * dp_cr) / (s * q);
    (regularised_sqrt_value(dp, dp_cr), dy)
}

/// The orifice coefficient `K = Cd A sqrt(2/rho)` \[m^3/(s Pa^(1/2))\] of an area `area`.
#[inline]
pub fn orifice_coefficient<S: Real>(cd: S, area: S, rho: S) -> S {
    cd * area * (S::cst(2.0) / rho).sqrt()
}

/// The regularised orifice flow `Q(dp)` \[m^3/s\] and `dQ/d(dp)` for a fixed area `area` \[m^2\].
pub fn orifice_flow(dp: f64, area: f64, cd: f64, rho: f64, dp_cr: f64) -> (f64, f64) {
    let k = orifice_coefficient(cd, area, rho);
    let (y, dy) = regularised_sqrt(dp, dp_cr);
    (k * y, k * dy)
}

/// The smooth ramp `(x + sqrt(x^2 + c^2)) / 2`, in any [`Real`] (the value of [`smooth_ramp`],
/// the same operations).
#[inline]
pub fn smooth_ramp_value<S: Real>(x: S, c: S) -> S {
    (x + (x * x + c * c).sqrt()) * 0.5
}

/// The smooth ramp [`smooth_ramp_value`] and its derivative: `max(x, 0)` with the corner
/// rounded over `|x| ~ c` (`c > 0`).
#[inline]
pub fn smooth_ramp(x: f64, c: f64) -> (f64, f64) {
    let r = (x * x + c * c).sqrt();
    (smooth_ramp_value(x, c), 0.5 * (1.0 + x / r))
}

/// Pressure at which the jet Reynolds number `Cd sqrt(2 dp/rho) d_h / nu` equals `re_cr`.
pub fn critical_pressure(re_cr: f64, nu: f64, d_h: f64, cd: f64, rho: f64) -> f64 {
    let v = re_cr * nu / (cd * d_h);
    0.5 * rho * v * v
}

/// Constant orifice parameters common to every restriction: in `f64` for the parameters'
/// values, in [`Dual`] for the laws, which carry each constant's derivative along the
/// parameter the model is built for (`OrificeFluid<f64>` converts, with zero derivatives).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrificeFluid<T = f64> {
    /// Discharge coefficient `Cd` \[-\].
    pub cd: T,
    /// Oil density `rho` \[kg/m^3\].
    pub rho: T,
    /// Laminar-transition pressure `dp_cr` \[Pa\].
    pub dp_cr: T,
}

impl From<OrificeFluid<f64>> for OrificeFluid<Dual> {
    /// The constants with zero derivatives.
    fn from(f: OrificeFluid<f64>) -> Self {
        OrificeFluid {
            cd: f.cd.into(),
            rho: f.rho.into(),
            dp_cr: f.dp_cr.into(),
        }
    }
}

/// The flow of a fixed orifice of coefficient `k` ([`orifice_coefficient`]) at the pressure
/// drop `dp`, in any [`Real`]: `k dp / (dp^2 + dp_cr^2)^(1/4)`, the value of the law of
/// [`fixed_orifice`].
#[inline]
pub fn fixed_orifice_flow<S: Real>(k: S, dp_cr: S, dp: S) -> S {
    k * regularised_sqrt_value(dp, dp_cr)
}

/// A fixed orifice of area `area` as an R law in conductance form (`f = Q(dp)`); its
/// hyper-dual form ([`NonlinearLaw::with_hyper`]) is [`fixed_orifice_flow`] with the constants'
/// derivatives.
///
/// Its value bound ([`NonlinearLaw::with_value_bound`]): with `K = Cd A sqrt(2/rho)`,
/// `|Q| <= K (dp² + 1)`. Since `(dp² + dp_cr²)^(1/4) >= |dp|^(1/2)`, `|Q| <= K |dp|^(1/2)`,
/// and `a^(1/2) <= a² + 1` for every `a >= 0` (`a^(1/2) <= 1` below 1, `<= a <= a²` above),
/// with at least 0.5 to spare (`a^(1/2) - a²` peaks at 0.47), far more than the few roundings
/// of the law. Declared when `dp_cr²` is a normal double (then `(dp² + dp_cr²)^(1/4)` is never
/// 0 and the law never 0/0) and `K` is finite; for `|dp| <= VALUE_BOUND_RANGE`, `dp²` does not
/// overflow.
pub fn fixed_orifice(
    label: impl Into<String>,
    area: impl Into<Dual>,
    fluid: impl Into<OrificeFluid<Dual>>,
) -> Law {
    let OrificeFluid { cd, rho, dp_cr } = fluid.into();
    let k_d = orifice_coefficient(cd, area.into(), rho);
    let (k, dp_cr_v) = (k_d.v, dp_cr.v);
    let bound =
        (k.abs().is_finite() && (dp_cr_v * dp_cr_v).is_normal()).then_some((k.abs(), k.abs()));
    Law::Conductance(
        NonlinearLaw::new(label, move |dp| {
            let dy = regularised_sqrt(dp, dp_cr_v).1;
            (fixed_orifice_flow(k, dp_cr_v, dp), k * dy)
        })
        .with_value_bound_if(bound)
        .with_hyper(move |dp, _| {
            fixed_orifice_flow(HyperDual::from(k_d), HyperDual::from(dp_cr), dp)
        }),
    )
}

/// The flow of a variable orifice at the pressure drop `dp` and modulator `m`, in any
/// [`Real`]: `k ramp(offset + sign m, clearance) dp / (dp^2 + dp_cr^2)^(1/4)`, `k` the
/// coefficient of the width ([`orifice_coefficient`]); the value of the law of
/// [`variable_orifice`].
#[inline]
pub fn variable_orifice_flow<S: Real>(
    k: S,
    offset: S,
    sign: f64,
    clearance: S,
    dp_cr: S,
    dp: S,
    m: S,
) -> S {
    k * smooth_ramp_value(offset + m * sign, clearance) * regularised_sqrt_value(dp, dp_cr)
}

/// A variable orifice whose area is `width * ramp(offset + sign * m, clearance)`, `m` the
/// modulating signal (spool or flapper position), as an R law in conductance form:
/// `Q = K(m) g(dp)` with exact `dQ/d(dp)` and `dQ/dm`; its hyper-dual form
/// ([`NonlinearLaw::with_hyper`]) is [`variable_orifice_flow`] with the constants' derivatives
/// (`sign` is a direction, no parameter).
///
/// * spool edge opening with `x_v`: `width` = area gradient `w`, `offset` = 0, `sign` = +1 or -1;
/// * nozzle with flapper `x_f`: `width` = `pi d_n`, `offset` = null gap `x_f0`, `sign` = -1 (the
///   nozzle the flapper moves towards) or +1.
///
/// Its value bound ([`NonlinearLaw::with_value_bound`]), with `s = max(|dp|, |m|)` and
/// `K = Cd width sqrt(2/rho)`: `|Q| <= K' (s² + 1)`, `K' = K (|sign| + |offset| +
/// clearance/2)`. The ramp `(x + sqrt(x² + c²))/2` lies in `[0, |x| + |c|/2]` and
/// `|x| <= |offset| + |sign| s`; the pressure factor is at most `|dp|^(1/2)` (as for
/// [`fixed_orifice`]); and `s^(3/2) <= s² + 1`, `s^(1/2) <= s² + 1` for `s >= 0`, each with at
/// least 0.5 to spare. Declared when `dp_cr²` is normal, `|sign| <= 2^10` and `|offset|`,
/// `clearance` at most `VALUE_BOUND_RANGE` (so that `x²` cannot overflow: `|x| <= 2^511`) and
/// `K` is finite.
pub fn variable_orifice(
    label: impl Into<String>,
    width: impl Into<Dual>,
    offset: impl Into<Dual>,
    sign: f64,
    clearance: impl Into<Dual>,
    fluid: impl Into<OrificeFluid<Dual>>,
) -> Law {
    let OrificeFluid { cd, rho, dp_cr } = fluid.into();
    let (offset_d, clearance_d) = (offset.into(), clearance.into());
    let k_d = orifice_coefficient(cd, width.into(), rho);
    let (k, offset, clearance, dp_cr_v) = (k_d.v, offset_d.v, clearance_d.v, dp_cr.v);
    let range = crate::bond_graph::VALUE_BOUND_RANGE;
    let k_bound = k.abs() * (sign.abs() + offset.abs() + 0.5 * clearance.abs());
    let bound = (k_bound.is_finite()
        && (dp_cr_v * dp_cr_v).is_normal()
        && sign.abs() <= 1024.0
        && offset.abs() <= range
        && clearance.abs() <= range)
        .then_some((k_bound, k_bound));
    Law::Conductance(
        NonlinearLaw::modulated(label, move |dp, m| {
            let (a, da) = smooth_ramp(offset + sign * m, clearance);
            let (y, dy) = regularised_sqrt(dp, dp_cr_v);
            (
                variable_orifice_flow(k, offset, sign, clearance, dp_cr_v, dp, m),
                k * a * dy,
                k * sign * da * y,
            )
        })
        .with_value_bound_if(bound)
        .with_hyper(move |dp, m| {
            let c = HyperDual::from;
            variable_orifice_flow(c(k_d), c(offset_d), sign, c(clearance_d), c(dp_cr), dp, m)
        }),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_matches_finite_difference() {
        for &dp in &[-1e7, -3e5, -1e3, -10.0, 0.0, 7.0, 2e3, 4e5, 2e7] {
            let (_, d) = regularised_sqrt(dp, 5e3);
            let h = 1e-6 * (dp.abs() + 5e3);
            let fd =
                (regularised_sqrt(dp + h, 5e3).0 - regularised_sqrt(dp - h, 5e3).0) / (2.0 * h);
            assert!((d - fd).abs() <= 1e-6 * d.abs(), "dp {dp}: {d} vs {fd}");
        }
        for &x in &[-1e-3, -1e-6, 0.0, 2e-6, 1e-3] {
            let (_, d) = smooth_ramp(x, 2e-6);
            let h = 1e-9;
            let fd = (smooth_ramp(x + h, 2e-6).0 - smooth_ramp(x - h, 2e-6).0) / (2.0 * h);
            assert!((d - fd).abs() < 1e-6, "x {x}: {d} vs {fd}");
        }
    }

    #[test]
    fn limits_are_turbulent_and_laminar() {
        let (y, _) = regularised_sqrt(1e7, 5e3);
        assert!((y / 1e7f64.sqrt() - 1.0).abs() < 1e-6);
        let (y, _) = regularised_sqrt(-1e7, 5e3);
        assert!((y / 1e7f64.sqrt() + 1.0).abs() < 1e-6);
        let (_, d0) = regularised_sqrt(0.0, 5e3);
        assert!((d0 - 1.0 / 5e3f64.sqrt()).abs() < 1e-15);
        // ramp(x) - ramp(-x) = x exactly (null flow gain unchanged)
        for &x in &[-3e-4, 1e-7, 5e-4] {
            assert!((smooth_ramp(x, 2e-6).0 - smooth_ramp(-x, 2e-6).0 - x).abs() < 1e-18);
        }
    }

    use crate::fragments::law_checks::{
        assert_hand_derivatives, assert_mixed, assert_same_bits, grid,
    };

    /// The inlet orifice's fluid (`Cd`, `rho`, `dp_cr`) and area, the nozzle's width, null gap
    /// and rounding.
    const FLUID: OrificeFluid = OrificeFluid {
        cd: 0.61,
        rho: 850.0,
        dp_cr: 5e3,
    };
    const AREA: f64 = 4.9e-8;
    const NOZZLE: (f64, f64, f64) = (1.26e-3, 3e-5, 3e-7);

    fn nonlinear(law: Law) -> NonlinearLaw {
        match law {
            Law::Conductance(law) | Law::Nonlinear(law) => law,
            Law::Linear(_) => panic!("a linear law"),
        }
    }

    fn nozzle(sign: f64) -> NonlinearLaw {
        let (width, offset, clearance) = NOZZLE;
        nonlinear(variable_orifice(
            "nozzle", width, offset, sign, clearance, FLUID,
        ))
    }

    #[test]
    fn fixed_orifice_in_hyper_dual_numbers() {
        let law = nonlinear(fixed_orifice("R1", AREA, FLUID));
        let k = orifice_coefficient(FLUID.cd, AREA, FLUID.rho);
        let dps = grid(FLUID.dp_cr);
        assert_same_bits(
            &law,
            |dp, _| fixed_orifice_flow(k, FLUID.dp_cr, dp),
            &dps,
            &[0.0],
        );
        // The law as it was before its value had one source: orifice_flow, bit for bit.
        for &dp in &dps {
            let old = orifice_flow(dp, AREA, FLUID.cd, FLUID.rho, FLUID.dp_cr);
            let (v, d, _) = law.eval(dp, 0.0);
            assert_eq!(
                (v.to_bits(), d.to_bits()),
                (old.0.to_bits(), old.1.to_bits())
            );
        }
        let dual = |dp: Dual, _| fixed_orifice_flow(Dual::from(k), Dual::from(FLUID.dp_cr), dp);
        assert_hand_derivatives(&law, dual, &dps, &[0.0], 1e-12, |_, _| (0.0, 0.0));
        // d²Q/d(dp) d(dp_cr): dQ/d(dp) varies in dp_cr over dp_cr itself.
        let with_dp_cr = |dp_cr: Dual| {
            let fluid = OrificeFluid {
                cd: Dual::from(FLUID.cd),
                rho: Dual::from(FLUID.rho),
                dp_cr,
            };
            nonlinear(fixed_orifice("R1", AREA, fluid))
        };
        for dp in [-2e4, -3e3, 0.0, 1e3, 7e3, 4e4] {
            assert_mixed(with_dp_cr, FLUID.dp_cr, 1e-4, FLUID.dp_cr, dp, 0.0, false);
        }
    }

    #[test]
    fn variable_orifice_in_hyper_dual_numbers() {
        let (width, offset, clearance) = NOZZLE;
        let k = orifice_coefficient(FLUID.cd, width, FLUID.rho);
        let dps = grid(FLUID.dp_cr);
        let ms = grid(offset);
        for sign in [-1.0, 1.0] {
            let law = nozzle(sign);
            let generic =
                |dp, m| variable_orifice_flow(k, offset, sign, clearance, FLUID.dp_cr, dp, m);
            assert_same_bits(&law, generic, &dps, &ms);
            // The closure as it was before its value had one source, bit for bit.
            for &dp in &dps {
                for &m in &ms {
                    let (a, da) = smooth_ramp(offset + sign * m, clearance);
                    let (y, dy) = regularised_sqrt(dp, FLUID.dp_cr);
                    let old = (k * a * y, k * a * dy, k * sign * da * y);
                    let new = law.eval(dp, m);
                    assert_eq!(
                        [new.0.to_bits(), new.1.to_bits(), new.2.to_bits()],
                        [old.0.to_bits(), old.1.to_bits(), old.2.to_bits()]
                    );
                }
            }
            let c = Dual::from;
            let dual = |dp, m| {
                variable_orifice_flow(c(k), c(offset), sign, c(clearance), c(FLUID.dp_cr), dp, m)
            };
            // dQ/dm = K g(dp) (1 + x/r)/2 cancels below the ramp's corner (x << -c): the sum
            // of its terms' magnitudes, K |g| (1 + |x|/r)/2 = K |g|, is its scale.
            let scale = |dp, _| (0.0, (k * regularised_sqrt(dp, FLUID.dp_cr).0).abs());
            assert_hand_derivatives(&law, dual, &dps, &ms, 1e-12, scale);
            // d²Q/d(dp) d(x_f0) and d²Q/d(x_f) d(x_f0): the ramp varies over the clearance.
            let with_offset = |offset: Dual| {
                nonlinear(variable_orifice(
                    "nozzle", width, offset, sign, clearance, FLUID,
                ))
            };
            // At the null gap, two clearances from contact, and at contact.
            for (dp, m) in [
                (2e6, 0.0),
                (-4e5, -sign * (offset - 2.0 * clearance)),
                (3e3, -sign * offset),
            ] {
                for along_m in [false, true] {
                    assert_mixed(with_offset, offset, 1e-4, clearance, dp, m, along_m);
                }
            }
        }
    }
}
