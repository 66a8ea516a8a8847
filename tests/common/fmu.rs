//! A thin driver over the library's exported `fmi2*` entry points, called in-process exactly as an
//! importer that has loaded the library would, with a log of its own per instance.

#![allow(dead_code)]

use std::ffi::{c_void, CStr, CString};
use std::os::raw::c_char;
use std::sync::Mutex;

use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::fmi2_exports::*;
use hydraulic_slewing_plate::model::variables::{GUID, VARIABLES};

#[path = "state_blob.rs"]
mod state_blob;
#[allow(unused_imports)]
pub use state_blob::{blob, find_key, payload};

/// One log line: status and message.
pub type Line = (Fmi2Status, String);

unsafe extern "C" fn logger(
    env: *mut c_void,
    _name: *const c_char,
    status: Fmi2Status,
    _category: *const c_char,
    message: *const c_char,
) {
    let log = &*(env as *const Mutex<Vec<Line>>);
    let m = CStr::from_ptr(message).to_string_lossy().replace("%%", "%");
    log.lock().unwrap().push((status, m));
}

/// An instance with its log; freed on drop.
pub struct Fmu {
    pub c: Fmi2Component,
    log: Box<Mutex<Vec<Line>>>,
}

impl Fmu {
    pub fn new() -> Fmu {
        Fmu::of_type(FMI2_CO_SIMULATION)
    }

    /// An instance for Model Exchange.
    pub fn model_exchange() -> Fmu {
        Fmu::of_type(FMI2_MODEL_EXCHANGE)
    }

    pub fn of_type(fmu_type: Fmi2Type) -> Fmu {
        let log = Box::new(Mutex::new(Vec::new()));
        let env = &*log as *const Mutex<Vec<Line>> as *mut c_void;
        let callbacks = Fmi2CallbackFunctions::with_plain_logger(logger, env);
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
        Fmu { c, log }
    }

    /// The log lines so far.
    pub fn log(&self) -> Vec<Line> {
        self.log.lock().unwrap().clone()
    }

    /// The number of log lines so far.
    pub fn log_len(&self) -> usize {
        self.log.lock().unwrap().len()
    }

    /// The last log line, or "" when there is none.
    pub fn last(&self) -> String {
        self.log().last().map(|l| l.1.clone()).unwrap_or_default()
    }

    pub fn vr(name: &str) -> u32 {
        VARIABLES
            .iter()
            .find(|v| v.name == name)
            .unwrap_or_else(|| panic!("no variable {name}"))
            .value_reference
    }

    pub fn set_real(&self, name: &str, v: f64) -> Fmi2Status {
        unsafe { fmi2SetReal(self.c, &Self::vr(name), 1, &v) }
    }

    pub fn set_integer(&self, name: &str, v: i32) -> Fmi2Status {
        unsafe { fmi2SetInteger(self.c, &Self::vr(name), 1, &v) }
    }

    pub fn set_boolean(&self, name: &str, v: bool) -> Fmi2Status {
        let v = Fmi2Boolean::from(v);
        unsafe { fmi2SetBoolean(self.c, &Self::vr(name), 1, &v) }
    }

    pub fn get_real(&self, name: &str) -> (Fmi2Status, f64) {
        let mut v = f64::NAN;
        let s = unsafe { fmi2GetReal(self.c, &Self::vr(name), 1, &mut v) };
        (s, v)
    }

    pub fn get_integer(&self, name: &str) -> (Fmi2Status, i32) {
        let mut v = 0;
        let s = unsafe { fmi2GetInteger(self.c, &Self::vr(name), 1, &mut v) };
        (s, v)
    }

    pub fn setup(&self, start: f64) -> Fmi2Status {
        unsafe { fmi2SetupExperiment(self.c, FMI2_FALSE, 0.0, start, FMI2_FALSE, 0.0) }
    }

    pub fn enter(&self) -> Fmi2Status {
        unsafe { fmi2EnterInitializationMode(self.c) }
    }

    pub fn exit(&self) -> Fmi2Status {
        unsafe { fmi2ExitInitializationMode(self.c) }
    }

    /// Setup at `start`, enter and exit initialisation mode; the status of the last.
    pub fn init(&self, start: f64) -> Fmi2Status {
        assert_eq!(self.setup(start), Fmi2Status::Ok);
        assert_eq!(self.enter(), Fmi2Status::Ok);
        self.exit()
    }

    pub fn step(&self, t: f64, h: f64) -> Fmi2Status {
        unsafe { fmi2DoStep(self.c, t, h, FMI2_TRUE) }
    }

    pub fn last_successful_time(&self) -> (Fmi2Status, f64) {
        let mut t = f64::NAN;
        let s = unsafe { fmi2GetRealStatus(self.c, FMI2_LAST_SUCCESSFUL_TIME, &mut t) };
        (s, t)
    }

    pub fn get_state(&self) -> (Fmi2Status, Fmi2FmuState) {
        let mut s: Fmi2FmuState = std::ptr::null_mut();
        let status = unsafe { fmi2GetFMUstate(self.c, &mut s) };
        (status, s)
    }

    pub fn set_state(&self, s: Fmi2FmuState) -> Fmi2Status {
        unsafe { fmi2SetFMUstate(self.c, s) }
    }

    pub fn free_state(&self, mut s: Fmi2FmuState) -> Fmi2Status {
        unsafe { fmi2FreeFMUstate(self.c, &mut s) }
    }

    pub fn serialize(&self, s: Fmi2FmuState) -> Vec<u8> {
        let mut size = 0usize;
        unsafe {
            assert_eq!(
                fmi2SerializedFMUstateSize(self.c, s, &mut size),
                Fmi2Status::Ok
            );
            let mut bytes = vec![0u8; size];
            assert_eq!(
                fmi2SerializeFMUstate(self.c, s, bytes.as_mut_ptr() as *mut Fmi2Byte, size),
                Fmi2Status::Ok
            );
            bytes
        }
    }

    pub fn deserialize(&self, bytes: &[u8]) -> (Fmi2Status, Fmi2FmuState) {
        let mut s: Fmi2FmuState = std::ptr::null_mut();
        let status = unsafe {
            fmi2DeSerializeFMUstate(
                self.c,
                bytes.as_ptr() as *const Fmi2Byte,
                bytes.len(),
                &mut s,
            )
        };
        (status, s)
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}

/// Takes FMU states from point `k` on, calling `advance(k)` to step one point further each time,
/// until a state's payload holds `key` (by the time point `limit`): the point reached, that state
/// and its payload.
pub fn until_state_holds(
    f: &Fmu,
    mut k: usize,
    key: &str,
    limit: usize,
    mut advance: impl FnMut(usize),
) -> (usize, Fmi2FmuState, serde_json::Value) {
    let quoted = format!("\"{key}\"");
    loop {
        let (s, saved) = f.get_state();
        assert_eq!(s, Fmi2Status::Ok);
        let p = payload(&f.serialize(saved));
        if p.to_string().contains(&quoted) {
            return (k, saved, p);
        }
        f.free_state(saved);
        assert!(
            k < limit,
            "no FMU state holds \"{key}\" at any point up to {limit}"
        );
        advance(k);
        k += 1;
    }
}
