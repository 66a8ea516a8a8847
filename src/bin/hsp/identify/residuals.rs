//! The weighted residuals of a fit and their sensitivities.
//!
//! At each measured point `k` of a response `H_d` the residual is the weighted relative error of
//! the model's response `H_m` (the linearisation at rest, [`crate::linearization_at_rest`], exact: dual
//! numbers through the compiled bond graph),
//!
//! ```text
//! e_k = w_k (H_m(j 2 pi f_k) - H_d,k) / |H_d,k|,
//! ```
//!
//! split into its real and imaginary parts, so that a 1 % error counts the same on a resonance
//! peak and in an anti-resonance, and the responses of outputs in different units weigh alike.
//! Measured resonance peaks (`--peaks`) add one residual each, the model's peak's error in units
//! of the measured one's uncertainty ([`super::peaks`]); measured time series (`--series`) one
//! per output and time, the error of the FMU's simulation relative to the output's RMS
//! ([`super::series`]).
//!
//! **Sensitivities.** The derivatives of the residuals with respect to the fitted parameters
//! (in their coordinates `z`, [`super::data::Scale`]) are exact where the model can give them,
//! for a parameter whose fragments carry dual numbers
//! ([`hydraulic_slewing_plate::model::sensitivity`]): for frequency responses and peaks from
//! `dA/dp, dB/dp, dC/dp, dD/dp` at rest by hyper-dual passes, then `dH/dp` from the same LU as
//! `H`; for time series, with `--series-sensitivities forward`, from the forward sensitivities
//! of the simulation ([`hydraulic_slewing_plate::model::sensitivity::series`]). Elsewhere they
//! are central finite differences of the model's residuals, step [`STEP`] in `z`: for a
//! parameter whose fragments still fold it in as an `f64` constant (the reason is kept and
//! reported, [`Problem::methods`]), and for time series by default (cheaper there,
//! docs/identify.md). A column is exact where every part of it is.

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use hydraulic_slewing_plate::bond_graph::{Linearization, LinearizationDerivative};
use hydraulic_slewing_plate::fmu::{Experiment, Value, Values};
use hydraulic_slewing_plate::model::frf::{
    output_derivative_of, output_of, peak_derivative, state_response_at, StateResponseLu,
};
use hydraulic_slewing_plate::model::parameters::{check, Parameters};
use hydraulic_slewing_plate::model::sensitivity::series::{simulate_with_sensitivities, Direction};
use hydraulic_slewing_plate::model::sensitivity::{linearization_at_rest_of, seeded_at_rest};
use nalgebra::{Complex, DMatrix, DVector};

use super::data::{Fitted, Frf};
use super::peaks::Peaks;
use super::series::Series;

/// The central-difference step in `z` (a relative step of 1e-4 for a log-scaled parameter):
/// truncation error of order `STEP^2` = 1e-8 of the sensitivity, round-off of order 1e-16 /
/// `STEP` of the response's own accuracy.
pub const STEP: f64 = 1e-4;

/// A fit's data and parameters on its starting configuration.
pub struct Problem {
    /// The starting configuration (preset and `--set`).
    pub base: Values,
    pub frfs: Vec<Frf>,
    pub peaks: Vec<Peaks>,
    pub series: Vec<Series>,
    pub fitted: Vec<Fitted>,
    /// Per response: the index of its input and its output in the linearisation.
    ports: Vec<(usize, usize)>,
    /// Per set of peaks: the same.
    peak_ports: Vec<(usize, usize)>,
    /// Model evaluations so far (one linearisation and its responses each).
    pub evaluations: AtomicUsize,
    /// Exact derivatives of the linearisation so far (one model built in dual numbers for one
    /// parameter, and its hyper-dual passes, each).
    pub derivatives: AtomicUsize,
    /// Per fitted parameter, why its sensitivities were central differences (the last reason
    /// met), `None` while they have been exact.
    finite_differences: Mutex<Vec<Option<String>>>,
    /// The model's peaks taken for the measured ones at the parameters last evaluated (their
    /// bits): the exact Jacobian at the same point takes them from here instead of searching
    /// the response again.
    last_peaks: Mutex<Option<KeptPeaks>>,
    /// How the sensitivities are asked for.
    sensitivities: Sensitivities,
    /// How the time series' sensitivities are asked for.
    pub series_sensitivities: SeriesSensitivities,
}

/// How the sensitivities are asked for (`--sensitivities`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Sensitivities {
    /// Exact where the model gives them, central differences elsewhere.
    Exact,
    /// Central differences for every parameter.
    Central,
}

/// How the time series' sensitivities are asked for (`--series-sensitivities`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SeriesSensitivities {
    /// Central differences of the FMU's simulation.
    Central,
    /// Forward sensitivities integrated beside the states
    /// ([`hydraulic_slewing_plate::model::sensitivity::series`]).
    Forward,
}

/// How a fitted parameter's sensitivities were computed ([`Problem::methods`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// Exact: dual numbers through the model.
    Exact,
    /// Central differences, and why.
    CentralDifferences(String),
}

impl Problem {
    /// Checks every response's input and output against the model of the starting
    /// configuration; an error names the file and lists the model's inputs or outputs.
    pub fn new(
        base: Values,
        frfs: Vec<Frf>,
        peaks: Vec<Peaks>,
        series: Vec<Series>,
        fitted: Vec<Fitted>,
        sensitivities: Sensitivities,
        series_sensitivities: SeriesSensitivities,
    ) -> Result<Problem, String> {
        if fitted.is_empty() {
            return Err("nothing to fit: give at least one --fit NAME".into());
        }
        if frfs.is_empty() && peaks.is_empty() && series.is_empty() {
            return Err(
                "no data: give at least one --frf INPUT:OUTPUT:FILE.csv, --peaks \
                 INPUT:OUTPUT:FILE.csv or --series FILE.csv"
                    .into(),
            );
        }
        for (i, a) in fitted.iter().enumerate() {
            if fitted[..i].iter().any(|b| b.index == a.index) {
                return Err(format!("--fit {}: given twice", a.name));
            }
        }
        let lin = linearization(&base)?;
        let port = |flag: &str, file: &str, input: &str, output: &str| {
            let i = lin.input_names.iter().position(|n| n == input);
            let o = lin.output_names.iter().position(|n| n == output);
            match (i, o) {
                (Some(i), Some(o)) => Ok((i, o)),
                (None, _) => Err(format!(
                    "{flag} {file}: '{input}' is not an input of the model ({:?})",
                    lin.input_names
                )),
                (_, None) => Err(format!(
                    "{flag} {file}: '{output}' is not an output of the model ({:?})",
                    lin.output_names
                )),
            }
        };
        let ports = frfs
            .iter()
            .map(|d| port("--frf", &d.file, &d.input, &d.output))
            .collect::<Result<_, _>>()?;
        let peak_ports = peaks
            .iter()
            .map(|d| port("--peaks", &d.file, &d.input, &d.output))
            .collect::<Result<_, _>>()?;
        Ok(Problem {
            base,
            frfs,
            peaks,
            series,
            ports,
            peak_ports,
            evaluations: AtomicUsize::new(0),
            derivatives: AtomicUsize::new(0),
            finite_differences: Mutex::new(vec![None; fitted.len()]),
            fitted,
            last_peaks: Mutex::new(None),
            sensitivities,
            series_sensitivities,
        })
    }

    /// The number of (real) residuals.
    pub fn len(&self) -> usize {
        2 * self.frfs.iter().map(|d| d.f_hz.len()).sum::<usize>()
            + self.peaks.iter().map(|d| d.f_hz.len()).sum::<usize>()
            + self.series.iter().map(Series::len).sum::<usize>()
    }

    /// Whether the residuals' variance is known: peaks alone, each residual in units of its
    /// standard uncertainty; with a frequency response or a time series it is estimated from
    /// the fit.
    pub fn known_variance(&self) -> bool {
        self.frfs.is_empty() && self.series.is_empty()
    }

    /// The starting configuration with the fitted parameters at `p`; an error names a value the
    /// model refuses (a positive parameter gone non-positive, say).
    pub fn values_at(&self, p: &[f64]) -> Result<Values, String> {
        let mut values = self.base.clone();
        for (f, &v) in self.fitted.iter().zip(p) {
            let value = Value::Real(v);
            check(f.index, &value)?;
            values.set(f.index, value);
        }
        Ok(values)
    }

    /// The model's linearisation at `p` (one model evaluation).
    fn evaluate(&self, p: &[f64]) -> Result<Linearization, String> {
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        linearization(&self.values_at(p)?)
    }

    /// The model's responses at `p`, one vector per measured response.
    pub fn responses(&self, p: &[f64]) -> Result<Vec<Vec<Complex<f64>>>, String> {
        self.responses_of(&self.evaluate(p)?)
    }

    /// The model's peaks at `p` taken for the measured ones, one vector per `--peaks`.
    pub fn model_peaks(&self, p: &[f64]) -> Result<Vec<Vec<f64>>, String> {
        let lin = self.evaluate(p)?;
        self.peaks.iter().map(|d| d.model(&lin)).collect()
    }

    /// The responses of the linearisation `lin`, one vector per measured response.
    fn responses_of(&self, lin: &Linearization) -> Result<Vec<Vec<Complex<f64>>>, String> {
        // One solve per input and frequency, shared by the outputs measured there.
        let mut states: HashMap<(usize, u64), DVector<Complex<f64>>> = HashMap::new();
        let mut out = Vec::with_capacity(self.frfs.len());
        for (d, &(i, o)) in self.frfs.iter().zip(&self.ports) {
            let mut h = Vec::with_capacity(d.f_hz.len());
            for &f in &d.f_hz {
                let x = match states.entry((i, f.to_bits())) {
                    std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                    std::collections::hash_map::Entry::Vacant(e) => {
                        e.insert(state_response_at(lin, i, f)?)
                    }
                };
                h.push(output_of(lin, x, i, o));
            }
            out.push(h);
        }
        Ok(out)
    }

    /// The weighted residuals at the parameters `p` (module doc).
    pub fn residuals(&self, p: &[f64]) -> Result<DVector<f64>, String> {
        let lin = self.evaluate(p)?;
        let model = self.responses_of(&lin)?;
        let mut r = Vec::with_capacity(self.len());
        for (d, m) in self.frfs.iter().zip(&model) {
            for ((model, data), w) in m.iter().zip(&d.h).zip(&d.weight) {
                let e = error(*model, *data, *w);
                r.push(e.re);
                r.push(e.im);
            }
        }
        let peaks: Vec<Vec<f64>> = self
            .peaks
            .iter()
            .map(|d| d.model(&lin))
            .collect::<Result<_, _>>()?;
        for (d, model) in self.peaks.iter().zip(&peaks) {
            for ((m, f), sigma) in model.iter().zip(&d.f_hz).zip(&d.sigma_hz) {
                r.push((m - f) / sigma);
            }
        }
        if !peaks.is_empty() {
            *self.last_peaks.lock().unwrap() = Some((bits(p), peaks));
        }
        if !self.series.is_empty() {
            let values = self.values_at(p)?;
            for d in &self.series {
                d.residuals(&d.simulate(&values)?, &mut r);
            }
        }
        Ok(DVector::from_vec(r))
    }

    /// Per measured response, the RMS over its points of the weighted relative error `|e_k|`
    /// (module doc) of the model at `p`.
    pub fn rms(&self, p: &[f64]) -> Result<Vec<f64>, String> {
        if self.frfs.is_empty() {
            return Ok(Vec::new());
        }
        let model = self.responses(p)?;
        Ok(self
            .frfs
            .iter()
            .zip(&model)
            .map(|(d, m)| {
                let sum: f64 = m
                    .iter()
                    .zip(&d.h)
                    .zip(&d.weight)
                    .map(|((model, data), w)| error(*model, *data, *w).norm_sqr())
                    .sum();
                (sum / d.h.len() as f64).sqrt()
            })
            .collect())
    }

    /// The fitted parameters' values at the coordinates `z`.
    pub fn p_of_z(&self, z: &[f64]) -> Vec<f64> {
        self.fitted.iter().zip(z).map(|(f, &z)| f.p_of(z)).collect()
    }

    /// The residuals at the coordinates `z`.
    pub fn residuals_z(&self, z: &[f64]) -> Result<DVector<f64>, String> {
        self.residuals(&self.p_of_z(z))
    }

    /// How each fitted parameter's sensitivities were computed so far: exact, or central
    /// differences and why (module doc).
    pub fn methods(&self) -> Vec<Method> {
        self.finite_differences
            .lock()
            .unwrap()
            .iter()
            .map(|r| match r {
                None => Method::Exact,
                Some(why) => Method::CentralDifferences(why.clone()),
            })
            .collect()
    }

    /// `d residuals / d z` at `z`, a column per parameter: exact where the model gives the
    /// derivative, central differences elsewhere (module doc).
    pub fn jacobian_z(&self, z: &[f64]) -> Result<DMatrix<f64>, String> {
        let mut jac = DMatrix::zeros(self.len(), z.len());
        let exact = self.exact_columns(z)?;
        for (j, column) in exact.into_iter().enumerate() {
            match column {
                Ok(column) => jac.set_column(j, &column),
                Err(why) => {
                    self.finite_differences.lock().unwrap()[j] = Some(why);
                    jac.set_column(j, &self.central_difference(z, j)?);
                }
            }
        }
        Ok(jac)
    }

    /// The exact columns of `d residuals / d z` at `z`, or for each parameter why there is
    /// none: the frequency responses' and peaks' from the linearisation's derivatives, the time
    /// series' from forward sensitivities; a column is exact where every part of it is.
    fn exact_columns(&self, z: &[f64]) -> Result<Vec<Result<DVector<f64>, String>>, String> {
        if self.sensitivities == Sensitivities::Central {
            let why = "asked for (--sensitivities central)".to_string();
            return Ok(vec![Err(why); z.len()]);
        }
        let p = self.p_of_z(z);
        let values = self.values_at(&p)?;
        let seeds: Vec<usize> = self.fitted.iter().map(|f| f.index).collect();
        let mut columns: Vec<Result<Vec<f64>, String>> = vec![Ok(Vec::new()); z.len()];
        let mut append = |parts: Vec<Result<Vec<f64>, String>>| {
            for (column, part) in columns.iter_mut().zip(parts) {
                if let Ok(c) = column {
                    match part {
                        Ok(part) => c.extend(part),
                        Err(e) => *column = Err(e),
                    }
                }
            }
        };
        if !self.frfs.is_empty() || !self.peaks.is_empty() {
            append(self.linear_columns(z, &values, &seeds)?);
        }
        for d in &self.series {
            append(self.series_columns(d, z, &values)?);
        }
        Ok(columns
            .into_iter()
            .map(|c| c.map(DVector::from_vec))
            .collect())
    }

    /// The time series `d`'s part of the exact columns at `z` (`values` the configuration
    /// there): the forward sensitivities of its simulation along each fitted parameter
    /// ([`simulate_with_sensitivities`]), relative to each output's RMS.
    fn series_columns(
        &self,
        d: &Series,
        z: &[f64],
        values: &Values,
    ) -> Result<Vec<Result<Vec<f64>, String>>, String> {
        if self.series_sensitivities == SeriesSensitivities::Central {
            let why = "time series: central differences of the simulation (forward \
                       sensitivities with --series-sensitivities forward)";
            return Ok(vec![Err(why.to_string()); z.len()]);
        }
        let directions: Vec<Direction> = self
            .fitted
            .iter()
            .zip(z)
            .map(|(f, &z)| Direction {
                seed: f.index,
                scale: f.dp_dz(z),
            })
            .collect();
        let run = d
            .with_drive(|drive| simulate_with_sensitivities(values, drive, &directions))
            .map_err(|e| format!("--series {}: {e}", d.file))?;
        Ok(run
            .derivatives
            .into_iter()
            .map(|dy| {
                let dy = dy?;
                self.derivatives.fetch_add(1, Ordering::Relaxed);
                Ok(d.outputs
                    .iter()
                    .zip(&dy)
                    .flat_map(|((.., rms), dy)| dy.iter().map(move |v| v / rms))
                    .collect())
            })
            .collect())
    }

    /// The frequency responses' and peaks' part of the exact columns at `z` (`values` the
    /// configuration there, `seeds` the fitted parameters): from the derivatives of the
    /// linearisation at rest.
    fn linear_columns(
        &self,
        z: &[f64],
        values: &Values,
        seeds: &[usize],
    ) -> Result<Vec<Result<Vec<f64>, String>>, String> {
        // Without any exact derivative, the linearisation would be computed for nothing.
        let seeded = seeded_at_rest(values, seeds);
        if seeded.iter().all(Result::is_err) {
            return Ok(seeded.into_iter().map(|s| s.map(|_| Vec::new())).collect());
        }
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        let (lin, derivatives) = linearization_at_rest_of(values, seeded)?;
        let p = self.p_of_z(z);
        let kept = match &*self.last_peaks.lock().unwrap() {
            Some((at, peaks)) if *at == bits(&p) => Some(peaks.clone()),
            _ => None,
        };
        let model_peaks: Vec<Vec<f64>> = match kept {
            Some(peaks) => peaks,
            None => self
                .peaks
                .iter()
                .map(|d| d.model(&lin))
                .collect::<Result<_, _>>()?,
        };
        // One LU per input and frequency, shared by the outputs measured there and by the
        // parameters.
        let mut states: HashMap<(usize, u64), StateResponseLu> = HashMap::new();
        for (data, &(i, _)) in self.frfs.iter().zip(&self.ports) {
            for &f in &data.f_hz {
                if let std::collections::hash_map::Entry::Vacant(e) = states.entry((i, f.to_bits()))
                {
                    e.insert(StateResponseLu::new(&lin, i, f)?);
                }
            }
        }
        let mut columns = Vec::with_capacity(z.len());
        for (j, d) in derivatives.iter().enumerate() {
            let d = match d {
                Ok(d) => d,
                Err(e) => {
                    columns.push(Err(e.clone()));
                    continue;
                }
            };
            self.derivatives.fetch_add(1, Ordering::Relaxed);
            let dp_dz = self.fitted[j].dp_dz(z[j]);
            columns.push(self.exact_column(&lin, d, dp_dz, &states, &model_peaks));
        }
        Ok(columns)
    }

    /// The exact column of `d residuals / d z` from the derivative `d` of the linearisation
    /// `lin` along a parameter, `dp_dz` its coordinate's scale, `states` the states' responses
    /// with their LUs by input and frequency, `model_peaks` the model's peaks taken for the
    /// measured ones: an error (central differences then) where a peak cannot be followed.
    fn exact_column(
        &self,
        lin: &Linearization,
        d: &LinearizationDerivative,
        dp_dz: f64,
        states: &HashMap<(usize, u64), StateResponseLu>,
        model_peaks: &[Vec<f64>],
    ) -> Result<Vec<f64>, String> {
        let mut column = Vec::with_capacity(self.len());
        // One derivative per input and frequency, shared by the outputs measured there.
        let mut derivatives: HashMap<(usize, u64), DVector<Complex<f64>>> = HashMap::new();
        for (data, &(i, o)) in self.frfs.iter().zip(&self.ports) {
            for ((&f, h), &w) in data.f_hz.iter().zip(&data.h).zip(&data.weight) {
                let key = (i, f.to_bits());
                let state = &states[&key];
                let dx = match derivatives.entry(key) {
                    std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                    std::collections::hash_map::Entry::Vacant(e) => e.insert(state.derivative(d)?),
                };
                let dh = output_derivative_of(lin, d, &state.x, dx, i, o);
                let de = dh * (w * dp_dz / h.norm());
                column.push(de.re);
                column.push(de.im);
            }
        }
        // A peak's residual (f_model - f_measured) / sigma moves with its frequency.
        for ((data, &(i, o)), model) in self.peaks.iter().zip(&self.peak_ports).zip(model_peaks) {
            for (&f, sigma) in model.iter().zip(&data.sigma_hz) {
                column.push(peak_derivative(lin, d, i, o, f)? * dp_dz / sigma);
            }
        }
        Ok(column)
    }

    /// The column `j` of `d residuals / d z` at `z` by central differences (module doc).
    fn central_difference(&self, z: &[f64], j: usize) -> Result<DVector<f64>, String> {
        let at = |dz: f64| {
            let mut zz = z.to_vec();
            zz[j] += dz;
            self.residuals_z(&zz).map_err(|e| {
                format!(
                    "the sensitivity to {} at {}: {e}",
                    self.fitted[j].name,
                    self.fitted[j].p_of(zz[j])
                )
            })
        };
        Ok((at(STEP)? - at(-STEP)?) / (2.0 * STEP))
    }
}

/// The model's peaks at parameters given by their bits ([`bits`]).
type KeptPeaks = (Vec<u64>, Vec<Vec<f64>>);

/// The bits of the parameters `p`: the key of what was computed at them.
fn bits(p: &[f64]) -> Vec<u64> {
    p.iter().map(|v| v.to_bits()).collect()
}

/// The weighted relative error `e_k = w_k (H_model - H_measured) / |H_measured|` of one point
/// (module doc).
fn error(model: Complex<f64>, data: Complex<f64>, w: f64) -> Complex<f64> {
    (model - data) * (w / data.norm())
}

/// The linearisation at rest of the configuration `values`.
fn linearization(values: &Values) -> Result<Linearization, String> {
    crate::linearization_at_rest(&Parameters::from_values(values, &Experiment::default())?)
}
