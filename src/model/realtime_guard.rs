//! The real-time mode's physical bounds: a fixed step has no error control, so a step too long
//! for what the inputs ask can land on a state no servo valve can be in (the spool metres past
//! its stops, pressures of 1e14 Pa) while every value is still finite. Such a step is not
//! returned as OK: [`check`] names the first quantity out of its bound, and the FMU discards the
//! communication step and keeps the last good state (`src/model/mod.rs`, `do_step`).
//!
//! The bounds are what the servo valve's own laws allow, with a margin of two:
//!
//! * **The spool** stays within `x_v_max (1 + 2/20)`: its end stops are a spring of stiffness
//!   `20 A_s (p_s - p_t) / x_v_max` ([`crate::fragments::servo_valve::limits::stop_stiffness`]),
//!   which the full pilot pressure difference on the spool's ends pushes `x_v_max/20` past the
//!   stop; twice that force, twice that overtravel.
//! * **The chamber pressures** (`p_1`, `p_2`, `p_a`, `p_b`) stay below `2 p_s` (gauge): the
//!   supply is the circuit's only source, and a chamber goes above it only while the motor's
//!   inertia pumps against a closing port. Their floor is the cavitation law's, which holds in
//!   every step.
//!
//! The adaptive methods do not need the check: their error control rejects such steps.
//! `tests/realtime.rs` checks that they stay inside these bounds in the scenarios that break the
//! fixed step, and that the fixed step is discarded there at the first step out of them.
//!
//! Not checked: the local error estimate (`solver.error_estimate`). It does not separate good
//! steps from bad: in a closed loop whose outputs stay within 5e-6 of their ranges it reaches
//! 1e4 (docs/realtime.md), and in the first step of a diverging 20 ms run, still in bounds, 4e5.

use crate::fmu::logging::Short;
use crate::fmu::Values;
use crate::fragments::servo_valve::ServoValveParameters;

use super::variables::{idx, VARIABLES};

/// How many times the full pilot force's overtravel the spool may be past its stop.
pub const SPOOL_OVERTRAVEL: f64 = 2.0;

/// How many times the supply pressure (gauge) a chamber may reach.
pub const PRESSURE_FACTOR: f64 = 2.0;

/// The spool's bound \[m\]: `x_v_max` plus [`SPOOL_OVERTRAVEL`] times the stop spring's
/// deflection under the full pilot pressure difference (`x_v_max/20`).
pub fn spool_bound(p: &ServoValveParameters) -> f64 {
    let full_force = p.spool_area() * (p.p_supply - p.p_tank);
    p.x_v_max + SPOOL_OVERTRAVEL * full_force / p.stop_stiffness()
}

/// The outputs [`check`] reads, the spool's position first, then the pressures: the caller
/// brings them up to date first (a communication point leaves them until read,
/// `Assembled::write_at_point`).
pub const CHECKED: [usize; 5] = [
    idx::SERVO_VALVE_X_V,
    idx::SERVO_VALVE_P_1,
    idx::SERVO_VALVE_P_2,
    idx::SERVO_VALVE_P_A,
    idx::SERVO_VALVE_P_B,
];

/// The first servo-valve output in `values` outside its physical bound, as a message naming it,
/// its value and the bound; `None` when all are inside. Reads the outputs of [`CHECKED`].
pub fn check(values: &Values, p: &ServoValveParameters) -> Option<String> {
    let x_v = values.real(CHECKED[0]);
    let bound = spool_bound(p);
    if x_v.abs() > bound {
        return Some(format!(
            "the spool at servo_valve.x_v = {x_v:.4e} m, {:.3} times its stroke x_v_max = {} m, \
             beyond the {bound:.4e} m its end stops allow",
            x_v.abs() / p.x_v_max,
            Short(p.x_v_max),
        ));
    }
    let ceiling = PRESSURE_FACTOR * (p.p_supply - p.p_tank);
    for &i in &CHECKED[1..] {
        let name = VARIABLES[i].name;
        let pressure = values.real(i);
        if pressure > ceiling {
            return Some(format!(
                "{name} = {pressure:.4e} Pa, {:.3} times the supply pressure {} Pa (no source in \
                 the circuit reaches {} Pa)",
                pressure / (p.p_supply - p.p_tank),
                Short(p.p_supply - p.p_tank),
                Short(ceiling)
            ));
        }
    }
    None
}
