//! The paper's analog position controller (section 2 of the paper, eq. 1).
//!
//! A potentiometer on the actuator shaft gives `y_POT = k_POT theta_a` (volts); an error
//! amplifier of gain `A1 = 2` forms `A1 (r - y_POT)`, and a power amplifier of gain `A2 = 10`
//! drives the servo-valve coil with `e_in = A2 A1 (r - y_POT)`. The paper calls the power
//! amplifier inverting; eq. 1 has the product `k_sv A1 A2` with a positive sign, i.e. the
//! inversion is compensated by the valve's polarity, so both gains are positive here.

use crate::bond_graph::{BondGraph, SignalId};

/// Potentiometer full-scale voltage assumed for the default `k_POT` \[V\].
pub const POT_FULL_SCALE_VOLTS: f64 = 10.0;
/// Potentiometer angle span for that voltage \[deg\] (docs/model-notes.md, item 7).
pub const POT_SPAN_DEG: f64 = 150.0;

/// Controller gains.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ControllerParameters {
    /// Error amplifier gain `A1` \[V/V\] (paper: 2).
    pub a1: f64,
    /// Power amplifier gain `A2` \[V/V\] (paper: 10).
    pub a2: f64,
    /// Potentiometer gain `k_POT` \[V/rad\]. The paper does not give it; default 10 V over 150 deg
    /// = 3.8197 V/rad (docs/model-notes.md, item 7).
    pub k_pot: f64,
}

impl Default for ControllerParameters {
    fn default() -> Self {
        ControllerParameters {
            a1: 2.0,
            a2: 10.0,
            k_pot: POT_FULL_SCALE_VOLTS / POT_SPAN_DEG.to_radians(),
        }
    }
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
    /// Power amplifier output (valve command) `e_in = A2 A1 (r - y_POT)` \[V\] (`<prefix>.A2`).
    pub command: SignalId,
}

/// The potentiometer: `y_POT = k_POT angle`, signal `<prefix>.k_pot`.
pub fn add_potentiometer(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters,
    angle: SignalId,
) -> SignalId {
    g.add_gain(format!("{prefix}.k_pot"), p.k_pot, angle)
}

/// The two amplifiers: returns `(A1 error, A2 A1 error)`, signals `<prefix>.A1`, `<prefix>.A2`.
pub fn add_amplifiers(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters,
    error: SignalId,
) -> (SignalId, SignalId) {
    let a1 = g.add_gain(format!("{prefix}.A1"), p.a1, error);
    let a2 = g.add_gain(format!("{prefix}.A2"), p.a2, a1);
    (a1, a2)
}

/// The closed-loop controller: potentiometer on `angle` \[rad\], error against `reference` \[V\],
/// both amplifiers.
pub fn add_controller(
    g: &mut BondGraph,
    prefix: &str,
    p: &ControllerParameters,
    reference: SignalId,
    angle: SignalId,
) -> ControllerPorts {
    let y_pot = add_potentiometer(g, prefix, p, angle);
    let error = g.add_sum(
        format!("{prefix}.error"),
        &[(1.0, reference), (-1.0, y_pot)],
    );
    let (amplified_error, command) = add_amplifiers(g, prefix, p, error);
    ControllerPorts {
        y_pot,
        error,
        amplified_error,
        command,
    }
}
