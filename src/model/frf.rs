//! Frequency response of the linearised model, `H(j w) = C (j w I - A)^-1 B + D`, and its
//! resonance peaks (`hsp frf`, the FRF tests; the paper's Fig. 9b and Table 1).

use nalgebra::{Complex, DMatrix, DVector};

use crate::bond_graph::{Linearization, LinearizationDerivative};

/// A frequency response on a grid, with its peaks.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrequencyResponse {
    pub input: String,
    pub output: String,
    /// Frequencies \[Hz\].
    pub f_hz: Vec<f64>,
    /// `|H|`.
    pub magnitude: Vec<f64>,
    /// Phase \[deg\].
    pub phase_deg: Vec<f64>,
    /// Resonance peaks: local maxima of `|H|`, refined, as `(f_hz, |H|)`, ascending in frequency.
    pub peaks: Vec<(f64, f64)>,
}

/// `H(j 2 pi f)` for one input and one output. An error, naming the frequency, where
/// `j 2 pi f I - A` is singular (`j 2 pi f` an eigenvalue of A: an undamped mode there, or a
/// free integrator at 0 Hz), where the response is unbounded.
pub fn response_at(
    lin: &Linearization,
    input: usize,
    output: usize,
    f_hz: f64,
) -> Result<Complex<f64>, String> {
    let x = state_response_at(lin, input, f_hz)?;
    Ok(output_of(lin, &x, input, output))
}

/// The states' response to `input` at `f_hz`, `X = (j 2 pi f I - A)^-1 B e_input`, from which
/// [`output_of`] gives every output's (one LU per input and frequency, whatever the outputs).
/// An error as [`response_at`]'s where the response is unbounded.
pub fn state_response_at(
    lin: &Linearization,
    input: usize,
    f_hz: f64,
) -> Result<DVector<Complex<f64>>, String> {
    let n = lin.a.nrows();
    let b = DVector::from_fn(n, |i, _| Complex::new(lin.b[(i, input)], 0.0));
    resolvent(lin, f_hz)
        .lu()
        .solve(&b)
        .ok_or_else(|| unbounded_at(f_hz))
}

/// `j 2 pi f I - A`.
fn resolvent(lin: &Linearization, f_hz: f64) -> DMatrix<Complex<f64>> {
    let n = lin.a.nrows();
    let s = Complex::new(0.0, 2.0 * std::f64::consts::PI * f_hz);
    DMatrix::from_fn(n, n, |i, j| {
        let a = Complex::new(-lin.a[(i, j)], 0.0);
        if i == j {
            a + s
        } else {
            a
        }
    })
}

/// The error where `j 2 pi f I - A` is singular.
fn unbounded_at(f_hz: f64) -> String {
    format!(
        "the response is unbounded at {f_hz} Hz: j 2 pi f I - A is singular there (an undamped \
         mode, or a free integrator at 0 Hz)"
    )
}

/// The state response `X` and its derivative `dX` ([`state_response_and_derivative_at`]).
pub type StateResponseAndDerivative = (DVector<Complex<f64>>, DVector<Complex<f64>>);

/// The states' response `X` to `input` at `f_hz` ([`state_response_at`]) and its derivative
/// `dX = (j 2 pi f I - A)^-1 (dA X + dB e_input)` along the parameter whose derivatives `d`
/// holds ([`crate::model::sensitivity`]), from one LU. An error as [`response_at`]'s.
pub fn state_response_and_derivative_at(
    lin: &Linearization,
    d: &LinearizationDerivative,
    input: usize,
    f_hz: f64,
) -> Result<StateResponseAndDerivative, String> {
    let n = lin.a.nrows();
    let lu = resolvent(lin, f_hz).lu();
    let unbounded = || unbounded_at(f_hz);
    let b = DVector::from_fn(n, |i, _| Complex::new(lin.b[(i, input)], 0.0));
    let x = lu.solve(&b).ok_or_else(unbounded)?;
    let rhs = DVector::from_fn(n, |i, _| {
        let mut v = Complex::new(d.b[(i, input)], 0.0);
        for j in 0..n {
            v += x[j] * d.a[(i, j)];
        }
        v
    });
    let dx = lu.solve(&rhs).ok_or_else(unbounded)?;
    Ok((x, dx))
}

/// `dH = dC_output X + C_output dX + dD_(output, input)`: the derivative of `output`'s
/// response from the states' response and its derivative
/// ([`state_response_and_derivative_at`]).
pub fn output_derivative_of(
    lin: &Linearization,
    d: &LinearizationDerivative,
    x: &DVector<Complex<f64>>,
    dx: &DVector<Complex<f64>>,
    input: usize,
    output: usize,
) -> Complex<f64> {
    let mut y = Complex::new(d.d[(output, input)], 0.0);
    for i in 0..x.len() {
        y += x[i] * d.c[(output, i)] + dx[i] * lin.c[(output, i)];
    }
    y
}

/// `H = C_output X + D_(output, input)`: the response of `output` from the states' response `x`
/// to `input` ([`state_response_at`]).
pub fn output_of(
    lin: &Linearization,
    x: &DVector<Complex<f64>>,
    input: usize,
    output: usize,
) -> Complex<f64> {
    let mut y = Complex::new(lin.d[(output, input)], 0.0);
    for i in 0..x.len() {
        y += x[i] * lin.c[(output, i)];
    }
    y
}

/// The response from `input` to `output` (names) on `points` log-spaced frequencies from
/// `from` to `to` Hz, with refined peaks.
pub fn frequency_response(
    lin: &Linearization,
    input: &str,
    output: &str,
    from: f64,
    to: f64,
    points: usize,
) -> Result<FrequencyResponse, String> {
    let iu = lin
        .input_names
        .iter()
        .position(|n| n == input)
        .ok_or_else(|| {
            format!(
                "'{input}' is not an input of the model ({:?})",
                lin.input_names
            )
        })?;
    let iy = lin
        .output_names
        .iter()
        .position(|n| n == output)
        .ok_or_else(|| format!("'{output}' is not an output of the model"))?;
    if !(from > 0.0 && to > from && points >= 3) {
        return Err(format!(
            "need 0 < from < to and at least 3 points, got {from}, {to}, {points}"
        ));
    }
    let ratio = crate::math::ln(to / from) / (points - 1) as f64;
    let f_hz: Vec<f64> = (0..points)
        .map(|k| from * crate::math::exp(ratio * k as f64))
        .collect();
    let h: Vec<Complex<f64>> = f_hz
        .iter()
        .map(|&f| response_at(lin, iu, iy, f))
        .collect::<Result<_, _>>()?;
    let magnitude: Vec<f64> = h.iter().map(|z| z.norm()).collect();
    let phase_deg = h.iter().map(|z| z.arg().to_degrees()).collect();
    let mut peaks = Vec::new();
    for k in 1..points - 1 {
        if magnitude[k] > magnitude[k - 1] && magnitude[k] >= magnitude[k + 1] {
            // golden-section refinement of |H| on [f_{k-1}, f_{k+1}]
            // An unbounded point inside the bracket is the peak itself.
            let mag = |f: f64| response_at(lin, iu, iy, f).map_or(f64::INFINITY, |h| h.norm());
            let (mut lo, mut hi) = (f_hz[k - 1], f_hz[k + 1]);
            let g = (5f64.sqrt() - 1.0) / 2.0;
            let mut x1 = hi - g * (hi - lo);
            let mut x2 = lo + g * (hi - lo);
            let (mut m1, mut m2) = (mag(x1), mag(x2));
            for _ in 0..60 {
                if m1 > m2 {
                    hi = x2;
                    x2 = x1;
                    m2 = m1;
                    x1 = hi - g * (hi - lo);
                    m1 = mag(x1);
                } else {
                    lo = x1;
                    x1 = x2;
                    m1 = m2;
                    x2 = lo + g * (hi - lo);
                    m2 = mag(x2);
                }
            }
            let f = 0.5 * (lo + hi);
            peaks.push((f, mag(f)));
        }
    }
    Ok(FrequencyResponse {
        input: input.to_string(),
        output: output.to_string(),
        f_hz,
        magnitude,
        phase_deg,
        peaks,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A free integrator (`x' = u`): unbounded at 0 Hz, 1/(j 2 pi f) elsewhere.
    #[test]
    fn a_singular_point_is_an_error_naming_the_frequency() {
        let lin = Linearization {
            a: DMatrix::zeros(1, 1),
            b: DMatrix::from_element(1, 1, 1.0),
            c: DMatrix::from_element(1, 1, 1.0),
            d: DMatrix::zeros(1, 1),
            state_names: vec!["x".into()],
            input_names: vec!["u".into()],
            output_names: vec!["y".into()],
            x0: vec![0.0],
            u0: vec![0.0],
        };
        let e = response_at(&lin, 0, 0, 0.0).unwrap_err();
        assert!(e.contains("unbounded at 0 Hz"), "{e}");
        let h = response_at(&lin, 0, 0, 1.0).unwrap();
        let w = 2.0 * std::f64::consts::PI;
        assert!((h - Complex::new(0.0, -1.0 / w)).norm() < 1e-15, "{h}");
    }
}
