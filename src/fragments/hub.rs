//! The central hub on its gas bearing (section 3 of the paper, Fig. 5b): a rigid inertia whose
//! angle `theta` is the plate's rigid rotation.
//!
//! Bond graph: a 1-junction `<prefix>.omega` (common flow: hub speed) with the hub inertia, a
//! one-port I `<prefix>.I`: `I = I_H + 2 I_P` on the hub angle in the paper formulation; in the
//! consistent one, where the mass matrix couples the hub and the plate modes, what is left of it
//! once the modes carry their share of the rotation (`I_r`,
//! [`crate::fragments::plate::AbsoluteRates`]). Without an inertia here, one is supplied later
//! through [`connect_inertia`]. The hub angle is the integral of its speed (integrator
//! `<prefix>.theta`, a state).

use crate::bond_graph::{BondGraph, BondId, Domain, ElementId, SignalId};
use crate::math::dual::Dual;

/// Handles into the hub fragment.
#[derive(Clone, Debug)]
pub struct HubPorts {
    /// The hub 1-junction (common flow: hub speed).
    pub junction: ElementId,
    /// The bond from the junction to the hub inertia, once known.
    pub inertia_bond: Option<BondId>,
    /// Hub speed \[rad/s\] (signal port `<prefix>.omega_hub`).
    pub omega: SignalId,
    /// Hub angle \[rad\] (integrator `<prefix>.theta`).
    pub theta: SignalId,
}

/// Adds the hub. With `Some(inertia)` a one-port I `<prefix>.I` (in `f64`, or with its
/// derivative along a parameter: exact sensitivities); with `None` the inertia is supplied
/// later ([`connect_inertia`]).
pub fn add_hub(g: &mut BondGraph, prefix: &str, inertia: Option<impl Into<Dual>>) -> HubPorts {
    let omega = g.add_signal_port(format!("{prefix}.omega_hub"));
    let theta = g.add_integrator(format!("{prefix}.theta"), omega);
    g.set_integrator_nominal(theta, 1.0);
    g.set_integrator_units(theta, Domain::Rotation.displacement());
    let junction = g.add_one(format!("{prefix}.omega"));
    let mut ports = HubPorts {
        junction,
        inertia_bond: None,
        omega,
        theta,
    };
    if let Some(i) = inertia.map(Into::into) {
        let el = g.add_i(format!("{prefix}.I"), i);
        g.set_nominal(el, &[i.v]); // momentum at 1 rad/s
        g.set_domains(el, &[Domain::Rotation]);
        let b = g.bond(junction, el);
        connect_inertia(g, &ports, b);
        ports.inertia_bond = Some(b);
    }
    ports
}

/// Wires the hub speed to the bond between the hub junction and its inertia.
pub fn connect_inertia(g: &mut BondGraph, hub: &HubPorts, bond: BondId) {
    let name = format!("{}.speed", g.element_name(hub.junction));
    let s = g.add_flow_sensor(name, bond);
    g.connect_signal_port(hub.omega, s);
}
