//! The full electro-hydraulic servo actuator of Fig. 2b: BG1 + BG2 + BG3 composed, with the
//! supply and tank, and closed into the paper's position loop with the [`controller`].
//!
//! * [`super::torque_motor`] (BG1): coil and flapper;
//! * [`super::flapper_nozzle`] (BG2): pilot stage and spool, plus the feedback wire and the
//!   spring field of flapper and spool;
//! * [`super::vane_motor`] (BG3): four-way spool metering, actuator chambers, leakage, vane
//!   motor and rotor;
//! * [`super::orifice`]: the regularised orifice law of every restriction;
//! * [`limits`]: the spool end stops and the cavitation floor of the chambers.
//!
//! This module composes them ([`add_servo_valve`], the closed loop [`build_loop`] and the
//! direct path [`build_open_loop`]); [`parameters`] holds the constants and their reasons,
//! [`rest`] the null state, [`g_est`](mod@g_est) the comparison with the identified `G_est` (the fit
//! itself is the tool `servo-valve-fit`).
//!
//! Supply `Se p_s` (`<prefix>.supply`) and tank `Se p_t` (`<prefix>.tank`) are effort sources on
//! two 0-junctions shared by the pilot and the main stage.
//!
//! # Parameters and where `G_est` comes from
//!
//! The paper gives no servo-valve parameter. The defaults ([`ServoValveParameters::default`])
//! are those of a two-stage flapper-nozzle valve of about 30 L/min with mechanical feedback,
//! each inside the datasheet ranges of such valves or with its reason stated, and the actuator
//! chambers sized for a vane motor of the LOES displacement plus its lines (150 cm^3 each, not
//! the 148 L that `2 C3 beta` would give: the paper's `C3` is a lumped identified constant, not
//! an oil volume). Three constants were then fitted (tool `servo-valve-fit`) so that the
//! linearised direct path reproduces `G_est(s) = 2.25e6 / (s (s+65) (s+753))` (eq. 2 of the
//! paper), each carrying one factor of it:
//!
//! * the 65 1/s pole is the coil: the power amplifier drives the coil with a voltage, so the
//!   current lags it by `R_bob / L_bob` (`L_bob` fitted, 1.252 H with `R_bob` = 80 ohm);
//! * the 753 1/s pole is the valve stage: the spool moves until the feedback wire brings the
//!   flapper back to null, at a rate set by the pilot flow gain and the wire's share of the
//!   flapper stiffness, `K_qp k_w / (A_s (k_f + k_w))` (`k_w` fitted, 53.4 N/m);
//! * the integrator is the vane motor, whose oil spring (`2 beta D_m^2 / V_1`, 1.2e5 N m/rad)
//!   puts the hydraulic natural frequency of the motor alone at 1.1 kHz, far above the band;
//! * the gain is the torque motor's force constant (`k_phi` fitted, 0.169 N/A: 10 V, 125 mA,
//!   move the spool by 0.4 mm, its full stroke, and pass 29 L/min without load, the LOES's `k_sv`).
//!
//! The damping of the LOES (`1/(R7 C3)`) has no counterpart here: with the oil spring far above
//! the band nothing in the band needs it. docs/model.md ("The full servo valve") has the table of
//! every constant with its reason, the fit and the coupled eigenvalues.

#[cfg(feature = "analysis")]
pub mod g_est;
pub mod limits;
pub mod parameters;
pub mod rest;

#[cfg(feature = "analysis")]
pub use g_est::{compare_with_g_est, g_est, log_frequencies, open_loop_linearization, GEstPoint};
pub use parameters::{CoilDrive, ServoValveParameters};
pub use rest::rest_state;

use crate::bond_graph::{BondGraph, BondId, Domain, ElementId, SignalId};
use crate::math::dual::Dual;

use super::controller::{self, ControllerParameters};
use super::flapper_nozzle::{add_flapper_nozzle, add_spring_field};
use super::torque_motor::add_torque_motor;
use super::vane_motor::add_vane_motor;

/// Handles into the composed servo actuator.
#[derive(Clone, Copy, Debug)]
pub struct ServoValvePorts {
    /// The rotor 1-junction `<prefix>.rotor` (common flow: rotor speed). The torsion bar of the
    /// coupled model bonds onto it, as onto [`super::loes::LoesPorts::rotor`].
    pub rotor: ElementId,
    /// The rotor inertia `<prefix>.I_m`.
    pub i_m: ElementId,
    /// Bond rotor -> I_m (its flow is the rotor speed).
    pub i_m_bond: BondId,
    /// The supply 0-junction (`p_s`).
    pub supply: ElementId,
    /// The tank 0-junction (`p_t`).
    pub tank: ElementId,
    /// Input signal port `<prefix>.e_in`: the amplifier voltage \[V\]; connect it with
    /// [`BondGraph::connect_signal_port`].
    pub valve_command: SignalId,
    /// Rotor angle \[rad\] (integrator `<prefix>.theta_a`, a state).
    pub theta: SignalId,
    /// Rotor speed \[rad/s\].
    pub omega: SignalId,
    /// Load pressure `p_1 - p_2` \[Pa\].
    pub p_load: SignalId,
    /// Metered flow into chamber 1 \[m^3/s\].
    pub q_valve: SignalId,
    /// Coil current \[A\].
    pub current: SignalId,
    /// Flapper displacement \[m\].
    pub x_f: SignalId,
    /// Spool position \[m\].
    pub x_v: SignalId,
    /// Control pressures \[Pa\].
    pub p_a: SignalId,
    pub p_b: SignalId,
    /// Actuator chamber pressures \[Pa\].
    pub p_1: SignalId,
    pub p_2: SignalId,
    /// Total flow drawn from the supply \[m^3/s\].
    pub q_supply: SignalId,
}

/// Adds the full servo actuator (BG1 + BG2 + feedback wire + BG3, supply and tank) under
/// `prefix`. The valve command port is left unconnected. Rejects invalid parameters (a supply
/// pressure of zero or below, with an error naming `servo_valve.p_supply`).
pub fn add_servo_valve<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ServoValveParameters<S>,
) -> Result<ServoValvePorts, String> {
    let p = &p.map(Into::<Dual>::into);
    p.map(|x| x.v).validate()?;
    let omega_port = g.add_signal_port(format!("{prefix}.omega_port"));
    let theta = g.add_integrator(format!("{prefix}.theta_a"), omega_port);
    g.set_integrator_nominal(theta, 1.0);
    g.set_integrator_units(theta, Domain::Rotation.displacement());

    let supply_src = g.add_se(format!("{prefix}.supply"), p.p_supply);
    let tank_src = g.add_se(format!("{prefix}.tank"), p.p_tank);
    let supply = g.add_zero(format!("{prefix}.supply_line"));
    let tank = g.add_zero(format!("{prefix}.tank_line"));
    g.bond(supply_src, supply);
    // The tank source's bond points into the tank line like the supply's: its flow is negative
    // (the tank absorbs the return flow).
    g.bond(tank_src, tank);

    let tm = add_torque_motor(g, prefix, p);
    let fnz = add_flapper_nozzle(g, prefix, p, supply, tank, tm.x_f);
    add_spring_field(g, prefix, p, tm.flapper, fnz.spool, tm.x_f, fnz.x_v);
    let vm = add_vane_motor(g, prefix, p, supply, tank, fnz.x_v);
    g.connect_signal_port(omega_port, vm.omega);

    let q_supply = g.add_signal_port(format!("{prefix}.q_supply_port"));
    let q_pilot_a = g.add_flow_sensor(format!("{prefix}.q_R1"), fnz.supply_a_bond);
    let q_pilot_b = g.add_flow_sensor(format!("{prefix}.q_R2"), fnz.supply_b_bond);
    let q_main_a = g.add_flow_sensor(format!("{prefix}.q_PA_supply"), vm.supply_bonds[0]);
    let q_main_b = g.add_flow_sensor(format!("{prefix}.q_PB_supply"), vm.supply_bonds[1]);
    let sum = g.add_sum(
        format!("{prefix}.q_supply"),
        &[
            (1.0, q_pilot_a),
            (1.0, q_pilot_b),
            (1.0, q_main_a),
            (1.0, q_main_b),
        ],
    );
    g.connect_signal_port(q_supply, sum);

    Ok(ServoValvePorts {
        rotor: vm.rotor,
        i_m: vm.i_m,
        i_m_bond: vm.i_m_bond,
        supply,
        tank,
        valve_command: tm.command,
        theta,
        omega: vm.omega,
        p_load: vm.p_load,
        q_valve: vm.q_valve,
        current: tm.current,
        x_f: tm.x_f,
        x_v: fnz.x_v,
        p_a: fnz.p_a,
        p_b: fnz.p_b,
        p_1: vm.p_1,
        p_2: vm.p_2,
        q_supply,
    })
}

/// The nominal magnitude of each state of `g` as its fragments stated it, 1 where none did.
pub fn nominals(g: &BondGraph) -> Vec<f64> {
    g.state_nominals()
        .into_iter()
        .map(|n| n.unwrap_or(1.0))
        .collect()
}

/// The closed position loop of the paper with the full servo actuator: reference input "r"
/// \[V\], the actuator under "servo_valve", the controller under "controller". Outputs:
/// "y_pot", "theta_motor", "omega_motor", "p_load", "q_valve" (as the LOES loop) and
/// "servo_valve.i_coil", ".x_f", ".x_v", ".p_a", ".p_b", ".p_1", ".p_2", ".q_supply".
pub fn build_loop(
    p: &ServoValveParameters,
    ctrl: &ControllerParameters,
) -> Result<BondGraph, String> {
    let mut g = BondGraph::new("servo_valve_closed_loop");
    let r = g.add_input("r");
    let (sv, y_pot) = add_servo_valve_loop(&mut g, "servo_valve", p, ctrl, r)?;
    add_standard_outputs(&mut g, &sv, y_pot);
    Ok(g)
}

/// Adds the actuator and the controller to `g` and closes the loop on the reference signal
/// `r`; returns the ports and `y_POT`. The building block for the coupled model (bond the
/// torsion bar onto `ports.rotor`).
pub fn add_servo_valve_loop(
    g: &mut BondGraph,
    prefix: &str,
    p: &ServoValveParameters,
    ctrl: &ControllerParameters,
    r: SignalId,
) -> Result<(ServoValvePorts, SignalId), String> {
    let sv = add_servo_valve(g, prefix, p)?;
    let c = controller::add_controller(g, "controller", ctrl, r, sv.theta, sv.p_load);
    g.connect_signal_port(sv.valve_command, c.command);
    Ok((sv, c.y_pot))
}

/// The direct path `G(s)` of the loop: input "e" (the error `r - y_POT`) through `A1`, `A2`,
/// the actuator and the potentiometer; same outputs as [`build_loop`].
pub fn build_open_loop(
    p: &ServoValveParameters,
    ctrl: &ControllerParameters,
) -> Result<BondGraph, String> {
    let mut g = BondGraph::new("servo_valve_open_loop");
    let e = g.add_input("e");
    let sv = add_servo_valve(&mut g, "servo_valve", p)?;
    let (_, command) = controller::add_amplifiers(&mut g, "controller", ctrl, e, sv.p_load);
    g.connect_signal_port(sv.valve_command, command);
    let y_pot = controller::add_potentiometer(&mut g, "controller", ctrl, sv.theta);
    add_standard_outputs(&mut g, &sv, y_pot);
    Ok(g)
}

fn add_standard_outputs(g: &mut BondGraph, sv: &ServoValvePorts, y_pot: SignalId) {
    super::add_loop_outputs(g, y_pot, sv.theta, sv.omega, sv.p_load, sv.q_valve);
    add_valve_outputs(g, sv);
}

/// The valve's own outputs, named as the FMU's `servo_valve.*` variables.
pub fn add_valve_outputs(g: &mut BondGraph, sv: &ServoValvePorts) {
    g.add_output("servo_valve.i_coil", sv.current);
    g.add_output("servo_valve.x_f", sv.x_f);
    g.add_output("servo_valve.x_v", sv.x_v);
    g.add_output("servo_valve.p_a", sv.p_a);
    g.add_output("servo_valve.p_b", sv.p_b);
    g.add_output("servo_valve.p_1", sv.p_1);
    g.add_output("servo_valve.p_2", sv.p_2);
    g.add_output("servo_valve.q_supply", sv.q_supply);
}
