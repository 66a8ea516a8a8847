//! The model description is the one source of the parameters' rules (issue 41, item 7): the
//! fragments check their values against the table `build.rs` generates from it
//! (`fragments::rules`), by the FMU variable's name, and keep no list of their own. Each
//! fragment's `named()` maps every one of its values to its variable; these tests check that the
//! map covers the variables of the fragment's prefix and that a value outside the XML's rule is
//! refused by the fragment itself, naming the variable and the rule.

use std::collections::BTreeSet;

use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::plate::{PlateParameters, MAX_FUNCTIONS};
use hydraulic_slewing_plate::fragments::reference::MoveParameters;
use hydraulic_slewing_plate::fragments::rules::{self, RULES};
use hydraulic_slewing_plate::fragments::servo_valve::ServoValveParameters;

/// The numeric parameters of the XML whose name starts with one of `prefixes`.
fn parameters_of(prefixes: &[&str]) -> BTreeSet<&'static str> {
    RULES
        .iter()
        .map(|(name, _)| *name)
        .filter(|name| prefixes.iter().any(|p| name.starts_with(p)))
        .collect()
}

fn names(named: &[(&'static str, f64)]) -> BTreeSet<&'static str> {
    named.iter().map(|(name, _)| *name).collect()
}

#[test]
fn each_fragment_names_every_parameter_of_its_prefix() {
    let sv = ServoValveParameters::default();
    assert_eq!(names(&sv.named()), parameters_of(&["servo_valve."]));
    let c = ControllerParameters::default();
    assert_eq!(names(&c.named()), parameters_of(&["controller."]));
    let r = MoveParameters::default();
    assert_eq!(names(&r.named()), parameters_of(&["reference."]));
    // The plate's material limits (`plate.sigma_y`, `plate.sigma_f`) belong to the validity
    // monitors, not to the plate's model.
    let p = PlateParameters::default();
    let mut plate = parameters_of(&["plate.", "hub.I_H"]);
    plate.remove("plate.sigma_y");
    plate.remove("plate.sigma_f");
    assert_eq!(names(&p.named()), plate);
}

#[test]
fn the_defaults_meet_the_descriptions_rules() {
    ServoValveParameters::default().validate().unwrap();
    ServoValveParameters::voltage_driven().validate().unwrap();
    ControllerParameters::default().validate().unwrap();
    ControllerParameters::paper().validate().unwrap();
    MoveParameters::default().validate().unwrap();
    PlateParameters::default().validate().unwrap();
}

#[test]
fn a_fragment_refuses_what_the_description_refuses() {
    // `<Positive>`: G_i has min="0" and is on the list (the disagreement the issue found).
    let e = ServoValveParameters {
        g_i: 0.0,
        ..Default::default()
    }
    .validate()
    .unwrap_err();
    assert!(
        e.contains("servo_valve.G_i") && e.contains("<Positive>"),
        "{e}"
    );
    // `max`: Poisson's ratio below 0.5.
    let e = PlateParameters {
        nu: 0.5,
        ..Default::default()
    }
    .validate()
    .unwrap_err();
    assert!(
        e.contains("plate.nu") && e.contains("at most 0.4999"),
        "{e}"
    );
    // `min`: a structural damping ratio of zero is allowed, a negative one is not.
    assert!(PlateParameters {
        zeta: 0.0,
        ..Default::default()
    }
    .validate()
    .is_ok());
    let e = PlateParameters {
        zeta: -0.01,
        ..Default::default()
    }
    .validate()
    .unwrap_err();
    assert!(e.contains("plate.zeta") && e.contains("at least 0"), "{e}");
    let e = ControllerParameters {
        f_pl: 0.0,
        ..Default::default()
    }
    .validate()
    .unwrap_err();
    assert!(e.contains("controller.f_pl"), "{e}");
    let e = MoveParameters {
        duration: f64::NAN,
        ..Default::default()
    }
    .validate()
    .unwrap_err();
    assert!(
        e.contains("reference.duration") && e.contains("finite"),
        "{e}"
    );
    // The relations the XML cannot state stay with the fragment.
    let sv = ServoValveParameters::default();
    let e = ServoValveParameters {
        p_tank: sv.p_supply,
        ..sv.clone()
    }
    .validate()
    .unwrap_err();
    assert!(e.contains("servo_valve.p_tank"), "{e}");
    let e = ServoValveParameters {
        t_s: 0.5 * sv.t_c,
        ..sv
    }
    .validate()
    .unwrap_err();
    assert!(e.contains("servo_valve.T_s"), "{e}");
}

#[test]
fn the_plate_sizes_range_is_the_beam_functions_tested_range() {
    // Two facts that must agree: the XML's max of plate.N and plate.M, and the number of beam
    // functions the plate model is tested to (tests/plate_modes.rs).
    for name in ["plate.N", "plate.M"] {
        let rule = rules::rule(name).unwrap();
        assert_eq!(rule.min, Some(1.0), "{name}");
        assert_eq!(rule.max, Some(MAX_FUNCTIONS as f64), "{name}");
    }
}
