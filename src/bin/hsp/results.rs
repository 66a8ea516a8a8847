//! The results of a run: a table of named time series (one row per communication point), written
//! as CSV and handed as it is to the summary and to plotters.

use std::fmt::Write as _;
use std::path::Path;

/// Named time series sampled at the communication points.
#[derive(Clone, Debug, Default)]
pub struct Results {
    /// Column names (FMU variable names), in CSV order; time is not one of them.
    pub names: Vec<String>,
    /// Communication points \[s\].
    pub time: Vec<f64>,
    /// One row per communication point, values in the order of `names` (SI units).
    pub rows: Vec<Vec<f64>>,
}

impl Results {
    pub fn new(names: Vec<String>) -> Self {
        Results {
            names,
            ..Self::default()
        }
    }

    pub fn push(&mut self, t: f64, row: Vec<f64>) {
        debug_assert_eq!(row.len(), self.names.len());
        self.time.push(t);
        self.rows.push(row);
    }

    /// The time series of a column, if recorded.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.names.iter().position(|n| n == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }

    /// The CSV text: a header `time,<names>` and one line per row.
    pub fn to_csv(&self) -> String {
        let mut csv = String::from("time");
        for name in &self.names {
            write!(csv, ",{name}").unwrap();
        }
        csv.push('\n');
        for (t, row) in self.time.iter().zip(&self.rows) {
            write!(csv, "{t}").unwrap();
            for v in row {
                write!(csv, ",{v:e}").unwrap();
            }
            csv.push('\n');
        }
        csv
    }

    /// Writes the CSV, creating the folder.
    pub fn write_csv(&self, path: &Path) -> Result<(), String> {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        std::fs::write(path, self.to_csv()).map_err(|e| format!("{}: {e}", path.display()))
    }
}
