//! The paper's analog position controller (section 2 of the paper, eq. 1), the power amplifier's
//! output limit, and the external drive of the valve coil.
//!
//! A potentiometer on the actuator shaft gives `y_POT = k_POT theta_a` (volts); an error
//! amplifier of gain `A1 = 2` forms `A1 (r - y_POT)`, and a power amplifier of gain `A2 = 10`
//! drives the servo-valve coil with `e_in = A2 A1 (r - y_POT)`. The paper calls the power
//! amplifier inverting; eq. 1 has the product `k_sv A1 A2` with a positive sign, i.e. the
//! inversion is compensated by the valve's polarity, so both gains are positive here.
//!
//! **Output limit** ([`AmplifierLimit`]). Eq. 1 is linear; a real power amplifier cannot drive
//! the coil beyond its supply rails. With `saturation` on, the amplifier output follows the
//! command exactly up to [`LINEAR_FRACTION`] of the rail `e_max` and then bends smoothly
//! (a `tanh` arc, continuous in value, slope and curvature) towards `+-e_max`, so the Jacobian
//! stays finite and the stiff integrator sees no kink. Default rail 12 V: an analog servo
//! amplifier on the usual +-15 V supply whose power stage (an op-amp output stage driving a coil
//! of some tens to hundreds of ohms) swings to within about 3 V of its rails. The paper's own loop
//! saturates early: a 1 V reference step asks for 20 V.
//!
//! **Load-pressure feedback** ([`add_pressure_feedback`], not in the paper). A differential
//! pressure transducer across the actuator reads `p_load = p_1 - p_2`; a first-order low-pass
//! (corner `f_pl`, the transducer's signal conditioning) gives `p_f`, and `k_pl p_f` is
//! subtracted from the error amplifier's output before the power amplifier:
//! `e_in = A2 (A1 (r - y_POT) - k_pl p_f)`. It is the electronic form of a bypass leak across
//! the motor (Merritt, *Hydraulic Control Systems*, 1967, sections 7.2 and 8.4): the valve opens
//! against the load pressure as if the motor leaked `A2 K_qe k_pl` per pascal, which damps the
//! oil column and the plate modes the loop excites, without the leak's flow loss. The price is a
//! static compliance against an external load torque `T`: the loop settles where
//! `A1 k_POT theta = k_pl T / D_m`. The default (5 mV/bar, 50 Hz) and why are in
//! docs/model.md ("The default loop's damping"). `k_pl = 0` is the paper's eq. 1 (no transducer).
//!
//! **External control** (`external`). The analog controller is replaced by the input `e_in`
//! \[V\], the coil drive voltage a user's own controller computes; it passes through the same
//! output limit (turn `saturation` off to drive the coil without one). The potentiometer stays,
//! so `y_POT` remains an output for the user's loop.

use crate::bond_graph::{BondGraph, NonlinearLaw, SignalId, StateUnits};
use crate::fragments::rules;
use crate::math::dual::{Dual, HyperDual, Real};

/// Potentiometer full-scale voltage assumed for the default `k_POT` \[V\].
pub const POT_FULL_SCALE_VOLTS: f64 = 10.0;
/// Potentiometer angle span for that voltage \[deg\] (10 V over 150 deg: the paper gives no
/// `k_POT`; docs/model-notes.md, item 7).
pub const POT_SPAN_DEG: f64 = 150.0;
/// Default output limit of the power amplifier \[V\]: a +-15 V supply less about 3 V of headroom
/// of the output stage.
pub const DEFAULT_E_MAX: f64 = 12.0;
/// Fraction of `e_max` up to which the limited amplifier is exactly linear.
pub const LINEAR_FRACTION: f64 = 0.8;

/// Controller gains, the amplifier's output limit and the choice of drive.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ControllerParameters<S = f64> {
    /// Error amplifier gain `A1` \[V/V\] (paper: 2).
    pub a1: S,
    /// Power amplifier gain `A2` \[V/V\] (paper: 10).
    pub a2: S,
    /// Potentiometer gain `k_POT` \[V/rad\]. The paper does not give it; default 10 V over 150 deg
    /// = 3.8197 V/rad (docs/model-notes.md, item 7).
    pub k_pot: S,
    /// Output limit of the power amplifier \[V\] (`controller.e_max`), used when `saturation`.
    pub e_max: S,
    /// Whether the power amplifier's output saturates at `+-e_max` (`controller.saturation`);
    /// false is the paper's linear eq. 1.
    pub saturation: bool,
    /// Whether the input `e_in` drives the coil in place of the analog controller
    /// (`controller.external`).
    pub external: bool,
    /// Load-pressure feedback gain \[V/Pa\] (`controller.k_pl`): volts subtracted from the error
    /// amplifier's output per pascal of filtered load pressure. Default 5e-8 V/Pa (5 mV/bar):
    /// inside the band of gains that keep the default loop damped over the assumed parameters'
    /// range (about 1.7e-8 to 6.5e-7), where the default move rings least (docs/model.md);
    /// 0 switches the feedback off (the paper).
    pub k_pl: S,
    /// Corner frequency of the pressure signal's first-order low-pass \[Hz\] (`controller.f_pl`):
    /// 50 Hz, ten times the loop's highest mode it damps, far below the valve's 120 Hz.
    pub f_pl: S,
}

impl<S: Copy> ControllerParameters<S> {
    /// The parameters `f(self, other)` field by field, the others (choices, counts) `self`'s:
    /// the one list of the real fields, for carrying them in another scalar (a value and its
    /// derivative, [`crate::math::dual::Dual`]).
    pub fn zip<T: Copy, U>(
        &self,
        other: &ControllerParameters<T>,
        f: impl Fn(S, T) -> U,
    ) -> ControllerParameters<U> {
        ControllerParameters {
            a1: f(self.a1, other.a1),
            a2: f(self.a2, other.a2),
            k_pot: f(self.k_pot, other.k_pot),
            e_max: f(self.e_max, other.e_max),
            saturation: self.saturation,
            external: self.external,
            k_pl: f(self.k_pl, other.k_pl),
            f_pl: f(self.f_pl, other.f_pl),
        }
    }

    /// The parameters `f(self)` field by field ([`ControllerParameters::zip`]).
    pub fn map<U>(&self, f: impl Fn(S) -> U) -> ControllerParameters<U> {
        self.zip(self, |a, _| f(a))
    }
}

/// Default load-pressure feedback gain \[V/Pa\]: 5 mV/bar.
pub const DEFAULT_K_PL: f64 = 5e-8;
/// Default corner of the pressure signal's low-pass \[Hz\].
pub const DEFAULT_F_PL: f64 = 50.0;

impl Default for ControllerParameters {
    /// The paper's gains with the output limit on, the analog controller in the loop and the
    /// load-pressure feedback (the FMU's defaults).
    fn default() -> Self {
        ControllerParameters {
            a1: 2.0,
            a2: 10.0,
            k_pot: POT_FULL_SCALE_VOLTS / POT_SPAN_DEG.to_radians(),
            e_max: DEFAULT_E_MAX,
            saturation: true,
            external: false,
            k_pl: DEFAULT_K_PL,
            f_pl: DEFAULT_F_PL,
        }
    }
}

impl ControllerParameters {
    /// The paper's controller exactly as in eq. 1: the default gains, a linear amplifier, no
    /// pressure feedback.
    pub fn linear() -> Self {
        ControllerParameters {
            saturation: false,
            ..Self::paper()
        }
    }

    /// The paper's analog controller (eq. 1) with the amplifier's output limit: no pressure
    /// feedback.
    pub fn paper() -> Self {
        ControllerParameters {
            k_pl: 0.0,
            ..Self::default()
        }
    }

    /// Whether the load-pressure feedback is in the loop.
    pub fn pressure_feedback(&self) -> bool {
        self.k_pl != 0.0
    }

    /// The amplifier's output law.
    pub fn limit(&self) -> AmplifierLimit {
        if self.saturation {
            AmplifierLimit::Saturating { e_max: self.e_max }
        } else {
            AmplifierLimit::Linear
        }
    }

    /// Every numeric value with the FMU variable it is (`controller.<name>`).
    pub fn named(&self) -> [(&'static str, f64); 6] {
        [
            ("controller.A1", self.a1),
            ("controller.A2", self.a2),
            ("controller.k_pot", self.k_pot),
            ("controller.e_max", self.e_max),
            ("controller.k_pl", self.k_pl),
            ("controller.f_pl", self.f_pl),
        ]
    }

    /// Checks the gains, the rail and the filter against the model description's rules
    /// ([`rules`]); the error names the FMU variable.
    pub fn validate(&self) -> Result<(), String> {
        rules::check_all(&self.named())
    }
}

/// The power amplifier's output as a function of its demanded output `u` \[V\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AmplifierLimit {
    /// `e = u` (eq. 1).
    Linear,
    /// `e = u` for `|u| <= LINEAR_FRACTION e_max`; beyond, with `k = LINEAR_FRACTION e_max` and
    /// `w = e_max - k`, `e = sign(u) (k + w tanh((|u| - k) / w))`: odd, monotonic, bounded by
    /// `e_max`, twice continuously differentiable.
    Saturating { e_max: f64 },
}

impl AmplifierLimit {
    /// `(e, de/du)`.
    pub fn eval(&self, u: f64) -> (f64, f64) {
        match *self {
            AmplifierLimit::Linear => (u, 1.0),
            AmplifierLimit::Saturating { e_max } => {
                let k = LINEAR_FRACTION * e_max;
                let a = u.abs();
                if a <= k {
                    return (u, 1.0);
                }
                let w = e_max - k;
                let t = crate::math::tanh((a - k) / w);
                ((k + w * t).copysign(u), 1.0 - t * t)
            }
        }
    }

    /// Its value bound as a law ([`NonlinearLaw::with_value_bound`]): `|e| <= 2 |e_max|` for
    /// the saturating amplifier. Within the linear range `|e| = |u| <= LINEAR_FRACTION |e_max|`;
    /// beyond, `tanh` lies in `[-1, 1]`, so `|k + w t| <= |k| + |w| = |e_max|`; the factor 2
    /// covers rounding many times over. For `e_max` finite (`(|u| - k)/w` may be ±inf at
    /// `e_max` = 0, which `tanh` takes, then `w t` = 0). None for the linear amplifier, which
    /// is no law.
    pub fn value_bound(&self) -> Option<(f64, f64)> {
        match *self {
            AmplifierLimit::Linear => None,
            AmplifierLimit::Saturating { e_max } => {
                e_max.is_finite().then_some((0.0, 2.0 * e_max.abs()))
            }
        }
    }

    /// Whether a demanded output `u` is beyond the linear range (the amplifier is limiting).
    pub fn is_limiting(&self, u: f64) -> bool {
        match *self {
            AmplifierLimit::Linear => false,
            AmplifierLimit::Saturating { e_max } => u.abs() > LINEAR_FRACTION * e_max,
        }
    }
}

/// The saturating amplifier's output [`AmplifierLimit::Saturating`] in any [`Real`]: the value
/// of [`AmplifierLimit::eval`], the same operations (its `copysign` as the sign bits' choice
/// between the magnitude and its negation, which is what `copysign` does) and branches (on the
/// values), so the same doubles.
pub fn saturating_value<S: Real>(e_max: S, u: S) -> S {
    let k = e_max * LINEAR_FRACTION;
    let a = u.abs();
    if a.value() <= k.value() {
        return u;
    }
    let w = e_max - k;
    let t = S::tanh((a - k) / w);
    let magnitude = k + w * t;
    if magnitude.value().is_sign_negative() == u.value().is_sign_negative() {
        magnitude
    } else {
        -magnitude
    }
}

/// The smooth output limit [`AmplifierLimit::Saturating`] with the rail `e_max` as a law of
/// the demanded output, with its value bound and its hyper-dual form
/// ([`NonlinearLaw::with_hyper`]), [`saturating_value`] with the rail's derivative: the power
/// amplifier's ([`add_output_limit`]) and the current amplifier's compliance limit
/// ([`super::torque_motor::add_current_amplifier`]).
pub fn saturation_law(label: impl Into<String>, e_max: impl Into<Dual>) -> NonlinearLaw {
    let e_max_d = e_max.into();
    let limit = AmplifierLimit::Saturating { e_max: e_max_d.v };
    NonlinearLaw::new(label, move |u| limit.eval(u))
        .with_value_bound_if(limit.value_bound())
        .with_hyper(move |u, _| saturating_value(HyperDual::from(e_max_d), u))
}

/// Signals of the controller fragment.
#[derive(Clone, Copy, Debug)]
pub struct ControllerPorts {
    /// Potentiometer voltage `y_POT = k_POT theta_a` \[V\] (`<prefix>.k_pot`).
    pub y_pot: SignalId,
    /// Error `r - y_POT` \[V\] (`<prefix>.error`).
    pub error: SignalId,
    /// Error amplifier output `A1 (r - y_POT)` \[V\] (`<prefix>.A1`).
    pub amplified_error: SignalId,
    /// Power amplifier output (valve command, the coil voltage `e_in` of eq. 1), after the output
    /// limit \[V\] (`<prefix>.A2`, or `<prefix>.e_out` when limited).
    pub command: SignalId,
}

// The fragments below take the parameters in `f64` or in dual numbers (`S: Copy + Into<Dual>`,
// as `loes::add_loes`): in dual numbers every constant they give the bond graph carries its
// derivative along the parameter the model is built for (exact sensitivities,
// `crate::model::sensitivity`); in `f64` the same constants with derivative zero.

/// The potentiometer: `y_POT = k_POT angle`, signal `<prefix>.k_pot`.
pub fn add_potentiometer<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters<S>,
    angle: SignalId,
) -> SignalId {
    g.add_gain(format!("{prefix}.k_pot"), p.k_pot.into(), angle)
}

/// The power amplifier's output limit on a demanded voltage `u`: `u` itself when linear,
/// otherwise the signal `<prefix>.e_out` ([`saturation_law`], the rail `e_max` with its
/// derivative).
pub fn add_output_limit<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters<S>,
    u: SignalId,
) -> SignalId {
    if !p.saturation {
        return u;
    }
    let e_max: Dual = p.e_max.into();
    g.add_function(
        format!("{prefix}.e_out"),
        // The label names the value, as f64 prints it (Dual's Display).
        saturation_law(format!("amplifier limit +-{e_max} V"), e_max),
        u,
    )
}

/// The load pressure's low-pass `p_f` \[Pa\], `dp_f/dt = 2 pi f_pl (p_load - p_f)`: the
/// integrator `<prefix>.p_f` (a state, nominal 10 bar) fed by `<prefix>.p_f_rate`. `None` without
/// pressure feedback (`k_pl = 0`, its value: a derivative of `k_pl` at 0 would need the state
/// the model does not have, which `crate::model::compose` refuses).
pub fn add_pressure_feedback<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters<S>,
    p_load: SignalId,
) -> Option<SignalId> {
    let (k_pl, f_pl): (Dual, Dual) = (p.k_pl.into(), p.f_pl.into());
    if k_pl.v == 0.0 {
        return None;
    }
    let w = 2.0 * core::f64::consts::PI * f_pl;
    let rate = g.add_signal_port(format!("{prefix}.p_f_rate"));
    let p_f = g.add_integrator(format!("{prefix}.p_f"), rate);
    g.set_integrator_nominal(p_f, 1e6);
    g.set_integrator_units(
        p_f,
        StateUnits {
            state: "Pa",
            derivative: "Pa/s",
        },
    );
    let sum = g.add_sum(format!("{prefix}.p_f_error"), &[(w, p_load), (-w, p_f)]);
    g.connect_signal_port(rate, sum);
    Some(p_f)
}

/// The two amplifiers: returns `(A1 error, power amplifier output)`, signals `<prefix>.A1`,
/// `<prefix>.A2` (and `<prefix>.e_out`, the limited output, when `saturation`). With pressure
/// feedback, `k_pl p_f` is subtracted between them (`<prefix>.A1_pl`).
pub fn add_amplifiers<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters<S>,
    error: SignalId,
    p_load: SignalId,
) -> (SignalId, SignalId) {
    let (a1_gain, a2_gain, k_pl): (Dual, Dual, Dual) = (p.a1.into(), p.a2.into(), p.k_pl.into());
    let a1 = g.add_gain(format!("{prefix}.A1"), a1_gain, error);
    let into_a2 = match add_pressure_feedback(g, prefix, p, p_load) {
        Some(p_f) => g.add_sum(
            format!("{prefix}.A1_pl"),
            &[(Dual::from(1.0), a1), (-k_pl, p_f)],
        ),
        None => a1,
    };
    let a2 = g.add_gain(format!("{prefix}.A2"), a2_gain, into_a2);
    (a1, add_output_limit(g, prefix, p, a2))
}

/// The closed-loop controller: potentiometer on `angle` \[rad\], error against `reference` \[V\],
/// both amplifiers, the pressure feedback from `p_load` \[Pa\].
pub fn add_controller<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters<S>,
    reference: SignalId,
    angle: SignalId,
    p_load: SignalId,
) -> ControllerPorts {
    let y_pot = add_potentiometer(g, prefix, p, angle);
    let error = g.add_sum(
        format!("{prefix}.error"),
        &[(1.0, reference), (-1.0, y_pot)],
    );
    let (amplified_error, command) = add_amplifiers(g, prefix, p, error, p_load);
    ControllerPorts {
        y_pot,
        error,
        amplified_error,
        command,
    }
}

/// The valve drive of the assembled model: the analog controller closing the loop on
/// `reference`, or, with `p.external`, the external coil voltage `e_in` through the amplifier's
/// output limit (the potentiometer stays; the pressure feedback is the analog controller's, so it
/// goes with it). Returns `(y_POT, coil voltage)`.
pub fn add_drive<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters<S>,
    reference: SignalId,
    e_in: SignalId,
    angle: SignalId,
    p_load: SignalId,
) -> (SignalId, SignalId) {
    if p.external {
        let y_pot = add_potentiometer(g, prefix, p, angle);
        (y_pot, add_output_limit(g, prefix, p, e_in))
    } else {
        let c = add_controller(g, prefix, p, reference, angle, p_load);
        (c.y_pot, c.command)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limit_is_exactly_linear_below_the_knee() {
        let l = AmplifierLimit::Saturating { e_max: 12.0 };
        for u in [-9.6, -5.0, -1e-9, 0.0, 3.3, 9.6] {
            assert_eq!(l.eval(u), (u, 1.0));
        }
        assert!(!l.is_limiting(9.6) && l.is_limiting(9.61));
    }

    #[test]
    fn limit_is_odd_monotonic_bounded_and_smooth() {
        let e_max = 12.0;
        let l = AmplifierLimit::Saturating { e_max };
        let mut last = f64::NEG_INFINITY;
        for i in -4000..=4000 {
            let u = i as f64 * 0.05;
            let (e, de) = l.eval(u);
            assert_eq!(l.eval(-u).0, -e, "odd at {u}");
            assert!(
                e >= last && e.abs() <= e_max,
                "monotonic and below the rail at {u}"
            );
            assert!((0.0..=1.0).contains(&de));
            // The derivative is the exact one (central difference, error O(h^2)).
            let h = 1e-6;
            let fd = (l.eval(u + h).0 - l.eval(u - h).0) / (2.0 * h);
            assert!((fd - de).abs() < 1e-6, "de/du at {u}: {de} vs {fd}");
            last = e;
        }
        // Far beyond the rail the output is the rail to round-off; the slope vanishes.
        assert!((l.eval(200.0).0 - e_max).abs() < 1e-12);
        // Slope and curvature are continuous at the knee u = 9.6: slope 1 - O(d^2) just beyond.
        let (_, d) = l.eval(9.6 + 1e-4);
        assert!((1.0 - d) < 1e-7);
    }

    use crate::fragments::law_checks::{
        assert_hand_derivatives, assert_mixed, assert_same_bits, grid,
    };

    #[test]
    fn limit_in_hyper_dual_numbers() {
        let e_max = 12.0;
        let law = saturation_law("limit", e_max);
        let mut us = grid(e_max);
        // At, below and above the knee (9.6 V) on both sides.
        for u in [9.6, 9.6 + 1e-12, 9.59, 9.61, 10.5, 14.0, 30.0] {
            us.extend([u, -u]);
        }
        us.push(f64::NAN);
        assert_same_bits(&law, |u, _| saturating_value(e_max, u), &us, &[0.0]);
        // copysign's choice holds for a negative rail too, where the arc is negative.
        let odd = saturation_law("negative rail", -12.0);
        assert_same_bits(&odd, |u, _| saturating_value(-12.0, u), &us, &[0.0]);
        let dual = |u, _| saturating_value(Dual::from(e_max), u);
        assert_hand_derivatives(&law, dual, &us, &[0.0], 1e-12, |_, _| (0.0, 0.0));
        // d²e/du de_max beyond the knee: the arc varies in e_max over its width w = 0.2 e_max.
        for u in [-20.0, -10.0, 9.7, 11.0, 15.0] {
            let law_of = |e_max: Dual| saturation_law("limit", e_max);
            assert_mixed(law_of, e_max, 1e-4, 0.2 * e_max, u, 0.0, false);
        }
    }
}
