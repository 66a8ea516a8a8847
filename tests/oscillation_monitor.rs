//! The oscillation monitor (`src/model/oscillation.rs`) through the C ABI, at 5 ms communication
//! steps: the paper's voltage-driven loop without pressure feedback on the rig-sized plant with
//! little vane leakage (`servo_valve.R_leak` = 1e12, 0.6 L/min at 100 bar) limit-cycles after the
//! default move, and the FMU says so once, with the frequency of the growing mode; the default
//! move, the 2 V step and the paper's presets settle and get no such warning.

#[path = "common/fmu.rs"]
mod fmu;

use fmu::Fmu;
use hydraulic_slewing_plate::fmi2::ffi::Fmi2Status;
use hydraulic_slewing_plate::fmu::Kind;
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::VARIABLES;

/// Runs the FMU with the preset and the settings `sets` (text, as `hsp run --set`) to `stop`;
/// returns the warnings logged.
fn warnings(preset: &str, sets: &[(&str, &str)], stop: f64) -> Vec<String> {
    let fmu = Fmu::new();
    assert_eq!(fmu.setup(0.0), Fmi2Status::Ok);
    let settings = presets::preset(preset).unwrap().settings.iter().copied();
    for (name, text) in settings.chain(sets.iter().copied()) {
        let var = VARIABLES.iter().find(|v| v.name == name).unwrap();
        let status = match var.kind {
            Kind::Real { .. } => fmu.set_real(name, text.parse().unwrap()),
            Kind::Boolean { .. } => fmu.set_boolean(name, text == "true"),
            _ => fmu.set_integer(name, text.parse().unwrap()),
        };
        assert_eq!(status, Fmi2Status::Ok, "{name} = {text}");
    }
    assert_eq!(fmu.enter(), Fmi2Status::Ok);
    assert_eq!(fmu.exit(), Fmi2Status::Ok);
    let h = 0.005;
    for k in 0..(stop / h).round() as usize {
        assert_eq!(fmu.step(k as f64 * h, h), Fmi2Status::Ok, "{}", fmu.last());
    }
    fmu.log()
        .into_iter()
        .filter(|(s, _)| *s == Fmi2Status::Warning)
        .map(|(_, m)| m)
        .collect()
}

fn oscillations(w: &[String]) -> Vec<&String> {
    w.iter().filter(|m| m.starts_with("oscillation")).collect()
}

#[test]
fn the_papers_loop_with_little_leakage_limit_cycles_and_is_caught() {
    let w = warnings(
        "complete",
        &[
            // the previous design: the paper's loop, no seal friction, no added mass
            ("servo_valve.drive", "1"),
            ("controller.k_pl", "0"),
            ("servo_valve.T_c", "0"),
            ("servo_valve.T_s", "0"),
            ("plate.Ca", "0"),
            ("servo_valve.R_leak", "1e12"),
        ],
        30.0,
    );
    println!("{w:#?}");
    let found = oscillations(&w);
    assert_eq!(found.len(), 1, "{w:?}");
    // "at 3.53 Hz": the growing hub-on-bar mode (the loop margin names 3.536 Hz at rest; an
    // outside review measured the grown limit cycle at 3.3 Hz): within 10 % of 3.3 Hz.
    let f: f64 = found[0]
        .split(" at ")
        .nth(1)
        .and_then(|s| s.split(" Hz").next())
        .unwrap()
        .parse()
        .unwrap();
    assert!((f - 3.3).abs() < 0.1 * 3.3, "{f}");
    // The loop margin warned at initialisation too.
    assert!(w.iter().any(|m| m.starts_with("loop margin")), "{w:?}");
}

#[test]
fn the_default_move_and_the_2_volt_step_settle_without_an_oscillation_warning() {
    assert!(warnings("complete", &[], 30.0).is_empty());
    let step = warnings("complete", &[("reference.angle", "0"), ("r", "2")], 20.0);
    assert!(oscillations(&step).is_empty(), "{step:?}");
}

#[test]
fn the_papers_presets_settle_without_an_oscillation_warning() {
    for preset in [
        "complete-hub-locked",
        "servo-valve-motor",
        "loes-motor",
        "paper-eq16",
        "paper-fig9b",
        "paper-fig10",
    ] {
        let w = warnings(preset, &[("r", "1")], 20.0);
        assert!(oscillations(&w).is_empty(), "{preset}: {w:?}");
    }
}
