//! Which fragments make up the model for a parameter set, composed into one bond graph and
//! compiled to `dx/dt = f(x, u)`; the compiled model with its held inputs is the
//! [`OdeSystem`] the integrator advances.

use nalgebra::DMatrix;

use crate::bond_graph::{BondGraph, CompiledModel};
use crate::fmi2::Values;
use crate::fragments::{loes, servo_valve};
use crate::solver::OdeSystem;

use super::parameters::{HydraulicsModel, Parameters};
use super::variables::{idx, VARIABLES};

/// The bond graph of the whole model for a parameter set.
pub fn bond_graph(p: &Parameters) -> Result<BondGraph, String> {
    match (p.hydraulics, p.motor_coupled) {
        (HydraulicsModel::Loes, false) => Ok(loes::build_loop(&p.loes, &p.controller)),
        (HydraulicsModel::ServoValve, false) => {
            servo_valve::build_loop(&p.servo_valve, &p.controller)
        }
        (_, true) => Err(
            "hydraulics.motor_coupled = true needs the hub, torsion bar and plate fragments, which this version does not have yet; use false (the motor alone, as in the paper's identification)".into(),
        ),
    }
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
    /// A typical magnitude of each state, scaling the absolute tolerance.
    nominal: Vec<f64>,
    /// The state at rest (all zero for the LOES; null pressures for the full servo valve).
    rest: Vec<f64>,
}

impl Assembled {
    pub fn new(p: &Parameters) -> Result<Self, String> {
        let graph = bond_graph(p)?;
        let compiled = graph.compile().map_err(|e| e.to_string())?;
        let position = |name: &str| VARIABLES.iter().position(|v| v.name == name);
        let input_index = compiled
            .input_names()
            .iter()
            .map(|n| {
                position(n).ok_or_else(|| format!("the model's input '{n}' is not an FMU variable"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let output_index = compiled
            .output_names()
            .iter()
            .map(|n| position(n))
            .collect();
        let nominal = compiled
            .state_names()
            .iter()
            .map(|n| nominal(n, p))
            .collect();
        let inputs = vec![0.0; input_index.len()];
        let rest = match p.hydraulics {
            HydraulicsModel::Loes => vec![0.0; compiled.n_states()],
            HydraulicsModel::ServoValve => {
                servo_valve::rest_state(&compiled, &inputs, "servo_valve", &p.servo_valve)?
            }
        };
        Ok(Assembled {
            inputs,
            rest,
            compiled,
            input_index,
            output_index,
            nominal,
        })
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
        changed
    }

    /// Puts back the inputs saved in an FMU state.
    pub fn restore_inputs(&mut self, inputs: &[f64]) {
        self.inputs.copy_from_slice(inputs);
    }

    /// Writes the outputs (and the stored energy) for state `x` into the FMU's values.
    pub fn write_outputs(&self, x: &[f64], values: &mut Values) {
        let mut y = vec![0.0; self.output_index.len()];
        self.compiled.outputs(x, &self.inputs, &mut y);
        for (v, i) in y.into_iter().zip(&self.output_index) {
            if let Some(i) = i {
                values.set_real(*i, v);
            }
        }
        values.set_real(idx::ENERGY, self.compiled.stored_energy(x));
    }
}

/// A typical magnitude of a state, by the element it belongs to: the rotor angle in radians, a
/// momentum at 10 rad/s, a displaced volume at 100 bar; for the full servo valve see
/// [`servo_valve::ServoValveParameters::nominal`] (its states span some 15 decades). Tolerances
/// are relative to these.
fn nominal(state: &str, p: &Parameters) -> f64 {
    if let Some(n) = p.servo_valve.nominal("servo_valve", state) {
        return n;
    }
    let element = state.rsplit_once('.').map_or(state, |(e, _)| e);
    match element {
        "loes.I_b" => p.loes.i_b * 10.0,
        "loes.C3" => p.loes.c3 * 1e7,
        _ => 1.0,
    }
}

impl OdeSystem for Assembled {
    fn dim(&self) -> usize {
        self.compiled.n_states()
    }

    fn rhs(&self, _t: f64, x: &[f64], dxdt: &mut [f64]) {
        self.compiled.derivatives(x, &self.inputs, dxdt);
    }

    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> bool {
        self.compiled.jacobian(x, &self.inputs, jac);
        true
    }

    fn is_autonomous(&self) -> bool {
        // The inputs are held constant over a communication step.
        true
    }
}
