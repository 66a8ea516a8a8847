//! The reference result of the default experiment, `<model>_out.csv`, as the Modelica Reference
//! FMUs ship theirs (the CSV `fmusim` writes and fmpy's `read_csv` reads): a column `time` and
//! one column per output of the model description, in its order, no inputs; an FMI 3.0 array is
//! one column whose cells hold its elements separated by spaces (`acc` of the FMI 3.0 FMU),
//! where the FMI 2.0 FMU has one column per scalar (`acc[1]` .. `acc[12]`).
//!
//! One run of the packaged FMU (through its FMI 2.0 C ABI, as `hsp run` loads it) records every
//! output; the two FMUs' files are two layouts of that one table. The run is the model
//! description's `<DefaultExperiment>` as an importer reads it: co-simulation from its start to
//! its stop time on its communication grid, the stop time and tolerance passed to
//! `fmi2SetupExperiment`, every parameter at its start value, the inputs left at their start
//! values.

use std::fmt::Write as _;
use std::path::Path;

use hydraulic_slewing_plate::fmu::variables::{Causality, Kind};
use hydraulic_slewing_plate::model::variables::VARIABLES;

use crate::loader::Fmu;
use crate::model_description::{get, ModelDescription};

/// The model description's `<DefaultExperiment>`.
pub struct DefaultExperiment {
    pub start: f64,
    pub stop: f64,
    pub step: f64,
    pub tolerance: f64,
}

impl DefaultExperiment {
    /// Reads it from the model description `xml`; fails on a missing attribute.
    pub fn read(xml: &str) -> Result<Self, String> {
        let md = ModelDescription::parse(xml)?;
        let de = md
            .default_experiment
            .ok_or("the model description has no <DefaultExperiment>")?;
        let number = |name: &str| -> Result<f64, String> {
            get(&de, name)
                .ok_or_else(|| format!("<DefaultExperiment> has no {name}"))?
                .parse::<f64>()
                .map_err(|e| format!("<DefaultExperiment> {name}: {e}"))
        };
        Ok(DefaultExperiment {
            start: number("startTime")?,
            stop: number("stopTime")?,
            step: number("stepSize")?,
            tolerance: number("tolerance")?,
        })
    }

    /// The communication points: `start + k * step`, computed from the index (no drift), the
    /// last one the stop time itself.
    fn grid(&self) -> Result<Vec<f64>, String> {
        let intervals = (self.stop - self.start) / self.step;
        let n = intervals.round();
        if !(n >= 1.0 && (intervals - n).abs() <= 1e-9 * n) {
            return Err(format!(
                "<DefaultExperiment>: {} s to {} s is no whole number of {} s steps",
                self.start, self.stop, self.step
            ));
        }
        let n = n as usize;
        Ok((0..=n)
            .map(|k| {
                if k == n {
                    self.stop
                } else {
                    self.start + k as f64 * self.step
                }
            })
            .collect())
    }
}

/// Every output of the FMU at every communication point of the default experiment.
pub struct Recorded {
    /// The outputs' FMI 2.0 names, in the model description's order.
    names: Vec<String>,
    /// Whether each output is an Integer (written without exponent).
    integer: Vec<bool>,
    /// The communication points \[s\].
    time: Vec<f64>,
    /// One row per communication point, the values in the order of `names` (Integers exact).
    rows: Vec<Vec<f64>>,
}

/// Runs the default experiment of the FMI 2.0 model description `xml` on the FMI 2.0 FMU `fmu`
/// and records every output.
pub fn run_default_experiment(fmu: &Path, xml: &str) -> Result<Recorded, String> {
    let de = DefaultExperiment::read(xml)?;
    let grid = de.grid()?;
    let outputs: Vec<_> = VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .collect();
    let integer: Vec<bool> = outputs
        .iter()
        .map(|v| matches!(v.kind, Kind::Integer { .. }))
        .collect();
    let reals: Vec<u32> = outputs
        .iter()
        .zip(&integer)
        .filter(|(_, i)| !**i)
        .map(|(v, _)| v.value_reference)
        .collect();
    let integers: Vec<u32> = outputs
        .iter()
        .zip(&integer)
        .filter(|(_, i)| **i)
        .map(|(v, _)| v.value_reference)
        .collect();
    let loaded = Fmu::load(fmu)?;
    let inst = loaded.instantiate("hsp-reference-result")?;
    inst.setup(Some(de.tolerance), de.start, de.stop)?;
    inst.enter_initialization()?;
    inst.exit_initialization()?;
    let row = || -> Result<Vec<f64>, String> {
        let (mut r, mut i) = (
            inst.get_reals(&reals)?.into_iter(),
            inst.get_integers(&integers)?.into_iter(),
        );
        Ok(integer
            .iter()
            .map(|is_int| {
                if *is_int {
                    f64::from(i.next().unwrap_or_default())
                } else {
                    r.next().unwrap_or_default()
                }
            })
            .collect())
    };
    let mut rows = vec![row()?];
    for w in grid.windows(2) {
        inst.do_step(w[0], w[1] - w[0])?;
        rows.push(row()?);
    }
    inst.terminate()?;
    Ok(Recorded {
        names: outputs.iter().map(|v| v.name.to_string()).collect(),
        integer,
        time: grid,
        rows,
    })
}

/// A column of the CSV: its header and the recorded outputs it holds (one, or an array's
/// elements in order).
struct Column {
    name: String,
    members: Vec<usize>,
}

impl Recorded {
    /// The FMI 2.0 FMU's file: one column per output.
    pub fn fmi2_csv(&self) -> String {
        let columns: Vec<Column> = self
            .names
            .iter()
            .enumerate()
            .map(|(k, n)| Column {
                name: n.clone(),
                members: vec![k],
            })
            .collect();
        self.csv(&columns)
    }

    /// The FMI 3.0 FMU's file: one column per output of the FMI 3.0 model description `xml3`,
    /// an array's column holding its elements (the FMI 2.0 scalars `name[1]` .. `name[n]`).
    /// Fails unless the columns hold every recorded output exactly once.
    pub fn fmi3_csv(&self, xml3: &str) -> Result<String, String> {
        let doc = roxmltree::Document::parse(xml3).map_err(|e| format!("FMI 3.0 XML: {e}"))?;
        let vars = super::fmi3_model_variables(&doc)?;
        let index = |name: &str| -> Result<usize, String> {
            self.names
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| format!("FMI 3.0 output {name} is no FMI 2.0 output"))
        };
        let mut columns = Vec::new();
        for v in vars
            .children()
            .filter(|n| n.attribute("causality") == Some("output"))
        {
            let name = v.attribute("name").unwrap_or_default();
            let dimensions: Vec<_> = v
                .children()
                .filter(|n| n.has_tag_name("Dimension"))
                .collect();
            let members = match dimensions.as_slice() {
                [] => vec![index(name)?],
                [d] => {
                    let n: usize = d
                        .attribute("start")
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| format!("FMI 3.0 output {name}: no fixed <Dimension>"))?;
                    (1..=n)
                        .map(|k| index(&format!("{name}[{k}]")))
                        .collect::<Result<_, _>>()?
                }
                _ => return Err(format!("FMI 3.0 output {name}: more than one <Dimension>")),
            };
            columns.push(Column {
                name: name.to_string(),
                members,
            });
        }
        let mut held: Vec<usize> = columns.iter().flat_map(|c| c.members.clone()).collect();
        held.sort_unstable();
        if held != (0..self.names.len()).collect::<Vec<_>>() {
            return Err("the FMI 3.0 outputs do not hold the FMI 2.0 outputs once each".into());
        }
        Ok(self.csv(&columns))
    }

    fn csv(&self, columns: &[Column]) -> String {
        let mut csv = String::from("time");
        for c in columns {
            write!(csv, ",{}", c.name).unwrap();
        }
        csv.push('\n');
        for (t, row) in self.time.iter().zip(&self.rows) {
            write!(csv, "{t}").unwrap();
            for c in columns {
                csv.push(',');
                for (j, &k) in c.members.iter().enumerate() {
                    if j > 0 {
                        csv.push(' ');
                    }
                    if self.integer[k] {
                        write!(csv, "{}", row[k] as i64).unwrap();
                    } else {
                        write!(csv, "{:e}", row[k]).unwrap();
                    }
                }
            }
            csv.push('\n');
        }
        csv
    }
}
