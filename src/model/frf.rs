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

/// The states' response to one input at one frequency, one complex entry per state.
pub type StateResponse = DVector<Complex<f64>>;

/// The states' response `X` to one input at one frequency with the LU of `j 2 pi f I - A`
/// that gave it, from which [`StateResponseLu::derivative`] gives its derivative along any
/// parameter with one more solve.
pub struct StateResponseLu {
    lu: nalgebra::LU<Complex<f64>, nalgebra::Dyn, nalgebra::Dyn>,
    input: usize,
    f_hz: f64,
    /// `X = (j 2 pi f I - A)^-1 B e_input`.
    pub x: StateResponse,
}

impl StateResponseLu {
    /// `X` for `input` at `f_hz` ([`state_response_at`]), keeping its LU. An error as
    /// [`response_at`]'s.
    pub fn new(lin: &Linearization, input: usize, f_hz: f64) -> Result<Self, String> {
        let n = lin.a.nrows();
        let lu = resolvent(lin, f_hz).lu();
        let b = DVector::from_fn(n, |i, _| Complex::new(lin.b[(i, input)], 0.0));
        let x = lu.solve(&b).ok_or_else(|| unbounded_at(f_hz))?;
        Ok(StateResponseLu { lu, input, f_hz, x })
    }

    /// `dX = (j 2 pi f I - A)^-1 (dA X + dB e_input)` along the parameter whose derivatives `d`
    /// holds ([`crate::model::sensitivity`]).
    pub fn derivative(&self, d: &LinearizationDerivative) -> Result<StateResponse, String> {
        let n = self.x.len();
        let rhs = DVector::from_fn(n, |i, _| {
            let mut v = Complex::new(d.b[(i, self.input)], 0.0);
            for j in 0..n {
                v += self.x[j] * d.a[(i, j)];
            }
            v
        });
        self.lu.solve(&rhs).ok_or_else(|| unbounded_at(self.f_hz))
    }
}

/// The states' response `X` to `input` at `f_hz` ([`state_response_at`]) and its derivative
/// along the parameter whose derivatives `d` holds, from one LU ([`StateResponseLu`]). An
/// error as [`response_at`]'s.
pub fn state_response_and_derivative_at(
    lin: &Linearization,
    d: &LinearizationDerivative,
    input: usize,
    f_hz: f64,
) -> Result<(StateResponse, StateResponse), String> {
    let r = StateResponseLu::new(lin, input, f_hz)?;
    let dx = r.derivative(d)?;
    Ok((r.x, dx))
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

/// The derivative `df*/dp` of a resonance peak's frequency `f*` (a stationary point of `|H|`
/// from `input` to `output`, as [`frequency_response`] refines it) along the parameter whose
/// derivatives `d` holds, exact: with `g(ω) = |H(jω)|²`, `g_ω(ω*) = 0`, so by the implicit
/// function `dω*/dp = -g_ωp / g_ωω`, where, with `R = (jω I - A)^-1`, `X = R B`, `Y = R X`,
/// `Z = R Y` (`dR/dω = -j R²`):
///
/// ```text
/// H_ω = -j C Y,   H_ωω = -2 C Z,   g_ωω = 2 Re(conj(H) H_ωω) + 2 |H_ω|²,
/// dX = R (dA X + dB),   dY = R (dA Y + dX),   H_p = dC X + C dX + dD,
/// H_ωp = -j (dC Y + C dY),   g_ωp = 2 Re(conj(H_p) H_ω + conj(H) H_ωp),
/// ```
///
/// five solves with one LU (`X` and `dX` those of [`StateResponseLu`]), at the stationary point
/// itself (Newton's steps on `g_ω` from `f_hz` first, until a step is below 1e-9 of the peak's
/// half-width). An error where the response is unbounded, or where `g_ωω` is not negative (not
/// a maximum: no peak to follow).
pub fn peak_derivative(
    lin: &Linearization,
    d: &LinearizationDerivative,
    input: usize,
    output: usize,
    f_hz: f64,
) -> Result<f64, String> {
    let n = lin.a.nrows();
    let times = |m: &DMatrix<f64>, v: &StateResponse| -> StateResponse {
        DVector::from_fn(n, |i, _| {
            (0..n).fold(Complex::new(0.0, 0.0), |s, j| s + v[j] * m[(i, j)])
        })
    };
    let row = |m: &DMatrix<f64>, v: &StateResponse| {
        (0..n).fold(Complex::new(0.0, 0.0), |s, i| s + v[i] * m[(output, i)])
    };
    let j = Complex::new(0.0, 1.0);
    let two_pi = 2.0 * std::f64::consts::PI;
    // |H| is flat at its maximum, so a search on |H| places it to about sqrt(eps) only; the
    // derivative wants the stationary point itself: Newton's steps on g_ω = 2 Re(conj(H) H_ω)
    // first, from `f_hz` (quadratic convergence: two or three steps to the settling rule below).
    let mut f = f_hz;
    for _ in 0..4 {
        let r = StateResponseLu::new(lin, input, f)?;
        let solve = |v: &StateResponse| r.lu.solve(v).ok_or_else(|| unbounded_at(f));
        let x = &r.x;
        let y = solve(x)?;
        let z = solve(&y)?;
        let h = output_of(lin, x, input, output);
        let h_w = -j * row(&lin.c, &y);
        let h_ww = row(&lin.c, &z) * -2.0;
        let g_w = 2.0 * (h.conj() * h_w).re;
        let g_ww = 2.0 * (h.conj() * h_ww).re + 2.0 * h_w.norm_sqr();
        if g_ww.is_nan() || g_ww >= 0.0 {
            return Err(format!(
                "no peak to follow at {f} Hz: |H| is not at a maximum there (d²|H|²/dω² = \
                 {g_ww:e})"
            ));
        }
        let step = -g_w / g_ww / two_pi;
        if step.is_nan() || step.abs() > 1e-3 * f {
            return Err(format!(
                "no peak to follow near {f_hz} Hz: Newton's step left it"
            ));
        }
        // Settled: a step below 1e-9 of the peak's half-width `sqrt(g / |g_ωω|)` (g falls to
        // half there), which moves the derivative by about as much relative (it varies on that
        // scale). The round-off of g_ω stops the steps short of the last bits where the
        // resolvent's solves are ill-conditioned (a stiff model: a few ulps of f, oscillating).
        let half_width = (h.norm_sqr() / -g_ww).sqrt() / two_pi;
        if step.abs() > 1e-9 * half_width {
            f += step;
            continue;
        }
        let dx = r.derivative(d)?;
        let dy = solve(&(times(&d.a, &y) + &dx))?;
        let h_p = output_derivative_of(lin, d, x, &dx, input, output);
        let h_wp = -j * (row(&d.c, &y) + row(&lin.c, &dy));
        let g_wp = 2.0 * (h_p.conj() * h_w + h.conj() * h_wp).re;
        // f = ω / 2π, and ω* moves as -g_ωp / g_ωω.
        return Ok(-g_wp / g_ww / two_pi);
    }
    Err(format!(
        "no peak to follow near {f_hz} Hz: Newton's steps did not settle"
    ))
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

    /// One mode `q'' + 2 ζ ω_n q' + ω_n² q = u`, `y = q`: `|H|` peaks at
    /// `ω* = ω_n sqrt(1 - 2 ζ²)`, so `dω*/dω_n = sqrt(1 - 2 ζ²)` and
    /// `dω*/dζ = -2 ζ ω_n / sqrt(1 - 2 ζ²)`: the closed forms the peak's derivative must give.
    #[test]
    fn a_peaks_derivative_is_the_closed_form_of_one_mode() {
        let (wn, zeta) = (2.0 * std::f64::consts::PI * 7.0, 0.05);
        let lin = Linearization {
            a: DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -wn * wn, -2.0 * zeta * wn]),
            b: DMatrix::from_column_slice(2, 1, &[0.0, 1.0]),
            c: DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
            d: DMatrix::zeros(1, 1),
            state_names: vec!["q".into(), "v".into()],
            input_names: vec!["u".into()],
            output_names: vec!["y".into()],
            x0: vec![0.0; 2],
            u0: vec![0.0],
        };
        let peak = frequency_response(&lin, "u", "y", 1.0, 30.0, 400)
            .unwrap()
            .peaks[0]
            .0;
        let exact_peak = wn * (1.0 - 2.0 * zeta * zeta).sqrt() / (2.0 * std::f64::consts::PI);
        assert!(
            (peak / exact_peak - 1.0).abs() < 1e-9,
            "{peak} {exact_peak}"
        );
        let along = |da: [f64; 4]| LinearizationDerivative {
            a: DMatrix::from_row_slice(2, 2, &da),
            b: DMatrix::zeros(2, 1),
            c: DMatrix::zeros(1, 2),
            d: DMatrix::zeros(1, 1),
            f: vec![0.0; 2],
            y: vec![0.0],
        };
        let two_pi = 2.0 * std::f64::consts::PI;
        let s = (1.0 - 2.0 * zeta * zeta).sqrt();
        let d_wn =
            peak_derivative(&lin, &along([0.0, 0.0, -2.0 * wn, -2.0 * zeta]), 0, 0, peak).unwrap();
        assert!((d_wn * two_pi / s - 1.0).abs() < 1e-12, "{}", d_wn * two_pi);
        let d_zeta = peak_derivative(&lin, &along([0.0, 0.0, 0.0, -2.0 * wn]), 0, 0, peak).unwrap();
        let exact = -2.0 * zeta * wn / s / two_pi;
        assert!((d_zeta / exact - 1.0).abs() < 1e-12, "{d_zeta} {exact}");
        // An anti-resonance or a slope is no peak: refused.
        assert!(peak_derivative(&lin, &along([0.0; 4]), 0, 0, 1.0).is_err());
    }
}
