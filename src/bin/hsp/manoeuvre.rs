//! The measures of a manoeuvre, one definition (docs/model.md, "Measures of a manoeuvre";
//! `tools/manoeuvre.py` is the same rule in Python and `tests/python/test_manoeuvre.py` holds
//! the two together):
//!
//! - the command's target: the motor angle `theta* = reference.angle` (when the built-in move
//!   is on) `+ r / controller.k_pot`; `y_pot`'s target is `k_pot theta*`;
//! - the command ends at `t_end = reference.t_start + reference.duration` (the move's end), or
//!   at t = 0 for a step of `r` without a move;
//! - the settling time of a quantity: the time from `t_end` after which it stays within
//!   [`BAND`] of the commanded change (target minus the quantity's value at t = 0) around its
//!   target; "not settled" when it is outside the band at the end of the run, or the run ends
//!   before `t_end`. No minimum hold: the target is known, so a quantity that enters the band
//!   only at the last point is settled at that point, and a later swing out of it is what a
//!   longer run shows;
//! - the residual vibration: the peak of `|w_tip|` from `t_end` on, and its ring-down time, the
//!   time from `t_end` after which `|w_tip|` stays at or below [`RING_LEVEL`]; "not rung down"
//!   when it is above at the end of the run or the run ends before `t_end`.
//!
//! Every measure reads the series at the communication points only.

use hydraulic_slewing_plate::model::parameters::Parameters;

/// The settling band, a fraction of the commanded change.
pub const BAND: f64 = 0.02;
/// The level of `|w_tip|` of the ring-down time \[m\]: 1 mm at the 1.41 m plate's tip is
/// 0.71 mrad of the arm seen from the hub, below the 1 mrad (1.5 counts of a 12-bit reading of
/// the potentiometer's 150 deg) that the oscillation monitor takes as the smallest motion the
/// rig resolves.
pub const RING_LEVEL: f64 = 1e-3;

/// A command with a target: what the measures are taken against.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Command {
    /// The motor angle the command asks for \[rad\].
    pub target: f64,
    /// The time the command ends \[s\].
    pub t_end: f64,
}

impl Command {
    /// The command of a run whose loop is the FMU's: the built-in move, when it is on, with a
    /// step of `r` \[V\] from t = 0.
    pub fn of(p: &Parameters, r: f64) -> Self {
        let mv = &p.reference;
        Command {
            target: r / p.controller.k_pot + if mv.is_on() { mv.angle } else { 0.0 },
            t_end: if mv.is_on() { mv.t_end() } else { 0.0 },
        }
    }
}

/// The first index at or after `t_end`; `None` when the run ends before it.
fn first_after(t: &[f64], t_end: f64) -> Option<usize> {
    t.iter().position(|&ti| ti >= t_end)
}

/// The time from `t_end` after which `outside` stays false over the samples at or after
/// `t_end` (0 when it never holds there); `None` when it holds at the last sample or the run
/// ends before `t_end`.
fn stays_inside_from(t: &[f64], t_end: f64, outside: impl Fn(usize) -> bool) -> Option<f64> {
    let first = first_after(t, t_end)?;
    match (first..t.len()).rev().find(|&i| outside(i)) {
        None => Some(0.0),
        Some(i) if i + 1 < t.len() => Some(t[i + 1] - t_end),
        Some(_) => None,
    }
}

/// The settling time of `y(t)` against `target` after `t_end` \[s from `t_end`\]: see the
/// module's definition. `None`: not settled.
pub fn settling(t: &[f64], y: &[f64], target: f64, t_end: f64) -> Option<f64> {
    let start = *y.first()?;
    let tol = BAND * (target - start).abs();
    stays_inside_from(t, t_end, |i| (y[i] - target).abs() > tol)
}

/// The peak of `|w|` at the samples at or after `t_end`; `None` when the run ends before it.
pub fn residual_peak(t: &[f64], w: &[f64], t_end: f64) -> Option<f64> {
    let first = first_after(t, t_end)?;
    Some(w[first..].iter().fold(0.0, |m, v| m.max(v.abs())))
}

/// The ring-down time of `w(t)` to `level` after `t_end` \[s from `t_end`\]. `None`: not rung
/// down.
pub fn ring_down(t: &[f64], w: &[f64], t_end: f64, level: f64) -> Option<f64> {
    stays_inside_from(t, t_end, |i| w[i].abs() > level)
}

/// The largest excursion of `y` beyond `target`, in % of the commanded change from `y[0]` (0
/// when it never goes beyond).
pub fn overshoot_pct(y: &[f64], target: f64) -> f64 {
    let Some(&start) = y.first() else {
        return 0.0;
    };
    let change = target - start;
    if change == 0.0 {
        return 0.0;
    }
    let s = change.signum();
    let peak = y.iter().map(|v| s * (v - target)).fold(0.0, f64::max);
    peak / change.abs() * 100.0
}

/// A settling time as the summary prints it.
pub fn settling_text(v: Option<f64>) -> String {
    v.map_or("not settled".into(), |s| format!("{s:.3} s"))
}

/// A ring-down time as the summary prints it.
pub fn ring_down_text(v: Option<f64>) -> String {
    v.map_or("not rung down".into(), |s| format!("{s:.3} s"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(stop: f64, h: f64) -> Vec<f64> {
        (0..=(stop / h).round() as usize)
            .map(|i| i as f64 * h)
            .collect()
    }

    #[test]
    fn a_first_order_approach_settles_at_tau_ln_50_after_the_command() {
        // y = A (1 - exp(-(t - t_end) / tau)) after t_end, 0 before: |y - A| = 0.02 A at
        // t - t_end = tau ln 50, so the settling time is the first sample at or after it.
        let (a, tau, t_end, h) = (0.5, 0.3, 1.0, 1e-3);
        let t = grid(4.0, h);
        let y: Vec<f64> = t
            .iter()
            .map(|&ti| {
                if ti < t_end {
                    0.0
                } else {
                    a * (1.0 - (-(ti - t_end) / tau).exp())
                }
            })
            .collect();
        let expected = tau * 50f64.ln();
        let s = settling(&t, &y, a, t_end).unwrap();
        assert!(s >= expected && s < expected + h, "{s} against {expected}");
        // Negative target: the same time.
        let neg: Vec<f64> = y.iter().map(|v| -v).collect();
        assert_eq!(settling(&t, &neg, -a, t_end), Some(s));
        // Cut before tau ln 50: not settled; cut before t_end: not settled.
        let cut = (t_end + 0.9 * expected) / h;
        let n = cut as usize;
        assert_eq!(settling(&t[..n], &y[..n], a, t_end), None);
        assert_eq!(settling(&t[..500], &y[..500], a, t_end), None);
        // A first-order approach does not overshoot.
        assert_eq!(overshoot_pct(&y, a), 0.0);
    }

    #[test]
    fn excursions_before_the_command_ends_do_not_count() {
        // Out of the band until t_end, inside from then on: settled when the command ends.
        let t = grid(3.0, 0.5);
        let y = [0.0, 2.0, 1.5, 1.0, 1.01, 0.99, 1.0];
        assert_eq!(settling(&t, &y, 1.0, 1.5), Some(0.0));
        // Out of the band at 2 s: settled from the next point, 0.5 s after t_end = 1.5 s.
        let y = [0.0, 2.0, 1.5, 1.0, 1.05, 0.99, 1.0];
        assert_eq!(settling(&t, &y, 1.0, 1.5), Some(1.0));
        // Out of the band at the last point: not settled.
        let y = [0.0, 2.0, 1.5, 1.0, 1.0, 1.0, 1.03];
        assert_eq!(settling(&t, &y, 1.0, 1.5), None);
        // The band is 2 % of the change from the first value: 1 to 2, band 0.02.
        let y = [1.0, 2.0, 2.03, 2.015, 2.0, 2.0, 2.0];
        assert_eq!(settling(&t, &y, 2.0, 0.0), Some(1.5));
        assert!((overshoot_pct(&y, 2.0) - 3.0).abs() < 1e-9);
    }

    #[test]
    fn a_decaying_sine_rings_down_where_its_envelope_reaches_the_level() {
        // w = W exp(-sigma s) sin(omega s), s = t - t_end, 0 before t_end but for a 0.2 m
        // swing that the residual must not see. The envelope reaches the level at
        // s_env = ln(W / L) / sigma; the last sample above L lies in the half-period before.
        let (big, sigma, omega, t_end, h) = (0.02, 0.8, 2.0 * std::f64::consts::PI, 2.5, 1e-4);
        let t = grid(12.0, h);
        let w: Vec<f64> = t
            .iter()
            .map(|&ti| {
                let s = ti - t_end;
                if s < 0.0 {
                    if (ti - 1.0).abs() < 1e-9 {
                        0.2
                    } else {
                        0.0
                    }
                } else {
                    big * (-sigma * s).exp() * (omega * s).sin()
                }
            })
            .collect();
        let s_env = (big / RING_LEVEL).ln() / sigma;
        let r = ring_down(&t, &w, t_end, RING_LEVEL).unwrap();
        assert!(
            r > s_env - std::f64::consts::PI / omega && r <= s_env + h,
            "{r} against {s_env}"
        );
        // The residual peak: the first maximum, tan(omega s) = omega / sigma.
        let s_star = (omega / sigma).atan() / omega;
        let expected = big * (-sigma * s_star).exp() * omega / omega.hypot(sigma);
        let peak = residual_peak(&t, &w, t_end).unwrap();
        assert!(peak <= expected && peak > expected * (1.0 - 1e-6), "{peak}");
        // Cut while above the level: not rung down; cut before t_end: no measure.
        // Cut at a crest, s = 1.25 s (sin = 1), where the envelope is 7.4 mm.
        let n = ((t_end + 1.25) / h).round() as usize + 1;
        assert!(w[n - 1] > 5.0 * RING_LEVEL);
        assert_eq!(ring_down(&t[..n], &w[..n], t_end, RING_LEVEL), None);
        assert_eq!(residual_peak(&t[..20_000], &w[..20_000], t_end), None);
        assert_eq!(
            ring_down(&t[..20_000], &w[..20_000], t_end, RING_LEVEL),
            None
        );
        // Never above the level after t_end: rung down when the command ends.
        assert_eq!(ring_down(&t, &w, t_end, 0.1), Some(0.0));
    }

    #[test]
    fn texts() {
        assert_eq!(settling_text(Some(0.2404)), "0.240 s");
        assert_eq!(settling_text(None), "not settled");
        assert_eq!(ring_down_text(None), "not rung down");
    }
}
