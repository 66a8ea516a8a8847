//! A measured time series as a fit's target (`--series FILE.csv`): a column `time` \[s\] and
//! columns named after the FMU's inputs, which drive the model, and its outputs, which are
//! fitted.
//!
//! The model is the FMU's own co-simulation (`HydraulicSlewingPlate` through the `FmuModel`
//! trait, its solver and tolerances from the configuration, [`simulate`]): initialised at the first time
//! with the first row's inputs, then stepped from row to row with each row's inputs held to the
//! next (zero-order hold, as an importer sets inputs at its communication points), the outputs
//! read at every row. The residual of output `o` at row `k` is
//!
//! ```text
//! e_ok = (y_model,ok - y_measured,ok) / s_o,
//! ```
//!
//! `s_o` the RMS of the measured column, so that outputs in different units weigh alike and a
//! 1 % error of a signal's size counts the same in each.

use hydraulic_slewing_plate::fmu::{Causality, Values};
use hydraulic_slewing_plate::model::sensitivity::series::{simulate, Drive};
use hydraulic_slewing_plate::model::variables::VARIABLES;

use super::data::Measured;

/// A measured time series: the times, the inputs that drive the model and the outputs fitted.
#[derive(Clone, Debug)]
pub struct Series {
    /// The file, as given.
    pub file: String,
    pub time: Vec<f64>,
    /// `(variable index, name, values)` of each input column.
    pub inputs: Vec<(usize, String, Vec<f64>)>,
    /// `(variable index, name, values, RMS)` of each output column.
    pub outputs: Vec<(usize, String, Vec<f64>, f64)>,
}

impl Series {
    /// Reads `FILE.csv`: a header with `time` and names of the FMU's inputs and outputs, then
    /// one row per time, the times strictly increasing, every value finite, at least one output
    /// and each output's RMS nonzero; an error names the file and the column or row.
    pub fn read(file: &str) -> Result<Series, String> {
        let m = Measured::read_file(file)?;
        let expected = "time and the FMU's inputs and outputs";
        let time = m.column("time", expected)?.to_vec();
        if time.len() < 2 {
            return Err(format!("{file}: fewer than two data rows"));
        }
        for k in 0..time.len() {
            let ok = time[k].is_finite() && (k == 0 || time[k] > time[k - 1]);
            if !ok {
                return Err(format!(
                    "{file}: data row {}: time {} is not finite and after the previous row's",
                    k + 1,
                    time[k]
                ));
            }
        }
        let (mut inputs, mut outputs) = (Vec::new(), Vec::new());
        for (name, values) in m.table.names.iter().zip(&m.table.columns) {
            if name == "time" {
                continue;
            }
            let index = VARIABLES.iter().position(|v| v.name == name);
            let causality = index.map(|i| VARIABLES[i].causality);
            if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                return Err(format!("{file}: data row {}: {name} is not finite", k + 1));
            }
            match (index, causality) {
                (Some(i), Some(Causality::Input)) => inputs.push((i, name.clone(), values.clone())),
                (Some(i), Some(Causality::Output)) => {
                    let rms =
                        (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt();
                    if rms == 0.0 {
                        return Err(format!(
                            "{file}: the output {name} is zero throughout (its residuals are \
                             relative to its RMS)"
                        ));
                    }
                    outputs.push((i, name.clone(), values.clone(), rms));
                }
                _ => {
                    return Err(format!(
                        "{file}: column '{name}' is neither an input nor an output of the FMU"
                    ))
                }
            }
        }
        if outputs.is_empty() {
            return Err(format!("{file}: no output column to fit"));
        }
        Ok(Series {
            file: file.to_string(),
            time,
            inputs,
            outputs,
        })
    }

    /// The number of residuals.
    pub fn len(&self) -> usize {
        self.time.len() * self.outputs.len()
    }

    /// The model's outputs in the configuration `values` driven by the inputs, one vector per
    /// output column (module doc).
    pub fn simulate(&self, values: &Values) -> Result<Vec<Vec<f64>>, String> {
        self.with_drive(|drive| simulate(values, drive))
            .map_err(|e| format!("--series {}: {e}", self.file))
    }

    /// `f` of the series as the library's [`Drive`]: its times, inputs and outputs.
    pub fn with_drive<R>(&self, f: impl FnOnce(Drive) -> R) -> R {
        let inputs: Vec<(usize, &[f64])> = self
            .inputs
            .iter()
            .map(|(i, _, u)| (*i, u.as_slice()))
            .collect();
        let outputs: Vec<usize> = self.outputs.iter().map(|(i, ..)| *i).collect();
        f(Drive {
            time: &self.time,
            inputs: &inputs,
            outputs: &outputs,
        })
    }

    /// The residuals of the model's outputs `model` ([`Series::simulate`]) (module doc).
    pub fn residuals(&self, model: &[Vec<f64>], r: &mut Vec<f64>) {
        for ((_, _, data, rms), m) in self.outputs.iter().zip(model) {
            r.extend(m.iter().zip(data).map(|(m, d)| (m - d) / rms));
        }
    }
}
