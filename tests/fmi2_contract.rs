//! The FMI contract defects an outside test campaign found (issue 11, D1-D7 and the FMU-state
//! pointer), each as a regression test through the exported C functions: a bad parameter, a
//! non-finite output, a step that cannot advance time or a hostile FMU state gets fmi2Error or
//! fmi2Discard with a log line naming the culprit, never fmi2OK and never fmi2Fatal.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::{blob, payload, Fmu};
use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::fmi2_exports::*;

/// A message is short: numbers printed short (1e-300 in 6 characters, not 302).
fn assert_short(message: &str) {
    assert!(
        message.len() < 400,
        "{} characters: {message}",
        message.len()
    );
    let longest_number = message
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(longest_number <= 24, "{message}");
}

/// Initialisation with one parameter set fails with fmi2Error naming `name`.
fn init_rejects(name: &str, value: f64, expect_in_message: &str) {
    let f = Fmu::new();
    let set = f.set_real(name, value);
    let status = if set == Fmi2Status::Ok {
        assert_eq!(f.setup(0.0), Fmi2Status::Ok);
        assert_eq!(f.enter(), Fmi2Status::Ok);
        f.exit()
    } else {
        set
    };
    assert_eq!(status, Fmi2Status::Error, "{name} = {value}");
    let last = f.last();
    assert!(
        last.contains(name) && last.contains(expect_in_message),
        "{name} = {value}: {last}"
    );
    assert_short(&last);
}

#[test]
fn d1_absurd_plate_density_is_rejected_by_name_without_a_panic() {
    for rho in [1e-300, 5e-324] {
        init_rejects("plate.rho", rho, "physically absurd");
    }
}

#[test]
fn d1_derived_plate_quantities_are_checked() {
    // Each value lies within the window for the parameter itself; the derived quantity does not.
    init_rejects("plate.rho", 1e-49, "the plate's mass");
    init_rejects("plate.E", 1e-49, "flexural rigidity");
}

#[test]
fn d2_a_state_taken_before_initialisation_restores_as_such() {
    let f = Fmu::new();
    let (s, early) = f.get_state();
    assert_eq!(s, Fmi2Status::Ok);
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    assert_eq!(f.step(0.0, 1e-3), Fmi2Status::Ok);
    assert_eq!(f.set_state(early), Fmi2Status::Ok);
    // Back in the instantiated state: stepping is an illegal call, not a discarded step, and
    // there is no last successful time to report.
    assert_eq!(f.step(0.0, 1e-3), Fmi2Status::Error);
    assert!(f.last().contains("illegal call sequence"), "{}", f.last());
    assert_eq!(f.last_successful_time().0, Fmi2Status::Error);
    assert_eq!(f.free_state(early), Fmi2Status::Ok);
}

#[test]
fn d2_a_state_taken_in_the_error_state_is_refused() {
    let f = Fmu::new();
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    assert_eq!(f.step(0.0, 1e-3), Fmi2Status::Ok);
    let (_, good) = f.get_state();
    assert_eq!(f.step(5.0, 1e-3), Fmi2Status::Error); // wrong communication point
    let (s, bad) = f.get_state();
    assert_eq!(s, Fmi2Status::Ok);
    assert_eq!(f.set_state(good), Fmi2Status::Ok);
    assert_eq!(f.set_state(bad), Fmi2Status::Error);
    assert!(f.last().contains("taken in state 'error'"), "{}", f.last());
    // The good state still restores and continues.
    assert_eq!(f.set_state(good), Fmi2Status::Ok);
    assert_eq!(f.step(1e-3, 1e-3), Fmi2Status::Ok);
    f.free_state(good);
    f.free_state(bad);
}

#[test]
fn d3_a_tiny_step_does_not_spoil_the_next() {
    let f = Fmu::new();
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    // The shortest step the FMU takes, its solver's minimum step (a shorter one is refused up
    // front, issue 24 N4: see contract_both_versions.rs).
    assert_eq!(f.step(0.0, 1e-14), Fmi2Status::Ok);
    assert_eq!(f.step(1e-14, 1e-3), Fmi2Status::Ok, "{}", f.last());
    assert_eq!(f.last_successful_time(), (Fmi2Status::Ok, 1e-14 + 1e-3));
}

/// With one input or parameter set, the FMU never returns fmi2OK with a non-finite output: the
/// step is refused (Error) or discarded at its start (Discard), with a log line naming `name`.
fn never_ok_with_non_finite(name: &str, value: f64, hydraulics: i32) {
    let f = Fmu::new();
    assert_eq!(
        f.set_integer("hydraulics.model", hydraulics),
        Fmi2Status::Ok
    );
    // Without the amplifier's output limit, which would clip a huge r to its 12 V (with it the
    // outputs stay finite and fmi2OK is right: see the test below).
    assert_eq!(
        f.set_boolean("controller.saturation", false),
        Fmi2Status::Ok
    );
    assert_eq!(f.set_real(name, value), Fmi2Status::Ok);
    assert_eq!(f.setup(0.0), Fmi2Status::Ok);
    assert_eq!(f.enter(), Fmi2Status::Ok);
    let mut status = f.exit();
    let mut t = 0.0;
    while status == Fmi2Status::Ok && t < 0.05 {
        for out in ["energy", "y_pot", "w_tip", "theta_hub"] {
            assert!(f.get_real(out).1.is_finite(), "{name} = {value}: {out}");
        }
        status = f.step(t, 1e-3);
        t += 1e-3;
    }
    assert!(
        matches!(status, Fmi2Status::Error | Fmi2Status::Discard),
        "{name} = {value}: {status:?}"
    );
    let last = f.last();
    assert!(last.contains(name), "{name} = {value}: {last}");
    assert_short(&last);
    if status == Fmi2Status::Discard {
        // The last good state is kept: its outputs are finite, at the last successful time.
        let (s, t_ok) = f.last_successful_time();
        assert_eq!(s, Fmi2Status::Ok);
        assert!(t_ok < t, "{t_ok} {t}");
        assert!(f.get_real("energy").1.is_finite());
    }
}

#[test]
fn d4_huge_inputs_give_no_ok_with_infinite_outputs() {
    never_ok_with_non_finite("F1", 1e300, 1);
    never_ok_with_non_finite("r", 1e300, 1);
}

#[test]
fn d4_with_the_amplifier_limit_a_huge_r_drives_at_the_limit_with_finite_outputs() {
    // The defaults (the complete system) limit the power amplifier: r = 1e300 asks for an
    // infinite drive and gets e_max, so the steps are fmi2OK and every output stays finite.
    let f = Fmu::new();
    assert_eq!(f.set_real("r", 1e300), Fmi2Status::Ok);
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    for k in 0..20 {
        assert_eq!(
            f.step(k as f64 * 1e-3, 1e-3),
            Fmi2Status::Ok,
            "{}",
            f.last()
        );
        for out in ["energy", "y_pot", "w_tip", "theta_hub", "controller.e_out"] {
            assert!(f.get_real(out).1.is_finite(), "{out}");
        }
    }
    let (_, e_max) = f.get_real("controller.e_max");
    assert!((f.get_real("controller.e_out").1 - e_max).abs() <= 1e-12 * e_max);
}

#[test]
fn d4_absurd_hydraulic_parameters_are_rejected() {
    for (name, value) in [
        ("servo_valve.beta", 1e-300),
        ("servo_valve.V_H", 1e300),
        ("servo_valve.V_1", 1e300),
    ] {
        // Whichever hydraulic model is chosen: a parameter is checked whether it is used or not.
        never_ok_with_non_finite(name, value, 1);
        never_ok_with_non_finite(name, value, 2);
    }
}

#[test]
fn d5_edited_states_are_validated_not_trusted() {
    let f = Fmu::new();
    assert_eq!(f.set_integer("hydraulics.model", 1), Fmi2Status::Ok);
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    for k in 0..50 {
        assert_eq!(f.step(k as f64 * 1e-3, 1e-3), Fmi2Status::Ok);
    }
    let (_, s) = f.get_state();
    let good = payload(&f.serialize(s));
    f.free_state(s);
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit, &str); 8] = [
        (
            "atol one short",
            |p| {
                p["model"]["integrator"]["options"]["atol"]["Vector"]
                    .as_array_mut()
                    .unwrap()
                    .pop();
            },
            "solver options differ",
        ),
        (
            "a Real stored as an Integer",
            |p| p["values"]["values"][0] = serde_json::json!({"Integer": 3}),
            "r is a Real, not a Integer",
        ),
        (
            "rtol = 0",
            |p| p["model"]["integrator"]["options"]["rtol"] = 0.0.into(),
            "solver options differ",
        ),
        (
            "initial_step = -1",
            |p| p["model"]["integrator"]["options"]["initial_step"] = (-1.0).into(),
            "solver options differ",
        ),
        (
            "max_steps = u64::MAX with min_step = 0",
            |p| {
                let o = &mut p["model"]["integrator"]["options"];
                o["max_steps"] = u64::MAX.into();
                o["min_step"] = 0.0.into();
            },
            "solver options differ",
        ),
        (
            "a saved Fatal state",
            |p| p["state"] = "Fatal".into(),
            "taken in state 'fatal'",
        ),
        (
            "integrator time -5 against FMU time 0.05",
            |p| p["model"]["integrator"]["t"] = (-5.0).into(),
            "its integrator is at t = -5, the FMU at t = 0.05",
        ),
        (
            "a negative step size",
            |p| p["model"]["integrator"]["h"] = (-1e-3).into(),
            "h = -0.001",
        ),
    ];
    for (what, edit, expected) in edits {
        let mut p = good.clone();
        edit(&mut p);
        let (s, state) = f.deserialize(&blob(&p));
        assert_eq!(s, Fmi2Status::Ok, "{what}: the checksum was recomputed");
        assert_eq!(f.set_state(state), Fmi2Status::Error, "{what}");
        assert!(f.last().contains(expected), "{what}: {}", f.last());
        // Nothing to step on: an illegal call, never fmi2Fatal.
        assert_eq!(f.step(0.05, 1e-3), Fmi2Status::Error, "{what}");
        f.free_state(state);
    }
    // The unedited state restores and continues.
    let (_, state) = f.deserialize(&blob(&good));
    assert_eq!(f.set_state(state), Fmi2Status::Ok);
    assert_eq!(f.step(0.05, 1e-3), Fmi2Status::Ok);
    f.free_state(state);
}

#[test]
fn d6_a_step_that_cannot_advance_time_is_an_error() {
    let f = Fmu::new();
    assert_eq!(f.init(1e15), Fmi2Status::Ok);
    assert_eq!(f.step(1e15, 1e-3), Fmi2Status::Error);
    let last = f.last();
    assert!(last.contains("cannot advance the time 1e15"), "{last}");
}

#[test]
fn d7_errors_name_the_parameter_and_print_numbers_short() {
    init_rejects("servo_valve.p_supply", 1e300, "physically absurd");
    init_rejects("plate.a", 1e300, "physically absurd");
    // Inside the window but still absurd: named through the derived quantity.
    init_rejects("servo_valve.p_supply", 1e40, "hydraulic energy");
    init_rejects("plate.a", 1e40, "the hub's total inertia");
}

#[test]
fn fmu_state_pointers_are_checked() {
    let f = Fmu::new();
    let other = Fmu::new();
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    let mut junk = vec![0u8; 4096];
    let junk = junk.as_mut_ptr() as Fmi2FmuState;
    // An instance pointer and a junk buffer are not FMU states.
    for bad in [other.c, junk] {
        assert_eq!(f.set_state(bad), Fmi2Status::Error);
        assert!(f.last().contains("not an FMU state"), "{}", f.last());
        assert_eq!(f.free_state(bad), Fmi2Status::Error);
        let mut size = 0usize;
        assert_eq!(
            unsafe { fmi2SerializedFMUstateSize(f.c, bad, &mut size) },
            Fmi2Status::Error
        );
        let mut buf = [0 as Fmi2Byte; 16];
        assert_eq!(
            unsafe { fmi2SerializeFMUstate(f.c, bad, buf.as_mut_ptr(), 16) },
            Fmi2Status::Error
        );
        assert!(f.last().contains("'FMUstate'"), "{}", f.last());
        // Back to a usable instance.
        assert_eq!(unsafe { fmi2Reset(f.c) }, Fmi2Status::Ok);
        assert_eq!(f.init(0.0), Fmi2Status::Ok);
    }
    // A state freed once is not freed twice (its memory is gone; the pointer is kept in a copy
    // only to show that fmi2FreeFMUstate sets the caller's pointer to NULL).
    let (_, mut s) = f.get_state();
    assert_eq!(unsafe { fmi2FreeFMUstate(f.c, &mut s) }, Fmi2Status::Ok);
    assert!(s.is_null());
}

#[test]
fn calls_in_the_error_state_are_refused_with_a_log_line() {
    let f = Fmu::new();
    assert_eq!(f.step(0.0, 1e-3), Fmi2Status::Error);
    let n = f.log_len();
    assert_eq!(f.enter(), Fmi2Status::Error);
    assert!(f.log_len() > n);
}
