//! Rough timing of the compiled plan: derivatives and Jacobian of the LOES and of a chain of 20
//! masses (`cargo run --release --bin bench-plan`). A benchmark, not a test: it prints figures
//! and asserts nothing.

use std::time::Instant;

use hydraulic_slewing_plate::bond_graph::{BondGraph, CompiledModel};
use hydraulic_slewing_plate::fragments::controller::ControllerParameters;
use hydraulic_slewing_plate::fragments::loes::{self, LoesParameters};
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
    let mut dx = vec![0.0; n];
    let reps = 200_000;
    let t = Instant::now();
    let mut acc = 0.0;
    for _ in 0..reps {
        m.derivatives(&x, &u, &mut dx);
        acc += dx[0];
    }
    let per = t.elapsed().as_secs_f64() / reps as f64;
    let mut jac = DMatrix::zeros(n, n);
    let jr = 2_000;
    let t = Instant::now();
    for _ in 0..jr {
        m.jacobian(&x, &u, &mut jac);
    }
    let perj = t.elapsed().as_secs_f64() / jr as f64;
    println!(
        "{label}: {n} states, {} ops: derivatives {:.3} us, jacobian {:.1} us ({acc:e})",
        m.plan_len(),
        per * 1e6,
        perj * 1e6
    );
}

fn main() {
    let l = loes::build_loop(&LoesParameters::default(), &ControllerParameters::default())
        .compile()
        .unwrap();
    time("LOES", &l);
    time("chain 20", &chain(20));
}
