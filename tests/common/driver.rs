//! One driver over the C ABI of both FMI versions: the shared rules of the FMI contract are
//! written once against [`Driver`] and run through FMI 2.0 ([`V2`]) and FMI 3.0 ([`V3`]), so a
//! rule broken in one version fails that version's run only. Each instance logs into a log of its
//! own; statuses are compared as [`St`], the five statuses both versions share.

#![allow(dead_code)]

use std::cell::Cell;
use std::ffi::{c_void, CStr, CString};
use std::fmt::Debug;
use std::os::raw::c_char;
use std::sync::Mutex;

use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::fmi2_exports::*;
use hydraulic_slewing_plate::fmi3::ffi::*;
use hydraulic_slewing_plate::fmi3::variables::Fmi3Table;
use hydraulic_slewing_plate::fmi3_exports::*;
use hydraulic_slewing_plate::fmu::{Causality, FmuModel, Kind as ValueKind};
use hydraulic_slewing_plate::model::variables::{GUID, VARIABLES};
use hydraulic_slewing_plate::model::HydraulicSlewingPlate;

#[path = "state_blob.rs"]
mod state_blob;
#[allow(unused_imports)]
pub use state_blob::{blob, find_key, payload};

/// The statuses both versions share, in order of severity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum St {
    Ok,
    Warning,
    Discard,
    Error,
    Fatal,
    /// `fmi2Pending`, which no call of this FMU may return.
    Pending,
}

impl From<Fmi2Status> for St {
    fn from(s: Fmi2Status) -> St {
        match s {
            Fmi2Status::Ok => St::Ok,
            Fmi2Status::Warning => St::Warning,
            Fmi2Status::Discard => St::Discard,
            Fmi2Status::Error => St::Error,
            Fmi2Status::Fatal => St::Fatal,
            Fmi2Status::Pending => St::Pending,
        }
    }
}

impl From<Fmi3Status> for St {
    fn from(s: Fmi3Status) -> St {
        match s {
            Fmi3Status::Ok => St::Ok,
            Fmi3Status::Warning => St::Warning,
            Fmi3Status::Discard => St::Discard,
            Fmi3Status::Error => St::Error,
            Fmi3Status::Fatal => St::Fatal,
        }
    }
}

impl From<St> for Fmi2Status {
    fn from(s: St) -> Fmi2Status {
        match s {
            St::Ok => Fmi2Status::Ok,
            St::Warning => Fmi2Status::Warning,
            St::Discard => Fmi2Status::Discard,
            St::Error => Fmi2Status::Error,
            St::Fatal => Fmi2Status::Fatal,
            St::Pending => Fmi2Status::Pending,
        }
    }
}

impl From<St> for Fmi3Status {
    fn from(s: St) -> Fmi3Status {
        match s {
            St::Ok => Fmi3Status::Ok,
            St::Warning => Fmi3Status::Warning,
            St::Discard => Fmi3Status::Discard,
            St::Error => Fmi3Status::Error,
            St::Fatal => Fmi3Status::Fatal,
            St::Pending => panic!("FMI 3.0 has no status Pending"),
        }
    }
}

/// One log line: status, category and message.
pub type Line = (St, String, String);

type Log = Mutex<Vec<Line>>;

/// A new log and the environment pointer that leads the logger to it.
fn new_log() -> (Box<Log>, *mut c_void) {
    let log: Box<Log> = Box::new(Mutex::new(Vec::new()));
    let env = &*log as *const Log as *mut c_void;
    (log, env)
}

/// # Safety
/// `env` from [`new_log`], its log alive; the strings NUL-terminated.
unsafe fn push(env: *mut c_void, status: St, category: *const c_char, message: String) {
    let log = &*(env as *const Log);
    let c = CStr::from_ptr(category).to_string_lossy().into_owned();
    log.lock().unwrap().push((status, c, message));
}

unsafe extern "C" fn log2(
    env: *mut c_void,
    _name: *const c_char,
    status: Fmi2Status,
    category: *const c_char,
    message: *const c_char,
) {
    let m = CStr::from_ptr(message).to_string_lossy().replace("%%", "%");
    push(env, status.into(), category, m);
}

unsafe extern "C" fn log3(
    env: *mut c_void,
    status: Fmi3Status,
    category: *const c_char,
    message: *const c_char,
) {
    let m = CStr::from_ptr(message).to_string_lossy().into_owned();
    push(env, status.into(), category, m);
}

/// The interface an instance is made for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    CoSimulation,
    ModelExchange,
}

/// The C functions of one FMI version, as the shared rules use them. Names are variable names of
/// the table (scalars), values in SI.
pub trait Driver: Sized {
    /// "fmi2" or "fmi3", the prefix of the version's function names.
    const PREFIX: &'static str;
    /// The prefix of the other version's functions, which no message of this version names.
    const OTHER_PREFIX: &'static str;
    /// How the version spells the FMU state in its function and argument names: FMI 2.0's
    /// `FMUstate`, FMI 3.0's `FMUState`.
    const FMU_STATE: &'static str;
    /// Whether the version has `fmi2GetRealStatus`, which answers for the last successful time
    /// in any state (FMI 3.0 hands it out of `fmi3DoStep` instead).
    const GET_REAL_STATUS: bool;
    /// The version's own status type.
    type Status: From<St> + Copy + Debug + PartialEq;
    fn new(kind: Kind) -> Self;
    /// The instance pointer (to pass where an FMU state belongs, say).
    fn instance(&self) -> *mut c_void;
    /// The log lines so far: status, category, message.
    fn lines(&self) -> Vec<Line>;
    /// The log so far: status and message.
    fn log(&self) -> Vec<(St, String)> {
        self.lines().into_iter().map(|(s, _, m)| (s, m)).collect()
    }
    fn log_len(&self) -> usize {
        self.lines().len()
    }
    /// The last log message, or "" when there is none.
    fn last(&self) -> String {
        self.lines().pop().map(|l| l.2).unwrap_or_default()
    }
    fn set_real(&self, name: &str, v: f64) -> St;
    fn set_integer(&self, name: &str, v: i32) -> St;
    fn set_boolean(&self, name: &str, v: bool) -> St;
    fn get_real(&self, name: &str) -> (St, f64);
    /// Reads every Real variable of the version's view once (FMI 3.0 reads an array whole):
    /// `(name, status, value)` per scalar.
    fn every_real(&self) -> Vec<(String, St, f64)>;
    /// Sets up the experiment from `start` and enters initialization mode.
    fn enter(&self, start: f64) -> St;
    /// `EnterInitializationMode` alone (FMI 2.0 without `fmi2SetupExperiment` before it; FMI 3.0
    /// with the experiment starting at 0).
    fn enter_initialization_mode(&self) -> St;
    fn exit(&self) -> St;
    fn init(&self, start: f64) -> St {
        match self.enter(start) {
            St::Ok => self.exit(),
            s => s,
        }
    }
    fn reset(&self) -> St;
    fn step(&self, t: f64, h: f64) -> St;
    /// The last successful time: FMI 2.0's `fmi2GetRealStatus(fmi2LastSuccessfulTime)`; FMI
    /// 3.0's `lastSuccessfulTime` of the last `fmi3DoStep` that returned OK or Discard, as OK
    /// (Error and NaN when none did).
    fn last_successful_time(&self) -> (St, f64);
    fn get_state(&self) -> (St, *mut c_void);
    fn set_state(&self, s: *mut c_void) -> St;
    /// `FreeFMUState`, which sets `*s` to NULL.
    fn free_state_at(&self, s: &mut *mut c_void) -> St;
    fn free_state(&self, mut s: *mut c_void) -> St {
        self.free_state_at(&mut s)
    }
    fn serialized_size(&self, s: *mut c_void) -> (St, usize);
    fn serialize_into(&self, s: *mut c_void, bytes: &mut [u8]) -> St;
    /// The serialised state (both calls must succeed).
    fn serialize(&self, s: *mut c_void) -> Vec<u8> {
        let (status, size) = self.serialized_size(s);
        assert_eq!(status, St::Ok, "{}", self.last());
        let mut bytes = vec![0u8; size];
        assert_eq!(
            self.serialize_into(s, &mut bytes),
            St::Ok,
            "{}",
            self.last()
        );
        bytes
    }
    fn deserialize(&self, bytes: &[u8]) -> (St, *mut c_void);
    // Model Exchange.
    fn enter_continuous_time_mode(&self) -> St;
    fn set_continuous_states(&self, x: &[f64]) -> St;
    fn continuous_states(&self, n: usize) -> (St, Vec<f64>);
    fn nominals(&self, n: usize) -> (St, Vec<f64>);
    fn derivatives(&self, n: usize) -> (St, Vec<f64>);
}

/// The value reference of a scalar of the table (for FMI 3.0 also the array's, for the first
/// element of an array: the tests use scalars).
pub fn vr(name: &str) -> u32 {
    VARIABLES
        .iter()
        .find(|v| v.name == name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

/// FMI 2.0 through the exported `fmi2*` functions.
pub struct V2 {
    pub c: Fmi2Component,
    log: Box<Log>,
}

impl V2 {
    /// An instance of `fmu_type`, which must not be NULL.
    pub fn of_type(fmu_type: Fmi2Type) -> V2 {
        let (log, env) = new_log();
        let callbacks = Fmi2CallbackFunctions::with_plain_logger(log2, env);
        let guid = CString::new(GUID).unwrap();
        let c = unsafe {
            fmi2Instantiate(
                c"contract".as_ptr(),
                fmu_type,
                guid.as_ptr(),
                std::ptr::null(),
                &callbacks,
                FMI2_FALSE,
                FMI2_FALSE,
            )
        };
        assert!(!c.is_null());
        V2 { c, log }
    }
}

impl Driver for V2 {
    const PREFIX: &'static str = "fmi2";
    const OTHER_PREFIX: &'static str = "fmi3";
    const FMU_STATE: &'static str = "FMUstate";
    const GET_REAL_STATUS: bool = true;
    type Status = Fmi2Status;

    fn new(kind: Kind) -> V2 {
        V2::of_type(match kind {
            Kind::CoSimulation => FMI2_CO_SIMULATION,
            Kind::ModelExchange => FMI2_MODEL_EXCHANGE,
        })
    }
    fn instance(&self) -> *mut c_void {
        self.c
    }
    fn lines(&self) -> Vec<Line> {
        self.log.lock().unwrap().clone()
    }
    fn set_real(&self, name: &str, v: f64) -> St {
        unsafe { fmi2SetReal(self.c, &vr(name), 1, &v) }.into()
    }
    fn set_integer(&self, name: &str, v: i32) -> St {
        unsafe { fmi2SetInteger(self.c, &vr(name), 1, &v) }.into()
    }
    fn set_boolean(&self, name: &str, v: bool) -> St {
        let v = if v { FMI2_TRUE } else { FMI2_FALSE };
        unsafe { fmi2SetBoolean(self.c, &vr(name), 1, &v) }.into()
    }
    fn get_real(&self, name: &str) -> (St, f64) {
        let mut v = f64::NAN;
        let s = unsafe { fmi2GetReal(self.c, &vr(name), 1, &mut v) };
        (s.into(), v)
    }
    fn every_real(&self) -> Vec<(String, St, f64)> {
        VARIABLES
            .iter()
            .filter(|v| matches!(v.kind, ValueKind::Real { .. }))
            .filter(|v| v.causality != Causality::Independent)
            .map(|v| {
                let (s, x) = self.get_real(v.name);
                (v.name.to_string(), s, x)
            })
            .collect()
    }
    fn enter(&self, start: f64) -> St {
        let s = unsafe { fmi2SetupExperiment(self.c, FMI2_FALSE, 0.0, start, FMI2_FALSE, 0.0) };
        if s != Fmi2Status::Ok {
            return s.into();
        }
        self.enter_initialization_mode()
    }
    fn enter_initialization_mode(&self) -> St {
        unsafe { fmi2EnterInitializationMode(self.c) }.into()
    }
    fn exit(&self) -> St {
        unsafe { fmi2ExitInitializationMode(self.c) }.into()
    }
    fn reset(&self) -> St {
        unsafe { fmi2Reset(self.c) }.into()
    }
    fn step(&self, t: f64, h: f64) -> St {
        unsafe { fmi2DoStep(self.c, t, h, FMI2_TRUE) }.into()
    }
    fn last_successful_time(&self) -> (St, f64) {
        let mut t = f64::NAN;
        let s = unsafe { fmi2GetRealStatus(self.c, FMI2_LAST_SUCCESSFUL_TIME, &mut t) };
        (s.into(), t)
    }
    fn get_state(&self) -> (St, *mut c_void) {
        let mut s: Fmi2FmuState = std::ptr::null_mut();
        let status = unsafe { fmi2GetFMUstate(self.c, &mut s) };
        (status.into(), s)
    }
    fn set_state(&self, s: *mut c_void) -> St {
        unsafe { fmi2SetFMUstate(self.c, s) }.into()
    }
    fn free_state_at(&self, s: &mut *mut c_void) -> St {
        unsafe { fmi2FreeFMUstate(self.c, s) }.into()
    }
    fn serialized_size(&self, s: *mut c_void) -> (St, usize) {
        let mut size = 0usize;
        let status = unsafe { fmi2SerializedFMUstateSize(self.c, s, &mut size) };
        (status.into(), size)
    }
    fn serialize_into(&self, s: *mut c_void, bytes: &mut [u8]) -> St {
        let p = bytes.as_mut_ptr() as *mut Fmi2Byte;
        unsafe { fmi2SerializeFMUstate(self.c, s, p, bytes.len()) }.into()
    }
    fn deserialize(&self, bytes: &[u8]) -> (St, *mut c_void) {
        let mut s: Fmi2FmuState = std::ptr::null_mut();
        let p = bytes.as_ptr() as *const Fmi2Byte;
        let status = unsafe { fmi2DeSerializeFMUstate(self.c, p, bytes.len(), &mut s) };
        (status.into(), s)
    }
    fn enter_continuous_time_mode(&self) -> St {
        let mut info = Fmi2EventInfo::default();
        let s = unsafe { fmi2NewDiscreteStates(self.c, &mut info) };
        if s != Fmi2Status::Ok {
            return s.into();
        }
        unsafe { fmi2EnterContinuousTimeMode(self.c) }.into()
    }
    fn set_continuous_states(&self, x: &[f64]) -> St {
        unsafe { fmi2SetContinuousStates(self.c, x.as_ptr(), x.len()) }.into()
    }
    fn continuous_states(&self, n: usize) -> (St, Vec<f64>) {
        let mut x = vec![f64::NAN; n];
        let s = unsafe { fmi2GetContinuousStates(self.c, x.as_mut_ptr(), n) };
        (s.into(), x)
    }
    fn nominals(&self, n: usize) -> (St, Vec<f64>) {
        let mut x = vec![f64::NAN; n];
        let s = unsafe { fmi2GetNominalsOfContinuousStates(self.c, x.as_mut_ptr(), n) };
        (s.into(), x)
    }
    fn derivatives(&self, n: usize) -> (St, Vec<f64>) {
        let mut x = vec![f64::NAN; n];
        let s = unsafe { fmi2GetDerivatives(self.c, x.as_mut_ptr(), n) };
        (s.into(), x)
    }
}

impl Drop for V2 {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}

/// FMI 3.0 through the exported `fmi3*` functions.
pub struct V3 {
    pub c: Fmi3Instance,
    log: Box<Log>,
    /// `lastSuccessfulTime` of the last `fmi3DoStep` that returned OK or Discard.
    last_successful_time: Cell<f64>,
}

impl V3 {
    /// An instance for `kind` with `loggingOn` and (co-simulation) `eventModeUsed` passed as the
    /// bytes given (C's `bool` arguments: an importer may pass any byte), or the log when
    /// instantiation returned NULL.
    pub fn instantiate(kind: Kind, logging_on: u8, event_mode_used: u8) -> Result<V3, Vec<Line>> {
        let (log, env) = new_log();
        let token = CString::new(GUID).unwrap();
        let name = c"contract".as_ptr();
        let c = unsafe {
            match kind {
                Kind::CoSimulation => fmi3InstantiateCoSimulation(
                    name,
                    token.as_ptr(),
                    std::ptr::null(),
                    0,
                    logging_on,
                    event_mode_used,
                    0,
                    std::ptr::null(),
                    0,
                    env,
                    Some(log3),
                    None,
                ),
                Kind::ModelExchange => fmi3InstantiateModelExchange(
                    name,
                    token.as_ptr(),
                    std::ptr::null(),
                    0,
                    logging_on,
                    env,
                    Some(log3),
                ),
            }
        };
        if c.is_null() {
            return Err(log.lock().unwrap().clone());
        }
        Ok(V3 {
            c,
            log,
            last_successful_time: Cell::new(f64::NAN),
        })
    }
}

impl Driver for V3 {
    const PREFIX: &'static str = "fmi3";
    const OTHER_PREFIX: &'static str = "fmi2";
    const FMU_STATE: &'static str = "FMUState";
    const GET_REAL_STATUS: bool = false;
    type Status = Fmi3Status;

    fn new(kind: Kind) -> V3 {
        V3::instantiate(kind, 0, 0).unwrap_or_else(|log| panic!("instantiation refused: {log:?}"))
    }
    fn instance(&self) -> *mut c_void {
        self.c
    }
    fn lines(&self) -> Vec<Line> {
        self.log.lock().unwrap().clone()
    }
    fn set_real(&self, name: &str, v: f64) -> St {
        unsafe { fmi3SetFloat64(self.c, &vr(name), 1, &v, 1) }.into()
    }
    fn set_integer(&self, name: &str, v: i32) -> St {
        unsafe { fmi3SetInt32(self.c, &vr(name), 1, &v, 1) }.into()
    }
    fn set_boolean(&self, name: &str, v: bool) -> St {
        let v = u8::from(v);
        unsafe { fmi3SetBoolean(self.c, &vr(name), 1, &v, 1) }.into()
    }
    fn get_real(&self, name: &str) -> (St, f64) {
        let mut v = f64::NAN;
        let s = unsafe { fmi3GetFloat64(self.c, &vr(name), 1, &mut v, 1) };
        (s.into(), v)
    }
    fn every_real(&self) -> Vec<(String, St, f64)> {
        let table = Fmi3Table::new(
            &VARIABLES,
            <HydraulicSlewingPlate as FmuModel>::continuous_states(),
        );
        let mut out = Vec::new();
        for v in table.variables() {
            if !matches!(VARIABLES[v.first].kind, ValueKind::Real { .. }) {
                continue;
            }
            let mut values = vec![f64::NAN; v.len];
            let s: St = unsafe {
                fmi3GetFloat64(self.c, &v.value_reference, 1, values.as_mut_ptr(), v.len)
            }
            .into();
            for (k, x) in values.into_iter().enumerate() {
                out.push((VARIABLES[v.first + k].name.to_string(), s, x));
            }
        }
        out
    }
    fn enter(&self, start: f64) -> St {
        unsafe { fmi3EnterInitializationMode(self.c, 0, 0.0, start, 0, 0.0) }.into()
    }
    fn enter_initialization_mode(&self) -> St {
        self.enter(0.0)
    }
    fn exit(&self) -> St {
        unsafe { fmi3ExitInitializationMode(self.c) }.into()
    }
    fn reset(&self) -> St {
        unsafe { fmi3Reset(self.c) }.into()
    }
    /// `fmi3DoStep`, as [`fmi3_do_step`]; `lastSuccessfulTime` is kept.
    fn step(&self, t: f64, h: f64) -> St {
        let (s, last) = fmi3_do_step(|event, terminate, early, last| unsafe {
            fmi3DoStep(self.c, t, h, 1, event, terminate, early, last)
        });
        if matches!(s, Fmi3Status::Ok | Fmi3Status::Discard) {
            self.last_successful_time.set(last);
        }
        s.into()
    }
    fn last_successful_time(&self) -> (St, f64) {
        let t = self.last_successful_time.get();
        (if t.is_nan() { St::Error } else { St::Ok }, t)
    }
    fn get_state(&self) -> (St, *mut c_void) {
        let mut s: Fmi3FmuState = std::ptr::null_mut();
        let status = unsafe { fmi3GetFMUState(self.c, &mut s) };
        (status.into(), s)
    }
    fn set_state(&self, s: *mut c_void) -> St {
        unsafe { fmi3SetFMUState(self.c, s) }.into()
    }
    fn free_state_at(&self, s: &mut *mut c_void) -> St {
        unsafe { fmi3FreeFMUState(self.c, s) }.into()
    }
    fn serialized_size(&self, s: *mut c_void) -> (St, usize) {
        let mut size = 0usize;
        let status = unsafe { fmi3SerializedFMUStateSize(self.c, s, &mut size) };
        (status.into(), size)
    }
    fn serialize_into(&self, s: *mut c_void, bytes: &mut [u8]) -> St {
        unsafe { fmi3SerializeFMUState(self.c, s, bytes.as_mut_ptr(), bytes.len()) }.into()
    }
    fn deserialize(&self, bytes: &[u8]) -> (St, *mut c_void) {
        let mut s: Fmi3FmuState = std::ptr::null_mut();
        let status =
            unsafe { fmi3DeserializeFMUState(self.c, bytes.as_ptr(), bytes.len(), &mut s) };
        (status.into(), s)
    }
    fn enter_continuous_time_mode(&self) -> St {
        let mut flags = [false; 5];
        let mut next = 0.0;
        let [a, b, c, d, e] = &mut flags;
        let s = unsafe { fmi3UpdateDiscreteStates(self.c, a, b, c, d, e, &mut next) };
        if s != Fmi3Status::Ok {
            return s.into();
        }
        unsafe { fmi3EnterContinuousTimeMode(self.c) }.into()
    }
    fn set_continuous_states(&self, x: &[f64]) -> St {
        unsafe { fmi3SetContinuousStates(self.c, x.as_ptr(), x.len()) }.into()
    }
    fn continuous_states(&self, n: usize) -> (St, Vec<f64>) {
        let mut x = vec![f64::NAN; n];
        let s = unsafe { fmi3GetContinuousStates(self.c, x.as_mut_ptr(), n) };
        (s.into(), x)
    }
    fn nominals(&self, n: usize) -> (St, Vec<f64>) {
        let mut x = vec![f64::NAN; n];
        let s = unsafe { fmi3GetNominalsOfContinuousStates(self.c, x.as_mut_ptr(), n) };
        (s.into(), x)
    }
    fn derivatives(&self, n: usize) -> (St, Vec<f64>) {
        let mut x = vec![f64::NAN; n];
        let s = unsafe { fmi3GetContinuousStateDerivatives(self.c, x.as_mut_ptr(), n) };
        (s.into(), x)
    }
}

/// Calls an `fmi3DoStep` (`step` with the out-arguments eventHandlingNeeded, terminateSimulation,
/// earlyReturn and lastSuccessfulTime, filled with true, true, true and NaN): its status and
/// lastSuccessfulTime. After OK or Discard the flags must say no event, no termination and no
/// early return (the model has no events and never returns early).
pub fn fmi3_do_step(
    step: impl FnOnce(&mut bool, &mut bool, &mut bool, &mut f64) -> Fmi3Status,
) -> (Fmi3Status, f64) {
    let (mut event, mut terminate, mut early, mut last) = (true, true, true, f64::NAN);
    let s = step(&mut event, &mut terminate, &mut early, &mut last);
    if matches!(s, Fmi3Status::Ok | Fmi3Status::Discard) {
        assert!(!event && !terminate && !early);
    }
    (s, last)
}

impl Drop for V3 {
    fn drop(&mut self) {
        unsafe { fmi3FreeInstance(self.c) };
    }
}

/// A driver whose calls answer in the version's own status type, for the tests of one version
/// (`common/fmu.rs`'s `Fmu` and `common/fmu3.rs`'s `Fmu3`, which add what their version alone
/// has); the instance pointer `c` is the driver's.
pub struct Native<D>(pub D);

impl<D> std::ops::Deref for Native<D> {
    type Target = D;
    fn deref(&self) -> &D {
        &self.0
    }
}

impl<D: Driver> Native<D> {
    /// The value reference of a scalar (for an FMI 3.0 array element: its array's only for the
    /// first element).
    pub fn vr(name: &str) -> u32 {
        vr(name)
    }
    pub fn log_len(&self) -> usize {
        self.0.log_len()
    }
    /// The last log message, or "" when there is none.
    pub fn last(&self) -> String {
        self.0.last()
    }
    pub fn set_real(&self, name: &str, v: f64) -> D::Status {
        self.0.set_real(name, v).into()
    }
    pub fn set_integer(&self, name: &str, v: i32) -> D::Status {
        self.0.set_integer(name, v).into()
    }
    pub fn set_boolean(&self, name: &str, v: bool) -> D::Status {
        self.0.set_boolean(name, v).into()
    }
    pub fn get_real(&self, name: &str) -> (D::Status, f64) {
        let (s, v) = self.0.get_real(name);
        (s.into(), v)
    }
    pub fn exit(&self) -> D::Status {
        self.0.exit().into()
    }
    /// Sets up the experiment at `start`, enters and exits initialisation mode (the first two
    /// must succeed); the status of the last.
    pub fn init(&self, start: f64) -> D::Status {
        assert_eq!(self.0.enter(start), St::Ok, "{}", self.0.last());
        self.0.exit().into()
    }
    pub fn step(&self, t: f64, h: f64) -> D::Status {
        self.0.step(t, h).into()
    }
    pub fn get_state(&self) -> (D::Status, *mut c_void) {
        let (s, state) = self.0.get_state();
        (s.into(), state)
    }
    pub fn set_state(&self, s: *mut c_void) -> D::Status {
        self.0.set_state(s).into()
    }
    pub fn free_state(&self, s: *mut c_void) -> D::Status {
        self.0.free_state(s).into()
    }
    pub fn serialize(&self, s: *mut c_void) -> Vec<u8> {
        self.0.serialize(s)
    }
    pub fn deserialize(&self, bytes: &[u8]) -> (D::Status, *mut c_void) {
        let (s, state) = self.0.deserialize(bytes);
        (s.into(), state)
    }
}

/// Runs a rule through both versions: `rule!(name, body)` makes `mod name { fn fmi2(); fn fmi3() }`
/// with the body generic over the driver `D` (`#[macro_use]` on the `mod driver` that includes this
/// file: it is not exported, so that a test binary may include this file more than once).
#[allow(unused_macros)]
macro_rules! both_versions {
    ($name:ident, $body:item) => {
        mod $name {
            #[allow(unused_imports)]
            use super::*;
            $body
            #[test]
            fn fmi2() {
                rule::<V2>();
            }
            #[test]
            fn fmi3() {
                rule::<V3>();
            }
        }
    };
}
