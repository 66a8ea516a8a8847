//! Measured resonance peaks as a fit's target (`--peaks INPUT:OUTPUT:FILE.csv`): the
//! frequencies where `|H|` of OUTPUT to INPUT has a local maximum, each with its standard
//! uncertainty, such as a table of a paper gives them (Table 1 of Barbosa & Góes) when the
//! response itself is not at hand.
//!
//! The model's peaks are those of `hsp frf` ([`frequency_response`]: local maxima of `|H|` on a
//! log-spaced grid, refined by golden section) of the linearisation at rest, on a grid from half
//! the lowest measured peak to twice the highest, spaced by [`GRID_STEP`]. Each measured peak is
//! the model's peak nearest to it in `ln f` (an error when two measured peaks would take the
//! same model peak, or the model has none). The residual of peak `k` is
//!
//! ```text
//! e_k = (f_model,k - f_measured,k) / sigma_k,
//! ```
//!
//! so that with peaks alone the residuals are in units of their standard uncertainties and the
//! fit's variance is known (`s^2 = 1`, super::intervals).

use hydraulic_slewing_plate::bond_graph::Linearization;
use hydraulic_slewing_plate::model::frf::frequency_response;

use super::data::Measured;

/// The model's grid: log-spaced, neighbours `1 + GRID_STEP` apart (0.5 %), four points within
/// the half-power band `2 zeta f` of a mode damped at `zeta` = 0.01, so that no such peak falls
/// between two points unseen.
pub const GRID_STEP: f64 = 0.005;

/// Measured resonance peaks of OUTPUT's response to INPUT.
#[derive(Clone, Debug)]
pub struct Peaks {
    pub input: String,
    pub output: String,
    /// The file they were read from, as given.
    pub file: String,
    /// The peaks' frequencies \[Hz\], ascending.
    pub f_hz: Vec<f64>,
    /// Their standard uncertainties \[Hz\].
    pub sigma_hz: Vec<f64>,
}

impl Peaks {
    /// Parses `INPUT:OUTPUT:FILE.csv` and reads the file: a header naming `f_Hz` and
    /// `sigma_Hz`, in any order, then one row per peak. Every frequency must be positive and
    /// finite, every uncertainty positive and finite, no two frequencies equal; an error names
    /// the file, the data row and the value. The rows are sorted by frequency.
    pub fn read(spec: &str) -> Result<Peaks, String> {
        let m = Measured::read("--peaks", spec)?;
        let file = &m.file;
        let column = |name: &str| m.column(name, "f_Hz,sigma_Hz");
        let (f, sigma) = (column("f_Hz")?, column("sigma_Hz")?);
        if f.is_empty() {
            return Err(format!("{file}: no data rows"));
        }
        for k in 0..f.len() {
            let row = k + 1;
            if !(f[k].is_finite() && f[k] > 0.0) {
                return Err(format!(
                    "{file}: data row {row}: f_Hz = {} is not a positive frequency",
                    f[k]
                ));
            }
            if !(sigma[k].is_finite() && sigma[k] > 0.0) {
                return Err(format!(
                    "{file}: data row {row}: sigma_Hz = {} is not a positive uncertainty",
                    sigma[k]
                ));
            }
        }
        let mut rows: Vec<(f64, f64)> = f.iter().copied().zip(sigma.iter().copied()).collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(w) = rows.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(format!("{file}: the peak at {} Hz is given twice", w[0].0));
        }
        Ok(Peaks {
            input: m.input.clone(),
            output: m.output.clone(),
            file: m.file.clone(),
            f_hz: rows.iter().map(|r| r.0).collect(),
            sigma_hz: rows.iter().map(|r| r.1).collect(),
        })
    }

    /// The model's peak taken for each measured one (module doc), Hz.
    pub fn model(&self, lin: &Linearization) -> Result<Vec<f64>, String> {
        let (lo, hi) = (self.f_hz[0] / 2.0, self.f_hz[self.f_hz.len() - 1] * 2.0);
        let points = ((hi / lo).ln() / GRID_STEP.ln_1p()).ceil() as usize + 1;
        let response = frequency_response(lin, &self.input, &self.output, lo, hi, points)
            .map_err(|e| format!("--peaks {}: {e}", self.file))?;
        let found: Vec<f64> = response.peaks.iter().map(|p| p.0).collect();
        if found.is_empty() {
            return Err(format!(
                "--peaks {}: the model's response of {} to {} has no peak between {lo} and {hi} Hz",
                self.file, self.output, self.input
            ));
        }
        let taken: Vec<usize> = self
            .f_hz
            .iter()
            .map(|&f| {
                (0..found.len())
                    .min_by(|&a, &b| {
                        (found[a] / f)
                            .ln()
                            .abs()
                            .total_cmp(&(found[b] / f).ln().abs())
                    })
                    .expect("at least one peak")
            })
            .collect();
        if let Some(k) = (1..taken.len()).find(|&k| taken[k] == taken[k - 1]) {
            let listed: Vec<String> = found.iter().map(|f| format!("{f:.4}")).collect();
            return Err(format!(
                "--peaks {}: the measured peaks at {} and {} Hz are both nearest the model's peak \
                 at {:.4} Hz (the model's peaks from {lo} to {hi} Hz: {}); start nearer with --set",
                self.file,
                self.f_hz[k - 1],
                self.f_hz[k],
                found[taken[k]],
                listed.join(", ")
            ));
        }
        Ok(taken.into_iter().map(|i| found[i]).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// Two lightly damped modes, at 5 and 16 Hz, of `x'' + 2 zeta w x' + w^2 x = u` each, summed
    /// into one output: its peaks, close to the undamped frequencies (`w sqrt(1 - 2 zeta^2)` for
    /// a displacement's peak), are taken by the measured peaks nearest them.
    fn two_modes() -> Linearization {
        let zeta = 0.01;
        let mut a = DMatrix::zeros(4, 4);
        for (m, f) in [5.0, 16.0].iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            a[(2 * m, 2 * m + 1)] = 1.0;
            a[(2 * m + 1, 2 * m)] = -w * w;
            a[(2 * m + 1, 2 * m + 1)] = -2.0 * zeta * w;
        }
        Linearization {
            a,
            b: DMatrix::from_column_slice(4, 1, &[0.0, 1.0, 0.0, 1.0]),
            c: DMatrix::from_row_slice(1, 4, &[1.0, 0.0, 1.0, 0.0]),
            d: DMatrix::zeros(1, 1),
            state_names: (0..4).map(|i| format!("x{i}")).collect(),
            input_names: vec!["u".into()],
            output_names: vec!["y".into()],
            x0: vec![0.0; 4],
            u0: vec![0.0],
        }
    }

    fn peaks(f_hz: &[f64]) -> Peaks {
        Peaks {
            input: "u".into(),
            output: "y".into(),
            file: "test.csv".into(),
            f_hz: f_hz.to_vec(),
            sigma_hz: vec![0.1; f_hz.len()],
        }
    }

    #[test]
    fn each_measured_peak_takes_the_models_nearest() {
        let lin = two_modes();
        let got = peaks(&[4.5, 17.0]).model(&lin).unwrap();
        for (g, f) in got.iter().zip([5.0, 16.0]) {
            // The displacement's peak of one mode alone is at f sqrt(1 - 2 zeta^2); the other
            // mode shifts it by less than 1e-3 relative.
            assert!(
                (g / (f * (1.0f64 - 2e-4).sqrt()) - 1.0).abs() < 1e-3,
                "{got:?}"
            );
        }
        let e = peaks(&[4.5, 5.5]).model(&lin).unwrap_err();
        assert!(e.contains("4.5 and 5.5 Hz are both nearest"), "{e}");
    }
}
