//! The continuous states and `<ModelStructure>` dependencies that `modelDescription.xml` declares
//! for Model Exchange are those of the compiled model.
//!
//! FMI 2.0 fixes the number of continuous states in the XML (one `<Derivatives>` entry per state),
//! but the model's states depend on its structural parameters (hydraulic model, motor coupled or
//! not, hub free or locked, plate modes N x M). The XML therefore declares the union of the states
//! of every configuration with at most [`PLATE_MODES`] plate modes, and each derivative and output
//! depends on the union of what it depends on in those configurations. This test computes that
//! union from the compiled models and compares it with `modelDescription/model_structure.json`,
//! which `modelDescription/update.py` turns into the XML's state variables and dependencies; it
//! also reads the XML back. The file also holds each state's nominal value in the default
//! configuration (1 for the states it does not have: what `fmi2GetNominalsOfContinuousStates`
//! returns for them), which update.py writes into the XML's `nominal` attributes
//! (tests/state_nominals.rs checks them against the FMU's functions). After a change to the model:
//!
//! ```text
//! HSP_WRITE_MODEL_STRUCTURE=1 cargo test --release --test model_structure
//! python3 modelDescription/update.py
//! ```

use std::collections::{BTreeMap, BTreeSet};

use hydraulic_slewing_plate::fmu::{Causality, Experiment, Values};
use hydraulic_slewing_plate::model::assembly::{Assembled, STATE_PREFIX};
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::{CONTINUOUS_STATES, VARIABLES};
use serde_json::{json, Value};

// The project's one reader of the XML (build.rs and hsp read it through the same file).
#[path = "../tools/model_description.rs"]
#[allow(dead_code)]
mod model_description;

use model_description::{ModelDescription, Unknown};

/// The most plate modes (plate.N x plate.M) Model Exchange declares states for: 25 covers the
/// default 3 x 5 and the paper's 5 beam functions across with up to 5 along; co-simulation takes
/// up to 20 x 20.
const PLATE_MODES: usize = 25;

const FILE: &str = "modelDescription/model_structure.json";

/// Every structural configuration: the switches that change which states exist or how they are
/// coupled, and every plate size up to [`PLATE_MODES`] modes.
fn configurations() -> Vec<Vec<(&'static str, String)>> {
    let mut out = Vec::new();
    for hydraulics in ["2", "1"] {
        for coupled in ["true", "false"] {
            for root in ["1", "2"] {
                for external in ["false", "true"] {
                    for formulation in ["1", "2"] {
                        for saturation in ["false", "true"] {
                            for n in (1..=20).rev() {
                                for m in (1..=20).rev().filter(|m| n * m <= PLATE_MODES) {
                                    out.push(vec![
                                        ("hydraulics.model", hydraulics.to_string()),
                                        ("hydraulics.motor_coupled", coupled.to_string()),
                                        ("plate.root", root.to_string()),
                                        ("controller.external", external.to_string()),
                                        ("plate.formulation", formulation.to_string()),
                                        ("controller.saturation", saturation.to_string()),
                                        ("plate.N", n.to_string()),
                                        ("plate.M", m.to_string()),
                                    ]);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

/// The union over all configurations: the states in order of first appearance, and for each
/// derivative (by state name) the states and inputs it depends on, for each output the states:
/// structural dependencies, paths through the compiled plan (a numerical zero of the Jacobian at
/// some point, a saturated law say, would hide one).
fn structure() -> Value {
    let mut states: Vec<String> = Vec::new();
    let mut derivatives: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut outputs: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    // Each state's [unit, derivative's unit]: the same in every configuration that has it.
    let mut units: BTreeMap<String, [&str; 2]> = BTreeMap::new();
    for config in configurations() {
        let mut values = Values::from_start(&VARIABLES);
        for (name, value) in &config {
            set_by_name(&mut values, name, value).unwrap();
        }
        let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
        // The full servo valve driving a locked hub through the bar has no regular rest state
        // (refused at initialisation, see tests/model_description.rs).
        let Ok(system) = Assembled::new(&p) else {
            continue;
        };
        let c = system.compiled();
        for s in c.state_names() {
            if !states.contains(s) {
                states.push(s.clone());
            }
        }
        for (s, u) in c.state_names().iter().zip(system.state_units()) {
            let u = u.unwrap_or_else(|| panic!("{s}: its fragment states no units ({config:?})"));
            let pair = [u.state, u.derivative];
            let known = units.entry(s.clone()).or_insert(pair);
            assert_eq!(
                *known, pair,
                "{s}: units differ between configurations ({config:?})"
            );
        }
        let (sn, un) = (c.state_names(), c.input_names());
        let n = c.n_states();
        let name = |k: &u32| {
            let k = *k as usize;
            if k < n {
                sn[k].clone()
            } else {
                un[k - n].clone()
            }
        };
        let (of_derivatives, of_outputs) = c.dependencies();
        for (i, deps) in of_derivatives.iter().enumerate() {
            let entry = derivatives.entry(sn[i].clone()).or_default();
            entry.extend(deps.iter().map(name));
            // The Jacobian's own pattern must lie within (it is read off the derivative plan).
            for j in &c.jacobian_pattern()[i] {
                assert!(deps.contains(j), "der({}) on {}", sn[i], sn[*j as usize]);
            }
        }
        // Outputs on states; their dependence on inputs is the FEEDTHROUGH table of update.py,
        // checked by tests/model_description.rs.
        for (o, deps) in of_outputs.iter().enumerate() {
            let entry = outputs.entry(c.output_names()[o].clone()).or_default();
            entry.extend(deps.iter().filter(|&&k| (k as usize) < n).map(name));
        }
        let energy = outputs.entry("energy".into()).or_default();
        energy.extend(c.storage_states().into_iter().map(|i| sn[i].clone()));
    }
    // The nominals of the default configuration, 1 for the states it lacks.
    let p =
        Parameters::from_values(&Values::from_start(&VARIABLES), &Experiment::default()).unwrap();
    let default = Assembled::new(&p).unwrap();
    let c = default.compiled();
    let nominals: BTreeMap<&String, f64> = states
        .iter()
        .map(|s| {
            let k = c.state_names().iter().position(|n| n == s);
            (s, k.map_or(1.0, |k| default.nominal()[k]))
        })
        .collect();
    json!({
        "plate_modes": PLATE_MODES,
        "nominals": nominals,
        "units": units,
        "states": states,
        "derivatives": derivatives,
        "outputs": outputs,
    })
}

/// The `dependencies` of each `<Unknown>` of a `<ModelStructure>` block, by 1-based index.
fn declared(unknowns: &[Unknown]) -> BTreeMap<usize, BTreeSet<usize>> {
    unknowns
        .iter()
        .map(|u| (u.index, u.dependencies.iter().flatten().copied().collect()))
        .collect()
}

#[test]
fn xml_declares_the_compiled_models_states_and_dependencies() {
    let computed = structure();
    let text = serde_json::to_string_pretty(&computed).unwrap() + "\n";
    let stored = std::fs::read_to_string(FILE).unwrap_or_default();
    if stored != text {
        if std::env::var_os("HSP_WRITE_MODEL_STRUCTURE").is_some() {
            std::fs::write(FILE, &text).unwrap();
        } else {
            panic!(
                "{FILE} is stale: run HSP_WRITE_MODEL_STRUCTURE=1 cargo test --release --test model_structure, then python3 modelDescription/update.py"
            );
        }
    }

    // The XML's continuous states are exactly those, in that order.
    let names: Vec<String> = computed["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| format!("{STATE_PREFIX}{}", s.as_str().unwrap()))
        .collect();
    let xml_states: Vec<&str> = CONTINUOUS_STATES
        .iter()
        .map(|&(x, _)| VARIABLES[x].name)
        .collect();
    assert_eq!(xml_states, names);
    for &(x, d) in &CONTINUOUS_STATES {
        assert_eq!(VARIABLES[d].name, format!("der({})", VARIABLES[x].name));
        assert_eq!(VARIABLES[x].causality, Causality::Local);
    }

    // And the XML's dependencies are the computed ones.
    let xml = std::fs::read_to_string("modelDescription/modelDescription.xml").unwrap();
    let structure = ModelDescription::parse(&xml).unwrap().structure;
    let position = |name: &str| VARIABLES.iter().position(|v| v.name == name).unwrap() + 1;
    let known = |name: &str| {
        VARIABLES
            .iter()
            .position(|v| v.name == name && v.causality == Causality::Input)
            .map(|i| i + 1)
            .unwrap_or_else(|| position(&format!("{STATE_PREFIX}{name}")))
    };
    let positions = |deps: &Value| -> BTreeSet<usize> {
        deps.as_array()
            .unwrap()
            .iter()
            .map(|n| known(n.as_str().unwrap()))
            .collect()
    };
    let derivatives = declared(&structure.derivatives);
    for (state, deps) in computed["derivatives"].as_object().unwrap() {
        let d = position(&format!("der({STATE_PREFIX}{state})"));
        assert_eq!(derivatives[&d], positions(deps), "der({state})");
    }
    assert_eq!(derivatives.len(), CONTINUOUS_STATES.len());
    let outputs = declared(&structure.outputs);
    let states: BTreeSet<usize> = CONTINUOUS_STATES.iter().map(|&(x, _)| x + 1).collect();
    for (output, deps) in computed["outputs"].as_object().unwrap() {
        let got: BTreeSet<usize> = outputs[&position(output)]
            .intersection(&states)
            .copied()
            .collect();
        assert_eq!(got, positions(deps), "{output}");
    }
}
