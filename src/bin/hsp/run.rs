//! `hsp run`: the main job. Builds the FMU, loads it through its C ABI, applies a preset (the
//! complete system by default) and the `--set` values, runs the experiment (by default the FMU's
//! own slewing move, from its command generator; with `--profile step` a step of the reference
//! `r` at t = 0, or, with `controller.external`, of the coil drive `e_in`), prints a summary of
//! the manoeuvre with the validity monitors' warnings and writes every recorded output at every
//! communication point to CSV.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};
use hydraulic_slewing_plate::fmu::Experiment;
use hydraulic_slewing_plate::fragments::controller::LINEAR_FRACTION;
use hydraulic_slewing_plate::fragments::plate::Root;
use hydraulic_slewing_plate::fragments::validity::{Monitor, SPIN_LIMIT, TIP_RATIO_LIMIT};
use hydraulic_slewing_plate::model::parameters::{HydraulicsModel, Parameters};
use hydraulic_slewing_plate::model::presets::{self, COMPLETE};
use hydraulic_slewing_plate::model::variables::{vr, VARIABLES};

use super::loader::Fmu;
use super::manoeuvre::{self, Command};
use super::package;
use super::results::Results;

#[derive(Args)]
pub struct RunArgs {
    /// The FMU to run (built first unless --no-build)
    #[arg(long, default_value = package::DEFAULT_FMU)]
    fmu: String,
    /// Use the FMU as it is, without rebuilding it
    #[arg(long)]
    no_build: bool,
    /// Parameter set to start from (`hsp presets` lists them); --set values apply after it
    #[arg(long, default_value = COMPLETE)]
    preset: String,
    /// The command: `move`, the FMU's command generator (a minimum-jerk move of reference.angle
    /// over reference.duration, 30 deg over 2 s by default); `step`, the generator off and a step
    /// of r at t = 0 (the paper's experiments)
    #[arg(long, value_enum, default_value_t = Profile::Move)]
    profile: Profile,
    /// Size of the step of the reference r at t = 0, V (default: 0 with --profile move, 2 V = 30
    /// deg of motor angle with --profile step)
    #[arg(long)]
    r: Option<f64>,
    /// Size of the step of the external coil drive e_in, V (used with controller.external=true)
    #[arg(long, default_value_t = 0.0)]
    e_in: f64,
    /// Close a digital loop around the FMU, as an importer's controller does: before every
    /// communication step set e_in = K (controller.reference - y_pot), V, held over the step
    /// (needs controller.external=true; the FMU's own analog loop has the gain
    /// controller.A1 * controller.A2 = 20, with its pressure feedback besides)
    #[arg(long, value_name = "K", conflicts_with = "e_in")]
    loop_gain: Option<f64>,
    /// Stop time, s (default: 6 s with --profile move, which lets the hub settle after the move;
    /// 150 s with --profile step, whose ring-down of the plate on the hub lasts minutes)
    #[arg(long)]
    stop: Option<f64>,
    /// Communication step, s
    #[arg(long, default_value_t = 5e-3)]
    step: f64,
    /// Relative tolerance passed to fmi2SetupExperiment (default: the FMU's solver.rtol)
    #[arg(long)]
    tolerance: Option<f64>,
    /// Apply an SSP 1.0 parameter set (`hsp ssp`'s, `hsp identify --out`'s) after the preset,
    /// before --set
    #[arg(long, value_name = "FILE.ssv")]
    ssv: Option<String>,
    /// Set a parameter, NAME=VALUE (repeatable)
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Where to write the results
    #[arg(long, default_value = "results/default_experiment.csv")]
    csv: String,
    #[command(flatten)]
    plot: super::plot::PlotArgs,
}

/// The command of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Profile {
    /// The FMU's command generator (`reference.*`).
    Move,
    /// A step of `r` at t = 0, the generator off.
    Step,
}

impl RunArgs {
    /// The step of `r` at t = 0 \[V\].
    pub fn r(&self) -> f64 {
        self.r.unwrap_or(match self.profile {
            Profile::Move => 0.0,
            Profile::Step => 2.0,
        })
    }

    /// The command of the run.
    pub fn profile(&self) -> Profile {
        self.profile
    }

    /// The stop time \[s\].
    pub fn stop(&self) -> f64 {
        self.stop.unwrap_or(match self.profile {
            Profile::Move => 6.0,
            Profile::Step => 150.0,
        })
    }
}

/// Outputs recorded for every configuration.
const RECORDED: &[&str] = &[
    "r",
    "controller.reference",
    "e_in",
    "controller.e_out",
    "y_pot",
    "theta_motor",
    "omega_motor",
    "theta_hub",
    "omega_hub",
    "torsion_bar.torque",
    "w_tip",
    "acc_tip",
    "p_load",
    "q_valve",
    "energy",
    "plate.stress",
    "plate.w_tip_ratio",
    "torsion_bar.stress",
    "hub.omega_ratio",
];

/// Outputs recorded with the full servo valve only (they are 0 with the LOES).
const RECORDED_SERVO_VALVE: &[&str] = &[
    "servo_valve.i_coil",
    "servo_valve.x_v",
    "servo_valve.p_1",
    "servo_valve.p_2",
];

/// The settings of a run in order: the preset's, the parameter set's (`--ssv`), the step
/// profile's, then the user's `--set`, then `extra`.
fn settings(args: &RunArgs, extra: &[String]) -> Result<Vec<String>, String> {
    let preset = presets::preset(&args.preset)?;
    let mut all: Vec<String> = preset
        .settings
        .iter()
        .map(|(n, v)| format!("{n}={v}"))
        .collect();
    if let Some(file) = &args.ssv {
        let text = std::fs::read_to_string(file).map_err(|e| format!("--ssv {file}: {e}"))?;
        let set = super::ecosystem::ssp::read_parameter_set(&text)
            .map_err(|e| format!("--ssv {file}: {e}"))?;
        all.extend(set.iter().map(|(n, v)| format!("{n}={v}")));
    }
    if args.profile == Profile::Step {
        all.push("reference.angle=0".into());
    }
    all.extend(args.set.iter().cloned());
    all.extend(extra.iter().cloned());
    Ok(all)
}

/// What the summary needs besides the results table.
pub struct RunInfo {
    pub preset: String,
    pub parameters: Parameters,
    /// Solver statistics: steps, rejected, f evaluations, Jacobians, LU factorisations.
    pub stats: Vec<i32>,
    /// Wall-clock time of the stepping loop \[s\].
    pub seconds: f64,
    /// The warnings the FMU logged (the loop margin's and the validity monitors').
    pub warnings: Vec<String>,
    /// The loop margin after initialisation: `margin.zeta` and `margin.f` \[Hz\].
    pub margin: (f64, f64),
}

pub fn run(args: &RunArgs) -> Result<(), String> {
    let (settings, parameters) = prepare(args, &[])?;
    let fmu_path = fmu_for(args)?;
    let (results, info) = experiment(args, &fmu_path, &settings, parameters)?;
    let csv_path = package::root().join(&args.csv);
    results.write_csv(&csv_path)?;
    print!(
        "{}",
        summary(args, &results, &info, &csv_path.display().to_string())
    );
    super::plot::after_run(&csv_path, &args.plot)
}

/// The FMU the run `args` uses: `--fmu`, built first unless `--no-build`.
pub(super) fn fmu_for(args: &RunArgs) -> Result<PathBuf, String> {
    Ok(if args.no_build {
        PathBuf::from(&args.fmu)
    } else {
        PathBuf::from(package::package(&args.fmu)?)
    })
}

/// The typed parameters of the run `args` (its preset and `--set`).
pub(super) fn parameters_of(args: &RunArgs) -> Result<Parameters, String> {
    Ok(prepare(args, &[])?.1)
}

/// The summary of the run `args` on the FMU `fmu` as it is (`hsp run --no-build --fmu FMU`),
/// writing nothing; the results line names the CSV as `--csv` gives it (`hsp docs`).
pub(super) fn summary_of(args: &RunArgs, fmu: &std::path::Path) -> Result<String, String> {
    let (results, info) = results_of(args, &[], fmu)?;
    Ok(summary(args, &results, &info, &args.csv))
}

/// The results of the run `args` with the settings `extra` after its own (`NAME=VALUE`) on the
/// FMU `fmu` as it is, writing nothing (`hsp fastest-move`).
pub(super) fn results_of(
    args: &RunArgs,
    extra: &[String],
    fmu: &std::path::Path,
) -> Result<(Results, RunInfo), String> {
    let (settings, parameters) = prepare(args, extra)?;
    experiment(args, fmu, &settings, parameters)
}

/// Checks the run's times; the settings of the run and the typed parameters it will use (the
/// FMU checks them again when it initialises).
fn prepare(args: &RunArgs, extra: &[String]) -> Result<(Vec<String>, Parameters), String> {
    let stop = args.stop();
    if !(stop > 0.0 && args.step > 0.0 && args.step <= stop) {
        return Err(format!(
            "--stop ({stop}) and --step ({}) must be positive with step <= stop",
            args.step
        ));
    }
    let settings = settings(args, extra)?;
    let values = super::values_with(None, &settings)?;
    let parameters = Parameters::from_values(&values, &Experiment::default())?;
    if let Some(k) = args.loop_gain {
        if !parameters.controller.external {
            return Err(format!(
                "--loop-gain {k} closes the loop through e_in, which the FMU reads only with \
                 controller.external=true (add --set controller.external=true)"
            ));
        }
        if !k.is_finite() {
            return Err(format!("--loop-gain must be a finite number, got {k}"));
        }
    }
    Ok((settings, parameters))
}

/// Runs the experiment on the FMU `fmu_path`: the results and what the summary needs.
fn experiment(
    args: &RunArgs,
    fmu_path: &std::path::Path,
    settings: &[String],
    parameters: Parameters,
) -> Result<(Results, RunInfo), String> {
    let (results, stats, seconds, margin) = simulate(args, fmu_path, settings, &parameters)?;
    let info = RunInfo {
        preset: args.preset.clone(),
        parameters,
        stats,
        seconds,
        warnings: super::loader::take_warnings(),
        margin,
    };
    Ok((results, info))
}

/// What [`simulate`] returns: the results table, the solver statistics, the wall time of the
/// stepping loop and the loop margin (`margin.zeta`, `margin.f`).
type Simulated = (Results, Vec<i32>, f64, (f64, f64));

/// Runs the experiment through the FMU's C ABI.
fn simulate(
    args: &RunArgs,
    fmu_path: &std::path::Path,
    settings: &[String],
    p: &Parameters,
) -> Result<Simulated, String> {
    let fmu = Fmu::load(fmu_path)?;
    let inst = fmu.instantiate("hsp-run")?;
    let stop = args.stop();
    inst.setup(args.tolerance, 0.0, stop)?;
    for s in settings {
        inst.set_from_text(s)?;
    }
    inst.set_real(vr::R, args.r())?;
    inst.set_real(vr::E_IN, args.e_in)?;
    inst.enter_initialization()?;
    inst.exit_initialization()?;
    let margin = inst.get_reals(&[vr::MARGIN_ZETA, vr::MARGIN_F])?;

    let mut names: Vec<&str> = RECORDED.to_vec();
    if p.hydraulics == HydraulicsModel::ServoValve {
        names.extend(RECORDED_SERVO_VALVE);
    }
    let vrs = names
        .iter()
        .map(|n| {
            VARIABLES
                .iter()
                .find(|v| v.name == *n)
                .map(|v| v.value_reference)
                .ok_or_else(|| format!("{n} is not an FMU variable"))
        })
        .collect::<Result<Vec<u32>, String>>()?;
    let mut results = Results::new(names.iter().map(|n| n.to_string()).collect());
    let n = (stop / args.step).round() as usize;
    results.push(0.0, inst.get_reals(&vrs)?);
    let wall = Instant::now();
    let mut progress = super::progress::Progress::new("hsp run");
    let mut fed_back = [0.0; 2];
    for i in 0..n {
        // Communication points computed from the index, not summed, so the grid does not drift.
        let t = i as f64 * args.step;
        let t_next = if i + 1 == n {
            stop
        } else {
            (i + 1) as f64 * args.step
        };
        if let Some(k) = args.loop_gain {
            inst.get_reals_into(&[vr::CONTROLLER_REFERENCE, vr::Y_POT], &mut fed_back)?;
            inst.set_real(vr::E_IN, k * (fed_back[0] - fed_back[1]))?;
        }
        inst.do_step(t, t_next - t)?;
        results.push(t_next, inst.get_reals(&vrs)?);
        progress.update(t_next / stop);
    }
    drop(progress);
    let seconds = wall.elapsed().as_secs_f64();
    let stats = inst.solver_stats()?;
    inst.terminate()?;
    Ok((results, stats, seconds, (margin[0], margin[1])))
}

/// Total time during which `pred` holds at the end of a communication interval \[s\].
fn time_where(t: &[f64], y: &[f64], pred: impl Fn(f64) -> bool) -> f64 {
    t.windows(2)
        .zip(&y[1..])
        .filter(|(_, v)| pred(**v))
        .map(|(w, _)| w[1] - w[0])
        .fold(0.0, |a, b| a + b)
}

pub(super) fn max_abs(y: &[f64]) -> f64 {
    y.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// The summary of a run: the manoeuvre (motor and hub angle, tip deflection), pressures, limits,
/// solver statistics and speed.
pub fn summary(args: &RunArgs, res: &Results, info: &RunInfo, csv: &str) -> String {
    let p = &info.parameters;
    let col = |n: &str| res.column(n).unwrap_or_default();
    let t = &res.time;
    let mut s = String::new();
    let preset = presets::preset(&info.preset).map_or("", |p| p.paper);
    let hydraulics = match p.hydraulics {
        HydraulicsModel::Loes => "LOES",
        HydraulicsModel::ServoValve => "full servo valve",
    };
    let coupling = if p.motor_coupled {
        "motor coupled to the hub"
    } else {
        "motor alone"
    };
    writeln!(
        s,
        "Hydraulic slewing plate, preset {} ({preset}): {hydraulics}, {coupling}{}",
        info.preset,
        if hub_locked(p) { ", hub locked" } else { "" }
    )
    .unwrap();
    let theta_motor = col("theta_motor");
    let theta_hub = col("theta_hub");
    let last = |y: &[f64]| y.last().copied().unwrap_or(0.0);
    let stop = args.stop();
    // The command with a target, when the loop is the FMU's (docs/model.md, "Measures of a
    // manoeuvre").
    let mut command = None;
    if p.controller.external {
        let drive = match args.loop_gain {
            Some(k) => format!(
                "digital loop e_in = {k} (controller.reference - y_pot), held over each step"
            ),
            None => format!("step of e_in = {} V", args.e_in),
        };
        writeln!(
            s,
            "  drive   external: {drive}, {stop} s in steps of {} s",
            args.step
        )
        .unwrap();
        writeln!(
            s,
            "  motor   final {:.3} deg, {:.4} rad/s",
            last(&theta_motor).to_degrees(),
            last(&col("omega_motor"))
        )
        .unwrap();
        if p.motor_coupled {
            writeln!(
                s,
                "  hub     final {:.3} deg, {:.4} rad/s",
                last(&theta_hub).to_degrees(),
                last(&col("omega_hub"))
            )
            .unwrap();
        }
    } else {
        let r = args.r();
        let mv = &p.reference;
        let cmd = Command::of(p, r);
        let target = cmd.target;
        let described = match (mv.is_on(), r != 0.0) {
            (true, step) => format!(
                "minimum-jerk move of {:.2} deg over {} s from t = {} s{} (motor target {:.2} deg)",
                mv.angle.to_degrees(),
                mv.duration,
                mv.t_start,
                if step {
                    format!(", on a step of r = {r} V")
                } else {
                    String::new()
                },
                target.to_degrees()
            ),
            (false, _) => format!(
                "step of r = {r} V (motor target {:.2} deg)",
                target.to_degrees()
            ),
        };
        writeln!(
            s,
            "  command {described}, {stop} s in steps of {} s",
            args.step
        )
        .unwrap();
        let line = |name: &str, y: &[f64]| {
            format!(
                "  {name:<7} final {:.3} deg, overshoot {:.2} %, settling ({} %, from t = {} s) {}\n",
                last(y).to_degrees(),
                manoeuvre::overshoot_pct(y, target),
                manoeuvre::BAND * 100.0,
                cmd.t_end,
                manoeuvre::settling_text(manoeuvre::settling(t, y, target, cmd.t_end))
            )
        };
        s.push_str(&line("motor", &theta_motor));
        if p.motor_coupled && !hub_locked(p) {
            s.push_str(&line("hub", &theta_hub));
        }
        command = Some(cmd);
    }
    let w_tip = col("w_tip");
    let residual = match command {
        None => "no residual measures (no command target)".to_string(),
        Some(c) => match manoeuvre::residual_peak(t, &w_tip, c.t_end) {
            None => format!(
                "no residual measures (the run ends before t = {} s)",
                c.t_end
            ),
            Some(peak) => format!(
                "from t = {} s residual peak {:.3} mm, ring-down to {} mm {}",
                c.t_end,
                peak * 1e3,
                manoeuvre::RING_LEVEL * 1e3,
                manoeuvre::ring_down_text(manoeuvre::ring_down(
                    t,
                    &w_tip,
                    c.t_end,
                    manoeuvre::RING_LEVEL
                ))
            ),
        },
    };
    writeln!(
        s,
        "  tip     peak |w_tip| {:.3} mm; {residual}",
        max_abs(&w_tip) * 1e3
    )
    .unwrap();
    let bar = |y: &[f64]| {
        (
            y.iter().copied().fold(f64::INFINITY, f64::min) * 1e-5,
            y.iter().copied().fold(f64::NEG_INFINITY, f64::max) * 1e-5,
        )
    };
    if p.hydraulics == HydraulicsModel::ServoValve {
        let (p1_lo, p1_hi) = bar(&col("servo_valve.p_1"));
        let (p2_lo, p2_hi) = bar(&col("servo_valve.p_2"));
        writeln!(
            s,
            "  press.  p_1 {p1_lo:.2} .. {p1_hi:.2} bar, p_2 {p2_lo:.2} .. {p2_hi:.2} bar (gauge; supply {:.0} bar), peak |p_load| {:.2} bar",
            p.servo_valve.p_supply * 1e-5,
            max_abs(&col("p_load")) * 1e-5
        )
        .unwrap();
    } else {
        writeln!(
            s,
            "  press.  peak |p_load| {:.2} bar",
            max_abs(&col("p_load")) * 1e-5
        )
        .unwrap();
    }
    let amplifier = if p.controller.saturation {
        let knee = LINEAR_FRACTION * p.controller.e_max;
        let e = col("controller.e_out");
        format!(
            "amplifier beyond its linear range (|e_out| > {knee:.1} V) for {:.3} s, peak |e_out| {:.2} V of {} V",
            time_where(t, &e, |v| v.abs() > knee),
            max_abs(&e),
            p.controller.e_max
        )
    } else {
        format!(
            "amplifier linear (no limit), peak |e_out| {:.2} V",
            max_abs(&col("controller.e_out"))
        )
    };
    writeln!(s, "  limits  {amplifier}").unwrap();
    if p.hydraulics == HydraulicsModel::ServoValve {
        // The end-stop force rises over the last twentieth of the stroke.
        let x_max = p.servo_valve.x_v_max;
        let x_v = col("servo_valve.x_v");
        writeln!(
            s,
            "          spool at its stop (|x_v| > 0.95 x_v_max = {:.3} mm) for {:.3} s, peak |x_v| {:.3} mm",
            0.95 * x_max * 1e3,
            time_where(t, &x_v, |v| v.abs() > 0.95 * x_max),
            max_abs(&x_v) * 1e3
        )
        .unwrap();
    }
    let l = &p.limits;
    let plate_rule = l.plate_rule().word;
    writeln!(
        s,
        "  validity peak w_tip/a {:.3} (limit {TIP_RATIO_LIMIT}), plate stress {:.1} MPa (limit {:.2}, {plate_rule} at the root), bar shear {:.1} MPa (limit {:.1}, half of yield), (omega_hub/omega_1)^2 {:.3} (limit {SPIN_LIMIT})",
        max_abs(&col("plate.w_tip_ratio")),
        max_abs(&col("plate.stress")) * 1e-6,
        Monitor::PlateStress.limit(l) * 1e-6,
        max_abs(&col("torsion_bar.stress")) * 1e-6,
        Monitor::BarStress.limit(l) * 1e-6,
        max_abs(&col("hub.omega_ratio")).powi(2)
    )
    .unwrap();
    let (zeta, f) = info.margin;
    writeln!(
        s,
        "  margin  least damped mode at rest {f:.3} Hz, damping ratio {zeta:.4} (the FMU warns below {:.4}, plate.zeta/3)",
        hydraulic_slewing_plate::model::margin::threshold(p)
    )
    .unwrap();
    if info.warnings.is_empty() {
        writeln!(
            s,
            "          no warning: the loop is damped and the run stays within the linear model's range"
        )
        .unwrap();
    }
    for w in &info.warnings {
        writeln!(s, "  WARNING {w}").unwrap();
    }
    let st = &info.stats;
    writeln!(
        s,
        "{SOLVER_LINE}{} steps, {} rejected, {} f evaluations, {} Jacobians, {} LU factorisations",
        st[0], st[1], st[2], st[3], st[4]
    )
    .unwrap();
    writeln!(
        s,
        "{TIME_LINE}{:.3} s wall, {:.1} x real time",
        info.seconds,
        stop / info.seconds.max(1e-9)
    )
    .unwrap();
    writeln!(s, "  results {csv}").unwrap();
    s
}

/// The start of the summary's solver line (the counts follow).
pub const SOLVER_LINE: &str = "  solver  ";
/// The start of the summary's line of wall time and real-time factor, the one line that depends
/// on the machine.
pub const TIME_LINE: &str = "  time    ";

fn hub_locked(p: &Parameters) -> bool {
    p.plate.root == Root::Locked
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_where_sums_the_intervals() {
        let t: Vec<f64> = (0..=10).map(|i| i as f64).collect();
        let y = [
            0.0, -0.5, -1.1, -1.05, -0.97, -1.01, -1.0, -1.0, -1.0, -1.0, -1.0,
        ];
        // Beyond -1 at t = 2, 3 and 5: three intervals of 1 s.
        assert!((time_where(&t, &y, |v| v < -1.0) - 3.0).abs() < 1e-12);
    }
}
