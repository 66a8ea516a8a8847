//! The varying entries of the Jacobian from the forms of the rows that are not affine, by the
//! chain rule through their nonlinear operations.
//!
//! A row that is not affine is `f_i = c + Σ a_v x_v + Σ a_v u_v + Σ a_z z` over the states,
//! the inputs and the nonlinear results `z` it reads ([`NonaffineForms`]); each nonlinear
//! result is a scalar function of one or two operands, themselves such forms over the states,
//! the inputs and the results before it. So
//!
//! ```text
//! ∂z_c/∂x = g_a ∂a_c/∂x + g_b ∂b_c/∂x,    ∂a_c/∂x = Σ a_v e_v + Σ a_z ∂z/∂x   (the same for b)
//! ∂f_i/∂x_j = a_j + Σ a_z ∂z/∂x_j
//! ```
//!
//! with `g_a`, `g_b` the operation's partial derivatives at the point (a law's from its
//! closure, exact; `b k` and `a k` for a product `k a b`; `k / b` and `-k a / b²` for a
//! quotient). Each gradient `∂z_c/∂x` is sparse, with a pattern fixed by the forms: the states
//! its operands read, directly or through the results they read. [`FormsJacobian`] lays out
//! those patterns and the chain's links once per parameter set; an evaluation is the forms'
//! values, then one multiply-add per link. On the default plant that is a few hundred
//! multiply-adds where the tangent sweeps of [`CompiledModel::jacobian_varying`] carry dual
//! numbers through every operation the varying columns reach.
//!
//! The entries are the sweeps' to rounding: the same derivatives, the products of the plan's
//! factors associated otherwise (`tests`: within 1e-13 of the largest entry of the row).

use std::cell::RefCell;

use nalgebra::DMatrix;

use super::super::compiled::CompiledModel;
use super::{Form, Kind, NonaffineForms, LANE_TERMS};
use crate::math::lanes::{Lanes, Run, Summation};

/// `src` of a [`Link`] that adds its coefficient alone (a state read directly).
const DIRECT: u32 = u32::MAX;

/// One term of the chain rule: `grad[dst] += g (a grad[src])`, or `grad[dst] += g a` for a
/// state read directly (`src` = [`DIRECT`]), `g` the partial derivative of the operation.
#[derive(Clone, Copy, Debug)]
struct Link {
    dst: u32,
    src: u32,
    a: f64,
}

/// A varying entry `(row, column)`: `direct + Σ a grad[src]` over `terms[start..end]`.
#[derive(Clone, Copy, Debug)]
struct Entry {
    row: u32,
    column: u32,
    direct: f64,
    start: u32,
    end: u32,
}

/// The varying entries of the Jacobian of a [`NonaffineForms`]' rows (see the module
/// documentation), laid out for one parameter set.
#[derive(Clone, Debug, Default)]
pub struct FormsJacobian {
    /// The gradient of nonlinear result `c` occupies `grad[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    /// For each nonlinear result, the links of its operand a, then of b: ranges of `links`.
    operands: Vec<[(u32, u32); 2]>,
    links: Vec<Link>,
    entries: Vec<Entry>,
    /// (grad position, coefficient) of the entries' chain terms.
    terms: Vec<(u32, f64)>,
    /// Runs of consecutive entries with as many chain terms, summed four at a time
    /// ([`crate::math::lanes`]; the same bits as alone).
    entry_runs: Vec<Run>,
    lanes: Lanes,
    /// Entries of the chain's pattern that `varying` did not list: none when the structure's
    /// analysis and the forms agree (it is asserted by the tests).
    unlisted: usize,
}

thread_local! {
    /// The values (states, inputs, nonlinear results), then the gradients.
    static WS: RefCell<(Vec<f64>, Vec<f64>)> = const { RefCell::new((Vec::new(), Vec::new())) };
}

impl NonaffineForms {
    /// The layout of the varying entries `varying` (by row, the columns, ascending: the
    /// structure's [`CompiledModel::jacobian_varying_pattern`]) of the rows these forms
    /// compute, over the first `n_states` variables.
    pub fn jacobian(&self, n_states: usize, varying: &[Vec<u32>]) -> FormsJacobian {
        let known = self.known;
        let mut out = FormsJacobian::default();
        // The pattern of each nonlinear result's gradient, ascending.
        let mut pattern: Vec<Vec<u32>> = Vec::with_capacity(self.nonlinear.len());
        let columns_of = |pattern: &[Vec<u32>], f: &Form| -> Vec<u32> {
            let mut cols = Vec::new();
            for &(v, _) in &self.entries[f.start as usize..f.end as usize] {
                let v = v as usize;
                if v < n_states {
                    cols.push(v as u32);
                } else if v >= known {
                    cols.extend_from_slice(&pattern[v - known]);
                }
            }
            cols
        };
        let mut grad_len = 0u32;
        for op in &self.nonlinear {
            let operands = [Some(op.a), op.b];
            let mut cols: Vec<u32> = operands
                .iter()
                .flatten()
                .flat_map(|f| columns_of(&pattern, f))
                .collect();
            cols.sort_unstable();
            cols.dedup();
            let base = grad_len;
            out.start.push(base);
            let place = |col: u32| base + cols.binary_search(&col).expect("in the pattern") as u32;
            let mut ranges = [(0, 0); 2];
            for (range, f) in ranges.iter_mut().zip(operands) {
                let first = out.links.len() as u32;
                for &(v, a) in f.iter().flat_map(|f| self.form_entries(f)) {
                    let v = v as usize;
                    if v < n_states {
                        out.links.push(Link {
                            dst: place(v as u32),
                            src: DIRECT,
                            a,
                        });
                    } else if v >= known {
                        let z = v - known;
                        for (p, &col) in pattern[z].iter().enumerate() {
                            out.links.push(Link {
                                dst: place(col),
                                src: out.start[z] + p as u32,
                                a,
                            });
                        }
                    }
                }
                *range = (first, out.links.len() as u32);
            }
            out.operands.push(ranges);
            grad_len += cols.len() as u32;
            pattern.push(cols);
        }
        out.start.push(grad_len);
        for &(row, f) in &self.rows {
            let listed = &varying[row as usize];
            let entries = self.form_entries(&f);
            for &column in listed {
                let direct = entries
                    .iter()
                    .find(|&&(v, _)| v == column)
                    .map_or(0.0, |&(_, a)| a);
                let start = out.terms.len() as u32;
                for &(v, a) in entries.iter().filter(|&&(v, _)| v as usize >= known) {
                    let z = v as usize - known;
                    if let Ok(p) = pattern[z].binary_search(&column) {
                        out.terms.push((out.start[z] + p as u32, a));
                    }
                }
                out.entries.push(Entry {
                    row,
                    column,
                    direct,
                    start,
                    end: out.terms.len() as u32,
                });
            }
            let mut through_chain: Vec<u32> = entries
                .iter()
                .filter(|&&(v, _)| v as usize >= known)
                .flat_map(|&(v, _)| pattern[v as usize - known].iter().copied())
                .collect();
            through_chain.sort_unstable();
            through_chain.dedup();
            out.unlisted += through_chain
                .iter()
                .filter(|j| listed.binary_search(j).is_err())
                .count();
        }
        let terms = |e: &Entry| &out.terms[e.start as usize..e.end as usize];
        let lengths: Vec<usize> = out.entries.iter().map(|e| terms(e).len()).collect();
        let mut lanes = Lanes::default();
        let mut entry_runs = Vec::new();
        for range in crate::math::lanes::equal_lengths(&lengths, LANE_TERMS) {
            let forms: Vec<&[(u32, f64)]> = out.entries[range.clone()].iter().map(terms).collect();
            entry_runs.push(lanes.add(range.start, &forms, Summation::Fold));
        }
        out.entry_runs = entry_runs;
        out.lanes = lanes;
        out
    }
}

impl FormsJacobian {
    /// Number of varying entries it writes and of chain links: the work of one evaluation.
    pub fn size(&self) -> (usize, usize) {
        (self.entries.len(), self.links.len() + self.terms.len())
    }

    /// Entries whose value the chain makes depend on x but that the varying pattern it was laid
    /// out for does not list (and that it therefore leaves alone).
    pub fn unlisted(&self) -> usize {
        self.unlisted
    }

    /// The varying entries into `jac` at the states `x` and inputs `u` of `m` (the model
    /// `forms` were made from, `forms` the forms it was laid out from). Returns whether they
    /// are all finite; where one is not, the entries written so far are left in `jac` and the
    /// caller computes them otherwise (a law's infinite slope times a zero weight is 0 in the
    /// plan's passes, not NaN).
    pub fn varying_entries(
        &self,
        forms: &NonaffineForms,
        m: &CompiledModel,
        x: &[f64],
        u: &[f64],
        jac: &mut DMatrix<f64>,
    ) -> bool {
        let known = forms.known;
        assert_eq!(x.len() + u.len(), known, "state and input lengths");
        WS.with(|ws| {
            let mut ws = ws.borrow_mut();
            let (w, grad) = &mut *ws;
            let len = known + forms.nonlinear.len();
            if w.len() < len {
                w.resize(len, 0.0);
            }
            let grad_len = *self.start.last().unwrap_or(&0) as usize;
            if grad.len() < grad_len {
                grad.resize(grad_len, 0.0);
            }
            let (w, grad) = (&mut w[..len], &mut grad[..grad_len]);
            w[..x.len()].copy_from_slice(x);
            w[x.len()..known].copy_from_slice(u);
            // Each result and its gradient from its operands' values.
            let result = |c: usize, a: f64, b: f64| -> f64 {
                let (y, ga, gb) = match forms.nonlinear[c].kind {
                    Kind::Law { law, ki, ko } => {
                        let (y, dx, dm) = (m.laws[law as usize].f)(a * ki, b);
                        (y * ko, dx * ki * ko, dm * ko)
                    }
                    Kind::Mul { k } => ((a * b) * k, b * k, a * k),
                    Kind::Div { k } => {
                        let q = a / b;
                        (q * k, k / b, -(q * k) / b)
                    }
                };
                let (lo, hi) = (self.start[c] as usize, self.start[c + 1] as usize);
                grad[lo..hi].fill(0.0);
                for (range, g) in self.operands[c].iter().zip([ga, gb]) {
                    for l in &self.links[range.0 as usize..range.1 as usize] {
                        let d = if l.src == DIRECT {
                            l.a
                        } else {
                            l.a * grad[l.src as usize]
                        };
                        grad[l.dst as usize] += g * d;
                    }
                }
                y
            };
            forms.operations(w, result);
            let mut finite = true;
            let mut write = |i: usize, v: f64| {
                let e = &self.entries[i];
                finite &= v.is_finite();
                jac[(e.row as usize, e.column as usize)] = v;
            };
            let alone = |e: &Entry| {
                let terms = &self.terms[e.start as usize..e.end as usize];
                Summation::Fold.sum(grad, e.direct, terms)
            };
            let mut i = 0;
            for run in &self.entry_runs {
                for i in i..run.forms().start {
                    write(i, alone(&self.entries[i]));
                }
                let direct = |i: usize| self.entries[i].direct;
                self.lanes.each_value(grad, run, direct, &mut write);
                i = run.forms().end;
            }
            for i in i..self.entries.len() {
                write(i, alone(&self.entries[i]));
            }
            finite
        })
    }
}
