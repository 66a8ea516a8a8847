//! The loop-margin monitor: how well damped the model is at rest, computed once when the FMU is
//! initialised (docs/model.md, "The default loop's damping").
//!
//! The model is linearised at its rest state with the inputs at zero (`A`, the exact Jacobian of
//! the compiled bond graph); its eigenvalues are the balanced ones of [`crate::eigen`]; the least
//! damped mode (the smallest damping ratio `ζ = −Re λ / |λ|`) is written to the calculated
//! parameters `margin.zeta` and `margin.f`. Eigenvalues of modulus below 1e-9 of the largest are
//! left out: they are the zeros of the free hub angle, of the command generator's clock and, with
//! the motor uncoupled, of the plate's rigid rotation, none of them a vibration.
//!
//! A warning is logged when the closed loop is unstable (`ζ < 0`) or damped less than a third of
//! the structure's own damping ratio (`plate.zeta / 3`, the rule the default loop is designed to
//! meet over the range of the unmeasured parameters, `tests/robust_plant.rs`): a disturbance of
//! that mode then rings three times longer than the structure alone would let it. With
//! `controller.external` the FMU's analog loop is open (the user's controller closes it), so the
//! monitor reports the plant with `e_in` held and does not warn.
//!
//! The vane motor's seal friction is left out of the linearisation (the motor sliding,
//! [`Parameters::sliding`]): at rest its regularised slope would clamp the motor and hide the
//! loop ([`jacobian_sliding_at_rest`]).
//!
//! Cost: one Jacobian and one eigenvalue problem of the state dimension when the model is built
//! (again only when a parameter changes), none in the steps; `bench-margin` measures it.

use nalgebra::Complex;

use crate::eigen::{eigenvalues, least_damped, modulus, Mode};

use crate::fragments::vane_motor;

use super::assembly::Assembled;
use super::parameters::Parameters;

/// Eigenvalues of modulus below this fraction of the largest are rigid-body and integrator zeros.
pub const ZERO_FRACTION: f64 = 1e-9;

/// The warning threshold as a fraction of `plate.zeta`.
pub const THRESHOLD_FRACTION: f64 = 1.0 / 3.0;

/// Round-off allowance on the damping ratio: a mode at exactly the threshold (an undamped plate
/// mode with `plate.zeta = 0`, whose real part is round-off) does not warn.
pub const ROUND_OFF: f64 = 1e-9;

/// The Jacobian at rest with zero inputs of the loop with the vane motor sliding
/// ([`Parameters::sliding`]), from the model as built. The seal friction is a resistor on the
/// rotor's 1-junction, whose flow is the rotor's momentum over `I_m`
/// ([`crate::fragments::vane_motor`]): its slope at rest, `T'(0)`, enters `A` at the rotor
/// momentum's own entry only, as `−T'(0) / I_m`, which is added back here. (The same matrix as
/// the sliding model's own Jacobian, without building that model a second time:
/// `tests/robust_plant.rs`, `the_margins_sliding_jacobian_is_the_sliding_models`.)
pub fn jacobian_sliding_at_rest(system: &Assembled, p: &Parameters) -> nalgebra::DMatrix<f64> {
    let model = system.compiled();
    let n = model.n_states();
    let mut a = nalgebra::DMatrix::zeros(n, n);
    let u = vec![0.0; model.n_inputs()];
    let x = system.initial_state();
    model.jacobian(&x, &u, &mut a);
    let sv = &p.servo_valve;
    if let Some(i) = model.state_index("servo_valve.I_m.p") {
        if sv.t_s > 0.0 {
            let (_, slope) = vane_motor::friction(sv.t_c, sv.t_s, sv.omega_s, x[i] / sv.i_m);
            a[(i, i)] += slope / sv.i_m;
        }
    }
    a
}

/// The balanced eigenvalues at rest of the loop with the vane motor sliding
/// ([`jacobian_sliding_at_rest`]).
pub fn eigenvalues_sliding_at_rest(system: &Assembled, p: &Parameters) -> Vec<Complex<f64>> {
    eigenvalues(&jacobian_sliding_at_rest(system, p))
}

/// The least damped mode at rest of the loop with the vane motor sliding, what the FMU's monitor
/// reports; `None` when every eigenvalue is a zero.
pub fn least_damped_sliding(system: &Assembled, p: &Parameters) -> Option<Mode> {
    least_damped_mode(&eigenvalues_sliding_at_rest(system, p))
}

/// The least damped mode of the eigenvalues `ev` of a model at rest, leaving out the zeros
/// ([`ZERO_FRACTION`] of the largest modulus); `None` when every eigenvalue is one.
pub fn least_damped_mode(ev: &[Complex<f64>]) -> Option<Mode> {
    let largest = ev.iter().map(|z| modulus(*z)).fold(0.0, f64::max);
    least_damped(ev, ZERO_FRACTION * largest)
}

/// How a damping ratio stands against the warning threshold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The mode grows (`ζ` below zero by more than round-off).
    Unstable,
    /// Damped less than the threshold (by more than round-off).
    PoorlyDamped,
    /// At or above the threshold, up to round-off.
    Damped,
}

/// The verdict on a damping ratio `zeta` against `threshold`, with the round-off allowance
/// (a mode at exactly the threshold, or an undamped one when the threshold is 0, is damped).
pub fn verdict(zeta: f64, threshold: f64) -> Verdict {
    if zeta < -ROUND_OFF {
        Verdict::Unstable
    } else if zeta < threshold - ROUND_OFF {
        Verdict::PoorlyDamped
    } else {
        Verdict::Damped
    }
}

/// The damping ratio below which the monitor warns.
pub fn threshold(p: &Parameters) -> f64 {
    THRESHOLD_FRACTION * p.plate.zeta
}

/// The warning for a least damped mode `m`, if it deserves one.
pub fn warning(m: &Mode, p: &Parameters) -> Option<String> {
    if p.controller.external {
        return None;
    }
    let limit = threshold(p);
    let f = m.frequency_hz();
    if m.zeta.is_nan() {
        return Some(
            "loop margin: the eigenvalues of the model at rest could not be computed".into(),
        );
    }
    let v = verdict(m.zeta, limit);
    if v == Verdict::Unstable {
        let sigma = m.eigenvalue.re;
        return Some(format!(
            "loop margin: the loop at rest is unstable: its mode at {f:.3} Hz grows (damping ratio {:.4}, \
             amplitude doubling every {:.3} s); a run will oscillate or drift away. Check \
             servo_valve.beta, servo_valve.R_leak, plate.zeta and the loop's design \
             (controller.k_pl, servo_valve.drive; docs/model.md, \"The default loop's damping\")",
            m.zeta,
            core::f64::consts::LN_2 / sigma
        ));
    }
    if v == Verdict::PoorlyDamped {
        return Some(format!(
            "loop margin: the loop at rest is poorly damped: its mode at {f:.3} Hz has a damping ratio \
             of {:.4}, below {limit:.4} (a third of plate.zeta), so a disturbance of it rings on \
             long after the structure's own modes have decayed. Check servo_valve.beta, \
             servo_valve.R_leak, plate.zeta and the loop's design (controller.k_pl, \
             servo_valve.drive; docs/model.md, \"The default loop's damping\")",
            m.zeta
        ));
    }
    None
}
