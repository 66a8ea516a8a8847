//! What the loop-margin monitor (`src/model/margin.rs`) costs: the Jacobian at rest and its
//! balanced eigenvalues, computed once when the model is built, beside the building of the model
//! itself and the default run's stepping, in the same process.
//!
//! ```text
//! cargo run --release --bin bench-margin [-- --rounds 5]
//! ```
//!
//! For the default (46 states) and the default with a 20 x 20 consistent plate (816 states):
//! median and range over the rounds of building the model (`Assembled::new`), of the margin, and
//! (default only) of the default experiment's 6 s run through the library's integrator, stopped at
//! each of its 1200 communication points (no dense output, so more steps than `hsp run` takes).

use std::time::Instant;

use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::margin::least_damped_sliding;
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::VARIABLES;
use hydraulic_slewing_plate::solver::Integrator;

fn parameters(sets: &[(&str, &str)]) -> Parameters {
    let mut values = Values::from_start(&VARIABLES);
    for (n, v) in sets {
        set_by_name(&mut values, n, v).expect("setting");
    }
    Parameters::from_values(&values, &Experiment::default()).expect("parameters")
}

/// Median and range of `rounds` timings of `f`, in seconds.
fn time<F: FnMut()>(rounds: usize, mut f: F) -> (f64, f64, f64) {
    let mut t: Vec<f64> = (0..rounds)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    (t[t.len() / 2], t[0], t[t.len() - 1])
}

fn show(label: &str, (median, lo, hi): (f64, f64, f64)) {
    println!(
        "  {label:<34} median {:>10.3} ms, range {:.3} .. {:.3} ms",
        median * 1e3,
        lo * 1e3,
        hi * 1e3
    );
}

fn main() {
    let mut rounds = 5;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--rounds" => {
                rounds = args
                    .next()
                    .and_then(|s| s.parse().ok())
                    .expect("--rounds N")
            }
            other => panic!("unknown argument {other}"),
        }
    }
    for (label, sets) in [
        ("default (preset complete)", vec![]),
        (
            "default, 20 x 20 consistent plate",
            vec![("plate.N", "20"), ("plate.M", "20")],
        ),
    ] {
        let p = parameters(&sets);
        let system = Assembled::new(&p).expect("model");
        let mode = least_damped_sliding(&system, &p).expect("a mode");
        println!(
            "{label}: {} states; least damped mode at rest {:.3} Hz, zeta {:.4}; {rounds} rounds",
            system.dim(),
            mode.frequency_hz(),
            mode.zeta
        );
        show(
            "building the model",
            time(rounds, || {
                Assembled::new(&p).expect("model");
            }),
        );
        show(
            "the loop margin",
            time(rounds, || {
                least_damped_sliding(&system, &p);
            }),
        );
        if sets.is_empty() {
            show(
                "the default run, 6 s, 1200 points of 5 ms",
                time(rounds, || {
                    let mut integ =
                        Integrator::new(p.solver_options(&system), 0.0, system.initial_state())
                            .expect("integrator");
                    for k in 1..=1200 {
                        integ.advance_to(&system, k as f64 * 0.005).expect("step");
                    }
                }),
            );
        }
    }
}
