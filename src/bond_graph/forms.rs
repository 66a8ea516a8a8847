//! The rows of `f` that are not affine in x as sparse linear forms over the states, the inputs
//! and the results of the plan's nonlinear operations.
//!
//! Every operation of the plan but the laws, products and quotients is linear with constant
//! coefficients (`Const`, `Copy`, `Lin`). So every slot is an affine combination, with
//! coefficients fixed per parameter set, of the states, the inputs and the results `z_c` of
//! the nonlinear operations before it; each nonlinear operation's operands are such
//! combinations too. [`NonaffineForms`] keeps, for the rows that are not affine, the
//! nonlinear operations they need in plan order with their operands as forms, and the rows as
//! forms. Evaluating it is a few dot products per nonlinear operation and per row, instead of a
//! pass through the hundreds of operations (most of them a single factor: transformers and
//! modal participations, as in the plate's air drag, summed at every drag point over the modes
//! and back) that compute the same combinations step by step.
//!
//! The forms' coefficients are the products of the plan's factors along each path, added up,
//! so a value differs from the plan's by rounding only (the same sums, associated otherwise).

use std::cell::RefCell;

use super::compiled::CompiledModel;
use super::plan::{Op, NONE};

/// `c + Σ a_v w_v` over `entries[start..end]` (variable, coefficient), `w` being the states,
/// the inputs, then the nonlinear results.
#[derive(Clone, Copy, Debug)]
struct Form {
    c: f64,
    start: u32,
    end: u32,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    /// `ko L(ki a, m)`, `m` = 0 without modulator.
    Law { law: u32, ki: f64, ko: f64 },
    /// `k a b`
    Mul { k: f64 },
    /// `k a / b`
    Div { k: f64 },
}

/// A nonlinear operation with its operands as forms.
#[derive(Clone, Copy, Debug)]
struct Nonlinear {
    kind: Kind,
    a: Form,
    b: Option<Form>,
}

/// The rows of `f` that are not affine, as forms (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct NonaffineForms {
    /// States and inputs: the first `known` variables.
    known: usize,
    nonlinear: Vec<Nonlinear>,
    /// (row, form).
    rows: Vec<(u32, Form)>,
    entries: Vec<(u32, f64)>,
}

thread_local! {
    static WS: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// A form under construction: the constant and the coefficients by variable.
#[derive(Clone, Default)]
struct Sparse {
    c: f64,
    terms: Vec<(u32, f64)>,
}

impl NonaffineForms {
    /// The forms of `targets` (`(index, slot)`: the slot's form is delivered at `index`)
    /// through `ops`, the operations of `m`'s plan they need (in plan order).
    pub(super) fn new(m: &CompiledModel, ops: &[Op], targets: &[(u32, u32)]) -> Self {
        let known = m.n_states() + m.n_inputs();
        let mut out = NonaffineForms {
            known,
            ..Default::default()
        };
        let mut slot: Vec<Option<Sparse>> = vec![None; m.n_slots];
        for (k, s) in slot.iter_mut().enumerate().take(known) {
            *s = Some(Sparse {
                c: 0.0,
                terms: vec![(k as u32, 1.0)],
            });
        }
        // Dense accumulator over the variables (states, inputs, nonlinear results).
        let mut acc: Vec<f64> = vec![0.0; known + ops.len()];
        let mut touched: Vec<u32> = Vec::new();
        let form_of = |slot: &[Option<Sparse>], s: u32| -> Sparse {
            slot[s as usize]
                .clone()
                .expect("an operation reads a slot written before it")
        };
        let push = |out: &mut NonaffineForms, f: &Sparse| -> Form {
            let start = out.entries.len() as u32;
            out.entries.extend_from_slice(&f.terms);
            Form {
                c: f.c,
                start,
                end: out.entries.len() as u32,
            }
        };
        for op in ops {
            let (dst, form) = match *op {
                Op::Const { dst, c } => (dst, Sparse { c, terms: vec![] }),
                Op::Copy { dst, src } => (dst, form_of(&slot, src)),
                Op::Lin { dst, start, end } => {
                    let mut c = 0.0;
                    for &(k, s) in &m.terms[start as usize..end as usize] {
                        let f = slot[s as usize].as_ref().expect("written before read");
                        c += k * f.c;
                        for &(v, a) in &f.terms {
                            if acc[v as usize] == 0.0 {
                                touched.push(v);
                            }
                            acc[v as usize] += k * a;
                        }
                    }
                    touched.sort_unstable();
                    touched.dedup();
                    let terms = touched
                        .iter()
                        .map(|&v| (v, std::mem::take(&mut acc[v as usize])))
                        .filter(|&(_, a)| a != 0.0)
                        .collect();
                    touched.clear();
                    (dst, Sparse { c, terms })
                }
                Op::Law {
                    dst,
                    law,
                    arg,
                    ki,
                    ko,
                    m: modulator,
                } => {
                    let a = push(&mut out, &form_of(&slot, arg));
                    let b = (modulator != NONE).then(|| push(&mut out, &form_of(&slot, modulator)));
                    out.nonlinear.push(Nonlinear {
                        kind: Kind::Law { law, ki, ko },
                        a,
                        b,
                    });
                    (dst, Self::result(known, out.nonlinear.len()))
                }
                Op::Mul { dst, a, b, k } | Op::Div { dst, a, b, k } => {
                    let fa = push(&mut out, &form_of(&slot, a));
                    let fb = push(&mut out, &form_of(&slot, b));
                    let kind = if matches!(op, Op::Mul { .. }) {
                        Kind::Mul { k }
                    } else {
                        Kind::Div { k }
                    };
                    out.nonlinear.push(Nonlinear {
                        kind,
                        a: fa,
                        b: Some(fb),
                    });
                    (dst, Self::result(known, out.nonlinear.len()))
                }
            };
            slot[dst as usize] = Some(form);
        }
        for &(i, s) in targets {
            let f = push(&mut out, &form_of(&slot, s));
            out.rows.push((i, f));
        }
        out
    }

    /// The form of the `count`-th nonlinear result (1-based).
    fn result(known: usize, count: usize) -> Sparse {
        Sparse {
            c: 0.0,
            terms: vec![((known + count - 1) as u32, 1.0)],
        }
    }

    /// Number of nonlinear operations and of coefficients: the work of one evaluation.
    pub fn size(&self) -> (usize, usize) {
        (self.nonlinear.len(), self.entries.len())
    }

    /// The rows that are not affine into their places in `dx` (the others left as they are),
    /// at the states `x` and inputs `u` of `m`, the model the forms were made from.
    pub fn derivatives(&self, m: &CompiledModel, x: &[f64], u: &[f64], dx: &mut [f64]) {
        assert_eq!(x.len() + u.len(), self.known, "state and input lengths");
        self.evaluate(m, Some(x), u, dx);
    }

    /// The targets into their places in `out` (the others left as they are), at the states
    /// `x` (zero for `None`) and inputs `u` of `m`, the model the forms were made from.
    pub(super) fn evaluate(
        &self,
        m: &CompiledModel,
        x: Option<&[f64]>,
        u: &[f64],
        out: &mut [f64],
    ) {
        self.evaluate_each(m, x, u, |i, v| out[i as usize] = v);
    }

    /// [`NonaffineForms::evaluate`], each target's value given to `each(index, value)`.
    fn evaluate_each(
        &self,
        m: &CompiledModel,
        x: Option<&[f64]>,
        u: &[f64],
        mut each: impl FnMut(u32, f64),
    ) {
        let n = self.known - u.len();
        WS.with(|ws| {
            let mut ws = ws.borrow_mut();
            let len = self.known + self.nonlinear.len();
            if ws.len() < len {
                ws.resize(len, 0.0);
            }
            let w = &mut ws[..len];
            match x {
                Some(x) => w[..n].copy_from_slice(x),
                None => w[..n].fill(0.0),
            }
            w[n..self.known].copy_from_slice(u);
            let entries = &self.entries;
            let dot = |w: &[f64], f: &Form| {
                entries[f.start as usize..f.end as usize]
                    .iter()
                    .fold(f.c, |acc, &(v, a)| acc + a * w[v as usize])
            };
            for (c, op) in self.nonlinear.iter().enumerate() {
                let a = dot(w, &op.a);
                let b = op.b.as_ref().map_or(0.0, |b| dot(w, b));
                w[self.known + c] = match op.kind {
                    Kind::Law { law, ki, ko } => (m.laws[law as usize].value)(a * ki, b) * ko,
                    Kind::Mul { k } => (a * b) * k,
                    Kind::Div { k } => (a / b) * k,
                };
            }
            for (i, f) in &self.rows {
                each(*i, dot(w, f));
            }
        })
    }
}

/// The outputs and the rows of `f` that are not affine in x, as forms (see the module
/// documentation): what a communication point computes at once when the rest is affine.
/// [`PointForms::for_each`] gives the values of
/// [`CompiledModel::for_each_nonaffine_output_and_derivative`] to rounding, with a few dot
/// products per nonlinear operation instead of a pass through the operations they need.
#[derive(Clone, Debug, Default)]
pub struct PointForms {
    /// Targets below `outputs` are the outputs; the others the rows, offset by `outputs`.
    forms: NonaffineForms,
    outputs: u32,
}

impl PointForms {
    /// The forms of `m`'s outputs that are not affine (`(output, slot)`) and of its rows that
    /// are not (`(row, slot)`), through `ops`, the operations they need.
    pub(super) fn new(
        m: &CompiledModel,
        ops: &[Op],
        outputs: &[(u32, u32)],
        rows: &[(u32, u32)],
    ) -> Self {
        let n_outputs = m.n_outputs() as u32;
        let targets: Vec<(u32, u32)> = outputs
            .iter()
            .copied()
            .chain(rows.iter().map(|&(i, s)| (n_outputs + i, s)))
            .collect();
        PointForms {
            forms: NonaffineForms::new(m, ops, &targets),
            outputs: n_outputs,
        }
    }

    /// Calls `output(k, y_k)` for every output that is not affine and `derivative(i, dx_i/dt)`
    /// for every row that is not, at the states `x` and inputs `u` of `m`, the model the forms
    /// were made from.
    pub fn for_each(
        &self,
        m: &CompiledModel,
        x: &[f64],
        u: &[f64],
        mut output: impl FnMut(usize, f64),
        mut derivative: impl FnMut(usize, f64),
    ) {
        assert_eq!(
            x.len() + u.len(),
            self.forms.known,
            "state and input lengths"
        );
        self.forms.evaluate_each(m, Some(x), u, |i, v| {
            if i < self.outputs {
                output(i as usize, v);
            } else {
                derivative((i - self.outputs) as usize, v);
            }
        });
    }
}
