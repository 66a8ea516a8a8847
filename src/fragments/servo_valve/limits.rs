//! The physical limits of the servo valve as smooth laws (exact derivatives, finite Jacobian):
//! the spool's end stops and the floor of the chamber pressures (cavitation). The third limit of
//! the actuator, the power amplifier's output saturation, belongs to the controller.
//!
//! Both are built on the softplus `sp(z) = ln(1 + e^z)`, a ramp `max(z, 0)` rounded over
//! `|z| ~ 1` whose tails are exponentially small: a limit of width `delta` at a distance `D`
//! changes the model at its operating point by `e^(-D/delta)`, which is below round-off for the
//! defaults (`D/delta` = 20 for the stops, 3500 for the chambers). The linearisation at rest,
//! and so the fit to `G_est`, does not see them.

use crate::bond_graph::{Law, NonlinearLaw};

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
        let e = (-z).exp();
        (z + e.ln_1p(), 1.0 / (1.0 + e))
    } else {
        let e = z.exp();
        (e.ln_1p(), e / (1.0 + e))
    }
}

/// Stiffness of the spool end stops \[N/m\]: the largest pilot force, `A_s p_s` (275 N with the
/// defaults), is held within a twentieth of the stroke past the stop.
pub fn stop_stiffness(a_s: f64, p_supply: f64, x_max: f64) -> f64 {
    20.0 * a_s * p_supply / x_max
}

/// The spool end stops: a force `F(x) = k delta (sp((x - x_max)/delta) - sp((-x - x_max)/delta))`
/// pushing the spool back inside `|x| <= x_max` (`delta = x_max / 20`), plus a contact damping
/// `c(x) v` with `c(x) = c_0 (sp'(..) + sp'(..))`, present only at the stops.
///
/// As an R law in resistance form on the spool's 1-junction, modulated by the spool position
/// `x`: `e = F(x) + c(x) f`, with `f` the spool velocity. The damping part dissipates; the
/// stop force is the contact spring, whose energy is not a state of the model (the law acts
/// within a few micrometres of the stop, where the spool's own spring energy is not of interest).
/// `c_0 = 2 zeta sqrt(k m_v)` with `zeta` = 0.5: the spool does not bounce.
pub fn spool_stop(x_max: f64, k: f64, m_v: f64) -> Law {
    let delta = x_max / 20.0;
    let c0 = 2.0 * 0.5 * (k * m_v).sqrt();
    Law::Nonlinear(NonlinearLaw::modulated("spool stop", move |v, x| {
        let (sp_hi, s_hi) = softplus((x - x_max) / delta);
        let (sp_lo, s_lo) = softplus((-x - x_max) / delta);
        let force = k * delta * (sp_hi - sp_lo);
        let dforce = k * (s_hi + s_lo);
        // d sigma/dz = sigma (1 - sigma)
        let c = c0 * (s_hi + s_lo);
        let dc = c0 * (s_hi * (1.0 - s_hi) - s_lo * (1.0 - s_lo)) / delta;
        (force + c * v, c, dforce + dc * v)
    }))
}

/// Absolute pressure below which the oil releases its dissolved air and the chamber becomes a
/// cavity, as gauge pressure \[Pa\]: 0.1 bar absolute (air release in mineral oil starts well
/// above the vapour pressure), -0.913 bar gauge at sea level.
pub const CAVITATION_PRESSURE: f64 = 0.1e5 - 1.01325e5;

/// Width of the cavitation transition \[Pa\] (0.02 bar).
pub const CAVITATION_WIDTH: f64 = 2e3;

/// The chamber law `p(q)` of an oil volume `volume` with bulk modulus `beta` and a cavitation
/// floor: `p = p_c + s sp((q beta / volume - p_c) / s)` with `p_c` = [`CAVITATION_PRESSURE`] and
/// `s` = [`CAVITATION_WIDTH`]. Above the floor it is the linear law `p = q beta / V` (to
/// `e^-3500` at the rest pressure); as oil is drawn out of a chamber below the floor, the
/// pressure stays above `p_c` and the effective bulk modulus `beta sp'` falls to zero: the
/// chamber opens a cavity instead of pulling a tension. The state is still the compressed (or
/// missing) oil volume \[m^3\].
pub fn chamber(volume: f64, beta: f64) -> Law {
    let k = beta / volume;
    let (pc, s) = (CAVITATION_PRESSURE, CAVITATION_WIDTH);
    Law::Nonlinear(NonlinearLaw::new("oil chamber with cavitation", move |q| {
        let (sp, sig) = softplus((k * q - pc) / s);
        (pc + s * sp, k * sig)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn softplus_skips_libm_only_where_its_answer_is_known() {
        // The formula without the shortcut, for comparison bit by bit.
        let formula = |z: f64| {
            if z > 0.0 {
                let e = (-z).exp();
                (z + e.ln_1p(), 1.0 / (1.0 + e))
            } else {
                let e = z.exp();
                (e.ln_1p(), e / (1.0 + e))
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

    #[test]
    fn laws_have_exact_derivatives_and_their_limits() {
        let stop = spool_stop(4e-4, 7e6, 3e-3);
        let Law::Nonlinear(stop) = stop else {
            unreachable!()
        };
        for &x in &[-5e-4, -4.1e-4, -3.9e-4, 0.0, 1e-4, 3.95e-4, 4.2e-4] {
            for &v in &[-0.3, 0.0, 0.2] {
                let (e, de_dv, de_dx) = stop.eval(v, x);
                let (hv, hx) = (1e-6, 1e-10);
                let fv = (stop.eval(v + hv, x).0 - stop.eval(v - hv, x).0) / (2.0 * hv);
                let fx = (stop.eval(v, x + hx).0 - stop.eval(v, x - hx).0) / (2.0 * hx);
                assert!((de_dv - fv).abs() <= 1e-6 * (1.0 + fv.abs()), "x {x} v {v}");
                assert!((de_dx - fx).abs() <= 1e-5 * (1.0 + fx.abs()), "x {x} v {v}");
                // odd in (v, x) together
                assert!((stop.eval(-v, -x).0 + e).abs() <= 1e-12 * (1.0 + e.abs()));
            }
        }
        // inside the stroke: no force (e^-20 of the stiffness at null), at the stop: k delta ln 2
        let (f0, _, k0) = stop.eval(0.0, 0.0);
        assert!(f0 == 0.0 && k0 < 1e-8 * 7e6, "{k0}");
        let (fs, _, _) = stop.eval(0.0, 4e-4);
        assert!((fs - 7e6 * 2e-5 * 2f64.ln()).abs() < 1e-9 * fs);

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
}
