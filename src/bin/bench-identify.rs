//! What a fit of `hsp identify` (docs/identify.md) costs: the three-parameter fit of the worked
//! synthetic case (`servo_valve.beta`, `plate.zeta`, `torsion_bar.k` from the defaults) to two
//! responses of 200 points (r to y_pot and to acc_tip, 0.5 to 120 Hz), the command run as a user
//! runs it, and one model evaluation (a linearisation and the 400 responses) in this process,
//! which splits the cost of an iteration.
//!
//! ```text
//! cargo build --release --bin hsp --bin bench-identify && target/release/bench-identify [--rounds 5] [--hsp PATH]...
//! ```
//!
//! `--hsp PATH` (repeatable; default: the `hsp` beside this binary) times each build given, the
//! rounds interleaved, so that a build before a change and after it are measured side by side in
//! one run. A build that has `--sensitivities` is timed twice, with the exact sensitivities and
//! with central differences (`--sensitivities central`), side by side; in this process the bench
//! also times the exact derivatives of one linearisation with respect to the three parameters
//! ([`linearization_at_rest_with_derivatives`]), what an exact Jacobian costs the model. The data are the generating model's responses without noise (the noisy case of the
//! docs takes the same number of iterations give or take one; the iterations and evaluations
//! printed are this run's). The machine's load (`/proc/loadavg`, the 1-minute average) is
//! printed before and after.

#[allow(dead_code)]
#[path = "bench-common/machine.rs"]
mod machine;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use hydraulic_slewing_plate::bond_graph::Linearization;
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::frf::{output_of, state_response_at};
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::sensitivity::linearization_at_rest_with_derivatives;
use hydraulic_slewing_plate::model::variables::VARIABLES;

/// The generating values of the docs' synthetic case (defaults 1.4e9 Pa, 0.02, 2500 N m/rad).
const TRUTH: [(&str, f64); 3] = [
    ("servo_valve.beta", 1.0e9),
    ("plate.zeta", 0.03),
    ("torsion_bar.k", 3200.0),
];
const OUTPUTS: [&str; 2] = ["y_pot", "acc_tip"];
const POINTS: usize = 200;

/// The frequencies: log-spaced from 0.5 to 120 Hz.
fn frequencies() -> Vec<f64> {
    (0..POINTS)
        .map(|k| 0.5 * (120.0f64 / 0.5).powf(k as f64 / (POINTS - 1) as f64))
        .collect()
}

/// The linearisation of `hsp identify` (at rest, the vane motor sliding) with `sets` applied to
/// the FMU's start values.
fn linearization(sets: &[(&str, f64)]) -> Linearization {
    let mut values = Values::from_start(&VARIABLES);
    for (name, v) in sets {
        set_by_name(&mut values, name, &format!("{v:?}")).expect("a parameter");
    }
    let p = Parameters::from_values(&values, &Experiment::default()).expect("parameters");
    let system = Assembled::new(&p.sliding()).expect("the model");
    system
        .compiled()
        .linearize(&system.initial_state(), system.inputs())
}

/// One model evaluation as the fit makes it: the linearisation and, per frequency, one solve for
/// the input `r` shared by the two outputs. The responses, per output.
fn evaluate(sets: &[(&str, f64)], f_hz: &[f64]) -> Vec<Vec<nalgebra::Complex<f64>>> {
    let lin = linearization(sets);
    let input = lin.input_names.iter().position(|n| n == "r").expect("r");
    let outputs: Vec<usize> = OUTPUTS
        .iter()
        .map(|o| {
            lin.output_names
                .iter()
                .position(|n| n == o)
                .expect("output")
        })
        .collect();
    let mut h = vec![Vec::with_capacity(f_hz.len()); outputs.len()];
    for &f in f_hz {
        let x = state_response_at(&lin, input, f).expect("bounded");
        for (k, &o) in outputs.iter().enumerate() {
            h[k].push(output_of(&lin, &x, input, o));
        }
    }
    h
}

/// Median, lowest and highest of `t`.
fn summary(t: &mut [f64]) -> (f64, f64, f64) {
    t.sort_by(f64::total_cmp);
    (t[t.len() / 2], t[0], t[t.len() - 1])
}

/// What to time (module doc).
#[derive(clap::Parser)]
struct Args {
    /// Rounds of each timing
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    rounds: u32,
    /// A build of hsp to time (repeatable; default: the hsp beside this binary)
    #[arg(long = "hsp", value_name = "PATH")]
    builds: Vec<PathBuf>,
}

fn main() {
    let Args { rounds, mut builds } = clap::Parser::parse();
    if builds.is_empty() {
        let me = std::env::current_exe().expect("this binary's path");
        builds.push(me.with_file_name("hsp"));
    }
    let dir = std::env::temp_dir().join(format!("bench-identify-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let f_hz = frequencies();
    let mut frfs = Vec::new();
    for (output, h) in OUTPUTS.iter().zip(evaluate(&TRUTH, &f_hz)) {
        let mut csv = String::from("f_Hz,re,im\n");
        for (f, h) in f_hz.iter().zip(h) {
            csv.push_str(&format!("{f:?},{:?},{:?}\n", h.re, h.im));
        }
        let file = dir.join(format!("{output}.csv"));
        std::fs::write(&file, csv).expect("writing the data");
        frfs.push(format!("r:{output}:{}", file.display()));
    }
    println!(
        "bench-identify: 3 parameters ({}) from 2 responses of {POINTS} points (r to {}), {rounds} \
         rounds; load before {}",
        TRUTH.map(|t| t.0).join(", "),
        OUTPUTS.join(", "),
        machine::load()
    );
    // Each build, and each way of its sensitivities where it has the choice.
    let mut variants: Vec<(PathBuf, Option<&str>)> = Vec::new();
    for hsp in &builds {
        let help = Command::new(hsp)
            .args(["identify", "--help"])
            .output()
            .expect("running hsp");
        if String::from_utf8_lossy(&help.stdout).contains("--sensitivities") {
            variants.push((hsp.clone(), Some("exact")));
            variants.push((hsp.clone(), Some("central")));
        } else {
            variants.push((hsp.clone(), None));
        }
    }
    let run = |hsp: &Path, way: Option<&str>| -> (f64, serde_json::Value) {
        let mut cmd = Command::new(hsp);
        cmd.args(["identify", "--json"]);
        if let Some(way) = way {
            cmd.args(["--sensitivities", way]);
        }
        for f in &frfs {
            cmd.args(["--frf", f]);
        }
        for (name, _) in TRUTH {
            cmd.args(["--fit", name]);
        }
        let start = Instant::now();
        let out = cmd.output().expect("running hsp");
        let t = start.elapsed().as_secs_f64();
        assert!(
            out.status.success(),
            "{}: {}",
            hsp.display(),
            String::from_utf8_lossy(&out.stderr)
        );
        (t, serde_json::from_slice(&out.stdout).expect("JSON"))
    };
    let mut times = vec![Vec::new(); variants.len()];
    let mut last = vec![serde_json::Value::Null; variants.len()];
    let mut evaluation = Vec::new();
    let mut exact = Vec::new();
    let defaults = Values::from_start(&VARIABLES);
    let seeds: Vec<usize> = TRUTH
        .iter()
        .map(|(name, _)| {
            VARIABLES
                .iter()
                .position(|v| v.name == *name)
                .expect("a variable")
        })
        .collect();
    for _ in 0..rounds {
        for (b, (hsp, way)) in variants.iter().enumerate() {
            let (t, json) = run(hsp, *way);
            times[b].push(t);
            last[b] = json;
        }
        let start = Instant::now();
        std::hint::black_box(evaluate(&[], &f_hz));
        evaluation.push(start.elapsed().as_secs_f64());
        let start = Instant::now();
        std::hint::black_box(linearization_at_rest_with_derivatives(&defaults, &seeds).ok());
        exact.push(start.elapsed().as_secs_f64());
    }
    let (e_med, e_lo, e_hi) = summary(&mut evaluation);
    let (x_med, x_lo, x_hi) = summary(&mut exact);
    println!(
        "one model evaluation (linearisation and 400 responses), in this process: median {:.1} ms, \
         range {:.1} .. {:.1} ms",
        e_med * 1e3,
        e_lo * 1e3,
        e_hi * 1e3
    );
    let exact_of: Vec<String> = linearization_at_rest_with_derivatives(&defaults, &seeds)
        .map(|(_, d)| {
            d.iter()
                .map(|d| if d.is_ok() { "exact" } else { "not available" }.to_string())
                .collect()
        })
        .unwrap_or_default();
    println!(
        "the linearisation and its exact derivatives with respect to the 3 parameters ({}), in \
         this process: median {:.1} ms, range {:.1} .. {:.1} ms",
        exact_of.join(", "),
        x_med * 1e3,
        x_lo * 1e3,
        x_hi * 1e3
    );
    for (b, (hsp, way)) in variants.iter().enumerate() {
        let (med, lo, hi) = summary(&mut times[b]);
        let json = &last[b];
        let iterations = json["iterations"].as_u64().expect("iterations");
        let evaluations = json["evaluations"].as_u64().expect("evaluations");
        let per_iteration = med / iterations as f64;
        let in_evaluations = evaluations as f64 * e_med / iterations as f64;
        match way {
            Some(way) => println!("{} --sensitivities {way}:", hsp.display()),
            None => println!("{}:", hsp.display()),
        }
        println!(
            "  the fit (hsp identify --json, the whole command): median {med:.3} s, range \
             {lo:.3} .. {hi:.3} s; {iterations} iterations, {evaluations} model evaluations, \
             cost {:.3e}",
            json["cost"].as_f64().expect("cost")
        );
        println!(
            "  per iteration: {:.1} ms, of which {:.1} model evaluations ({:.1} ms, {:.0} %) and \
             {:.1} exact derivatives; sensitivities: {}",
            per_iteration * 1e3,
            evaluations as f64 / iterations as f64,
            in_evaluations * 1e3,
            100.0 * in_evaluations / per_iteration,
            json["derivatives"].as_u64().unwrap_or(0) as f64 / iterations as f64,
            json["sensitivities"].as_str().unwrap_or("?"),
        );
    }
    println!("load after {}", machine::load());
    let _ = std::fs::remove_dir_all(&dir);
}
