//! `hsp fastest-move`: the torque budget of the actuator (docs/model.md, "Sizing the actuator").
//! Bisects `reference.duration`, to 1 ms, for the fastest minimum-jerk move of the run's
//! `reference.angle` whose peak `|plate.w_tip_ratio|` stays at or below the validity monitor's
//! limit (the plate stays linear), and reports that move's peak bar torque, peak load pressure
//! and hub overshoot, and the motor's margin over that torque.

use std::path::Path;

use clap::Args;
use hydraulic_slewing_plate::fragments::validity::TIP_RATIO_LIMIT;
use hydraulic_slewing_plate::model::parameters::HydraulicsModel;

use super::manoeuvre::{self, Command};
use super::results::Results;
use super::run::{self, max_abs, Profile, RunArgs};

#[derive(Args)]
pub struct FastestArgs {
    /// Largest peak |w_tip|/a the move may reach (default: the validity monitor's limit)
    #[arg(long, default_value_t = TIP_RATIO_LIMIT)]
    limit: f64,
    /// The shortest duration tried, s: its move must exceed the limit
    #[arg(long, default_value_t = 0.5)]
    from: f64,
    #[command(flatten)]
    run: RunArgs,
}

pub fn main(args: &FastestArgs) -> Result<(), String> {
    let fmu = run::fmu_for(&args.run)?;
    print!("{}", report(args, &fmu)?);
    Ok(())
}

/// One move of `ms` milliseconds: its results and its peak `|w_tip|/a`.
fn trial(args: &FastestArgs, ms: u32, fmu: &Path) -> Result<(Results, f64), String> {
    let extra = [format!("reference.duration={}", f64::from(ms) / 1000.0)];
    let (results, _) = run::results_of(&args.run, &extra, fmu)?;
    let peak = max_abs(&results.column("plate.w_tip_ratio").unwrap_or_default());
    Ok((results, peak))
}

/// The report `hsp fastest-move` prints (and `hsp docs`' block `fastest-move`), computed on the
/// FMU `fmu` as it is.
pub fn report(args: &FastestArgs, fmu: &Path) -> Result<String, String> {
    if args.run.profile() != Profile::Move {
        return Err("hsp fastest-move bisects the built-in move: --profile move".into());
    }
    let p = run::parameters_of(&args.run)?;
    if !p.reference.is_on() || p.hydraulics != HydraulicsModel::ServoValve {
        return Err(
            "hsp fastest-move needs the built-in move (reference.angle != 0) and the full servo \
             valve (hydraulics.model = 2)"
                .into(),
        );
    }
    let mut lo = (args.from * 1000.0).round() as u32;
    let mut hi = (p.reference.duration * 1000.0).round() as u32;
    let lo_peak = trial(args, lo, fmu)?.1;
    // The fastest move within the limit so far, with its results.
    let (mut res, mut peak) = trial(args, hi, fmu)?;
    if lo_peak <= args.limit || peak > args.limit || lo >= hi {
        return Err(format!(
            "the bisection needs a move of --from ({lo} ms) beyond the limit and the run's \
             reference.duration ({hi} ms) within it: peak w_tip/a {lo_peak:.4} and {peak:.4}"
        ));
    }
    let mut below = lo_peak;
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        let (mid_res, mid_peak) = trial(args, mid, fmu)?;
        if mid_peak <= args.limit {
            (hi, res, peak) = (mid, mid_res, mid_peak);
        } else {
            (lo, below) = (mid, mid_peak);
        }
    }
    let col = |n: &str| res.column(n).unwrap_or_default();
    let torque = max_abs(&col("torsion_bar.torque"));
    let target = Command::of(&p, args.run.r()).target;
    let sv = &p.servo_valve;
    let motor = sv.d_m * 2.0 / 3.0 * sv.p_supply;
    Ok(format!(
        "fastest minimum-jerk move of {:.2} deg with peak |w_tip|/a <= {}, to 1 ms: reference.duration = {:.3} s ({:.3} s reaches {below:.4})\n\
         \x20 peak |w_tip|/a {peak:.4}, peak bar torque {torque:.1} N m (bar shear {:.1} MPa), peak |p_load| {:.2} bar, hub overshoot {:.2} %\n\
         \x20 motor {:.3e} m^3/rad: {motor:.1} N m at two thirds of the {:.0} bar supply, a margin of {:.2} over the peak bar torque ({:.1} N m at the full supply)\n",
        p.reference.angle.to_degrees(),
        args.limit,
        f64::from(hi) / 1000.0,
        f64::from(lo) / 1000.0,
        max_abs(&col("torsion_bar.stress")) * 1e-6,
        max_abs(&col("p_load")) * 1e-5,
        manoeuvre::overshoot_pct(&col("theta_hub"), target),
        sv.d_m,
        sv.p_supply * 1e-5,
        motor / torque,
        sv.d_m * sv.p_supply,
    ))
}
