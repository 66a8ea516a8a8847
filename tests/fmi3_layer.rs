//! The generic FMI 3.0 layer on its own, over the tiny test model of `common/decay.rs` (dx/dt =
//! -k x, with a switch that makes it fail or panic): the twin of `fmi2_layer.rs`. A panic inside
//! a model call becomes fmi3Fatal with a log line naming the fmi3 function and never unwinds into
//! the caller, nor prints to stderr; after it only fmi3FreeInstance is allowed. A model failure
//! becomes fmi3Discard with the time reached in `lastSuccessfulTime`. The generic entry points of
//! `fmi3::entries` are called directly, as the exported symbols do.

use std::ffi::{c_char, c_void, CStr};
use std::sync::{Mutex, OnceLock};

#[path = "common/decay.rs"]
mod decay;
#[path = "common/driver.rs"]
mod driver;

use decay::{Decay, VARS};
use driver::fmi3_do_step;
use hydraulic_slewing_plate::fmi3::entries as x;
use hydraulic_slewing_plate::fmi3::ffi::*;
use hydraulic_slewing_plate::fmi3::variables::Fmi3Table;
use hydraulic_slewing_plate::fmu::Value;

/// One log line: status, category, message.
type Line = (Fmi3Status, String, String);

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

/// The model's FMI 3.0 variables (all scalars: no arrays, no Model Exchange states).
fn table() -> &'static Fmi3Table {
    static TABLE: OnceLock<Fmi3Table> = OnceLock::new();
    TABLE.get_or_init(|| Fmi3Table::new(&VARS, &[]))
}

/// A co-simulation instance of the model with a log of its own; freed on drop (the only call
/// allowed after fmi3Fatal).
struct Inst {
    c: Fmi3Instance,
    log: Box<Mutex<Vec<Line>>>,
}

impl Inst {
    fn new(name: &CStr) -> Inst {
        let log = Box::new(Mutex::new(Vec::new()));
        let env = &*log as *const Mutex<Vec<Line>> as *mut c_void;
        let c = unsafe {
            x::instantiate_co_simulation::<Decay>(
                name.as_ptr(),
                c"{decay}".as_ptr(),
                std::ptr::null(),
                false,
                false,
                env,
                Some(log_message),
            )
        };
        assert!(!c.is_null());
        Inst { c, log }
    }

    fn log(&self) -> Vec<Line> {
        self.log.lock().unwrap().clone()
    }

    /// The last log message, or "" when there is none.
    fn last(&self) -> String {
        self.log().pop().map(|l| l.2).unwrap_or_default()
    }

    /// Sets `mode`, enters and exits initialisation mode with the experiment starting at 0.
    fn start(&self, mode: i32) {
        let c = self.c;
        unsafe {
            assert_eq!(
                x::set_values::<Decay, i32>(
                    table(),
                    c,
                    "fmi3SetInt32",
                    "Int32",
                    &2,
                    1,
                    &mode,
                    1,
                    Value::Integer
                ),
                Fmi3Status::Ok
            );
            assert_eq!(
                x::enter_initialization_mode::<Decay>(c, false, 0.0, 0.0, false, 0.0),
                Fmi3Status::Ok
            );
            assert_eq!(
                x::simple_call::<Decay>(c, "fmi3ExitInitializationMode", |i| i
                    .exit_initialization_mode()),
                Fmi3Status::Ok
            );
        }
    }

    fn get_x(&self) -> (Fmi3Status, f64) {
        let mut v = f64::NAN;
        let s = unsafe {
            x::get_values::<Decay, f64>(
                table(),
                self.c,
                "fmi3GetFloat64",
                "Float64",
                &3,
                1,
                &mut v,
                1,
                |v| match v {
                    Value::Real(r) => *r,
                    _ => f64::NAN,
                },
            )
        };
        (s, v)
    }

    fn reset(&self) -> Fmi3Status {
        unsafe { x::simple_call::<Decay>(self.c, "fmi3Reset", |i| i.reset()) }
    }

    /// `fmi3DoStep`: its status and `lastSuccessfulTime`.
    fn step(&self, t: f64, h: f64) -> (Fmi3Status, f64) {
        step(self.c, t, h)
    }
}

impl Drop for Inst {
    fn drop(&mut self) {
        unsafe { x::free_instance::<Decay>(self.c) };
    }
}

/// `fmi3DoStep` on any pointer: its status and `lastSuccessfulTime` (see [`fmi3_do_step`]).
fn step(c: Fmi3Instance, t: f64, h: f64) -> (Fmi3Status, f64) {
    fmi3_do_step(|event, terminate, early, last| unsafe {
        x::do_step::<Decay>(c, t, h, true, event, terminate, early, last)
    })
}

#[test]
fn normal_steps_follow_the_exact_solution() {
    let f = Inst::new(c"normal");
    f.start(0);
    for i in 0..10 {
        let t = i as f64 * 0.1;
        assert_eq!(f.step(t, 0.1), (Fmi3Status::Ok, t + 0.1), "{}", f.last());
    }
    let (s, v) = f.get_x();
    assert_eq!(s, Fmi3Status::Ok);
    assert!((v - (-2.0f64).exp()).abs() < 1e-14, "{v}");
}

#[test]
fn a_panic_becomes_fatal_and_stays_inside() {
    let f = Inst::new(c"panics");
    f.start(2);
    assert_eq!(f.step(0.0, 0.1).0, Fmi3Status::Fatal);
    // The message and its place go to the FMU's logger, as a fatal line naming the function.
    let (status, category, message) = f.log().pop().expect("a log line");
    assert_eq!(status, Fmi3Status::Fatal);
    assert_eq!(category, "logStatusFatal");
    assert!(
        message.starts_with(
            "fmi3DoStep: internal error: deliberate panic in do_step (at tests/common/decay.rs:"
        ),
        "{message}"
    );
    // After fmi3Fatal nothing but fmi3FreeInstance: every call is refused with a line saying so.
    let refused = |function: &str| {
        let (status, _, message) = f.log().pop().expect("a log line");
        assert_eq!(status, Fmi3Status::Error, "{message}");
        assert_eq!(
            message,
            format!(
                "{function}: illegal call sequence: after fmi3Fatal only fmi3FreeInstance is allowed"
            )
        );
    };
    assert_eq!(f.get_x().0, Fmi3Status::Error);
    refused("fmi3GetFloat64");
    assert_eq!(f.reset(), Fmi3Status::Error);
    refused("fmi3Reset");
    assert_eq!(f.step(0.0, 0.1).0, Fmi3Status::Error);
    refused("fmi3DoStep");
    // Dropping `f` frees the instance: allowed.
}

#[test]
fn a_failed_step_is_a_discard_at_the_time_reached() {
    let f = Inst::new(c"fails");
    f.start(1);
    let (s, last_successful_time) = f.step(0.0, 0.2);
    assert_eq!(s, Fmi3Status::Discard);
    assert_eq!(last_successful_time, 0.1);
    assert!(
        f.last()
            .contains("discarded at t = 0.1: deliberate failure"),
        "{}",
        f.last()
    );
    assert!(!f.last().contains("fmi2"), "{}", f.last());
    // The outputs are those of the last good state, and stepping on is refused.
    let (s, v) = f.get_x();
    assert_eq!(s, Fmi3Status::Ok);
    assert!((v - (-0.2f64).exp()).abs() < 1e-14);
    assert_eq!(f.step(0.1, 0.1).0, Fmi3Status::Error);
    assert!(f.last().starts_with("fmi3DoStep"), "{}", f.last());
    assert!(f.last().contains("illegal call sequence"), "{}", f.last());
}

#[test]
fn state_machine_refuses_out_of_order_calls() {
    let f = Inst::new(c"order");
    unsafe {
        // Getting before initialisation mode.
        assert_eq!(f.get_x().0, Fmi3Status::Error);
        assert!(f.last().starts_with("fmi3GetFloat64"), "{}", f.last());
        assert_eq!(f.reset(), Fmi3Status::Ok);
        // Entering initialisation mode twice.
        let enter = || x::enter_initialization_mode::<Decay>(f.c, false, 0.0, 0.0, false, 0.0);
        assert_eq!(enter(), Fmi3Status::Ok);
        assert_eq!(enter(), Fmi3Status::Error);
        assert!(
            f.last().starts_with("fmi3EnterInitializationMode"),
            "{}",
            f.last()
        );
        assert_eq!(f.reset(), Fmi3Status::Ok);
        // Terminate before initialisation.
        assert_eq!(
            x::simple_call::<Decay>(f.c, "fmi3Terminate", |i| i.terminate()),
            Fmi3Status::Error
        );
        assert!(f.last().starts_with("fmi3Terminate"), "{}", f.last());
    }
}

#[test]
fn null_and_foreign_pointers_are_refused() {
    assert_eq!(step(std::ptr::null_mut(), 0.0, 0.1).0, Fmi3Status::Error);
    // A pointer that is not an instance of this library (the magic check), not dereferenced
    // beyond the instance's size.
    let mut junk = vec![0u8; 4096];
    let p = junk.as_mut_ptr() as Fmi3Instance;
    assert_eq!(step(p, 0.0, 0.1).0, Fmi3Status::Error);
    unsafe { x::free_instance::<Decay>(p) };
    // A wrong instantiation token gives NULL, with a log line saying why.
    let log: Box<Mutex<Vec<Line>>> = Box::new(Mutex::new(Vec::new()));
    let env = &*log as *const Mutex<Vec<Line>> as *mut c_void;
    let c = unsafe {
        x::instantiate_co_simulation::<Decay>(
            c"a".as_ptr(),
            c"{not decay}".as_ptr(),
            std::ptr::null(),
            false,
            false,
            env,
            Some(log_message),
        )
    };
    assert!(c.is_null());
    let lines = log.lock().unwrap().clone();
    let (status, _, message) = lines.last().cloned().expect("a log line");
    assert_eq!(status, Fmi3Status::Error);
    assert!(
        message.starts_with("fmi3InstantiateCoSimulation"),
        "{message}"
    );
}

/// The panic of `a_panic_becomes_fatal_and_stays_inside` and the calls refused after it, run in
/// a child process of this test binary so that its stderr can be read: nothing reaches it.
#[test]
fn a_panic_prints_nothing_to_stderr() {
    decay::passes_with_nothing_on_stderr(
        "a_panic_becomes_fatal_and_stays_inside",
        "FMI3_LAYER_CHILD",
    );
}
