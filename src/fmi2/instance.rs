//! One FMU instance: the FMI 2.0 co-simulation state machine over a model.
//!
//! Every method returns the `fmi2Status` to hand back to the environment and logs why when it is
//! not `fmi2OK`. Any `fmi2Error` puts the instance into the error state, from which only
//! `fmi2Reset`, `fmi2SetFMUstate`, the getters and `fmi2FreeInstance` lead on (FMI 2.0.4,
//! section 4.2.4).

use std::ffi::{CStr, CString};
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::ffi::{Fmi2CallbackFunctions, Fmi2Status};
use super::variables::{check_value, Value, Values};
use super::{Experiment, FmuModel, LogCategory};

/// Guards against pointers that are not instances of this library.
const INSTANCE_MAGIC: u64 = 0x4853_505f_464d_5532; // "HSP_FMU2"

/// The states of the co-simulation state machine (FMI 2.0.4, figure 9).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MachineState {
    Instantiated,
    InitializationMode,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
    Fatal,
}

impl MachineState {
    fn name(self) -> &'static str {
        match self {
            MachineState::Instantiated => "instantiated",
            MachineState::InitializationMode => "initialization mode",
            MachineState::StepComplete => "step complete",
            MachineState::StepFailed => "step failed",
            MachineState::Terminated => "terminated",
            MachineState::Error => "error",
            MachineState::Fatal => "fatal",
        }
    }
}

use MachineState::*;

/// The states in which the getters may be called.
const GETTER_STATES: &[MachineState] = &[
    InitializationMode,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
];
/// Every state but fatal: where logging can be set, the instance reset, and FMU states taken,
/// restored and serialised.
const NOT_FATAL: &[MachineState] = &[
    Instantiated,
    InitializationMode,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
];

/// The environment's side: logger callback, instance name and which categories it wants.
pub struct Logger {
    instance_name: CString,
    callbacks: Fmi2CallbackFunctions,
    /// Which debug categories are on, indexed by `LogCategory as usize`.
    enabled: [bool; LogCategory::ALL.len()],
}

impl Logger {
    /// Sends a message to the environment's logger. Warnings, discards, errors and fatal errors
    /// are always sent (as the Reference FMUs do); the other categories when they are on.
    pub fn log(&self, status: Fmi2Status, category: LogCategory, message: &str) {
        let always = matches!(
            category,
            LogCategory::StatusWarning
                | LogCategory::StatusDiscard
                | LogCategory::StatusError
                | LogCategory::StatusFatal
        );
        // logAll switches on every category.
        let wanted = self.enabled[category as usize] || self.enabled[LogCategory::All as usize];
        if !(always || wanted) {
            return;
        }
        let Some(logger) = self.callbacks.logger else {
            return;
        };
        let category = CString::new(category.name()).unwrap_or_default();
        // The logger's message is a printf format. Importers that format it and importers that
        // print it as it is both exist; passing the message itself, with '%' doubled, reads right
        // in the first and nearly right in the second, and never lets a '%' in a message be taken
        // for a conversion.
        let message =
            CString::new(message.replace('\0', " ").replace('%', "%%")).unwrap_or_default();
        unsafe {
            logger(
                self.callbacks.component_environment,
                self.instance_name.as_ptr(),
                status,
                category.as_ptr(),
                message.as_ptr(),
            );
        }
    }
}

/// What an FMU state holds: everything needed to continue bit-identically.
#[derive(Clone, Serialize, Deserialize)]
pub struct Snapshot<S> {
    guid: String,
    state: MachineState,
    time: f64,
    last_successful_time: f64,
    experiment: Experiment,
    values: Values,
    needs_initialize: bool,
    model: S,
}

/// Magic bytes at the start of a serialised FMU state.
const SERIAL_MAGIC: &[u8; 8] = b"HSPFMUS1";
const SERIAL_HEADER: usize = 8 + 8 + 8;

/// FNV-1a over bytes: a checksum that catches corrupted serialised states.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        hash ^= u64::from(*b);
        hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
    hash
}

/// A saved FMU state, with its serialised form computed once when asked for.
pub struct SavedState<S> {
    snapshot: Snapshot<S>,
    serialized: Option<Vec<u8>>,
}

impl<S: Serialize + for<'de> Deserialize<'de>> SavedState<S> {
    /// The serialised form: magic, payload length, payload checksum, JSON payload.
    pub fn serialized(&mut self) -> Result<&[u8], String> {
        if self.serialized.is_none() {
            let payload = serde_json::to_vec(&self.snapshot)
                .map_err(|e| format!("cannot serialise the FMU state: {e}"))?;
            let mut bytes = Vec::with_capacity(SERIAL_HEADER + payload.len());
            bytes.extend_from_slice(SERIAL_MAGIC);
            bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
            bytes.extend_from_slice(&fnv1a64(&payload).to_le_bytes());
            bytes.extend_from_slice(&payload);
            self.serialized = Some(bytes);
        }
        Ok(self.serialized.as_deref().unwrap_or_default())
    }

    /// Reads a serialised state, checking its header, length, checksum and GUID.
    pub fn deserialize(bytes: &[u8], guid: &str) -> Result<Self, String> {
        if bytes.len() < SERIAL_HEADER || &bytes[..8] != SERIAL_MAGIC {
            return Err(format!(
                "the serialized FMU state ({} bytes) does not start with this FMU's header",
                bytes.len()
            ));
        }
        let len = u64::from_le_bytes(bytes[8..16].try_into().unwrap_or_default());
        let sum = u64::from_le_bytes(bytes[16..24].try_into().unwrap_or_default());
        let payload = &bytes[SERIAL_HEADER..];
        if payload.len() as u64 != len {
            return Err(format!(
                "the serialized FMU state is truncated or padded: header says {len} payload bytes, got {}",
                payload.len()
            ));
        }
        if fnv1a64(payload) != sum {
            return Err("the serialized FMU state is corrupted: checksum mismatch".to_string());
        }
        let snapshot: Snapshot<S> = serde_json::from_slice(payload)
            .map_err(|e| format!("the serialized FMU state cannot be read: {e}"))?;
        if snapshot.guid != guid {
            return Err(format!(
                "the serialized FMU state belongs to GUID {}, not to this FMU ({guid})",
                snapshot.guid
            ));
        }
        Ok(SavedState {
            snapshot,
            serialized: None,
        })
    }
}

/// One FMU instance. `repr(C)` puts the magic number first, so that a pointer can be checked
/// before a reference to the whole instance is made.
#[repr(C)]
pub struct Instance<M: FmuModel> {
    magic: u64,
    pub logger: Logger,
    pub resource_location: Option<PathBuf>,
    state: MachineState,
    experiment: Experiment,
    values: Values,
    model: M,
    time: f64,
    last_successful_time: f64,
    /// A parameter or input changed since the model was last initialised.
    needs_initialize: bool,
    /// Strings handed out by `fmi2GetString`, valid until the next call.
    string_buffer: Vec<CString>,
}

impl<M: FmuModel> Instance<M> {
    /// `fmi2Instantiate`'s checks; `Err` carries the message to log before returning NULL.
    pub fn new(
        instance_name: &str,
        guid: &str,
        resource_location: Option<&str>,
        callbacks: Fmi2CallbackFunctions,
        logging_on: bool,
    ) -> Result<Self, (Logger, String)> {
        let logger = Logger {
            instance_name: CString::new(instance_name).unwrap_or_default(),
            callbacks,
            // fmi2Instantiate's loggingOn switches every category (FMI 2.0.4, 2.1.5).
            enabled: [logging_on; LogCategory::ALL.len()],
        };
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
        let resource_location = resource_location.and_then(file_uri_to_path);
        Ok(Instance {
            magic: INSTANCE_MAGIC,
            logger,
            resource_location,
            state: Instantiated,
            experiment: Experiment::default(),
            values: Values::from_start(M::variables()),
            model: M::new(),
            time: 0.0,
            last_successful_time: 0.0,
            needs_initialize: true,
            string_buffer: Vec::new(),
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

    pub fn values(&self) -> &Values {
        &self.values
    }

    pub fn time(&self) -> f64 {
        self.time
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

    /// Logs the call when the `logCalls` category is on.
    pub fn log_call(&self, call: impl FnOnce() -> String) {
        if self.logger.enabled[LogCategory::Calls as usize]
            || self.logger.enabled[LogCategory::All as usize]
        {
            self.logger.log(Fmi2Status::Ok, LogCategory::Calls, &call());
        }
    }

    /// Checks that `function` may be called in the current state.
    pub fn allowed(&mut self, function: &str, states: &[MachineState]) -> Result<(), Fmi2Status> {
        if states.contains(&self.state) {
            Ok(())
        } else if self.state == Fatal {
            // After fmi2Fatal nothing but fmi2FreeInstance is allowed, and nothing is logged
            // into an error state on top of it.
            Err(Fmi2Status::Error)
        } else {
            let state = self.state.name();
            Err(self.error(&format!(
                "{function}: illegal call sequence: not allowed in state '{state}'"
            )))
        }
    }

    pub fn set_debug_logging(&mut self, logging_on: bool, categories: &[&str]) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2SetDebugLogging", NOT_FATAL) {
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
        if chosen.is_empty() {
            self.logger.enabled = [logging_on; LogCategory::ALL.len()];
        } else {
            for c in chosen {
                self.logger.enabled[c as usize] = logging_on;
            }
        }
        Fmi2Status::Ok
    }

    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2SetupExperiment", &[Instantiated]) {
            return s;
        }
        if let Some(tol) = tolerance {
            if !(tol.is_finite() && tol > 0.0) {
                return self.error(&format!(
                    "fmi2SetupExperiment: tolerance must be positive and finite, got {tol}"
                ));
            }
        }
        if !start_time.is_finite() {
            return self.error(&format!(
                "fmi2SetupExperiment: startTime must be finite, got {start_time}"
            ));
        }
        if let Some(stop) = stop_time {
            if !(stop.is_finite() && stop >= start_time) {
                return self.error(&format!(
                    "fmi2SetupExperiment: stopTime {stop} must be finite and not before startTime {start_time}"
                ));
            }
        }
        self.experiment = Experiment {
            tolerance,
            start_time,
            stop_time,
        };
        self.time = start_time;
        self.last_successful_time = start_time;
        self.needs_initialize = true;
        Fmi2Status::Ok
    }

    pub fn enter_initialization_mode(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2EnterInitializationMode", &[Instantiated]) {
            return s;
        }
        self.state = InitializationMode;
        self.time = self.experiment.start_time;
        Fmi2Status::Ok
    }

    /// Builds the model if a parameter changed since it was last built.
    fn ensure_initialized(&mut self) -> Result<(), Fmi2Status> {
        if self.needs_initialize {
            if let Err(msg) = self.model.initialize(&mut self.values, &self.experiment) {
                return Err(self.error(&format!("initialization failed: {msg}")));
            }
            self.needs_initialize = false;
        }
        Ok(())
    }

    pub fn exit_initialization_mode(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2ExitInitializationMode", &[InitializationMode]) {
            return s;
        }
        self.needs_initialize = true;
        if let Err(s) = self.ensure_initialized() {
            return s;
        }
        self.state = StepComplete;
        self.time = self.experiment.start_time;
        self.last_successful_time = self.time;
        Fmi2Status::Ok
    }

    pub fn terminate(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2Terminate", &[StepComplete, StepFailed]) {
            return s;
        }
        self.state = Terminated;
        Fmi2Status::Ok
    }

    /// `fmi2Reset`: exactly the state of a fresh instantiation (the logging settings stay).
    pub fn reset(&mut self) -> Fmi2Status {
        if let Err(s) = self.allowed("fmi2Reset", NOT_FATAL) {
            return s;
        }
        self.state = Instantiated;
        self.experiment = Experiment::default();
        self.values = Values::from_start(M::variables());
        self.model = M::new();
        self.time = 0.0;
        self.last_successful_time = 0.0;
        self.needs_initialize = true;
        Fmi2Status::Ok
    }

    /// Resolves value references to table positions, checking each one's type.
    fn resolve(
        &mut self,
        function: &str,
        vrs: &[u32],
        type_name: &str,
    ) -> Result<Vec<usize>, Fmi2Status> {
        let mut out = Vec::with_capacity(vrs.len());
        for &vr in vrs {
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
            out.push(index);
        }
        Ok(out)
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
        if let Err(s) = self.allowed(function, GETTER_STATES) {
            return s;
        }
        let indices = match self.resolve(function, vrs, type_name) {
            Ok(i) => i,
            Err(s) => return s,
        };
        if self.state == InitializationMode {
            if let Err(s) = self.ensure_initialized() {
                return s;
            }
        }
        for (slot, index) in out.iter_mut().zip(indices) {
            *slot = convert(self.values.get(index));
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
        if let Err(s) = self.allowed(function, &[Instantiated, InitializationMode, StepComplete]) {
            return s;
        }
        let indices = match self.resolve(function, vrs, type_name) {
            Ok(i) => i,
            Err(s) => return s,
        };
        let running = self.state == StepComplete;
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
        if let Err(s) = self.allowed("fmi2DoStep", &[StepComplete]) {
            return s;
        }
        if !(step_size.is_finite() && step_size > 0.0) {
            return self.error(&format!(
                "fmi2DoStep: communicationStepSize must be positive and finite, got {step_size}"
            ));
        }
        // A master that adds up its steps drifts by round-off; anything more is a wrong call.
        let slack = 1e-9 * self.time.abs().max(1.0);
        if !current_communication_point.is_finite()
            || (current_communication_point - self.time).abs() > slack
        {
            return self.error(&format!(
                "fmi2DoStep: currentCommunicationPoint {current_communication_point} does not match the FMU's time {}",
                self.time
            ));
        }
        let t_end = current_communication_point + step_size;
        if let Some(stop) = self.experiment.stop_time {
            if t_end > stop + 1e-9 * stop.abs().max(1.0) {
                return self.error(&format!(
                    "fmi2DoStep: the step to {t_end} goes past stopTime {stop}"
                ));
            }
        }
        let logger = &self.logger;
        let mut log = |category: LogCategory, message: &str| {
            let status = if category == LogCategory::StatusWarning {
                Fmi2Status::Warning
            } else {
                Fmi2Status::Ok
            };
            logger.log(status, category, message);
        };
        match self
            .model
            .do_step(&mut self.values, self.time, t_end, &mut log)
        {
            Ok(()) => {
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
                        "fmi2DoStep: step from {current_communication_point} to {t_end} discarded at t = {}: {}",
                        failure.last_successful_time, failure.message
                    ),
                );
                Fmi2Status::Discard
            }
        }
    }

    /// `fmi2GetRealStatus(fmi2LastSuccessfulTime)`.
    pub fn last_successful_time(&mut self) -> Result<f64, Fmi2Status> {
        self.allowed("fmi2GetRealStatus", &[StepComplete, StepFailed, Terminated])?;
        Ok(self.last_successful_time)
    }

    /// `fmi2GetBooleanStatus(fmi2Terminated)`: the FMU never asks to end the simulation itself;
    /// a discarded step can be retried from a restored FMU state.
    pub fn terminated_status(&mut self) -> Result<bool, Fmi2Status> {
        self.allowed(
            "fmi2GetBooleanStatus",
            &[StepComplete, StepFailed, Terminated],
        )?;
        Ok(false)
    }

    pub fn check_fmu_state_call(&mut self, function: &str) -> Result<(), Fmi2Status> {
        self.allowed(function, NOT_FATAL)
    }

    /// `fmi2GetFMUstate`.
    pub fn save(&mut self) -> SavedState<M::State> {
        SavedState {
            snapshot: Snapshot {
                guid: M::GUID.to_string(),
                state: self.state,
                time: self.time,
                last_successful_time: self.last_successful_time,
                experiment: self.experiment,
                values: self.values.clone(),
                needs_initialize: self.needs_initialize,
                model: self.model.save_state(),
            },
            serialized: None,
        }
    }

    /// `fmi2SetFMUstate`.
    pub fn restore(&mut self, saved: &SavedState<M::State>) -> Fmi2Status {
        let s = &saved.snapshot;
        if s.values.len() != M::variables().len() {
            return self.error("fmi2SetFMUstate: the FMU state has the wrong number of variables");
        }
        if let Err(msg) = self.model.restore_state(&s.model, &s.values, &s.experiment) {
            return self.error(&format!("fmi2SetFMUstate: {msg}"));
        }
        self.state = match s.state {
            Error | Fatal => StepComplete,
            other => other,
        };
        self.time = s.time;
        self.last_successful_time = s.last_successful_time;
        self.experiment = s.experiment;
        self.values = s.values.clone();
        self.needs_initialize = s.needs_initialize;
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

    #[test]
    fn checksum_is_fnv1a() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
