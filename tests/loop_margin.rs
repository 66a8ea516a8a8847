//! The loop-margin monitor (`src/model/margin.rs`) through the C ABI: at initialisation the FMU
//! writes the least damped mode at rest into `margin.zeta` and `margin.f` and warns, once, when
//! the loop is unstable or damped less than `plate.zeta / 3`. The paper's voltage-driven loop
//! without pressure feedback on the rig-sized plant is the case it is for: unstable with
//! `servo_valve.beta` = 0.7 GPa or `plate.zeta` = 0.005; the default loop is not.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;

/// The paper's loop: the voltage-driven coil, no pressure feedback.
const PAPER_LOOP: &[(&str, Setting)] = &[
    ("servo_valve.drive", Setting::Integer(1)),
    ("controller.k_pl", Setting::Real(0.0)),
];

#[derive(Clone, Copy)]
enum Setting {
    Real(f64),
    Integer(i32),
    Boolean(bool),
}

/// Initialises the FMU with `sets` (reading `margin.zeta` once in initialisation mode, as an
/// importer reading the initial unknowns does); returns the margin and the warnings logged.
fn initialise(sets: &[(&str, Setting)]) -> (f64, f64, Vec<String>) {
    let fmu = Fmu::new();
    assert_eq!(fmu.setup(0.0), Fmi2Status::Ok);
    for &(n, v) in sets {
        let status = match v {
            Setting::Real(x) => fmu.set_real(n, x),
            Setting::Integer(k) => fmu.set_integer(n, k),
            Setting::Boolean(b) => fmu.set_boolean(n, b),
        };
        assert_eq!(status, Fmi2Status::Ok, "{n}");
    }
    assert_eq!(fmu.enter(), Fmi2Status::Ok);
    assert_eq!(fmu.get_real("margin.zeta").0, Fmi2Status::Ok);
    assert_eq!(fmu.exit(), Fmi2Status::Ok);
    let (s1, zeta) = fmu.get_real("margin.zeta");
    let (s2, f) = fmu.get_real("margin.f");
    assert_eq!((s1, s2), (Fmi2Status::Ok, Fmi2Status::Ok));
    let warnings = fmu
        .log()
        .into_iter()
        .filter(|(s, _)| *s == Fmi2Status::Warning)
        .map(|(_, m)| m)
        .collect();
    (zeta, f, warnings)
}

fn with_paper_loop(extra: &[(&'static str, Setting)]) -> Vec<(&'static str, Setting)> {
    PAPER_LOOP.iter().chain(extra).copied().collect()
}

#[test]
fn the_default_loop_is_damped_and_does_not_warn() {
    let (zeta, f, warnings) = initialise(&[]);
    println!("default: least damped {f:.3} Hz, zeta {zeta:.4}");
    assert!(warnings.is_empty(), "{warnings:?}");
    // The rule of the design (a third of plate.zeta = 0.02): here the structure's own modes.
    assert!(zeta >= 0.02 / 3.0, "{zeta}");
    assert!(f > 0.0);
}

#[test]
fn the_papers_loop_with_soft_oil_or_little_damping_warns_once_that_it_is_unstable() {
    for extra in [
        ("servo_valve.beta", Setting::Real(0.7e9)),
        ("plate.zeta", Setting::Real(0.005)),
    ] {
        let (zeta, f, warnings) = initialise(&with_paper_loop(&[extra]));
        println!("{}: {f:.3} Hz, zeta {zeta:.4}: {warnings:?}", extra.0);
        assert!(zeta < 0.0, "{zeta}");
        // The hub-on-bar mode, 3.2 to 3.3 Hz.
        assert!((3.0..3.5).contains(&f), "{f}");
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        let w = &warnings[0];
        assert!(w.contains("loop margin") && w.contains("unstable"), "{w}");
        assert!(w.contains(&format!("{f:.3} Hz")), "{w}");
        assert!(
            w.contains("servo_valve.beta") && w.contains("controller.k_pl"),
            "{w}"
        );
    }
}

#[test]
fn the_papers_loop_at_the_defaults_warns_that_it_is_poorly_damped() {
    let (zeta, f, warnings) = initialise(PAPER_LOOP);
    println!("paper's loop: {f:.3} Hz, zeta {zeta:.4}: {warnings:?}");
    assert!(zeta > 0.0 && zeta < 0.02 / 3.0, "{zeta}");
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("poorly damped"), "{}", warnings[0]);
}

/// With an external controller the FMU's loop is open: the margin is the plant's, no warning.
#[test]
fn an_external_controller_gets_no_warning() {
    let (_, _, warnings) = initialise(&with_paper_loop(&[
        ("servo_valve.beta", Setting::Real(0.7e9)),
        ("controller.external", Setting::Boolean(true)),
    ]));
    assert!(warnings.is_empty(), "{warnings:?}");
}
