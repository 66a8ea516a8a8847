//! The linearisation `A, B, C, D` of the compiled model at an operating point, exact: dual
//! numbers through the full plan, one pass per state and per input (outputs included, so not
//! the coloured derivative plan the Jacobian uses). Used for frequency responses, the exact
//! discretisation (`discretisation.rs`), `hsp linearize` and the FMU benchmark, which write it
//! with [`Linearization::to_json`], the one JSON layout of a linearisation.

use nalgebra::DMatrix;

use super::compiled::CompiledModel;

/// Linearisation `dx = A dx + B du`, `dy = C dx + D du` at an operating point.
#[derive(Clone, Debug)]
pub struct Linearization {
    /// `df/dx`, n x n.
    pub a: DMatrix<f64>,
    /// `df/du`, n x m.
    pub b: DMatrix<f64>,
    /// `dy/dx`, p x n.
    pub c: DMatrix<f64>,
    /// `dy/du`, p x m.
    pub d: DMatrix<f64>,
    /// State names (rows of A).
    pub state_names: Vec<String>,
    /// Input names (columns of B, D).
    pub input_names: Vec<String>,
    /// Output names (rows of C, D).
    pub output_names: Vec<String>,
    /// Operating point: states.
    pub x0: Vec<f64>,
    /// Operating point: inputs.
    pub u0: Vec<f64>,
}

/// A matrix as a JSON array of rows.
fn matrix_json(m: &DMatrix<f64>) -> serde_json::Value {
    serde_json::Value::Array(
        (0..m.nrows())
            .map(|i| serde_json::json!((0..m.ncols()).map(|j| m[(i, j)]).collect::<Vec<_>>()))
            .collect(),
    )
}

impl Linearization {
    /// The JSON layout of a linearisation, `{"states", "inputs", "outputs", "x0", "u0", "A",
    /// "B", "C", "D"}`: the names of the states, inputs and outputs, the operating point and the
    /// matrices as arrays of rows. `hsp linearize` prints it; `bench/scipy_reference.py --linear`
    /// reads it (with fields the benchmark adds).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "states": self.state_names,
            "inputs": self.input_names,
            "outputs": self.output_names,
            "x0": self.x0,
            "u0": self.u0,
            "A": matrix_json(&self.a),
            "B": matrix_json(&self.b),
            "C": matrix_json(&self.c),
            "D": matrix_json(&self.d),
        })
    }
}

impl CompiledModel {
    /// Exact linearisation at `(x, u)`.
    pub fn linearize(&self, x: &[f64], u: &[f64]) -> Linearization {
        let (n, m, p) = (self.n_states(), self.n_inputs(), self.n_outputs());
        let mut a = DMatrix::zeros(n, n);
        let mut b = DMatrix::zeros(n, m);
        let mut c = DMatrix::zeros(p, n);
        let mut d = DMatrix::zeros(p, m);
        for j in 0..n + m {
            self.with_dual(&self.ops, x, u, &[j as u32], |s| {
                self.copy_column(j, s, |v| v.d, [&mut a, &mut b, &mut c, &mut d])
            });
        }
        Linearization {
            a,
            b,
            c,
            d,
            state_names: self.state_names.clone(),
            input_names: self.input_names.clone(),
            output_names: self.output_names.clone(),
            x0: x.to_vec(),
            u0: u.to_vec(),
        }
    }

    /// Copies the column `j` of a linearisation (state `j` for `j < n`, input `j - n` after)
    /// out of the slots `s` of its pass: `part` of each derivative's slot into `a` (or `b`), of
    /// each output's into `c` (or `d`). [`CompiledModel::linearize`]'s dual passes and the
    /// hyper-dual ones of [`CompiledModel::linearize_with_sensitivity`].
    pub(super) fn copy_column<T: Copy>(
        &self,
        j: usize,
        s: &[T],
        part: impl Fn(T) -> f64,
        [a, b, c, d]: [&mut DMatrix<f64>; 4],
    ) {
        let n = self.n_states();
        let (rows, outputs, column) = if j < n { (a, c, j) } else { (b, d, j - n) };
        for (i, &k) in self.deriv_slots.iter().enumerate() {
            rows[(i, column)] = part(s[k as usize]);
        }
        for (i, &k) in self.output_slots.iter().enumerate() {
            outputs[(i, column)] = part(s[k as usize]);
        }
    }
}
