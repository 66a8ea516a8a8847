//! FMI 3.0 Model Exchange and the partial derivatives of the FMI 3.0 layer, through the exported
//! `fmi3*` functions in-process: the call sequence of an importer's integrator, the same states
//! and derivatives as the FMI 2.0 interface of the same library, directional derivatives equal to
//! FMI 2.0's and to central differences of the derivatives, the adjoint equal to the transpose
//! (`w . (J v) = (J^T w) . v`), arrays as knowns and unknowns, and the interface rules.

#[path = "common/fmu3.rs"]
mod fmu3;

use std::ffi::{c_void, CString};
use std::os::raw::c_char;

use fmu3::Fmu3;
use hydraulic_slewing_plate::fmi2::ffi::{Fmi2CallbackFunctions, Fmi2Status, FMI2_MODEL_EXCHANGE};
use hydraulic_slewing_plate::fmi2_exports as f2;
use hydraulic_slewing_plate::fmi3::ffi::*;
use hydraulic_slewing_plate::fmi3_exports::*;
use hydraulic_slewing_plate::model::variables::{CONTINUOUS_STATES, GUID, VARIABLES};

unsafe extern "C" fn quiet3(_: *mut c_void, _: Fmi3Status, _: *const c_char, _: *const c_char) {}
unsafe extern "C" fn quiet2(
    _: *mut c_void,
    _: *const c_char,
    _: Fmi2Status,
    _: *const c_char,
    _: *const c_char,
) {
}

fn vr(name: &str) -> u32 {
    Fmu3::vr(name)
}

/// An FMI 3.0 Model Exchange instance of the complete system at rest with r = 2 V, in
/// continuous-time mode.
unsafe fn me3() -> Fmi3Instance {
    let token = CString::new(GUID).unwrap();
    let c = fmi3InstantiateModelExchange(
        c"me3".as_ptr(),
        token.as_ptr(),
        std::ptr::null(),
        0,
        0,
        std::ptr::null_mut(),
        Some(quiet3),
    );
    assert!(!c.is_null());
    assert_eq!(
        fmi3EnterInitializationMode(c, 0, 0.0, 0.0, 0, 0.0),
        Fmi3Status::Ok
    );
    assert_eq!(fmi3SetFloat64(c, &vr("r"), 1, &2.0, 1), Fmi3Status::Ok);
    assert_eq!(fmi3ExitInitializationMode(c), Fmi3Status::Ok);
    let mut flags = [true; 5];
    let mut next = 0.0;
    let [a, b, d, e, g] = &mut flags;
    assert_eq!(
        fmi3UpdateDiscreteStates(c, a, b, d, e, g, &mut next),
        Fmi3Status::Ok
    );
    assert_eq!(flags, [false; 5], "no discrete states, no events");
    assert_eq!(fmi3EnterContinuousTimeMode(c), Fmi3Status::Ok);
    c
}

/// The FMI 2.0 twin of [`me3`].
unsafe fn me2() -> *mut c_void {
    let c = me2_in_initialization_mode();
    assert_eq!(f2::fmi2SetReal(c, &vr("r"), 1, &2.0), Fmi2Status::Ok);
    assert_eq!(f2::fmi2ExitInitializationMode(c), Fmi2Status::Ok);
    let mut info = std::mem::zeroed();
    assert_eq!(f2::fmi2NewDiscreteStates(c, &mut info), Fmi2Status::Ok);
    assert_eq!(f2::fmi2EnterContinuousTimeMode(c), Fmi2Status::Ok);
    c
}

/// A reproducible pseudo-random sequence in [-1, 1).
fn noise(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
        .collect()
}

#[test]
fn model_exchange_matches_the_fmi2_interface_state_for_state() {
    unsafe {
        let (c3, c2) = (me3(), me2());
        let n = CONTINUOUS_STATES.len();
        let mut count = 0usize;
        assert_eq!(
            fmi3GetNumberOfContinuousStates(c3, &mut count),
            Fmi3Status::Ok
        );
        assert_eq!(count, n);
        let mut z = 7usize;
        assert_eq!(fmi3GetNumberOfEventIndicators(c3, &mut z), Fmi3Status::Ok);
        assert_eq!(z, 0);
        let (mut x3, mut x2) = (vec![0.0; n], vec![0.0; n]);
        assert_eq!(
            fmi3GetContinuousStates(c3, x3.as_mut_ptr(), n),
            Fmi3Status::Ok
        );
        assert_eq!(
            f2::fmi2GetContinuousStates(c2, x2.as_mut_ptr(), n),
            Fmi2Status::Ok
        );
        assert_eq!(x3, x2);
        let (mut nom3, mut nom2) = (vec![0.0; n], vec![0.0; n]);
        assert_eq!(
            fmi3GetNominalsOfContinuousStates(c3, nom3.as_mut_ptr(), n),
            Fmi3Status::Ok
        );
        assert_eq!(
            f2::fmi2GetNominalsOfContinuousStates(c2, nom2.as_mut_ptr(), n),
            Fmi2Status::Ok
        );
        assert_eq!(nom3, nom2);
        // A few explicit Euler steps of an importer's integrator, on both, then the derivatives
        // at a perturbed state.
        let mut x = x3.clone();
        for k in 0..5 {
            let t = k as f64 * 1e-6;
            let (mut d3, mut d2) = (vec![0.0; n], vec![0.0; n]);
            assert_eq!(fmi3SetTime(c3, t), Fmi3Status::Ok);
            assert_eq!(f2::fmi2SetTime(c2, t), Fmi2Status::Ok);
            assert_eq!(fmi3SetContinuousStates(c3, x.as_ptr(), n), Fmi3Status::Ok);
            assert_eq!(
                f2::fmi2SetContinuousStates(c2, x.as_ptr(), n),
                Fmi2Status::Ok
            );
            assert_eq!(
                fmi3GetContinuousStateDerivatives(c3, d3.as_mut_ptr(), n),
                Fmi3Status::Ok
            );
            assert_eq!(
                f2::fmi2GetDerivatives(c2, d2.as_mut_ptr(), n),
                Fmi2Status::Ok
            );
            assert_eq!(d3, d2, "step {k}");
            assert!(d3.iter().any(|d| *d != 0.0), "r = 2 V moves something");
            let (mut event, mut terminate) = (true, true);
            assert_eq!(
                fmi3CompletedIntegratorStep(c3, 1, &mut event, &mut terminate),
                Fmi3Status::Ok
            );
            assert!(!event && !terminate);
            for (xi, di) in x.iter_mut().zip(&d3) {
                *xi += 1e-6 * di;
            }
        }
        // Outputs too.
        let (mut y3, mut y2) = (0.0, 0.0);
        assert_eq!(
            fmi3GetFloat64(c3, &vr("y_pot"), 1, &mut y3, 1),
            Fmi3Status::Ok
        );
        assert_eq!(
            f2::fmi2GetReal(c2, &vr("y_pot"), 1, &mut y2),
            Fmi2Status::Ok
        );
        assert_eq!(y3, y2);
        assert_eq!(fmi3Terminate(c3), Fmi3Status::Ok);
        fmi3FreeInstance(c3);
        f2::fmi2FreeInstance(c2);
    }
}

#[test]
fn directional_derivatives_equal_fmi2_and_central_differences() {
    unsafe {
        let (c3, c2) = (me3(), me2());
        let n = CONTINUOUS_STATES.len();
        let states: Vec<u32> = CONTINUOUS_STATES
            .iter()
            .map(|&(x, _)| VARIABLES[x].value_reference)
            .collect();
        let derivatives: Vec<u32> = CONTINUOUS_STATES
            .iter()
            .map(|&(_, d)| VARIABLES[d].value_reference)
            .collect();
        let mut x = vec![0.0; n];
        assert_eq!(
            fmi3GetContinuousStates(c3, x.as_mut_ptr(), n),
            Fmi3Status::Ok
        );
        let mut nominal = vec![0.0; n];
        assert_eq!(
            fmi3GetNominalsOfContinuousStates(c3, nominal.as_mut_ptr(), n),
            Fmi3Status::Ok
        );
        // A random state around rest, on the states' own scales.
        for (k, (xi, e)) in x.iter_mut().zip(noise(1, n)).enumerate() {
            *xi += 1e-2 * nominal[k] * e;
        }
        assert_eq!(fmi3SetContinuousStates(c3, x.as_ptr(), n), Fmi3Status::Ok);
        assert_eq!(
            f2::fmi2SetContinuousStates(c2, x.as_ptr(), n),
            Fmi2Status::Ok
        );
        let v: Vec<f64> = noise(2, n)
            .iter()
            .zip(&nominal)
            .map(|(e, s)| e * s)
            .collect();
        let (mut jv3, mut jv2) = (vec![0.0; n], vec![0.0; n]);
        let s = fmi3GetDirectionalDerivative(
            c3,
            derivatives.as_ptr(),
            n,
            states.as_ptr(),
            n,
            v.as_ptr(),
            n,
            jv3.as_mut_ptr(),
            n,
        );
        assert_eq!(s, Fmi3Status::Ok);
        let s = f2::fmi2GetDirectionalDerivative(
            c2,
            derivatives.as_ptr(),
            n,
            states.as_ptr(),
            n,
            v.as_ptr(),
            jv2.as_mut_ptr(),
        );
        assert_eq!(s, Fmi2Status::Ok);
        assert_eq!(jv3, jv2, "the same Jacobian behind both versions");
        // Central differences of the derivatives along v: (f(x + h v) - f(x - h v)) / 2h.
        let h = 1e-6;
        let f_at = |sign: f64| {
            let xs: Vec<f64> = x.iter().zip(&v).map(|(a, b)| a + sign * h * b).collect();
            assert_eq!(fmi3SetContinuousStates(c3, xs.as_ptr(), n), Fmi3Status::Ok);
            let mut d = vec![0.0; n];
            assert_eq!(
                fmi3GetContinuousStateDerivatives(c3, d.as_mut_ptr(), n),
                Fmi3Status::Ok
            );
            d
        };
        let (plus, minus) = (f_at(1.0), f_at(-1.0));
        let scale = jv3.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        for k in 0..n {
            let fd = (plus[k] - minus[k]) / (2.0 * h);
            // 1e-6 of the largest component: central differences err by O(h^2 |f'''|) plus
            // round-off |f| eps / h; both are far below it at h = 1e-6 on nominal scales.
            assert!(
                (fd - jv3[k]).abs() <= 1e-6 * scale,
                "{}: directional {} vs central difference {fd}",
                VARIABLES[CONTINUOUS_STATES[k].1].name,
                jv3[k]
            );
        }
        fmi3FreeInstance(c3);
        f2::fmi2FreeInstance(c2);
    }
}

#[test]
fn the_adjoint_is_the_transpose_and_arrays_expand() {
    unsafe {
        let c3 = me3();
        let n = CONTINUOUS_STATES.len();
        let states: Vec<u32> = CONTINUOUS_STATES
            .iter()
            .map(|&(x, _)| VARIABLES[x].value_reference)
            .collect();
        let derivatives: Vec<u32> = CONTINUOUS_STATES
            .iter()
            .map(|&(_, d)| VARIABLES[d].value_reference)
            .collect();
        // Unknowns: every state derivative, y_pot and the 12 accelerometers (one value reference);
        // knowns: the states and the inputs F1, F2.
        let mut unknowns = derivatives.clone();
        unknowns.extend([vr("y_pot"), vr("acc[1]")]);
        let mut knowns = states.clone();
        knowns.extend([vr("F1"), vr("F2")]);
        let (nu, nk) = (n + 13, n + 2);
        let v = noise(3, nk);
        let w = noise(4, nu);
        let mut jv = vec![0.0; nu];
        let s = fmi3GetDirectionalDerivative(
            c3,
            unknowns.as_ptr(),
            unknowns.len(),
            knowns.as_ptr(),
            knowns.len(),
            v.as_ptr(),
            nk,
            jv.as_mut_ptr(),
            nu,
        );
        assert_eq!(s, Fmi3Status::Ok);
        let mut jtw = vec![0.0; nk];
        let s = fmi3GetAdjointDerivative(
            c3,
            unknowns.as_ptr(),
            unknowns.len(),
            knowns.as_ptr(),
            knowns.len(),
            w.as_ptr(),
            nu,
            jtw.as_mut_ptr(),
            nk,
        );
        assert_eq!(s, Fmi3Status::Ok);
        let lhs: f64 = w.iter().zip(&jv).map(|(a, b)| a * b).sum();
        let rhs: f64 = jtw.iter().zip(&v).map(|(a, b)| a * b).sum();
        let scale = w.iter().zip(&jv).map(|(a, b)| (a * b).abs()).sum::<f64>();
        assert!(
            (lhs - rhs).abs() <= 1e-12 * scale,
            "w.(Jv) = {lhs}, (J^T w).v = {rhs}"
        );
        // Newton's law: the accelerometers feel the shaker forces at once.
        assert!(
            jv[n + 1..].iter().any(|a| *a != 0.0),
            "acc depends on F1, F2"
        );
        // The sizes are the expanded ones: 12 for acc.
        let mut short = vec![0.0; nu - 1];
        let s = fmi3GetDirectionalDerivative(
            c3,
            unknowns.as_ptr(),
            unknowns.len(),
            knowns.as_ptr(),
            knowns.len(),
            v.as_ptr(),
            nk,
            short.as_mut_ptr(),
            nu - 1,
        );
        assert_eq!(s, Fmi3Status::Error);
        fmi3FreeInstance(c3);
    }
}

#[test]
fn interface_rules() {
    // A co-simulation instance refuses Model Exchange calls, naming both interfaces.
    let f = Fmu3::new();
    assert_eq!(f.init(0.0), Fmi3Status::Ok);
    assert_eq!(unsafe { fmi3SetTime(f.c, 0.0) }, Fmi3Status::Error);
    let last = f.last();
    assert!(
        last.starts_with("fmi3SetTime") && last.contains("Model Exchange"),
        "{last}"
    );
    // A Model Exchange instance refuses fmi3DoStep.
    unsafe {
        let c = me3();
        let (mut a, mut b, mut d, mut t) = (false, false, false, 0.0);
        assert_eq!(
            fmi3DoStep(c, 0.0, 1e-3, 1, &mut a, &mut b, &mut d, &mut t),
            Fmi3Status::Error
        );
        // Time is not a known of a derivative.
        let mut out = [0.0];
        let s =
            fmi3GetDirectionalDerivative(c, &vr("y_pot"), 1, &0, 1, &1.0, 1, out.as_mut_ptr(), 1);
        assert_eq!(s, Fmi3Status::Error);
        fmi3FreeInstance(c);
    }
}

/// FMI 3.0 allows `fmi3GetContinuousStateDerivatives` in initialization mode (FMI 3.0, section
/// 2.3.3, "State: Initialization Mode", allowed function calls): the derivatives at the initial
/// point, the same as read in event mode right after initialisation. (FMI 2.0.4 allows
/// `fmi2GetDerivatives` only after initialisation; that layer keeps refusing it there.)
#[test]
fn derivatives_are_readable_in_initialization_mode() {
    unsafe {
        let token = CString::new(GUID).unwrap();
        let c = fmi3InstantiateModelExchange(
            c"init".as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            0,
            0,
            std::ptr::null_mut(),
            Some(quiet3),
        );
        assert!(!c.is_null());
        let mut n = 0usize;
        assert_eq!(fmi3GetNumberOfContinuousStates(c, &mut n), Fmi3Status::Ok);
        assert_eq!(
            fmi3EnterInitializationMode(c, 0, 0.0, 0.0, 0, 0.0),
            Fmi3Status::Ok
        );
        assert_eq!(fmi3SetFloat64(c, &vr("r"), 1, &2.0, 1), Fmi3Status::Ok);
        let mut initial = vec![f64::NAN; n];
        assert_eq!(
            fmi3GetContinuousStateDerivatives(c, initial.as_mut_ptr(), n),
            Fmi3Status::Ok
        );
        assert!(initial.iter().all(|d| d.is_finite()));
        // A step of r = 2 V at rest: the loop drives the coil at once, so something moves.
        assert!(initial.iter().any(|&d| d != 0.0), "{initial:?}");
        assert_eq!(fmi3ExitInitializationMode(c), Fmi3Status::Ok);
        let mut after = vec![f64::NAN; n];
        assert_eq!(
            fmi3GetContinuousStateDerivatives(c, after.as_mut_ptr(), n),
            Fmi3Status::Ok
        );
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&initial), bits(&after));
        fmi3FreeInstance(c);

        // FMI 2.0: refused in initialization mode, as before.
        let c = me2_in_initialization_mode();
        let mut dx = vec![0.0; n];
        assert_eq!(
            f2::fmi2GetDerivatives(c, dx.as_mut_ptr(), n),
            Fmi2Status::Error
        );
        f2::fmi2FreeInstance(c);
    }
}

/// An FMI 2.0 Model Exchange instance in initialization mode.
unsafe fn me2_in_initialization_mode() -> *mut c_void {
    let callbacks = Fmi2CallbackFunctions::with_plain_logger(quiet2, std::ptr::null_mut());
    let guid = CString::new(GUID).unwrap();
    let c = f2::fmi2Instantiate(
        c"me2".as_ptr(),
        FMI2_MODEL_EXCHANGE,
        guid.as_ptr(),
        std::ptr::null(),
        &callbacks,
        0,
        0,
    );
    assert!(!c.is_null());
    assert_eq!(
        f2::fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0),
        Fmi2Status::Ok
    );
    assert_eq!(f2::fmi2EnterInitializationMode(c), Fmi2Status::Ok);
    c
}

/// The Model Exchange entry points' scalar Booleans are bytes too (see `fmi3_contract.rs`
/// `scalar_boolean_arguments_take_any_nonzero_byte_as_true` for Co-Simulation): any nonzero
/// `loggingOn` logs, and `noSetFMUStatePriorToCurrentPoint` of `fmi3CompletedIntegratorStep` is
/// read without undefined behaviour and without effect.
#[test]
fn model_exchange_scalar_booleans_take_any_nonzero_byte_as_true() {
    for b in [0u8, 1, 2, 255] {
        let truth = b != 0;
        let f = Fmu3::model_exchange_bytes(b).expect("instantiated");
        let c = f.0.c;
        unsafe {
            assert_eq!(
                fmi3EnterInitializationMode(c, 0, 0.0, 0.0, 0, 0.0),
                Fmi3Status::Ok
            );
            assert_eq!(fmi3ExitInitializationMode(c), Fmi3Status::Ok);
            let mut flags = [true; 5];
            let mut next = 0.0;
            let [d, e, g, h, k] = &mut flags;
            assert_eq!(
                fmi3UpdateDiscreteStates(c, d, e, g, h, k, &mut next),
                Fmi3Status::Ok
            );
            assert_eq!(fmi3EnterContinuousTimeMode(c), Fmi3Status::Ok);
            let (mut event, mut terminate) = (true, true);
            assert_eq!(
                fmi3CompletedIntegratorStep(c, b, &mut event, &mut terminate),
                Fmi3Status::Ok,
                "noSetFMUStatePriorToCurrentPoint byte {b}"
            );
            assert!(!event && !terminate, "byte {b}");
        }
        assert_eq!(
            !f.log().is_empty(),
            truth,
            "loggingOn byte {b}: {:?}",
            f.log()
        );
    }
}
