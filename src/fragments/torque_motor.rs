//! BG1 of the paper (Fig. 2b): the torque motor of the servo valve, a voice coil driving the
//! flapper.
//!
//! ```text
//!   MSe e_in ---> 1 (coil current i) ---> GY k_phi ---> 1 (flapper velocity v_f)
//!                 |        |                            |        |        |
//!                 v        v                            v        v        v
//!               R_bob    I L_bob                      I m_f    R b_f    C 1/k_f
//! ```
//!
//! * `MSe` `<prefix>.amplifier`: the coil voltage `u_coil` \[V\]. With the voltage drive (the
//!   paper's power operational amplifier, [`CoilDrive::Voltage`]) it is the controller's command
//!   `e_in`; with a current-feedback amplifier ([`CoilDrive::Current`]) it is
//!   `K_i (G_i e_in - i)` within the compliance voltage `+-U_c` ([`add_current_amplifier`]);
//! * 1-junction `<prefix>.coil`: coil current `i` \[A\]; `R_bob` \[ohm\] in series with `L_bob`
//!   \[H\] (state `<prefix>.L_bob.p` = flux linkage `L_bob i` \[Wb\]);
//! * GY `<prefix>.k_phi` \[N/A = V s/m\]: force on the flapper `F = k_phi i`, back-EMF
//!   `k_phi v_f`;
//! * 1-junction `<prefix>.flapper`: flapper velocity `v_f` \[m/s\]; inertia `m_f` \[kg\] (effective
//!   armature-flapper mass referred to the nozzle), viscous friction `b_f` \[N s/m\]. The pivot
//!   (flexure tube) stiffness `k_f` \[N/m\] is not a one-port C here: the flapper, the spool and the
//!   feedback wire between them are three springs on two coordinates, which as three C elements
//!   would give dependent states (a singular Jacobian). They form one 2-port C-field,
//!   [`super::flapper_nozzle::add_spring_field`], whose first state is the flapper displacement
//!   `x_f` \[m\], positive towards nozzle A. The signal [`TorqueMotorPorts::x_f`] is a port that
//!   field connects.
//!
//! The flapper displacement is a signal ([`TorqueMotorPorts::x_f`]) that modulates the nozzle
//! restrictions of BG2: as in the paper, the fragments are coupled through control signals; the
//! nozzle jet reaction force on the flapper is not modelled. The feedback wire from the spool
//! (in the spring field of [`super::flapper_nozzle::add_spring_field`]) bonds onto the flapper junction.
//!
//! Sign conventions: a positive amplifier voltage drives a positive current, a positive force and
//! a positive `x_f` (the flapper moves towards nozzle A, raising control pressure `p_a`).

use crate::bond_graph::{BondGraph, BondId, Domain, ElementId, SignalId};
use crate::math::dual::Dual;

use super::controller::saturation_law;
use super::servo_valve::{CoilDrive, ServoValveParameters};

/// Coil current at which the flux state is stated nominal \[A\]: 10 V over the default 80 ohm.
const NOMINAL_CURRENT: f64 = 0.125;

/// Handles into the torque motor fragment.
#[derive(Clone, Copy, Debug)]
pub struct TorqueMotorPorts {
    /// The flapper 1-junction `<prefix>.flapper` (common flow: flapper velocity).
    pub flapper: ElementId,
    /// The coil 1-junction `<prefix>.coil` (common flow: coil current).
    pub coil: ElementId,
    /// Input signal port `<prefix>.e_in`: amplifier voltage \[V\], to be connected.
    pub command: SignalId,
    /// Coil current \[A\] (`<prefix>.i_coil`).
    pub current: SignalId,
    /// Flapper displacement \[m\] (signal port `<prefix>.x_f`, connected by the spring field).
    pub x_f: SignalId,
    /// Bond coil -> L_bob (its flow is the coil current).
    pub coil_bond: BondId,
}

/// Adds BG1 under `prefix` (e.g. "servo_valve"): element names `<prefix>.R_bob`, `.L_bob`,
/// `.k_phi`, `.m_f`, `.b_f`. The flapper stiffness `k_f` is added with the spring field.
pub fn add_torque_motor<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ServoValveParameters<S>,
) -> TorqueMotorPorts {
    let p = &p.map(Into::<Dual>::into);
    let command = g.add_signal_port(format!("{prefix}.e_in"));
    let coil_voltage = g.add_signal_port(format!("{prefix}.u_coil"));
    let amp = g.add_se(format!("{prefix}.amplifier"), coil_voltage);
    let coil = g.add_one(format!("{prefix}.coil"));
    let r_bob = g.add_r(format!("{prefix}.R_bob"), p.r_bob);
    let l_bob = g.add_i(format!("{prefix}.L_bob"), p.l_bob);
    let gy = g.add_gy(format!("{prefix}.k_phi"), p.k_phi);
    let flapper = g.add_one(format!("{prefix}.flapper"));
    let m_f = g.add_i(format!("{prefix}.m_f"), p.m_f);
    let b_f = g.add_r(format!("{prefix}.b_f"), p.b_f);
    // Flux at the nominal current; flapper momentum at 50 mm/s.
    g.set_nominal(l_bob, &[p.l_bob.v * NOMINAL_CURRENT]);
    g.set_nominal(m_f, &[p.m_f.v * 0.05]);
    g.set_domains(l_bob, &[Domain::Electrical]);
    g.set_domains(m_f, &[Domain::Translation]);

    g.bond(amp, coil);
    g.bond(coil, r_bob);
    let coil_bond = g.bond(coil, l_bob);
    g.bond(coil, gy);
    g.bond(gy, flapper);
    g.bond(flapper, m_f);
    g.bond(flapper, b_f);

    let current = g.add_flow_sensor(format!("{prefix}.i_coil"), coil_bond);
    let voltage = match p.drive {
        CoilDrive::Voltage => command,
        CoilDrive::Current => add_current_amplifier(g, prefix, p, command, current),
    };
    g.connect_signal_port(coil_voltage, voltage);
    let x_f = g.add_signal_port(format!("{prefix}.x_f"));
    TorqueMotorPorts {
        flapper,
        coil,
        command,
        current,
        x_f,
        coil_bond,
    }
}

/// The current-feedback amplifier (`drive` = current): the coil voltage
/// `u = lim(K_i (G_i e_in - i))`, signals `<prefix>.i_demand` (`G_i e_in`), `<prefix>.i_error`,
/// `<prefix>.K_i` and `<prefix>.u_limited`, the compliance limit `+-U_c` as the power
/// amplifier's smooth limit ([`super::controller::AmplifierLimit::Saturating`], [`saturation_law`]). The current is a state function
/// (the flux over `L_bob`), so the loop is not algebraic.
///
/// With the coil `i = u_L / (R_bob + L_bob s)` and ignoring the back-EMF, the current follows its
/// demand as `i / (G_i e_in) = K_i / (R_bob + K_i + L_bob s)`: a lag at `(R_bob + K_i) / L_bob`
/// (1.0 kHz with the defaults) in place of the voltage drive's `R_bob / L_bob` (64 1/s).
pub fn add_current_amplifier<S: Copy + Into<Dual>>(
    g: &mut BondGraph,
    prefix: &str,
    p: &ServoValveParameters<S>,
    command: SignalId,
    current: SignalId,
) -> SignalId {
    let p = &p.map(Into::<Dual>::into);
    let demand = g.add_gain(format!("{prefix}.i_demand"), p.g_i, command);
    let error = g.add_sum(
        format!("{prefix}.i_error"),
        &[(1.0, demand), (-1.0, current)],
    );
    let u = g.add_gain(format!("{prefix}.K_i"), p.k_i, error);
    g.add_function(
        format!("{prefix}.u_limited"),
        saturation_law(format!("compliance limit +-{} V", p.u_c), p.u_c),
        u,
    )
}
