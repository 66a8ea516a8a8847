//! Which fragments make up the model for a parameter set, composed into one bond graph
//! ([`bond_graph`]), and the plate's natural frequencies for that set.

use crate::bond_graph::BondGraph;
use crate::fmu::Values;
use crate::fragments::plate::modes::{natural_modes, NaturalMode};
use crate::fragments::plate::{self, Formulation, PlateModel};
use crate::fragments::{
    self, controller, hub, loes, reference, servo_valve, torsion_bar, validity,
};
use crate::math::dual::Dual;

use super::assembly::Assembled;
use super::parameters::{HydraulicsModel, Parameters};
use super::variables::position;

/// The bond graph of the whole model for a parameter set.
///
/// Always: the inputs `r`, `F1`, `F2`, `e_in`; the hydraulic actuator (the LOES of Fig. 3, or the
/// full servo valve of Fig. 2b, per `hydraulics.model`) driven by the analog controller closing
/// the position loop on `r`, or with `controller.external` by `e_in` (see
/// [`controller::add_drive`]); the power amplifier's output limit; the plate (with its hub unless
/// the root is locked). With `hydraulics.motor_coupled` the motor rotor drives the hub through
/// the torsion bar (Fig. 8); without it the motor runs alone, as in the paper's identification,
/// and the plate is driven by F1 and F2 only (hub free on its gas bearing, or locked).
pub fn bond_graph(p: &Parameters) -> Result<BondGraph, String> {
    Ok(bond_graph_and_plate(p)?.0)
}

/// The bond graph of the whole model for a parameter set ([`bond_graph`]) and the plate model
/// it was built from, whose mass and stiffness give the plate's natural frequencies (eq. 14)
/// without building the plate model a second time (its damping, which they do not read, set
/// for the graph).
pub fn bond_graph_and_plate(p: &Parameters) -> Result<(BondGraph, PlateModel), String> {
    bond_graph_and_plate_for(&p.map(Dual::from))
}

/// [`bond_graph_and_plate`] from parameters in dual numbers: the model built for the parameter
/// whose derivatives they carry ([`Parameters::seeded`]), its constants with their derivatives
/// (`crate::model::sensitivity`). The LOES, the servo valve, the controller, the torsion bar
/// (stiffness and damping ratio), the plate (every `plate.*`: its Ritz model built in dual
/// numbers, [`PlateModel::for_parameters`]) and the hub's inertia `hub.I_H` carry them (the
/// structure's modal dashpots with the derivatives of its modes along all of these), the
/// command generator's move, and the validity monitors' gains: every Real parameter but
/// `controller.k_pl` at 0, which is refused (the pressure feedback is not in the model there).
pub fn bond_graph_and_plate_for(p: &Parameters<Dual>) -> Result<(BondGraph, PlateModel), String> {
    // The plate and hub carry their derivatives through the Ritz model (every `plate.*` and
    // `hub.I_H`); the values alone for the choices and the nominal magnitudes.
    let plate_parameters = p.plate.map(|x| x.v);
    let controller = &p.controller;
    let controller_values = controller.map(|x| x.v);
    controller_values.validate()?;
    if !controller_values.pressure_feedback() && controller.k_pl.d != 0.0 {
        return Err(
            "controller.k_pl at 0 has no exact sensitivity: the pressure feedback and its \
             filter's state are not in the model at 0, and are at any other value"
                .into(),
        );
    }
    let zeta = p.plate.zeta;
    let mut model = PlateModel::for_parameters(&p.plate)?;
    // The consistent structure on its hub is damped on its own modes (bar included, motor
    // clamped), in place of the R per clamped-plate mode and the bar's dashpot.
    let modal_damping = model.hub && plate_parameters.formulation == Formulation::Consistent;
    if modal_damping {
        // The structure's modes, and so its dashpots, move with the bar's stiffness and with
        // the plate's and hub's parameters (the model's derivatives).
        let bar = p.motor_coupled.then_some(p.torsion_bar_k);
        model.dashpots = plate::damping::modal_dashpots(&model, bar, zeta)?;
        // The coordinates the dashpots span lose their own R (`damping` is per plate coordinate).
        for j in plate::damping::damped_coordinates(&model) {
            let first = model.first_plate();
            model.damping[j - first] = 0.0;
            model.damping_derivative[j - first] = 0.0;
        }
    }
    let mut g = BondGraph::new("hydraulic_slewing_plate");
    let r = g.add_input("r");
    let f1 = g.add_input("F1");
    let f2 = g.add_input("F2");
    let e_in = g.add_input("e_in");
    // The actuator, its valve command port left open for the drive.
    let (rotor, valve_command, theta, omega, p_load, q_valve) = match p.hydraulics {
        HydraulicsModel::Loes => {
            let l = loes::add_loes(&mut g, "loes", &p.loes);
            // Momentum at 10 rad/s, compressed volume at 100 bar.
            g.set_nominal(l.i_b, &[p.loes.i_b.v * 10.0]);
            g.set_nominal(l.c3, &[p.loes.c3.v * 1e7]);
            (
                l.rotor,
                l.valve_command,
                l.theta,
                l.omega,
                l.p_load,
                l.q_valve,
            )
        }
        HydraulicsModel::ServoValve => {
            let sv = servo_valve::add_servo_valve(&mut g, "servo_valve", &p.servo_valve)?;
            servo_valve::add_valve_outputs(&mut g, &sv);
            (
                sv.rotor,
                sv.valve_command,
                sv.theta,
                sv.omega,
                sv.p_load,
                sv.q_valve,
            )
        }
    };
    // The command generator's move on top of r, unless an external controller drives the coil.
    let reference = &p.reference;
    let loop_reference = if reference.map(|x| x.v).is_on() && !controller.external {
        reference::add_reference(&mut g, "reference", reference, controller.k_pot, r).reference
    } else {
        r
    };
    g.add_output("controller.reference", loop_reference);
    let (y_pot, command) = controller::add_drive(
        &mut g,
        "controller",
        controller,
        loop_reference,
        e_in,
        theta,
        p_load,
    );
    g.connect_signal_port(valve_command, command);
    g.add_output("controller.e_out", command);
    let bar = p.motor_coupled.then(|| {
        let c = if modal_damping {
            Dual::from(0.0)
        } else {
            torsion_bar::damping_coefficient(
                p.torsion_bar_k,
                p.torsion_bar_zeta,
                p.plate.hub_total_inertia(),
            )
        };
        torsion_bar::add_torsion_bar(&mut g, "torsion_bar", p.torsion_bar_k, c, rotor)
    });
    let hub = model
        .hub
        .then(|| hub::add_hub(&mut g, "hub", model.hub_one_port()));
    let plate = plate::add_plate(
        &mut g,
        "plate",
        &model,
        hub.as_ref(),
        bar.map(|b| b.node),
        bar.map(|b| b.twist),
        [f1, f2],
    );
    fragments::add_loop_outputs(&mut g, y_pot, theta, omega, p_load, q_valve);
    let (theta_hub, omega_hub) = match &hub {
        Some(h) => (h.theta, h.omega),
        None => {
            let zero = g.add_constant("hub.locked", 0.0);
            (zero, zero)
        }
    };
    g.add_output("theta_hub", theta_hub);
    g.add_output("omega_hub", omega_hub);
    let torque = match &bar {
        Some(b) => b.torque,
        None => g.add_constant("torsion_bar.uncoupled", 0.0),
    };
    g.add_output("torsion_bar.torque", torque);
    g.add_output("w_tip", plate.w_tip);
    g.add_output("acc_tip", plate.acc_tip);
    validity::add_monitors(
        &mut g,
        validity::Watched {
            w_tip: plate.w_tip,
            plate_stress: plate.stress,
            bar_torque: torque,
            omega_hub,
        },
        &p.limits,
        p.plate.a,
        validity::first_clamped_bending(p.plate.a, p.plate.rigidity(), p.plate.areal_mass()),
    );
    for (k, &a) in plate.acc.iter().enumerate() {
        g.add_output(format!("acc[{}]", k + 1), a);
    }
    Ok((g, model))
}

/// The natural frequencies of the plate model of a parameter set (eq. 14; the chosen
/// formulation and root condition, hub free, rigid mode left out), ascending.
pub fn plate_modes(p: &Parameters) -> Result<Vec<NaturalMode>, String> {
    natural_modes(&PlateModel::new(&p.plate)?)
}

/// Number of calculated frequency parameters `plate.f[1]` ... `plate.f[20]`.
pub const PLATE_FREQUENCIES: usize = 20;

/// Writes `plate.f[i]` (0 where the model has fewer modes) of the plate model the model was
/// built from ([`Assembled::plate`]).
pub fn write_plate_frequencies(system: &Assembled, values: &mut Values) -> Result<(), String> {
    let modes = natural_modes(system.plate())?;
    for i in 0..PLATE_FREQUENCIES {
        let name = format!("plate.f[{}]", i + 1);
        let index = position(&name).ok_or_else(|| format!("{name} is not an FMU variable"))?;
        values.set_real(index, modes.get(i).map_or(0.0, |m| m.f_hz));
    }
    Ok(())
}
