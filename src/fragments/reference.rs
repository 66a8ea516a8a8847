//! The command generator of the position loop: a smooth slewing move added to the reference `r`.
//!
//! The paper drives its loop with steps of `r` (the identification of eq. 2). What an engineer
//! commands on a slewing rig is a smooth move: a step asks the amplifier for many times its rail
//! and throws the plate far beyond the range of linear plate theory, while a move of a few
//! seconds keeps the loop linear and the plate's deflection small (docs/model-notes.md,
//! item 22). The generator makes the move the FMU's default, so that an importer that only
//! presses "simulate" sees a real manoeuvre.
//!
//! **Minimum-jerk profile** (Flash and Hogan, 1985): the motor-angle command
//!
//! `theta_ref(t) = theta_f (10 s^3 - 15 s^4 + 6 s^5)`, `s = (t - t_0) / T` clamped to `[0, 1]`,
//!
//! the quintic with zero speed and acceleration at both ends; it is what minimises the integral
//! of the squared jerk over the move. In volts for the loop, `r_move = k_POT theta_ref`, added to
//! the input `r` (so that an importer can still add steps or its own signal on top).
//! Peak speed `1.875 theta_f / T` at mid-move, peak acceleration `5.774 theta_f / T^2`.
//!
//! **Time** enters through a clock, an integrator `<prefix>.clock` of the constant 1 (a state,
//! seconds since the start of the simulation): the state equations stay autonomous, so the
//! integrators' exact Jacobian, the FMU state and Model Exchange need nothing new. The move's
//! `t_0` counts from the start of the simulation.
//!
//! Bond graph (signals only): constant 1 -> integrator `<prefix>.clock` -> function
//! `<prefix>.move` (volts) -> sum with `r` `<prefix>.r` (the loop's reference).

use crate::bond_graph::{BondGraph, NonlinearLaw, SignalId, StateUnits};
use crate::fragments::rules;
use crate::math::dual::{Dual, HyperDual, Real};

/// The move (SI units).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MoveParameters<S = f64> {
    /// Motor-angle amplitude `theta_f` \[rad\] (`reference.angle`); 0 turns the generator off.
    pub angle: S,
    /// Start of the move `t_0` \[s\] after the start of the simulation (`reference.t_start`).
    pub t_start: S,
    /// Duration `T` \[s\] (`reference.duration`).
    pub duration: S,
}

impl<S: Copy> MoveParameters<S> {
    /// The parameters `f(self, other)` field by field, the others (choices, counts) `self`'s:
    /// the one list of the real fields, for carrying them in another scalar (a value and its
    /// derivative, [`crate::math::dual::Dual`]).
    pub fn zip<T: Copy, U>(
        &self,
        other: &MoveParameters<T>,
        f: impl Fn(S, T) -> U,
    ) -> MoveParameters<U> {
        MoveParameters {
            angle: f(self.angle, other.angle),
            t_start: f(self.t_start, other.t_start),
            duration: f(self.duration, other.duration),
        }
    }

    /// The parameters `f(self)` field by field ([`MoveParameters::zip`]).
    pub fn map<U>(&self, f: impl Fn(S) -> U) -> MoveParameters<U> {
        self.zip(self, |a, _| f(a))
    }
}

impl Default for MoveParameters {
    /// 30 degrees of motor angle over 2 s, starting 0.5 s into the run (the FMU's default
    /// experiment; docs/model-notes.md, item 22).
    fn default() -> Self {
        MoveParameters {
            angle: 30f64.to_radians(),
            t_start: 0.5,
            duration: 2.0,
        }
    }
}

impl MoveParameters {
    /// Whether the generator adds anything.
    pub fn is_on(&self) -> bool {
        self.angle != 0.0
    }

    /// The time the move ends \[s\].
    pub fn t_end(&self) -> f64 {
        self.t_start + self.duration
    }

    /// Every value with the FMU variable it is (`reference.<name>`).
    pub fn named(&self) -> [(&'static str, f64); 3] {
        [
            ("reference.angle", self.angle),
            ("reference.t_start", self.t_start),
            ("reference.duration", self.duration),
        ]
    }

    /// Checks the values against the model description's rules ([`rules`]); the error names the
    /// FMU variable.
    pub fn validate(&self) -> Result<(), String> {
        rules::check_all(&self.named())
    }

    /// `(theta_ref, d theta_ref / dt)` at time `t` since the start of the simulation \[rad,
    /// rad/s\].
    pub fn profile(&self, t: f64) -> (f64, f64) {
        minimum_jerk(self.angle, self.t_start, self.duration, t)
    }
}

/// The minimum-jerk move of amplitude `amplitude` from `t0` over `duration` at time `t`, in any
/// [`Real`]: 0 before the move, `amplitude` after it, `amplitude s³ (10 - 15 s + 6 s²)`,
/// `s = (t - t0) / duration`, during it (the branches on the value of `s`).
#[inline]
pub fn minimum_jerk_value<S: Real>(amplitude: S, t0: S, duration: S, t: S) -> S {
    let s = (t - t0) / duration;
    if s.value() <= 0.0 {
        S::cst(0.0)
    } else if s.value() >= 1.0 {
        amplitude
    } else {
        let s2 = s * s;
        // 10 + s (-15 + 6 s), each sum and product commuted (the same doubles), x - 15 being
        // x + (-15) in IEEE 754.
        amplitude * s2 * s * (s * (s * 6.0 - 15.0) + 10.0)
    }
}

/// The minimum-jerk move of amplitude `amplitude` from `t0` over `duration` at time `t`: the
/// value ([`minimum_jerk_value`]) and its time derivative.
#[inline]
pub fn minimum_jerk(amplitude: f64, t0: f64, duration: f64, t: f64) -> (f64, f64) {
    let value = minimum_jerk_value(amplitude, t0, duration, t);
    let s = (t - t0) / duration;
    let slope = if s <= 0.0 || s >= 1.0 {
        0.0
    } else {
        amplitude * 30.0 * (s * s) * (1.0 - s) * (1.0 - s) / duration
    };
    (value, slope)
}

/// The move in volts as a law of the clock: `k_pot theta_ref(t)` ([`minimum_jerk`] of the
/// motor angle `angle` from `t_start` over `duration`), with its value bound ([`move_bound`])
/// and its hyper-dual form ([`NonlinearLaw::with_hyper`]), [`minimum_jerk_value`] with the
/// constants' derivatives.
pub fn move_law(
    angle: impl Into<Dual>,
    t_start: impl Into<Dual>,
    duration: impl Into<Dual>,
    k_pot: impl Into<Dual>,
) -> NonlinearLaw {
    let (angle_d, t_start_d, duration_d, k_pot_d) =
        (angle.into(), t_start.into(), duration.into(), k_pot.into());
    let m = MoveParameters {
        angle: angle_d.v,
        t_start: t_start_d.v,
        duration: duration_d.v,
    };
    let k_pot = k_pot_d.v;
    NonlinearLaw::new(
        format!(
            "minimum-jerk move of {:.4} V over {} s from t = {} s",
            k_pot * m.angle,
            m.duration,
            m.t_start
        ),
        {
            let m = m.clone();
            move |t| {
                let (v, dv) = m.profile(t);
                (k_pot * v, k_pot * dv)
            }
        },
    )
    .with_value_bound_if(move_bound(&m, k_pot))
    .with_hyper(move |t, _| {
        let c = HyperDual::from;
        c(k_pot_d) * minimum_jerk_value(c(angle_d), c(t_start_d), c(duration_d), t)
    })
}

/// The value bound of the move as a law of the clock ([`NonlinearLaw::with_value_bound`]):
/// `|k_pot theta(t)| <= 2 |k_pot theta_f|` at every time. The move is 0 before `t_0`,
/// `theta_f` after `t_0 + T`, and `theta_f s³ (10 - 15 s + 6 s²)` between, a polynomial rising
/// from 0 to 1 over `s` in `[0, 1]`; the factor 2 covers its rounding many times over.
/// Declared for `T > 0` (at `T` = 0, `(t - t_0)/T` is 0/0 at `t_0`) and finite `t_0`,
/// `theta_f`, `k_pot`: `(t - t_0)/T` may overflow to ±inf, which the branches take.
pub fn move_bound(p: &MoveParameters, k_pot: f64) -> Option<(f64, f64)> {
    let amplitude = k_pot * p.angle;
    (p.duration > 0.0 && p.t_start.is_finite() && amplitude.is_finite())
        .then_some((0.0, 2.0 * amplitude.abs()))
}

/// Handles into the generator.
#[derive(Clone, Copy, Debug)]
pub struct ReferencePorts {
    /// Seconds since the start of the simulation (state `<prefix>.clock`).
    pub clock: SignalId,
    /// The loop's reference, `r` plus the move \[V\] (`<prefix>.r`).
    pub reference: SignalId,
}

/// Adds the generator: the loop's reference is `r + k_pot theta_ref(clock)` (the move's
/// parameters and `k_pot` in `f64` or with their derivatives, which [`move_law`] carries).
pub fn add_reference<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &MoveParameters<S>,
    k_pot: impl Into<Dual>,
    r: SignalId,
) -> ReferencePorts {
    let one = g.add_constant(format!("{prefix}.rate"), 1.0);
    let clock = g.add_integrator(format!("{prefix}.clock"), one);
    g.set_integrator_nominal(clock, p.duration.into().v);
    g.set_integrator_units(
        clock,
        StateUnits {
            state: "s",
            derivative: "1",
        },
    );
    let volts = g.add_function(
        format!("{prefix}.move"),
        move_law(p.angle, p.t_start, p.duration, k_pot),
        clock,
    );
    let reference = g.add_sum(format!("{prefix}.r"), &[(1.0, r), (1.0, volts)]);
    ReferencePorts { clock, reference }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quintic's boundary conditions (value, speed and acceleration at both ends), its
    /// symmetry about mid-move and the textbook peak speed `1.875 theta_f / T`.
    #[test]
    fn minimum_jerk_meets_its_boundary_conditions() {
        let (a, t0, d) = (0.7, 0.5, 2.0);
        let at = |t| minimum_jerk(a, t0, d, t);
        assert_eq!(at(0.0), (0.0, 0.0));
        assert_eq!(at(t0), (0.0, 0.0));
        assert_eq!(at(t0 + d), (a, 0.0));
        assert_eq!(at(10.0), (a, 0.0));
        let (mid, speed) = at(t0 + d / 2.0);
        assert!((mid - a / 2.0).abs() < 1e-15);
        assert!((speed - 1.875 * a / d).abs() < 1e-14);
        // Acceleration (central difference of the exact speed) vanishes at both ends.
        let h = 1e-6;
        for t in [t0 + h, t0 + d - h] {
            let acc = (at(t + h).1 - at(t - h).1) / (2.0 * h);
            assert!(acc.abs() < 1e-4, "acceleration {acc} at {t}");
        }
        // The speed is the derivative of the value.
        for k in 1..20 {
            let t = t0 + d * k as f64 / 20.0;
            let fd = (at(t + h).0 - at(t - h).0) / (2.0 * h);
            assert!((fd - at(t).1).abs() < 1e-8, "at {t}: {fd} vs {}", at(t).1);
            // Odd symmetry about mid-move.
            let mirror = at(2.0 * t0 + d - t).0;
            assert!((at(t).0 + mirror - a).abs() < 1e-14);
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let bad = MoveParameters {
            duration: 0.0,
            ..MoveParameters::default()
        };
        assert!(bad.validate().unwrap_err().contains("reference.duration"));
        let bad = MoveParameters {
            t_start: -1.0,
            ..MoveParameters::default()
        };
        assert!(bad.validate().unwrap_err().contains("reference.t_start"));
    }

    use crate::fragments::law_checks::{
        assert_hand_derivatives, assert_mixed, assert_same_bits, grid,
    };

    /// The move as it was before its value had one source.
    fn minimum_jerk_before(amplitude: f64, t0: f64, duration: f64, t: f64) -> (f64, f64) {
        let s = (t - t0) / duration;
        if s <= 0.0 {
            (0.0, 0.0)
        } else if s >= 1.0 {
            (amplitude, 0.0)
        } else {
            let s2 = s * s;
            let value = amplitude * s2 * s * (10.0 + s * (-15.0 + 6.0 * s));
            let slope = amplitude * 30.0 * s2 * (1.0 - s) * (1.0 - s) / duration;
            (value, slope)
        }
    }

    #[test]
    fn move_in_hyper_dual_numbers() {
        let p = MoveParameters::default();
        let k_pot = crate::fragments::controller::ControllerParameters::default().k_pot;
        let law = move_law(p.angle, p.t_start, p.duration, k_pot);
        let mut ts = grid(1.0);
        for k in 0..=400 {
            ts.push(p.t_start + p.duration * (f64::from(k) / 200.0 - 0.5));
        }
        ts.extend([p.t_start, p.t_end(), f64::NAN, f64::INFINITY]);
        for &t in &ts {
            let (v, d) = minimum_jerk(p.angle, p.t_start, p.duration, t);
            let (v0, d0) = minimum_jerk_before(p.angle, p.t_start, p.duration, t);
            assert_eq!(
                (v.to_bits(), d.to_bits()),
                (v0.to_bits(), d0.to_bits()),
                "t {t}"
            );
        }
        let generic = |t, _| k_pot * minimum_jerk_value(p.angle, p.t_start, p.duration, t);
        assert_same_bits(&law, generic, &ts, &[0.0]);
        let c = Dual::from;
        let dual = |t, _| c(k_pot) * minimum_jerk_value(c(p.angle), c(p.t_start), c(p.duration), t);
        // The speed 30 s² (1 - s)² is the sum of 3 s² (10 - 15 s + 6 s²) and s³ (-15 + 12 s),
        // which cancel towards the end of the move: their magnitudes, at most 60 (k_pot
        // theta_f / T), are its scale.
        let scale = |_, _| (60.0 * (k_pot * p.angle / p.duration).abs(), 0.0);
        assert_hand_derivatives(&law, dual, &ts, &[0.0], 1e-12, scale);
        // d²r/dt dT: the speed varies in the duration over the duration itself.
        for k in [1, 5, 10, 17] {
            let t = p.t_start + p.duration * f64::from(k) / 20.0;
            let law_of = |duration: Dual| move_law(p.angle, p.t_start, duration, k_pot);
            assert_mixed(law_of, p.duration, 1e-4, p.duration, t, 0.0, false);
        }
    }
}
