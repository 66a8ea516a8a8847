//! What `hsp identify` reads: the measured frequency responses (`--frf INPUT:OUTPUT:FILE.csv`)
//! and the parameters to fit (`--fit NAME[:LOW:HIGH]`), each with the coordinates the fit works
//! in.

use std::path::Path;

use hydraulic_slewing_plate::fmu::{Causality, Kind, Value, Values};
use hydraulic_slewing_plate::fragments::rules;
use hydraulic_slewing_plate::model::variables::VARIABLES;
use nalgebra::Complex;

use crate::plot::Table;

/// A measurement given as `INPUT:OUTPUT:FILE.csv`: the names and the file's table.
pub struct Measured {
    pub input: String,
    pub output: String,
    /// The file, as given.
    pub file: String,
    pub table: Table,
}

impl Measured {
    /// Parses `spec`, given to the option `flag`, and reads the file's table.
    pub fn read(flag: &str, spec: &str) -> Result<Measured, String> {
        let mut parts = spec.splitn(3, ':');
        let (Some(input), Some(output), Some(file)) = (parts.next(), parts.next(), parts.next())
        else {
            return Err(format!("{flag} '{spec}': expected INPUT:OUTPUT:FILE.csv"));
        };
        Ok(Measured {
            input: input.to_string(),
            output: output.to_string(),
            ..Measured::read_file(file)?
        })
    }

    /// Reads `file`'s table, with no input and output named (a time series names them in its
    /// columns).
    pub fn read_file(file: &str) -> Result<Measured, String> {
        Ok(Measured {
            input: String::new(),
            output: String::new(),
            file: file.to_string(),
            table: Table::read_csv(Path::new(file))?,
        })
    }

    /// The column `name`, or an error naming the file, its header and the `expected` columns.
    pub fn column(&self, name: &str, expected: &str) -> Result<&[f64], String> {
        self.table.column(name).ok_or_else(|| {
            format!(
                "{}: no column '{name}' (the header has {:?}; expected {expected})",
                self.file, self.table.names
            )
        })
    }
}

/// One measured frequency response: the complex response of `output` to `input` (SI units) at
/// the frequencies `f_hz`, each point with its weight (1 where the file has no `weight` column).
#[derive(Clone, Debug)]
pub struct Frf {
    pub input: String,
    pub output: String,
    /// The file it was read from, as given.
    pub file: String,
    pub f_hz: Vec<f64>,
    pub h: Vec<Complex<f64>>,
    pub weight: Vec<f64>,
}

impl Frf {
    /// Parses `INPUT:OUTPUT:FILE.csv` and reads the file: a header naming `f_Hz`, `re`, `im`
    /// and optionally `weight`, in any order, then one row per frequency. Every number must be
    /// finite, every frequency positive, every weight non-negative and every measured response
    /// nonzero (the residual is relative to it); an error names the file, the data row and the
    /// value.
    pub fn read(spec: &str) -> Result<Frf, String> {
        let m = Measured::read("--frf", spec)?;
        let expected = "f_Hz,re,im and optionally weight";
        let (input, output, file, table) = (&m.input, &m.output, &m.file, &m.table);
        let column = |name: &str| m.column(name, expected);
        let (f_hz, re, im) = (column("f_Hz")?, column("re")?, column("im")?);
        let weight = match table.column("weight") {
            Some(w) => w.to_vec(),
            None => vec![1.0; f_hz.len()],
        };
        if f_hz.is_empty() {
            return Err(format!("{file}: no data rows"));
        }
        let mut h = Vec::with_capacity(f_hz.len());
        for k in 0..f_hz.len() {
            let row = k + 1;
            let z = Complex::new(re[k], im[k]);
            if !(f_hz[k].is_finite() && f_hz[k] > 0.0) {
                return Err(format!(
                    "{file}: data row {row}: f_Hz = {} is not a positive frequency",
                    f_hz[k]
                ));
            }
            if !(z.re.is_finite() && z.im.is_finite()) || z.norm() == 0.0 {
                return Err(format!(
                    "{file}: data row {row}: the response {} + {} j is not finite and nonzero (the \
                     residual is relative to it)",
                    z.re, z.im
                ));
            }
            if !(weight[k].is_finite() && weight[k] >= 0.0) {
                return Err(format!(
                    "{file}: data row {row}: weight {} is not a finite non-negative number",
                    weight[k]
                ));
            }
            h.push(z);
        }
        Ok(Frf {
            input: input.to_string(),
            output: output.to_string(),
            file: file.to_string(),
            f_hz: f_hz.to_vec(),
            h,
            weight,
        })
    }
}

/// How a fitted parameter `p` maps to the coordinate `z` in which its sensitivities, its
/// covariance and its interval are computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    /// `z = ln p`: a parameter that is positive (its start and its lower bound, if any, > 0).
    Log,
    /// `z = p / s`: any other, scaled by `s` (`|start|`, or the width of its bounds if it starts
    /// at 0, or 1).
    Linear(f64),
}

/// A parameter to fit: `--fit NAME[:LOW:HIGH]`.
#[derive(Clone, Debug)]
pub struct Fitted {
    pub name: String,
    /// Its index among the FMU's variables.
    pub index: usize,
    /// Its value in the starting configuration.
    pub start: f64,
    /// The box `[LOW, HIGH]`, if given.
    pub bounds: Option<(f64, f64)>,
    pub scale: Scale,
}

impl Fitted {
    /// Parses `NAME[:LOW:HIGH]` against the starting configuration `values`: NAME must be a
    /// Real parameter of the FMU, LOW < start < HIGH, and a parameter of the model
    /// description's `<Positive>` list needs LOW > 0.
    pub fn parse(spec: &str, values: &Values) -> Result<Fitted, String> {
        let fields: Vec<&str> = spec.split(':').collect();
        let name = fields[0].trim();
        let index = VARIABLES
            .iter()
            .position(|v| v.name == name)
            .ok_or_else(|| format!("--fit '{spec}': '{name}' is not a variable of the FMU"))?;
        let var = &VARIABLES[index];
        if var.causality != Causality::Parameter || !matches!(var.kind, Kind::Real { .. }) {
            return Err(format!(
                "--fit '{spec}': '{name}' is not a Real parameter of the FMU"
            ));
        }
        let Value::Real(start) = *values.get(index) else {
            unreachable!("a Real variable holds a Real value")
        };
        let number = |s: &str| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("--fit '{spec}': '{s}' is not a finite number"))
        };
        let bounds = match fields.len() {
            1 => None,
            3 => Some((number(fields[1])?, number(fields[2])?)),
            _ => return Err(format!("--fit '{spec}': expected NAME or NAME:LOW:HIGH")),
        };
        if let Some((lo, hi)) = bounds {
            if !(lo < start && start < hi) {
                return Err(format!(
                    "--fit '{spec}': the start value {start} of {name} must lie strictly \
                     between LOW and HIGH"
                ));
            }
            if rules::rule(name).is_some_and(|r| r.positive) && lo <= 0.0 {
                return Err(format!(
                    "--fit '{spec}': {name} is positive; LOW must be > 0"
                ));
            }
        }
        let positive = start > 0.0 && bounds.is_none_or(|(lo, _)| lo > 0.0);
        let scale = if positive {
            Scale::Log
        } else if start != 0.0 {
            Scale::Linear(start.abs())
        } else {
            Scale::Linear(bounds.map_or(1.0, |(lo, hi)| hi - lo))
        };
        Ok(Fitted {
            name: name.to_string(),
            index,
            start,
            bounds,
            scale,
        })
    }

    /// `z` of the value `p`.
    pub fn z_of(&self, p: f64) -> f64 {
        match self.scale {
            Scale::Log => p.ln(),
            Scale::Linear(s) => p / s,
        }
    }

    /// The value of `z`: the start value itself, bit for bit, at the start's `z` (`exp(ln p)`
    /// may differ from `p` in its last bit; a parameter the fit leaves alone stays as given).
    pub fn p_of(&self, z: f64) -> f64 {
        if z == self.z_of(self.start) {
            return self.start;
        }
        match self.scale {
            Scale::Log => z.exp(),
            Scale::Linear(s) => z * s,
        }
    }

    /// `dp/dz` at `z`: `p` for a log-scaled parameter, its scale for a linear one.
    pub fn dp_dz(&self, z: f64) -> f64 {
        match self.scale {
            Scale::Log => self.p_of(z),
            Scale::Linear(s) => s,
        }
    }

    /// The bounds in `z`.
    pub fn z_bounds(&self) -> Option<(f64, f64)> {
        self.bounds.map(|(lo, hi)| (self.z_of(lo), self.z_of(hi)))
    }

    /// `z` of the optimiser's unconstrained coordinate `t`: `z = t` without bounds, else the
    /// logistic map of `t` onto `(z_lo, z_hi)`, `z = z_lo + (z_hi - z_lo) / (1 + e^-t)`.
    pub fn z_of_t(&self, t: f64) -> f64 {
        match self.z_bounds() {
            None => t,
            Some((lo, hi)) => lo + (hi - lo) / (1.0 + (-t).exp()),
        }
    }

    /// `t` of `z` (the inverse of [`Fitted::z_of_t`], the logit on `(z_lo, z_hi)`).
    pub fn t_of_z(&self, z: f64) -> f64 {
        match self.z_bounds() {
            None => z,
            Some((lo, hi)) => {
                let u = (z - lo) / (hi - lo);
                (u / (1.0 - u)).ln()
            }
        }
    }

    /// `dz/dt` at `t`.
    pub fn dz_dt(&self, t: f64) -> f64 {
        match self.z_bounds() {
            None => 1.0,
            Some((lo, hi)) => {
                let s = 1.0 / (1.0 + (-t).exp());
                (hi - lo) * s * (1.0 - s)
            }
        }
    }

    /// Whether `p` is within 1e-4 of the box's width (in `z`) of a bound: the optimum is then on
    /// it, and its interval, from the curvature there, does not describe it (the logistic map
    /// approaches a bound only as `t` runs off, so an optimum beyond the box ends close to its
    /// edge, not on it).
    pub fn at_bound(&self, p: f64) -> bool {
        self.z_bounds().is_some_and(|(lo, hi)| {
            let z = self.z_of(p);
            (z - lo).min(hi - z) < 1e-4 * (hi - lo)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start() -> Values {
        Values::from_start(&VARIABLES)
    }

    #[test]
    fn a_positive_parameter_is_log_scaled_and_its_bounds_map_back_and_forth() {
        let f = Fitted::parse("torsion_bar.k:100:1e5", &start()).unwrap();
        assert_eq!(f.scale, Scale::Log);
        for p in [150.0, f.start, 9e4] {
            let t = f.t_of_z(f.z_of(p));
            assert!((f.p_of(f.z_of_t(t)) / p - 1.0).abs() < 1e-13, "{p}");
            // dz/dt against the logistic's closed form (z - z_lo) (z_hi - z) / (z_hi - z_lo)
            let (lo, hi, z) = (100f64.ln(), 1e5f64.ln(), p.ln());
            let d = (z - lo) * (hi - z) / (hi - lo);
            assert!(
                (f.dz_dt(t) / d - 1.0).abs() < 1e-12,
                "{p}: {} against {d}",
                f.dz_dt(t)
            );
        }
    }

    #[test]
    fn a_bad_fit_names_the_culprit() {
        let e = Fitted::parse("torsion_bar.kk", &start()).unwrap_err();
        assert!(e.contains("'torsion_bar.kk' is not a variable"), "{e}");
        let e = Fitted::parse("y_pot", &start()).unwrap_err();
        assert!(e.contains("not a Real parameter"), "{e}");
        let e = Fitted::parse("torsion_bar.k:1:2", &start()).unwrap_err();
        assert!(e.contains("strictly between LOW and HIGH"), "{e}");
        let e = Fitted::parse("torsion_bar.k:1", &start()).unwrap_err();
        assert!(e.contains("NAME:LOW:HIGH"), "{e}");
    }
}
