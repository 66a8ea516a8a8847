//! Which fragments make up the model for a parameter set, composed into one bond graph and
//! compiled to `dx/dt = f(x, u)`; the compiled model with its held inputs is the
//! [`OdeSystem`] the integrator advances.

use nalgebra::DMatrix;

use crate::bond_graph::{BondGraph, CompiledModel};
use crate::fmu::Values;
use crate::fnv1a;
use crate::fragments::plate::modes::{natural_modes, NaturalMode};
use crate::fragments::plate::{self, Formulation, PlateModel};
use crate::fragments::{
    self, controller, hub, loes, reference, servo_valve, torsion_bar, validity,
};
use crate::solver::OdeSystem;

use super::affine::{max_abs, Affine, FINITE_BOUND, MAX_AFFINE_OUTPUTS};
use super::parameters::{HydraulicsModel, Parameters};
use super::variables::{idx, CONTINUOUS_STATES, VARIABLES};

/// The prefix of a continuous state's variable name before the compiled model's state name
/// (`x.hub.theta`): the states form their own tree, apart from the parameters of the elements
/// they belong to (`loes.C3` is a parameter, `x.loes.C3.q` the volume it stores).
pub const STATE_PREFIX: &str = "x.";

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
    p.controller.validate()?;
    let mut model = PlateModel::new(&p.plate)?;
    // The consistent structure on its hub is damped on its own modes (bar included, motor
    // clamped), in place of the R per clamped-plate mode and the bar's dashpot.
    let modal_damping = model.hub && p.plate.formulation == Formulation::Consistent;
    if modal_damping {
        let bar = p.motor_coupled.then_some(p.torsion_bar_k);
        model.dashpots = plate::damping::modal_dashpots(&model, bar, p.plate.zeta)?;
        // The coordinates the dashpots span lose their own R (`damping` is per plate coordinate).
        for j in plate::damping::damped_coordinates(&model) {
            let first = model.first_plate();
            model.damping[j - first] = 0.0;
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
            g.set_nominal(l.i_b, &[p.loes.i_b * 10.0]);
            g.set_nominal(l.c3, &[p.loes.c3 * 1e7]);
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
    let loop_reference = if p.reference.is_on() && !p.controller.external {
        reference::add_reference(&mut g, "reference", &p.reference, p.controller.k_pot, r).reference
    } else {
        r
    };
    g.add_output("controller.reference", loop_reference);
    let (y_pot, command) = controller::add_drive(
        &mut g,
        "controller",
        &p.controller,
        loop_reference,
        e_in,
        theta,
    );
    g.connect_signal_port(valve_command, command);
    g.add_output("controller.e_out", command);
    let bar = p.motor_coupled.then(|| {
        let c = if modal_damping {
            0.0
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
    Ok(g)
}

/// The natural frequencies of the plate model of a parameter set (eq. 14; the chosen
/// formulation and root condition, hub free, rigid mode left out), ascending.
pub fn plate_modes(p: &Parameters) -> Result<Vec<NaturalMode>, String> {
    natural_modes(&PlateModel::new(&p.plate)?)
}

/// Number of calculated frequency parameters `plate.f[1]` ... `plate.f[20]`.
pub const PLATE_FREQUENCIES: usize = 20;

/// Writes `plate.f[i]` (0 where the model has fewer modes).
pub fn write_plate_frequencies(p: &Parameters, values: &mut Values) -> Result<(), String> {
    let modes = plate_modes(p)?;
    for i in 0..PLATE_FREQUENCIES {
        let name = format!("plate.f[{}]", i + 1);
        let index = VARIABLES
            .iter()
            .position(|v| v.name == name)
            .ok_or_else(|| format!("{name} is not an FMU variable"))?;
        values.set_real(index, modes.get(i).map_or(0.0, |m| m.f_hz));
    }
    Ok(())
}

/// The compiled model, its held inputs, and where its inputs and outputs live among the FMU's
/// variables.
#[derive(Clone, Debug)]
pub struct Assembled {
    compiled: CompiledModel,
    /// The inputs held over the current communication step, in the compiled model's order.
    inputs: Vec<f64>,
    /// For each compiled input, its position among the FMU's variables.
    input_index: Vec<usize>,
    /// For each compiled output, its position among the FMU's variables, if it is one.
    output_index: Vec<Option<usize>>,
    /// For each compiled state, its place `k` among the continuous states the XML declares
    /// ([`CONTINUOUS_STATES`]), if it has one (a plate with more modes than Model Exchange
    /// declares has states without).
    state_slot: Vec<Option<usize>>,
    /// A typical magnitude of each state, scaling the absolute tolerance.
    nominal: Vec<f64>,
    /// The state at rest (all zero for the LOES; null pressures for the full servo valve).
    rest: Vec<f64>,
    /// The Jacobian and its stamp (a hash of its bits) when it is constant (the LOES with the
    /// plate: linear with constant coefficients), evaluated once per parameter set.
    constant_jacobian: Option<(u64, DMatrix<f64>)>,
    /// When the Jacobian varies: the stamp of its constant entries (kept by the compiled model),
    /// so that the integrator updates only the varying ones
    /// ([`OdeSystem::jacobian_constant_part`]).
    constant_part: Option<u64>,
    /// `dx/dt` and the outputs as sparse products for their affine rows (see [`Affine`]): all
    /// of them with a constant Jacobian, all but the servo valve's with the full valve.
    affine: Option<Affine>,
    /// For each of the FMU's variables, how it is computed on its own when it is read after a
    /// step ([`Assembled::write_at_point`]); empty when nothing is.
    on_demand: Vec<OnDemand>,
    /// K with |stored energy| ≤ K max|x|² when every storage is linear (the energy is then
    /// left until read too).
    energy_bound: Option<f64>,
}

/// How one of the FMU's variables is computed on its own, from the state, when it is read.
#[derive(Clone, Copy, Debug, PartialEq)]
enum OnDemand {
    /// Written at every communication point.
    No,
    /// The affine output `k` of the compiled model: `C_k x + y_k(0, u)`.
    Output(u32),
    /// The compiled state `i`.
    State(u32),
    /// The affine row `i` of f: `J_i x + f_i(0, u)`.
    Derivative(u32),
    /// The stored energy, all of whose storages are linear.
    Energy,
}

impl Assembled {
    pub fn new(p: &Parameters) -> Result<Self, String> {
        let graph = bond_graph(p)?;
        let mut compiled = graph.compile().map_err(|e| e.to_string())?;
        let position = |name: &str| VARIABLES.iter().position(|v| v.name == name);
        let input_index = compiled
            .input_names()
            .iter()
            .map(|n| {
                position(n).ok_or_else(|| format!("the model's input '{n}' is not an FMU variable"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let output_index: Vec<Option<usize>> = compiled
            .output_names()
            .iter()
            .map(|n| position(n))
            .collect();
        let state_slot: Vec<Option<usize>> = compiled
            .state_names()
            .iter()
            .map(|n| {
                let name = format!("{STATE_PREFIX}{n}");
                CONTINUOUS_STATES
                    .iter()
                    .position(|&(x, _)| VARIABLES[x].name == name)
            })
            .collect();
        let nominal = graph
            .state_nominals()
            .into_iter()
            .map(|n| n.unwrap_or(1.0))
            .collect::<Vec<f64>>();
        let inputs = vec![0.0; input_index.len()];
        let rest = match p.hydraulics {
            HydraulicsModel::Loes => vec![0.0; compiled.n_states()],
            HydraulicsModel::ServoValve => servo_valve::rest_state(
                &compiled,
                &inputs,
                "servo_valve",
                &p.servo_valve,
                &nominal,
            )?,
        };
        compiled.fix_constant_entries(&rest, &inputs);
        let constant_jacobian = compiled.jacobian_is_constant().then(|| {
            let n = compiled.n_states();
            let mut jac = DMatrix::zeros(n, n);
            compiled.jacobian(&rest, &inputs, &mut jac);
            (stamp(&jac), jac)
        });
        // All rows affine with a constant J; with a varying one the rows that are not affine
        // go through their part of the plan (worth it while they are a minority).
        let affine = match (&constant_jacobian, compiled.constant_entries()) {
            (Some((_, jac)), _) => Some(Affine::new(jac, &compiled, &rest, &inputs)),
            (None, Some(fixed)) if 2 * compiled.nonaffine_rows().len() < compiled.n_states() => {
                Some(Affine::new(fixed, &compiled, &rest, &inputs))
            }
            _ => None,
        };
        let constant_part = match (&constant_jacobian, compiled.constant_entries()) {
            (None, Some(fixed)) => Some(stamp(fixed)),
            _ => None,
        };
        let energy_bound = compiled.stored_energy_bound();
        let mut on_demand = on_demand(&compiled, affine.as_ref(), &output_index, &state_slot);
        if energy_bound.is_some() && !on_demand.is_empty() {
            on_demand[idx::ENERGY] = OnDemand::Energy;
        }
        Ok(Assembled {
            energy_bound,
            constant_jacobian,
            constant_part,
            affine,
            on_demand,
            inputs,
            rest,
            compiled,
            input_index,
            output_index,
            state_slot,
            nominal,
        })
    }

    /// For each compiled state, its place among the declared continuous states, if any.
    pub fn state_slots(&self) -> &[Option<usize>] {
        &self.state_slot
    }

    /// The first compiled state without a place among the declared continuous states.
    pub fn state_without_slot(&self) -> Option<&str> {
        let names = self.compiled.state_names();
        (0..names.len())
            .find(|&i| self.state_slot[i].is_none())
            .map(|i| names[i].as_str())
    }

    /// The compiled state vector from the continuous states in the FMU's values (0 for a state
    /// the XML does not declare).
    pub fn state_from_values(&self, values: &Values, x: &mut Vec<f64>) {
        x.clear();
        x.resize(self.dim(), 0.0);
        self.overlay_declared_states(values, x);
    }

    /// Overwrites the states of `x` that the XML declares with their values in `values`.
    pub fn overlay_declared_states(&self, values: &Values, x: &mut [f64]) {
        for (xi, slot) in x.iter_mut().zip(&self.state_slot) {
            if let Some(k) = slot {
                *xi = values.real(CONTINUOUS_STATES[*k].0);
            }
        }
    }

    /// The inputs in the FMU's values, in the compiled model's order (the held inputs unchanged).
    pub fn inputs_from_values(&self, values: &Values) -> Vec<f64> {
        self.input_index.iter().map(|&i| values.real(i)).collect()
    }

    pub fn compiled(&self) -> &CompiledModel {
        &self.compiled
    }

    pub fn dim(&self) -> usize {
        self.compiled.n_states()
    }

    pub fn nominal(&self) -> &[f64] {
        &self.nominal
    }

    pub fn inputs(&self) -> &[f64] {
        &self.inputs
    }

    /// The state at rest with zero inputs, where the simulation starts (for the full servo valve
    /// the null pressures, found by Newton's method when the model is built).
    pub fn initial_state(&self) -> Vec<f64> {
        self.rest.clone()
    }

    /// Takes the inputs from the FMU's values; true if any changed.
    pub fn set_inputs(&mut self, values: &Values) -> bool {
        let mut changed = false;
        for (u, &i) in self.inputs.iter_mut().zip(&self.input_index) {
            let v = values.real(i);
            if v.to_bits() != u.to_bits() {
                *u = v;
                changed = true;
            }
        }
        if changed {
            self.inputs_changed();
        }
        changed
    }

    /// Puts back the inputs saved in an FMU state.
    pub fn restore_inputs(&mut self, inputs: &[f64]) {
        self.inputs.copy_from_slice(inputs);
        self.inputs_changed();
    }

    fn inputs_changed(&mut self) {
        if let Some(affine) = &mut self.affine {
            affine.set_inputs(&self.compiled, &self.inputs);
        }
    }

    /// Writes the outputs (and the stored energy), the continuous states and their derivatives
    /// for state `x` into the FMU's values. A declared state the model does not have keeps its
    /// value, with derivative 0.
    pub fn write_outputs(&self, x: &[f64], values: &mut Values) {
        match &self.affine {
            Some(
                affine @ Affine {
                    outputs: Some(outputs),
                    ..
                },
            ) => {
                // Linear outputs: y(0, u) + C x instead of a pass through the plan.
                let mut y = [0.0; MAX_AFFINE_OUTPUTS];
                let y = &mut y[..outputs.y0.len()];
                outputs.blocks.product(x, &outputs.y0, y);
                for (i, slot) in self.state_slot.iter().enumerate() {
                    if let Some(k) = *slot {
                        values.set_real(CONTINUOUS_STATES[k].1, affine.derivative(i, x));
                    }
                }
                if affine.partial {
                    // The valve's outputs and rows through their part of the plan.
                    self.compiled.for_each_nonaffine_output_and_derivative(
                        x,
                        &self.inputs,
                        |k, v| y[k] = v,
                        |i, v| {
                            if let Some(k) = self.state_slot[i] {
                                values.set_real(CONTINUOUS_STATES[k].1, v);
                            }
                        },
                    );
                }
                for (&yk, target) in y.iter().zip(&self.output_index) {
                    if let Some(i) = *target {
                        values.set_real(i, yk);
                    }
                }
            }
            _ => self.write_plan_values(values, |output, derivative| {
                self.compiled
                    .for_each_output_and_derivative(x, &self.inputs, output, derivative)
            }),
        }
        for (slot, &xi) in self.state_slot.iter().zip(x) {
            if let Some(k) = slot {
                values.set_real(CONTINUOUS_STATES[*k].0, xi);
            }
        }
        values.set_real(idx::ENERGY, self.compiled.stored_energy(x));
    }

    /// Runs `pass`, a pass of the plan that reports compiled outputs `(k, y_k)` and rows of f
    /// `(i, dx_i/dt)`, writing each into its place among the FMU's values (an output that is no
    /// FMU variable, or the row of a state the XML does not declare, is dropped).
    fn write_plan_values(
        &self,
        values: &mut Values,
        pass: impl FnOnce(&mut dyn FnMut(usize, f64), &mut dyn FnMut(usize, f64)),
    ) {
        let values = std::cell::RefCell::new(values);
        pass(
            &mut |k, v| {
                if let Some(i) = self.output_index[k] {
                    values.borrow_mut().set_real(i, v);
                }
            },
            &mut |i, v| {
                if let Some(k) = self.state_slot[i] {
                    values.borrow_mut().set_real(CONTINUOUS_STATES[k].1, v);
                }
            },
        );
    }

    /// Writes what a communication point at state `x` needs at once and leaves the rest until it
    /// is read ([`Assembled::write_on_demand`]): writes the outputs and derivatives that are not
    /// affine (the servo valve's, from their part of the plan) and the stored energy if a
    /// storage is nonlinear, and returns true, when the affine outputs and derivatives (and the
    /// energy of linear storages) are shown to be finite at `x` (`Affine::finite_within`,
    /// `CompiledModel::stored_energy_bound`), so that none of them can turn out infinite when
    /// read. Otherwise (or when the model has nothing to leave) writes nothing and returns
    /// false: the caller writes everything with [`Assembled::write_outputs`].
    ///
    /// An importer reads a few of the 23 to 31 outputs, and the states and their derivatives
    /// rarely in co-simulation: computing all of them at every point cost as much as the steps
    /// of a linear configuration.
    pub fn write_at_point(&self, x: &[f64], values: &mut Values) -> bool {
        let Some(affine) = &self.affine else {
            return false;
        };
        let x_max = max_abs(x, |_| true);
        let energy_finite = self
            .energy_bound
            .is_none_or(|k| k * x_max * x_max < FINITE_BOUND);
        if self.on_demand.is_empty() || !affine.finite_within(x_max) || !energy_finite {
            return false;
        }
        if affine.partial {
            self.write_plan_values(values, |output, derivative| {
                self.compiled.for_each_nonaffine_output_and_derivative(
                    x,
                    &self.inputs,
                    output,
                    derivative,
                )
            });
        }
        if self.energy_bound.is_none() {
            values.set_real(idx::ENERGY, self.compiled.stored_energy(x));
        }
        true
    }

    /// Is the FMU's variable `index` left by [`Assembled::write_at_point`] to be computed when
    /// it is read?
    pub fn on_demand(&self, index: usize) -> bool {
        self.on_demand
            .get(index)
            .is_some_and(|&d| d != OnDemand::No)
    }

    /// Computes the FMU's variable `index` at state `x` into `values`, if it is one that
    /// [`Assembled::write_at_point`] leaves: the value [`Assembled::write_outputs`] writes.
    pub fn write_on_demand(&self, x: &[f64], index: usize, values: &mut Values) {
        let v = match (self.on_demand.get(index), &self.affine) {
            (Some(&OnDemand::Output(k)), Some(a)) => a.output(k as usize, x),
            (Some(&OnDemand::State(i)), _) => Some(x[i as usize]),
            (Some(&OnDemand::Derivative(i)), Some(a)) => Some(a.derivative(i as usize, x)),
            (Some(&OnDemand::Energy), _) => Some(self.compiled.stored_energy(x)),
            _ => None,
        };
        if let Some(v) = v {
            values.set_real(index, v);
        }
    }

    /// Exact directional derivatives at state `x` and inputs `u`: `dz = (d unknowns / d
    /// knowns) dv`, with `unknowns` positions of outputs or state derivatives among the FMU's
    /// variables and `knowns` positions of inputs or continuous states (checked by the caller).
    /// One forward pass of dual numbers through the plan.
    pub fn directional_derivative(
        &self,
        x: &[f64],
        u: &[f64],
        (unknowns, knowns): (&[usize], &[usize]),
        dv: &[f64],
        dz: &mut [f64],
    ) -> Result<(), String> {
        let c = &self.compiled;
        let mut vx = vec![0.0; c.n_states()];
        let mut vu = vec![0.0; c.n_inputs()];
        for (&k, &v) in knowns.iter().zip(dv) {
            if let Some(j) = self.input_index.iter().position(|&i| i == k) {
                vu[j] += v;
            } else if let Some(slot) = CONTINUOUS_STATES.iter().position(|&(s, _)| s == k) {
                // A declared state the model does not have moves nothing.
                if let Some(i) = self.state_slot.iter().position(|&s| s == Some(slot)) {
                    vx[i] += v;
                }
            } else {
                return Err(format!(
                    "'{}' is neither an input nor a continuous state of the model",
                    VARIABLES[k].name
                ));
            }
        }
        let mut ddx = vec![0.0; c.n_states()];
        let mut dy = vec![0.0; c.n_outputs()];
        c.directional(x, u, (&vx, &vu), &mut ddx, &mut dy);
        for (&k, out) in unknowns.iter().zip(dz.iter_mut()) {
            *out = if k == idx::ENERGY {
                c.stored_energy_derivative(x, &vx)
            } else if let Some(o) = self.output_index.iter().position(|&i| i == Some(k)) {
                dy[o]
            } else if let Some(slot) = CONTINUOUS_STATES.iter().position(|&(_, d)| d == k) {
                match self.state_slot.iter().position(|&s| s == Some(slot)) {
                    Some(i) => ddx[i],
                    // The derivative of a declared state the model does not have is 0.
                    None => 0.0,
                }
            } else if VARIABLES[k].causality == crate::fmu::Causality::Output {
                // An output of another configuration (the servo valve's with the LOES): 0.
                0.0
            } else {
                return Err(format!(
                    "'{}' is neither an output nor a state derivative of the model",
                    VARIABLES[k].name
                ));
            };
        }
        Ok(())
    }
}

/// Which of the FMU's variables can be left until they are read (see [`OnDemand`]): with affine
/// outputs, those outputs, the declared states and their affine derivatives; none otherwise.
fn on_demand(
    compiled: &CompiledModel,
    affine: Option<&Affine>,
    output_index: &[Option<usize>],
    state_slot: &[Option<usize>],
) -> Vec<OnDemand> {
    if affine.is_none_or(|a| a.outputs.is_none()) {
        return Vec::new();
    }
    let mut table = vec![OnDemand::No; VARIABLES.len()];
    let nonaffine = |list: &[u32], i: usize| list.binary_search(&(i as u32)).is_ok();
    for (k, target) in output_index.iter().enumerate() {
        if let (Some(i), false) = (*target, nonaffine(compiled.nonaffine_outputs(), k)) {
            table[i] = OnDemand::Output(k as u32);
        }
    }
    for (i, slot) in state_slot.iter().enumerate() {
        if let Some(k) = *slot {
            let (state, derivative) = CONTINUOUS_STATES[k];
            table[state] = OnDemand::State(i as u32);
            if !nonaffine(compiled.nonaffine_rows(), i) {
                table[derivative] = OnDemand::Derivative(i as u32);
            }
        }
    }
    table
}

/// FNV-1a hash of a matrix's bits: identifies a constant Jacobian for the solver's cache.
fn stamp(m: &DMatrix<f64>) -> u64 {
    m.iter().fold(fnv1a::OFFSET_BASIS, |h, v| {
        fnv1a::fnv1a64_from(h, &v.to_bits().to_le_bytes())
    })
}

impl OdeSystem for Assembled {
    fn dim(&self) -> usize {
        self.compiled.n_states()
    }

    fn rhs(&self, _t: f64, x: &[f64], dxdt: &mut [f64]) {
        match &self.affine {
            Some(affine) => affine.derivatives(&self.compiled, x, &self.inputs, dxdt),
            None => self.compiled.derivatives(x, &self.inputs, dxdt),
        }
    }

    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> bool {
        match &self.constant_jacobian {
            Some((_, j)) => jac.copy_from(j),
            None => self.compiled.jacobian(x, &self.inputs, jac),
        }
        true
    }

    fn constant_jacobian(&self) -> Option<u64> {
        self.constant_jacobian.as_ref().map(|(s, _)| *s)
    }

    fn jacobian_constant_part(&self) -> Option<u64> {
        self.constant_part
    }

    fn jacobian_varying(&self, _t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> bool {
        self.constant_part.is_some() && self.compiled.jacobian_varying(x, &self.inputs, jac)
    }

    fn jacobian_pattern(&self) -> Option<&[Vec<u32>]> {
        // The compiled plan's structural dependencies: J is zero outside them at every point.
        Some(self.compiled.jacobian_pattern())
    }

    fn is_autonomous(&self) -> bool {
        // The inputs are held constant over a communication step.
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmu::Experiment;
    use crate::model::parameters::set_by_name;

    fn assembled(sets: &[(&str, &str)]) -> (Assembled, Values) {
        let mut values = Values::from_start(&VARIABLES);
        for (name, value) in sets {
            set_by_name(&mut values, name, value).unwrap();
        }
        let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
        (Assembled::new(&p).unwrap(), values)
    }

    /// What a communication point leaves to be computed when read, computed then, is what
    /// `write_outputs` writes, bit for bit (the LOES with the plate, all of whose outputs wait;
    /// the full servo valve, whose own outputs and rows are written at once); and at a state
    /// too large for the bounds to show the waiting values finite, nothing waits.
    #[test]
    fn values_computed_when_read_are_those_written_at_once() {
        let configurations: [&[(&str, &str)]; 2] = [
            &[
                ("hydraulics.model", "1"),
                ("controller.saturation", "false"),
                ("hydraulics.motor_coupled", "true"),
                ("reference.angle", "0"),
                ("plate.Cd", "0"),
            ],
            &[
                ("hydraulics.model", "2"),
                ("hydraulics.motor_coupled", "true"),
            ],
        ];
        for (c, sets) in configurations.iter().enumerate() {
            let (mut a, mut values) = assembled(sets);
            values.set_real(idx::R, 0.3);
            a.set_inputs(&values);
            let x: Vec<f64> = a
                .initial_state()
                .iter()
                .zip(a.nominal())
                .enumerate()
                .map(|(i, (r, s))| r + s * (0.37 * i as f64).sin())
                .collect();
            let mut eager = values.clone();
            a.write_outputs(&x, &mut eager);
            let mut lazy = values.clone();
            assert!(a.write_at_point(&x, &mut lazy), "configuration {c}");
            let waiting: Vec<usize> = (0..VARIABLES.len()).filter(|&i| a.on_demand(i)).collect();
            // Every output of the LOES configuration waits; the valve's own do not.
            let outputs = a.output_index.iter().flatten().count();
            let waiting_outputs = a
                .output_index
                .iter()
                .flatten()
                .filter(|&&i| a.on_demand(i))
                .count();
            if c == 0 {
                assert_eq!(waiting_outputs, outputs);
            } else {
                assert!(waiting_outputs > 0 && waiting_outputs < outputs);
            }
            assert!(a.on_demand(idx::ENERGY) == (c == 0), "configuration {c}");
            for &i in &waiting {
                a.write_on_demand(&x, i, &mut lazy);
            }
            for (i, variable) in VARIABLES.iter().enumerate() {
                if let (crate::fmu::Value::Real(e), crate::fmu::Value::Real(l)) =
                    (eager.get(i), lazy.get(i))
                {
                    assert!(
                        e.to_bits() == l.to_bits() || (*e == 0.0 && *l == 0.0),
                        "configuration {c}, {}: {l} read, {e} written",
                        variable.name
                    );
                }
            }
            let huge: Vec<f64> = x.iter().map(|_| 1e300).collect();
            assert!(!a.write_at_point(&huge, &mut lazy), "configuration {c}");
        }
    }

    /// The sparse product `J x + f(0, u)` is the plan's `f(x, u)` to rounding, at points far
    /// from rest and after the inputs change (held or restored), and so are the outputs
    /// `C x + y(0, u)`; with the full servo valve, the valve's rows and outputs come from the
    /// plan's operations (the same bits) and the others from the products.
    #[test]
    fn affine_derivatives_and_outputs_are_the_plans() {
        let (mut a, mut values) = assembled(&[
            ("hydraulics.model", "1"),
            ("controller.saturation", "false"),
            ("hydraulics.motor_coupled", "true"),
        ]);
        assert!(a.affine.is_some());
        let n = a.dim();
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let (mut sparse, mut plan) = (vec![0.0; n], vec![0.0; n]);
        for trial in 0..20 {
            let x: Vec<f64> = a.nominal().iter().map(|s| s * next() * 100.0).collect();
            match trial % 3 {
                0 => {
                    values.set_real(idx::R, next());
                    values.set_real(idx::F1, 50.0 * next());
                    assert!(a.set_inputs(&values));
                }
                1 => a.restore_inputs(&[next(), 0.0, 10.0 * next(), 0.0]),
                _ => {}
            }
            a.rhs(0.0, &x, &mut sparse);
            a.compiled.derivatives(&x, &a.inputs, &mut plan);
            let scale = plan.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for i in 0..n {
                assert!(
                    (sparse[i] - plan[i]).abs() <= 1e-12 * scale,
                    "trial {trial}, {}: {} against {}",
                    a.compiled.state_names()[i],
                    sparse[i],
                    plan[i]
                );
            }
        }
        // The outputs written as C x + y(0, u) are the plan's, to rounding.
        assert!(a.affine.as_ref().unwrap().outputs.is_some());
        let x: Vec<f64> = a.nominal().iter().map(|s| s * next() * 100.0).collect();
        let mut written = Values::from_start(&VARIABLES);
        a.write_outputs(&x, &mut written);
        let mut y = vec![0.0; a.compiled.n_outputs()];
        a.compiled.outputs(&x, &a.inputs, &mut y);
        let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut compared = 0;
        for (k, target) in a.output_index.iter().enumerate() {
            if let Some(i) = *target {
                let v = written.real(i);
                assert!(
                    (v - y[k]).abs() <= 1e-12 * scale,
                    "{}: {v} against {}",
                    a.compiled.output_names()[k],
                    y[k]
                );
                compared += 1;
            }
        }
        assert!(compared >= 20, "{compared} outputs compared");
        // The full servo valve: its 7 valve rows through their part of the plan (the same
        // operations on the same numbers: the same bits), the other rows as the product.
        let (mut sv, mut values) = assembled(&[("hydraulics.model", "2")]);
        assert!(!sv.compiled.outputs_are_affine());
        let rows = sv.compiled.nonaffine_rows().to_vec();
        assert!(!rows.is_empty() && 2 * rows.len() < sv.dim(), "{rows:?}");
        let affine = sv.affine.as_ref().expect("partly affine");
        assert!(affine.partial && affine.outputs.is_some());
        assert!(!sv.compiled.nonaffine_outputs().is_empty());
        let n = sv.dim();
        let (mut mixed, mut plan) = (vec![0.0; n], vec![0.0; n]);
        for trial in 0..20 {
            let x: Vec<f64> = (sv.rest.iter().zip(sv.nominal()))
                .map(|(r, s)| r + s * next() * 0.2)
                .collect();
            if trial % 2 == 0 {
                values.set_real(idx::R, next());
                values.set_real(idx::F2, 50.0 * next());
                assert!(sv.set_inputs(&values));
            }
            sv.rhs(0.0, &x, &mut mixed);
            sv.compiled.derivatives(&x, &sv.inputs, &mut plan);
            assert!(plan.iter().all(|v| v.is_finite()), "trial {trial}");
            let scale = plan.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for i in 0..n {
                let name = &sv.compiled.state_names()[i];
                if rows.contains(&(i as u32)) {
                    assert_eq!(
                        mixed[i].to_bits(),
                        plan[i].to_bits(),
                        "trial {trial}, {name}"
                    );
                } else {
                    assert!(
                        (mixed[i] - plan[i]).abs() <= 1e-12 * scale,
                        "trial {trial}, {name}: {} against {}",
                        mixed[i],
                        plan[i]
                    );
                }
            }
            // The outputs and derivatives written at a communication point: the valve's from
            // the plan's operations (the same bits), the others as products.
            let mut written = Values::from_start(&VARIABLES);
            sv.write_outputs(&x, &mut written);
            let mut y = vec![0.0; sv.compiled.n_outputs()];
            sv.compiled.evaluate(&x, &sv.inputs, &mut plan, &mut y);
            let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for (k, target) in sv.output_index.iter().enumerate() {
                let (Some(i), name) = (*target, &sv.compiled.output_names()[k]) else {
                    continue;
                };
                let v = written.real(i);
                if sv.compiled.nonaffine_outputs().contains(&(k as u32)) {
                    assert_eq!(v.to_bits(), y[k].to_bits(), "trial {trial}, {name}");
                } else {
                    let tol = 1e-12 * scale;
                    assert!(
                        (v - y[k]).abs() <= tol,
                        "trial {trial}, {name}: {v}, {}",
                        y[k]
                    );
                }
            }
            for (i, slot) in sv.state_slot.iter().enumerate() {
                if let Some(k) = *slot {
                    let v = written.real(CONTINUOUS_STATES[k].1);
                    let scale = plan.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                    assert!(
                        (v - plan[i]).abs() <= 1e-12 * scale,
                        "trial {trial}, der {i}"
                    );
                }
            }
        }
    }
}
