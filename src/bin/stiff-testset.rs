//! Run one stiff test problem and print one JSON line with accuracy and work.
//!
//! ```text
//! cargo run --release --bin stiff-testset -- <problem> --method rodas5p|radau5 --rtol 1e-8 [--atol X]
//! ```
//! Problems: rober, vdpol, hires, orego, prothero-robinson, oscillator. Without `--atol` the
//! problem's prescribed absolute tolerance is used (see `solver::testset`).
//! Output keys: problem, method, rtol, atol, scd, steps, rejected, f_evals, jac_evals, lu,
//! seconds (and error, if the integration failed; scd is then null). Exit status 1 on failure.

use clap::Parser;
use hydraulic_slewing_plate::solver::testset::{problem, run, PROBLEMS};
use hydraulic_slewing_plate::solver::Method;

#[derive(Parser)]
#[command(about = "Run one stiff test problem, print a JSON line")]
struct Args {
    /// rober, vdpol, hires, orego, prothero-robinson or oscillator
    problem: String,
    /// rodas5p or radau5
    #[arg(long, default_value = "rodas5p")]
    method: Method,
    #[arg(long, default_value_t = 1e-6)]
    rtol: f64,
    /// absolute tolerance (default: the problem's prescribed one)
    #[arg(long)]
    atol: Option<f64>,
}

fn main() {
    let args = Args::parse();
    let Some(prob) = problem(&args.problem) else {
        eprintln!(
            "unknown problem {:?}; expected one of {}",
            args.problem,
            PROBLEMS.join(", ")
        );
        std::process::exit(2);
    };
    let r = run(prob.as_ref(), args.method, args.rtol, args.atol);
    // A struct keeps the key order of the issue (serde_json's map would sort the keys).
    #[derive(serde::Serialize)]
    struct Line<'a> {
        problem: &'a str,
        method: &'a str,
        rtol: f64,
        atol: f64,
        scd: Option<f64>,
        steps: u64,
        rejected: u64,
        f_evals: u64,
        jac_evals: u64,
        lu: u64,
        seconds: f64,
        #[serde(skip_serializing_if = "Option::is_none")]
        error: Option<&'a str>,
    }
    let line = Line {
        problem: &r.problem,
        method: &r.method,
        rtol: r.rtol,
        atol: r.atol,
        scd: r.scd,
        steps: r.steps,
        rejected: r.rejected,
        f_evals: r.f_evals,
        jac_evals: r.jac_evals,
        lu: r.lu,
        seconds: r.seconds,
        error: r.error.as_deref(),
    };
    println!("{}", serde_json::to_string(&line).expect("serialise"));
    if r.error.is_some() {
        std::process::exit(1);
    }
}
