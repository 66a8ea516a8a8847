//! The variable table generated from `modelDescription.xml` agrees with the Rust model: the XML's
//! start values are the fragments' documented defaults, every compiled input and output is an FMU
//! variable, and `hsp linearize` gives eq. 1 of the paper.

use std::collections::BTreeMap;

use hydraulic_slewing_plate::fmu::{Causality, Experiment, Values};
use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::loes::LoesParameters;
use hydraulic_slewing_plate::fragments::plate::PlateParameters;
use hydraulic_slewing_plate::fragments::reference::MoveParameters;
use hydraulic_slewing_plate::fragments::servo_valve::ServoValveParameters;
use hydraulic_slewing_plate::fragments::validity::Limits;
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::{idx, VARIABLES};

// The project's one reader of the XML (build.rs and hsp read it through the same file).
#[path = "../tools/model_description.rs"]
#[allow(dead_code)]
mod model_description;

use model_description::ModelDescription;

fn model_description() -> ModelDescription {
    let xml = std::fs::read_to_string("modelDescription/modelDescription.xml").unwrap();
    ModelDescription::parse(&xml).unwrap()
}

fn defaults() -> Parameters {
    Parameters::from_values(&Values::from_start(&VARIABLES), &Experiment::default()).unwrap()
}

fn with_preset(name: &str) -> Parameters {
    let mut values = Values::from_start(&VARIABLES);
    presets::apply(&mut values, name).unwrap();
    Parameters::from_values(&values, &Experiment::default()).unwrap()
}

/// Every fragment's Rust default is the XML's start values, bit for bit, so that a library user
/// (the fragments alone) and an FMU user start from the same model: the LOES (the
/// G(s)-consistent set with all its digits), the servo valve, the controller, the move, the
/// material limits and the plate with its hub. A parameter added to one side only fails here.
#[test]
fn xml_start_values_are_the_documented_defaults() {
    let p = defaults();
    assert_eq!(p.loes, LoesParameters::default());
    assert_eq!(p.servo_valve, ServoValveParameters::default());
    assert_eq!(p.controller, ControllerParameters::default());
    assert_eq!(p.reference, MoveParameters::default());
    assert_eq!(p.limits, Limits::default());
    assert_eq!(p.plate, PlateParameters::default());
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
        ("solver.method", "5"),
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

/// The `dependencies` of every output in `<ModelStructure><Outputs>` are exactly the inputs the
/// compiled model's outputs depend on directly, in any configuration (hydraulic model, motor
/// coupled or not, hub or locked root, analog or external drive): found by perturbing each input at states spread over each
/// state's nominal range and seeing which outputs change by a bit. In particular y_pot and theta
/// depend on no input, so feeding y_pot back to r makes no algebraic loop.
#[test]
fn output_dependencies_are_those_of_the_compiled_model() {
    use std::collections::{BTreeMap, BTreeSet};
    let position = |name: &str| VARIABLES.iter().position(|v| v.name == name).unwrap() + 1;
    let mut found: BTreeMap<usize, BTreeSet<usize>> = VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .map(|v| (position(v.name), BTreeSet::new()))
        .collect();
    for hydraulics in ["1", "2"] {
        for coupled in ["false", "true"] {
            for (root, external) in [("1", "false"), ("2", "false"), ("1", "true")] {
                let mut values = Values::from_start(&VARIABLES);
                set_by_name(&mut values, "hydraulics.model", hydraulics).unwrap();
                set_by_name(&mut values, "hydraulics.motor_coupled", coupled).unwrap();
                set_by_name(&mut values, "plate.root", root).unwrap();
                set_by_name(&mut values, "controller.external", external).unwrap();
                // The amplifier's output limit does not change which input reaches which output,
                // but at the spread states below it is saturated, where tanh rounds to 1 and a
                // perturbed r changes no bit: the linear amplifier shows the dependence.
                set_by_name(&mut values, "controller.saturation", "false").unwrap();
                let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
                // The full servo valve driving a locked hub through the bar has no regular rest
                // state (a known limit of that combination, refused at initialisation).
                let Ok(system) = Assembled::new(&p) else {
                    assert_eq!((hydraulics, coupled, root), ("2", "true", "2"));
                    continue;
                };
                let c = system.compiled();
                let (m, k) = (c.n_inputs(), c.n_outputs());
                // A deterministic spread of states: nominal times a factor in [-1, 1].
                let x: Vec<f64> = system
                    .nominal()
                    .iter()
                    .enumerate()
                    .map(|(i, s)| s * ((i * 7919 % 13) as f64 / 6.0 - 1.0))
                    .collect();
                let mut y0 = vec![0.0; k];
                c.outputs(&x, &vec![0.0; m], &mut y0);
                for j in 0..m {
                    let mut u = vec![0.0; m];
                    u[j] = 123.4;
                    let mut y = vec![0.0; k];
                    c.outputs(&x, &u, &mut y);
                    for (o, (a, b)) in y0.iter().zip(&y).enumerate() {
                        if a.to_bits() != b.to_bits() {
                            let out = position(&c.output_names()[o]);
                            found
                                .get_mut(&out)
                                .unwrap()
                                .insert(position(&c.input_names()[j]));
                        }
                    }
                }
            }
        }
    }
    assert!(found[&position("y_pot")].is_empty());
    let mut declared = BTreeMap::new();
    for u in &model_description().structure.outputs {
        // The dependencies on inputs; those on the continuous states are checked by
        // tests/model_structure.rs.
        let deps: BTreeSet<usize> = u
            .dependencies
            .iter()
            .flatten()
            .copied()
            .filter(|&d| VARIABLES[d - 1].causality == Causality::Input)
            .collect();
        declared.insert(u.index, deps);
    }
    assert_eq!(declared, found);
}

/// The display units' factors agree with their names (build.rs checks every one; this pins the
/// one that was wrong): 1 bar min/L = 1e5 Pa * 60 s / 1e-3 m^3 = 6e9 N s/m^5.
#[test]
fn bar_min_per_litre_is_six_billion_si() {
    let md = model_description();
    let factor = md
        .units
        .iter()
        .flat_map(|u| &u.display_units)
        .find(|d| d.name == "bar.min/L")
        .unwrap()
        .factor;
    assert!((factor * 6e9 - 1.0).abs() < 1e-15, "{factor}");
}

/// Issue 41, item 8: every continuous state and its derivative carry a unit (the fragment that
/// owns the state states it, `bond_graph::units`), and the derivative's unit is the state's per
/// second by the base units the XML gives both (an I element's momentum and its effort, a C
/// element's displacement and its flow, an integrator and its input).
#[test]
fn every_state_and_derivative_has_a_unit_and_they_differ_by_a_second() {
    let md = model_description();
    let base = |unit: &str| -> BTreeMap<String, i32> {
        let u = md
            .units
            .iter()
            .find(|u| u.name == unit)
            .unwrap_or_else(|| panic!("unit {unit} is not defined"));
        u.base_unit
            .iter()
            .flatten()
            .map(|(k, v)| (k.clone(), v.parse::<i32>().unwrap()))
            .filter(|(_, v)| *v != 0)
            .collect()
    };
    let mut checked = 0;
    for d in md.variables.iter().filter(|v| v.derivative.is_some()) {
        let x = &md.variables[d.derivative.as_ref().unwrap().parse::<usize>().unwrap() - 1];
        let (Some(ux), Some(ud)) = (x.unit.as_deref(), d.unit.as_deref()) else {
            panic!("{} or {} has no unit", x.name, d.name);
        };
        let mut per_second = base(ux);
        *per_second.entry("s".into()).or_default() -= 1;
        per_second.retain(|_, v| *v != 0);
        assert_eq!(
            base(ud),
            per_second,
            "{} in {ux}, {} in {ud}",
            x.name,
            d.name
        );
        checked += 1;
    }
    assert_eq!(
        checked,
        hydraulic_slewing_plate::model::variables::CONTINUOUS_STATES.len()
    );
}
