//! FMI 2.0 Model Exchange through the exported C functions: the call sequence of an importer whose
//! own solver integrates the states, the contract (calls of the other interface, calls in the
//! wrong mode, NULL and size mismatches), and `fmi2GetDirectionalDerivative` against central
//! finite differences and against the linearisation `hsp linearize` prints.

// Matrix entries by row and column read clearest as index loops.
#![allow(clippy::needless_range_loop)]

#[path = "common/fmu.rs"]
mod fmu;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::*;
use hydraulic_slewing_plate::fmi2_exports::*;
use hydraulic_slewing_plate::fmu::{Causality, Experiment, Values};
use hydraulic_slewing_plate::model::assembly::{Assembled, STATE_PREFIX};
use hydraulic_slewing_plate::model::parameters::Parameters;
use hydraulic_slewing_plate::model::variables::{CONTINUOUS_STATES, VARIABLES};
use hydraulic_slewing_plate::solver::{Atol, Integrator, OdeSystem, SolverOptions};
use nalgebra::DMatrix;

const NX: usize = CONTINUOUS_STATES.len();

fn state_vrs() -> Vec<u32> {
    CONTINUOUS_STATES
        .iter()
        .map(|&(x, _)| VARIABLES[x].value_reference)
        .collect()
}

fn derivative_vrs() -> Vec<u32> {
    CONTINUOUS_STATES
        .iter()
        .map(|&(_, d)| VARIABLES[d].value_reference)
        .collect()
}

/// Value references of the Real variables of a causality, in XML order.
fn real_vrs(causality: Causality) -> Vec<u32> {
    VARIABLES
        .iter()
        .filter(|v| v.causality == causality && v.kind.type_name() == "Real")
        .map(|v| v.value_reference)
        .collect()
}

fn states(f: &Fmu) -> (Fmi2Status, Vec<f64>) {
    let mut x = vec![f64::NAN; NX];
    let s = unsafe { fmi2GetContinuousStates(f.c, x.as_mut_ptr(), NX) };
    (s, x)
}

fn set_states(f: &Fmu, x: &[f64]) -> Fmi2Status {
    unsafe { fmi2SetContinuousStates(f.c, x.as_ptr(), x.len()) }
}

fn derivatives(f: &Fmu) -> (Fmi2Status, Vec<f64>) {
    let mut dx = vec![f64::NAN; NX];
    let s = unsafe { fmi2GetDerivatives(f.c, dx.as_mut_ptr(), NX) };
    (s, dx)
}

fn nominals(f: &Fmu) -> Vec<f64> {
    let mut n = vec![f64::NAN; NX];
    assert_eq!(
        unsafe { fmi2GetNominalsOfContinuousStates(f.c, n.as_mut_ptr(), NX) },
        Fmi2Status::Ok
    );
    n
}

fn get_reals(f: &Fmu, vrs: &[u32]) -> Vec<f64> {
    let mut v = vec![f64::NAN; vrs.len()];
    assert_eq!(
        unsafe { fmi2GetReal(f.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) },
        Fmi2Status::Ok
    );
    v
}

fn directional(f: &Fmu, unknowns: &[u32], knowns: &[u32], dv: &[f64]) -> (Fmi2Status, Vec<f64>) {
    let mut dz = vec![f64::NAN; unknowns.len()];
    let s = unsafe {
        fmi2GetDirectionalDerivative(
            f.c,
            unknowns.as_ptr(),
            unknowns.len(),
            knowns.as_ptr(),
            knowns.len(),
            dv.as_ptr(),
            dz.as_mut_ptr(),
        )
    };
    (s, dz)
}

/// The paper's identification setup (preset loes-motor): the LOES on the motor alone, linear
/// amplifier.
fn loes_motor(f: &Fmu) {
    assert_eq!(f.set_integer("hydraulics.model", 1), Fmi2Status::Ok);
    assert_eq!(
        f.set_boolean("hydraulics.motor_coupled", false),
        Fmi2Status::Ok
    );
    assert_eq!(
        f.set_boolean("controller.saturation", false),
        Fmi2Status::Ok
    );
}

/// Initialised and in continuous-time mode.
fn running(f: &Fmu) {
    assert_eq!(f.init(0.0), Fmi2Status::Ok, "{}", f.last());
    let mut info = Fmi2EventInfo::default();
    assert_eq!(
        unsafe { fmi2NewDiscreteStates(f.c, &mut info) },
        Fmi2Status::Ok
    );
    assert_eq!(info.new_discrete_states_needed, FMI2_FALSE);
    assert_eq!(info.next_event_time_defined, FMI2_FALSE);
    assert_eq!(unsafe { fmi2EnterContinuousTimeMode(f.c) }, Fmi2Status::Ok);
}

/// The FMU's equations as an ODE for the crate's own integrator, an importer's solver: the
/// right-hand side through fmi2SetTime, fmi2SetContinuousStates and fmi2GetDerivatives, the
/// Jacobian column by column through fmi2GetDirectionalDerivative.
struct ThroughTheAbi<'a>(&'a Fmu);

impl OdeSystem for ThroughTheAbi<'_> {
    fn dim(&self) -> usize {
        NX
    }

    fn rhs(&self, t: f64, x: &[f64], dxdt: &mut [f64]) {
        assert_eq!(unsafe { fmi2SetTime(self.0.c, t) }, Fmi2Status::Ok);
        assert_eq!(set_states(self.0, x), Fmi2Status::Ok);
        let (s, dx) = derivatives(self.0);
        assert_eq!(s, Fmi2Status::Ok);
        dxdt.copy_from_slice(&dx);
    }

    fn jacobian(&self, t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> bool {
        assert_eq!(unsafe { fmi2SetTime(self.0.c, t) }, Fmi2Status::Ok);
        assert_eq!(set_states(self.0, x), Fmi2Status::Ok);
        let (xs, ds) = (state_vrs(), derivative_vrs());
        for (j, known) in xs.iter().enumerate() {
            let (s, column) = directional(self.0, &ds, &[*known], &[1.0]);
            assert_eq!(s, Fmi2Status::Ok);
            jac.column_mut(j).copy_from_slice(&column);
        }
        true
    }
}

/// An importer's solver integrates the LOES step through Model Exchange and lands where the
/// co-simulation interface does (both at rtol 1e-10; the difference is the solvers' error).
#[test]
fn model_exchange_integrates_the_loes_step_as_co_simulation_does() {
    let me = Fmu::model_exchange();
    loes_motor(&me);
    assert_eq!(me.set_real("r", 1.0), Fmi2Status::Ok);
    running(&me);
    let (s, x0) = states(&me);
    assert_eq!(s, Fmi2Status::Ok);
    assert!(x0.iter().all(|&x| x == 0.0), "the LOES starts at rest");
    let n = nominals(&me);
    let options = SolverOptions {
        rtol: 1e-10,
        atol: Atol::Vector(n.iter().map(|n| 1e-10 * n).collect()),
        ..SolverOptions::default()
    };
    let system = ThroughTheAbi(&me);
    let mut integrator = Integrator::new(options, 0.0, x0).unwrap();
    for k in 1..=50 {
        let t = 0.01 * k as f64;
        integrator.advance_to(&system, t).unwrap();
        assert_eq!(unsafe { fmi2SetTime(me.c, t) }, Fmi2Status::Ok);
        assert_eq!(set_states(&me, integrator.x()), Fmi2Status::Ok);
        let (mut event, mut terminate) = (FMI2_TRUE, FMI2_TRUE);
        let s = unsafe { fmi2CompletedIntegratorStep(me.c, FMI2_TRUE, &mut event, &mut terminate) };
        assert_eq!(
            (s, event, terminate),
            (Fmi2Status::Ok, FMI2_FALSE, FMI2_FALSE)
        );
    }
    let y_me = me.get_real("y_pot").1;

    let cs = Fmu::new();
    loes_motor(&cs);
    assert_eq!(cs.set_real("r", 1.0), Fmi2Status::Ok);
    assert_eq!(
        unsafe { fmi2SetupExperiment(cs.c, FMI2_TRUE, 1e-10, 0.0, FMI2_FALSE, 0.0) },
        Fmi2Status::Ok
    );
    assert_eq!(cs.enter(), Fmi2Status::Ok);
    assert_eq!(cs.exit(), Fmi2Status::Ok);
    for k in 0..50 {
        assert_eq!(cs.step(0.01 * k as f64, 0.01), Fmi2Status::Ok);
    }
    let y_cs = cs.get_real("y_pot").1;
    // The step has overshot and is settling (0.5 s): a value well away from 0 and 1.
    assert!((y_cs - 1.0).abs() < 0.2 && y_cs > 0.5, "{y_cs}");
    assert!((y_me - y_cs).abs() < 1e-8, "ME {y_me} vs CS {y_cs}");
    // The CS instance exposes its states too: the same state vector as ME's, to the same reach.
    let x_cs = get_reals(&cs, &state_vrs());
    let x_me = states(&me).1;
    for (k, (a, b)) in x_me.iter().zip(&x_cs).enumerate() {
        assert!((a - b).abs() <= 1e-7 * n[k], "x[{k}]: ME {a} vs CS {b}");
    }
}

/// fmi2GetContinuousStates hands out exactly the states the XML declares, which fmi2GetReal reads
/// too; after fmi2SetContinuousStates the derivatives and outputs follow the new states.
#[test]
fn the_states_are_the_declared_variables() {
    let f = Fmu::model_exchange();
    running(&f);
    let (s, x) = states(&f);
    assert_eq!(s, Fmi2Status::Ok);
    assert_eq!(x, get_reals(&f, &state_vrs()));
    let hub = CONTINUOUS_STATES
        .iter()
        .position(|&(x, _)| VARIABLES[x].name == "x.hub.theta")
        .unwrap();
    let mut moved = x.clone();
    moved[hub] = 0.25;
    assert_eq!(set_states(&f, &moved), Fmi2Status::Ok);
    assert_eq!(f.get_real("theta_hub").1, 0.25);
    assert_eq!(get_reals(&f, &state_vrs()), moved);
    let (s, dx) = derivatives(&f);
    assert_eq!(s, Fmi2Status::Ok);
    assert_eq!(dx, get_reals(&f, &derivative_vrs()));
    // The LOES states are not part of the complete system: derivative 0 whatever they hold.
    let loes = CONTINUOUS_STATES
        .iter()
        .position(|&(x, _)| VARIABLES[x].name == "x.loes.C3.q")
        .unwrap();
    moved[loes] = 3.0;
    assert_eq!(set_states(&f, &moved), Fmi2Status::Ok);
    let (_, dx2) = derivatives(&f);
    assert_eq!(dx2, dx);
    assert_eq!(dx[loes], 0.0);
    assert_eq!(states(&f).1[loes], 3.0);
}

#[test]
fn calls_of_the_other_interface_are_refused() {
    let cs = Fmu::new();
    assert_eq!(cs.init(0.0), Fmi2Status::Ok);
    assert_eq!(unsafe { fmi2SetTime(cs.c, 0.0) }, Fmi2Status::Error);
    assert!(cs.last().contains("fmi2SetTime") && cs.last().contains("Model Exchange"));
    let cs = Fmu::new();
    assert_eq!(cs.init(0.0), Fmi2Status::Ok);
    assert_eq!(derivatives(&cs).0, Fmi2Status::Error);
    assert!(
        cs.last().contains("instantiated for Co-Simulation"),
        "{}",
        cs.last()
    );

    let me = Fmu::model_exchange();
    running(&me);
    assert_eq!(me.step(0.0, 1e-3), Fmi2Status::Error);
    assert!(
        me.last().contains("fmi2DoStep") && me.last().contains("instantiated for Model Exchange")
    );
    let me = Fmu::model_exchange();
    running(&me);
    assert_eq!(me.last_successful_time().0, Fmi2Status::Error);
    let me = Fmu::model_exchange();
    running(&me);
    assert_eq!(me.get_state().0, Fmi2Status::Error);
    assert!(me.last().contains("canGetAndSetFMUstate"), "{}", me.last());
}

#[test]
fn calls_in_the_wrong_mode_are_refused() {
    // States are set in continuous-time mode only (FMI 2.0.4, figure 6).
    let f = Fmu::model_exchange();
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    let x = states(&f).1;
    assert_eq!(set_states(&f, &x), Fmi2Status::Error);
    assert!(
        f.last().contains("not allowed in state 'event mode'"),
        "{}",
        f.last()
    );
    // No derivatives before initialisation, no continuous-time mode twice.
    let f = Fmu::model_exchange();
    assert_eq!(derivatives(&f).0, Fmi2Status::Error);
    assert!(f.last().contains("'instantiated'"), "{}", f.last());
    let f = Fmu::model_exchange();
    running(&f);
    assert_eq!(
        unsafe { fmi2EnterContinuousTimeMode(f.c) },
        Fmi2Status::Error
    );
    // After an error only reset, the FMU-state functions and the getters.
    assert_eq!(unsafe { fmi2SetTime(f.c, 0.1) }, Fmi2Status::Error);
    assert_eq!(unsafe { fmi2Reset(f.c) }, Fmi2Status::Ok);
    running(&f);
    // Event mode and back, then the end.
    assert_eq!(unsafe { fmi2EnterEventMode(f.c) }, Fmi2Status::Ok);
    assert_eq!(unsafe { fmi2EnterContinuousTimeMode(f.c) }, Fmi2Status::Ok);
    assert_eq!(unsafe { fmi2Terminate(f.c) }, Fmi2Status::Ok);
    assert_eq!(derivatives(&f).0, Fmi2Status::Ok);
    assert_eq!(set_states(&f, &states(&f).1), Fmi2Status::Error);
}

#[test]
fn null_pointers_and_size_mismatches_are_refused_by_name() {
    let f = Fmu::model_exchange();
    running(&f);
    let s = unsafe { fmi2GetContinuousStates(f.c, std::ptr::null_mut(), NX) };
    assert_eq!(s, Fmi2Status::Error);
    assert!(f.last().contains("argument 'x' is NULL"), "{}", f.last());

    let f = Fmu::model_exchange();
    running(&f);
    let mut dx = vec![0.0; 3];
    assert_eq!(
        unsafe { fmi2GetDerivatives(f.c, dx.as_mut_ptr(), 3) },
        Fmi2Status::Error
    );
    assert!(
        f.last().contains(&format!(
            "has 3 elements, but the model has {NX} continuous states"
        )),
        "{}",
        f.last()
    );

    let f = Fmu::model_exchange();
    running(&f);
    let mut x = states(&f).1;
    x[5] = f64::NAN;
    assert_eq!(set_states(&f, &x), Fmi2Status::Error);
    let name = VARIABLES[CONTINUOUS_STATES[5].0].name;
    assert!(
        f.last().contains("x[5]") && f.last().contains(name),
        "{}",
        f.last()
    );

    let f = Fmu::model_exchange();
    running(&f);
    let mut z = [0.0];
    assert_eq!(
        unsafe { fmi2GetEventIndicators(f.c, z.as_mut_ptr(), 1) },
        Fmi2Status::Error
    );
    assert!(f.last().contains("no event indicators"), "{}", f.last());
    let f = Fmu::model_exchange();
    running(&f);
    assert_eq!(
        unsafe { fmi2GetEventIndicators(f.c, std::ptr::null_mut(), 0) },
        Fmi2Status::Ok
    );
}

#[test]
fn directional_derivative_arguments_are_checked_by_name() {
    let theta = Fmu::vr("theta_hub");
    let r = Fmu::vr("r");
    for (unknown, known, culprit) in [
        (99_999, r, "unknown value reference 99999"),
        (theta, 99_998, "unknown value reference 99998"),
        (theta, Fmu::vr("loes.C3"), "'loes.C3'"),
        (r, r, "unknown 'r'"),
        (Fmu::vr("solver.steps"), r, "'solver.steps'"),
    ] {
        let f = Fmu::model_exchange();
        running(&f);
        let (s, _) = directional(&f, &[unknown], &[known], &[1.0]);
        assert_eq!(s, Fmi2Status::Error, "{culprit}");
        assert!(f.last().contains(culprit), "{culprit}: {}", f.last());
    }
    let f = Fmu::new();
    assert_eq!(f.init(0.0), Fmi2Status::Ok);
    let mut dz = [0.0];
    let s = unsafe {
        fmi2GetDirectionalDerivative(f.c, &theta, 1, &r, 1, std::ptr::null(), dz.as_mut_ptr())
    };
    assert_eq!(s, Fmi2Status::Error);
    assert!(f.last().contains("'dvKnown' is NULL"), "{}", f.last());
}

#[test]
fn a_plate_larger_than_declared_is_refused_for_model_exchange_only() {
    let me = Fmu::model_exchange();
    assert_eq!(me.set_integer("plate.N", 6), Fmi2Status::Ok);
    assert_eq!(me.init(0.0), Fmi2Status::Error);
    assert!(
        me.last().contains("plate.N = 6") && me.last().contains("Co-Simulation"),
        "{}",
        me.last()
    );
    let cs = Fmu::new();
    assert_eq!(cs.set_integer("plate.N", 6), Fmi2Status::Ok);
    assert_eq!(cs.init(0.0), Fmi2Status::Ok);
    assert_eq!(cs.step(0.0, 1e-3), Fmi2Status::Ok);
}

/// A small deterministic generator of numbers in [-1, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Checks a Jacobian block from directional derivatives against central differences of `eval`
/// (unknowns as a function of one known): each entry to 1e-6 of the largest of its row, in units
/// scaled by the nominal values (the row's scale is what a solver's error test sees).
fn check_against_central_differences(
    what: &str,
    exact: &[Vec<f64>],
    step: &[f64],
    mut eval: impl FnMut(usize, f64) -> Vec<f64>,
) {
    let columns = exact.len();
    let mut fd = vec![];
    for j in 0..columns {
        let plus = eval(j, step[j]);
        let minus = eval(j, -step[j]);
        fd.push(
            plus.iter()
                .zip(&minus)
                .map(|(p, m)| (p - m) / (2.0 * step[j]))
                .collect::<Vec<_>>(),
        );
        eval(j, 0.0);
    }
    let rows = exact[0].len();
    for i in 0..rows {
        let scale = (0..columns)
            .map(|j| (exact[j][i] * step[j]).abs())
            .fold(0.0, f64::max);
        for j in 0..columns {
            let err = ((exact[j][i] - fd[j][i]) * step[j]).abs();
            assert!(
                err <= 1e-6 * scale,
                "{what}: row {i}, column {j}: exact {} vs central difference {} (row scale {scale})",
                exact[j][i],
                fd[j][i]
            );
        }
    }
}

/// At random states of the complete system (full servo valve, torsion bar, hub, plate), the
/// directional derivatives of the derivatives and outputs with respect to the states and inputs
/// equal central differences of fmi2GetDerivatives and fmi2GetReal.
#[test]
fn directional_derivatives_equal_central_differences_at_random_states() {
    let f = Fmu::model_exchange();
    // The amplifier's smooth limit is on (the default); a modest r keeps it near its knee.
    assert_eq!(f.set_real("r", 0.3), Fmi2Status::Ok);
    running(&f);
    let nominal = nominals(&f);
    let (xs, ds) = (state_vrs(), derivative_vrs());
    let inputs = real_vrs(Causality::Input);
    let outputs: Vec<u32> = real_vrs(Causality::Output)
        .into_iter()
        .filter(|&v| v != Fmu::vr("energy"))
        .collect();
    let rest = states(&f).1;
    let mut rng = Lcg(12345);
    for trial in 0..3 {
        let x: Vec<f64> = rest
            .iter()
            .zip(&nominal)
            .map(|(r, n)| r + 0.2 * n * rng.next())
            .collect();
        assert_eq!(set_states(&f, &x), Fmi2Status::Ok);
        let unknowns: Vec<u32> = ds.iter().chain(&outputs).copied().collect();
        let read = |f: &Fmu| {
            let (s, mut v) = derivatives(f);
            assert_eq!(s, Fmi2Status::Ok);
            v.extend(get_reals(f, &outputs));
            v
        };
        // With respect to the states.
        let exact: Vec<Vec<f64>> = xs
            .iter()
            .map(|&k| directional(&f, &unknowns, &[k], &[1.0]).1)
            .collect();
        let step: Vec<f64> = nominal.iter().map(|n| 1e-5 * n).collect();
        check_against_central_differences(
            &format!("trial {trial}, d/dx"),
            &exact,
            &step,
            |j, h| {
                let mut moved = x.clone();
                moved[j] += h;
                assert_eq!(set_states(&f, &moved), Fmi2Status::Ok);
                read(&f)
            },
        );
        // With respect to the inputs.
        let u = get_reals(&f, &inputs);
        let exact: Vec<Vec<f64>> = inputs
            .iter()
            .map(|&k| directional(&f, &unknowns, &[k], &[1.0]).1)
            .collect();
        let step = vec![1e-4; inputs.len()];
        check_against_central_differences(
            &format!("trial {trial}, d/du"),
            &exact,
            &step,
            |j, h| {
                let v = u[j] + h;
                assert_eq!(
                    unsafe { fmi2SetReal(f.c, &inputs[j], 1, &v) },
                    Fmi2Status::Ok
                );
                read(&f)
            },
        );
        // A combined direction is the sum of the columns (linearity of one forward pass).
        let dv: Vec<f64> = (0..NX).map(|_| rng.next()).collect();
        let combined = directional(&f, &unknowns, &xs, &dv).1;
        let columns: Vec<Vec<f64>> = xs
            .iter()
            .map(|&k| directional(&f, &unknowns, &[k], &[1.0]).1)
            .collect();
        for (i, c) in combined.iter().enumerate() {
            let sum: f64 = (0..NX).map(|j| columns[j][i] * dv[j]).sum();
            let scale: f64 = (0..NX).map(|j| (columns[j][i] * dv[j]).abs()).sum();
            assert!((c - sum).abs() <= 1e-12 * scale, "row {i}: {c} vs {sum}");
        }
    }
}

/// The default parameters, built as `hsp linearize` builds them.
fn default_system() -> Assembled {
    let p =
        Parameters::from_values(&Values::from_start(&VARIABLES), &Experiment::default()).unwrap();
    Assembled::new(&p).unwrap()
}

/// At rest, the directional derivatives of both interfaces are the linearisation A, B, C, D of
/// the library (bit for bit: the same dual-number pass), and `hsp linearize` prints the library's
/// A of the sliding motor.
#[test]
fn directional_derivatives_are_the_linearisation() {
    let system = default_system();
    let c = system.compiled();
    let lin = c.linearize(&system.initial_state(), system.inputs());
    let vr_of = |name: &str| Fmu::vr(name);
    let state_vr = |i: usize| vr_of(&format!("{STATE_PREFIX}{}", c.state_names()[i]));
    let derivative_vr = |i: usize| vr_of(&format!("der({STATE_PREFIX}{})", c.state_names()[i]));
    let me = Fmu::model_exchange();
    running(&me);
    let cs = Fmu::new();
    assert_eq!(cs.init(0.0), Fmi2Status::Ok);
    for j in 0..c.n_states() {
        let known = [state_vr(j)];
        let ds: Vec<u32> = (0..c.n_states()).map(derivative_vr).collect();
        let a = directional(&me, &ds, &known, &[1.0]).1;
        for i in 0..c.n_states() {
            assert_eq!(a[i], lin.a[(i, j)], "A[{i}][{j}]");
        }
        let ys: Vec<u32> = c.output_names().iter().map(|n| vr_of(n)).collect();
        for f in [&me, &cs] {
            let col = directional(f, &ys, &known, &[1.0]).1;
            for i in 0..c.n_outputs() {
                assert_eq!(col[i], lin.c[(i, j)], "C[{i}][{j}]");
            }
        }
    }
    for j in 0..c.n_inputs() {
        let known = [vr_of(&c.input_names()[j])];
        let ds: Vec<u32> = (0..c.n_states()).map(derivative_vr).collect();
        let b = directional(&me, &ds, &known, &[1.0]).1;
        let ys: Vec<u32> = c.output_names().iter().map(|n| vr_of(n)).collect();
        let d = directional(&cs, &ys, &known, &[1.0]).1;
        for i in 0..c.n_states() {
            assert_eq!(b[i], lin.b[(i, j)], "B[{i}][{j}]");
        }
        for i in 0..c.n_outputs() {
            assert_eq!(d[i], lin.d[(i, j)], "D[{i}][{j}]");
        }
    }

    // The CLI prints the A of the vane motor sliding (its seal friction's Coulomb and breakaway
    // parts left out, `Parameters::sliding`), the library's to the bit (JSON numbers round-trip
    // exactly).
    let p = Parameters::from_values(&Values::from_start(&VARIABLES), &Experiment::default())
        .unwrap()
        .sliding();
    let sliding = Assembled::new(&p).unwrap();
    let lin_sliding = sliding
        .compiled()
        .linearize(&sliding.initial_state(), sliding.inputs());
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hsp"))
        .arg("linearize")
        .output()
        .unwrap();
    assert!(out.status.success());
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let names: Vec<&str> = json["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    assert_eq!(names, c.state_names());
    for (i, row) in json["A"].as_array().unwrap().iter().enumerate() {
        for (j, a) in row.as_array().unwrap().iter().enumerate() {
            assert_eq!(
                lin_sliding.a[(i, j)],
                a.as_f64().unwrap(),
                "hsp linearize A[{i}][{j}]"
            );
        }
    }
}

/// The stored energy's directional derivative is its gradient (the co-energy variables): equal
/// to the central difference of the energy output.
#[test]
fn energy_derivative_is_its_gradient() {
    let f = Fmu::model_exchange();
    running(&f);
    let nominal = nominals(&f);
    let mut rng = Lcg(777);
    let x: Vec<f64> = states(&f)
        .1
        .iter()
        .zip(&nominal)
        .map(|(r, n)| r + 0.2 * n * rng.next())
        .collect();
    assert_eq!(set_states(&f, &x), Fmi2Status::Ok);
    let energy = [Fmu::vr("energy")];
    let exact: Vec<Vec<f64>> = state_vrs()
        .iter()
        .map(|&k| directional(&f, &energy, &[k], &[1.0]).1)
        .collect();
    let step: Vec<f64> = nominal.iter().map(|n| 1e-5 * n).collect();
    check_against_central_differences("dE/dx", &exact, &step, |j, h| {
        let mut moved = x.clone();
        moved[j] += h;
        assert_eq!(set_states(&f, &moved), Fmi2Status::Ok);
        get_reals(&f, &energy)
    });
}

/// The derivatives read after fmi2Terminate are those of the last states set, as before it.
#[test]
fn derivatives_after_terminate_follow_the_last_states() {
    let moved = |f: &Fmu| {
        running(f);
        let mut x = states(f).1;
        let hub = CONTINUOUS_STATES
            .iter()
            .position(|&(x, _)| VARIABLES[x].name == "x.torsion_bar.k.q")
            .unwrap();
        x[hub] = 1e-3;
        assert_eq!(set_states(f, &x), Fmi2Status::Ok);
    };
    let (a, b) = (Fmu::model_exchange(), Fmu::model_exchange());
    moved(&a);
    moved(&b);
    let before = derivatives(&a).1;
    assert_eq!(unsafe { fmi2Terminate(b.c) }, Fmi2Status::Ok);
    let (s, after) = derivatives(&b);
    assert_eq!(s, Fmi2Status::Ok);
    assert_eq!(after, before);
    let rest = Fmu::model_exchange();
    running(&rest);
    assert_ne!(after, derivatives(&rest).1);
}

/// An evaluation of Model Exchange gives the derivatives the Co-Simulation's integrator advances
/// (the library's right-hand side, to the bit) and leaves the outputs until they are read: every
/// Real output and the stored energy read after fmi2SetContinuousStates are, to the bit, what the
/// library writes for that state all at once; and they follow the states from one evaluation to
/// the next, including after fmi2GetDirectionalDerivative, which needs every value.
#[test]
fn evaluations_give_the_integrators_derivatives_and_the_outputs_when_read() {
    let system = default_system();
    let f = Fmu::model_exchange();
    running(&f);
    let (_, x0) = states(&f);
    let outputs: Vec<u32> = real_vrs(Causality::Output)
        .into_iter()
        .chain([Fmu::vr("energy")])
        .collect();
    let declared = |x: &[f64]| {
        // The compiled state from the declared one, as the FMU gathers it.
        let mut values = Values::from_start(&VARIABLES);
        for (&(state, _), &v) in CONTINUOUS_STATES.iter().zip(x) {
            values.set_real(state, v);
        }
        let mut compiled = Vec::new();
        system.state_from_values(&values, &mut compiled);
        (values, compiled)
    };
    let mut x = x0.clone();
    for k in 0..4 {
        // Away from rest, further each time: the valve's states, the hub, the plate.
        for (i, v) in x.iter_mut().enumerate() {
            *v = x0[i] + (k as f64 + 1.0) * 1e-3 * (1.0 + 0.1 * i as f64) * nominals(&f)[i];
        }
        assert_eq!(set_states(&f, &x), Fmi2Status::Ok);
        let (values, compiled) = declared(&x);
        let mut rhs = vec![0.0; compiled.len()];
        system.rhs(0.0, &compiled, &mut rhs);
        let (s, dx) = derivatives(&f);
        assert_eq!(s, Fmi2Status::Ok);
        for (i, slot) in system.state_slots().iter().enumerate() {
            if let Some(slot) = *slot {
                assert_eq!(dx[slot].to_bits(), rhs[i].to_bits(), "row {i}, point {k}");
            }
        }
        let mut eager = values;
        system.write_outputs(&compiled, &mut eager);
        if k == 2 {
            // Every value at once (the directional derivatives read them all).
            let (s, _) = directional(&f, &[Fmu::vr("y_pot")], &[Fmu::vr("r")], &[1.0]);
            assert_eq!(s, Fmi2Status::Ok);
        }
        let read = get_reals(&f, &outputs);
        for (&vr, v) in outputs.iter().zip(&read) {
            let i = VARIABLES
                .iter()
                .position(|w| w.value_reference == vr)
                .unwrap();
            assert_eq!(
                v.to_bits(),
                eager.real(i).to_bits(),
                "{} at point {k}",
                VARIABLES[i].name
            );
        }
        // The derivatives again, after the outputs: unchanged.
        assert_eq!(derivatives(&f).1, dx);
    }
}
