//! The generic FMI 2.0 layer on its own, over a tiny test model (dx/dt = -k x, with switches that
//! make it fail or panic): what the shipped model cannot provoke on purpose. A panic inside a
//! model call becomes fmi2Fatal with a log line and never unwinds into the caller; after it only
//! fmi2FreeInstance is allowed. A model failure becomes fmi2Discard with the time reached. The
//! generic entry points of `fmi2::entries` are called directly, as the exported symbols do.

use std::ffi::{c_char, c_void, CStr};
use std::sync::Mutex;

#[path = "common/decay.rs"]
mod decay;

use decay::Decay;
use hydraulic_slewing_plate::fmi2::entries as x;
use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::fmu::Value;

/// Log lines of all instances of this test binary: (status, message).
static LOG: Mutex<Vec<(Fmi2Status, String)>> = Mutex::new(Vec::new());

unsafe extern "C" fn logger(
    _env: *mut c_void,
    _name: *const c_char,
    status: Fmi2Status,
    _category: *const c_char,
    message: *const c_char,
) {
    let m = CStr::from_ptr(message).to_string_lossy().replace("%%", "%");
    LOG.lock().unwrap().push((status, m));
}

fn logged(needle: &str) -> bool {
    LOG.lock().unwrap().iter().any(|(_, m)| m.contains(needle))
}

fn instantiate(name: &std::ffi::CStr) -> Fmi2Component {
    let callbacks = Fmi2CallbackFunctions::with_plain_logger(logger, std::ptr::null_mut());
    let c = unsafe {
        x::instantiate::<Decay>(
            name.as_ptr(),
            FMI2_CO_SIMULATION,
            c"{decay}".as_ptr(),
            std::ptr::null(),
            &callbacks,
            0,
            0,
        )
    };
    assert!(!c.is_null());
    c
}

fn start(c: Fmi2Component, mode: i32) {
    unsafe {
        assert_eq!(
            x::set_values::<Decay, i32>(c, "fmi2SetInteger", "Integer", &2, 1, &mode, |v| Some(
                Value::Integer(v)
            )),
            Fmi2Status::Ok
        );
        assert_eq!(
            x::setup_experiment::<Decay>(c, 0, 0.0, 0.0, 0, 0.0),
            Fmi2Status::Ok
        );
        assert_eq!(
            x::simple_call::<Decay>(c, "fmi2EnterInitializationMode", |i| i
                .enter_initialization_mode()),
            Fmi2Status::Ok
        );
        assert_eq!(
            x::simple_call::<Decay>(c, "fmi2ExitInitializationMode", |i| i
                .exit_initialization_mode()),
            Fmi2Status::Ok
        );
    }
}

fn get_x(c: Fmi2Component) -> (Fmi2Status, f64) {
    let mut v = f64::NAN;
    let s = unsafe {
        x::get_values::<Decay, f64>(c, "fmi2GetReal", "Real", &3, 1, &mut v, |v| match v {
            Value::Real(r) => *r,
            _ => f64::NAN,
        })
    };
    (s, v)
}

#[test]
fn normal_steps_follow_the_exact_solution() {
    let c = instantiate(c"normal");
    start(c, 0);
    for i in 0..10 {
        assert_eq!(
            unsafe { x::do_step::<Decay>(c, i as f64 * 0.1, 0.1, 1) },
            Fmi2Status::Ok
        );
    }
    let (s, v) = get_x(c);
    assert_eq!(s, Fmi2Status::Ok);
    assert!((v - (-2.0f64).exp()).abs() < 1e-14, "{v}");
    unsafe { x::free_instance::<Decay>(c) };
}

#[test]
fn a_panic_becomes_fatal_and_stays_inside() {
    let c = instantiate(c"panics");
    start(c, 2);
    let status = unsafe { x::do_step::<Decay>(c, 0.0, 0.1, 1) };
    assert_eq!(status, Fmi2Status::Fatal);
    // The message and its place go to the FMU's logger.
    assert!(logged(
        "fmi2DoStep: internal error: deliberate panic in do_step (at tests/common/decay.rs:"
    ));
    // After fmi2Fatal nothing but fmi2FreeInstance: every call is refused.
    assert_eq!(get_x(c).0, Fmi2Status::Error);
    assert_eq!(
        unsafe { x::simple_call::<Decay>(c, "fmi2Reset", |i| i.reset()) },
        Fmi2Status::Error
    );
    assert_eq!(
        unsafe { x::do_step::<Decay>(c, 0.0, 0.1, 1) },
        Fmi2Status::Error
    );
    unsafe { x::free_instance::<Decay>(c) };
}

#[test]
fn a_failed_step_is_a_discard_at_the_time_reached() {
    let c = instantiate(c"fails");
    start(c, 1);
    assert_eq!(
        unsafe { x::do_step::<Decay>(c, 0.0, 0.2, 1) },
        Fmi2Status::Discard
    );
    assert!(logged("discarded at t = 0.1: deliberate failure"));
    let mut t = 0.0;
    assert_eq!(
        unsafe { x::get_real_status::<Decay>(c, FMI2_LAST_SUCCESSFUL_TIME, &mut t) },
        Fmi2Status::Ok
    );
    assert_eq!(t, 0.1);
    // The outputs are those of the last good state, and stepping on is refused.
    let (s, v) = get_x(c);
    assert_eq!(s, Fmi2Status::Ok);
    assert!((v - (-0.2f64).exp()).abs() < 1e-14);
    assert_eq!(
        unsafe { x::do_step::<Decay>(c, 0.1, 0.1, 1) },
        Fmi2Status::Error
    );
    assert!(logged("illegal call sequence"));
    unsafe { x::free_instance::<Decay>(c) };
}

#[test]
fn state_machine_refuses_out_of_order_calls() {
    let c = instantiate(c"order");
    unsafe {
        // Getting before initialisation mode, setting up after entering it.
        assert_eq!(get_x(c).0, Fmi2Status::Error);
        assert_eq!(
            x::simple_call::<Decay>(c, "fmi2Reset", |i| i.reset()),
            Fmi2Status::Ok
        );
        assert_eq!(
            x::simple_call::<Decay>(c, "fmi2EnterInitializationMode", |i| i
                .enter_initialization_mode()),
            Fmi2Status::Ok
        );
        assert_eq!(
            x::setup_experiment::<Decay>(c, 0, 0.0, 0.0, 0, 0.0),
            Fmi2Status::Error
        );
        assert_eq!(
            x::simple_call::<Decay>(c, "fmi2Reset", |i| i.reset()),
            Fmi2Status::Ok
        );
        // Terminate before initialisation.
        assert_eq!(
            x::simple_call::<Decay>(c, "fmi2Terminate", |i| i.terminate()),
            Fmi2Status::Error
        );
        x::free_instance::<Decay>(c);
    }
}

#[test]
fn null_and_foreign_pointers_are_refused() {
    unsafe {
        assert_eq!(
            x::do_step::<Decay>(std::ptr::null_mut(), 0.0, 0.1, 1),
            Fmi2Status::Error
        );
        // A pointer that is not an instance of this library (the magic check), not dereferenced
        // beyond the instance's size.
        let mut junk = vec![0u8; 4096];
        let p = junk.as_mut_ptr() as Fmi2Component;
        assert_eq!(x::do_step::<Decay>(p, 0.0, 0.1, 1), Fmi2Status::Error);
        x::free_instance::<Decay>(p);
        // Instantiation without callbacks gives NULL.
        let c = x::instantiate::<Decay>(
            c"a".as_ptr(),
            FMI2_CO_SIMULATION,
            c"{decay}".as_ptr(),
            std::ptr::null(),
            std::ptr::null(),
            0,
            0,
        );
        assert!(c.is_null());
    }
}

/// The panic of `a_panic_becomes_fatal_and_stays_inside`, run in a child process of this test
/// binary so that its stderr can be read: the panic hook keeps "panicked at" off the host's stderr.
#[test]
fn a_panic_prints_nothing_to_stderr() {
    decay::passes_with_nothing_on_stderr(
        "a_panic_becomes_fatal_and_stays_inside",
        "FMI2_LAYER_CHILD",
    );
}
