//! A thin driver over the library's exported `fmi3*` entry points (co-simulation), called
//! in-process exactly as an importer that has loaded the library would, with a log of its own per
//! instance: the FMI 3.0 twin of `fmu.rs`.

#![allow(dead_code)]

use std::cell::Cell;
use std::ffi::{c_void, CStr, CString};
use std::os::raw::c_char;
use std::sync::Mutex;

use hydraulic_slewing_plate::fmi3::ffi::*;
use hydraulic_slewing_plate::fmi3_exports::*;
use hydraulic_slewing_plate::model::variables::{GUID, VARIABLES};

/// One log line: status, category and message.
pub type Line = (Fmi3Status, String, String);

unsafe extern "C" fn log_message(
    env: *mut c_void,
    status: Fmi3Status,
    category: *const c_char,
    message: *const c_char,
) {
    let log = &*(env as *const Mutex<Vec<Line>>);
    let c = CStr::from_ptr(category).to_string_lossy().into_owned();
    let m = CStr::from_ptr(message).to_string_lossy().into_owned();
    log.lock().unwrap().push((status, c, m));
}

/// An FMI 3.0 co-simulation instance with its log; freed on drop.
pub struct Fmu3 {
    pub c: Fmi3Instance,
    log: Box<Mutex<Vec<Line>>>,
    last_successful_time: Cell<f64>,
}

impl Fmu3 {
    pub fn new() -> Fmu3 {
        Self::try_new(false).expect("fmi3InstantiateCoSimulation returned NULL")
    }

    /// The instance, or the log when instantiation returned NULL.
    pub fn try_new(event_mode_used: bool) -> Result<Fmu3, Vec<Line>> {
        Self::try_new_bytes(0, u8::from(event_mode_used))
    }

    /// As [`Fmu3::try_new`], with `loggingOn` and `eventModeUsed` passed as the bytes given
    /// (C's `bool` arguments: an importer may pass any byte).
    pub fn try_new_bytes(logging_on: u8, event_mode_used: u8) -> Result<Fmu3, Vec<Line>> {
        let log = Box::new(Mutex::new(Vec::new()));
        let env = &*log as *const Mutex<Vec<Line>> as *mut c_void;
        let token = CString::new(GUID).unwrap();
        let c = unsafe {
            fmi3InstantiateCoSimulation(
                c"contract3".as_ptr(),
                token.as_ptr(),
                std::ptr::null(),
                0,
                logging_on,
                event_mode_used,
                0,
                std::ptr::null(),
                0,
                env,
                Some(log_message),
                None,
            )
        };
        if c.is_null() {
            return Err(log.lock().unwrap().clone());
        }
        Ok(Fmu3 {
            c,
            log,
            last_successful_time: Cell::new(f64::NAN),
        })
    }

    pub fn log(&self) -> Vec<Line> {
        self.log.lock().unwrap().clone()
    }

    pub fn log_len(&self) -> usize {
        self.log.lock().unwrap().len()
    }

    /// The last log message, or "" when there is none.
    pub fn last(&self) -> String {
        self.log().last().map(|l| l.2.clone()).unwrap_or_default()
    }

    /// The FMI 3.0 value reference of a scalar (for an array element: its array's, see vr_of).
    pub fn vr(name: &str) -> u32 {
        VARIABLES
            .iter()
            .find(|v| v.name == name)
            .unwrap_or_else(|| panic!("no variable {name}"))
            .value_reference
    }

    pub fn set_real(&self, name: &str, v: f64) -> Fmi3Status {
        unsafe { fmi3SetFloat64(self.c, &Self::vr(name), 1, &v, 1) }
    }

    pub fn set_integer(&self, name: &str, v: i32) -> Fmi3Status {
        unsafe { fmi3SetInt32(self.c, &Self::vr(name), 1, &v, 1) }
    }

    pub fn set_boolean(&self, name: &str, v: bool) -> Fmi3Status {
        let v = u8::from(v);
        unsafe { fmi3SetBoolean(self.c, &Self::vr(name), 1, &v, 1) }
    }

    pub fn get_real(&self, name: &str) -> (Fmi3Status, f64) {
        let mut v = f64::NAN;
        let s = unsafe { fmi3GetFloat64(self.c, &Self::vr(name), 1, &mut v, 1) };
        (s, v)
    }

    /// `fmi3EnterInitializationMode` with the experiment starting at `start`.
    pub fn enter(&self, start: f64) -> Fmi3Status {
        unsafe { fmi3EnterInitializationMode(self.c, 0, 0.0, start, 0, 0.0) }
    }

    pub fn exit(&self) -> Fmi3Status {
        unsafe { fmi3ExitInitializationMode(self.c) }
    }

    /// Enter and exit initialisation mode; the status of the last.
    pub fn init(&self, start: f64) -> Fmi3Status {
        assert_eq!(self.enter(start), Fmi3Status::Ok);
        self.exit()
    }

    pub fn step(&self, t: f64, h: f64) -> Fmi3Status {
        let (mut event, mut terminate, mut early, mut last) = (true, true, true, f64::NAN);
        let s = unsafe {
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
        };
        if matches!(s, Fmi3Status::Ok | Fmi3Status::Discard) {
            assert!(!event && !terminate && !early);
            self.last_successful_time.set(last);
        }
        s
    }

    /// lastSuccessfulTime of the last step that returned OK or Discard.
    pub fn last_successful_time(&self) -> f64 {
        self.last_successful_time.get()
    }

    pub fn get_state(&self) -> (Fmi3Status, Fmi3FmuState) {
        let mut s: Fmi3FmuState = std::ptr::null_mut();
        let status = unsafe { fmi3GetFMUState(self.c, &mut s) };
        (status, s)
    }

    pub fn set_state(&self, s: Fmi3FmuState) -> Fmi3Status {
        unsafe { fmi3SetFMUState(self.c, s) }
    }

    pub fn free_state(&self, mut s: Fmi3FmuState) -> Fmi3Status {
        unsafe { fmi3FreeFMUState(self.c, &mut s) }
    }

    pub fn serialize(&self, s: Fmi3FmuState) -> Vec<u8> {
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

    pub fn deserialize(&self, bytes: &[u8]) -> (Fmi3Status, Fmi3FmuState) {
        let mut s: Fmi3FmuState = std::ptr::null_mut();
        let status =
            unsafe { fmi3DeserializeFMUState(self.c, bytes.as_ptr(), bytes.len(), &mut s) };
        (status, s)
    }
}

impl Drop for Fmu3 {
    fn drop(&mut self) {
        unsafe { fmi3FreeInstance(self.c) };
    }
}
