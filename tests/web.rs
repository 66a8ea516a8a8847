//! The browser build's simulation API (`src/web/`), natively: what the `.wasm` exports and
//! `docs/web/hsp.js` calls. The page itself, in Chromium, is `tests/python/test_web.py`.

use hydraulic_slewing_plate::web::{
    parameter_set_json, parse_request, value_reference, variables_json, Simulation,
};

fn vr(name: &str) -> u32 {
    value_reference(name).unwrap_or_else(|| panic!("no variable {name}"))
}

fn settings(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs
        .iter()
        .map(|(n, v)| (n.to_string(), v.to_string()))
        .collect()
}

fn run(sim: &mut Simulation, steps: usize, names: &[&str]) -> Vec<Vec<f64>> {
    let refs: Vec<u32> = names.iter().map(|n| vr(n)).collect();
    let mut rows = Vec::new();
    for _ in 0..steps {
        sim.step(1e-3).unwrap();
        let mut row = vec![0.0; refs.len()];
        sim.get_reals(&refs, &mut row).unwrap();
        rows.push(row);
    }
    rows
}

#[test]
fn the_drawn_plate_at_the_tip_is_the_models_w_tip() {
    // The grid's point (a, b/2) is where the model's w_tip is taken (eq. 22): the drawing's shape
    // functions and coordinates against the model's own output, for both plate formulations.
    for preset in ["complete", "paper-fig9b"] {
        let mut sim = Simulation::new(preset, &settings(&[("reference.angle", "0.5")])).unwrap();
        let (nx, ny) = (11, 5);
        let mut grid = vec![0.0; nx * ny];
        let mut largest = 0.0f64;
        for _ in 0..8 {
            // r steps the paper's presets; the move drives the complete system.
            sim.set_real(vr("r"), 0.2).unwrap();
            for _ in 0..150 {
                sim.step(1e-3).unwrap();
            }
            sim.deflection(nx, ny, &mut grid).unwrap();
            let mut w_tip = [0.0];
            sim.get_reals(&[vr("w_tip")], &mut w_tip).unwrap();
            let tip = grid[(nx - 1) + nx * (ny / 2)];
            assert!(
                (tip - w_tip[0]).abs() <= 1e-12 * w_tip[0].abs().max(1e-9),
                "{preset} t = {}: grid {tip} against w_tip {}",
                sim.time(),
                w_tip[0]
            );
            largest = largest.max(w_tip[0].abs());
            // Relative to the hub: the root does not move.
            assert!(grid[nx * (ny / 2)].abs() <= 1e-12 * largest.max(1e-9));
        }
        assert!(
            largest > 1e-4,
            "{preset}: the plate barely moved ({largest} m)"
        );
    }
}

#[test]
fn a_reset_simulation_repeats_itself_bit_for_bit() {
    let names = ["y_pot", "theta_hub", "w_tip", "servo_valve.p_1"];
    let mut sim = Simulation::new("complete", &[]).unwrap();
    let first = run(&mut sim, 800, &names);
    sim.reset().unwrap();
    assert_eq!(sim.time(), 0.0);
    assert_eq!(run(&mut sim, 800, &names), first);
    let mut fresh = Simulation::new("complete", &[]).unwrap();
    assert_eq!(run(&mut fresh, 800, &names), first);
}

#[test]
fn bad_requests_name_their_culprit() {
    let err = |r: Result<Simulation, String>| r.err().expect("must fail");
    assert!(err(Simulation::new("nope", &[])).contains("unknown preset 'nope'"));
    assert!(err(Simulation::new("", &settings(&[("no.such", "1")]))).contains("'no.such'"));
    let e = err(Simulation::new("", &settings(&[("torsion_bar.k", "-1")])));
    assert!(e.contains("torsion_bar.k"), "{e}");
    let e = err(Simulation::new("", &settings(&[("plate.N", "two")])));
    assert!(e.contains("plate.N") && e.contains("'two'"), "{e}");
    // An output is not a setting.
    assert!(err(Simulation::new("", &settings(&[("w_tip", "1")]))).contains("w_tip"));

    assert!(parse_request("{").unwrap_err().contains("not JSON"));
    assert!(parse_request(r#"{"preset": 3}"#)
        .unwrap_err()
        .contains("preset"));
    assert!(parse_request(r#"{"settings": [1]}"#)
        .unwrap_err()
        .contains("settings"));
    let e = parse_request(r#"{"settings": {"plate.a": [1]}}"#).unwrap_err();
    assert!(e.contains("plate.a"), "{e}");
    let (preset, s) =
        parse_request(r#"{"preset": "loes-motor", "settings": {"controller.saturation": false, "plate.root": "Locked", "loes.C3": 6e-11}}"#)
            .unwrap();
    assert_eq!(preset, "loes-motor");
    assert!(s.contains(&("loes.C3".into(), "6e-11".into())));
    assert!(s.contains(&("plate.root".into(), "Locked".into())));
    assert!(s.contains(&("controller.saturation".into(), "false".into())));
    // And the typed texts are what the model takes.
    Simulation::new(&preset, &s).unwrap();
}

#[test]
fn a_refused_call_keeps_the_last_good_state_until_a_reset() {
    // As in FMI: a refused call puts the instance in the error state, where it keeps its time
    // and values; only a reset goes on.
    let mut sim = Simulation::new("complete", &[]).unwrap();
    run(&mut sim, 10, &["y_pot"]);
    let t = sim.time();
    let mut before = [0.0];
    sim.get_reals(&[vr("y_pot")], &mut before).unwrap();
    let e = sim.step(-1e-3).unwrap_err();
    assert!(e.contains("communicationStepSize"), "{e}");
    assert!(sim.step(1e-3).is_err(), "the error state refuses steps");
    assert_eq!(sim.time(), t);
    let mut after = [0.0];
    sim.get_reals(&[vr("y_pot")], &mut after).unwrap();
    assert_eq!(after, before);
    sim.reset().unwrap();
    assert_eq!(sim.time(), 0.0);
    sim.step(1e-3).unwrap();

    for (name, value) in [("plate.a", 2.0), ("r", f64::NAN)] {
        let mut sim = Simulation::new("complete", &[]).unwrap();
        let e = sim.set_real(vr(name), value).unwrap_err();
        assert!(e.contains(name), "{name}: {e}");
    }
    let mut sim = Simulation::new("complete", &[]).unwrap();
    let mut out = [0.0; 2];
    assert!(sim.get_reals(&[vr("y_pot")], &mut out).is_err());
    let e = sim.deflection(1, 5, &mut [0.0; 5]).unwrap_err();
    assert!(e.contains("2 x 2"), "{e}");
}

#[test]
fn the_monitors_and_messages_are_the_fmus() {
    // The paper's 2 V step drives the default plant out of the linear model's range: the FMU's
    // validity warnings reach the page.
    let mut sim = Simulation::new("complete", &settings(&[("reference.angle", "0")])).unwrap();
    let monitors = sim.monitors();
    let names: Vec<&str> = monitors.iter().map(|m| m.0).collect();
    assert_eq!(
        names,
        [
            "plate.w_tip_ratio",
            "plate.stress",
            "torsion_bar.stress",
            "hub.omega_ratio"
        ]
    );
    assert!(monitors.iter().all(|m| m.1 > 0.0 && m.1.is_finite()));
    sim.set_real(vr("r"), 2.0).unwrap();
    let mut warned = false;
    for _ in 0..2000 {
        warned |= sim.step(1e-3).unwrap();
    }
    let messages = sim.take_messages();
    assert!(warned);
    assert!(
        messages
            .iter()
            .any(|m| m.status == "warning" && m.message.contains("validity:")),
        "{messages:?}"
    );
    assert!(sim.take_messages().is_empty(), "taken once");
}

#[test]
fn the_variable_table_is_the_fmus() {
    let table = variables_json();
    let list = table.as_array().unwrap();
    let find = |name: &str| list.iter().find(|v| v["name"] == name).unwrap().clone();
    let k = find("torsion_bar.k");
    assert_eq!(k["valueReference"], vr("torsion_bar.k"));
    assert_eq!(k["causality"], "parameter");
    assert_eq!(k["type"], "Real");
    assert_eq!(k["unit"], "N.m/rad");
    assert_eq!(k["start"], 2500.0);
    assert_eq!(find("r")["causality"], "input");
    let method = find("solver.method");
    assert_eq!(method["type"], "Enumeration");
    assert_eq!(
        (method["min"].as_i64(), method["max"].as_i64()),
        (Some(1), Some(4))
    );
}

#[test]
fn run_is_step_by_step_in_one_call() {
    // sim.run (what the page calls) against the same steps one by one, to the bit, and its rows
    // up to a failure are kept.
    let names = ["y_pot", "theta_hub", "w_tip", "controller.e_out"];
    let refs: Vec<u32> = names.iter().map(|n| vr(n)).collect();
    let inputs: Vec<f64> = (0..700).map(|k| if k < 300 { 0.0 } else { 0.3 }).collect();
    let mut one = Simulation::new("complete", &[]).unwrap();
    let mut expected = Vec::new();
    let mut warned = false;
    for &u in &inputs {
        one.set_real(vr("r"), u).unwrap();
        warned |= one.step(1e-3).unwrap();
        let mut row = vec![0.0; refs.len()];
        one.get_reals(&refs, &mut row).unwrap();
        expected.extend(row);
    }
    let mut batch = Simulation::new("complete", &[]).unwrap();
    let mut out = vec![0.0; inputs.len() * refs.len()];
    let (done, result) = batch.run(1e-3, vr("r"), &inputs, &refs, &mut out);
    assert_eq!((done, result), (inputs.len(), Ok(warned)));
    assert_eq!(out, expected);
    assert_eq!(batch.time(), one.time());
    // A NaN input is refused at its step: the rows before it stay.
    let mut bad = inputs[..5].to_vec();
    bad[3] = f64::NAN;
    let mut fresh = Simulation::new("complete", &[]).unwrap();
    let mut rows = vec![0.0; bad.len() * refs.len()];
    let (done, result) = fresh.run(1e-3, vr("r"), &bad, &refs, &mut rows);
    assert_eq!(done, 3);
    assert!(result.unwrap_err().contains('r'));
    assert_eq!(rows[..3 * refs.len()], expected[..3 * refs.len()]);
    let (_, result) = fresh.run(1e-3, vr("r"), &inputs[..2], &refs, &mut rows);
    assert!(result.unwrap_err().contains("places"));
}

#[test]
fn the_deflection_map_times_the_recorded_coordinates_is_the_deflection() {
    // What the page draws at a scrubbed time (the map times the coordinates it recorded then)
    // is what `deflection` gives at that time, to the bit (the same products summed in order).
    let mut sim = Simulation::new("complete", &settings(&[("reference.duration", "1")])).unwrap();
    let (nx, ny) = (21, 7);
    let (coordinates, map) = sim.deflection_map(nx, ny).unwrap();
    let n = coordinates.len();
    assert!(
        n > 0 && map.len() == nx * ny * n,
        "{n} coordinates, {}",
        map.len()
    );
    let mut moved = 0.0f64;
    for _ in 0..6 {
        for _ in 0..200 {
            sim.step(1e-3).unwrap();
        }
        let mut eta = vec![0.0; n];
        sim.get_reals(&coordinates, &mut eta).unwrap();
        let mut grid = vec![0.0; nx * ny];
        sim.deflection(nx, ny, &mut grid).unwrap();
        for (k, w) in grid.iter().enumerate() {
            let drawn: f64 = (0..n).map(|c| map[k * n + c] * eta[c]).sum();
            assert_eq!(
                drawn.to_bits(),
                w.to_bits(),
                "point {k} at t = {}",
                sim.time()
            );
        }
        moved = moved.max(grid[nx - 1 + nx * (ny / 2)].abs());
    }
    assert!(moved > 1e-5, "the plate barely moved ({moved} m)");
    assert!(sim.deflection_map(1, 7).unwrap_err().contains("2 x 2"));
}

#[test]
fn the_pages_parameter_set_is_the_preset_with_its_settings_over_it() {
    let set = parameter_set_json(
        r#"{"preset": "loes-motor", "settings": {"controller.A1": 3, "reference.angle": 0.1, "plate.root": "Locked"}, "name": "run-1"}"#,
    )
    .unwrap();
    assert!(
        set.contains(r#"<ssv:ParameterSet version="1.0" name="run-1""#),
        "{set}"
    );
    // The preset's switch, written as its integer with the item's name.
    assert!(set.contains(r#"<ssv:Parameter name="hydraulics.model"><ssv:Integer value="1"/><!-- HydraulicsModel.Loes -->"#), "{set}");
    // A setting over the preset replaces its value in place; a new one comes after; an item's
    // name becomes its value; a Real is the shortest text of its double.
    assert_eq!(set.matches(r#"name="reference.angle""#).count(), 1, "{set}");
    assert!(
        set.contains(r#"<ssv:Parameter name="reference.angle"><ssv:Real value="0.1"/>"#),
        "{set}"
    );
    assert!(
        set.contains(r#"<ssv:Parameter name="controller.A1"><ssv:Real value="3.0"/>"#),
        "{set}"
    );
    assert!(
        set.contains(r#"<ssv:Parameter name="plate.root"><ssv:Integer value="2"/>"#),
        "{set}"
    );
    let angle = set.find("reference.angle").unwrap();
    assert!(
        set.find("hydraulics.model").unwrap() < angle && angle < set.find("controller.A1").unwrap()
    );
    // Bad settings are named.
    let bad = parameter_set_json(r#"{"preset": "complete", "settings": {"controller.A1": "x"}}"#);
    assert!(bad
        .unwrap_err()
        .contains("controller.A1: 'x' is not a number"));
    let bad = parameter_set_json(r#"{"settings": {"nope": 1}}"#);
    assert!(bad.unwrap_err().contains("unknown variable 'nope'"));
}

#[test]
fn the_variable_table_gives_each_parameter_its_group_and_display_unit() {
    let table = variables_json();
    let find = |name: &str| {
        table
            .as_array()
            .unwrap()
            .iter()
            .find(|v| v["name"] == name)
            .unwrap()
            .clone()
    };
    // modelDescription.xml: controller.k_pot is in the "analog controller" group, in V/deg.
    let k_pot = find("controller.k_pot");
    assert_eq!(k_pot["group"], "analog controller");
    assert_eq!(k_pot["displayUnit"]["name"], "V/deg");
    assert_eq!(k_pot["displayUnit"]["factor"], 0.017453292519943295);
    assert_eq!(k_pot["variability"], "fixed");
    // No displayUnit attribute: the unit's first display unit (cm3/rad for m3/rad).
    assert_eq!(find("loes.D_m")["displayUnit"]["name"], "cm3/rad");
    assert!(find("controller.A1")["displayUnit"].is_null());
    let root = find("plate.root");
    assert_eq!(root["items"][1]["name"], "Locked");
    assert_eq!(root["items"][1]["value"], 2);
    assert!(find("servo_valve.p_supply")["group"]
        .as_str()
        .unwrap()
        .starts_with("servo valve"));
}
