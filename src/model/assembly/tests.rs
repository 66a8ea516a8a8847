//! The assembled model's own tests: values left until read, and the affine plans.

use super::*;
use crate::fmu::Experiment;
use crate::model::parameters::set_by_name;

fn assembled(sets: &[(&str, &str)]) -> (Assembled, Values) {
    let mut values = Values::from_start(&VARIABLES);
    for (name, value) in sets {
        set_by_name(&mut values, name, value).unwrap();
    }
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    (Assembled::new(&p).unwrap(), values)
}

/// What a communication point leaves to be computed when read, computed then, is what
/// `write_outputs` writes, bit for bit (the LOES with the plate, all of whose outputs wait;
/// the full servo valve, whose own outputs and rows are written at once); and at a state
/// too large for the bounds to show the waiting values finite, nothing waits.
#[test]
fn values_computed_when_read_are_those_written_at_once() {
    let configurations: [&[(&str, &str)]; 2] = [
        &[
            ("hydraulics.model", "1"),
            ("controller.saturation", "false"),
            ("hydraulics.motor_coupled", "true"),
            ("reference.angle", "0"),
            ("plate.Cd", "0"),
        ],
        &[
            ("hydraulics.model", "2"),
            ("hydraulics.motor_coupled", "true"),
        ],
    ];
    for (c, sets) in configurations.iter().enumerate() {
        let (mut a, mut values) = assembled(sets);
        values.set_real(idx::R, 0.3);
        a.set_inputs(&values);
        let x: Vec<f64> = a
            .initial_state()
            .iter()
            .zip(a.nominal())
            .enumerate()
            .map(|(i, (r, s))| r + s * crate::math::sin(0.37 * i as f64))
            .collect();
        let mut eager = values.clone();
        a.write_outputs(&x, &mut eager);
        let mut lazy = values.clone();
        assert!(a.write_at_point(&x, &mut lazy), "configuration {c}");
        let waiting: Vec<usize> = (0..VARIABLES.len()).filter(|&i| a.on_demand(i)).collect();
        // Every output of the LOES configuration waits; the valve's own do not.
        let outputs = a.output_index.iter().flatten().count();
        let waiting_outputs = a
            .output_index
            .iter()
            .flatten()
            .filter(|&&i| a.on_demand(i))
            .count();
        if c == 0 {
            assert_eq!(waiting_outputs, outputs);
        } else {
            assert!(waiting_outputs > 0 && waiting_outputs < outputs);
        }
        // The stored energy waits in both: the LOES's storages are linear, and the valve's
        // nonlinear ones (its chambers, its spool stops) declare a bound on their energy.
        assert!(a.on_demand(idx::ENERGY), "configuration {c}");
        for &i in &waiting {
            a.write_on_demand(&x, i, &mut lazy);
        }
        for (i, variable) in VARIABLES.iter().enumerate() {
            if let (crate::fmu::Value::Real(e), crate::fmu::Value::Real(l)) =
                (eager.get(i), lazy.get(i))
            {
                assert!(
                    e.to_bits() == l.to_bits() || (*e == 0.0 && *l == 0.0),
                    "configuration {c}, {}: {l} read, {e} written",
                    variable.name
                );
            }
        }
        let huge: Vec<f64> = x.iter().map(|_| 1e300).collect();
        assert!(!a.write_at_point(&huge, &mut lazy), "configuration {c}");
    }
}

/// The sparse product `J x + f(0, u)` is the plan's `f(x, u)` to rounding, at points far
/// from rest and after the inputs change (held or restored), and so are the outputs
/// `C x + y(0, u)`; with the full servo valve, the valve's rows come from their forms
/// (`NonaffineForms`, the plan's sums to rounding), its outputs from the plan's operations, and
/// the others from the products.
#[test]
fn affine_derivatives_and_outputs_are_the_plans() {
    let (mut a, mut values) = assembled(&[
        ("hydraulics.model", "1"),
        ("controller.saturation", "false"),
        ("hydraulics.motor_coupled", "true"),
    ]);
    assert!(a.affine.is_some());
    let n = a.dim();
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let (mut sparse, mut plan) = (vec![0.0; n], vec![0.0; n]);
    for trial in 0..20 {
        let x: Vec<f64> = a.nominal().iter().map(|s| s * next() * 100.0).collect();
        match trial % 3 {
            0 => {
                values.set_real(idx::R, next());
                values.set_real(idx::F1, 50.0 * next());
                assert!(a.set_inputs(&values));
            }
            1 => a.restore_inputs(&[next(), 0.0, 10.0 * next(), 0.0]),
            _ => {}
        }
        a.rhs(0.0, &x, &mut sparse);
        a.compiled.derivatives(&x, &a.inputs, &mut plan);
        let scale = plan.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            assert!(
                (sparse[i] - plan[i]).abs() <= 1e-12 * scale,
                "trial {trial}, {}: {} against {}",
                a.compiled.state_names()[i],
                sparse[i],
                plan[i]
            );
        }
    }
    // The outputs written as C x + y(0, u) are the plan's, to rounding.
    assert!(a.affine.as_ref().unwrap().outputs.is_some());
    let x: Vec<f64> = a.nominal().iter().map(|s| s * next() * 100.0).collect();
    let mut written = Values::from_start(&VARIABLES);
    a.write_outputs(&x, &mut written);
    let mut y = vec![0.0; a.compiled.n_outputs()];
    a.compiled.outputs(&x, &a.inputs, &mut y);
    let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut compared = 0;
    for (k, target) in a.output_index.iter().enumerate() {
        if let Some(i) = *target {
            let v = written.real(i);
            assert!(
                (v - y[k]).abs() <= 1e-12 * scale,
                "{}: {v} against {}",
                a.compiled.output_names()[k],
                y[k]
            );
            compared += 1;
        }
    }
    assert!(compared >= 20, "{compared} outputs compared");
    // The full servo valve: its 7 valve rows as forms over the states, inputs and its laws'
    // results (the plan's sums, associated otherwise: the same to rounding), the other rows
    // as the product.
    let (mut sv, mut values) = assembled(&[("hydraulics.model", "2")]);
    assert!(!sv.compiled.outputs_are_affine());
    let rows = sv.compiled.nonaffine_rows().to_vec();
    assert!(!rows.is_empty() && 2 * rows.len() < sv.dim(), "{rows:?}");
    let affine = sv.affine.as_ref().expect("partly affine");
    assert!(affine.partial && affine.outputs.is_some());
    assert!(!sv.compiled.nonaffine_outputs().is_empty());
    let n = sv.dim();
    let (mut mixed, mut plan) = (vec![0.0; n], vec![0.0; n]);
    for trial in 0..20 {
        let x: Vec<f64> = (sv.rest.iter().zip(sv.nominal()))
            .map(|(r, s)| r + s * next() * 0.2)
            .collect();
        if trial % 2 == 0 {
            values.set_real(idx::R, next());
            values.set_real(idx::F2, 50.0 * next());
            assert!(sv.set_inputs(&values));
        }
        sv.rhs(0.0, &x, &mut mixed);
        sv.compiled.derivatives(&x, &sv.inputs, &mut plan);
        assert!(plan.iter().all(|v| v.is_finite()), "trial {trial}");
        let scale = plan.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            let name = &sv.compiled.state_names()[i];
            assert!(
                (mixed[i] - plan[i]).abs() <= 1e-12 * scale,
                "trial {trial}, {name}: {} against {}",
                mixed[i],
                plan[i]
            );
        }
        // The outputs and derivatives written at a communication point: the valve's as forms
        // over the states, inputs and laws (`PointForms`: the plan's sums associated otherwise,
        // so the same to rounding), the others as products.
        let mut written = Values::from_start(&VARIABLES);
        sv.write_outputs(&x, &mut written);
        let mut y = vec![0.0; sv.compiled.n_outputs()];
        sv.compiled.evaluate(&x, &sv.inputs, &mut plan, &mut y);
        let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (k, target) in sv.output_index.iter().enumerate() {
            let (Some(i), name) = (*target, &sv.compiled.output_names()[k]) else {
                continue;
            };
            let v = written.real(i);
            // A valve output against its own size (tests/plan_kernels.rs checks the forms
            // over many points), the others against the largest output.
            let size = if sv.compiled.nonaffine_outputs().contains(&(k as u32)) {
                y[k].abs()
            } else {
                scale
            };
            assert!(
                (v - y[k]).abs() <= 1e-12 * size,
                "trial {trial}, {name}: {v}, {}",
                y[k]
            );
        }
        for (i, slot) in sv.state_slot.iter().enumerate() {
            if let Some(k) = *slot {
                let v = written.real(CONTINUOUS_STATES[k].1);
                let scale = plan.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                assert!(
                    (v - plan[i]).abs() <= 1e-12 * scale,
                    "trial {trial}, der {i}"
                );
            }
        }
    }
}
