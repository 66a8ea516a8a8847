//! The linearised direct path of the full servo valve against the identified
//! `G_est(s) = 2.25e6 / (s (s+65) (s+753))` (eq. 2 of the paper).

use nalgebra::Complex;

use crate::bond_graph::Linearization;

use crate::fragments::controller::ControllerParameters;
use crate::fragments::loes::{G_EST_GAIN, G_EST_POLE_1, G_EST_POLE_2};
use crate::model::frf::response_at;

use super::{build_loop, build_open_loop, nominals, rest_state, ServoValveParameters};

/// `G_est(j omega) = 2.25e6 / (j omega (j omega + 65)(j omega + 753))` (eq. 2).
pub fn g_est(omega: f64) -> Complex<f64> {
    let s = Complex::new(0.0, omega);
    Complex::new(G_EST_GAIN, 0.0) / (s * (s + G_EST_POLE_1) * (s + G_EST_POLE_2))
}

/// One row of the comparison with `G_est`.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct GEstPoint {
    /// Frequency \[Hz\].
    pub f_hz: f64,
    /// `|G_full|` \[dB\].
    pub mag_db: f64,
    /// `|G_est|` \[dB\].
    pub mag_db_est: f64,
    /// `arg G_full` \[deg\].
    pub phase_deg: f64,
    /// `arg G_est` \[deg\].
    pub phase_deg_est: f64,
}

impl GEstPoint {
    /// `|G_full| / |G_est|` in dB.
    pub fn mag_err_db(&self) -> f64 {
        self.mag_db - self.mag_db_est
    }
    /// `arg G_full - arg G_est` in degrees, wrapped to (-180, 180].
    pub fn phase_err_deg(&self) -> f64 {
        let d = self.phase_deg - self.phase_deg_est;
        d - 360.0 * ((d + 180.0) / 360.0).floor()
    }
}

/// The linearised direct path of the full model (open loop, motor uncoupled) at its rest state.
pub fn open_loop_linearization(
    p: &ServoValveParameters,
    ctrl: &ControllerParameters,
) -> Result<Linearization, String> {
    let graph = build_loop(p, ctrl)?;
    let closed = graph.compile().map_err(|e| e.to_string())?;
    let x_closed = rest_state(&closed, &[0.0], "servo_valve", p, &nominals(&graph))?;
    let open = build_open_loop(p, ctrl)?
        .compile()
        .map_err(|e| e.to_string())?;
    let x: Vec<f64> = open
        .state_names()
        .iter()
        .map(|n| {
            closed
                .state_index(n)
                .map(|i| x_closed[i])
                .ok_or_else(|| format!("state {n} of the open loop is not in the closed loop"))
        })
        .collect::<Result<_, _>>()?;
    Ok(open.linearize(&x, &[0.0]))
}

/// The linearised direct path against `G_est` at the given frequencies \[Hz\].
pub fn compare_with_g_est(
    p: &ServoValveParameters,
    ctrl: &ControllerParameters,
    freqs_hz: &[f64],
) -> Result<Vec<GEstPoint>, String> {
    let lin = open_loop_linearization(p, ctrl)?;
    let out = lin
        .output_names
        .iter()
        .position(|n| n == "y_pot")
        .expect("y_pot output");
    freqs_hz
        .iter()
        .map(|&f| {
            let g = response_at(&lin, 0, out, f)?;
            let e = g_est(2.0 * std::f64::consts::PI * f);
            Ok(GEstPoint {
                f_hz: f,
                mag_db: 20.0 * crate::math::log10(g.norm()),
                mag_db_est: 20.0 * crate::math::log10(e.norm()),
                phase_deg: g.arg().to_degrees(),
                phase_deg_est: e.arg().to_degrees(),
            })
        })
        .collect()
}

/// Log-spaced frequencies from `f0` to `f1` \[Hz\], `n` points.
pub fn log_frequencies(f0: f64, f1: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| f0 * crate::math::powf(f1 / f0, i as f64 / (n - 1) as f64))
        .collect()
}
