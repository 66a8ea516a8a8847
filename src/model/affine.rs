//! The model's right-hand side and outputs as sparse products where they are affine in x.
//!
//! The analysis of the compiled plan (`bond_graph::structure`) tells which rows of
//! `dx/dt = f(x, u)` and which outputs are affine in x with coefficients that depend on neither
//! x nor u: every one of them for the LOES with the plate (a linear model), all but the servo
//! valve's with the full valve. For those, `f_i(x, u) = J_i x + f_i(0, u)` and
//! `y_k = C_k x + y_k(0, u)` exactly; J is 1–5 % dense and C has a few dense rows (the
//! accelerometers sum over every mode), so the products cost a fraction of a pass through the
//! plan. [`Affine`] holds them; [`super::assembly::Assembled`] uses it for `f` at every stage
//! of the integrator and for the outputs at the communication points.

use nalgebra::DMatrix;

use crate::bond_graph::{
    AffineOffsets, CompiledModel, FormsJacobian, Linearization, NonaffineForms, PointForms,
};
use crate::math::lanes::{self, Lanes, Run, Summation};

/// A sparse matrix by rows: row `i`'s nonzeros are `entries[row_start[i]..row_start[i + 1]]`,
/// as (column, value).
#[derive(Clone, Debug)]
pub(super) struct SparseRows {
    row_start: Vec<usize>,
    entries: Vec<(u32, f64)>,
    /// Runs of consecutive rows of one length (the plate's modes that the drag does not reach
    /// read the same momenta), whose products [`SparseRows::times`] computes four rows at a
    /// time ([`lanes`]).
    runs: Vec<Run>,
    lanes: Lanes,
}

/// Rows shorter than this are multiplied alone: too few terms for the lanes' set-up to pay.
const LANE_TERMS: usize = 4;

impl SparseRows {
    /// The nonzeros of `m`'s rows `i` for which `keep(i)`; the other rows are left empty.
    pub(super) fn from_dense(m: &DMatrix<f64>, keep: impl Fn(usize) -> bool) -> Self {
        let mut row_start = vec![0];
        let mut entries = Vec::new();
        for i in 0..m.nrows() {
            if keep(i) {
                let nonzeros = (0..m.ncols()).filter(|&j| m[(i, j)] != 0.0);
                entries.extend(nonzeros.map(|j| (j as u32, m[(i, j)])));
            }
            row_start.push(entries.len());
        }
        let rows = |range: std::ops::Range<usize>| {
            range
                .map(|i| &entries[row_start[i]..row_start[i + 1]])
                .collect::<Vec<_>>()
        };
        let lengths: Vec<usize> = rows(0..m.nrows()).iter().map(|r| r.len()).collect();
        let mut lanes = Lanes::default();
        let runs = lanes::equal_lengths(&lengths, LANE_TERMS)
            .into_iter()
            .map(|range| lanes.add(range.start, &rows(range), Summation::Fold))
            .collect();
        SparseRows {
            row_start,
            entries,
            runs,
            lanes,
        }
    }

    /// `offset_i + (row i) x` into `out[i]` for every row, the same bits as
    /// [`SparseRows::row_times`] row by row.
    pub(super) fn times(&self, x: &[f64], offset: &[f64], out: &mut [f64]) {
        let mut i = 0;
        for run in &self.runs {
            for i in i..run.forms().start {
                out[i] = self.row_times(i, x, offset[i]);
            }
            self.lanes
                .each_value(x, run, |i| offset[i], |i, v| out[i] = v);
            i = run.forms().end;
        }
        for i in i..out.len() {
            out[i] = self.row_times(i, x, offset[i]);
        }
    }

    /// The largest Σ_j |m_ij| over the rows.
    fn max_abs_row_sum(&self) -> f64 {
        self.row_start
            .windows(2)
            .map(|r| self.entries[r[0]..r[1]].iter().map(|(_, a)| a.abs()).sum())
            .fold(0.0, f64::max)
    }

    /// `offset_i + (row i) x`.
    #[inline]
    pub(super) fn row_times(&self, i: usize, x: &[f64], offset: f64) -> f64 {
        Summation::Fold.sum(
            x,
            offset,
            &self.entries[self.row_start[i]..self.row_start[i + 1]],
        )
    }
}

/// `C x` four outputs at a time, for a C whose rows are partly dense (the accelerometers sum over
/// every mode, most other outputs read one or two states): for each block of four consecutive
/// outputs, the columns where one of the four has a non-zero entry, with the four entries. The
/// four sums stay in registers across the columns instead of going through memory at each, and
/// the columns no output of a block reads are skipped.
#[derive(Clone, Debug)]
pub(super) struct BlockRows {
    rows: usize,
    /// Block `b`'s columns are `entries[block_start[b]..block_start[b + 1]]`.
    block_start: Vec<usize>,
    entries: Vec<(u32, [f64; 4])>,
}

impl BlockRows {
    pub(super) fn from_dense(c: &DMatrix<f64>) -> Self {
        let (rows, cols) = c.shape();
        let mut block_start = vec![0];
        let mut entries = Vec::new();
        for first in (0..rows).step_by(4) {
            let entry = |k: usize, j: usize| if k < rows { c[(k, j)] } else { 0.0 };
            for j in 0..cols {
                let four = [0, 1, 2, 3].map(|d| entry(first + d, j));
                if four.iter().any(|&v| v != 0.0) {
                    entries.push((j as u32, four));
                }
            }
            block_start.push(entries.len());
        }
        BlockRows {
            rows,
            block_start,
            entries,
        }
    }

    /// `y = y0 + C x`; each output's sum runs over its columns in ascending order.
    pub(super) fn product(&self, x: &[f64], y0: &[f64], y: &mut [f64]) {
        for (b, range) in self.block_start.windows(2).enumerate() {
            let first = 4 * b;
            let mut acc = [0, 1, 2, 3].map(|d| y0.get(first + d).copied().unwrap_or(0.0));
            for &(j, c) in &self.entries[range[0]..range[1]] {
                let xj = x[j as usize];
                for d in 0..4 {
                    acc[d] += c[d] * xj;
                }
            }
            let last = (first + 4).min(self.rows);
            y[first..last].copy_from_slice(&acc[..last - first]);
        }
    }
}

/// The most outputs [`Affine`] evaluates as `C x + y(0, u)` (on the stack, so that a
/// communication point allocates nothing); the model has 23 to 31.
pub(super) const MAX_AFFINE_OUTPUTS: usize = 64;

/// `dx_i/dt = J_i x + f_i(0, u)` for the rows `i` of `f` that are affine in x (every row of the
/// LOES with the plate, whose Jacobian J is constant; all but the servo valve's 7 and, with the
/// air drag, the plate's modes with the full valve), the other rows as forms over the states,
/// inputs and the results of the nonlinear operations they need ([`NonaffineForms`]); likewise `y_k = C_k x +
/// y_k(0, u)` for the outputs that are affine, the others through the plan.
///
/// An affine row has coefficients `J_i` that depend on neither x nor u (they are among the
/// Jacobian's constant entries), so the identity is exact; only the rounding differs from the
/// plan's. J is 1–5 % dense (the plate's modes meet only at the hub and the torsion bar), so
/// the product over its nonzeros costs a fraction of a pass through the plan, which also
/// evaluates every bond variable on the way. The offsets `f(0, u)` and `y(0, u)` are evaluated
/// whenever the held inputs change, as forms over the inputs and the nonlinear results they
/// need ([`AffineOffsets`]: the plan's values to rounding).
#[derive(Clone, Debug)]
pub(super) struct Affine {
    /// The affine rows of J (the other rows empty).
    pub(super) jac: SparseRows,
    /// Some rows are not affine (their entries in `offset` are unused).
    pub(super) partial: bool,
    /// The rows that are not affine as forms over the states, inputs and nonlinear results.
    nonaffine: NonaffineForms,
    /// The varying entries of J by the chain rule through `nonaffine`.
    jacobian: FormsJacobian,
    /// The outputs and rows that are not affine, as a communication point computes them.
    pub(super) point: PointForms,
    /// The largest max(|x_i|, |u_j|) within which every value of `point` is shown finite
    /// (below [`FINITE_BOUND`]) from the laws' declared value bounds
    /// ([`PointForms::finite_radius`]): 0 when one of them declares none (or a quotient is
    /// among them), or when there is nothing to leave.
    pub(super) point_radius: f64,
    /// The offsets `f(0, u)` and `y(0, u)` as forms over the inputs and nonlinear results.
    offsets: AffineOffsets,
    /// `f(0, u)` at the held inputs.
    pub(super) offset: Vec<f64>,
    /// The largest `|f_i(0, u)|` of the affine rows (+inf if one is not finite).
    offset_max: f64,
    /// The affine rows, ascending (the complement of the compiled model's nonaffine rows).
    affine_rows: Vec<u32>,
    /// The largest Σ_j |J_ij| of the affine rows.
    jac_row_sum: f64,
    /// The affine outputs, if there are at most [`MAX_AFFINE_OUTPUTS`] outputs.
    pub(super) outputs: Option<AffineOutputs>,
}

/// `y = C x + y(0, u)` for the affine outputs (the other rows of C zero, their `y0` unused).
#[derive(Clone, Debug)]
pub(super) struct AffineOutputs {
    /// C four rows at a time, for all outputs at once.
    pub(super) blocks: BlockRows,
    /// C row by row, for an output read on its own.
    pub(super) rows: SparseRows,
    /// `y(0, u)` at the held inputs.
    pub(super) y0: Vec<f64>,
    /// The largest `|y_k(0, u)|` of the affine outputs (+inf if one is not finite).
    y0_max: f64,
    /// The affine outputs, ascending.
    affine: Vec<u32>,
    /// The largest Σ_j |C_kj|.
    row_sum: f64,
}

/// What the bounds of [`Affine::finite_within`] must stay under: far enough below the largest
/// double that the rounding of a sum of up to a few hundred products cannot reach it.
pub(super) const FINITE_BOUND: f64 = f64::MAX / 16.0;

/// The largest magnitude among the entries of `v` at `at`, +inf if one of them is not finite.
pub(super) fn max_abs(v: &[f64], at: &[u32]) -> f64 {
    at.iter().fold(0.0, |m, &i| {
        let x = v[i as usize];
        if x.is_finite() {
            m.max(x.abs())
        } else {
            f64::INFINITY
        }
    })
}

/// The positions `0..n` not in the ascending list `skip`.
fn complement(n: usize, skip: &[u32]) -> Vec<u32> {
    (0..n as u32)
        .filter(|i| skip.binary_search(i).is_err())
        .collect()
}

/// [`max_abs`] of every entry of `v` (the same value), in a loop without branches that
/// vectorises: a communication point bounds its state with it.
pub(super) fn max_abs_all(v: &[f64]) -> f64 {
    let (mut m, mut finite) = (0.0f64, true);
    for &x in v {
        finite &= x.is_finite();
        let a = x.abs();
        m = if a > m { a } else { m };
    }
    if finite {
        m
    } else {
        f64::INFINITY
    }
}

impl Affine {
    /// From the Jacobian's constant entries `jac` (all of J when it is constant); the output
    /// matrix `C` from the linearisation at `(rest, inputs)`, `at_rest`, computed there if it
    /// is not yet.
    pub(super) fn new(
        jac: &DMatrix<f64>,
        compiled: &CompiledModel,
        rest: &[f64],
        inputs: &[f64],
        at_rest: &mut Option<Linearization>,
    ) -> Self {
        let partial = !compiled.nonaffine_rows().is_empty();
        let jac_rows = jac.nrows();
        let outputs = (compiled.n_outputs() <= MAX_AFFINE_OUTPUTS).then(|| {
            // The affine outputs' rows (the others, evaluated through the plan, zero).
            let mut c = at_rest
                .get_or_insert_with(|| compiled.linearize(rest, inputs))
                .c
                .clone();
            for &k in compiled.nonaffine_outputs() {
                c.row_mut(k as usize).fill(0.0);
            }
            let rows = SparseRows::from_dense(&c, |_| true);
            AffineOutputs {
                blocks: BlockRows::from_dense(&c),
                row_sum: rows.max_abs_row_sum(),
                rows,
                y0: vec![0.0; c.nrows()],
                y0_max: 0.0,
                affine: complement(c.nrows(), compiled.nonaffine_outputs()),
            }
        });
        let affine_row = |i: usize| {
            compiled
                .nonaffine_rows()
                .binary_search(&(i as u32))
                .is_err()
        };
        let jac = SparseRows::from_dense(jac, affine_row);
        let (point, point_radius) = if partial {
            let point = compiled.nonaffine_point_forms();
            let radius = point.finite_radius(compiled, FINITE_BOUND);
            (point, radius)
        } else {
            (PointForms::default(), 0.0)
        };
        let nonaffine = if partial {
            compiled.nonaffine_forms()
        } else {
            NonaffineForms::default()
        };
        let jacobian = nonaffine.jacobian(compiled.n_states(), compiled.jacobian_varying_pattern());
        let mut affine = Affine {
            point,
            point_radius,
            jac_row_sum: jac.max_abs_row_sum(),
            jac,
            partial,
            nonaffine,
            jacobian,
            offsets: compiled.affine_offset_forms(),
            offset: vec![0.0; jac_rows],
            offset_max: 0.0,
            affine_rows: complement(jac_rows, compiled.nonaffine_rows()),
            outputs,
        };
        affine.set_inputs(compiled, inputs);
        affine
    }

    pub(super) fn set_inputs(&mut self, compiled: &CompiledModel, inputs: &[f64]) {
        self.offsets.rows(compiled, inputs, &mut self.offset);
        self.offset_max = max_abs(&self.offset, &self.affine_rows);
        if let Some(o) = &mut self.outputs {
            self.offsets.outputs(compiled, inputs, &mut o.y0);
            o.y0_max = max_abs(&o.y0, &o.affine);
        }
    }

    /// Are the affine rows of f and the affine outputs finite at every x with max|x_i| ≤
    /// `x_max`, whatever the rounding? Shown from bounds, without computing them:
    /// |J_i x + f_i(0, u)| ≤ Σ_j |J_ij| max|x| + max|f(0, u)|, likewise for the outputs, and both
    /// stay far below the largest double. So an output left to be computed when it is read
    /// cannot turn out infinite then. False if the bounds are too large (or `x_max` is not
    /// finite): the caller computes and checks them.
    pub(super) fn finite_within(&self, x_max: f64) -> bool {
        let rows = self.jac_row_sum * x_max + self.offset_max;
        let outputs = self
            .outputs
            .as_ref()
            .map_or(0.0, |o| o.row_sum * x_max + o.y0_max);
        rows < FINITE_BOUND && outputs < FINITE_BOUND
    }

    /// The affine output `k` at `x`: the value [`BlockRows::product`] gives (the same products
    /// added in the same order; the blocks add exact zeros besides).
    pub(super) fn output(&self, k: usize, x: &[f64]) -> Option<f64> {
        let o = self.outputs.as_ref()?;
        Some(o.rows.row_times(k, x, o.y0[k]))
    }

    /// The affine row `i` of f at `x`.
    pub(super) fn derivative(&self, i: usize, x: &[f64]) -> f64 {
        self.jac.row_times(i, x, self.offset[i])
    }

    pub(super) fn derivatives(
        &self,
        compiled: &CompiledModel,
        x: &[f64],
        u: &[f64],
        dx: &mut [f64],
    ) {
        self.jac.times(x, &self.offset, dx);
        if self.partial {
            self.nonaffine.derivatives(compiled, x, u, dx);
        }
    }

    /// The Jacobian's varying entries into `jac` from the forms of the rows that are not affine
    /// ([`FormsJacobian`]); false where one is not finite (then the plan's passes must give
    /// them).
    pub(super) fn jacobian_varying(
        &self,
        compiled: &CompiledModel,
        x: &[f64],
        u: &[f64],
        jac: &mut DMatrix<f64>,
    ) -> bool {
        self.jacobian
            .varying_entries(&self.nonaffine, compiled, x, u, jac)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The branch-free maximum is the filtered one's, with non-finite entries anywhere.
    #[test]
    fn max_abs_all_is_max_abs_of_every_entry() {
        let cases: [&[f64]; 7] = [
            &[],
            &[-0.0],
            &[1.0, -3.5, 2.0],
            &[1.0, f64::NAN, 2.0],
            &[f64::NEG_INFINITY, 1.0],
            &[1e300, -1e308, 5.0, 0.0],
            &[2.0, 3.0, f64::INFINITY, f64::NAN],
        ];
        for v in cases {
            let every: Vec<u32> = (0..v.len() as u32).collect();
            let (a, b) = (max_abs_all(v), max_abs(v, &every));
            assert_eq!(a.to_bits(), b.to_bits(), "{v:?}");
        }
    }

    /// The affine positions are those not listed as nonaffine.
    #[test]
    fn the_complement_leaves_out_the_listed_positions() {
        assert_eq!(complement(6, &[1, 4]), vec![0, 2, 3, 5]);
        assert_eq!(complement(3, &[]), vec![0, 1, 2]);
        assert_eq!(complement(2, &[0, 1]), Vec::<u32>::new());
        let v = [9.0, -1.0, 4.0, f64::NAN];
        assert_eq!(max_abs(&v, &complement(4, &[0, 3])), 4.0);
        assert_eq!(max_abs(&v, &complement(4, &[0])), f64::INFINITY);
    }

    /// The blocked product is the plain dense one, to the bit, for rows that are not a
    /// multiple of four and columns that no row of a block reads.
    #[test]
    fn blocked_output_product_is_the_dense_product() {
        let (rows, cols) = (11, 9);
        let c = DMatrix::from_fn(rows, cols, |k, j| {
            if (k * 7 + j * 3) % 5 == 0 || j == 4 {
                0.0
            } else {
                (k as f64 + 1.0) * 0.37 - j as f64 * 1.9
            }
        });
        let x: Vec<f64> = (0..cols)
            .map(|j| crate::math::sin(j as f64 * 0.77) * 1e3)
            .collect();
        let y0: Vec<f64> = (0..rows).map(|k| k as f64 - 3.5).collect();
        let mut y = vec![f64::NAN; rows];
        let blocked = BlockRows::from_dense(&c);
        blocked.product(&x, &y0, &mut y);
        for k in 0..rows {
            let dense = (0..cols)
                .filter(|&j| c[(k, j)] != 0.0)
                .fold(y0[k], |acc, j| acc + c[(k, j)] * x[j]);
            assert_eq!(y[k].to_bits(), dense.to_bits(), "row {k}");
        }
        // Column 4 is zero everywhere: no block stores it.
        assert!(blocked.entries.iter().all(|&(j, _)| j != 4));
    }
}
