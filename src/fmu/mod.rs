//! The version-neutral FMU core: everything an FMU instance is and does, whatever FMI version the
//! importer speaks. The FMI layers (`crate::fmi2`, `crate::fmi3`) are thin translations over
//! it: their C types, their arguments turned into the core's, and the exported symbols. Nothing
//! here names an FMI version's types; the messages name the function the importer called, which
//! the layer passes in at the boundary ([`boundary::with_instance`]), in the manner of the
//! Modelica Reference FMUs' shared checks.
//!
//! - [`status`]: the neutral [`Status`] every call returns, mapped once by each layer.
//! - [`calls`]: the one table of which call is allowed in which state, and which interface each
//!   call belongs to.
//! - [`variables`]: variable metadata (generated from `modelDescription.xml` by `build.rs`) and
//!   the value store.
//! - [`logging`]: the logger with its categories and numbers printed short; each layer plugs in
//!   its callback as a [`LogSink`](logging::LogSink).
//! - [`panic_guard`]: the panic hook and guard that keep panics inside the FMU and off the host's
//!   stderr.
//! - [`instance`]: one FMU instance: state machine, get/set, step, Model Exchange's continuous
//!   states and derivatives, directional derivatives, saving and restoring FMU states.
//! - [`fmu_state`]: what an FMU state holds and its serialised form.
//! - [`boundary`]: what every C entry point does the same way in both versions: checking instance
//!   and FMU-state pointers, reading C arrays and strings, the panic guard around the call.
//!
//! A model plugs in by implementing [`FmuModel`].

pub mod boundary;
pub mod calls;
pub mod fmu_state;
pub mod instance;
pub mod logging;
pub mod panic_guard;
pub mod status;
pub mod variables;

pub use calls::Interface;
use serde::{de::DeserializeOwned, Serialize};
pub use status::Status;
pub use variables::{Causality, EnumerationType, Item, Kind, Value, Values, Variability, Variable};

/// The experiment the importer sets up (FMI 2.0 `fmi2SetupExperiment`, FMI 3.0
/// `fmi3EnterInitializationMode`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Experiment {
    pub tolerance: Option<f64>,
    pub start_time: f64,
    pub stop_time: Option<f64>,
}

impl Default for Experiment {
    fn default() -> Self {
        Experiment {
            tolerance: None,
            start_time: 0.0,
            stop_time: None,
        }
    }
}

/// The log categories every FMU of this crate declares, in `modelDescription.xml` order (which is
/// also the order of the discriminants: `category as usize` indexes [`LogCategory::ALL`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogCategory {
    StatusWarning,
    StatusDiscard,
    StatusError,
    StatusFatal,
    All,
    Calls,
    Solver,
}

impl LogCategory {
    pub const ALL: [LogCategory; 7] = [
        LogCategory::StatusWarning,
        LogCategory::StatusDiscard,
        LogCategory::StatusError,
        LogCategory::StatusFatal,
        LogCategory::All,
        LogCategory::Calls,
        LogCategory::Solver,
    ];

    /// The name in `<LogCategories>`.
    pub fn name(self) -> &'static str {
        match self {
            LogCategory::StatusWarning => "logStatusWarning",
            LogCategory::StatusDiscard => "logStatusDiscard",
            LogCategory::StatusError => "logStatusError",
            LogCategory::StatusFatal => "logStatusFatal",
            LogCategory::All => "logAll",
            LogCategory::Calls => "logCalls",
            LogCategory::Solver => "logSolver",
        }
    }

    pub fn from_name(name: &str) -> Option<LogCategory> {
        LogCategory::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// Where a model sends log messages during a step: the message is built (by the closure) only
/// when its category is enabled, so that a step costs no formatting with logging off.
pub type StepLog<'a> = dyn FnMut(LogCategory, &dyn Fn() -> String) + 'a;

/// A communication step the model could not complete: the time it reached (its state stays there)
/// and why.
#[derive(Clone, Debug, PartialEq)]
pub struct StepFailure {
    pub last_successful_time: f64,
    pub message: String,
}

/// What a model provides to be exported as an FMU (FMI 2.0 and 3.0 alike).
///
/// The generic layer owns the [`Values`] of all variables (checked against type, range and
/// call-sequence rules before the model sees them); the model reads parameters and inputs from
/// them and writes its outputs and calculated parameters into them.
///
/// For Model Exchange the continuous states are variables too (`<Derivatives>` of the XML names
/// each state's derivative, [`FmuModel::continuous_states`]): the generic layer keeps the states
/// the importer sets in [`Values`], and [`FmuModel::evaluate`] computes the derivatives and
/// outputs from them. A model without continuous states offers co-simulation only.
pub trait FmuModel: Sized + Send {
    /// The model's part of an FMU state: everything besides the variable values that the model
    /// needs to continue bit-identically (the integrator, say).
    type State: Clone + Serialize + DeserializeOwned + Send;

    const MODEL_IDENTIFIER: &'static str;
    const GUID: &'static str;

    /// The variable table, in `modelDescription.xml` order.
    fn variables() -> &'static [Variable];

    /// The position in [`FmuModel::variables`] of a value reference.
    fn index_of(value_reference: u32) -> Option<usize>;

    /// A model before initialisation.
    fn new() -> Self;

    /// Checks a value the environment sets, beyond its type and declared range (e.g. a strictly
    /// positive capacitance). The message names the variable.
    fn check(&self, _index: usize, _value: &Value) -> Result<(), String> {
        Ok(())
    }

    /// Builds the model from the parameter values and computes the initial outputs and calculated
    /// parameters into `values`. Called when initialisation mode ends, and before then when the
    /// environment reads an initial unknown; it may be called several times. Warnings about the
    /// parameters go to `log`.
    fn initialize(
        &mut self,
        values: &mut Values,
        experiment: &Experiment,
        log: &mut StepLog,
    ) -> Result<(), String>;

    /// Advances from `t_start` to exactly `t_end` with the inputs in `values` held constant, then
    /// writes the outputs into `values` (or leaves some to [`FmuModel::refresh`]). On failure the model stays at the last time it reached,
    /// with its outputs written for that time.
    fn do_step(
        &mut self,
        values: &mut Values,
        t_start: f64,
        t_end: f64,
        log: &mut StepLog,
    ) -> Result<(), StepFailure>;

    /// Brings values that [`FmuModel::do_step`] left to be computed when read up to date:
    /// variable `index` before it is read, or every such value (`None`) before the values are
    /// used as a whole (saved in an FMU state, or read by the model itself). Default: nothing
    /// to do (`do_step` writes every value).
    ///
    /// Whatever `do_step` leaves must be shown finite when it returns OK: a value computed
    /// here may not turn out non-finite.
    fn refresh(&mut self, _values: &mut Values, _index: Option<usize>) {}

    /// The continuous states as `(state, derivative)` positions in [`FmuModel::variables`], in
    /// the order of `<ModelStructure><Derivatives>` (the order of the continuous-state arrays of the C API).
    /// Empty: the model offers no Model Exchange.
    fn continuous_states() -> &'static [(usize, usize)] {
        &[]
    }

    /// Model Exchange: called once initialisation has built the model; fails with a message
    /// naming the parameters when the built model does not fit the declared continuous states.
    fn check_model_exchange(&self) -> Result<(), String> {
        Err("this model offers co-simulation only".into())
    }

    /// Model Exchange: computes the derivatives, outputs and other continuous variables into
    /// `values` from the continuous states and inputs in `values` at `time`. Called lazily, when
    /// a value is read after the time, the states or an input changed.
    fn evaluate(&mut self, _values: &mut Values, _time: f64) -> Result<(), String> {
        Err("this model offers co-simulation only".into())
    }

    /// The nominal value of each continuous state (in [`FmuModel::continuous_states`] order) of
    /// the built model.
    fn nominals(&self, out: &mut [f64]) {
        out.fill(1.0);
    }

    /// The directional derivative `dz = (d unknowns / d knowns) dv` at the point in `values`
    /// (states and inputs), from the model's exact Jacobian. `unknowns` are positions of outputs
    /// or state derivatives, `knowns` of inputs or continuous states (checked by the caller).
    fn directional_derivative(
        &mut self,
        _values: &Values,
        _unknowns: &[usize],
        _knowns: &[usize],
        _dv: &[f64],
        _dz: &mut [f64],
    ) -> Result<(), String> {
        Err("the model provides no directional derivatives".into())
    }

    /// The model's part of an FMU state.
    fn save_state(&self) -> Self::State;

    /// Restores a state saved by [`FmuModel::save_state`], together with the `values` and
    /// experiment saved with it (already checked against the variable table). `time` is the FMU's
    /// time when the state was taken after initialisation, `None` before. The state may come from
    /// a hostile blob: check it as strictly as fresh input (sizes, finite numbers, options as the
    /// parameters give them, the model's time against `time`) and fail with a message naming what
    /// is wrong.
    fn restore_state(
        &mut self,
        state: &Self::State,
        values: &Values,
        experiment: &Experiment,
        time: Option<f64>,
    ) -> Result<(), String>;
}
