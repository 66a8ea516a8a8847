//! The assembled model's own tests: values left until read, and the affine plans.

use super::*;
use crate::bond_graph::NonlinearLaw;
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
/// the full servo valve, whose own outputs and rows wait too: their laws declare value
/// bounds); and at a state too large for the bounds to show the waiting values finite,
/// nothing waits.
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
        assert_eq!(waiting_outputs, outputs, "configuration {c}");
        // The valve's rows wait too.
        for &i in a.compiled.nonaffine_rows() {
            if let Some(k) = a.state_slot[i as usize] {
                assert!(
                    a.on_demand(CONTINUOUS_STATES[k].1),
                    "configuration {c}, row {i}"
                );
            }
        }
        // The stored energy waits in both: the LOES's storages are linear, and the valve's
        // nonlinear ones (its chambers, its spool stops) declare a bound on their energy.
        assert!(a.on_demand(idx::ENERGY), "configuration {c}");
        // Read backwards (the valve's rows before its outputs, each computing what it needs
        // that an earlier read has not), then a few again at the same point.
        let mut point = PointCache::default();
        for &i in waiting.iter().rev().chain(&waiting[..3]) {
            a.write_on_demand(&x, i, &mut lazy, (&mut point, 1));
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

/// A value that is not affine read on its own after a point is what `write_outputs` writes, to
/// the bit, whichever is read first: each read computes only the nonlinear results it needs
/// (`PointForms::output`), at a point and at the next (a new stamp forgets the first's).
#[test]
fn each_value_that_is_not_affine_read_first_is_the_one_written() {
    let (a, values) = assembled(&[]);
    let affine = a.affine.as_ref().expect("partly affine");
    assert!(affine.partial && affine.point_radius > 0.0);
    let point_values: Vec<usize> = (0..VARIABLES.len())
        .filter(|&i| {
            matches!(
                a.on_demand[i],
                OnDemand::PointOutput(_) | OnDemand::PointDerivative(_)
            )
        })
        .collect();
    assert!(point_values.len() >= 20, "{point_values:?}");
    let mut point = PointCache::default();
    for (stamp, scale) in [(1, 0.3), (2, -0.7)] {
        let x: Vec<f64> = a
            .initial_state()
            .iter()
            .zip(a.nominal())
            .enumerate()
            .map(|(i, (r, s))| r + scale * s * crate::math::sin(1.3 * i as f64 + 0.2))
            .collect();
        let mut eager = values.clone();
        a.write_outputs(&x, &mut eager);
        for &first in &point_values {
            // Alone, at a fresh point.
            let mut lazy = values.clone();
            assert!(a.write_at_point(&x, &mut lazy));
            let mut alone = PointCache::default();
            a.write_on_demand(&x, first, &mut lazy, (&mut alone, 7));
            // And after the others, sharing their results.
            a.write_on_demand(&x, first, &mut lazy, (&mut point, stamp));
            let (e, l) = (eager.real(first), lazy.real(first));
            assert_eq!(
                e.to_bits(),
                l.to_bits(),
                "{}: {l} read, {e} written",
                VARIABLES[first].name
            );
        }
    }
}

/// The radius within which the values that are not affine wait (`Affine::point_radius`): for
/// the default plant a power of 2, finite and positive, far above the states of a run; a law
/// of the point's forms without a declared value bound makes it 0 (everything written at the
/// point, as before the bounds), and so nothing waits.
#[test]
fn the_point_radius_is_positive_for_the_default_and_zero_without_a_bound() {
    let (a, _) = assembled(&[]);
    let affine = a.affine.as_ref().expect("partly affine");
    let radius = affine.point_radius;
    eprintln!("the default plant's point radius: {radius:e}");
    assert!(radius.is_finite() && radius >= 1e20, "{radius:e}");
    // A power of 2: a normal double with an all-zero mantissa.
    assert!(
        radius.is_normal() && radius.to_bits() & ((1 << 52) - 1) == 0,
        "{radius:e}"
    );
    // Just beyond it the bounds fail, within it they hold.
    assert!(affine
        .point
        .bounded_within(&a.compiled, radius, FINITE_BOUND));
    assert!(!affine
        .point
        .bounded_within(&a.compiled, 2.0 * radius, FINITE_BOUND));
    // Every law the forms call declares a bound; strip one and the radius is 0.
    let mut compiled = a.compiled.clone();
    let law = compiled
        .laws_mut()
        .iter_mut()
        .find(|l| l.label.starts_with("air drag"))
        .expect("the plate's air drag");
    assert!(law.value_bound.is_some());
    law.value_bound = None;
    assert_eq!(affine.point.finite_radius(&compiled, FINITE_BOUND), 0.0);
    // A state beyond the radius (but within the affine bounds): the point's values are
    // written at once, the same bits.
    let mut x = a.initial_state();
    x[0] = 4.0 * radius;
    if affine.finite_within(4.0 * radius) {
        let (mut eager, mut lazy) = (
            Values::from_start(&VARIABLES),
            Values::from_start(&VARIABLES),
        );
        a.write_outputs(&x, &mut eager);
        assert!(a.write_at_point(&x, &mut lazy));
        for (k, target) in a.output_index.iter().enumerate() {
            if let (Some(i), true) = (
                *target,
                a.compiled.nonaffine_outputs().contains(&(k as u32)),
            ) {
                assert_eq!(eager.real(i).to_bits(), lazy.real(i).to_bits());
            }
        }
    }
}

/// Each law's declared value bound (`NonlinearLaw::with_value_bound`: |L(v, m)| <= k s² + c,
/// s = max(|v|, |m|), for s up to `VALUE_BOUND_RANGE`) holds for the laws of the default
/// plant and of the LOES configuration, sampled as the stored-energy bounds are: from
/// the scales of their operating points (a chamber's 1e-10 m³ to a pressure's 1e7 Pa) out to
/// 64,000 times beyond, on both sides, and on powers of 2 from 2^-500 to 2^500 and their
/// neighbours; modulated laws over pairs of them.
#[test]
fn the_laws_stay_within_their_declared_value_bounds() {
    let mut samples: Vec<f64> = vec![0.0];
    for scale in [1e-10, 1e-6, 1e-3, 1.0, 1e3, 1e7] {
        samples.extend(
            (-4000..=4000)
                .step_by(7)
                .map(|i| scale * (i as f64 / 100.0).powi(3)),
        );
    }
    for e in -500..=500 {
        let p = 2f64.powi(e);
        for v in [p, p * (1.0 + f64::EPSILON), p * 0.75] {
            if v <= crate::bond_graph::VALUE_BOUND_RANGE {
                samples.extend([v, -v]);
            }
        }
    }
    let coarse: Vec<f64> = samples.iter().copied().step_by(41).collect();
    let check = |law: &NonlinearLaw, v: f64, m: f64| {
        let (k, c) = law.value_bound.expect("declared");
        let s = v.abs().max(m.abs());
        let y = (law.value)(v, m);
        assert!(
            y.is_finite() && y.abs() <= k * s * s + c,
            "{}: L({v:e}, {m:e}) = {y:e} > {k:e} s² + {c:e}",
            law.label
        );
    };
    let mut seen = std::collections::BTreeSet::new();
    for sets in [&[][..], &[("hydraulics.model", "1")][..]] {
        let (a, _) = assembled(sets);
        for law in a.compiled.laws() {
            if law.value_bound.is_none() {
                continue;
            }
            seen.insert(law.label.split(' ').next().unwrap_or("").to_string());
            for &v in &samples {
                check(law, v, 0.0);
            }
            for &v in &coarse {
                for &m in &coarse {
                    check(law, v, m);
                }
            }
        }
    }
    eprintln!("sampled: {seen:?}");
    // The default's point forms call them all (the radius is positive only then).
    let (a, _) = assembled(&[]);
    assert!(a.affine.as_ref().unwrap().point_radius > 0.0);
}

/// The plate's natural frequencies from the plate model the graph was built from (its damping
/// set) are those of a plate model built on its own, to the bit: the FMU writes `plate.f[i]`
/// from the former.
#[test]
fn plate_modes_of_the_built_model_are_the_plates_own() {
    let configurations: [&[(&str, &str)]; 3] = [
        &[],
        &[("plate.formulation", "1")],
        &[("hydraulics.model", "1"), ("plate.root", "2")],
    ];
    for sets in configurations {
        let (a, values) = assembled(sets);
        let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
        let own = crate::model::compose::plate_modes(&p).unwrap();
        let built = crate::fragments::plate::modes::natural_modes(a.plate()).unwrap();
        let bits = |m: &[crate::fragments::plate::modes::NaturalMode]| {
            m.iter()
                .map(|m| (m.f_hz.to_bits(), m.label))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&own), bits(&built), "{sets:?}");
    }
}

/// The linearisation at rest handed out with the model (the one its affine outputs were built
/// from) is the model's own linearisation at rest, computed afresh, to the bit.
#[test]
fn the_linearization_kept_at_rest_is_the_models_own() {
    let configurations: [&[(&str, &str)]; 2] = [&[], &[("hydraulics.model", "1")]];
    for sets in configurations {
        let (_, values) = assembled(sets);
        let p = Parameters::from_values(&values, &Experiment::default())
            .unwrap()
            .sliding();
        let (system, kept) = Assembled::with_linearization_at_rest(&p).unwrap();
        let fresh = Assembled::new(&p).unwrap();
        let afresh = fresh
            .compiled()
            .linearize(&fresh.initial_state(), fresh.inputs());
        let bits = |l: &crate::bond_graph::Linearization| {
            [&l.a, &l.b, &l.c, &l.d]
                .iter()
                .flat_map(|m| m.iter().map(|v| v.to_bits()))
                .chain(l.x0.iter().chain(&l.u0).map(|v| v.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&kept), bits(&afresh), "{sets:?}");
        assert_eq!(system.dim(), fresh.dim());
    }
}
