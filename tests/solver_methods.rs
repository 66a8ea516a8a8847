//! The solver's methods behind one trait (issue 40, item 1).
//!
//! * The contract every registered method keeps ([`solver::methods`], the crate's three and
//!   Heun's, registered by this test from its own module `common/heun.rs`): bit-exact stop
//!   times, output times from its dense output, accuracy on a non-stiff problem, a restored copy
//!   equal to the original and continuing bit for bit, a saved state of another format version
//!   refused naming both versions, and no allocation in a warm call.
//! * A method registered in a test runs through the FMU core (the FMI 2.0 entries over a toy
//!   model whose FMU state holds the integrator): steps, FMU states saved, serialised, restored,
//!   and a state of another version refused.
//! * RADAU5's give-up after repeated singular matrices (NSING = 5).

#[path = "common/heun.rs"]
mod heun;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::{c_char, c_void, CStr};
use std::sync::Mutex;

use heun::Heun;
use hydraulic_slewing_plate::fmi2::entries as fmi2;
use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::fmu::{
    Causality, Experiment, FmuModel, Kind, StepFailure, StepLog, Values, Variability, Variable,
};
use hydraulic_slewing_plate::solver::radau5::Radau5Options;
use hydraulic_slewing_plate::solver::{
    self, Atol, Integrator, Method, OdeSystem, SolverErrorKind, SolverOptions,
};
use nalgebra::DMatrix;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        System.alloc(layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        System.realloc(ptr, layout, new_size)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

/// The harmonic oscillator x0' = x1, x1' = -x0 from (1, 0): x = (cos t, -sin t). Not stiff.
struct Oscillator;

impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, x: &[f64], f: &mut [f64]) {
        f[0] = x[1];
        f[1] = -x[0];
    }
    fn jacobian(&self, _t: f64, _x: &[f64], j: &mut DMatrix<f64>) -> bool {
        j.fill(0.0);
        j[(0, 1)] = 1.0;
        j[(1, 0)] = -1.0;
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

fn exact(t: f64) -> [f64; 2] {
    [t.cos(), -t.sin()]
}

fn options(method: Method) -> SolverOptions {
    SolverOptions {
        method,
        rtol: 1e-6,
        atol: Atol::Scalar(1e-9),
        ..Default::default()
    }
}

fn heun() -> Method {
    solver::register::<Heun>().unwrap()
}

/// Communication step of the contract's runs, and their number.
const DT: f64 = 0.05;
const CALLS: usize = 40;
/// The largest error allowed on the oscillator at rtol 1e-6 (amplitude 1): every method is
/// well within it (the fixed-step one, one Rodas5P step of 0.05 per call, has about 1e-7).
const ACCURACY: f64 = 1e-4;

/// Calls `k0+1..=k1` of the contract's run: each to k·DT with three output times inside and
/// one at its end.
fn run(integ: &mut Integrator, k0: usize, k1: usize) {
    let sys = Oscillator;
    for k in k0 + 1..=k1 {
        let t_end = k as f64 * DT;
        let mut times: Vec<f64> = (1..4)
            .map(|i| (k - 1) as f64 * DT + i as f64 * DT / 4.0)
            .collect();
        times.push(t_end);
        let mut seen = 0;
        integ
            .advance_to_with_output(&sys, t_end, &times, &mut |t, x| {
                let e = exact(t);
                assert!(
                    (x[0] - e[0]).abs() < ACCURACY && (x[1] - e[1]).abs() < ACCURACY,
                    "output at t = {t}: {x:?}, exact {e:?}"
                );
                seen += 1;
            })
            .unwrap();
        assert_eq!(seen, times.len(), "output times reported");
        assert_eq!(integ.t().to_bits(), t_end.to_bits(), "bit-exact stop");
        let e = exact(t_end);
        let x = integ.x();
        assert!(
            (x[0] - e[0]).abs() < ACCURACY && (x[1] - e[1]).abs() < ACCURACY,
            "t = {t_end}: {x:?}, exact {e:?}"
        );
    }
}

fn contract(method: Method) {
    let mut integ = Integrator::new(options(method), 0.0, vec![1.0, 0.0]).unwrap();
    run(&mut integ, 0, CALLS / 2);
    let saved = integ.clone();
    let json = serde_json::to_string(&integ).unwrap();

    // A restored copy equals the original and continues bit for bit.
    let mut restored: Integrator = serde_json::from_str(&json).unwrap();
    assert_eq!(restored, saved, "{}", method.name());
    run(&mut integ, CALLS / 2, CALLS);
    run(&mut restored, CALLS / 2, CALLS);
    let bits = |i: &Integrator| i.x().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&restored), bits(&integ), "{}", method.name());
    assert_eq!(restored.stats(), integ.stats(), "{}", method.name());
    assert_eq!(restored, integ, "{}", method.name());

    // The saved state names its method and the version of the method's format; another
    // version is refused, naming both.
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(value["options"]["method"], method.name());
    let version = value["state_version"].as_u64().expect("state_version");
    value["state_version"] = serde_json::json!(version + 1);
    let err = serde_json::from_str::<Integrator>(&value.to_string())
        .unwrap_err()
        .to_string();
    let both = format!(
        "its {} solver state is of format version {}, this build reads version {version}",
        method.name(),
        version + 1
    );
    assert!(err.contains(&both), "{err}");

    // A warm call allocates nothing, ending on the point or stepping past it, also after an
    // input jump.
    // (The first 20 calls warm the buffers of the calls that step past their point.)
    let sys = Oscillator;
    let mut before = 0;
    for k in CALLS + 1..=CALLS + 40 {
        if k == CALLS + 21 {
            before = allocations();
        }
        let t_end = k as f64 * DT;
        if k % 5 == 0 {
            integ.notify_discontinuity();
        }
        if k % 2 == 0 {
            integ.advance_to(&sys, t_end).unwrap();
        } else {
            integ.advance_past(&sys, t_end, t_end + DT).unwrap();
        }
        assert_eq!(integ.t().to_bits(), t_end.to_bits());
    }
    let allocated = allocations() - before;
    assert_eq!(allocated, 0, "{}: {allocated} allocations", method.name());
}

#[test]
fn every_registered_method_keeps_the_contract() {
    let heun = heun();
    let all = solver::methods();
    for m in [Method::Rodas5P, Method::Radau5, Method::Rodas5PFixed, heun] {
        assert!(all.contains(&m), "{m:?} is registered");
    }
    for m in all {
        contract(m);
    }
}

#[test]
fn a_method_is_found_by_its_name_and_a_name_is_taken_once() {
    let heun = heun();
    assert_eq!("heun-test".parse::<Method>(), Ok(heun));
    assert_eq!("radau".parse::<Method>(), Ok(Method::Radau5));
    let unknown = "euler".parse::<Method>().unwrap_err();
    assert!(
        unknown.contains("heun-test") && unknown.contains("rodas5p"),
        "{unknown}"
    );
    // Registering again is harmless; another method under a taken name is refused.
    assert_eq!(solver::register::<Heun>(), Ok(heun));
    struct Impostor;
    impl solver::OdeMethod for Impostor {
        const NAME: &'static str = "radau5";
        const STATE_VERSION: u32 = 1;
        type State = heun::HeunState;
        fn fresh(o: &SolverOptions, n: usize) -> heun::HeunState {
            <Heun as solver::OdeMethod>::fresh(o, n)
        }
        fn advance(
            run: &mut solver::Stepper<heun::HeunState>,
            sys: &dyn OdeSystem,
            t_end: f64,
            limit: f64,
            times: &[f64],
            out: &mut dyn FnMut(f64, &[f64]),
        ) -> Result<(), solver::SolverError> {
            Heun::advance(run, sys, t_end, limit, times, out)
        }
        fn notify_discontinuity(_: &mut heun::HeunState) {}
        fn after_failure(_: &mut heun::HeunState) {}
    }
    let taken = solver::register::<Impostor>().unwrap_err();
    assert!(taken.contains("\"radau5\" is taken"), "{taken}");
}

/// A test method switched to and from: the counters and the point carry over, the method's
/// state starts fresh.
#[test]
fn set_options_switches_to_a_registered_method() {
    let heun = heun();
    let sys = Oscillator;
    let mut integ = Integrator::new(options(Method::Rodas5P), 0.0, vec![1.0, 0.0]).unwrap();
    integ.advance_to(&sys, 0.5).unwrap();
    let accepted = integ.stats().accepted;
    integ.set_options(options(heun)).unwrap();
    assert_eq!(integ.options().method, heun);
    assert_eq!(integ.step_size(), 0.0);
    integ.advance_to(&sys, 1.0).unwrap();
    assert!(
        integ.stats().accepted > accepted + 100,
        "{:?}",
        integ.stats()
    );
    let e = exact(1.0);
    assert!((integ.x()[0] - e[0]).abs() < ACCURACY);
    integ.set_options(options(Method::Radau5)).unwrap();
    integ.advance_to(&sys, 1.5).unwrap();
    assert!((integ.x()[0] - exact(1.5)[0]).abs() < ACCURACY);
}

// ---- The test method through the FMU core ----

/// A toy FMU over the oscillator, integrated by Heun's method (registered by this test): the
/// FMU state is the integrator.
struct HeunFmu {
    integ: Option<Integrator>,
}

const VARS: [Variable; 1] = [Variable {
    name: "x",
    value_reference: 1,
    causality: Causality::Output,
    variability: Variability::Continuous,
    kind: Kind::Real {
        start: None,
        min: None,
        max: None,
    },
    unit: None,
    description: "position",
}];

impl FmuModel for HeunFmu {
    type State = Option<Integrator>;
    const MODEL_IDENTIFIER: &'static str = "HeunOscillator";
    const GUID: &'static str = "{heun-oscillator}";

    fn variables() -> &'static [Variable] {
        &VARS
    }
    fn index_of(vr: u32) -> Option<usize> {
        VARS.iter().position(|v| v.value_reference == vr)
    }
    fn new() -> Self {
        HeunFmu { integ: None }
    }
    fn initialize(
        &mut self,
        values: &mut Values,
        e: &Experiment,
        _log: &mut StepLog,
    ) -> Result<(), String> {
        let integ = Integrator::new(options(heun()), e.start_time, vec![1.0, 0.0])
            .map_err(|e| e.to_string())?;
        values.set_real(0, integ.x()[0]);
        self.integ = Some(integ);
        Ok(())
    }
    fn do_step(
        &mut self,
        values: &mut Values,
        t0: f64,
        t1: f64,
        _log: &mut StepLog,
    ) -> Result<(), StepFailure> {
        let integ = self.integ.as_mut().ok_or_else(|| StepFailure {
            last_successful_time: t0,
            message: "not initialised".into(),
        })?;
        let result = integ.advance_to(&Oscillator, t1);
        values.set_real(0, integ.x()[0]);
        result.map_err(|e| StepFailure {
            last_successful_time: integ.t(),
            message: e.to_string(),
        })
    }
    fn save_state(&self) -> Option<Integrator> {
        self.integ.clone()
    }
    fn restore_state(
        &mut self,
        s: &Option<Integrator>,
        _: &Values,
        e: &Experiment,
        time: Option<f64>,
    ) -> Result<(), String> {
        if let Some(integ) = s {
            integ.check_restored(&Oscillator, &options(heun()), time.unwrap_or(e.start_time))?;
        }
        self.integ = s.clone();
        Ok(())
    }
}

static LOG: Mutex<Vec<String>> = Mutex::new(Vec::new());

unsafe extern "C" fn logger(
    _env: *mut c_void,
    _name: *const c_char,
    _status: Fmi2Status,
    _category: *const c_char,
    message: *const c_char,
) {
    let m = CStr::from_ptr(message).to_string_lossy().replace("%%", "%");
    LOG.lock().unwrap().push(m);
}

fn last_log() -> String {
    LOG.lock().unwrap().last().cloned().unwrap_or_default()
}

fn x_of(c: Fmi2Component) -> f64 {
    let mut v = 0.0;
    let s = unsafe {
        fmi2::get_values::<HeunFmu, f64>(c, "fmi2GetReal", "Real", &1, 1, &mut v, |v| match v {
            hydraulic_slewing_plate::fmu::Value::Real(x) => *x,
            _ => f64::NAN,
        })
    };
    assert_eq!(s, Fmi2Status::Ok);
    v
}

fn steps(c: Fmi2Component, k0: usize, k1: usize) -> Vec<u64> {
    (k0..k1)
        .map(|k| {
            let s = unsafe { fmi2::do_step::<HeunFmu>(c, k as f64 * 0.01, 0.01, 1) };
            assert_eq!(s, Fmi2Status::Ok, "{}", last_log());
            x_of(c).to_bits()
        })
        .collect()
}

#[test]
fn a_method_registered_in_a_test_runs_through_the_fmu_core() {
    use fmi2::fmu_state as st;
    let callbacks = Fmi2CallbackFunctions::with_plain_logger(logger, std::ptr::null_mut());
    let c = unsafe {
        fmi2::instantiate::<HeunFmu>(
            c"heun".as_ptr(),
            FMI2_CO_SIMULATION,
            c"{heun-oscillator}".as_ptr(),
            std::ptr::null(),
            &callbacks,
            0,
            0,
        )
    };
    assert!(!c.is_null());
    unsafe {
        assert_eq!(
            fmi2::setup_experiment::<HeunFmu>(c, 0, 0.0, 0.0, 0, 0.0),
            Fmi2Status::Ok
        );
        let enter = |i: &mut hydraulic_slewing_plate::fmu::instance::Instance<HeunFmu>| {
            i.enter_initialization_mode()
        };
        assert_eq!(
            fmi2::simple_call::<HeunFmu>(c, "fmi2EnterInitializationMode", enter),
            Fmi2Status::Ok
        );
        let exit = |i: &mut hydraulic_slewing_plate::fmu::instance::Instance<HeunFmu>| {
            i.exit_initialization_mode()
        };
        assert_eq!(
            fmi2::simple_call::<HeunFmu>(c, "fmi2ExitInitializationMode", exit),
            Fmi2Status::Ok
        );
    }
    steps(c, 0, 50);
    assert!((x_of(c) - 0.5f64.cos()).abs() < ACCURACY);

    // Save, serialise, go on; deserialise, restore, go on again: the same bits.
    let mut state: Fmi2FmuState = std::ptr::null_mut();
    assert_eq!(unsafe { st::get::<HeunFmu>(c, &mut state) }, Fmi2Status::Ok);
    let mut size = 0;
    assert_eq!(
        unsafe { st::serialized_size::<HeunFmu>(c, state, &mut size) },
        Fmi2Status::Ok
    );
    let mut bytes = vec![0u8; size];
    assert_eq!(
        unsafe { st::serialize::<HeunFmu>(c, state, bytes.as_mut_ptr().cast(), size) },
        Fmi2Status::Ok
    );
    let first = steps(c, 50, 100);
    let mut copy: Fmi2FmuState = std::ptr::null_mut();
    assert_eq!(
        unsafe { st::deserialize::<HeunFmu>(c, bytes.as_ptr().cast(), size, &mut copy) },
        Fmi2Status::Ok,
        "{}",
        last_log()
    );
    assert_eq!(unsafe { st::set::<HeunFmu>(c, copy) }, Fmi2Status::Ok);
    assert_eq!(steps(c, 50, 100), first);
    assert!((x_of(c) - 1.0f64.cos()).abs() < ACCURACY);

    // The method's state in the serialised FMU state is Heun's, of its version; another
    // version is refused, naming both.
    let mut payload: serde_json::Value = serde_json::from_slice(&bytes[24..]).unwrap();
    let integ = &mut payload["model"];
    assert_eq!(integ["options"]["method"], "heun-test");
    assert_eq!(integ["state_version"], heun::STATE_VERSION);
    integ["state_version"] = serde_json::json!(heun::STATE_VERSION - 1);
    let edited = {
        let p = serde_json::to_vec(&payload).unwrap();
        let mut b = bytes[..8].to_vec();
        b.extend_from_slice(&(p.len() as u64).to_le_bytes());
        b.extend_from_slice(&hydraulic_slewing_plate::fnv1a::fnv1a64(&p).to_le_bytes());
        b.extend_from_slice(&p);
        b
    };
    let mut bad: Fmi2FmuState = std::ptr::null_mut();
    assert_eq!(
        unsafe { st::deserialize::<HeunFmu>(c, edited.as_ptr().cast(), edited.len(), &mut bad) },
        Fmi2Status::Error
    );
    let m = last_log();
    let both = format!(
        "heun-test solver state is of format version {}, this build reads version {}",
        heun::STATE_VERSION - 1,
        heun::STATE_VERSION
    );
    assert!(m.contains(&both), "{m}");
    unsafe {
        assert_eq!(st::free::<HeunFmu>(c, &mut state), Fmi2Status::Ok);
        assert_eq!(st::free::<HeunFmu>(c, &mut copy), Fmi2Status::Ok);
        fmi2::free_instance::<HeunFmu>(c);
    }
}

// ---- RADAU5's NSING ----

/// x' = J x with J = M [[1, 1], [1, 1]], M = 1e300, from x = (1, -1), where f = 0: every
/// iteration matrix (γ/h) I − J rounds to −J, which is singular, whatever h (γ/h is far below
/// ulp(M)).
struct AlwaysSingular;

const M: f64 = 1e300;

impl OdeSystem for AlwaysSingular {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, x: &[f64], f: &mut [f64]) {
        let s = M * (x[0] + x[1]);
        f[0] = s;
        f[1] = s;
    }
    fn jacobian(&self, _t: f64, _x: &[f64], j: &mut DMatrix<f64>) -> bool {
        j.fill(M);
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// RADAU5 gives up at the NSING-th singular matrix of a call (5, its default) instead of
/// halving the step up to `max_consecutive_rejections` (50) times.
#[test]
fn radau5_gives_up_after_nsing_singular_matrices() {
    let nsing = Radau5Options::default().nsing;
    assert_eq!(nsing, 5);
    let opts = SolverOptions {
        initial_step: Some(1e-3),
        ..options(Method::Radau5)
    };
    let mut integ = Integrator::new(opts, 0.0, vec![1.0, -1.0]).unwrap();
    let err = integ.advance_to(&AlwaysSingular, 1.0).unwrap_err();
    assert_eq!(err.kind, SolverErrorKind::SingularMatrix, "{err}");
    assert_eq!(err.t, 0.0);
    assert!(
        err.message
            .contains("the iteration matrix was singular 5 times in this call"),
        "{err}"
    );
    // Five attempts, each rejected: four halvings of h, then the give-up.
    assert_eq!(
        integ.stats().rejected,
        u64::from(nsing),
        "{:?}",
        integ.stats()
    );
    assert_eq!(integ.stats().accepted, 0);
    // The integrator stays usable at the last accepted point.
    assert_eq!(integ.t(), 0.0);
    assert_eq!(integ.x(), &[1.0, -1.0]);
}
