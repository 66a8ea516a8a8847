//! The variable table generated from `modelDescription.xml` agrees with the Rust model: the XML's
//! start values are the fragments' documented defaults, every compiled input and output is an FMU
//! variable, and `hsp linearize` gives eq. 1 of the paper.

use hydraulic_slewing_plate::fmi2::{Causality, Experiment, Values};
use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::loes::LoesParameters;
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::{idx, VARIABLES};

fn defaults() -> Parameters {
    Parameters::from_values(&Values::from_start(&VARIABLES), &Experiment::default()).unwrap()
}

fn with_preset(name: &str) -> Parameters {
    let mut values = Values::from_start(&VARIABLES);
    presets::apply(&mut values, name).unwrap();
    Parameters::from_values(&values, &Experiment::default()).unwrap()
}

#[test]
fn xml_start_values_are_the_documented_defaults() {
    let p = defaults();
    // Bit-for-bit: the XML carries the G(s)-consistent set with all its digits.
    assert_eq!(p.loes, LoesParameters::default());
    assert_eq!(p.controller, ControllerParameters::default());
}

#[test]
fn every_model_input_and_output_is_an_fmu_variable() {
    for preset in presets::PRESETS {
        let system = Assembled::new(&with_preset(preset.name)).unwrap();
        for name in system.compiled().input_names() {
            let v = VARIABLES.iter().find(|v| v.name == name).unwrap();
            assert_eq!(v.causality, Causality::Input, "{name}");
        }
        for name in system.compiled().output_names() {
            let v = VARIABLES.iter().find(|v| v.name == name).unwrap();
            assert_eq!(v.causality, Causality::Output, "{name}");
        }
    }
}

#[test]
fn linearisation_through_the_model_is_eq_1() {
    let p = with_preset("loes-motor");
    let system = Assembled::new(&p).unwrap();
    let lin = system
        .compiled()
        .linearize(&system.initial_state(), system.inputs());
    let (l, c) = (&p.loes, &p.controller);
    let k = l.k_sv * c.a1 * c.a2;
    // Eq. 1a with states (theta_a, p_b, q_3).
    let a = [
        [0.0, 1.0 / l.i_b, 0.0],
        [0.0, 0.0, l.d_m / l.c3],
        [-k * c.k_pot, -l.d_m / l.i_b, -1.0 / (l.r7 * l.c3)],
    ];
    for (i, row) in a.iter().enumerate() {
        for (j, want) in row.iter().enumerate() {
            let got = lin.a[(i, j)];
            assert!(
                (got - want).abs() <= 1e-12 * want.abs(),
                "A[{i}][{j}] = {got} vs {want}"
            );
        }
    }
    assert!((lin.b[(2, 0)] - k).abs() <= 1e-12 * k);
    let y_pot = lin.output_names.iter().position(|n| n == "y_pot").unwrap();
    assert_eq!(lin.c[(y_pot, 0)], c.k_pot);
}

#[test]
fn set_by_name_checks_like_the_fmu() {
    let mut values = Values::from_start(&VARIABLES);
    set_by_name(&mut values, "loes.C3", "6e-11").unwrap();
    assert_eq!(values.real(idx::LOES_C3), 6e-11);
    for (name, text) in [
        ("loes.C3", "-1"),
        ("loes.I_b", "0"),
        ("loes.C3", "abc"),
        ("y_pot", "1"),
        ("no.such", "1"),
        ("solver.method", "3"),
    ] {
        let err = set_by_name(&mut values, name, text).unwrap_err();
        assert!(err.contains(name), "{err}");
    }
}

#[test]
fn tolerance_of_setup_experiment_overrides_solver_rtol() {
    let values = Values::from_start(&VARIABLES);
    let exp = Experiment {
        tolerance: Some(1e-9),
        ..Experiment::default()
    };
    assert_eq!(Parameters::from_values(&values, &exp).unwrap().rtol, 1e-9);
    assert_eq!(defaults().rtol, values.real(idx::SOLVER_RTOL));
}
