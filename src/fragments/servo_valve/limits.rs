//! The physical limits of the servo valve as smooth laws (exact derivatives, finite Jacobian):
//! the spool's end stops and the floor of the chamber pressures (cavitation). The third limit of
//! the actuator, the power amplifier's output saturation, belongs to the controller.
//!
//! Both are built on the softplus `sp(z) = ln(1 + e^z)`, a ramp `max(z, 0)` rounded over
//! `|z| ~ 1` whose tails are exponentially small: a limit of width `delta` at a distance `D`
//! changes the model at its operating point by `e^(-D/delta)`, which is below round-off for the
//! defaults (`D/delta` = 20 for the stops, 3500 for the chambers). The linearisation at rest,
//! and so the fit to `G_est`, does not see them.
//!
//! Each law's value is also written once generic in [`Real`] ([`stop_spring_force`],
//! [`stop_damping_force`], [`chamber_pressure`], on [`softplus_value`] and [`logistic_value`]),
//! the same operations as its closure and so the same doubles; the laws' hyper-dual forms
//! ([`NonlinearLaw::with_hyper`]) run it with the constants' derivatives.

use crate::bond_graph::{Law, NonlinearLaw};
use crate::math::dual::{Dual, HyperDual, Real};

/// Beyond this |z|, `e^-|z|` is 0 in double precision (the smallest subnormal is e^-745.1).
/// The chambers sit at z = 3500: asking libm for that zero takes its underflow path, which
/// sets errno through a wrapper and cost a fifth of the servo valve's run time.
const UNDERFLOW: f64 = 746.0;

/// `(ln(1 + e^z), 1 / (1 + e^-z))`, without overflow.
pub fn softplus(z: f64) -> (f64, f64) {
    if z > UNDERFLOW {
        (z, 1.0)
    } else if z < -UNDERFLOW {
        (0.0, 0.0)
    } else if z > 0.0 {
        let e = crate::math::exp(-z);
        (z + crate::math::ln_1p(e), 1.0 / (1.0 + e))
    } else {
        let e = crate::math::exp(z);
        (crate::math::ln_1p(e), e / (1.0 + e))
    }
}

/// `ln(1 + e^z)` in any [`Real`]: [`softplus`]'s value, the same operations and branches (on
/// the value of `z`), so the same doubles.
pub fn softplus_value<S: Real>(z: S) -> S {
    let zv = z.value();
    if zv > UNDERFLOW {
        z
    } else if zv < -UNDERFLOW {
        S::cst(0.0)
    } else if zv > 0.0 {
        z + S::ln_1p(S::exp(-z))
    } else {
        S::ln_1p(S::exp(z))
    }
}

/// The logistic `1 / (1 + e^-z)` in any [`Real`]: [`logistic`], the same operations and
/// branches (on the value of `z`), so the same doubles.
pub fn logistic_value<S: Real>(z: S) -> S {
    let zv = z.value();
    if zv > UNDERFLOW {
        S::cst(1.0)
    } else if zv < -UNDERFLOW {
        S::cst(0.0)
    } else if zv > 0.0 {
        S::cst(1.0) / (S::exp(-z) + 1.0)
    } else {
        let e = S::exp(z);
        e / (e + 1.0)
    }
}

/// The logistic `1 / (1 + e^-z)`, [`softplus`]'s derivative: its second value, the same
/// operations and so the same bits, without the logarithm a law that needs only the derivative
/// would otherwise pay for (libm's `log1p` is not known to the compiler as free of effects, so
/// an unused result is still computed).
pub fn logistic(z: f64) -> f64 {
    if z > UNDERFLOW {
        1.0
    } else if z < -UNDERFLOW {
        0.0
    } else if z > 0.0 {
        1.0 / (1.0 + crate::math::exp(-z))
    } else {
        let e = crate::math::exp(z);
        e / (1.0 + e)
    }
}

/// Stiffness of the spool end stops \[N/m\]: the largest pilot force, `A_s p_s` (275 N with the
/// defaults), is held within a twentieth of the stroke past the stop.
pub fn stop_stiffness<S: Real>(a_s: S, p_supply: S, x_max: S) -> S {
    a_s * 20.0 * p_supply / x_max
}

/// The width `delta = x_max / 20` of the spool end stops' contact laws.
#[inline]
pub fn stop_width<S: Real>(x_max: S) -> S {
    x_max / 20.0
}

/// The force of the spool end stops' contact spring at the spool position `x`, in any
/// [`Real`]: `k delta (sp((x - x_max)/delta) - sp((-x - x_max)/delta))`, `delta` =
/// [`stop_width`]; the value of [`spool_stop_spring`]'s law, the same operations.
pub fn stop_spring_force<S: Real>(x_max: S, k: S, x: S) -> S {
    let delta = stop_width(x_max);
    k * delta * (softplus_value((x - x_max) / delta) - softplus_value((-x - x_max) / delta))
}

/// The spool end stops' contact spring: `F(x) = k delta (sp((x - x_max)/delta) - sp((-x - x_max)/delta))`
/// pushes the spool back inside `|x| <= x_max` (`delta = x_max / 20`), a law on the spool port of
/// the spring field (so its state is the spool position `x`, which the field already holds).
///
/// A stored-energy law: with `d/dz Li₂(-e^z) = -sp(z)` its energy is
/// `E(x) = -k delta² (Li₂(-e^z₊) + Li₂(-e^z₋)) + 2 k delta² Li₂(-e^(-x_max/delta))`,
/// `z± = (±x - x_max)/delta`, zero at `x = 0` and the exact integral of `F`; so the contact's
/// energy is in the model's `energy` and it returns what it takes.
///
/// Its value bound ([`NonlinearLaw::with_value_bound`]): `|F(x)| <= k x² + k (1/4 + delta)`.
/// Both softplus terms are nonnegative, so `|F| <= k delta max(sp(z₊), sp(z₋))`, and
/// `sp(z) <= max(z, 0) + ln 2` with `z± <= |x|/delta`: `|F| <= k |x| + k delta ln 2`; then
/// `|x| <= x² + 1/4` (`(|x| - 1/2)² >= 0`) and `ln 2 < 1` leaves `0.3 k delta` for rounding.
/// Declared for `x_max > 0` (a positive `delta`: no 0/0 at the stop) and finite `k`.
///
/// Its hyper-dual form ([`NonlinearLaw::with_hyper`]) is [`stop_spring_force`] with the
/// constants' derivatives.
pub fn spool_stop_spring(x_max: impl Into<Dual>, k: impl Into<Dual>) -> NonlinearLaw {
    let (x_max_d, k_d) = (x_max.into(), k.into());
    let (x_max, k) = (x_max_d.v, k_d.v);
    let delta = stop_width(x_max);
    let e_side =
        move |x: f64| -> f64 { -k * delta * delta * dilog_of_minus_exp((x - x_max) / delta) };
    let e0 = 2.0 * e_side(0.0);
    NonlinearLaw::new("spool stop spring", move |x| {
        let (sp_hi, s_hi) = softplus((x - x_max) / delta);
        let (sp_lo, s_lo) = softplus((-x - x_max) / delta);
        (k * delta * (sp_hi - sp_lo), k * (s_hi + s_lo))
    })
    .with_energy(move |x| e_side(x) + e_side(-x) - e0)
    .with_energy_bound(
        2.0 * k.abs(),
        2.0 * k.abs() * (x_max * x_max + delta * delta * DILOG_BOUND) + e0.abs(),
    )
    .with_value_bound_if(
        (x_max > 0.0 && x_max.is_finite() && k.is_finite())
            .then_some((k.abs(), k.abs() * (0.25 + delta))),
    )
    .with_hyper(move |x, _| stop_spring_force(HyperDual::from(x_max_d), HyperDual::from(k_d), x))
}

/// The contact damping coefficient `c_0 = 2 zeta sqrt(k m_v)`, `zeta` = 0.5, of the spool end
/// stops ([`spool_stop_damping`]).
#[inline]
pub fn stop_damping_coefficient<S: Real>(k: S, m_v: S) -> S {
    (k * m_v).sqrt() * (2.0 * 0.5)
}

/// The force of the spool end stops' contact damping at the spool speed `v` and position `x`,
/// in any [`Real`]: `c_0 (sp'(z₊) + sp'(z₋)) v` (`z±` as in [`stop_spring_force`], `c_0` =
/// [`stop_damping_coefficient`]); the value of [`spool_stop_damping`]'s law, the same
/// operations.
pub fn stop_damping_force<S: Real>(x_max: S, c0: S, v: S, x: S) -> S {
    let delta = stop_width(x_max);
    let s_hi = logistic_value((x - x_max) / delta);
    let s_lo = logistic_value((-x - x_max) / delta);
    c0 * (s_hi + s_lo) * v
}

/// The spool end stops' contact damping: `e = c(x) v` with `c(x) = c_0 (sp'(z₊) + sp'(z₋))`
/// (`z±` as in [`spool_stop_spring`]), present only at the stops, as an R law in resistance form
/// on the spool's 1-junction modulated by the spool position `x`; it dissipates `c(x) v² >= 0`.
/// `c_0 = 2 zeta sqrt(k m_v)` with `zeta` = 0.5: the spool does not bounce.
///
/// Its value bound ([`NonlinearLaw::with_value_bound`]): `|e| <= 2 c_0 v² + c_0`, `s = max(|v|,
/// |x|)`. The logistic `sp'` lies in `[0, 1]`, so `0 <= c(x) <= 2 c_0` and `|e| <= 2 c_0 |v|`;
/// then `|v| <= v² + 1/4` leaves `c_0 / 2` for rounding. Declared for `x_max > 0` (a positive
/// `delta`) and a finite `c_0`.
///
/// Its hyper-dual form ([`NonlinearLaw::with_hyper`]) is [`stop_damping_force`] with the
/// constants' derivatives.
pub fn spool_stop_damping(x_max: impl Into<Dual>, k: impl Into<Dual>, m_v: impl Into<Dual>) -> Law {
    let x_max_d = x_max.into();
    let c0_d = stop_damping_coefficient(k.into(), m_v.into());
    let (x_max, c0) = (x_max_d.v, c0_d.v);
    let delta = stop_width(x_max);
    let bound =
        (x_max > 0.0 && x_max.is_finite() && c0.is_finite()).then_some((2.0 * c0.abs(), c0.abs()));
    Law::Nonlinear(
        NonlinearLaw::modulated("spool stop damping", move |v, x| {
            let s_hi = logistic((x - x_max) / delta);
            let s_lo = logistic((-x - x_max) / delta);
            let c = c0 * (s_hi + s_lo);
            // d sigma/dz = sigma (1 - sigma)
            let dc = c0 * (s_hi * (1.0 - s_hi) - s_lo * (1.0 - s_lo)) / delta;
            (c * v, c, dc * v)
        })
        .with_value_bound_if(bound)
        .with_hyper(move |v, x| {
            stop_damping_force(HyperDual::from(x_max_d), HyperDual::from(c0_d), v, x)
        }),
    )
}

/// Absolute pressure below which the oil releases its dissolved air and the chamber becomes a
/// cavity, as gauge pressure \[Pa\]: 0.1 bar absolute (air release in mineral oil starts well
/// above the vapour pressure), -0.913 bar gauge at sea level.
pub const CAVITATION_PRESSURE: f64 = 0.1e5 - 1.01325e5;

/// Width of the cavitation transition \[Pa\] (0.02 bar).
pub const CAVITATION_WIDTH: f64 = 2e3;

/// The pressure of an oil chamber of stiffness `k = beta / V` holding the compressed oil volume
/// `q`, in any [`Real`]: `p_c + s sp((k q - p_c) / s)`; the value of [`chamber`]'s law, the
/// same operations.
pub fn chamber_pressure<S: Real>(k: S, q: S) -> S {
    softplus_value((k * q - CAVITATION_PRESSURE) / CAVITATION_WIDTH) * CAVITATION_WIDTH
        + CAVITATION_PRESSURE
}

/// The chamber law `p(q)` of an oil volume `volume` with bulk modulus `beta` and a cavitation
/// floor: `p = p_c + s sp((q beta / volume - p_c) / s)` with `p_c` = [`CAVITATION_PRESSURE`] and
/// `s` = [`CAVITATION_WIDTH`]. Above the floor it is the linear law `p = q beta / V` (to
/// `e^-3500` at the rest pressure); as oil is drawn out of a chamber below the floor, the
/// pressure stays above `p_c` and the effective bulk modulus `beta sp'` falls to zero: the
/// chamber opens a cavity instead of pulling a tension. The state is still the compressed (or
/// missing) oil volume \[m^3\].
///
/// Its stored energy is exact (the FMU reports it at every communication point, where a
/// quadrature of the law cost a fifth of the servo valve's run time): with `z = (k q - p_c)/s`
/// and `sp(z) = z + sp(-z)` the law is `p = k q + s sp(-z)`, so
/// `E(q) = k q²/2 + (s²/k) (Li₂(-e^-z) - Li₂(-e^-z₀))`, `z₀ = z(0)`, since
/// `d/dz Li₂(-e^-z) = sp(-z)`. Above the floor the second term is below e^-45 of the first.
///
/// Its value bound ([`NonlinearLaw::with_value_bound`]): `|p(q)| <= k q² + 2 (|p_c| + s) +
/// k/4`. With `sp(z) <= max(z, 0) + ln 2` and `z <= (k |q| + |p_c|)/s`,
/// `|p| <= |p_c| + k |q| + |p_c| + s ln 2`, and `|q| <= q² + 1/4`; `ln 2 < 1` leaves `0.3 s`
/// (600 Pa) for rounding. For `|q| <= VALUE_BOUND_RANGE`, `k q` stays finite for any `k`
/// below 2^520 (declared only then).
///
/// Its hyper-dual form ([`NonlinearLaw::with_hyper`]) is [`chamber_pressure`] with the
/// stiffness's derivative.
pub fn chamber(volume: impl Into<Dual>, beta: impl Into<Dual>) -> Law {
    let k_d = beta.into() / volume.into();
    let k = k_d.v;
    let (pc, s) = (CAVITATION_PRESSURE, CAVITATION_WIDTH);
    let tail = move |q: f64| dilog_of_minus_exp(-(k * q - pc) / s);
    let tail0 = tail(0.0);
    Law::Nonlinear(
        NonlinearLaw::new("oil chamber with cavitation", move |q| {
            let (sp, sig) = softplus((k * q - pc) / s);
            (pc + s * sp, k * sig)
        })
        .with_energy(move |q| 0.5 * k * q * q + (s * s / k) * (tail(q) - tail0))
        .with_energy_bound(
            1.5 * k.abs(),
            (pc * pc + s * s * (DILOG_BOUND + tail0.abs())) / k.abs(),
        )
        .with_value_bound_if(
            (k.abs() < 2f64.powi(520)).then_some((k.abs(), 2.0 * (pc.abs() + s) + 0.25 * k.abs())),
        )
        .with_hyper(move |q, _| chamber_pressure(HyperDual::from(k_d), q)),
    )
}

/// `|Li₂(-e^w)| <= w²/2 + DILOG_BOUND` for every real `w`: `Li₂(-e^w)` lies in `[-π²/12, 0)` for
/// `w <= 0`, and for `w > 0` the inversion `Li₂(-e^w) = -π²/6 - w²/2 - Li₂(-e^-w)` with
/// `-Li₂(-e^-w)` in `(0, π²/12]`. It bounds the stored energy of the laws above by a quadratic:
/// with `(a - b)² <= 2 a² + 2 b²`,
/// - the chamber, `w = (p_c - k q)/s`: `(s²/k) |Li₂| <= p_c²/k + k q² + s² DILOG_BOUND / k`, so
///   `|E(q)| <= 1.5 k q² + (p_c² + s² (DILOG_BOUND + |Li₂(-e^-z₀)|)) / k`;
/// - a stop side, `w = (x - x_max)/delta`: `k delta² |Li₂| <= k (x² + x_max²) + k delta²
///   DILOG_BOUND`, two sides and `e0`: `|E(x)| <= 2 k x² + 2 k (x_max² + delta² DILOG_BOUND) +
///   |e0|`.
const DILOG_BOUND: f64 = std::f64::consts::PI * std::f64::consts::PI / 6.0;

/// `Li₂(-e^w)`, the dilogarithm `Li₂(y) = -∫₀^y ln(1 - t)/t dt` at `y = -e^w`.
///
/// For `y` in [-1, 0) ('t Hooft and Veltman's method) the series in `u = -ln(1 - y)`,
/// `Li₂ = Σ B_n u^(n+1)/(n+1)!` with the Bernoulli numbers, converges fast: `|u| <= ln 2`,
/// and the terms up to `u^15` leave an error below 1e-16. For `y < -1` the inversion
/// `Li₂(y) = -π²/6 - ln²(-y)/2 - Li₂(1/y)` brings the argument back into [-1, 0).
fn dilog_of_minus_exp(w: f64) -> f64 {
    /// `B_n/(n+1)!` for n = 0, 1, 2, 4, 6, ..., 14 (the odd Bernoulli numbers past B_1 vanish).
    const C: [f64; 9] = [
        1.0,
        -1.0 / 4.0,
        1.0 / 36.0,
        -1.0 / 3600.0,
        1.0 / 211_680.0,
        -1.0 / 10_886_400.0,
        1.0 / 526_901_760.0,
        -691.0 / (2730.0 * 6_227_020_800.0),
        7.0 / (6.0 * 1_307_674_368_000.0),
    ];
    let series = |w: f64| {
        if w < -UNDERFLOW {
            return 0.0; // e^w is 0 (and libm's underflow path is slow)
        }
        // y = -e^w in [-1, 0): u = -ln(1 + e^w).
        let u = -crate::math::ln_1p(crate::math::exp(w));
        let u2 = u * u;
        let mut sum = C[0] * u + C[1] * u2;
        let mut p = u * u2;
        for c in &C[2..] {
            sum += c * p;
            p *= u2;
        }
        sum
    };
    if w <= 0.0 {
        series(w)
    } else {
        -std::f64::consts::PI.powi(2) / 6.0 - 0.5 * w * w - series(-w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The declared bounds `|E(x)| <= K x² + C` hold from the operating point to far beyond
    /// the limits, on both sides (each law's own energy function, sampled).
    #[test]
    fn the_stored_energies_stay_within_their_declared_bounds() {
        let Law::Nonlinear(chamber) = chamber(1.2e-6, 1.4e9) else {
            panic!("the chamber law is nonlinear")
        };
        let stop = spool_stop_spring(5e-4, stop_stiffness(2.8e-5, 2.1e7, 5e-4));
        for (law, scale) in [(&chamber, 1.2e-6 * 2.1e7 / 1.4e9), (&stop, 5e-4)] {
            let (k, c) = law.energy_bound.expect("a declared bound");
            let energy = law.energy.as_ref().expect("an energy function");
            for i in -4000..=4000 {
                let x = scale * (i as f64 / 100.0).powi(3);
                let e = energy(x);
                assert!(
                    e.is_finite() && e.abs() <= k * x * x + c,
                    "{}: E({x}) = {e}",
                    law.label
                );
            }
        }
    }

    #[test]
    fn softplus_skips_libm_only_where_its_answer_is_known() {
        // The formula without the shortcut, for comparison bit by bit.
        let formula = |z: f64| {
            if z > 0.0 {
                let e = crate::math::exp(-z);
                (z + crate::math::ln_1p(e), 1.0 / (1.0 + e))
            } else {
                let e = crate::math::exp(z);
                (crate::math::ln_1p(e), e / (1.0 + e))
            }
        };
        for z in [
            -3500.0, -746.5, -746.0, -745.5, -700.0, -1.0, 0.0, 1.0, 700.0, 745.5, 746.0, 746.5,
            3500.0,
        ] {
            let (a, b) = (softplus(z), formula(z));
            assert_eq!(a.0.to_bits(), b.0.to_bits(), "sp({z})");
            assert_eq!(a.1.to_bits(), b.1.to_bits(), "sp'({z})");
        }
    }

    /// Arguments on both sides of `±UNDERFLOW`, where softplus and the logistic leave libm
    /// for their limits.
    const EXP_EDGES: [f64; 6] = [745.9, 746.0, 746.1, -745.9, -746.0, -746.1];

    #[test]
    fn the_logistic_is_softplus_derivative_to_the_bit() {
        let mut zs = vec![
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            -5e-324,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        zs.extend(EXP_EDGES);
        // Both signs over the decades a stop's z spans (-20 at rest, 0 at the stop).
        for k in -300..=300 {
            zs.push(f64::from(k) * 0.137);
            zs.push(crate::math::powf(10.0, f64::from(k) / 100.0));
            zs.push(-crate::math::powf(10.0, f64::from(k) / 100.0));
        }
        for z in zs {
            assert_eq!(logistic(z).to_bits(), softplus(z).1.to_bits(), "z {z}");
        }
    }

    #[test]
    fn dilogarithm_matches_its_series_and_its_known_values() {
        // Li₂(-1) = -π²/12, and for small |y| the defining series Σ y^k/k².
        let pi2 = std::f64::consts::PI.powi(2);
        assert!((dilog_of_minus_exp(0.0) + pi2 / 12.0).abs() < 1e-15);
        for w in [-30.0, -5.0, -2.0] {
            let y = -crate::math::exp(w);
            let direct: f64 = (1..200).map(|k| y.powi(k) / (k * k) as f64).sum();
            assert!((dilog_of_minus_exp(w) - direct).abs() < 1e-15, "w {w}");
        }
        // Across the inversion: d/dw Li₂(-e^w) = -ln(1 + e^w).
        for w in [-1.0, -1e-3, 1e-3, 1.0, 10.0] {
            let h = 1e-5;
            let fd = (dilog_of_minus_exp(w + h) - dilog_of_minus_exp(w - h)) / (2.0 * h);
            assert!(
                (fd + crate::math::ln_1p(crate::math::exp(w))).abs() < 1e-8 * (1.0 + fd.abs()),
                "w {w}"
            );
        }
    }

    /// `int_0^x phi(s) ds` by the trapezoidal rule on 200 000 intervals.
    fn trapezoid(law: &NonlinearLaw, x: f64) -> f64 {
        let n = 200_000;
        let h = x / n as f64;
        (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n { 0.5 } else { 1.0 };
                w * law.eval(i as f64 * h, 0.0).0
            })
            .sum::<f64>()
            * h
    }

    #[test]
    fn chamber_energy_is_the_integral_of_its_law() {
        let Law::Nonlinear(ch) = chamber(1.5e-4, 1.4e9) else {
            unreachable!()
        };
        let energy = ch.energy.as_ref().unwrap();
        let k = 1.4e9 / 1.5e-4;
        // Above the floor: the linear chamber's k q²/2, to rounding.
        for p in [1e5, 70e5, 280e5] {
            let q = p / k;
            assert!((energy(q) - 0.5 * k * q * q).abs() <= 1e-14 * 0.5 * k * q * q);
        }
        // Through the cavitation knee: against a fine trapezoidal integral of the law.
        for p_target in [-0.5e5, -0.9e5, -0.913e5] {
            let q = p_target / k;
            let trapezoid = trapezoid(&ch, q);
            let e = energy(q);
            assert!(
                (e - trapezoid).abs() <= 1e-8 * e.abs(),
                "{p_target}: {e} vs {trapezoid}"
            );
        }
        // Deep in the cavity the energy grows linearly (p stays at the floor).
        let q = -1e-6;
        let e = energy(q);
        assert!(e.is_finite() && e > 0.0, "{e}");
    }

    #[test]
    fn stop_spring_energy_is_the_integral_of_its_law() {
        let (x_max, k) = (4e-4, 7e6);
        let spring = spool_stop_spring(x_max, k);
        let energy = spring.energy.as_ref().unwrap();
        assert_eq!(energy(0.0), 0.0);
        // Against a fine trapezoidal integral of the law, inside the stroke, at and past the
        // stops, on both sides.
        for x in [1e-4, 3.9e-4, 4e-4, 4.3e-4, -4.1e-4, -5e-4] {
            let trapezoid = trapezoid(&spring, x);
            let e = energy(x);
            assert!(e >= 0.0, "{x}: {e}");
            assert!(
                (e - trapezoid).abs() <= 1e-8 * trapezoid.abs() + 1e-22,
                "{x}: {e} vs {trapezoid}"
            );
        }
    }

    #[test]
    fn laws_have_exact_derivatives_and_their_limits() {
        let (x_max, k) = (4e-4, 7e6);
        let spring = spool_stop_spring(x_max, k);
        let Law::Nonlinear(damping) = spool_stop_damping(x_max, k, 3e-3) else {
            unreachable!()
        };
        for &x in &[-5e-4, -4.1e-4, -3.9e-4, 0.0, 1e-4, 3.95e-4, 4.2e-4] {
            let hx = 1e-10;
            let (f, df, _) = spring.eval(x, 0.0);
            let fx = (spring.eval(x + hx, 0.0).0 - spring.eval(x - hx, 0.0).0) / (2.0 * hx);
            assert!((df - fx).abs() <= 1e-5 * (1.0 + fx.abs()), "x {x}");
            // odd in x
            assert!((spring.eval(-x, 0.0).0 + f).abs() <= 1e-12 * (1.0 + f.abs()));
            for &v in &[-0.3, 0.0, 0.2] {
                let (e, de_dv, de_dx) = damping.eval(v, x);
                let hv = 1e-6;
                let fv = (damping.eval(v + hv, x).0 - damping.eval(v - hv, x).0) / (2.0 * hv);
                let fx = (damping.eval(v, x + hx).0 - damping.eval(v, x - hx).0) / (2.0 * hx);
                assert!((de_dv - fv).abs() <= 1e-6 * (1.0 + fv.abs()), "x {x} v {v}");
                assert!((de_dx - fx).abs() <= 1e-5 * (1.0 + fx.abs()), "x {x} v {v}");
                // a damper: never delivers power, and odd in v
                assert!(e * v >= 0.0, "x {x} v {v}");
                assert!((damping.eval(-v, x).0 + e).abs() <= 1e-12 * (1.0 + e.abs()));
            }
        }
        // inside the stroke: no force (e^-20 of the stiffness at null), at the stop: k delta ln 2
        let (f0, k0, _) = spring.eval(0.0, 0.0);
        assert!(f0 == 0.0 && k0 < 1e-8 * k, "{k0}");
        let (fs, _, _) = spring.eval(x_max, 0.0);
        assert!((fs - k * 2e-5 * crate::math::ln(2f64)).abs() < 1e-9 * fs);

        let Law::Nonlinear(ch) = chamber(1.5e-4, 1.4e9) else {
            unreachable!()
        };
        let k = 1.4e9 / 1.5e-4;
        // linear in the working range, exactly
        for &p in &[70e5, 1e5, 280e5] {
            let (e, de, _) = ch.eval(p / k, 0.0);
            assert!((e - p).abs() <= 1e-9 * p && (de - k).abs() <= 1e-12 * k);
        }
        // never below the cavitation floor, the stiffness vanishing there
        for &q in &[-1e-5, -1e-7, -1.0] {
            let (e, de, _) = ch.eval(q, 0.0);
            assert!(
                e >= CAVITATION_PRESSURE && de >= 0.0 && de < 1e-3 * k,
                "q {q}: {e} {de}"
            );
        }
        for &q in &[-1e-9, -9.8e-11, 0.0, 1e-10] {
            let h = 1e-16;
            let fd = (ch.eval(q + h, 0.0).0 - ch.eval(q - h, 0.0).0) / (2.0 * h);
            let de = ch.eval(q, 0.0).1;
            assert!((de - fd).abs() <= 1e-5 * k, "q {q}: {de} vs {fd}");
        }
    }

    use crate::fragments::law_checks::{
        assert_hand_derivatives, assert_mixed, assert_same_bits, grid,
    };

    /// The default spool stroke, a stop stiffness of its order and the spool's mass.
    const X_MAX: f64 = 4e-4;
    const K_STOP: f64 = 7e6;
    const M_V: f64 = 3e-3;

    #[test]
    fn softplus_and_logistic_in_any_real_are_the_f64_ones() {
        let mut zs = grid(1.0);
        zs.extend(EXP_EDGES);
        zs.extend([3500.0, -3500.0, f64::NAN]);
        for z in zs {
            let (sp, sig) = softplus(z);
            assert_eq!(softplus_value(z).to_bits(), sp.to_bits(), "sp({z})");
            assert_eq!(logistic_value(z).to_bits(), sig.to_bits(), "sp'({z})");
            let d = softplus_value(Dual::new(z, 1.0));
            assert_eq!(d.v.to_bits(), sp.to_bits());
            if sig.is_finite() && sp.is_finite() {
                assert!(
                    (d.d - sig).abs() <= 1e-15 * sig,
                    "sp'({z}): {} vs {sig}",
                    d.d
                );
                // sp'' = sigma (1 - sigma) = e^-|z| / (1 + e^-|z|)², the logistic's derivative
                let l = logistic_value(Dual::new(z, 1.0));
                let e = crate::math::exp(-z.abs());
                let exact = e / ((1.0 + e) * (1.0 + e));
                assert!(
                    (l.d - exact).abs() <= 1e-14 * exact,
                    "sp''({z}): {} vs {exact}",
                    l.d
                );
            }
        }
    }

    #[test]
    fn stop_spring_in_hyper_dual_numbers() {
        let law = spool_stop_spring(X_MAX, K_STOP);
        let xs = grid(X_MAX);
        assert_same_bits(
            &law,
            |x, _| stop_spring_force(X_MAX, K_STOP, x),
            &xs,
            &[0.0],
        );
        let dual = |x, _| stop_spring_force(Dual::from(X_MAX), Dual::from(K_STOP), x);
        assert_hand_derivatives(&law, dual, &xs, &[0.0], 1e-12, |_, _| (0.0, 0.0));
        // d²F/dx dx_max: the stiffness k (sp'(z₊) + sp'(z₋)) moves with the stop over its
        // width delta = x_max/20 (not at null, where z± = -20 whatever x_max).
        for x in [1e-4, 3.9e-4, 4e-4, 4.2e-4, -4.1e-4] {
            let law_of = |x_max: Dual| spool_stop_spring(x_max, K_STOP);
            assert_mixed(law_of, X_MAX, 1e-4, X_MAX / 20.0, x, 0.0, false);
        }
    }

    #[test]
    fn stop_damping_in_hyper_dual_numbers() {
        let Law::Nonlinear(law) = spool_stop_damping(X_MAX, K_STOP, M_V) else {
            unreachable!()
        };
        let c0 = stop_damping_coefficient(K_STOP, M_V);
        let (vs, xs) = (grid(0.3), grid(X_MAX));
        assert_same_bits(&law, |v, x| stop_damping_force(X_MAX, c0, v, x), &vs, &xs);
        let dual = |v, x| stop_damping_force(Dual::from(X_MAX), Dual::from(c0), v, x);
        // The hand-coded de/dx = c_0 v (s₊(1 - s₊) - s₋(1 - s₋)) / delta cancels twice: in
        // the difference near null, where the two sides are alike, and in 1 - s past a stop,
        // where s -> 1 (a few ulps of s, e^-z of 1 - s). Its error is then a few ulps of
        // c_0 |v| (s₊ + s₋) / delta, its scale.
        let scale = |v: f64, x: f64| {
            let delta = stop_width(X_MAX);
            let s_hi = logistic((x - X_MAX) / delta);
            let s_lo = logistic((-x - X_MAX) / delta);
            (0.0, (c0 * v * (s_hi + s_lo) / delta).abs())
        };
        assert_hand_derivatives(&law, dual, &vs, &xs, 1e-12, scale);
        let law_of = |x_max: Dual| {
            let Law::Nonlinear(law) = spool_stop_damping(x_max, K_STOP, M_V) else {
                unreachable!()
            };
            law
        };
        for (v, x) in [(0.2, 3.9e-4), (-0.3, 4e-4), (0.1, -4.2e-4)] {
            for along_m in [false, true] {
                assert_mixed(law_of, X_MAX, 1e-4, X_MAX / 20.0, v, x, along_m);
            }
        }
    }

    #[test]
    fn chamber_in_hyper_dual_numbers() {
        let (volume, beta) = (1.5e-4, 1.4e9);
        let Law::Nonlinear(law) = chamber(volume, beta) else {
            unreachable!()
        };
        let k = beta / volume;
        // From deep in the cavity to far above the supply pressure, through the knee at
        // q = p_c / k (-1e-8 m³).
        let mut qs = grid(1e-8);
        qs.extend([-9.8e-9, -9.7e-9, -9.9e-9, 2e-6, 3e-6]);
        assert_same_bits(&law, |q, _| chamber_pressure(k, q), &qs, &[0.0]);
        let dual = |q, _| chamber_pressure(Dual::from(k), q);
        assert_hand_derivatives(&law, dual, &qs, &[0.0], 1e-12, |_, _| (0.0, 0.0));
        // d²p/dq dbeta through the knee: k sp'((k q - p_c)/s) varies in beta over s V / |q|
        // (3e7 Pa there).
        let law_of = |beta: Dual| {
            let Law::Nonlinear(law) = chamber(volume, beta) else {
                unreachable!()
            };
            law
        };
        for z in [-2.0, 0.0, 1.5] {
            let q = (CAVITATION_PRESSURE + z * CAVITATION_WIDTH) / k;
            let scale = CAVITATION_WIDTH * volume / q.abs();
            assert_mixed(law_of, beta, 1e-4, scale, q, 0.0, false);
        }
    }
}
