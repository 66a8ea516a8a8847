//! The C types of the FMI 2.0 API (`fmi2TypesPlatform.h`, `fmi2FunctionTypes.h`), written by hand
//! so that building the FMU needs no libclang.

use std::os::raw::{c_char, c_double, c_int, c_uint, c_void};

use crate::fmu::Status;

pub type Fmi2Component = *mut c_void;
pub type Fmi2ComponentEnvironment = *mut c_void;
pub type Fmi2FmuState = *mut c_void;
pub type Fmi2ValueReference = c_uint;
pub type Fmi2Real = c_double;
pub type Fmi2Integer = c_int;
/// `fmi2Boolean` is an `int`: 0 is false, anything else true.
pub type Fmi2Boolean = c_int;
pub type Fmi2Char = c_char;
pub type Fmi2String = *const c_char;
pub type Fmi2Byte = c_char;

pub const FMI2_TRUE: Fmi2Boolean = 1;
pub const FMI2_FALSE: Fmi2Boolean = 0;

/// `fmi2Status`, ordered by severity.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Fmi2Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
    Pending = 5,
}

/// `fmi2Type`, an enum in C; kept as an `int` so that any value the environment passes is
/// defined behaviour.
pub type Fmi2Type = c_int;
pub const FMI2_MODEL_EXCHANGE: Fmi2Type = 0;
pub const FMI2_CO_SIMULATION: Fmi2Type = 1;

/// `fmi2StatusKind`, an `int` for the same reason.
pub type Fmi2StatusKind = c_int;
pub const FMI2_DO_STEP_STATUS: Fmi2StatusKind = 0;
pub const FMI2_PENDING_STATUS: Fmi2StatusKind = 1;
pub const FMI2_LAST_SUCCESSFUL_TIME: Fmi2StatusKind = 2;
pub const FMI2_TERMINATED: Fmi2StatusKind = 3;

/// `fmi2CallbackLogger`: variadic, the message is a printf format.
pub type Fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        Fmi2ComponentEnvironment,
        Fmi2String,
        Fmi2Status,
        Fmi2String,
        Fmi2String,
        ...
    ),
>;
pub type Fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
pub type Fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
pub type Fmi2StepFinished = Option<unsafe extern "C" fn(Fmi2ComponentEnvironment, Fmi2Status)>;

/// `fmi2CallbackFunctions`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct Fmi2CallbackFunctions {
    pub logger: Fmi2CallbackLogger,
    pub allocate_memory: Fmi2CallbackAllocateMemory,
    pub free_memory: Fmi2CallbackFreeMemory,
    pub step_finished: Fmi2StepFinished,
    pub component_environment: Fmi2ComponentEnvironment,
}

/// A logger for importing this crate's FMUs from Rust. FMI's logger is variadic, which stable Rust
/// cannot define; this crate's FMUs pass each message as the format (with '%' doubled) and no
/// further arguments, so a five-argument function receives all of it.
pub type Fmi2PlainLogger =
    unsafe extern "C" fn(Fmi2ComponentEnvironment, Fmi2String, Fmi2Status, Fmi2String, Fmi2String);

impl Fmi2CallbackFunctions {
    /// Callbacks with a [`Fmi2PlainLogger`], for calling this crate's FMUs from Rust (the
    /// memory callbacks are unused: `canNotUseMemoryManagementFunctions` is true).
    pub fn with_plain_logger(
        logger: Fmi2PlainLogger,
        environment: Fmi2ComponentEnvironment,
    ) -> Self {
        type Variadic = unsafe extern "C" fn(
            Fmi2ComponentEnvironment,
            Fmi2String,
            Fmi2Status,
            Fmi2String,
            Fmi2String,
            ...
        );
        Fmi2CallbackFunctions {
            // SAFETY: the callee reads only the five fixed arguments, and the FMU passes no
            // variadic ones (see `Fmi2Sink` in `fmi2/logger.rs`).
            logger: Some(unsafe { std::mem::transmute::<Fmi2PlainLogger, Variadic>(logger) }),
            allocate_memory: None,
            free_memory: None,
            step_finished: None,
            component_environment: environment,
        }
    }
}

/// `fmi2EventInfo`, filled by `fmi2NewDiscreteStates`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Fmi2EventInfo {
    pub new_discrete_states_needed: Fmi2Boolean,
    pub terminate_simulation: Fmi2Boolean,
    pub nominals_of_continuous_states_changed: Fmi2Boolean,
    pub values_of_continuous_states_changed: Fmi2Boolean,
    pub next_event_time_defined: Fmi2Boolean,
    pub next_event_time: Fmi2Real,
}

/// The FMI 2.0 status of the core's status: the same five numbers; the core never returns
/// `fmi2Pending`.
impl From<Status> for Fmi2Status {
    fn from(s: Status) -> Self {
        match s {
            Status::Ok => Fmi2Status::Ok,
            Status::Warning => Fmi2Status::Warning,
            Status::Discard => Fmi2Status::Discard,
            Status::Error => Fmi2Status::Error,
            Status::Fatal => Fmi2Status::Fatal,
        }
    }
}

/// An FMI 2.0 Boolean of a Rust one.
pub fn fmi2_boolean(b: bool) -> Fmi2Boolean {
    if b {
        FMI2_TRUE
    } else {
        FMI2_FALSE
    }
}
