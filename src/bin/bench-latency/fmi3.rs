//! The few FMI 3.0 Co-Simulation calls the latency benchmark makes, through the C ABI of the
//! library the FMI 2.0 loader has opened (one binary exports both versions' functions).

use std::ffi::{c_void, CString};
use std::os::raw::c_char;

use hydraulic_slewing_plate::fmi3::ffi::{
    Fmi3Instance, Fmi3IntermediateUpdateCallback, Fmi3LogMessageCallback, Fmi3Status,
};
use hydraulic_slewing_plate::fmu::Value;
use hydraulic_slewing_plate::model::variables::{GUID, VARIABLES};

use crate::loader::Fmu;

type Instantiate = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    u8,
    u8,
    u8,
    u8,
    *const u32,
    usize,
    *mut c_void,
    Fmi3LogMessageCallback,
    Fmi3IntermediateUpdateCallback,
) -> Fmi3Instance;
type EnterInit = unsafe extern "C" fn(Fmi3Instance, u8, f64, f64, u8, f64) -> Fmi3Status;
type Simple = unsafe extern "C" fn(Fmi3Instance) -> Fmi3Status;
type Set<T> = unsafe extern "C" fn(Fmi3Instance, *const u32, usize, *const T, usize) -> Fmi3Status;
type Get<T> = unsafe extern "C" fn(Fmi3Instance, *const u32, usize, *mut T, usize) -> Fmi3Status;
type DoStep = unsafe extern "C" fn(
    Fmi3Instance,
    f64,
    f64,
    u8,
    *mut bool,
    *mut bool,
    *mut bool,
    *mut f64,
) -> Fmi3Status;
type Free = unsafe extern "C" fn(Fmi3Instance);

/// Prints what the FMU logs (only errors reach here: logging is off).
unsafe extern "C" fn log(
    _env: *mut c_void,
    status: Fmi3Status,
    _category: *const c_char,
    message: *const c_char,
) {
    if !message.is_null() {
        // SAFETY: a non-null message of the log callback is NUL-terminated (FMI 3.0).
        let m = unsafe { std::ffi::CStr::from_ptr(message) }.to_string_lossy();
        eprintln!("[fmi3 {status:?}] {m}");
    }
}

fn check(status: Fmi3Status, what: &str) -> Result<(), String> {
    if status <= Fmi3Status::Warning {
        Ok(())
    } else {
        Err(format!("{what} returned {status:?}"))
    }
}

/// One FMI 3.0 Co-Simulation instance of the loaded library.
pub struct Instance {
    c: Fmi3Instance,
    enter_init: EnterInit,
    exit_init: Simple,
    set_f64: Set<f64>,
    set_i32: Set<i32>,
    set_i64: Set<i64>,
    set_bool: Set<u8>,
    get_f64: Get<f64>,
    do_step: DoStep,
    free: Free,
}

impl Instance {
    pub fn new(fmu: &Fmu) -> Result<Instance, String> {
        // SAFETY: the names are the FMI 3.0 functions with the types above.
        let (instantiate, inst) = unsafe {
            let instantiate: Instantiate = fmu.symbol("fmi3InstantiateCoSimulation")?;
            let inst = Instance {
                c: std::ptr::null_mut(),
                enter_init: fmu.symbol("fmi3EnterInitializationMode")?,
                exit_init: fmu.symbol("fmi3ExitInitializationMode")?,
                set_f64: fmu.symbol("fmi3SetFloat64")?,
                set_i32: fmu.symbol("fmi3SetInt32")?,
                set_i64: fmu.symbol("fmi3SetInt64")?,
                set_bool: fmu.symbol("fmi3SetBoolean")?,
                get_f64: fmu.symbol("fmi3GetFloat64")?,
                do_step: fmu.symbol("fmi3DoStep")?,
                free: fmu.symbol("fmi3FreeInstance")?,
            };
            (instantiate, inst)
        };
        let name = CString::new("bench-latency").map_err(|e| e.to_string())?;
        let token = CString::new(GUID).map_err(|e| e.to_string())?;
        // SAFETY: NUL-terminated strings and a callback that outlive the call; no required
        // intermediate variables.
        let c = unsafe {
            instantiate(
                name.as_ptr(),
                token.as_ptr(),
                std::ptr::null(),
                0,
                0,
                0,
                0,
                std::ptr::null(),
                0,
                std::ptr::null_mut(),
                Some(log),
                None,
            )
        };
        if c.is_null() {
            return Err("fmi3InstantiateCoSimulation returned NULL".into());
        }
        Ok(Instance { c, ..inst })
    }

    /// Sets a parameter or input by name from text, as `--set` does (the value is read by the
    /// model's own parser, then set through the FMI 3.0 function of its type).
    pub fn set_from_text(&self, name: &str, text: &str) -> Result<(), String> {
        let mut values = hydraulic_slewing_plate::fmu::Values::from_start(&VARIABLES);
        hydraulic_slewing_plate::model::parameters::set_by_name(&mut values, name, text)?;
        let index = VARIABLES.iter().position(|v| v.name == name).unwrap_or(0);
        let var = &VARIABLES[index];
        let vr = var.value_reference;
        let enumeration = matches!(
            var.kind,
            hydraulic_slewing_plate::fmu::Kind::Enumeration { .. }
        );
        // SAFETY: functions of the loaded library with its live instance and one value.
        let status = unsafe {
            match values.get(index) {
                Value::Real(v) => (self.set_f64)(self.c, &vr, 1, v, 1),
                Value::Integer(v) if enumeration => {
                    (self.set_i64)(self.c, &vr, 1, &i64::from(*v), 1)
                }
                Value::Integer(v) => (self.set_i32)(self.c, &vr, 1, v, 1),
                Value::Boolean(v) => (self.set_bool)(self.c, &vr, 1, &u8::from(*v), 1),
                Value::String(_) => return Err(format!("{name}: String variables are not set")),
            }
        };
        check(status, &format!("fmi3Set* of {name}"))
    }

    pub fn initialize(&self, tolerance: f64, stop: f64) -> Result<(), String> {
        // SAFETY: functions of the loaded library with its live instance.
        unsafe {
            check(
                (self.enter_init)(self.c, 1, tolerance, 0.0, 1, stop),
                "fmi3EnterInitializationMode",
            )?;
            check((self.exit_init)(self.c), "fmi3ExitInitializationMode")
        }
    }

    /// `fmi3SetFloat64` of one value; the status only (no allocation).
    #[inline]
    pub fn set_real(&self, vr: u32, v: f64) -> Fmi3Status {
        // SAFETY: a function of the loaded library with its live instance and one value.
        unsafe { (self.set_f64)(self.c, &vr, 1, &v, 1) }
    }

    /// `fmi3GetFloat64` of one value.
    #[inline]
    pub fn get_real(&self, vr: u32, v: &mut f64) -> Fmi3Status {
        // SAFETY: a function of the loaded library with its live instance and one value.
        unsafe { (self.get_f64)(self.c, &vr, 1, v, 1) }
    }

    /// `fmi3DoStep`.
    #[inline]
    pub fn do_step(&self, t: f64, h: f64) -> Fmi3Status {
        let (mut event, mut terminate, mut early, mut last) = (false, false, false, 0.0);
        // SAFETY: a function of the loaded library with its live instance and out-pointers to
        // locals.
        unsafe {
            (self.do_step)(
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
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: the live instance, freed once.
        unsafe { (self.free)(self.c) };
    }
}
