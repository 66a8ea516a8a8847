//! The paper's physical parts as bond-graph fragments.
//!
//! A fragment is a function that adds its elements and signal blocks to a shared
//! [`BondGraph`] under a name prefix ("loes", "controller", ...)
//! and returns a small struct of handles (junctions to bond onto, signals to wire), so that
//! fragments compose into one graph. Element names match the FMU parameter names where possible
//! ("loes.C3", "controller.A1").
//!
//! * [`loes`]: the low-order equivalent system of the hydraulic loop (Fig. 3, eq. 1).
//! * [`controller`]: the analog position controller (potentiometer, error and power amplifiers).
//! * [`reference`](mod@reference): the command generator (a minimum-jerk move added to the reference `r`).
//! * [`torsion_bar`]: the bar between the motor shaft and the hub.
//! * [`hub`]: the hub inertia on its gas bearing.
//! * [`plate`]: the flexible plate (assumed modes, eqs. 7-22): beam functions, the paper's and a
//!   consistent formulation, natural frequencies, the plate fragment.
//! * The full servo actuator of Fig. 2b: [`torque_motor`] (BG1), [`flapper_nozzle`] (BG2),
//!   [`vane_motor`] (BG3), with the regularised [`orifice`] law, composed by [`servo_valve`].
//! * [`validity`]: the monitors of the linear model's range (deflection, stresses, spin).

pub mod controller;
pub mod flapper_nozzle;
pub mod hub;
#[cfg(test)]
mod law_checks;
pub mod loes;
pub mod orifice;
pub mod plate;
pub mod reference;
pub mod rules;
pub mod servo_valve;
pub mod torque_motor;
pub mod torsion_bar;
pub mod validity;
pub mod vane_motor;

use crate::bond_graph::{BondGraph, SignalId};

/// Adds the position loop's outputs under the names of the FMU's variables: `y_pot`,
/// `theta_motor`, `omega_motor`, `p_load`, `q_valve`. Either hydraulic model provides them.
pub fn add_loop_outputs(
    g: &mut BondGraph,
    y_pot: SignalId,
    theta: SignalId,
    omega: SignalId,
    p_load: SignalId,
    q_valve: SignalId,
) {
    g.add_output("y_pot", y_pot);
    g.add_output("theta_motor", theta);
    g.add_output("omega_motor", omega);
    g.add_output("p_load", p_load);
    g.add_output("q_valve", q_valve);
}
