//! The assembled model behind the FMU: the paper's fragments composed into one bond graph,
//! compiled to state equations, advanced by the stiff integrator, and exposed through the variable
//! table of `modelDescription.xml`.
//!
//! - [`variables`]: the generated variable table (positions and value references by name).
//! - [`parameters`]: the typed parameter set read from the FMU's values, and `--set NAME=VALUE`.
//! - [`presets`]: the paper's configurations as named parameter sets (`hsp run --preset NAME`).
//! - [`assembly`]: which fragments make up the model for a parameter set, and the resulting
//!   [`OdeSystem`](crate::solver::OdeSystem).
//! - [`frf`]: frequency responses of the linearised model and their resonance peaks.
//! - [`HydraulicSlewingPlate`]: the [`FmuModel`] the C ABI exports.

pub mod assembly;
pub mod frf;
pub mod parameters;
pub mod presets;
pub mod variables;

use serde::{Deserialize, Serialize};

use crate::fmi2::{Experiment, FmuModel, LogCategory, StepFailure, Value, Values, Variable};
use crate::solver::Integrator;
use assembly::Assembled;
use parameters::Parameters;
use variables::idx;

/// The hydraulic slewing plate as an FMU model.
#[derive(Default)]
pub struct HydraulicSlewingPlate {
    /// The parameters the model was last built from.
    parameters: Option<Parameters>,
    /// The compiled model with its held inputs.
    system: Option<Assembled>,
    integrator: Option<Integrator>,
}

/// The model's part of an FMU state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ModelState {
    integrator: Option<Integrator>,
    inputs: Vec<f64>,
}

impl HydraulicSlewingPlate {
    /// (Re)builds the compiled model when the parameters differ from those it was built from.
    fn build(&mut self, values: &Values, experiment: &Experiment) -> Result<(), String> {
        let parameters = Parameters::from_values(values, experiment)?;
        if self.parameters.as_ref() != Some(&parameters) || self.system.is_none() {
            self.system = Some(Assembled::new(&parameters)?);
            self.parameters = Some(parameters);
        }
        Ok(())
    }

    /// The compiled model, once built.
    pub fn system(&self) -> Option<&Assembled> {
        self.system.as_ref()
    }

    pub fn integrator(&self) -> Option<&Integrator> {
        self.integrator.as_ref()
    }

    /// Writes outputs and solver statistics for the integrator's current point.
    fn write_outputs(&self, values: &mut Values) {
        let (Some(system), Some(integrator)) = (&self.system, &self.integrator) else {
            return;
        };
        system.write_outputs(integrator.x(), values);
        let stats = integrator.stats();
        let clamp = |n: u64| i32::try_from(n).unwrap_or(i32::MAX);
        values.set_integer(idx::SOLVER_STEPS, clamp(stats.accepted));
        values.set_integer(idx::SOLVER_REJECTED, clamp(stats.rejected));
        values.set_integer(idx::SOLVER_F_EVALS, clamp(stats.f_evals));
        values.set_integer(idx::SOLVER_JAC_EVALS, clamp(stats.jac_evals));
        values.set_integer(idx::SOLVER_LU, clamp(stats.lu_decompositions));
    }
}

impl FmuModel for HydraulicSlewingPlate {
    type State = ModelState;

    const MODEL_IDENTIFIER: &'static str = variables::MODEL_IDENTIFIER;
    const GUID: &'static str = variables::GUID;

    fn variables() -> &'static [Variable] {
        &variables::VARIABLES
    }

    fn index_of(value_reference: u32) -> Option<usize> {
        variables::index_of(value_reference)
    }

    fn new() -> Self {
        Self::default()
    }

    fn check(&self, index: usize, value: &Value) -> Result<(), String> {
        parameters::check(index, value)
    }

    fn initialize(&mut self, values: &mut Values, experiment: &Experiment) -> Result<(), String> {
        self.build(values, experiment)?;
        let (Some(system), Some(parameters)) = (&mut self.system, &self.parameters) else {
            return Err("the model was not built".into());
        };
        system.set_inputs(values);
        assembly::write_plate_frequencies(parameters, values)?;
        let integrator = Integrator::new(
            parameters.solver_options(system),
            experiment.start_time,
            system.initial_state(),
        )
        .map_err(|e| e.to_string())?;
        self.integrator = Some(integrator);
        self.write_outputs(values);
        Ok(())
    }

    fn do_step(
        &mut self,
        values: &mut Values,
        _t_start: f64,
        t_end: f64,
        log: &mut dyn FnMut(LogCategory, &str),
    ) -> Result<(), StepFailure> {
        let (Some(system), Some(integrator)) = (&mut self.system, &mut self.integrator) else {
            return Err(StepFailure {
                last_successful_time: t_end,
                message: "the model was not initialized".into(),
            });
        };
        if system.set_inputs(values) {
            // A zero-order-hold jump of the inputs: the solution has a kink here.
            integrator.notify_discontinuity();
        }
        let result = integrator.advance_to(&*system, t_end);
        let stats = *integrator.stats();
        log(
            LogCategory::Solver,
            &format!(
                "t = {}: {} steps ({} rejected), {} f evaluations, {} Jacobians, {} LU factorisations so far",
                integrator.t(),
                stats.accepted,
                stats.rejected,
                stats.f_evals,
                stats.jac_evals,
                stats.lu_decompositions
            ),
        );
        let reached = integrator.t();
        self.write_outputs(values);
        result.map_err(|e| StepFailure {
            last_successful_time: reached,
            message: e.to_string(),
        })
    }

    fn save_state(&self) -> ModelState {
        ModelState {
            integrator: self.integrator.clone(),
            inputs: self
                .system
                .as_ref()
                .map(|s| s.inputs().to_vec())
                .unwrap_or_default(),
        }
    }

    fn restore_state(
        &mut self,
        state: &ModelState,
        values: &Values,
        experiment: &Experiment,
    ) -> Result<(), String> {
        let Some(integrator) = &state.integrator else {
            // Saved before initialisation: nothing is built yet.
            self.integrator = None;
            return Ok(());
        };
        self.build(values, experiment)?;
        let Some(system) = &mut self.system else {
            return Err("the model was not built".into());
        };
        if integrator.x().len() != system.dim() || state.inputs.len() != system.inputs().len() {
            return Err(format!(
                "the FMU state has {} states and {} inputs, the model {} and {}",
                integrator.x().len(),
                state.inputs.len(),
                system.dim(),
                system.inputs().len()
            ));
        }
        system.restore_inputs(&state.inputs);
        self.integrator = Some(integrator.clone());
        Ok(())
    }
}
