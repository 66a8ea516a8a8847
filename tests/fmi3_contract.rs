//! The rules of the FMI contract that FMI 3.0 alone has: arrays and `nValues`, the independent
//! variable `time`, one-byte Booleans, the types the model has no variable of, `eventModeUsed`,
//! the instantiation token and the adjoint derivative. The rules FMI 3.0 shares with FMI 2.0 (bad
//! parameters rejected by name, never OK with non-finite outputs, a step that cannot advance
//! time, hostile or foreign FMU states, the error state) are written once, in
//! `contract_both_versions.rs`, and run through both versions.

#[path = "common/fmu.rs"]
mod fmu;
#[path = "common/fmu3.rs"]
mod fmu3;

use fmu3::Fmu3;
use hydraulic_slewing_plate::fmi3::ffi::*;
use hydraulic_slewing_plate::fmi3_exports::*;

#[test]
fn arrays_are_read_whole_and_n_values_is_checked() {
    let f = Fmu3::new();
    assert_eq!(f.init(0.0), Fmi3Status::Ok);
    assert_eq!(f.step(0.0, 1e-3), Fmi3Status::Ok);
    let acc = Fmu3::vr("acc[1]");
    let y = Fmu3::vr("y_pot");
    // y_pot, the 12 accelerometers and time: 14 values from 3 value references.
    let mut v = [f64::NAN; 14];
    let s = unsafe { fmi3GetFloat64(f.c, [y, acc, 0].as_ptr(), 3, v.as_mut_ptr(), 14) };
    assert_eq!(s, Fmi3Status::Ok, "{}", f.last());
    assert_eq!(v[0], f.get_real("y_pot").1);
    // The array alone gives the same 12 values, which are the FMI 2.0 scalars acc[1..12].
    let mut alone = [f64::NAN; 12];
    let s = unsafe { fmi3GetFloat64(f.c, &acc, 1, alone.as_mut_ptr(), 12) };
    assert_eq!(s, Fmi3Status::Ok);
    assert_eq!(&v[1..13], &alone[..]);
    assert!(alone.iter().all(|a| a.is_finite()));
    for k in 0..12 {
        assert_eq!(fmu::Fmu::vr(&format!("acc[{}]", k + 1)), acc + k as u32);
    }
    assert_eq!(v[13], 1e-3, "time");
    // One value short, one too many: an error naming both counts.
    for n in [13, 15] {
        let mut w = [0.0; 15];
        let s = unsafe { fmi3GetFloat64(f.c, [y, acc, 0].as_ptr(), 3, w.as_mut_ptr(), n) };
        assert_eq!(s, Fmi3Status::Error);
        assert!(
            f.last().contains(&format!("nValues is {n}")) && f.last().contains("14 values"),
            "{}",
            f.last()
        );
        assert_eq!(unsafe { fmi3Reset(f.c) }, Fmi3Status::Ok);
        assert_eq!(f.init(0.0), Fmi3Status::Ok);
    }
    // acc[2]'s FMI 2.0 value reference is no FMI 3.0 variable.
    let mut w = [0.0; 1];
    let s = unsafe { fmi3GetFloat64(f.c, &(acc + 1), 1, w.as_mut_ptr(), 1) };
    assert_eq!(s, Fmi3Status::Error);
    assert!(
        f.last()
            .contains(&format!("unknown value reference {}", acc + 1)),
        "{}",
        f.last()
    );
}

#[test]
fn time_is_read_not_set_and_types_are_checked() {
    let f = Fmu3::new();
    assert_eq!(f.init(0.0), Fmi3Status::Ok);
    let t = 1.0;
    assert_eq!(
        unsafe { fmi3SetFloat64(f.c, &0, 1, &t, 1) },
        Fmi3Status::Error
    );
    assert!(
        f.last().contains("'time' is the independent variable"),
        "{}",
        f.last()
    );
    let f = Fmu3::new();
    assert_eq!(f.enter(0.0), Fmi3Status::Ok);
    // A Float64 read as Int32, and an Int8 the model does not have.
    let mut i = 0i32;
    let r = Fmu3::vr("r");
    assert_eq!(
        unsafe { fmi3GetInt32(f.c, &r, 1, &mut i, 1) },
        Fmi3Status::Error
    );
    assert!(
        f.last().contains("'r', a Float64, not a Int32"),
        "{}",
        f.last()
    );
    let f = Fmu3::new();
    assert_eq!(f.enter(0.0), Fmi3Status::Ok);
    let mut b = 0i8;
    assert_eq!(
        unsafe { fmi3GetInt8(f.c, &r, 1, &mut b, 1) },
        Fmi3Status::Error
    );
    assert!(
        f.last().contains("'r', a Float64, not a Int8"),
        "{}",
        f.last()
    );
    // No value references: nothing to do, whatever the type.
    let f = Fmu3::new();
    assert_eq!(f.enter(0.0), Fmi3Status::Ok);
    assert_eq!(
        unsafe { fmi3GetInt8(f.c, std::ptr::null(), 0, &mut b, 0) },
        Fmi3Status::Ok
    );
}

#[test]
fn any_nonzero_byte_is_true() {
    // C's bool holds 0 or 1, but an importer may pass any byte; it must not be undefined
    // behaviour, and it means true.
    let f = Fmu3::new();
    let vr = Fmu3::vr("controller.saturation");
    let byte = 2u8;
    assert_eq!(
        unsafe { fmi3SetBoolean(f.c, &vr, 1, &byte, 1) },
        Fmi3Status::Ok
    );
    assert_eq!(f.enter(0.0), Fmi3Status::Ok);
    let mut out = 7u8;
    assert_eq!(
        unsafe { fmi3GetBoolean(f.c, &vr, 1, &mut out, 1) },
        Fmi3Status::Ok
    );
    assert_eq!(out, 1);
}

#[test]
fn event_mode_is_refused_at_instantiation_with_a_reason() {
    let log = Fmu3::try_new(true)
        .err()
        .expect("eventModeUsed = true must be refused");
    let (status, category, message) = log.last().cloned().expect("a log line");
    assert_eq!(status, Fmi3Status::Error);
    assert_eq!(category, "logStatusError");
    assert!(
        message.contains("eventModeUsed") && message.contains("no events"),
        "{message}"
    );
}

#[test]
fn a_wrong_instantiation_token_is_refused() {
    let token = c"{00000000-0000-0000-0000-000000000000}";
    let c = unsafe {
        fmi3InstantiateCoSimulation(
            c"x".as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            0,
            0,
            0,
            0,
            std::ptr::null(),
            0,
            std::ptr::null_mut(),
            None,
            None,
        )
    };
    assert!(c.is_null());
}

/// FMI 3.0's scalar Booleans are C `bool`s, taken as the byte the caller passed: 0 is false and
/// any other byte true (C's truthiness), at every scalar Boolean argument, with no undefined
/// behaviour for bytes other than 0 and 1 (a Rust `bool` holding 2 would be).
#[test]
fn scalar_boolean_arguments_take_any_nonzero_byte_as_true() {
    for b in [0u8, 1, 2, 255] {
        let truth = b != 0;
        // eventModeUsed: the FMU has no event mode and refuses to be instantiated with it.
        assert_eq!(
            Fmu3::try_new_bytes(0, b).is_err(),
            truth,
            "eventModeUsed byte {b}"
        );
        // loggingOn: with logging on, a step logs its statistics; off, nothing.
        let f = Fmu3::try_new_bytes(b, 0).expect("instantiated");
        assert_eq!(f.init(0.0), Fmi3Status::Ok);
        let before = f.log_len();
        assert_eq!(f.step(0.0, 1e-3), Fmi3Status::Ok);
        assert_eq!(
            f.log_len() > before,
            truth,
            "loggingOn byte {b}: {:?}",
            f.log()
        );
        // fmi3SetDebugLogging's loggingOn: the same, switched after instantiation.
        let g = Fmu3::new();
        assert_eq!(
            unsafe { fmi3SetDebugLogging(g.c, b, 0, std::ptr::null()) },
            Fmi3Status::Ok
        );
        assert_eq!(g.init(0.0), Fmi3Status::Ok);
        let before = g.log_len();
        assert_eq!(g.step(0.0, 1e-3), Fmi3Status::Ok);
        assert_eq!(g.log_len() > before, truth, "fmi3SetDebugLogging byte {b}");
        // toleranceDefined and stopTimeDefined: a tolerance of -1 and a stop time before the
        // start are refused when defined, ignored when not.
        for (tol_defined, stop_defined) in [(b, 0), (0, b)] {
            let h = Fmu3::new();
            let s = unsafe {
                fmi3EnterInitializationMode(h.c, tol_defined, -1.0, 1.0, stop_defined, 0.0)
            };
            let expected = if truth {
                Fmi3Status::Error
            } else {
                Fmi3Status::Ok
            };
            assert_eq!(
                s,
                expected,
                "byte {b} ({tol_defined}, {stop_defined}): {}",
                h.last()
            );
        }
        // noSetFMUStatePriorToCurrentPoint: read, and without effect on the step.
        let k = Fmu3::new();
        assert_eq!(k.init(0.0), Fmi3Status::Ok);
        let (mut event, mut terminate, mut early, mut last) = (true, true, true, f64::NAN);
        let s = unsafe {
            fmi3DoStep(
                k.c,
                0.0,
                1e-3,
                b,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last,
            )
        };
        assert_eq!(
            s,
            Fmi3Status::Ok,
            "noSetFMUStatePriorToCurrentPoint byte {b}"
        );
    }
}

/// `fmi3GetAdjointDerivative` with no knowns (nKnowns = 0, so nSensitivity = 0) is checked as
/// any other call: refused before initialisation and with a parameter as unknown, allowed with
/// an output once initialised (campaign defect N2: it returned OK in every case, its checks ran
/// inside the loop over the knowns).
#[test]
fn adjoint_derivative_without_knowns_is_checked_like_any_call() {
    let none: [u32; 0] = [];
    let mut sensitivity: [f64; 0] = [];
    let seed = [1.0];
    let mut adjoint = |f: &Fmu3, unknown: &str| unsafe {
        fmi3GetAdjointDerivative(
            f.c,
            &Fmu3::vr(unknown),
            1,
            none.as_ptr(),
            0,
            seed.as_ptr(),
            1,
            sensitivity.as_mut_ptr(),
            0,
        )
    };
    // Instantiated, not initialised: refused.
    let f = Fmu3::new();
    assert_eq!(adjoint(&f, "y_pot"), Fmi3Status::Error, "{}", f.last());
    assert!(f.last().contains("fmi3G"), "{}", f.last());
    // A parameter as the unknown: refused, naming it.
    let g = Fmu3::new();
    assert_eq!(g.init(0.0), Fmi3Status::Ok);
    assert_eq!(adjoint(&g, "plate.zeta"), Fmi3Status::Error);
    assert!(g.last().contains("plate.zeta"), "{}", g.last());
    // An output, initialised: allowed (an empty sensitivity).
    let h = Fmu3::new();
    assert_eq!(h.init(0.0), Fmi3Status::Ok);
    assert_eq!(adjoint(&h, "y_pot"), Fmi3Status::Ok, "{}", h.last());
}

/// `fmi3GetAdjointDerivative` checks its seed as the directional derivative does (campaign
/// finding F2: a NaN seed returned OK when the call had no knowns, whose loop never read it):
/// refused, naming the element, with knowns and without.
#[test]
fn adjoint_derivative_refuses_a_non_finite_seed() {
    let f = Fmu3::new();
    assert_eq!(f.init(0.0), Fmi3Status::Ok);
    let unknown = [Fmu3::vr("y_pot")];
    let adjoint = |knowns: &[u32], seed: f64| {
        let mut sensitivity = vec![0.0; knowns.len()];
        unsafe {
            fmi3GetAdjointDerivative(
                f.c,
                unknown.as_ptr(),
                1,
                knowns.as_ptr(),
                knowns.len(),
                [seed].as_ptr(),
                1,
                sensitivity.as_mut_ptr(),
                knowns.len(),
            )
        }
    };
    for (knowns, bad) in [(vec![], f64::NAN), (vec![Fmu3::vr("r")], f64::INFINITY)] {
        assert_eq!(
            adjoint(&knowns, bad),
            Fmi3Status::Error,
            "{knowns:?}: {}",
            f.last()
        );
        assert!(f.last().contains("seed[0]"), "{}", f.last());
        // A finite seed is still answered.
        assert_eq!(adjoint(&knowns, 1.0), Fmi3Status::Ok, "{}", f.last());
    }
}

#[test]
fn setters_of_types_the_fmu_has_not_name_the_value_reference_in_instantiated() {
    // F3 of the fuzz round: the setters of types the FMU has no variable of answered "illegal
    // call sequence" in Instantiated, where setting is allowed; they name the value reference
    // and its type there, as the getters do in the states that allow getting.
    let r = Fmu3::vr("r");
    let check = |function: &str, call: &dyn Fn(&Fmu3) -> Fmi3Status| {
        let f = Fmu3::new(); // Instantiated
        assert_eq!(call(&f), Fmi3Status::Error, "{function}");
        let m = f.last();
        assert!(
            m.starts_with(function) && m.contains("'r', a Float64") && !m.contains("illegal call"),
            "{function}: {m}"
        );
    };
    let s = c"text".as_ptr();
    check("fmi3SetString", &|f| unsafe {
        fmi3SetString(f.c, &r, 1, &s, 1)
    });
    check("fmi3SetFloat32", &|f| unsafe {
        fmi3SetFloat32(f.c, &r, 1, &1.0f32, 1)
    });
    check("fmi3SetInt8", &|f| unsafe {
        fmi3SetInt8(f.c, &r, 1, &1i8, 1)
    });
    check("fmi3SetUInt16", &|f| unsafe {
        fmi3SetUInt16(f.c, &r, 1, &1u16, 1)
    });
    let bytes = [1u8];
    let (b, size) = (bytes.as_ptr(), 1usize);
    check("fmi3SetBinary", &|f| unsafe {
        fmi3SetBinary(f.c, &r, 1, &size, &b, 1)
    });
    check("fmi3SetClock", &|f| unsafe {
        fmi3SetClock(f.c, &r, 1, &true)
    });
}
