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

/// `(Q/K, d(Q/K)/d(dp))` of the regularised law, per unit of `K = Cd A sqrt(2/rho)`:
/// `dp / (dp^2 + dp_cr^2)^(1/4)` and its derivative.
pub fn regularised_sqrt(dp: f64, dp_cr: f64) -> (f64, f64) {
    let s = dp * dp + dp_cr * dp_cr;
    let q = s.sqrt().sqrt(); // s^(1/4)
    let y = dp / q;
    let dy = (0.5 * dp * dp + dp_cr * dp_cr) / (s * q);
    (y, dy)
}

/// The regularised orifice flow `Q(dp)` \[m^3/s\] and `dQ/d(dp)` for a fixed area `area` \[m^2\].
pub fn orifice_flow(dp: f64, area: f64, cd: f64, rho: f64, dp_cr: f64) -> (f64, f64) {
    let k = cd * area * (2.0 / rho).sqrt();
    let (y, dy) = regularised_sqrt(dp, dp_cr);
    (k * y, k * dy)
}

/// The smooth ramp `(x + sqrt(x^2 + c^2)) / 2` and its derivative: `max(x, 0)` with the corner
/// rounded over `|x| ~ c` (`c > 0`).
pub fn smooth_ramp(x: f64, c: f64) -> (f64, f64) {
    let r = (x * x + c * c).sqrt();
    (0.5 * (x + r), 0.5 * (1.0 + x / r))
}

/// Pressure at which the jet Reynolds number `Cd sqrt(2 dp/rho) d_h / nu` equals `re_cr`.
pub fn critical_pressure(re_cr: f64, nu: f64, d_h: f64, cd: f64, rho: f64) -> f64 {
    let v = re_cr * nu / (cd * d_h);
    0.5 * rho * v * v
}

/// Constant orifice parameters common to every restriction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrificeFluid {
    /// Discharge coefficient `Cd` \[-\].
    pub cd: f64,
    /// Oil density `rho` \[kg/m^3\].
    pub rho: f64,
    /// Laminar-transition pressure `dp_cr` \[Pa\].
    pub dp_cr: f64,
}

/// A fixed orifice of area `area` as an R law in conductance form (`f = Q(dp)`).
///
/// Its value bound ([`NonlinearLaw::with_value_bound`]): with `K = Cd A sqrt(2/rho)`,
/// `|Q| <= K (dp² + 1)`. Since `(dp² + dp_cr²)^(1/4) >= |dp|^(1/2)`, `|Q| <= K |dp|^(1/2)`,
/// and `a^(1/2) <= a² + 1` for every `a >= 0` (`a^(1/2) <= 1` below 1, `<= a <= a²` above),
/// with at least 0.5 to spare (`a^(1/2) - a²` peaks at 0.47), far more than the few roundings
/// of the law. Declared when `dp_cr²` is a normal double (then `(dp² + dp_cr²)^(1/4)` is never
/// 0 and the law never 0/0) and `K` is finite; for `|dp| <= VALUE_BOUND_RANGE`, `dp²` does not
/// overflow.
pub fn fixed_orifice(label: impl Into<String>, area: f64, fluid: OrificeFluid) -> Law {
    let OrificeFluid { cd, rho, dp_cr } = fluid;
    let k = (cd * area * (2.0 / rho).sqrt()).abs();
    let bound = (k.is_finite() && (dp_cr * dp_cr).is_normal()).then_some((k, k));
    Law::Conductance(
        NonlinearLaw::new(label, move |dp| orifice_flow(dp, area, cd, rho, dp_cr))
            .with_value_bound_if(bound),
    )
}

/// A variable orifice whose area is `width * ramp(offset + sign * m, clearance)`, `m` the
/// modulating signal (spool or flapper position), as an R law in conductance form:
/// `Q = K(m) g(dp)` with exact `dQ/d(dp)` and `dQ/dm`.
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
    width: f64,
    offset: f64,
    sign: f64,
    clearance: f64,
    fluid: OrificeFluid,
) -> Law {
    let OrificeFluid { cd, rho, dp_cr } = fluid;
    let k = cd * width * (2.0 / rho).sqrt();
    let range = crate::bond_graph::VALUE_BOUND_RANGE;
    let k_bound = k.abs() * (sign.abs() + offset.abs() + 0.5 * clearance.abs());
    let bound = (k_bound.is_finite()
        && (dp_cr * dp_cr).is_normal()
        && sign.abs() <= 1024.0
        && offset.abs() <= range
        && clearance.abs() <= range)
        .then_some((k_bound, k_bound));
    Law::Conductance(
        NonlinearLaw::modulated(label, move |dp, m| {
            let (a, da) = smooth_ramp(offset + sign * m, clearance);
            let (y, dy) = regularised_sqrt(dp, dp_cr);
            (k * a * y, k * a * dy, k * sign * da * y)
        })
        .with_value_bound_if(bound),
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
}
