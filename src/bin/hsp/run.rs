//! `hsp run`: the main job. Builds the FMU, loads it through its C ABI, applies a step of the
//! reference `r` at t = 0, runs the experiment, prints a readable summary and writes every output
//! at every communication point to CSV.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use hydraulic_slewing_plate::model::variables::vr;

use super::loader::Fmu;
use super::package;

#[derive(Args)]
pub struct RunArgs {
    /// The FMU to run (built first unless --no-build)
    #[arg(long, default_value = package::DEFAULT_FMU)]
    fmu: String,
    /// Use the FMU as it is, without rebuilding it
    #[arg(long)]
    no_build: bool,
    /// Size of the reference step r, V
    #[arg(long, default_value_t = 1.0)]
    r: f64,
    /// Stop time, s
    #[arg(long, default_value_t = 1.0)]
    stop: f64,
    /// Communication step, s
    #[arg(long, default_value_t = 1e-3)]
    step: f64,
    /// Relative tolerance passed to fmi2SetupExperiment (default: the FMU's solver.rtol)
    #[arg(long)]
    tolerance: Option<f64>,
    /// Set a parameter, NAME=VALUE (repeatable)
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Where to write the results
    #[arg(long, default_value = "results/default_experiment.csv")]
    csv: String,
    #[command(flatten)]
    plot: super::plot::PlotArgs,
}

/// The outputs recorded, with a display scale and unit for the summary.
const RECORDED: &[(&str, u32)] = &[
    ("y_pot", vr::Y_POT),
    ("theta_motor", vr::THETA_MOTOR),
    ("omega_motor", vr::OMEGA_MOTOR),
    ("p_load", vr::P_LOAD),
    ("q_valve", vr::Q_VALVE),
    ("energy", vr::ENERGY),
];

pub fn run(args: &RunArgs) -> Result<(), String> {
    if !(args.stop > 0.0 && args.step > 0.0 && args.step <= args.stop) {
        return Err(format!(
            "--stop ({}) and --step ({}) must be positive with step <= stop",
            args.stop, args.step
        ));
    }
    let fmu_path = if args.no_build {
        PathBuf::from(&args.fmu)
    } else {
        PathBuf::from(package::package(&args.fmu)?)
    };
    let fmu = Fmu::load(&fmu_path)?;
    let inst = fmu.instantiate("hsp-run")?;
    inst.setup(args.tolerance, 0.0, args.stop)?;
    for s in &args.set {
        inst.set_from_text(s)?;
    }
    inst.set_real(vr::R, args.r)?;
    inst.enter_initialization()?;
    inst.exit_initialization()?;

    let vrs: Vec<u32> = RECORDED.iter().map(|(_, v)| *v).collect();
    let n = (args.stop / args.step).round() as usize;
    let mut rows: Vec<(f64, Vec<f64>)> = Vec::with_capacity(n + 1);
    rows.push((0.0, inst.get_reals(&vrs)?));
    let wall = Instant::now();
    let mut progress = super::progress::Progress::new("hsp run");
    for i in 0..n {
        // Communication points computed from the index, not summed, so the grid does not drift.
        let t = i as f64 * args.step;
        let t_next = if i + 1 == n {
            args.stop
        } else {
            (i + 1) as f64 * args.step
        };
        inst.do_step(t, t_next - t)?;
        rows.push((t_next, inst.get_reals(&vrs)?));
        progress.update(t_next / args.stop);
    }
    drop(progress);
    let seconds = wall.elapsed().as_secs_f64();
    let stats = inst.solver_stats()?;
    inst.terminate()?;

    // CSV
    let csv_path = package::root().join(&args.csv);
    if let Some(dir) = csv_path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let mut csv = String::from("time");
    for (name, _) in RECORDED {
        write!(csv, ",{name}").unwrap();
    }
    csv.push('\n');
    for (t, y) in &rows {
        write!(csv, "{t}").unwrap();
        for v in y {
            write!(csv, ",{v:e}").unwrap();
        }
        csv.push('\n');
    }
    std::fs::write(&csv_path, csv).map_err(|e| format!("{}: {e}", csv_path.display()))?;

    print!(
        "{}",
        summary(
            args,
            &rows,
            &stats,
            seconds,
            &csv_path.display().to_string()
        )
    );
    super::plot::after_run(&csv_path, &args.plot)
}

/// Step-response figures of y_pot against the reference r.
fn summary(
    args: &RunArgs,
    rows: &[(f64, Vec<f64>)],
    stats: &[i32],
    seconds: f64,
    csv: &str,
) -> String {
    let y: Vec<f64> = rows.iter().map(|(_, v)| v[0]).collect();
    let t: Vec<f64> = rows.iter().map(|(t, _)| *t).collect();
    let last = rows.last().map(|(_, v)| v.clone()).unwrap_or_default();
    let r = args.r;
    let peak = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let overshoot = if r != 0.0 {
        (peak - r) / r * 100.0
    } else {
        0.0
    };
    let crossing = |level: f64| {
        t.iter()
            .zip(&y)
            .find(|(_, y)| **y >= level * r)
            .map(|(t, _)| *t)
    };
    let rise = match (crossing(0.1), crossing(0.9)) {
        (Some(a), Some(b)) => format!("{:.1} ms", (b - a) * 1e3),
        _ => "not reached".into(),
    };
    let settled = y.iter().rposition(|v| (v - r).abs() > 0.02 * r.abs());
    let settling = match settled {
        Some(i) if i + 1 < t.len() => format!("{:.1} ms", t[i + 1] * 1e3),
        Some(_) => "not settled".into(),
        None => "0 ms".into(),
    };
    let max_abs = |k: usize| rows.iter().map(|(_, v)| v[k].abs()).fold(0.0, f64::max);
    let mut s = String::new();
    writeln!(
        s,
        "Hydraulic slewing plate: step of r = {r} V, {} s in steps of {} s",
        args.stop, args.step
    )
    .unwrap();
    writeln!(
        s,
        "  final   y_pot = {:.6} V, theta_motor = {:.4} deg, omega_motor = {:.3e} rad/s",
        last[0],
        last[1].to_degrees(),
        last[2]
    )
    .unwrap();
    writeln!(s, "  step    overshoot {overshoot:.2} %, rise time (10-90 %) {rise}, settling time (2 %) {settling}").unwrap();
    writeln!(
        s,
        "  peaks   |p_load| = {:.2} bar, |q_valve| = {:.3} L/min, |omega_motor| = {:.3} rad/s",
        max_abs(3) * 1e-5,
        max_abs(4) * 6e4,
        max_abs(2)
    )
    .unwrap();
    writeln!(
        s,
        "  solver  {} steps, {} rejected, {} f evaluations, {} Jacobians, {} LU factorisations",
        stats[0], stats[1], stats[2], stats[3], stats[4]
    )
    .unwrap();
    writeln!(
        s,
        "  time    {:.3} s wall, {:.0} x real time",
        seconds,
        args.stop / seconds.max(1e-9)
    )
    .unwrap();
    writeln!(s, "  results {csv}").unwrap();
    s
}
