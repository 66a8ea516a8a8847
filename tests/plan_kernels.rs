//! The kernels that stand in for passes through the compiled plan at every step, against the
//! plan on every preset at scattered points: the tangent sweeps that give the Jacobian's
//! varying entries (the bits of the dual-number passes) and the forms that give the rows of `f`
//! that are not affine (the plan's values to rounding).

#[path = "common/points.rs"]
mod points;

use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::{assembly::Assembled, compose::bond_graph};
use nalgebra::DMatrix;
use points::parameters;

/// `count` points `(x, u)`: each state off rest by up to `spread` times its nominal value,
/// inputs in [-1, 1], from a xorshift generator.
fn points(system: &Assembled, count: usize, spread: f64, seed: u64) -> Vec<(Vec<f64>, Vec<f64>)> {
    let mut s = seed | 1;
    points::around_rest(system, count, spread, move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    })
}

/// The sweeps (one value pass, tangents of several groups at a time through the operations the seeds
/// reach) give the bits of the dual passes over the variable columns and of a full dual
/// Jacobian of a model without fixed entries, near rest and far from it; and they do not
/// decline (no NaN zero tangent at finite points), so it is their entries that are compared.
#[test]
fn tangent_sweeps_give_the_bits_of_the_dual_passes() {
    let mut compared = 0;
    for preset in presets::PRESETS {
        let p = parameters(preset.name);
        let system = Assembled::new(&p).unwrap();
        let m = system.compiled();
        if m.jacobian_is_constant() {
            continue;
        }
        let full = bond_graph(&p).unwrap().compile().unwrap();
        let n = m.n_states();
        let mut pts = points(&system, 10, 0.1, 17);
        pts.extend(points(&system, 10, 1.0, 29));
        pts.extend(points(&system, 5, 10.0, 31));
        for (x, u) in pts {
            let (mut sweeps, mut passes, mut reference) = (
                DMatrix::from_element(n, n, 7.0),
                DMatrix::from_element(n, n, 7.0),
                DMatrix::zeros(n, n),
            );
            assert!(
                m.jacobian_varying_by_sweeps(&x, &u, &mut sweeps),
                "{}: the sweeps declined at a finite point",
                preset.name
            );
            m.jacobian_varying_by_passes(&x, &u, &mut passes);
            full.jacobian(&x, &u, &mut reference);
            for (i, row) in m.jacobian_varying_pattern().iter().enumerate() {
                for &j in row {
                    let j = j as usize;
                    let (a, b, c) = (sweeps[(i, j)], passes[(i, j)], reference[(i, j)]);
                    assert!(
                        a.to_bits() == b.to_bits() && a.to_bits() == c.to_bits(),
                        "{}: J({i}, {j}): sweeps {a:e}, dual passes {b:e}, full {c:e}",
                        preset.name
                    );
                    compared += 1;
                }
            }
            // Only the varying entries are written.
            assert_eq!(sweeps, passes, "{}", preset.name);
        }
    }
    assert!(compared > 1000, "{compared} entries compared");
}

/// The forms of the rows that are not affine give the plan's `f_i` to rounding: within
/// 1e-12 of the row's largest magnitude over the points, on every preset with such rows.
#[test]
fn forms_of_the_nonaffine_rows_are_the_plans_values() {
    let mut presets_with_rows = 0;
    for preset in presets::PRESETS {
        let system = Assembled::new(&parameters(preset.name)).unwrap();
        let m = system.compiled();
        let rows = m.nonaffine_rows();
        if rows.is_empty() {
            continue;
        }
        presets_with_rows += 1;
        let forms = m.nonaffine_forms();
        let n = m.n_states();
        let mut pts = points(&system, 20, 0.1, 5);
        pts.extend(points(&system, 20, 1.0, 7));
        let mut plan = Vec::new();
        let mut by_forms = Vec::new();
        for (x, u) in &pts {
            let mut a = vec![f64::NAN; n];
            m.nonaffine_derivatives(x, u, &mut a);
            // Only the rows that are not affine are written.
            let mut b = vec![f64::NAN; n];
            forms.derivatives(m, x, u, &mut b);
            for i in 0..n {
                assert_eq!(a[i].is_nan(), b[i].is_nan(), "{}: row {i}", preset.name);
            }
            plan.push(a);
            by_forms.push(b);
        }
        for &i in rows {
            let i = i as usize;
            let scale = plan.iter().fold(0.0_f64, |s, a| s.max(a[i].abs()));
            assert!(scale > 0.0 && scale.is_finite(), "{}: row {i}", preset.name);
            for (k, (a, b)) in plan.iter().zip(&by_forms).enumerate() {
                assert!(
                    (a[i] - b[i]).abs() <= 1e-12 * scale,
                    "{}: {} at point {k}: plan {:e}, forms {:e}",
                    preset.name,
                    m.state_names()[i],
                    a[i],
                    b[i]
                );
            }
        }
    }
    assert!(presets_with_rows >= 3, "{presets_with_rows} presets");
}

/// The forms of a communication point (the outputs and rows that are not affine) give the
/// plan's values to rounding: the same outputs and rows, each within 1e-12 of its largest
/// magnitude over the points, near rest and far from it (up to 1000 times the nominals, where
/// an explicit method's divergence takes the states), on every preset with such rows.
#[test]
fn forms_of_a_communication_point_are_the_plans_values() {
    let mut presets_with_rows = 0;
    for preset in presets::PRESETS {
        let system = Assembled::new(&parameters(preset.name)).unwrap();
        let m = system.compiled();
        if m.nonaffine_rows().is_empty() {
            continue;
        }
        presets_with_rows += 1;
        let forms = m.nonaffine_point_forms();
        let mut pts = points(&system, 20, 0.1, 11);
        pts.extend(points(&system, 20, 1.0, 13));
        pts.extend(points(&system, 20, 10.0, 15));
        pts.extend(points(&system, 20, 1000.0, 19));
        // (output, value) and (row, value) as each reports them, outputs first.
        let mut plan = Vec::new();
        let mut by_forms = Vec::new();
        for (x, u) in &pts {
            let named = |names: &[String], v: &mut Vec<(String, f64)>, k: usize, value| {
                v.push((names[k].clone(), value))
            };
            let (mut a, mut a_rows, mut b, mut b_rows) = (vec![], vec![], vec![], vec![]);
            m.for_each_nonaffine_output_and_derivative(
                x,
                u,
                |k, v| named(m.output_names(), &mut a, k, v),
                |i, v| named(m.state_names(), &mut a_rows, i, v),
            );
            forms.for_each(
                m,
                x,
                u,
                |k, v| named(m.output_names(), &mut b, k, v),
                |i, v| named(m.state_names(), &mut b_rows, i, v),
            );
            a.extend(a_rows);
            b.extend(b_rows);
            let names = |v: &[(String, f64)]| v.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
            assert_eq!(names(&a), names(&b), "{}", preset.name);
            assert_eq!(
                a.len(),
                m.nonaffine_outputs().len() + m.nonaffine_rows().len()
            );
            plan.push(a);
            by_forms.push(b);
        }
        for i in 0..plan[0].len() {
            let scale = plan.iter().fold(0.0_f64, |s, a| s.max(a[i].1.abs()));
            assert!(scale.is_finite(), "{}: {}", preset.name, plan[0][i].0);
            for (k, (a, b)) in plan.iter().zip(&by_forms).enumerate() {
                assert!(
                    (a[i].1 - b[i].1).abs() <= 1e-12 * scale,
                    "{}: {} at point {k}: plan {:e}, forms {:e}",
                    preset.name,
                    a[i].0,
                    a[i].1,
                    b[i].1
                );
            }
        }
    }
    assert!(presets_with_rows >= 3, "{presets_with_rows} presets");
}

/// The forms of the affine rows' and outputs' offsets give the plan's `f_i(0, u)` and
/// `y_k(0, u)` to rounding: within 1e-12 of the largest magnitude over the inputs tried, on
/// every preset.
#[test]
fn forms_of_the_affine_offsets_are_the_plans_values() {
    let mut compared = 0;
    for preset in presets::PRESETS {
        let system = Assembled::new(&parameters(preset.name)).unwrap();
        let m = system.compiled();
        let forms = m.affine_offset_forms();
        let (n, o) = (m.n_states(), m.n_outputs());
        let mut pts = points(&system, 20, 0.0, 3);
        for (k, (_, u)) in pts.iter_mut().enumerate() {
            // Inputs from small to large.
            u.iter_mut()
                .for_each(|v| *v *= 10f64.powi(k as i32 % 5 - 1));
        }
        let mut results = Vec::new();
        for (_, u) in &pts {
            let (mut a, mut b) = (vec![f64::NAN; n], vec![f64::NAN; n]);
            let (mut ya, mut yb) = (vec![f64::NAN; o], vec![f64::NAN; o]);
            m.affine_offsets(u, &mut a);
            forms.rows(m, u, &mut b);
            m.affine_output_offsets(u, &mut ya);
            forms.outputs(m, u, &mut yb);
            a.extend(ya);
            b.extend(yb);
            // The same entries are written.
            for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                assert_eq!(x.is_nan(), y.is_nan(), "{}: entry {i}", preset.name);
            }
            results.push((a, b));
        }
        for i in 0..n + o {
            let scale = results.iter().fold(0.0_f64, |s, (a, _)| s.max(a[i].abs()));
            for (k, (a, b)) in results.iter().enumerate() {
                if a[i].is_nan() {
                    continue;
                }
                assert!(
                    (a[i] - b[i]).abs() <= 1e-12 * scale,
                    "{}: entry {i} at point {k}: plan {:e}, forms {:e}",
                    preset.name,
                    a[i],
                    b[i]
                );
                compared += 1;
            }
        }
    }
    assert!(compared > 1000, "{compared} values compared");
}
