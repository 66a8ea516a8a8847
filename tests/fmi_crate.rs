//! The packaged FMU works with an independent importer, the Rust `fmi` crate (0.8).
//!
//! The test loads `fmu/HydraulicSlewingPlate.fmu` (building it with `hsp package` if missing) and
//! proves that
//! * the crate's parser accepts `modelDescription.xml` and reads the model identifier, the GUID
//!   and the variables the library was generated from;
//! * a co-simulation instance created and stepped by the crate follows the analytic closed-loop
//!   step response of the identified direct path `G_est(s) = 2.25e6 / (s (s + 65) (s + 753))`
//!   under unity feedback, to 1e-5 V;
//! * `fmi2GetFMUstate`/`fmi2SetFMUstate` and serialisation through the crate restore the FMU
//!   exactly: repeating steps from a restored state gives bit-identical outputs.

#[path = "common/packaged.rs"]
mod packaged;

use std::path::PathBuf;

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use fmi::traits::{FmiImport, FmiStatus};
use hydraulic_slewing_plate::fmu::Kind;
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::{vr, GUID, MODEL_IDENTIFIER, VARIABLES};
use nalgebra::Complex;

/// Communication step [s].
const H: f64 = 1e-3;

const REAL_OUTPUTS: [u32; 6] = [
    vr::Y_POT,
    vr::THETA_MOTOR,
    vr::OMEGA_MOTOR,
    vr::P_LOAD,
    vr::Q_VALVE,
    vr::ENERGY,
];
const INTEGER_OUTPUTS: [u32; 5] = [
    vr::SOLVER_STEPS,
    vr::SOLVER_REJECTED,
    vr::SOLVER_F_EVALS,
    vr::SOLVER_JAC_EVALS,
    vr::SOLVER_LU,
];

/// The packaged FMU, built from these sources (rebuilt by `hsp package` when missing or stale).
fn fmu_path() -> PathBuf {
    packaged::fresh_fmu(packaged::Version::Fmi2)
}

/// Closed-loop step response `y(t)` of `T(s) = K / (s^3 + 818 s^2 + 48945 s + K)`, `K = 2.25e6`,
/// to a unit step, by partial fractions: `y(t) = 1 + sum_i c_i exp(p_i t)` with
/// `c_i = K / (p_i prod_{j != i} (p_i - p_j))`, the residues of `T(s)/s` at the poles `p_i`.
struct ClosedLoop {
    poles: [Complex<f64>; 3],
    residues: [Complex<f64>; 3],
}

impl ClosedLoop {
    fn new() -> ClosedLoop {
        let (a, b, k) = (65.0 + 753.0, 65.0 * 753.0, 2.25e6);
        let p = |s: f64| ((s + a) * s + b) * s + k;
        let dp = |s: f64| (3.0 * s + 2.0 * a) * s + b;
        // A real cubic has a real root; p(-a) = -a b + k < 0 < p(0) = k brackets it. Bisection to
        // get close, Newton to polish to machine precision.
        let (mut lo, mut hi) = (-a, 0.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if p(mid) < 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        let mut r = 0.5 * (lo + hi);
        for _ in 0..3 {
            r -= p(r) / dp(r);
        }
        // Deflate: s^3 + a s^2 + b s + k = (s - r)(s^2 + e s + f).
        let e = a + r;
        let f = b + r * e;
        let disc = Complex::new(e * e - 4.0 * f, 0.0).sqrt();
        let poles = [Complex::new(r, 0.0), (-e + disc) / 2.0, (-e - disc) / 2.0];
        let residues = std::array::from_fn(|i| {
            let mut d = poles[i];
            for (j, pj) in poles.iter().enumerate() {
                if j != i {
                    d *= poles[i] - pj;
                }
            }
            Complex::new(k, 0.0) / d
        });
        ClosedLoop { poles, residues }
    }

    /// `d^n y / dt^n` at `t` (n = 0 is the response itself).
    fn derivative(&self, n: i32, t: f64) -> f64 {
        let sum: Complex<f64> = self
            .poles
            .iter()
            .zip(&self.residues)
            .map(|(p, c)| c * p.powi(n) * (p * t).exp())
            .sum();
        sum.re + if n == 0 { 1.0 } else { 0.0 }
    }
}

fn reals(inst: &mut InstanceCS) -> Vec<u64> {
    let mut v = [0.0; REAL_OUTPUTS.len()];
    inst.get_real(&REAL_OUTPUTS, &mut v).expect("fmi2GetReal");
    v.iter().map(|x| x.to_bits()).collect()
}

fn integers(inst: &mut InstanceCS) -> Vec<i32> {
    let mut v = [0; INTEGER_OUTPUTS.len()];
    inst.get_integer(&INTEGER_OUTPUTS, &mut v)
        .expect("fmi2GetInteger");
    v.to_vec()
}

/// Takes `n` steps from communication point number `k0`; returns every step's outputs.
fn steps(inst: &mut InstanceCS, k0: usize, n: usize) -> Vec<(Vec<u64>, Vec<i32>)> {
    (k0..k0 + n)
        .map(|k| {
            inst.do_step(k as f64 * H, H, true)
                .unwrap_or_else(|e| panic!("fmi2DoStep at step {k}: {e:?}"));
            (reals(inst), integers(inst))
        })
        .collect()
}

#[test]
fn analytic_closed_loop_is_exact() {
    // The reference itself, checked: y(0) = y'(0) = y''(0) = 0 (relative degree 3), y(inf) = 1.
    let cl = ClosedLoop::new();
    for n in 0..3 {
        let scale = cl
            .poles
            .iter()
            .map(|p| p.norm().powi(n))
            .fold(1.0, f64::max);
        assert!(
            cl.derivative(n, 0.0).abs() < 1e-12 * scale,
            "y^({n})(0) != 0"
        );
    }
    assert!((cl.derivative(0, 10.0) - 1.0).abs() < 1e-12);
}

#[test]
fn fmi_crate_imports_steps_and_restores_the_fmu() {
    let fmu = fmu_path();

    // Model description, through the crate's own parser.
    let import: Result<Fmi2Import, _> = fmi::import::from_path(&fmu);
    let import =
        import.unwrap_or_else(|e| panic!("the fmi crate rejects {}: {e} ({e:?})", fmu.display()));
    let md = import.model_description();
    assert_eq!(md.fmi_version, "2.0");
    assert_eq!(md.guid, GUID);
    let cs = md
        .co_simulation
        .as_ref()
        .expect("no <CoSimulation> element");
    assert_eq!(cs.model_identifier, MODEL_IDENTIFIER);
    assert_eq!(md.num_variables(), VARIABLES.len());
    for v in &VARIABLES {
        let sv = md
            .get_model_variables()
            .find(|sv| sv.value_reference == v.value_reference)
            .unwrap_or_else(|| panic!("vr {} missing", v.value_reference));
        assert_eq!(sv.name, v.name, "vr {}", v.value_reference);
    }

    // Instantiate and run the step response at the FMU's default tolerance (solver.rtol = 1e-6).
    let mut inst = import
        .instantiate_cs("fmi-crate", false, false)
        .expect("fmi2Instantiate");
    inst.setup_experiment(None, 0.0, None)
        .expect("fmi2SetupExperiment");
    // The analytic step response below is eq. 1's: the LOES on the motor alone, linear amplifier.
    for (name, value) in presets::preset("loes-motor").unwrap().settings {
        let var = VARIABLES.iter().find(|v| v.name == *name).unwrap();
        let vr = var.value_reference;
        match var.kind {
            Kind::Boolean { .. } => inst.set_boolean(&[vr], &[i32::from(*value == "true")]),
            Kind::Integer { .. } | Kind::Enumeration { .. } => {
                inst.set_integer(&[vr], &[value.parse().unwrap()])
            }
            _ => inst.set_real(&[vr], &[value.parse().unwrap()]),
        }
        .unwrap_or_else(|e| panic!("setting {name}: {e:?}"));
    }
    Common::enter_initialization_mode(&mut inst).expect("fmi2EnterInitializationMode");
    inst.set_real(&[vr::R], &[1.0]).expect("fmi2SetReal(r)");
    Common::exit_initialization_mode(&mut inst).expect("fmi2ExitInitializationMode");

    // Tolerance 1e-5 V: the default parameters reproduce G_est to round-off, so what is left is
    // the integrator's error. Rodas5P controls the local error to rtol 1e-6 (atol 1e-8 of each
    // state's nominal); with |y| <= ~1.1 V and an asymptotically stable loop that does not
    // amplify past errors, the global error stays of the order of 1e-6 V, and 1e-5 V bounds it
    // with a 10x margin. (Observed: ~2e-12 V, as the error control is conservative on this
    // smooth linear system.)
    let cl = ClosedLoop::new();
    let n = 300;
    let mut worst: f64 = 0.0;
    for k in 0..n {
        inst.do_step(k as f64 * H, H, true)
            .unwrap_or_else(|e| panic!("fmi2DoStep at step {k}: {e:?}"));
        let mut y = [0.0];
        inst.get_real(&[vr::Y_POT], &mut y).expect("fmi2GetReal");
        let t = (k + 1) as f64 * H;
        let err = (y[0] - cl.derivative(0, t)).abs();
        assert!(
            err < 1e-5,
            "t = {t}: y_pot = {}, analytic {}",
            y[0],
            cl.derivative(0, t)
        );
        worst = worst.max(err);
    }
    eprintln!("largest |y_pot - analytic| over 0.3 s: {worst:e} V");

    // Get the state, step on, restore, step again: the same outputs to the bit.
    let saved = inst.get_fmu_state().expect("fmi2GetFMUstate");
    let first = steps(&mut inst, n, 50);
    inst.set_fmu_state(&saved).ok().expect("fmi2SetFMUstate");
    let again = steps(&mut inst, n, 50);
    assert_eq!(again, first, "stepping from a restored FMU state differs");

    // The same through a serialised state, deserialised by the crate.
    let bytes = inst
        .serialize_fmu_state(&saved)
        .expect("fmi2SerializeFMUstate");
    assert!(!bytes.is_empty());
    let restored = inst
        .deserialize_fmu_state(&bytes)
        .expect("fmi2DeSerializeFMUstate");
    inst.set_fmu_state(&restored)
        .ok()
        .expect("fmi2SetFMUstate (deserialised)");
    let third = steps(&mut inst, n, 50);
    assert_eq!(
        third, first,
        "stepping from a deserialised FMU state differs"
    );

    Common::terminate(&mut inst).expect("fmi2Terminate");
}
