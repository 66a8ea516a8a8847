//! One FMU instance: the state machines of Co-Simulation and Model Exchange over a model, the same
//! for FMI 2.0 and FMI 3.0.
//!
//! Every method returns the [`Status`] to hand back to the environment and logs why when it is not
//! OK, naming the function the importer called ([`Instance::begin_call`], set at the boundary).
//! Which call is allowed in which state is decided by one table, [`Operation::allowed_in`], and
//! which interface it belongs to by [`Operation::interface`]: the instance knows the interface it
//! was instantiated for and refuses the other's calls. Any error puts the instance into the error
//! state, from which only a reset, the FMU-state functions, the getters and freeing the instance
//! lead on (FMI 2.0.4, sections 3.2.3 and 4.2.4; FMI 3.0, section 3.2 and 4.2).
//!
//! The methods are split by job:
//! - this file: the instance, its life cycle (set-up, initialisation, termination, reset) and the
//!   checks every call shares;
//! - [`values`]: getting and setting variables;
//! - [`co_simulation`]: the communication step and its status;
//! - [`model_exchange`]: time, continuous states, derivatives, nominals and the event modes;
//! - [`derivatives`]: directional derivatives from the model's exact Jacobian;
//! - [`restore`]: saving and restoring FMU states.
//!
//! Model Exchange keeps the continuous states among the variable values: setting the states writes
//! them there, and the model's [`FmuModel::evaluate`] brings the derivatives and outputs up to date
//! lazily, on the first read after the time, a state or an input changed.

pub mod co_simulation;
pub mod derivatives;
pub mod model_exchange;
pub mod restore;
pub mod values;

use std::ffi::CString;
use std::path::PathBuf;

use super::calls::{Interface, MachineState, Operation};
use super::logging::{Logger, Short};
use super::variables::{reals_of, Causality, Values};
use super::{Experiment, FmuModel, LogCategory, Status};

use MachineState::*;

/// Guards against pointers that are not instances of this library.
const INSTANCE_MAGIC: u64 = 0x4853_505f_464d_5532; // "HSP_FMU2"

/// The words of one FMI version that the core's messages use besides the name of the called
/// function: each FMI layer has one, and passes it when it makes an instance.
#[derive(Debug)]
pub struct Vocabulary {
    /// The fatal status (`fmi2Fatal`).
    pub fatal: &'static str,
    /// The function that frees an instance (`fmi2FreeInstance`).
    pub free_instance: &'static str,
    /// The FMU-state argument of the FMU-state functions (`FMUstate` in FMI 2.0, `FMUState` in
    /// FMI 3.0).
    pub fmu_state: &'static str,
    /// The capability flag of FMU states (`canGetAndSetFMUstate`).
    pub can_get_and_set_fmu_state: &'static str,
}

/// The slack with which a communication point matches the FMU's time: a master that adds up its
/// steps drifts by round-off; anything more is a wrong call.
fn time_slack(t: f64) -> f64 {
    1e-9 * t.abs().max(1.0)
}

/// Checks an experiment as the importer sets it up (and as an FMU state carries it).
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
    /// The C function being served, for messages (set by [`Instance::begin_call`]).
    function: &'static str,
    vocabulary: &'static Vocabulary,
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
    /// Strings handed out by the String getter, valid until the next call.
    string_buffer: Vec<CString>,
    /// The Reals a step or the initialisation computes (outputs, calculated parameters and
    /// locals): none may be handed out non-finite with OK.
    results: Vec<usize>,
}

impl<M: FmuModel> Instance<M> {
    /// The checks of instantiation (FMI 2.0's `fmi2Instantiate`, FMI 3.0's `fmi3Instantiate*`,
    /// whose instantiation token is this GUID), made by `function`. `resource_location` is the
    /// resources directory as a path (FMI 2.0 gives a URI, FMI 3.0 a path); the logger is made by
    /// the caller. `Err` carries the logger back with the message to log before returning NULL.
    pub fn new(
        function: &'static str,
        vocabulary: &'static Vocabulary,
        instance_name: &str,
        guid: &str,
        resource_location: Option<PathBuf>,
        logger: Logger,
        interface: Interface,
    ) -> Result<Self, (Logger, String)> {
        if instance_name.is_empty() {
            return Err((logger, format!("{function}: instanceName is empty")));
        }
        if guid != M::GUID {
            return Err((
                logger,
                format!(
                    "{function}: GUID {guid} does not match this FMU's GUID {}",
                    M::GUID
                ),
            ));
        }
        if interface == Interface::ModelExchange && M::continuous_states().is_empty() {
            return Err((
                logger,
                format!("{function}: this FMU supports co-simulation only, not model exchange"),
            ));
        }
        Ok(Instance {
            magic: INSTANCE_MAGIC,
            logger,
            resource_location,
            function,
            vocabulary,
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
        // SAFETY: the caller guarantees 8 readable bytes at `ptr`; `magic` is the first field of
        // this `repr(C)` struct, read unaligned without a reference to the rest.
        unsafe { std::ptr::addr_of!((*ptr).magic).read_unaligned() == INSTANCE_MAGIC }
    }

    /// Marks the instance freed so that a dangling use is caught while the memory is still ours.
    pub fn invalidate(&mut self) {
        self.magic = 0;
    }

    /// Names the C function now being served: the boundary calls it first in every entry point,
    /// and every message of the call starts with that name.
    pub fn begin_call(&mut self, function: &'static str) {
        self.function = function;
    }

    /// The C function being served.
    pub fn function(&self) -> &'static str {
        self.function
    }

    /// The words of the instance's FMI version.
    pub fn vocabulary(&self) -> &'static Vocabulary {
        self.vocabulary
    }

    pub fn state(&self) -> MachineState {
        self.state
    }

    /// The model, read-only: for layers that show more of it than FMI variables can (the
    /// browser build draws the plate from the model's parameters).
    pub fn model(&self) -> &M {
        &self.model
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    /// The interface the instance was made for.
    pub fn interface(&self) -> Interface {
        self.interface
    }

    /// Logs an error, enters the error state and returns [`Status::Error`].
    pub fn error(&mut self, message: &str) -> Status {
        self.logger
            .log(Status::Error, LogCategory::StatusError, message);
        if self.state != Fatal {
            self.state = Error;
        }
        Status::Error
    }

    /// Logs an error that starts with the called function's name (`"{function}: {message}"`) and
    /// enters the error state.
    pub fn refuse(&mut self, message: &str) -> Status {
        let f = self.function;
        self.error(&format!("{f}: {message}"))
    }

    /// Logs a fatal error (a panic caught at the boundary) and enters the fatal state.
    pub fn fatal(&mut self, message: &str) -> Status {
        self.logger
            .log(Status::Fatal, LogCategory::StatusFatal, message);
        self.state = Fatal;
        Status::Fatal
    }

    /// Logs the call when the `logCalls` category is on; the message is built only then.
    pub fn log_call(&self, call: impl FnOnce() -> String) {
        if self.logger.enabled(LogCategory::Calls) {
            self.logger.log(Status::Ok, LogCategory::Calls, &call());
        }
    }

    /// Checks in the table of [`Operation::allowed_in`] that the called function may be called
    /// now.
    pub fn allowed(&mut self, operation: Operation) -> Result<(), Status> {
        let function = self.function;
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
            // After a fatal error nothing but freeing the instance is allowed; the state stays
            // fatal.
            let v = self.vocabulary;
            self.logger.log(
                Status::Error,
                LogCategory::StatusError,
                &format!(
                    "{function}: illegal call sequence: after {} only {} is allowed",
                    v.fatal, v.free_instance
                ),
            );
            Err(Status::Error)
        } else {
            let state = self.state.name();
            Err(self.error(&format!(
                "{function}: illegal call sequence: not allowed in state '{state}'"
            )))
        }
    }

    pub fn set_debug_logging(&mut self, logging_on: bool, categories: &[&str]) -> Status {
        if let Err(s) = self.allowed(Operation::SetDebugLogging) {
            return s;
        }
        let mut chosen = Vec::with_capacity(categories.len());
        for name in categories {
            match LogCategory::from_name(name) {
                Some(c) => chosen.push(c),
                None => {
                    return self.refuse(&format!(
                        "unknown log category '{name}'; known: {}",
                        LogCategory::ALL.map(|c| c.name()).join(", ")
                    ))
                }
            }
        }
        // With no categories the switch applies to all, else only to those named (FMI 2.0.4, 2.1.5).
        self.logger.switch(logging_on, &chosen);
        Status::Ok
    }

    /// Sets up the experiment (FMI 2.0's `fmi2SetupExperiment`; FMI 3.0 passes it to
    /// `fmi3EnterInitializationMode`).
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        if let Err(s) = self.allowed(Operation::SetupExperiment) {
            return s;
        }
        let experiment = Experiment {
            tolerance,
            start_time,
            stop_time,
        };
        if let Err(msg) = check_experiment(&experiment) {
            return self.refuse(&msg);
        }
        self.experiment = experiment;
        self.time = start_time;
        self.last_successful_time = start_time;
        self.needs_initialize = true;
        Status::Ok
    }

    pub fn enter_initialization_mode(&mut self) -> Status {
        if let Err(s) = self.allowed(Operation::EnterInitializationMode) {
            return s;
        }
        self.state = InitializationMode;
        self.time = self.experiment.start_time;
        Status::Ok
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
    fn ensure_initialized(&mut self) -> Result<(), Status> {
        if self.needs_initialize {
            let logger = &self.logger;
            let mut log = |category: LogCategory, message: &dyn Fn() -> String| {
                logger.model_log(category, message)
            };
            if let Err(msg) = self
                .model
                .initialize(&mut self.values, &self.experiment, &mut log)
            {
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

    pub fn exit_initialization_mode(&mut self) -> Status {
        if let Err(s) = self.allowed(Operation::ExitInitializationMode) {
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
                    return self.refuse(&msg);
                }
                // Event mode first: the importer may look at the point before integrating.
                EventMode
            }
        };
        Status::Ok
    }

    pub fn terminate(&mut self) -> Status {
        if let Err(s) = self.allowed(Operation::Terminate) {
            return s;
        }
        self.state = Terminated;
        Status::Ok
    }

    /// Reset: exactly the state of a fresh instantiation (the logging settings stay).
    pub fn reset(&mut self) -> Status {
        if let Err(s) = self.allowed(Operation::Reset) {
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
        Status::Ok
    }

    /// A function the FMU does not support (its capability flag is false in the XML): refused in
    /// every state, with `why`.
    pub fn unsupported(&mut self, why: &str) -> Status {
        if let Err(s) = self.allowed(Operation::Unsupported) {
            return s;
        }
        self.refuse(&format!("not supported: {why}"))
    }
}
