//! One FMU instance: the FMI 2.0 state machines (Co-Simulation and Model Exchange) over a model.
//!
//! Every method returns the `fmi2Status` to hand back to the environment and logs why when it is
//! not `fmi2OK`. Which call is allowed in which state is decided by one table,
//! [`Operation::allowed_in`], and which interface it belongs to by [`Operation::interface`]: the
//! instance knows the interface it was instantiated for and refuses the other's calls. Any
//! `fmi2Error` puts the instance into the error state, from which only `fmi2Reset`, the FMU-state
//! functions, the getters and `fmi2FreeInstance` lead on (FMI 2.0.4, sections 3.2.3 and 4.2.4).
//!
//! Model Exchange keeps the continuous states among the variable values: `fmi2SetContinuousStates`
//! writes them there, and the model's [`FmuModel::evaluate`] brings the derivatives and outputs up
//! to date lazily, on the first read after the time, a state or an input changed.

use std::ffi::{CStr, CString};
use std::path::PathBuf;

use super::calls::{Interface, MachineState, Operation, RESTORABLE};
use super::ffi::{Fmi2CallbackFunctions, Fmi2EventInfo, Fmi2Status, FMI2_FALSE};
use super::fmu_state::{SavedState, Snapshot};
use super::logging::{Logger, Short};
use super::variables::{check_value, reals_of, Causality, Value, Values};
use super::{Experiment, FmuModel, LogCategory};

use MachineState::*;

/// Guards against pointers that are not instances of this library.
const INSTANCE_MAGIC: u64 = 0x4853_505f_464d_5532; // "HSP_FMU2"

/// The slack with which a communication point matches the FMU's time: a master that adds up its
/// steps drifts by round-off; anything more is a wrong call.
fn time_slack(t: f64) -> f64 {
    1e-9 * t.abs().max(1.0)
}

/// Checks an experiment as `fmi2SetupExperiment` gives it (and as an FMU state carries it).
pub fn check_experiment(e: &Experiment) -> Result<(), String> {
    if let Some(tol) = e.tolerance {
        if !(tol.is_finite() && tol > 0.0) {
            return Err(format!(
                "tolerance must be positive and finite, got {}",
                Short(tol)
            ));
        }
    }
    if !e.start_time.is_finite() {
        return Err(format!(
            "startTime must be finite, got {}",
            Short(e.start_time)
        ));
    }
    if let Some(stop) = e.stop_time {
        if !(stop.is_finite() && stop >= e.start_time) {
            return Err(format!(
                "stopTime {} must be finite and not before startTime {}",
                Short(stop),
                Short(e.start_time)
            ));
        }
    }
    Ok(())
}

/// One FMU instance. `repr(C)` puts the magic number first, so that a pointer can be checked
/// before a reference to the whole instance is made.
#[repr(C)]
pub struct Instance<M: FmuModel> {
    magic: u64,
    pub logger: Logger,
    pub resource_location: Option<PathBuf>,
    state: MachineState,
    interface: Interface,
    experiment: Experiment,
    values: Values,
    model: M,
    time: f64,
    last_successful_time: f64,
    /// A parameter or input changed since the model was last initialised.
    needs_initialize: bool,
    /// Model Exchange: the time, a continuous state or an input changed since the model last
    /// evaluated the derivatives and outputs.
    needs_evaluate: bool,
    /// Strings handed out by `fmi2GetString`, valid until the next call.
    string_buffer: Vec<CString>,
    /// The Reals a step or the initialisation computes (outputs, calculated parameters and
    /// locals): none may be handed out non-finite with fmi2OK.
    results: Vec<usize>,
}

impl<M: FmuModel> Instance<M> {
    /// `fmi2Instantiate`'s checks; `Err` carries the message to log before returning NULL.
    pub fn new(
        instance_name: &str,
        guid: &str,
        resource_location: Option<&str>,
        callbacks: Fmi2CallbackFunctions,
        logging_on: bool,
        interface: Interface,
    ) -> Result<Self, (Logger, String)> {
        let logger = Logger::new(instance_name, callbacks, logging_on);
        let resources = resource_location.and_then(file_uri_to_path);
        Self::with_logger(instance_name, guid, resources, logger, interface)
    }

    /// The checks of `fmi2Instantiate` (and FMI 3.0's `fmi3Instantiate*`, whose instantiation
    /// token is this GUID) with a logger made by the caller. `resource_location` is the
    /// resources directory as a path (FMI 2.0 gives a URI, FMI 3.0 a path).
    pub fn with_logger(
        instance_name: &str,
        guid: &str,
        resource_location: Option<PathBuf>,
        logger: Logger,
        interface: Interface,
    ) -> Result<Self, (Logger, String)> {
        if instance_name.is_empty() {
            return Err((logger, "fmi2Instantiate: instanceName is empty".into()));
        }
        if guid != M::GUID {
            return Err((
                logger,
                format!(
                    "fmi2Instantiate: GUID {guid} does not match this FMU's GUID {}",
                    M::GUID
                ),
            ));
        }
        if interface == Interface::ModelExchange && M::continuous_states().is_empty() {
            return Err((
                logger,
                "fmi2Instantiate: this FMU supports co-simulation only, not model exchange".into(),
            ));
        }
        Ok(Instance {
            magic: INSTANCE_MAGIC,
            logger,
            resource_location,
            state: Instantiated,
            interface,
            experiment: Experiment::default(),
            values: Values::from_start(M::variables()),
            model: M::new(),
            time: 0.0,
            last_successful_time: 0.0,
            needs_initialize: true,
            needs_evaluate: false,
            string_buffer: Vec::new(),
            results: reals_of(
                M::variables(),
                &[
                    Causality::Output,
                    Causality::CalculatedParameter,
                    Causality::Local,
                ],
            ),
        })
    }

    /// Whether `ptr` looks like an instance made by [`Instance::new`] and not yet freed. Reads only
    /// the leading magic number, without making a reference to the rest.
    ///
    /// # Safety
    /// `ptr` is non-null and points to at least 8 readable bytes.
    pub unsafe fn is_instance(ptr: *const Self) -> bool {
        std::ptr::addr_of!((*ptr).magic).read_unaligned() == INSTANCE_MAGIC
    }

    /// Marks the instance freed so that a dangling use is caught while the memory is still ours.
    pub fn invalidate(&mut self) {
        self.magic = 0;
    }

    pub fn state(&self) -> MachineState {
        self.state
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    /// The interface the instance was made for.
    pub fn interface(&self) -> Interface {
        self.interface
    }

    /// Logs an error, enters the error state and returns `fmi2Error`.
    pub fn error(&mut self, message: &str) -> Fmi2Status {
        self.logger
            .log(Fmi2Status::Error, LogCategory::StatusError, message);
        if self.state != Fatal {
            self.state = Error;
        }
        Fmi2Status::Error
    }

    /// Logs a fatal error (a panic caught at the boundary) and enters the fatal state.
    pub fn fatal(&mut self, message: &str) -> Fmi2Status {
        self.logger
            .log(Fmi2Status::Fatal, LogCategory::StatusFatal, message);
        self.state = Fatal;
        Fmi2Status::Fatal
    }

    /// Logs the call when the `logCalls` category is on; the message is built only then.
    pub fn log_call(&self, call: impl FnOnce() -> String) {
        if self.logger.enabled(LogCategory::Calls) {
            self.logger.log(Fmi2Status::Ok, LogCategory::Calls, &call());
        }
    }

    /// Checks in the table of [`Operation::allowed_in`] that `function` may be called now.
    pub fn allowed(&mut self, function: &str, operation: Operation) -> Result<(), Fmi2Status> {
        if let Some(interface) = operation.interface() {
            if interface != self.interface && self.state != Fatal {
                return Err(self.error(&format!(
                    "{function}: belongs to {}, but this instance was instantiated for {}",
                    interface.name(),
                    self.interface.name()
                )));
            }
        }
        if operation.allowed_in().contains(self.state) {
            Ok(())
        } else if self.state == Fatal {
            // After fmi2Fatal nothing but fmi2FreeInstance is allowed; the state stays fatal.
            self.logger.log(
                Fmi2Status::Error,
                LogCategory::StatusError,
                &format!("{function}: illegal call sequence: after fmi2Fatal only fmi2FreeInstance is allowed"),
            );
            Err(Fmi2Status::Error)
        } else {
            let state = self.state.name();
            Err(self.error(&format!(
                "{function}: illegal call sequence: not allowed in state '{state}'"
            )))
        }
    }

    pub fn set_debug_logging(&mut self, logging_on: bool, categories: &[&str]) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2SetDebugLogging", Operation::SetDebugLogging) {
            return s;
        }
        let mut chosen = Vec::with_capacity(categories.len());
        for name in categories {
            match LogCategory::from_name(name) {
                Some(c) => chosen.push(c),
                None => {
                    return self.error(&format!(
                        "fmi2SetDebugLogging: unknown log category '{name}'; known: {}",
                        LogCategory::ALL.map(|c| c.name()).join(", ")
                    ))
                }
            }
        }
        // With no categories the switch applies to all, else only to those named (FMI 2.0.4, 2.1.5).
        self.logger.switch(logging_on, &chosen);
        Fmi2Status::Ok
    }

    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2SetupExperiment", Operation::SetupExperiment) {
            return s;
        }
        let experiment = Experiment {
            tolerance,
            start_time,
            stop_time,
        };
        if let Err(msg) = check_experiment(&experiment) {
            return self.error(&format!("fmi2SetupExperiment: {msg}"));
        }
        self.experiment = experiment;
        self.time = start_time;
        self.last_successful_time = start_time;
        self.needs_initialize = true;
        Fmi2Status::Ok
    }

    pub fn enter_initialization_mode(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed(
            "fmi2EnterInitializationMode",
            Operation::EnterInitializationMode,
        ) {
            return s;
        }
        self.state = InitializationMode;
        self.time = self.experiment.start_time;
        Fmi2Status::Ok
    }

    /// The first output or calculated parameter that is a non-finite Real, as "name = value".
    fn non_finite_result(&mut self) -> Option<String> {
        match self.values.first_non_finite(&self.results) {
            Some(i) => Some(format!(
                "{} = {}",
                M::variables()[i].name,
                self.values.real(i)
            )),
            None => {
                self.values.recheck_finite();
                None
            }
        }
    }

    /// Builds the model if a parameter changed since it was last built.
    fn ensure_initialized(&mut self) -> Result<(), Fmi2Status> {
        if self.needs_initialize {
            if let Err(msg) = self.model.initialize(&mut self.values, &self.experiment) {
                return Err(self.error(&format!("initialization failed: {msg}")));
            }
            if let Some(bad) = self.non_finite_result() {
                return Err(self.error(&format!(
                    "initialization failed: {bad} is not finite; the parameters give no finite initial point"
                )));
            }
            self.needs_initialize = false;
        }
        Ok(())
    }

    pub fn exit_initialization_mode(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed(
            "fmi2ExitInitializationMode",
            Operation::ExitInitializationMode,
        ) {
            return s;
        }
        self.needs_initialize = true;
        if let Err(s) = self.ensure_initialized() {
            return s;
        }
        self.time = self.experiment.start_time;
        self.last_successful_time = self.time;
        self.state = match self.interface {
            Interface::CoSimulation => StepComplete,
            Interface::ModelExchange => {
                if let Err(msg) = self.model.check_model_exchange() {
                    return self.error(&format!("fmi2ExitInitializationMode: {msg}"));
                }
                // Event mode first: the importer may look at the point before integrating.
                EventMode
            }
        };
        Fmi2Status::Ok
    }

    pub fn terminate(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2Terminate", Operation::Terminate) {
            return s;
        }
        self.state = Terminated;
        Fmi2Status::Ok
    }

    /// `fmi2Reset`: exactly the state of a fresh instantiation (the logging settings stay).
    pub fn reset(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2Reset", Operation::Reset) {
            return s;
        }
        self.state = Instantiated;
        self.experiment = Experiment::default();
        self.values = Values::from_start(M::variables());
        self.model = M::new();
        self.time = 0.0;
        self.last_successful_time = 0.0;
        self.needs_initialize = true;
        self.needs_evaluate = false;
        Fmi2Status::Ok
    }

    /// Resolves value references to table positions, checking each one's type.
    fn resolve(
        &mut self,
        function: &str,
        vrs: &[u32],
        type_name: &str,
    ) -> Result<Vec<usize>, Fmi2Status> {
        vrs.iter()
            .map(|&vr| self.resolve_one(function, vr, type_name))
            .collect()
    }

    /// The table position of one value reference, checking its type.
    fn resolve_one(
        &mut self,
        function: &str,
        vr: u32,
        type_name: &str,
    ) -> Result<usize, Fmi2Status> {
        let Some(index) = M::index_of(vr) else {
            return Err(self.error(&format!("{function}: unknown value reference {vr}")));
        };
        let var = &M::variables()[index];
        if var.kind.type_name() != type_name {
            return Err(self.error(&format!(
                "{function}: value reference {vr} is '{}', a {}, not a {type_name}",
                var.name,
                var.kind.type_name()
            )));
        }
        Ok(index)
    }

    /// The getters: `fmi2GetReal` and its siblings.
    pub fn get<T>(
        &mut self,
        function: &str,
        type_name: &str,
        vrs: &[u32],
        out: &mut [T],
        convert: impl Fn(&Value) -> T,
    ) -> Fmi2Status {
        if let Err(s) = self.allowed(function, Operation::GetValues) {
            return s;
        }
        // Every reference is checked before anything is read; then each is looked up again
        // rather than collected, so that a getter called after every step allocates nothing.
        for &vr in vrs {
            if let Err(s) = self.resolve_one(function, vr, type_name) {
                return s;
            }
        }
        if let Err(s) = self.bring_up_to_date(function) {
            return s;
        }
        for (slot, &vr) in out.iter_mut().zip(vrs) {
            if let Some(index) = M::index_of(vr) {
                self.model.refresh(&mut self.values, Some(index));
                *slot = convert(self.values.get(index));
            }
        }
        Fmi2Status::Ok
    }

    /// The setters: `fmi2SetReal` and its siblings. Either every value is set or none.
    pub fn set(
        &mut self,
        function: &str,
        type_name: &str,
        vrs: &[u32],
        new: Vec<Value>,
    ) -> Fmi2Status {
        if let Err(s) = self.allowed(function, Operation::SetValues) {
            return s;
        }
        let indices = match self.resolve(function, vrs, type_name) {
            Ok(i) => i,
            Err(s) => return s,
        };
        let running = matches!(self.state, StepComplete | EventMode | ContinuousTimeMode);
        for (&index, value) in indices.iter().zip(&new) {
            let var = &M::variables()[index];
            let allowed = if running {
                var.settable_during_simulation()
            } else {
                var.settable_before_initialization()
            };
            if !allowed {
                let when = if running {
                    "after initialization"
                } else {
                    "at all"
                };
                return self.error(&format!(
                    "{function}: variable '{}' (causality {:?}, variability {:?}) cannot be set {when}",
                    var.name, var.causality, var.variability
                ));
            }
            let checked = check_value(var, value).and_then(|_| self.model.check(index, value));
            if let Err(msg) = checked {
                return self.error(&format!("{function}: {msg}"));
            }
        }
        for (index, value) in indices.into_iter().zip(new) {
            self.values.set(index, value);
        }
        if !running {
            self.needs_initialize = true;
        }
        self.needs_evaluate = true;
        Fmi2Status::Ok
    }

    /// Before values are read: builds the model in initialisation mode, and in Model Exchange
    /// evaluates it at the current time, states and inputs if any changed.
    fn bring_up_to_date(&mut self, function: &str) -> Result<(), Fmi2Status> {
        if self.state == InitializationMode {
            self.ensure_initialized()?;
        }
        let evaluated = match self.interface {
            Interface::ModelExchange => {
                matches!(self.state, EventMode | ContinuousTimeMode | Terminated)
            }
            Interface::CoSimulation => false,
        };
        if evaluated && self.needs_evaluate {
            if let Err(msg) = self.model.evaluate(&mut self.values, self.time) {
                return Err(self.error(&format!("{function}: {msg}")));
            }
            self.needs_evaluate = false;
        }
        Ok(())
    }

    /// Checks that an array argument has as many elements as the model has continuous states.
    fn check_state_count(
        &mut self,
        function: &str,
        what: &str,
        n: usize,
    ) -> Result<(), Fmi2Status> {
        let nx = M::continuous_states().len();
        if n == nx {
            Ok(())
        } else {
            Err(self.error(&format!(
                "{function}: argument '{what}' has {n} elements, but the model has {nx} continuous states"
            )))
        }
    }

    /// `fmi2SetTime`.
    pub fn set_time(&mut self, time: f64) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2SetTime", Operation::SetTime) {
            return s;
        }
        if !time.is_finite() {
            return self.error(&format!("fmi2SetTime: time {} is not finite", Short(time)));
        }
        self.time = time;
        self.last_successful_time = time;
        self.needs_evaluate = true;
        Fmi2Status::Ok
    }

    /// `fmi2SetContinuousStates`: every state is set, or none.
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Fmi2Status {
        const F: &str = "fmi2SetContinuousStates";
        if let Err(s) = self.allowed(F, Operation::SetContinuousStates) {
            return s;
        }
        if let Err(s) = self.check_state_count(F, "x", x.len()) {
            return s;
        }
        let states = M::continuous_states();
        if let Some((k, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            let name = M::variables()[states[k].0].name;
            return self.error(&format!("{F}: x[{k}] ('{name}') = {v} is not finite"));
        }
        for (&(state, _), &v) in states.iter().zip(x) {
            self.values.set_real(state, v);
        }
        self.needs_evaluate = true;
        Fmi2Status::Ok
    }

    /// `fmi2GetContinuousStates`.
    pub fn continuous_states(&mut self, x: &mut [f64]) -> Fmi2Status {
        const F: &str = "fmi2GetContinuousStates";
        if let Err(s) = self.allowed(F, Operation::GetContinuousStates) {
            return s;
        }
        if let Err(s) = self.check_state_count(F, "x", x.len()) {
            return s;
        }
        if let Err(s) = self.bring_up_to_date(F) {
            return s;
        }
        for (slot, &(state, _)) in x.iter_mut().zip(M::continuous_states()) {
            *slot = self.values.real(state);
        }
        Fmi2Status::Ok
    }

    /// `fmi2GetDerivatives`: `fmi2Discard` when a derivative is not finite (the importer's solver
    /// should retry with a smaller step, FMI 2.0.4 section 2.1.3).
    pub fn derivatives(&mut self, dx: &mut [f64]) -> Fmi2Status {
        const F: &str = "fmi2GetDerivatives";
        if let Err(s) = self.allowed(F, Operation::GetDerivatives) {
            return s;
        }
        if let Err(s) = self.check_state_count(F, "derivatives", dx.len()) {
            return s;
        }
        if let Err(s) = self.bring_up_to_date(F) {
            return s;
        }
        for (slot, &(_, derivative)) in dx.iter_mut().zip(M::continuous_states()) {
            *slot = self.values.real(derivative);
        }
        if let Some(k) = dx.iter().position(|d| !d.is_finite()) {
            let name = M::variables()[M::continuous_states()[k].1].name;
            self.logger.log(
                Fmi2Status::Discard,
                LogCategory::StatusDiscard,
                &format!(
                    "{F}: {name} = {} is not finite at t = {}; retry with a smaller step",
                    dx[k],
                    Short(self.time)
                ),
            );
            return Fmi2Status::Discard;
        }
        Fmi2Status::Ok
    }

    /// `fmi2GetNominalsOfContinuousStates`: 1 before the model is built (its nominals follow
    /// from the parameters), the model's nominals after.
    pub fn nominals_of_continuous_states(&mut self, out: &mut [f64]) -> Fmi2Status {
        const F: &str = "fmi2GetNominalsOfContinuousStates";
        if let Err(s) = self.allowed(F, Operation::GetNominals) {
            return s;
        }
        if let Err(s) = self.check_state_count(F, "x_nominal", out.len()) {
            return s;
        }
        if self.state == Instantiated {
            out.fill(1.0);
        } else {
            self.model.nominals(out);
        }
        Fmi2Status::Ok
    }

    /// `fmi2GetEventIndicators`: the model has none (its limits are smooth laws).
    pub fn event_indicators(&mut self, n: usize) -> Fmi2Status {
        const F: &str = "fmi2GetEventIndicators";
        if let Err(s) = self.allowed(F, Operation::GetContinuousStates) {
            return s;
        }
        if n != 0 {
            return self.error(&format!(
                "{F}: argument 'ni' is {n}, but the model has no event indicators (numberOfEventIndicators = 0)"
            ));
        }
        Fmi2Status::Ok
    }

    /// `fmi2EnterEventMode`.
    pub fn enter_event_mode(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2EnterEventMode", Operation::EnterEventMode) {
            return s;
        }
        self.state = EventMode;
        Fmi2Status::Ok
    }

    /// `fmi2NewDiscreteStates`: the model has no discrete states and no time events.
    pub fn new_discrete_states(&mut self, info: &mut Fmi2EventInfo) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2NewDiscreteStates", Operation::NewDiscreteStates) {
            return s;
        }
        *info = Fmi2EventInfo {
            new_discrete_states_needed: FMI2_FALSE,
            terminate_simulation: FMI2_FALSE,
            nominals_of_continuous_states_changed: FMI2_FALSE,
            values_of_continuous_states_changed: FMI2_FALSE,
            next_event_time_defined: FMI2_FALSE,
            next_event_time: 0.0,
        };
        Fmi2Status::Ok
    }

    /// `fmi2EnterContinuousTimeMode`.
    pub fn enter_continuous_time_mode(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed(
            "fmi2EnterContinuousTimeMode",
            Operation::EnterContinuousTimeMode,
        ) {
            return s;
        }
        self.state = ContinuousTimeMode;
        Fmi2Status::Ok
    }

    /// `fmi2CompletedIntegratorStep`: `(enterEventMode, terminateSimulation)`, never either (no
    /// step events, no end the model asks for).
    pub fn completed_integrator_step(&mut self) -> Result<(bool, bool), Fmi2Status> {
        self.allowed(
            "fmi2CompletedIntegratorStep",
            Operation::CompletedIntegratorStep,
        )?;
        Ok((false, false))
    }

    /// The checks of a partial-derivative call before anything is computed: the call is allowed
    /// in this state, every value reference is a Real, every unknown an output or a state
    /// derivative and every known an input or a continuous state. Returns the variables'
    /// indices. FMI 3.0's adjoint runs it once up front, so that a call with no knowns is
    /// refused wherever one with knowns would be.
    pub fn check_derivative_call(
        &mut self,
        unknown_vrs: &[u32],
        known_vrs: &[u32],
    ) -> Result<(Vec<usize>, Vec<usize>), Fmi2Status> {
        const F: &str = "fmi2GetDirectionalDerivative";
        self.allowed(F, Operation::DirectionalDerivative)?;
        let unknowns = self.resolve(F, unknown_vrs, "Real")?;
        let knowns = self.resolve(F, known_vrs, "Real")?;
        let states = M::continuous_states();
        for &u in &unknowns {
            let var = &M::variables()[u];
            let derivative = states.iter().any(|&(_, d)| d == u);
            if !(var.causality == Causality::Output || derivative) {
                return Err(self.error(&format!(
                    "{F}: unknown '{}' (value reference {}) is neither an output nor a state derivative",
                    var.name, var.value_reference
                )));
            }
        }
        for &k in &knowns {
            let var = &M::variables()[k];
            let state = states.iter().any(|&(x, _)| x == k);
            if !(var.causality == Causality::Input || state) {
                return Err(self.error(&format!(
                    "{F}: known '{}' (value reference {}) is neither an input nor a continuous state",
                    var.name, var.value_reference
                )));
            }
        }
        Ok((unknowns, knowns))
    }

    /// `fmi2GetDirectionalDerivative`: `dv_unknown = (d unknowns / d knowns) dv_known` from the
    /// model's exact Jacobian, at the current point. Unknowns are outputs or state derivatives,
    /// knowns inputs or continuous states (FMI 2.0.4, section 2.1.9), all Real.
    pub fn directional_derivative(
        &mut self,
        unknown_vrs: &[u32],
        known_vrs: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Fmi2Status {
        const F: &str = "fmi2GetDirectionalDerivative";
        let (unknowns, knowns) = match self.check_derivative_call(unknown_vrs, known_vrs) {
            Ok(indices) => indices,
            Err(s) => return s,
        };
        if let Some((k, v)) = dv_known.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return self.error(&format!("{F}: dvKnown[{k}] = {v} is not finite"));
        }
        if let Err(s) = self.bring_up_to_date(F) {
            return s;
        }
        self.model.refresh(&mut self.values, None);
        let result = self.model.directional_derivative(
            &self.values,
            &unknowns,
            &knowns,
            dv_known,
            dv_unknown,
        );
        if let Err(msg) = result {
            return self.error(&format!("{F}: {msg}"));
        }
        if let Some(k) = dv_unknown.iter().position(|d| !d.is_finite()) {
            let name = M::variables()[unknowns[k]].name;
            return self.error(&format!(
                "{F}: the derivative of '{name}' is not finite at t = {}",
                Short(self.time)
            ));
        }
        Fmi2Status::Ok
    }

    /// `fmi2GetString`: the pointers stay valid until the next call on this instance.
    pub fn get_strings(
        &mut self,
        vrs: &[u32],
        out: &mut [*const std::os::raw::c_char],
    ) -> Fmi2Status {
        let mut texts = vec![String::new(); vrs.len()];
        let status = self.get("fmi2GetString", "String", vrs, &mut texts, |v| match v {
            Value::String(s) => s.clone(),
            _ => String::new(),
        });
        if status != Fmi2Status::Ok {
            return status;
        }
        self.string_buffer = texts
            .into_iter()
            .map(|t| CString::new(t.replace('\0', " ")).unwrap_or_default())
            .collect();
        for (slot, s) in out.iter_mut().zip(&self.string_buffer) {
            *slot = s.as_ptr();
        }
        Fmi2Status::Ok
    }

    pub fn do_step(&mut self, current_communication_point: f64, step_size: f64) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2DoStep", Operation::DoStep) {
            return s;
        }
        if !(step_size.is_finite() && step_size > 0.0) {
            return self.error(&format!(
                "fmi2DoStep: communicationStepSize must be positive and finite, got {}",
                Short(step_size)
            ));
        }
        if !current_communication_point.is_finite()
            || (current_communication_point - self.time).abs() > time_slack(self.time)
        {
            return self.error(&format!(
                "fmi2DoStep: currentCommunicationPoint {} does not match the FMU's time {}",
                Short(current_communication_point),
                Short(self.time)
            ));
        }
        let t_end = current_communication_point + step_size;
        // Near large times a small step vanishes in round-off: the FMU's time cannot advance.
        if t_end <= self.time {
            return self.error(&format!(
                "fmi2DoStep: communicationStepSize {} cannot advance the time {} in double precision (t + h rounds to t)",
                Short(step_size),
                Short(self.time)
            ));
        }
        if let Some(stop) = self.experiment.stop_time {
            if t_end > stop + time_slack(stop) {
                return self.error(&format!(
                    "fmi2DoStep: the step to {} goes past stopTime {}",
                    Short(t_end),
                    Short(stop)
                ));
            }
        }
        let logger = &self.logger;
        let mut log = |category: LogCategory, message: &dyn Fn() -> String| {
            if logger.enabled(category) {
                let status = if category == LogCategory::StatusWarning {
                    Fmi2Status::Warning
                } else {
                    Fmi2Status::Ok
                };
                logger.log(status, category, &message());
            }
        };
        let result = self
            .model
            .do_step(&mut self.values, self.time, t_end, &mut log);
        match result {
            Ok(()) => {
                if let Some(bad) = self.non_finite_result() {
                    // The model should have discarded the step; never hand out fmi2OK with it.
                    return self.error(&format!(
                        "fmi2DoStep: {bad} is not finite at t = {}",
                        Short(t_end)
                    ));
                }
                self.time = t_end;
                self.last_successful_time = t_end;
                Fmi2Status::Ok
            }
            Err(failure) => {
                self.time = failure.last_successful_time;
                self.last_successful_time = failure.last_successful_time;
                self.state = StepFailed;
                self.logger.log(
                    Fmi2Status::Discard,
                    LogCategory::StatusDiscard,
                    &format!(
                        "fmi2DoStep: step from {} to {} discarded at t = {}: {}",
                        Short(current_communication_point),
                        Short(t_end),
                        Short(failure.last_successful_time),
                        failure.message
                    ),
                );
                Fmi2Status::Discard
            }
        }
    }

    /// `fmi2GetRealStatus(fmi2LastSuccessfulTime)`.
    pub fn last_successful_time(&mut self) -> Result<f64, Fmi2Status> {
        self.allowed("fmi2GetRealStatus", Operation::GetStatus)?;
        Ok(self.last_successful_time)
    }

    /// `fmi2GetBooleanStatus(fmi2Terminated)`: the FMU never asks to end the simulation itself;
    /// a discarded step can be retried from a restored FMU state.
    pub fn terminated_status(&mut self) -> Result<bool, Fmi2Status> {
        self.allowed("fmi2GetBooleanStatus", Operation::GetStatus)?;
        Ok(false)
    }

    pub fn check_fmu_state_call(&mut self, function: &str) -> Result<(), Fmi2Status> {
        if self.interface == Interface::ModelExchange && self.state != Fatal {
            // The importer's solver holds the continuous states: save them there.
            return Err(self.error(&format!(
                "{function}: not supported in Model Exchange (canGetAndSetFMUstate is false there)"
            )));
        }
        self.allowed(function, Operation::FmuState)
    }

    /// `fmi2GetFMUstate`.
    pub fn save(&mut self) -> SavedState<M::State> {
        self.model.refresh(&mut self.values, None);
        SavedState::new(Snapshot {
            guid: M::GUID.to_string(),
            state: self.state,
            time: self.time,
            last_successful_time: self.last_successful_time,
            experiment: self.experiment,
            values: self.values.clone(),
            needs_initialize: self.needs_initialize,
            model: self.model.save_state(),
        })
    }

    /// Checks the generic part of an FMU state as strictly as fresh input: the state it was taken
    /// in, the experiment, the times and every value (type, range, the model's own checks).
    fn check_snapshot(s: &Snapshot<M::State>, model: &M) -> Result<(), String> {
        if !RESTORABLE.contains(s.state) {
            return Err(format!(
                "the FMU state was taken in state '{}', from which the simulation cannot go on",
                s.state.name()
            ));
        }
        check_experiment(&s.experiment).map_err(|m| format!("its experiment: {m}"))?;
        let e = &s.experiment;
        let after_start = matches!(s.state, StepComplete | StepFailed | Terminated);
        let times_ok = s.time.is_finite()
            && s.last_successful_time.to_bits() == s.time.to_bits()
            && if after_start {
                s.time >= e.start_time
                    && e.stop_time
                        .is_none_or(|stop| s.time <= stop + time_slack(stop))
            } else {
                s.time == e.start_time
            };
        if !times_ok {
            return Err(format!(
                "its time {} (last successful time {}) does not fit its state '{}' and startTime {}",
                Short(s.time),
                Short(s.last_successful_time),
                s.state.name(),
                Short(e.start_time)
            ));
        }
        let variables = M::variables();
        if s.values.len() != variables.len() {
            return Err(format!(
                "it has {} variables, this FMU {}",
                s.values.len(),
                variables.len()
            ));
        }
        for (i, var) in variables.iter().enumerate() {
            let value = s.values.get(i);
            check_value(var, value)?;
            if var.settable_before_initialization() {
                model.check(i, value)?;
            }
        }
        Ok(())
    }

    /// `fmi2SetFMUstate`: the state is validated as strictly as fresh input before anything of
    /// the instance changes; a state that fails leaves the instance in the error state.
    pub fn restore(&mut self, saved: &SavedState<M::State>) -> Fmi2Status {
        let s = &saved.snapshot;
        if let Err(msg) = Self::check_snapshot(s, &self.model) {
            return self.error(&format!("fmi2SetFMUstate: invalid FMU state: {msg}"));
        }
        let initialized = matches!(s.state, StepComplete | StepFailed | Terminated);
        let time = initialized.then_some(s.time);
        // The current values complete, whether the model takes up the state or refuses it.
        self.model.refresh(&mut self.values, None);
        if let Err(msg) = self
            .model
            .restore_state(&s.model, &s.values, &s.experiment, time)
        {
            return self.error(&format!("fmi2SetFMUstate: invalid FMU state: {msg}"));
        }
        self.state = s.state;
        self.time = s.time;
        self.last_successful_time = s.last_successful_time;
        self.experiment = s.experiment;
        self.values = s.values.clone();
        self.needs_initialize = s.needs_initialize && !initialized;
        Fmi2Status::Ok
    }
}

/// Turns a `file:` resource URI into a path: `file:///a/b`, `file://localhost/a/b` and `file:/a/b`,
/// with percent-decoding. Anything else gives `None`.
pub fn file_uri_to_path(uri: &str) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let path = if let Some(r) = rest.strip_prefix("//") {
        // Authority: empty or localhost.
        let slash = r.find('/')?;
        let (host, p) = r.split_at(slash);
        if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
            return None;
        }
        p
    } else {
        rest
    };
    let bytes = path.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            decoded.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            decoded.push(bytes[i]);
            i += 1;
        }
    }
    Some(PathBuf::from(String::from_utf8(decoded).ok()?))
}

/// Reads a C string argument, `None` for NULL.
///
/// # Safety
/// `ptr` is NULL or a valid NUL-terminated string.
pub unsafe fn c_str<'a>(ptr: *const std::os::raw::c_char) -> Option<&'a str> {
    if ptr.is_null() {
        None
    } else {
        CStr::from_ptr(ptr).to_str().ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_uris() {
        assert_eq!(
            file_uri_to_path("file:///tmp/a%20b/"),
            Some(PathBuf::from("/tmp/a b/"))
        );
        assert_eq!(
            file_uri_to_path("file:/tmp/x"),
            Some(PathBuf::from("/tmp/x"))
        );
        assert_eq!(
            file_uri_to_path("file://localhost/tmp"),
            Some(PathBuf::from("/tmp"))
        );
        assert_eq!(file_uri_to_path("http://x/y"), None);
        assert_eq!(file_uri_to_path("file:///bad%2"), None);
    }
}
