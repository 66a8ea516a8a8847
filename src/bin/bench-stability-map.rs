//! The stability map of the complete system at rest: the least damping ratio of the linearised
//! model (the loop margin of `src/model/margin.rs`: balanced eigenvalues, rigid-body and
//! integrator zeros left out) over the parameters nobody measured, for the default loop design
//! and for the paper's voltage-driven loop without pressure feedback.
//!
//! ```text
//! cargo run --release --bin bench-stability-map > docs/stability-map.md.part
//! ```
//!
//! Prints markdown: one table over the effective bulk modulus `servo_valve.beta` × the vane
//! motor's leakage (`servo_valve.R_leak`, as L/min at 100 bar) per design, and one over
//! `plate.zeta` × the four combinations of coil drive and pressure feedback. Each cell is the
//! least damping ratio of the slow pairs (below [`SLOW_HZ`]: the loop's and the structure's
//! slowest modes, the ones the loop moves and can destabilise) and that mode's frequency; the
//! structure's other modes keep `plate.zeta` (or more). A cell where any mode is below the design
//! rule (`plate.zeta / 3`) is marked `!`, one where any mode grows `!!`; the defaults' cell is in
//! bold.

use hydraulic_slewing_plate::eigen::{least_damped, Mode};
use hydraulic_slewing_plate::fmu::{Experiment, Values};
use hydraulic_slewing_plate::fragments::controller::DEFAULT_K_PL;
use hydraulic_slewing_plate::model::assembly::Assembled;
use hydraulic_slewing_plate::model::margin::{
    eigenvalues_sliding_at_rest, least_damped_mode, verdict, Verdict, ROUND_OFF, THRESHOLD_FRACTION,
};
use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
use hydraulic_slewing_plate::model::variables::VARIABLES;

/// `R_leak` \[N s/m^5\] of a leakage of `l_per_min` L/min at 100 bar.
fn r_leak(l_per_min: f64) -> f64 {
    100e5 / (l_per_min / 60_000.0)
}

/// The two loop designs compared: (name, settings).
const DESIGNS: &[(&str, &[(&str, &str)])] = &[
    (
        "the default loop (current drive, pressure feedback 5 mV/bar)",
        &[],
    ),
    (
        "the paper's loop (voltage drive, no pressure feedback)",
        &[("servo_valve.drive", "1"), ("controller.k_pl", "0")],
    ),
];

/// The modes below this frequency \[Hz\] are the slow ones.
const SLOW_HZ: f64 = 5.0;

/// The least damped mode's text for the settings `sets` over the defaults (the command
/// generator off: its clock is no mode).
fn cell(sets: &[(&str, String)], zeta_rule: f64, default: bool) -> String {
    let mut values = Values::from_start(&VARIABLES);
    set_by_name(&mut values, "reference.angle", "0").expect("reference.angle");
    for (n, v) in sets {
        set_by_name(&mut values, n, v).unwrap_or_else(|e| panic!("{e}"));
    }
    let p = Parameters::from_values(&values, &Experiment::default()).expect("parameters");
    let system = Assembled::new(&p).expect("model");
    let ev = eigenvalues_sliding_at_rest(&system, &p);
    let slow: Option<Mode> = least_damped(
        &ev.iter()
            .copied()
            .filter(|z| z.im.abs() > 0.0 && z.norm() < 2.0 * std::f64::consts::PI * SLOW_HZ)
            .collect::<Vec<_>>(),
        0.0,
    );
    let mark = match least_damped_mode(&ev).map(|m| verdict(m.zeta, zeta_rule)) {
        Some(Verdict::Unstable) => " !!",
        Some(Verdict::PoorlyDamped) => " !",
        _ => "",
    };
    let text = match slow {
        // A damping ratio at round-off is printed as 0.
        Some(s) => format!(
            "{:.4} ({:.2} Hz){mark}",
            if s.zeta.abs() < ROUND_OFF {
                0.0
            } else {
                s.zeta
            },
            s.frequency_hz()
        ),
        None => format!("–{mark}"),
    };
    if default {
        format!("**{text}**")
    } else {
        text
    }
}

fn main() {
    let betas = [0.5e9, 0.7e9, 1.0e9, 1.4e9, 1.8e9, 2.2e9];
    let leaks = [0.05, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0];
    let zeta_default = 0.02;
    println!("## Bulk modulus × leakage (`plate.zeta` = {zeta_default})\n");
    for (name, design) in DESIGNS {
        println!("{name}: least damping ratio of the slow pairs (frequency of that mode)\n");
        print!("| β (GPa) \\ leakage at 100 bar (L/min) |");
        for l in leaks {
            print!(" {l} |");
        }
        println!();
        println!("| ---:{} |", " | ---:".repeat(leaks.len()));
        for beta in betas {
            print!("| {:.1} |", beta * 1e-9);
            for l in leaks {
                let mut sets: Vec<(&str, String)> =
                    design.iter().map(|(n, v)| (*n, v.to_string())).collect();
                sets.push(("servo_valve.beta", beta.to_string()));
                sets.push(("servo_valve.R_leak", r_leak(l).to_string()));
                let default = beta == 1.4e9 && l == 1.0;
                print!(
                    " {} |",
                    cell(&sets, THRESHOLD_FRACTION * zeta_default, default)
                );
            }
            println!();
        }
        println!();
    }
    let zetas = [0.0, 0.002, 0.005, 0.01, 0.02, 0.03, 0.05];
    let k_pl = DEFAULT_K_PL.to_string();
    let loops: [(&str, [(&str, &str); 2]); 4] = [
        (
            "current drive, pressure feedback (the default)",
            [("servo_valve.drive", "2"), ("controller.k_pl", &k_pl)],
        ),
        (
            "current drive, no pressure feedback",
            [("servo_valve.drive", "2"), ("controller.k_pl", "0")],
        ),
        (
            "voltage drive, pressure feedback",
            [("servo_valve.drive", "1"), ("controller.k_pl", &k_pl)],
        ),
        (
            "voltage drive, no pressure feedback (the paper's loop)",
            [("servo_valve.drive", "1"), ("controller.k_pl", "0")],
        ),
    ];
    println!("## Structural damping × drive (β 1.4 GPa, leakage 1 L/min at 100 bar)\n");
    print!("| `plate.zeta` |");
    for (name, _) in &loops {
        print!(" {name} |");
    }
    println!();
    println!("| ---:{} |", " | ---:".repeat(loops.len()));
    for zeta in zetas {
        print!("| {zeta} |");
        for (k, (_, sets)) in loops.iter().enumerate() {
            let mut s: Vec<(&str, String)> =
                sets.iter().map(|(n, v)| (*n, v.to_string())).collect();
            s.push(("plate.zeta", zeta.to_string()));
            let default = k == 0 && zeta == zeta_default;
            print!(" {} |", cell(&s, THRESHOLD_FRACTION * zeta, default));
        }
        println!();
    }
}
