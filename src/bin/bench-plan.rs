//! Rough timing of the compiled plan: derivatives and Jacobian of the LOES, of a chain of 20
//! masses, and of the complete system with the full servo valve (preset `complete`, 44 states),
//! whose Jacobian is timed twice in the same run: every entry evaluated, and with the constant
//! entries fixed once (`CompiledModel::fix_constant_entries`); then what the integrators call
//! at every stage and step (the assembled model's right-hand side, the affine rows as a sparse
//! product and the others as forms, and its varying Jacobian entries from the forms, beside the
//! same entries by the plan's tangent sweeps) (`cargo run --release --bin bench-plan`). A benchmark, not a test: it prints figures and
//! asserts nothing.

use std::time::Instant;

use hydraulic_slewing_plate::bond_graph::{BondGraph, CompiledModel};
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::loes::{self, LoesParameters};
use hydraulic_slewing_plate::model::parameters::Parameters;
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::VARIABLES;
use hydraulic_slewing_plate::model::{assembly::Assembled, compose::bond_graph};
use hydraulic_slewing_plate::solver::OdeSystem;
use nalgebra::DMatrix;

/// A chain of `n` masses and springs driven by a force: 2n states.
fn chain(n: usize) -> CompiledModel {
    let mut g = BondGraph::new("chain");
    let f = g.add_input("F");
    let se = g.add_se("force", f);
    let mut prev = g.add_one("v0");
    g.bond(se, prev);
    let m0 = g.add_i("m0", 1.0);
    g.bond(prev, m0);
    for k in 1..n {
        let z = g.add_zero(format!("s{k}"));
        let c = g.add_c(format!("k{k}"), 1e-3);
        let d = g.add_r(format!("d{k}"), 0.1);
        let j = g.add_one(format!("v{k}"));
        let m = g.add_i(format!("m{k}"), 1.0 + k as f64);
        g.bond(prev, z);
        g.bond(z, c);
        g.bond(z, j);
        g.bond(j, d);
        g.bond(j, m);
        prev = j;
    }
    g.compile().unwrap()
}

fn time(label: &str, m: &CompiledModel) {
    let n = m.n_states();
    let x: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
    let u = vec![1.0; m.n_inputs()];
    time_at(label, m, &x, &u);
}

/// Time per Jacobian of `m` at `(x, u)`, in µs.
fn jacobian_time(m: &CompiledModel, x: &[f64], u: &[f64]) -> f64 {
    let n = m.n_states();
    let mut jac = DMatrix::zeros(n, n);
    let reps = 20_000;
    let t = Instant::now();
    for _ in 0..reps {
        m.jacobian(x, u, &mut jac);
    }
    t.elapsed().as_secs_f64() / reps as f64 * 1e6
}

/// Mean time of `f` over `reps` calls, in µs.
fn mean_time(reps: usize, mut f: impl FnMut()) -> f64 {
    let t = Instant::now();
    for _ in 0..reps {
        f();
    }
    t.elapsed().as_secs_f64() / reps as f64 * 1e6
}

fn time_at(label: &str, m: &CompiledModel, x: &[f64], u: &[f64]) {
    let n = m.n_states();
    let mut dx = vec![0.0; n];
    let reps = 200_000;
    let t = Instant::now();
    let mut acc = 0.0;
    for _ in 0..reps {
        m.derivatives(x, u, &mut dx);
        acc += dx[0];
    }
    let per = t.elapsed().as_secs_f64() / reps as f64;
    println!(
        "{label}: {n} states, {} ops: derivatives {:.3} us, jacobian {:.1} us ({acc:e})",
        m.plan_len(),
        per * 1e6,
        jacobian_time(m, x, u)
    );
}

fn main() {
    let l = loes::build_loop(&LoesParameters::default(), &ControllerParameters::default())
        .compile()
        .unwrap();
    time("LOES", &l);
    time("chain 20", &chain(20));

    let mut values = Values::from_start(&VARIABLES);
    presets::apply(&mut values, presets::COMPLETE).unwrap();
    let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
    let system = Assembled::new(&p).unwrap();
    let fixed = system.compiled();
    let full = bond_graph(&p).unwrap().compile().unwrap();
    // Off rest by a tenth of each state's nominal value, inputs at 0.5.
    let x: Vec<f64> = system
        .initial_state()
        .iter()
        .zip(system.nominal())
        .enumerate()
        .map(|(i, (r, n))| r + 0.1 * n * (i as f64).sin())
        .collect();
    let u = vec![0.5; full.n_inputs()];
    time_at("complete (servo valve)", &full, &x, &u);
    // Alternate the two Jacobians so that a change of the machine's speed hits both.
    let (mut t_full, mut t_fixed) = (Vec::new(), Vec::new());
    for _ in 0..5 {
        t_full.push(jacobian_time(&full, &x, &u));
        t_fixed.push(jacobian_time(fixed, &x, &u));
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "complete (servo valve) Jacobian, median of 5 alternating runs: every entry {:.2} us \
         ({} passes of {} ops), constant entries fixed {:.2} us ({} groups: {} ops as dual passes, {} as a value pass \
         and tangent sweeps)",
        median(&mut t_full),
        full.jacobian_colours(),
        full.derivative_plan_len(),
        median(&mut t_fixed),
        fixed.variable_jacobian_colours(),
        fixed.variable_jacobian_pass_ops(),
        fixed.variable_jacobian_ops(),
    );
    // What the integrators call, alternating the same way: the right-hand side, and the
    // varying entries from the forms against the same entries by tangent sweeps.
    let n = system.dim();
    let (mut dx, mut jac) = (vec![0.0; n], DMatrix::zeros(n, n));
    let inputs = system.inputs().to_vec();
    let (mut t_rhs, mut t_forms, mut t_sweeps) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..5 {
        t_rhs.push(mean_time(200_000, || system.rhs(0.0, &x, &mut dx)));
        t_forms.push(mean_time(100_000, || {
            assert!(system.jacobian_varying(0.0, &x, &mut jac));
        }));
        t_sweeps.push(mean_time(20_000, || {
            assert!(fixed.jacobian_varying_by_sweeps(&x, &inputs, &mut jac));
        }));
    }
    let varying: usize = fixed.jacobian_varying_pattern().iter().map(Vec::len).sum();
    println!(
        "complete (servo valve) as the integrators call it, median of 5 alternating runs: \
         right-hand side {:.3} us; the {varying} varying entries from the forms {:.3} us, by \
         tangent sweeps {:.3} us",
        median(&mut t_rhs),
        median(&mut t_forms),
        median(&mut t_sweeps),
    );
}
