//! Validity monitors: where the linear model stops describing the rig.
//!
//! The plate is a linear Kirchhoff plate in small deflections on a hub that turns slowly compared
//! with its bending; the torsion bar and the plate are elastic. A hard manoeuvre leaves that range
//! long before anything in the equations says so (docs/model-notes.md, item 23). Four outputs
//! watch it, each a linear function of the state (so they cost nothing to integrate and keep the
//! model's affine structure):
//!
//! | output | quantity | the model stops holding when |
//! | --- | --- | --- |
//! | `plate.w_tip_ratio` | `w_tip / a` | above [`TIP_RATIO_LIMIT`] = 0.1: an elastica departs from linear bending by about 1 % there, 4 % at 0.21 and 33 % at 0.81 |
//! | `plate.stress` | bending stress at the plate's most bent section | above `min(plate.sigma_f, plate.sigma_y) /` [`ROOT_CONCENTRATION`]: a clamped root concentrates stress by about 2, so the root's peak stress then reaches the fatigue strength (48 MPa nominal for 6061-T6) |
//! | `torsion_bar.stress` | shear stress `16 T / (pi d^3)` at the bar's surface | above [`YIELD_FRACTION`] of `torsion_bar.tau_y`, which is also the steel's torsional endurance limit (below) |
//! | `hub.omega_ratio` | hub speed over the plate's first clamped bending frequency | its square above [`SPIN_LIMIT`] = 0.1: the spin-softening terms the linear model omits grow as `(Omega / omega_1)^2` |
//!
//! The FMU checks the monitors at every communication point and logs one warning per quantity
//! (the first time it goes out of range), naming the quantity, its value and the time.
//!
//! Material limits (parameters): the plate of the paper in aluminium 6061-T6, yield 276 MPa
//! (ASM Aerospace Specification Metals, MIL-HDBK-5) and fatigue strength 96.5 MPa at 5e8 cycles
//! of completely reversed stress (R. R. Moore rotating beam; ASM). A slewing rig reverses the
//! plate's bending at every move and rings in its slow mode after it, thousands of cycles an
//! hour, and aluminium has no endurance limit, so the plate's rule is fatigue at the clamped root, not
//! yield: the yield strength still caps it for a material whose fatigue strength exceeds its yield.
//! The bar in AISI 4140 quenched and tempered, tensile yield 655 MPa, shear yield by von Mises
//! `0.577 x 655` = 378 MPa. Steel has an endurance limit, about half its ultimate strength
//! (Shigley, *Mechanical Engineering Design*, `S'e = 0.5 S_ut` below 1400 MPa), in shear `0.577`
//! of it: with `S_ut` at least the 655 MPa yield, at least `0.577 x 0.5 x 655` = 189 MPa, the
//! bar's threshold [`YIELD_FRACTION`] `x 378`. The bar's rule stays half its shear yield: that
//! is at or below its unnotched torsional endurance limit (a shouldered bar's fillets would need
//! their own concentration factor, which the model does not know).

use crate::bond_graph::{BondGraph, SignalId};
use crate::math::dual::{Dual, Real};

/// `|w_tip / a|` above which linear plate theory is not trusted.
pub const TIP_RATIO_LIMIT: f64 = 0.1;
/// Fraction of the torsion bar's shear yield stress above which its monitor warns.
pub const YIELD_FRACTION: f64 = 0.5;
/// The stress concentration at the plate's clamped root: the plate's monitor warns when this
/// times the nominal stress `plate.stress` exceeds the smaller of the fatigue and yield strengths.
pub const ROOT_CONCENTRATION: f64 = 2.0;
/// `(Omega / omega_1)^2` above which the omitted spin terms matter.
pub const SPIN_LIMIT: f64 = 0.1;

/// The material limits and the bar's diameter (SI).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Limits<S = f64> {
    /// Yield strength of the plate \[Pa\] (`plate.sigma_y`, 6061-T6: 276 MPa).
    pub plate_sigma_y: S,
    /// Fatigue strength of the plate, completely reversed stress \[Pa\] (`plate.sigma_f`,
    /// 6061-T6: 96.5 MPa at 5e8 cycles).
    pub plate_sigma_f: S,
    /// Diameter of the torsion bar \[m\] (`torsion_bar.d`).
    pub bar_d: S,
    /// Shear yield strength of the torsion bar \[Pa\] (`torsion_bar.tau_y`).
    pub bar_tau_y: S,
}

impl<S: Copy> Limits<S> {
    /// The parameters `f(self, other)` field by field, the others (choices, counts) `self`'s:
    /// the one list of the real fields, for carrying them in another scalar (a value and its
    /// derivative, [`crate::math::dual::Dual`]).
    pub fn zip<T: Copy, U>(&self, other: &Limits<T>, f: impl Fn(S, T) -> U) -> Limits<U> {
        Limits {
            plate_sigma_y: f(self.plate_sigma_y, other.plate_sigma_y),
            plate_sigma_f: f(self.plate_sigma_f, other.plate_sigma_f),
            bar_d: f(self.bar_d, other.bar_d),
            bar_tau_y: f(self.bar_tau_y, other.bar_tau_y),
        }
    }

    /// The parameters `f(self)` field by field ([`Limits::zip`]).
    pub fn map<U>(&self, f: impl Fn(S) -> U) -> Limits<U> {
        self.zip(self, |a, _| f(a))
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            plate_sigma_y: 276e6,
            plate_sigma_f: 96.5e6,
            bar_d: 0.02,
            bar_tau_y: 378e6,
        }
    }
}

impl Limits {
    /// The plate's strength its monitor compares with the root's concentrated stress: the
    /// smaller of the fatigue and yield strengths \[Pa\].
    pub fn plate_strength(&self) -> f64 {
        self.plate_sigma_f.min(self.plate_sigma_y)
    }

    /// Which strength [`Limits::plate_strength`] is: the fatigue strength unless the yield
    /// strength is the smaller.
    pub fn plate_rule(&self) -> PlateRule {
        if self.plate_sigma_f <= self.plate_sigma_y {
            PlateRule {
                word: "fatigue",
                strength: "fatigue strength at 5e8 reversed cycles",
                parameter: "sigma_f",
            }
        } else {
            PlateRule {
                word: "yield",
                strength: "yield strength",
                parameter: "sigma_y",
            }
        }
    }

    /// The shear stress at the surface of the bar per unit torque, `16 / (pi d^3)` \[Pa/(N m)\].
    pub fn bar_stress_per_torque(&self) -> f64 {
        self.map(Dual::from).bar_stress_per_torque().v
    }
}

impl Limits<Dual> {
    /// [`Limits::bar_stress_per_torque`] with its derivative (along `torsion_bar.d`).
    pub fn bar_stress_per_torque(&self) -> Dual {
        let d = self.bar_d;
        let cube = Dual::new(d.v.powi(3), 3.0 * d.v.powi(2) * d.d);
        16.0 / (std::f64::consts::PI * cube)
    }
}

/// The plate strength a monitor compares with, as its messages name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlateRule {
    /// One word: `fatigue` or `yield`.
    pub word: &'static str,
    /// What the strength is.
    pub strength: &'static str,
    /// Its parameter, after `plate.`.
    pub parameter: &'static str,
}

/// One monitored quantity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Monitor {
    TipRatio,
    PlateStress,
    BarStress,
    SpinRatio,
}

impl Monitor {
    pub const ALL: [Monitor; 4] = [
        Monitor::TipRatio,
        Monitor::PlateStress,
        Monitor::BarStress,
        Monitor::SpinRatio,
    ];

    /// The FMU output that carries it.
    pub fn variable(self) -> &'static str {
        match self {
            Monitor::TipRatio => "plate.w_tip_ratio",
            Monitor::PlateStress => "plate.stress",
            Monitor::BarStress => "torsion_bar.stress",
            Monitor::SpinRatio => "hub.omega_ratio",
        }
    }

    /// The largest magnitude of the output within the model's range.
    pub fn limit(self, limits: &Limits) -> f64 {
        match self {
            Monitor::TipRatio => TIP_RATIO_LIMIT,
            Monitor::PlateStress => limits.plate_strength() / ROOT_CONCENTRATION,
            Monitor::BarStress => YIELD_FRACTION * limits.bar_tau_y,
            Monitor::SpinRatio => SPIN_LIMIT.sqrt(),
        }
    }

    /// Whether the output's value is out of range.
    pub fn exceeded(self, value: f64, limits: &Limits) -> bool {
        value.abs() > self.limit(limits)
    }

    /// The warning for a value out of range at time `t`.
    pub fn message(self, value: f64, t: f64, limits: &Limits) -> String {
        let quantity = match self {
            Monitor::TipRatio => format!(
                "the plate's tip deflection w_tip/a = {value:.3} exceeds {TIP_RATIO_LIMIT} \
                 (large deflection: linear plate theory no longer holds)"
            ),
            Monitor::PlateStress => format!(
                "the plate's bending stress {:.1} MPa exceeds {:.2} MPa: concentrated {} times \
                 at the clamped root it passes the plate's {} (plate.{} = {:.1} MPa)",
                value.abs() * 1e-6,
                self.limit(limits) * 1e-6,
                ROOT_CONCENTRATION,
                limits.plate_rule().strength,
                limits.plate_rule().parameter,
                limits.plate_strength() * 1e-6
            ),
            Monitor::BarStress => format!(
                "the torsion bar's shear stress {:.1} MPa exceeds {YIELD_FRACTION} of its shear \
                 yield strength torsion_bar.tau_y = {:.0} MPa",
                value * 1e-6,
                limits.bar_tau_y * 1e-6
            ),
            Monitor::SpinRatio => format!(
                "the hub spins fast against the plate's bending: (omega_hub/omega_1)^2 = {:.3} \
                 exceeds {SPIN_LIMIT} (the spin-softening terms the linear model omits)",
                value * value
            ),
        };
        format!(
            "validity: {} = {value:.4e} at t = {t:.4} s: {quantity}; the results are outside \
             the model's range",
            self.variable()
        )
    }
}

/// The first bending frequency of the plate clamped at the root, `omega_1 = 1.8751^2 /
/// a^2 sqrt(D / (rho h))` \[rad/s\] (the clamped-free beam with the plate's rigidity: 1.12 Hz for
/// the paper's plate), the scale of `hub.omega_ratio`.
pub fn first_clamped_bending<S: Real>(a: S, rigidity: S, areal_mass: S) -> S {
    const BETA_1: f64 = 1.875_104_068_711_961;
    S::cst(BETA_1 * BETA_1) / (a * a) * S::sqrt(rigidity / areal_mass)
}

/// The signals the monitors read.
#[derive(Clone, Copy, Debug)]
pub struct Watched {
    /// `w_tip` \[m\].
    pub w_tip: SignalId,
    /// The plate's bending stress \[Pa\].
    pub plate_stress: SignalId,
    /// The torsion bar's torque \[N m\].
    pub bar_torque: SignalId,
    /// The hub speed \[rad/s\].
    pub omega_hub: SignalId,
}

/// Adds the four monitor outputs under the names of [`Monitor::variable`]; `a` is the plate's
/// length and `omega_1` its first clamped bending frequency \[rad/s\], both in `f64` or with
/// their derivatives along a parameter (the gains `1 / a`, `1 / omega_1` and the bar's
/// `16 / (pi d^3)` carry them; the strengths only set the warnings' thresholds, which are not
/// outputs).
pub fn add_monitors(
    g: &mut BondGraph,
    s: Watched,
    limits: &Limits<Dual>,
    a: impl Into<Dual>,
    omega_1: impl Into<Dual>,
) {
    let (a, omega_1): (Dual, Dual) = (a.into(), omega_1.into());
    let ratio = g.add_gain("validity.w_tip_ratio", 1.0 / a, s.w_tip);
    g.add_output(Monitor::TipRatio.variable(), ratio);
    g.add_output(Monitor::PlateStress.variable(), s.plate_stress);
    let tau = g.add_gain(
        "validity.bar_stress",
        limits.bar_stress_per_torque(),
        s.bar_torque,
    );
    g.add_output(Monitor::BarStress.variable(), tau);
    let spin = g.add_gain("validity.omega_ratio", 1.0 / omega_1, s.omega_hub);
    g.add_output(Monitor::SpinRatio.variable(), spin);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_clamped_bending_of_the_papers_plate() {
        // 6061-T6 plate of the paper: D = E h^3 / (12 (1 - nu^2)), 1.1207 Hz (the paper
        // formulation's locked (1,1) mode, which is this beam's).
        let (e, h, nu, rho, a): (f64, f64, f64, f64, f64) = (6.89e10, 2.65e-3, 0.3, 2795.0, 1.41);
        let d = e * h.powi(3) / (12.0 * (1.0 - nu * nu));
        let f = first_clamped_bending(a, d, rho * h) / (2.0 * std::f64::consts::PI);
        assert!((f - 1.1207).abs() < 5e-4, "{f}");
    }

    #[test]
    fn bar_stress_of_a_20_mm_bar() {
        // 100 N m on 20 mm: 16 * 100 / (pi 8e-6) = 63.66 MPa.
        let tau = 100.0 * Limits::default().bar_stress_per_torque();
        assert!((tau - 63.662e6).abs() < 1e3, "{tau}");
    }

    #[test]
    fn the_plate_warns_at_half_its_fatigue_strength() {
        // 6061-T6: 96.5 MPa fatigue strength, 276 MPa yield; at the root's concentration of 2
        // the plate warns above 48.25 MPa of nominal stress, the fatigue strength named.
        let l = Limits::default();
        assert_eq!(Monitor::PlateStress.limit(&l), 48.25e6);
        let text = Monitor::PlateStress.message(50e6, 1.0, &l);
        assert!(
            text.contains("fatigue") && text.contains("96.5 MPa"),
            "{text}"
        );
        // A material whose fatigue strength exceeds its yield: the yield strength rules.
        let soft = Limits {
            plate_sigma_y: 50e6,
            ..l
        };
        assert_eq!(Monitor::PlateStress.limit(&soft), 25e6);
        let text = Monitor::PlateStress.message(30e6, 1.0, &soft);
        assert!(
            text.contains("yield") && text.contains("sigma_y = 50.0"),
            "{text}"
        );
    }

    #[test]
    fn messages_name_the_quantity_value_and_time() {
        let l = Limits::default();
        for m in Monitor::ALL {
            let v = 1.5 * m.limit(&l);
            assert!(m.exceeded(v, &l) && m.exceeded(-v, &l) && !m.exceeded(0.5 * v, &l));
            let text = m.message(v, 1.25, &l);
            assert!(
                text.contains(m.variable()) && text.contains("t = 1.25"),
                "{text}"
            );
        }
    }
}
