//! The complete system as the FMU ships it (preset `complete`, the FMU's start values): the
//! default move through the C ABI stays inside the model's range and settles; a 2 V step of the
//! reference leaves it and the FMU says so; the default plant has one hub angle and its slowest
//! coupled pair is converged in the number of beam functions.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::Fmu;
use hydraulic_slewing_plate::eigen;
use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::fragments::controller::LINEAR_FRACTION;
use hydraulic_slewing_plate::fragments::plate::Formulation;
use hydraulic_slewing_plate::fragments::validity::Monitor;
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::VARIABLES;

/// The recorded series of a run through `fmi2DoStep` at 5 ms.
struct Run {
    t: Vec<f64>,
    series: Vec<Vec<f64>>,
    names: Vec<&'static str>,
    warnings: Vec<String>,
}

impl Run {
    fn col(&self, name: &str) -> &[f64] {
        &self.series[self.names.iter().position(|n| *n == name).unwrap()]
    }
    fn peak(&self, name: &str) -> f64 {
        self.col(name).iter().fold(0.0, |m, v| m.max(v.abs()))
    }
}

/// Runs the FMU's defaults with `sets` (parameters, or the input `r`) to `stop`.
fn run(sets: &[(&str, f64)], stop: f64, names: &[&'static str]) -> Run {
    let fmu = Fmu::new();
    assert_eq!(fmu.setup(0.0), Fmi2Status::Ok);
    for &(n, v) in sets {
        assert_eq!(fmu.set_real(n, v), Fmi2Status::Ok, "{n}");
    }
    assert_eq!(fmu.enter(), Fmi2Status::Ok);
    assert_eq!(fmu.exit(), Fmi2Status::Ok);
    let h = 0.005;
    let n = (stop / h).round() as usize;
    let mut run = Run {
        t: Vec::new(),
        series: vec![Vec::new(); names.len()],
        names: names.to_vec(),
        warnings: Vec::new(),
    };
    for k in 0..n {
        assert_eq!(fmu.step(k as f64 * h, h), Fmi2Status::Ok, "{}", fmu.last());
        run.t.push((k + 1) as f64 * h);
        for (s, n) in run.series.iter_mut().zip(names) {
            let (status, v) = fmu.get_real(n);
            assert_eq!(status, Fmi2Status::Ok);
            s.push(v);
        }
    }
    run.warnings = fmu
        .log()
        .into_iter()
        .filter(|(s, _)| *s == Fmi2Status::Warning)
        .map(|(_, m)| m)
        .collect();
    run
}

const RECORDED: &[&str] = &[
    "theta_motor",
    "theta_hub",
    "x.torsion_bar.k.q",
    "plate.w_tip_ratio",
    "plate.stress",
    "torsion_bar.stress",
    "hub.omega_ratio",
    "controller.e_out",
    "servo_valve.x_v",
];

fn start(name: &str) -> f64 {
    Values::from_start(&VARIABLES).real(VARIABLES.iter().position(|v| v.name == name).unwrap())
}

/// The default move (30 deg over 2 s from t = 0.5 s), as an importer that just presses
/// "simulate" runs it: the thresholds are the issue's acceptance figures for a credible default.
#[test]
fn the_default_move_settles_inside_the_models_range() {
    let r = run(&[], 6.0, RECORDED);
    let target = start("reference.angle");
    let end = start("reference.t_start") + start("reference.duration");
    assert!((target.to_degrees() - 30.0).abs() < 1e-12 && end == 2.5);
    let hub = r.col("theta_hub");
    let overshoot = (r.peak("theta_hub") - target) / target;
    // Settling as docs/model.md defines it ("Measures of a manoeuvre"): from the move's end, into
    // 2 % of the move around its target, and still inside at the end of the run.
    let first = r.t.iter().position(|&t| t >= end).unwrap();
    let last_out = (first..hub.len())
        .rev()
        .find(|&i| (hub[i] - target).abs() > 0.02 * target);
    assert!(
        last_out.is_none_or(|i| i + 1 < hub.len()),
        "the hub is not settled"
    );
    let settled_from = last_out.map_or(end, |i| r.t[i + 1]);
    let sigma_y = start("plate.sigma_y");
    let tau_y = start("torsion_bar.tau_y");
    println!(
        "hub overshoot {:.3} %, settled (2 %) from {settled_from:.3} s, the move ending at {end} s; peak w/a {:.4}, plate {:.2} MPa, bar {:.2} MPa, (omega/omega_1)^2 {:.4}, |e_out| {:.3} V, |x_v| {:.4} mm",
        overshoot * 100.0,
        r.peak("plate.w_tip_ratio"),
        r.peak("plate.stress") * 1e-6,
        r.peak("torsion_bar.stress") * 1e-6,
        r.peak("hub.omega_ratio").powi(2),
        r.peak("controller.e_out"),
        r.peak("servo_valve.x_v") * 1e3
    );
    assert!(overshoot < 0.02, "hub overshoot {overshoot}");
    assert!(settled_from < end + 1.5, "hub settles at {settled_from} s");
    assert!(r.peak("plate.w_tip_ratio") < 0.05);
    assert!(r.peak("plate.stress") < 0.1 * sigma_y);
    // Below the plate's fatigue threshold too (half of 96.5 MPa): no plate-stress warning (the
    // run has none at all, below).
    assert!(r.peak("plate.stress") < 0.5 * start("plate.sigma_f"));
    assert!(r.peak("torsion_bar.stress") < 0.1 * tau_y);
    // No limit reached: the amplifier stays in its linear range, the spool off its stops.
    assert!(r.peak("controller.e_out") < LINEAR_FRACTION * start("controller.e_max"));
    assert!(r.peak("servo_valve.x_v") < 0.95 * start("servo_valve.x_v_max"));
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    // One hub angle: the bar's far end (motor angle less the twist) is the hub's angle. Both
    // integrate the same speed, so they differ only by the integrator's error.
    let far_end_gap = r
        .col("theta_motor")
        .iter()
        .zip(r.col("x.torsion_bar.k.q"))
        .zip(hub)
        .fold(0.0f64, |m, ((a, q), h)| m.max((a - q - h).abs()));
    assert!(
        far_end_gap < 1e-9,
        "bar end and hub differ by {far_end_gap} rad"
    );
}

/// The paper's 2 V step of the reference, the generator off: the plate leaves linear theory, and
/// the FMU warns once per quantity, naming it, while the step itself succeeds.
#[test]
fn the_2_volt_step_warns_that_it_leaves_the_models_range() {
    let r = run(&[("reference.angle", 0.0), ("r", 2.0)], 3.0, RECORDED);
    println!("{:#?}", r.warnings);
    assert!(r.peak("plate.w_tip_ratio") > 0.1);
    let named = |m: Monitor| {
        r.warnings
            .iter()
            .filter(|w| w.contains(m.variable()))
            .count()
    };
    // The tip swings to w/a 0.38 and the hub spins at (Omega/omega_1)^2 0.14 (both past 0.1);
    // the rig-sized motor stalls at 140 N m, which the 20 mm bar carries at 0.24 of its yield.
    // The plate's nominal root stress passes half of 6061-T6's fatigue strength (96.5 MPa at
    // 5e8 reversed cycles, concentrated twice at the clamped root: 48.25 MPa), though not half
    // of its yield (138 MPa): the plate's monitor warns.
    assert_eq!(named(Monitor::TipRatio), 1, "{:?}", r.warnings);
    assert_eq!(named(Monitor::SpinRatio), 1, "{:?}", r.warnings);
    assert_eq!(named(Monitor::BarStress), 0, "{:?}", r.warnings);
    let sigma_f = start("plate.sigma_f");
    assert!(
        r.peak("plate.stress") > 0.5 * sigma_f
            && r.peak("plate.stress") < 0.5 * start("plate.sigma_y")
    );
    assert_eq!(named(Monitor::PlateStress), 1, "{:?}", r.warnings);
    assert!(r.warnings.iter().all(|w| w.contains(" t = ")));
}

/// In the paper formulation the hub inertia and the bar's far end turn by different angles
/// (`theta` and `theta + sum t_n eta_n`): the reason it is not the default plant.
#[test]
fn the_paper_formulation_gives_the_hub_two_angles() {
    let fmu = Fmu::new();
    assert_eq!(fmu.setup(0.0), Fmi2Status::Ok);
    assert_eq!(fmu.set_integer("plate.formulation", 1), Fmi2Status::Ok);
    assert_eq!(fmu.set_real("reference.angle", 0.0), Fmi2Status::Ok);
    assert_eq!(fmu.set_real("r", 2.0), Fmi2Status::Ok);
    assert_eq!(fmu.enter(), Fmi2Status::Ok);
    assert_eq!(fmu.exit(), Fmi2Status::Ok);
    let mut gap = 0.0f64;
    for k in 0..300 {
        assert_eq!(fmu.step(k as f64 * 0.005, 0.005), Fmi2Status::Ok);
        let v = |n: &str| fmu.get_real(n).1;
        gap = gap.max((v("theta_motor") - v("x.torsion_bar.k.q") - v("theta_hub")).abs());
    }
    println!("largest gap between the bar's far end and the hub: {gap} rad");
    assert!(gap > 0.1, "{gap}");
}

/// The slowest coupled pair of the complete system (consistent formulation): converged in the
/// number of beam functions along the plate, to 0.5 % from N = 3 to N = 10.
#[test]
fn the_slowest_coupled_pair_is_converged() {
    let slowest = |n: usize| {
        let mut values = Values::from_start(&VARIABLES);
        set_by_name(&mut values, "plate.N", &n.to_string()).unwrap();
        let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
        assert_eq!(p.plate.formulation, Formulation::Consistent);
        let sys = Assembled::new(&p).unwrap();
        let lin = sys.compiled().linearize(&sys.initial_state(), sys.inputs());
        let eig = eigen::eigenvalues(&lin.a);
        // The slowest oscillatory pair: the smallest |lambda| with an imaginary part.
        eig.iter()
            .filter(|l| l.im > 1e-3)
            .map(|l| l.norm())
            .fold(f64::INFINITY, f64::min)
    };
    let (w3, w10) = (slowest(3), slowest(10));
    println!("slowest pair |lambda|: N = 3 {w3:.5}, N = 10 {w10:.5} rad/s");
    assert!(((w3 - w10) / w10).abs() < 5e-3, "{w3} vs {w10}");
}
