//! The Jacobian's constant entries, fixed once per parameter set
//! (`CompiledModel::fix_constant_entries`, called by `Assembled::new`): on every preset, the
//! structural analysis agrees with the constant flag, the entries it calls constant are the same
//! at every point, and the Jacobian with the fixed entries has the bits of a full evaluation.

use hydraulic_slewing_plate::bond_graph::CompiledModel;
#[path = "common/points.rs"]
mod points;

use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::{assembly::Assembled, compose::bond_graph};
use nalgebra::DMatrix;
use points::{parameters, parameters_with};

/// `count` points `(x, u)` around the rest state: each state off rest by up to `spread` times
/// its nominal value, inputs in [-1, 1], scattered by the sines of unrelated integers.
fn points(system: &Assembled, count: usize, spread: f64, seed: u64) -> Vec<(Vec<f64>, Vec<f64>)> {
    let mut k = seed;
    points::around_rest(system, count, spread, move || {
        k += 1;
        ((k * 7919) as f64).sin()
    })
}

/// Whether `a` and `b` hold the same bits, entry by entry.
fn same_bits(a: &DMatrix<f64>, b: &DMatrix<f64>) -> bool {
    a.iter()
        .zip(b.iter())
        .all(|(x, y)| x.to_bits() == y.to_bits())
}

fn jacobian(m: &CompiledModel, x: &[f64], u: &[f64]) -> DMatrix<f64> {
    let n = m.n_states();
    let mut jac = DMatrix::zeros(n, n);
    m.jacobian(x, u, &mut jac);
    jac
}

#[test]
fn constant_flag_means_no_variable_column_on_every_preset() {
    for preset in presets::PRESETS {
        let system = Assembled::new(&parameters(preset.name)).unwrap();
        let m = system.compiled();
        let varying = m.jacobian_varying_pattern();
        for (i, (v, p)) in varying.iter().zip(m.jacobian_pattern()).enumerate() {
            assert!(
                v.iter().all(|j| p.contains(j)),
                "{}: row {i} varies outside its pattern",
                preset.name
            );
        }
        let variable = m.jacobian_variable_columns();
        assert_eq!(
            m.jacobian_is_constant(),
            variable.is_empty(),
            "{}: constant flag against {} variable columns",
            preset.name,
            variable.len()
        );
        assert_eq!(
            m.variable_jacobian_colours() == 0,
            m.jacobian_is_constant(),
            "{}",
            preset.name
        );
        assert!(m.variable_jacobian_colours() <= m.jacobian_colours());
        assert!(m.constant_entries_fixed(), "{}", preset.name);
        println!(
            "{:<20} {} states, {} variable columns, {} of {} entries vary; passes {} -> {}, \
             operations {} -> {}",
            preset.name,
            m.n_states(),
            variable.len(),
            varying.iter().map(Vec::len).sum::<usize>(),
            m.jacobian_pattern().iter().map(Vec::len).sum::<usize>(),
            m.jacobian_colours(),
            m.variable_jacobian_colours(),
            m.jacobian_colours() * m.derivative_plan_len(),
            m.variable_jacobian_ops(),
        );
    }
}

#[test]
fn the_servo_valve_needs_less_work_with_fixed_entries() {
    // The point of fixing the constant entries: the plate, hub, torsion bar and controller are
    // linear, so only the servo valve's and the motor's columns vary. Where the plate couples to
    // the motor (`complete`), that saves passes; in every servo valve preset it shortens each
    // pass to the operations of the rows it reads. (The air drag and the command generator's
    // clock, both nonlinear, add the plate's momenta and the clock: without them here.)
    for preset in ["complete", "complete-hub-locked", "servo-valve-motor"] {
        let p = parameters_with(preset, &[("plate.Cd", "0"), ("reference.angle", "0")]);
        let system = Assembled::new(&p).unwrap();
        let m = system.compiled();
        assert!(!m.jacobian_is_constant());
        assert!(
            m.jacobian_variable_columns().len() < m.n_states() / 2,
            "{preset}: {} variable columns of {}",
            m.jacobian_variable_columns().len(),
            m.n_states()
        );
        assert!(
            m.variable_jacobian_colours() <= m.jacobian_colours(),
            "{preset}"
        );
        assert!(
            3 * m.variable_jacobian_ops() < m.jacobian_colours() * m.derivative_plan_len(),
            "{preset}: {} of {} operations",
            m.variable_jacobian_ops(),
            m.jacobian_colours() * m.derivative_plan_len()
        );
    }
    let complete = Assembled::new(&parameters(presets::COMPLETE)).unwrap();
    let m = complete.compiled();
    assert!(m.variable_jacobian_colours() < m.jacobian_colours());
}

#[test]
fn entries_called_constant_are_the_same_everywhere() {
    // Full evaluations (no fixed entries) at random points: every entry outside the varying
    // pattern has the bits it has at rest. A rule of the analysis that missed a nonlinearity
    // would show here.
    for preset in presets::PRESETS {
        let p = parameters(preset.name);
        let system = Assembled::new(&p).unwrap();
        let full = bond_graph(&p).unwrap().compile().unwrap();
        assert!(!full.constant_entries_fixed());
        let at_rest = jacobian(&full, &system.initial_state(), system.inputs());
        for (x, u) in points(&system, 8, 0.1, 1) {
            let jac = jacobian(&full, &x, &u);
            for (i, row) in full.jacobian_pattern().iter().enumerate() {
                let varying = &full.jacobian_varying_pattern()[i];
                for &j in row.iter().filter(|j| !varying.contains(j)) {
                    let (a, b) = (at_rest[(i, j as usize)], jac[(i, j as usize)]);
                    assert_eq!(
                        a.to_bits(),
                        b.to_bits(),
                        "{}: constant entry ({i}, {j}) is {a:e} at rest, {b:e} at {x:?}",
                        preset.name
                    );
                }
            }
        }
    }
}

#[test]
fn fixed_entries_give_the_bits_of_a_full_evaluation() {
    // `Assembled::new` fixes the constant entries at rest; a model compiled from the same
    // parameters without the fix evaluates every entry at the point. Both must agree bit for
    // bit at points near rest and farther off it.
    for preset in presets::PRESETS {
        let p = parameters(preset.name);
        let system = Assembled::new(&p).unwrap();
        let fixed = system.compiled();
        let full = bond_graph(&p).unwrap().compile().unwrap();
        let mut pts = points(&system, 8, 0.1, 1000);
        pts.extend(points(&system, 8, 0.5, 2000));
        for (x, u) in pts {
            let (a, b) = (jacobian(&full, &x, &u), jacobian(fixed, &x, &u));
            for i in 0..a.nrows() {
                for j in 0..a.ncols() {
                    assert_eq!(
                        a[(i, j)].to_bits(),
                        b[(i, j)].to_bits(),
                        "{}: entry ({i}, {j}): full {:e}, fixed {:e}",
                        preset.name,
                        a[(i, j)],
                        b[(i, j)]
                    );
                }
            }
        }
    }
}

/// `jacobian_varying` on a buffer that holds a J of the same model (written at another point)
/// gives, point after point, the bits of a full evaluation there: the update the integrators
/// make at every step for a Jacobian with varying entries.
#[test]
fn varying_update_gives_the_bits_of_a_full_evaluation() {
    for preset in presets::PRESETS {
        let system = Assembled::new(&parameters(preset.name)).unwrap();
        let m = system.compiled();
        if m.jacobian_is_constant() {
            continue;
        }
        let pts = points(&system, 8, 0.5, 3000);
        let (x0, u0) = &pts[0];
        let mut held = jacobian(m, x0, u0);
        for (x, u) in &pts[1..] {
            assert!(m.jacobian_varying(x, u, &mut held), "{}", preset.name);
            let full = jacobian(m, x, u);
            assert!(
                same_bits(&held, &full),
                "{}: the update differs from the full J",
                preset.name
            );
        }
    }
}

/// The varying entries from the forms of the rows that are not affine, by the chain rule
/// through their nonlinear operations (`FormsJacobian`, what the integrators use), against the
/// plan's tangent sweeps (dual numbers through every operation, an independent evaluation of
/// the same derivatives): on every preset and on the default with a 20 x 20 consistent plate,
/// at points near and far from rest, every varying entry agrees within 1e-13 of the largest
/// entry of its row; the forms reach no entry the structure calls constant.
#[test]
fn the_forms_give_the_varying_entries_of_the_sweeps() {
    let mut cases: Vec<(String, Assembled)> = presets::PRESETS
        .iter()
        .map(|p| {
            (
                p.name.to_string(),
                Assembled::new(&parameters(p.name)).unwrap(),
            )
        })
        .collect();
    let large = parameters_with("complete", &[("plate.N", "20"), ("plate.M", "20")]);
    cases.push(("complete 20 x 20".into(), Assembled::new(&large).unwrap()));
    let mut checked = 0;
    for (name, system) in &cases {
        let m = system.compiled();
        if m.jacobian_is_constant() {
            continue;
        }
        let forms = m.nonaffine_forms();
        let by_forms = forms.jacobian(m.n_states(), m.jacobian_varying_pattern());
        assert_eq!(
            by_forms.unlisted(),
            0,
            "{name}: the chain reaches constant entries"
        );
        let (entries, links) = by_forms.size();
        println!("{name:<20} {entries} varying entries, {links} chain links");
        let mut worst: f64 = 0.0;
        for (spread, seed) in [(0.1, 11), (1.0, 12), (3.0, 13)] {
            for (x, u) in points(system, 6, spread, seed) {
                let full = jacobian(m, &x, &u);
                let mut a = full.clone();
                let mut b = full.clone();
                a.fill(f64::NAN);
                b.fill(f64::NAN);
                assert!(
                    by_forms.varying_entries(&forms, m, &x, &u, &mut a),
                    "{name}"
                );
                assert!(m.jacobian_varying_by_sweeps(&x, &u, &mut b), "{name}");
                for (i, row) in m.jacobian_varying_pattern().iter().enumerate() {
                    let scale = full.row(i).iter().fold(0.0f64, |s, v| s.max(v.abs()));
                    for &j in row {
                        let (fa, fb) = (a[(i, j as usize)], b[(i, j as usize)]);
                        let error = (fa - fb).abs() / scale;
                        assert!(error <= 1e-13, "{name}: ({i}, {j}) {fa:e} against {fb:e}");
                        worst = worst.max(error);
                        checked += 1;
                    }
                }
            }
        }
        println!("{name:<20} largest difference {worst:.1e} of the row's largest entry");
    }
    assert!(checked > 0);
}

/// The servo valve's rest state by Newton steps through the LU with partial pivoting (what the
/// FMU does) is the one by least-norm SVD steps (the reference, which handles singular
/// Jacobians), on every preset with the full valve and on the default with a 20 x 20 plate:
/// every state within 1e-10 of its nominal value.
#[test]
fn the_lu_rest_state_is_the_least_norm_one() {
    use hydraulic_slewing_plate::fragments::servo_valve::rest::rest_state_least_norm;
    use hydraulic_slewing_plate::model::parameters::HydraulicsModel;
    let mut cases: Vec<(String, _)> = presets::PRESETS
        .iter()
        .map(|p| (p.name.to_string(), parameters(p.name)))
        .collect();
    let large = parameters_with("complete", &[("plate.N", "20"), ("plate.M", "20")]);
    cases.push(("complete 20 x 20".into(), large));
    let mut checked = 0;
    for (name, p) in &cases {
        if !matches!(p.hydraulics, HydraulicsModel::ServoValve) {
            continue;
        }
        let system = Assembled::new(p).unwrap();
        let m = system.compiled();
        let u = vec![0.0; m.n_inputs()];
        let reference =
            rest_state_least_norm(m, &u, "servo_valve", &p.servo_valve, system.nominal()).unwrap();
        let rest = system.initial_state();
        for (i, ((a, b), n)) in rest
            .iter()
            .zip(&reference)
            .zip(system.nominal())
            .enumerate()
        {
            assert!(
                (a - b).abs() <= 1e-10 * n,
                "{name}: {} {a:e} against {b:e}",
                m.state_names()[i]
            );
        }
        checked += 1;
    }
    assert!(checked >= 3, "{checked}");
}

/// The assembled model's full Jacobian and its update of a held one (`OdeSystem::jacobian`
/// and `OdeSystem::jacobian_varying`, what the integrators call) give the same bits point after
/// point, on every preset: a restored FMU state starts from a full evaluation where the run it
/// repeats updated a held matrix.
#[test]
fn the_assembled_jacobian_and_its_update_agree_to_the_bit() {
    use hydraulic_slewing_plate::solver::OdeSystem;
    let mut checked = 0;
    for preset in presets::PRESETS {
        let system = Assembled::new(&parameters(preset.name)).unwrap();
        if system.jacobian_constant_part().is_none() {
            continue;
        }
        let n = system.dim();
        let pts = points(&system, 8, 0.5, 4000);
        let mut held = DMatrix::zeros(n, n);
        system.jacobian(0.0, &pts[0].0, &mut held);
        for (x, _) in &pts[1..] {
            assert!(
                system.jacobian_varying(0.0, x, &mut held),
                "{}",
                preset.name
            );
            let mut full = DMatrix::from_element(n, n, f64::NAN);
            system.jacobian(0.0, x, &mut full);
            assert!(
                same_bits(&held, &full),
                "{}: the update differs from the full J",
                preset.name
            );
            checked += 1;
        }
    }
    assert!(checked > 0);
}
