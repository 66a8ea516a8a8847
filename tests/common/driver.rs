//! One driver over the C ABI of both FMI versions: the shared rules of the FMI contract are
//! written once against [`Driver`] and run through FMI 2.0 ([`V2`]) and FMI 3.0 ([`V3`]), so a
//! rule broken in one version fails that version's run only. Each instance logs into a log of its
//! own; statuses are compared as [`St`], the five statuses both versions share.

#![allow(dead_code)]

use std::ffi::{c_void, CStr, CString};
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

type Log = Mutex<Vec<(St, String)>>;

unsafe extern "C" fn log2(
    env: *mut c_void,
    _name: *const c_char,
    status: Fmi2Status,
    _category: *const c_char,
    message: *const c_char,
) {
    let log = &*(env as *const Log);
    let m = CStr::from_ptr(message).to_string_lossy().replace("%%", "%");
    log.lock().unwrap().push((status.into(), m));
}

unsafe extern "C" fn log3(
    env: *mut c_void,
    status: Fmi3Status,
    _category: *const c_char,
    message: *const c_char,
) {
    let log = &*(env as *const Log);
    let m = CStr::from_ptr(message).to_string_lossy().into_owned();
    log.lock().unwrap().push((status.into(), m));
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
    fn new(kind: Kind) -> Self;
    fn log(&self) -> Vec<(St, String)>;
    /// The last log message, or "" when there is none.
    fn last(&self) -> String {
        self.log().last().map(|l| l.1.clone()).unwrap_or_default()
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
    fn exit(&self) -> St;
    fn init(&self, start: f64) -> St {
        match self.enter(start) {
            St::Ok => self.exit(),
            s => s,
        }
    }
    fn step(&self, t: f64, h: f64) -> St;
    fn get_state(&self) -> (St, *mut c_void);
    fn set_state(&self, s: *mut c_void) -> St;
    fn free_state(&self, s: *mut c_void) -> St;
    fn serialize(&self, s: *mut c_void) -> Vec<u8>;
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
    c: Fmi2Component,
    log: Box<Log>,
}

impl Driver for V2 {
    const PREFIX: &'static str = "fmi2";

    fn new(kind: Kind) -> V2 {
        let log: Box<Log> = Box::new(Mutex::new(Vec::new()));
        let env = &*log as *const Log as *mut c_void;
        let callbacks = Fmi2CallbackFunctions::with_plain_logger(log2, env);
        let guid = CString::new(GUID).unwrap();
        let fmu_type = match kind {
            Kind::CoSimulation => FMI2_CO_SIMULATION,
            Kind::ModelExchange => FMI2_MODEL_EXCHANGE,
        };
        let c = unsafe {
            fmi2Instantiate(
                c"both".as_ptr(),
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
    fn log(&self) -> Vec<(St, String)> {
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
        unsafe { fmi2EnterInitializationMode(self.c) }.into()
    }
    fn exit(&self) -> St {
        unsafe { fmi2ExitInitializationMode(self.c) }.into()
    }
    fn step(&self, t: f64, h: f64) -> St {
        unsafe { fmi2DoStep(self.c, t, h, FMI2_TRUE) }.into()
    }
    fn get_state(&self) -> (St, *mut c_void) {
        let mut s: Fmi2FmuState = std::ptr::null_mut();
        let status = unsafe { fmi2GetFMUstate(self.c, &mut s) };
        (status.into(), s)
    }
    fn set_state(&self, s: *mut c_void) -> St {
        unsafe { fmi2SetFMUstate(self.c, s) }.into()
    }
    fn free_state(&self, mut s: *mut c_void) -> St {
        unsafe { fmi2FreeFMUstate(self.c, &mut s) }.into()
    }
    fn serialize(&self, s: *mut c_void) -> Vec<u8> {
        let mut size = 0usize;
        unsafe {
            assert_eq!(
                fmi2SerializedFMUstateSize(self.c, s, &mut size),
                Fmi2Status::Ok
            );
            let mut bytes = vec![0u8; size];
            let p = bytes.as_mut_ptr() as *mut Fmi2Byte;
            assert_eq!(fmi2SerializeFMUstate(self.c, s, p, size), Fmi2Status::Ok);
            bytes
        }
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
    c: Fmi3Instance,
    log: Box<Log>,
}

impl Driver for V3 {
    const PREFIX: &'static str = "fmi3";

    fn new(kind: Kind) -> V3 {
        let log: Box<Log> = Box::new(Mutex::new(Vec::new()));
        let env = &*log as *const Log as *mut c_void;
        let token = CString::new(GUID).unwrap();
        let c = unsafe {
            match kind {
                Kind::CoSimulation => fmi3InstantiateCoSimulation(
                    c"both".as_ptr(),
                    token.as_ptr(),
                    std::ptr::null(),
                    0,
                    0,
                    0,
                    0,
                    std::ptr::null(),
                    0,
                    env,
                    Some(log3),
                    None,
                ),
                Kind::ModelExchange => fmi3InstantiateModelExchange(
                    c"both".as_ptr(),
                    token.as_ptr(),
                    std::ptr::null(),
                    0,
                    0,
                    env,
                    Some(log3),
                ),
            }
        };
        assert!(!c.is_null());
        V3 { c, log }
    }
    fn log(&self) -> Vec<(St, String)> {
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
    fn exit(&self) -> St {
        unsafe { fmi3ExitInitializationMode(self.c) }.into()
    }
    fn step(&self, t: f64, h: f64) -> St {
        let (mut event, mut terminate, mut early, mut last) = (false, false, false, f64::NAN);
        unsafe {
            fmi3DoStep(
                self.c,
                t,
                h,
                1,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last,
            )
        }
        .into()
    }
    fn get_state(&self) -> (St, *mut c_void) {
        let mut s: Fmi3FmuState = std::ptr::null_mut();
        let status = unsafe { fmi3GetFMUState(self.c, &mut s) };
        (status.into(), s)
    }
    fn set_state(&self, s: *mut c_void) -> St {
        unsafe { fmi3SetFMUState(self.c, s) }.into()
    }
    fn free_state(&self, mut s: *mut c_void) -> St {
        unsafe { fmi3FreeFMUState(self.c, &mut s) }.into()
    }
    fn serialize(&self, s: *mut c_void) -> Vec<u8> {
        let mut size = 0usize;
        unsafe {
            assert_eq!(
                fmi3SerializedFMUStateSize(self.c, s, &mut size),
                Fmi3Status::Ok
            );
            let mut bytes = vec![0u8; size];
            assert_eq!(
                fmi3SerializeFMUState(self.c, s, bytes.as_mut_ptr(), size),
                Fmi3Status::Ok
            );
            bytes
        }
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

impl Drop for V3 {
    fn drop(&mut self) {
        unsafe { fmi3FreeInstance(self.c) };
    }
}

/// Runs a rule through both versions: `rule!(name, body)` makes `mod name { fn fmi2(); fn fmi3() }`
/// with the body generic over the driver `D`.
#[macro_export]
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
