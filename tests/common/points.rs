//! What the tests of the compiled plan's kernels share (`jacobian_constant_entries.rs`,
//! `plan_kernels.rs`): a preset's parameters, and scattered points around the rest state.

#![allow(dead_code)]

use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::presets;
use hydraulic_slewing_plate::model::variables::VARIABLES;

/// The parameters of `preset` with `sets` applied after it.
pub fn parameters_with(preset: &str, sets: &[(&str, &str)]) -> Parameters {
    let mut values = Values::from_start(&VARIABLES);
    presets::apply(&mut values, preset).unwrap();
    for (n, v) in sets {
        set_by_name(&mut values, n, v).unwrap();
    }
    Parameters::from_values(&values, &Experiment::default()).unwrap()
}

/// The parameters of `preset`.
pub fn parameters(preset: &str) -> Parameters {
    parameters_with(preset, &[])
}

/// `count` points `(x, u)` around the rest state: each state off rest by `spread` times its
/// nominal value times a number from `next` (in [-1, 1]), each input a number from `next`.
pub fn around_rest(
    system: &Assembled,
    count: usize,
    spread: f64,
    mut next: impl FnMut() -> f64,
) -> Vec<(Vec<f64>, Vec<f64>)> {
    let rest = system.initial_state();
    (0..count)
        .map(|_| {
            let x = rest
                .iter()
                .zip(system.nominal())
                .map(|(r, n)| r + spread * n * next())
                .collect();
            let u = (0..system.compiled().n_inputs()).map(|_| next()).collect();
            (x, u)
        })
        .collect()
}
