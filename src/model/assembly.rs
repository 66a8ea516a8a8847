//! The model compiled to `dx/dt = f(x, u)` for a parameter set (its bond graph from
//! [`compose`](super::compose)), with its held inputs and where its inputs, outputs and states
//! live among the FMU's variables. Split by job:
//! - this file: building it, the states and the inputs;
//! - `outputs`: writing the outputs, the states and their derivatives into the FMU's values, at
//!   once or when read, and the directional derivatives;
//! - `ode`: the [`OdeSystem`] the integrator advances.

mod ode;
mod outputs;
#[cfg(test)]
mod tests;

use nalgebra::DMatrix;

use crate::bond_graph::{CompiledModel, Linearization, PointCache, StateUnits};
use crate::fmu::Values;
use crate::fnv1a;
use crate::fragments::plate::PlateModel;
use crate::fragments::servo_valve;
use crate::solver::OdeSystem;

use super::compose::bond_graph_and_plate;
use ode::stamp;
use outputs::on_demand;

use super::affine::{max_abs_all, Affine, FINITE_BOUND, MAX_AFFINE_OUTPUTS};
use super::parameters::{HydraulicsModel, Parameters};
use super::variables::{idx, CONTINUOUS_STATES, VARIABLES};

/// The prefix of a continuous state's variable name before the compiled model's state name
/// (`x.hub.theta`): the states form their own tree, apart from the parameters of the elements
/// they belong to (`loes.C3` is a parameter, `x.loes.C3.q` the volume it stores).
pub const STATE_PREFIX: &str = "x.";

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
    /// Each state's units and its derivative's, as its fragment stated them.
    units: Vec<Option<StateUnits>>,
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
    /// `(K, C)` with |stored energy| ≤ K max|x|² + C when every storage is linear or declares a
    /// bound (`CompiledModel::stored_energy_bound`; the energy is then left until read too).
    energy_bound: Option<(f64, f64)>,
    /// The plate model the bond graph was built from, for the plate's natural frequencies.
    plate: PlateModel,
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
    /// The stored energy, all of whose storages are linear or declare a bound.
    Energy,
    /// The output `k` of the compiled model that is not affine, from its form
    /// ([`crate::bond_graph::PointForms::output`]).
    PointOutput(u32),
    /// The row `i` of f that is not affine, from its form
    /// ([`crate::bond_graph::PointForms::derivative`]).
    PointDerivative(u32),
}

impl Assembled {
    pub fn new(p: &Parameters) -> Result<Self, String> {
        Ok(Self::assemble(p)?.0)
    }

    /// The model and its linearisation at rest (the rest state, zero inputs; `A`, `B`, `C`, `D`
    /// by dual numbers, [`CompiledModel::linearize`]), which building the model's affine outputs
    /// computes already: what `hsp identify` compares with the measured responses at each trial.
    pub fn with_linearization_at_rest(p: &Parameters) -> Result<(Self, Linearization), String> {
        let (system, at_rest) = Self::assemble(p)?;
        let at_rest =
            at_rest.unwrap_or_else(|| system.compiled.linearize(&system.rest, &system.inputs));
        Ok((system, at_rest))
    }

    /// The model, and its linearisation at rest if building it computed that.
    fn assemble(p: &Parameters) -> Result<(Self, Option<Linearization>), String> {
        let (graph, plate) = bond_graph_and_plate(p)?;
        let mut compiled = graph.compile().map_err(|e| e.to_string())?;
        let position = super::variables::position;
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
        let mut at_rest = None;
        let affine = match (&constant_jacobian, compiled.constant_entries()) {
            (Some((_, jac)), _) => Some(Affine::new(jac, &compiled, &rest, &inputs, &mut at_rest)),
            (None, Some(fixed)) if 2 * compiled.nonaffine_rows().len() < compiled.n_states() => {
                Some(Affine::new(fixed, &compiled, &rest, &inputs, &mut at_rest))
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
        let system = Assembled {
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
            units: graph.state_units(),
            plate,
        };
        Ok((system, at_rest))
    }

    /// The plate model the bond graph was built from (eq. 4 and 5; its damping as the graph
    /// has it).
    pub fn plate(&self) -> &PlateModel {
        &self.plate
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

    /// Each state's units and its derivative's (`None` where its fragment stated none), in the
    /// compiled model's state order.
    pub fn state_units(&self) -> &[Option<StateUnits>] {
        &self.units
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
}
