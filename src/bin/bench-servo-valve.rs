//! Benchmark of the full servo-valve model through the FMU (issue 6). Not a test.
//!
//! ```text
//! cargo run --release --bin hsp -- package            # build fmu/HydraulicSlewingPlate.fmu
//! cargo run --release --bin bench-servo-valve          # writes bench/servo_valve.md
//! cargo run --release --bin bench-servo-valve -- --set hydraulics.motor_coupled=true
//! ```
//!
//! Loads the packaged FMU through its C ABI (as an importer does), sets `hydraulics.model = 2`
//! and any `--set NAME=VALUE`, and runs 10 s at 1 ms communication steps with rtol 1e-6 (through
//! `fmi2SetupExperiment`), the reference `r` a square wave of +-0.1 V with a period of 2 s (a
//! zero-order-hold jump every second), once with Rodas5P and once with Radau5. Reports wall time
//! (median of 3 runs), real-time factor, accepted steps, f evaluations, Jacobians and LU
//! factorisations, and writes them as a markdown table to `bench/servo_valve.md` (or `--out`).

#[allow(dead_code)]
#[path = "hsp/loader.rs"]
mod loader;

use std::fmt::Write as _;
use std::time::Instant;

use hydraulic_slewing_plate::model::variables::vr;
use loader::Fmu;

const STOP: f64 = 10.0;
const STEP: f64 = 1e-3;
const RTOL: f64 = 1e-6;

struct Run {
    wall: f64,
    stats: Vec<i32>,
    y_end: f64,
}

fn run_once(fmu: &Fmu, method: i32, sets: &[String]) -> Result<Run, String> {
    let inst = fmu.instantiate("bench-servo-valve")?;
    inst.setup(Some(RTOL), 0.0, STOP)?;
    inst.set_integer(vr::HYDRAULICS_MODEL, 2)?;
    inst.set_integer(vr::SOLVER_METHOD, method)?;
    for s in sets {
        inst.set_from_text(s)?;
    }
    inst.set_real(vr::R, 0.1)?;
    inst.enter_initialization()?;
    inst.exit_initialization()?;
    let n = (STOP / STEP).round() as usize;
    let start = Instant::now();
    for k in 0..n {
        let t = k as f64 * STEP;
        let r = if (k / 1000) % 2 == 0 { 0.1 } else { -0.1 };
        inst.set_real(vr::R, r)?;
        inst.do_step(t, STEP)?;
    }
    let wall = start.elapsed().as_secs_f64();
    let stats = inst.solver_stats()?;
    let y_end = inst.get_reals(&[vr::Y_POT])?[0];
    inst.terminate()?;
    Ok(Run { wall, stats, y_end })
}

fn main() {
    let mut sets = Vec::new();
    let mut fmu_path = "fmu/HydraulicSlewingPlate.fmu".to_string();
    let mut out = "bench/servo_valve.md".to_string();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--set" => sets.push(args.next().expect("--set NAME=VALUE")),
            "--fmu" => fmu_path = args.next().expect("--fmu PATH"),
            "--out" => out = args.next().expect("--out PATH"),
            other => {
                eprintln!(
                    "unknown argument '{other}' (use --set NAME=VALUE, --fmu PATH, --out PATH)"
                );
                std::process::exit(2);
            }
        }
    }
    let fmu = Fmu::load(std::path::Path::new(&fmu_path)).unwrap_or_else(|e| {
        eprintln!("{e} (build it with: cargo run --release --bin hsp -- package)");
        std::process::exit(1)
    });
    let mut md = String::new();
    writeln!(
        md,
        "# Full servo valve benchmark (issue 6)\n\n`cargo run --release --bin bench-servo-valve{}`: \
         `hydraulics.model = 2`{}, {STOP} s at {STEP} s communication steps (10 000 `fmi2DoStep` \
         calls through the C ABI), rtol {RTOL:e} (atol 1e-8 of each state's nominal value), `r` a \
         +-0.1 V square wave of period 2 s. Wall time is the median of 3 runs on a shared 2-core \
         machine.\n",
        sets.iter().map(|s| format!(" --set {s}")).collect::<String>(),
        sets.iter().map(|s| format!(", `{s}`")).collect::<String>(),
    )
    .unwrap();
    writeln!(md, "| method | wall (s) | real-time factor | steps | rejected | f evals | Jacobians | LU | y_pot(10 s) (V) |").unwrap();
    writeln!(
        md,
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    )
    .unwrap();
    for (method, name) in [(1, "Rodas5P"), (2, "Radau5")] {
        let mut runs: Vec<Run> = (0..3)
            .map(|_| run_once(&fmu, method, &sets).unwrap_or_else(|e| panic!("{name}: {e}")))
            .collect();
        runs.sort_by(|a, b| a.wall.total_cmp(&b.wall));
        let r = &runs[1];
        let line = format!(
            "| {name} | {:.3} | {:.1} | {} | {} | {} | {} | {} | {:.6} |",
            r.wall,
            STOP / r.wall,
            r.stats[0],
            r.stats[1],
            r.stats[2],
            r.stats[3],
            r.stats[4],
            r.y_end
        );
        eprintln!("{line}");
        writeln!(md, "{line}").unwrap();
    }
    if let Some(dir) = std::path::Path::new(&out).parent() {
        std::fs::create_dir_all(dir).expect("create output directory");
    }
    std::fs::write(&out, md).expect("write the report");
    eprintln!("wrote {out}");
}
