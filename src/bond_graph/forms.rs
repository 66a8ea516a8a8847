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
//!
//! Consecutive forms of one length, the drag points' operands (all over the same momenta) and
//! rows of one length, are evaluated four at a time ([`crate::math::lanes`]), each summed in
//! the order [`NonaffineForms::dot`] sums it alone: a value has the same bits however it is
//! reached, alone at a communication point ([`PointForms::output`]) or in a run.

use std::cell::RefCell;

mod jacobian;

pub use jacobian::FormsJacobian;

use crate::math::lanes::{self, Lanes, Run, Summation};

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
    /// Runs of nonlinear operations evaluated side by side ([`lanes`]): laws without a
    /// modulator whose first operands have one length and read no result of their run (so the
    /// run's operands are known at its start).
    operation_runs: Vec<Run>,
    /// Runs of rows of one length evaluated side by side.
    row_runs: Vec<Run>,
    lanes: Lanes,
}

thread_local! {
    static WS: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// The number of terms from which [`NonaffineForms::dot`] sums in four running sums.
const DOT_SPLIT: usize = 8;

/// How [`NonaffineForms::dot`] sums, for the lanes.
const SUMMATION: Summation = Summation::Split { from: DOT_SPLIT };

/// Forms shorter than this are evaluated alone: too few terms for the lanes' set-up to pay.
const LANE_TERMS: usize = 4;

/// The most operations in one run (a longer stretch makes several): their results wait in a
/// scratch of this size on the stack until the run's operands are all read.
const MAX_RUN: usize = 32;

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
        out.lay_out_lanes();
        out
    }

    /// The runs of operations and rows evaluated side by side.
    fn lay_out_lanes(&mut self) {
        let known = self.known;
        // The operations that may join a run begun at `first`, with their operands' lengths.
        let joins = |c: usize, first: usize| -> Option<usize> {
            let op = &self.nonlinear[c];
            let a = self.form_entries(&op.a);
            let fits = matches!(op.kind, Kind::Law { .. })
                && op.b.is_none()
                && a.iter().all(|&(v, _)| (v as usize) < known + first);
            fits.then_some(a.len())
        };
        let mut operations = Vec::new();
        let mut c = 0;
        while c < self.nonlinear.len() {
            let Some(len) = joins(c, c).filter(|&len| len >= LANE_TERMS) else {
                c += 1;
                continue;
            };
            let end = c
                + (c..self.nonlinear.len())
                    .take_while(|&e| joins(e, c) == Some(len))
                    .count();
            if end - c >= 2 {
                operations.extend((c..end).step_by(MAX_RUN).map(|s| s..(s + MAX_RUN).min(end)));
            }
            c = end;
        }
        let lengths: Vec<usize> = self
            .rows
            .iter()
            .map(|(_, f)| self.form_entries(f).len())
            .collect();
        let mut lanes = Lanes::default();
        for range in operations {
            let forms: Vec<&[(u32, f64)]> = self.nonlinear[range.clone()]
                .iter()
                .map(|op| self.form_entries(&op.a))
                .collect();
            self.operation_runs
                .push(lanes.add(range.start, &forms, SUMMATION));
        }
        for range in lanes::equal_lengths(&lengths, LANE_TERMS) {
            let forms: Vec<&[(u32, f64)]> = self.rows[range.clone()]
                .iter()
                .map(|(_, f)| self.form_entries(f))
                .collect();
            self.row_runs
                .push(lanes.add(range.start, &forms, SUMMATION));
        }
        self.lanes = lanes;
    }

    /// The form of the `count`-th nonlinear result (1-based).
    fn result(known: usize, count: usize) -> Sparse {
        Sparse {
            c: 0.0,
            terms: vec![((known + count - 1) as u32, 1.0)],
        }
    }

    /// The (variable, coefficient) terms of `f`.
    fn form_entries(&self, f: &Form) -> &[(u32, f64)] {
        &self.entries[f.start as usize..f.end as usize]
    }

    /// Numbers of nonlinear operations whose operands, and of rows, that are summed four at a
    /// time ([`lanes`]), and of those operations whose four forms of a chunk read the same
    /// variables (the kernel loads each once instead of gathering it).
    pub fn side_by_side(&self) -> (usize, usize, usize) {
        let count = |runs: &[Run]| runs.iter().map(|r| r.forms().len()).sum();
        let shared = (self.operation_runs.iter())
            .flat_map(|r| {
                (0..r.chunks())
                    .filter(|&k| r.is_shared(k))
                    .map(|k| r.chunk(k).len())
            })
            .sum();
        (count(&self.operation_runs), count(&self.row_runs), shared)
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

    /// `c + Σ a_v w_v` of `f` (the same sum, in the same order, wherever it is evaluated):
    /// a form of [`DOT_SPLIT`] terms or more in four running sums ([`Summation::Split`]; the
    /// drag points' forms read a dozen states each, and one running sum would make each
    /// product wait on the addition before it).
    #[inline(always)]
    fn dot(&self, w: &[f64], f: &Form) -> f64 {
        SUMMATION.sum(w, f.c, &self.entries[f.start as usize..f.end as usize])
    }

    /// The values of the `c`-th nonlinear operation's operands from the variables before it
    /// in `w` (`b` 0 without a second one).
    #[inline(always)]
    fn operands(&self, w: &[f64], c: usize) -> (f64, f64) {
        let op = &self.nonlinear[c];
        let a = self.dot(w, &op.a);
        match &op.b {
            Some(b) => (a, self.dot(w, b)),
            None => (a, 0.0),
        }
    }

    /// The `c`-th nonlinear result from the variables before it in `w`.
    #[inline]
    fn nonlinear_value(&self, m: &CompiledModel, w: &[f64], c: usize) -> f64 {
        let (a, b) = self.operands(w, c);
        self.law_value(m, c, a, b)
    }

    /// The `c`-th nonlinear result from the values `a` and `b` of its operands.
    #[inline]
    fn law_value(&self, m: &CompiledModel, c: usize, a: f64, b: f64) -> f64 {
        match self.nonlinear[c].kind {
            Kind::Law { law, ki, ko } => (m.laws[law as usize].value)(a * ki, b) * ko,
            Kind::Mul { k } => (a * b) * k,
            Kind::Div { k } => (a / b) * k,
        }
    }

    /// Every nonlinear result into its place in `w` (whose states and inputs are set), in plan
    /// order, `result(c, a, b)` giving the `c`-th from the values of its operands (`b` 0
    /// without a second one). The operands of a run (see [`lanes`]) are computed four at a
    /// time, the others alone.
    #[inline]
    fn operations(&self, w: &mut [f64], mut result: impl FnMut(usize, f64, f64) -> f64) {
        let known = self.known;
        let mut c = 0;
        for run in &self.operation_runs {
            for c in c..run.forms().start {
                let (a, b) = self.operands(w, c);
                w[known + c] = result(c, a, b);
            }
            // A run reads no result of its own: its operands are known at its start (the
            // results go to a scratch first, `w` being read meanwhile). Its laws have no
            // modulator.
            let mut results = [0.0; MAX_RUN];
            let constant = |c: usize| self.nonlinear[c].a.c;
            let first = run.forms().start;
            self.lanes.each_value(w, run, constant, |c, a| {
                results[c - first] = result(c, a, 0.0);
            });
            w[known + first..known + run.forms().end]
                .copy_from_slice(&results[..run.forms().len()]);
            c = run.forms().end;
        }
        for c in c..self.nonlinear.len() {
            let (a, b) = self.operands(w, c);
            w[known + c] = result(c, a, b);
        }
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
            self.operations(w, |c, a, b| self.law_value(m, c, a, b));
            let mut r = 0;
            for run in &self.row_runs {
                for (i, f) in &self.rows[r..run.forms().start] {
                    each(*i, self.dot(w, f));
                }
                let constant = |p: usize| self.rows[p].1.c;
                let each = |p: usize, value| each(self.rows[p].0, value);
                self.lanes.each_value(w, run, constant, each);
                r = run.forms().end;
            }
            for (i, f) in &self.rows[r..] {
                each(*i, self.dot(w, f));
            }
        })
    }
}

/// The outputs and the rows of `f` that are not affine in x, as forms (see the module
/// documentation): what a communication point computes at once when the rest is affine, or
/// leaves until read when it can show them finite ([`PointForms::finite_radius`]).
/// [`PointForms::for_each`] gives the values of
/// [`CompiledModel::for_each_nonaffine_output_and_derivative`] to rounding, with a few dot
/// products per nonlinear operation instead of a pass through the operations they need;
/// [`PointForms::output`] and [`PointForms::derivative`] give one of them, the same bits, with
/// only the nonlinear operations it needs.
#[derive(Clone, Debug, Default)]
pub struct PointForms {
    /// Targets below `outputs` are the outputs; the others the rows, offset by `outputs`.
    forms: NonaffineForms,
    outputs: u32,
    /// For each target index (output, or `outputs` + row), its place among the forms' rows.
    place: Vec<Option<u32>>,
    /// For each of the forms' rows, the range of `needs` listing the nonlinear operations its
    /// value depends on, in plan order (those its form reads and those they read, and so on).
    needs_of: Vec<(u32, u32)>,
    needs: Vec<u32>,
}

/// The nonlinear results computed so far at one communication point, for
/// [`PointForms::output`] and [`PointForms::derivative`]: a value read after another reuses
/// the operations both need. `stamp` names the point (0: none yet): a new one starts afresh.
#[derive(Clone, Debug, Default)]
pub struct PointCache {
    stamp: u64,
    w: Vec<f64>,
    done: Vec<bool>,
}

/// The factor by which every bound of [`PointForms::finite_radius`] is raised to cover the
/// rounding of what it bounds: a dot product of `n` terms is within `n` units in the last place
/// (2^-53) of the exact sum of the magnitudes, a few hundred of them at most here; 2^-20 covers
/// that for forms of up to about 2^32 entries, and the rounding of the bound's own arithmetic.
const ROUNDING_MARGIN: f64 = 1.0 + 1.0 / (1u64 << 20) as f64;

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
        let forms = NonaffineForms::new(m, ops, &targets);
        let mut place = vec![None; (n_outputs as usize) + m.n_states()];
        for (p, &(i, _)) in forms.rows.iter().enumerate() {
            place[i as usize] = Some(p as u32);
        }
        // The operations each nonlinear result needs, then each row: as flags over the
        // operations before it (a few dozen), in plan order.
        let known = forms.known;
        let n_nonlinear = forms.nonlinear.len();
        let reads = |f: &Form| -> Vec<usize> {
            forms.entries[f.start as usize..f.end as usize]
                .iter()
                .filter(|&&(v, _)| v as usize >= known)
                .map(|&(v, _)| v as usize - known)
                .collect()
        };
        let mut need: Vec<Vec<bool>> = Vec::with_capacity(n_nonlinear);
        let closure = |need: &[Vec<bool>], read: Vec<usize>| -> Vec<bool> {
            let mut flags = vec![false; n_nonlinear];
            for c in read {
                flags[c] = true;
                for (f, &n) in flags.iter_mut().zip(&need[c]) {
                    *f |= n;
                }
            }
            flags
        };
        for op in &forms.nonlinear {
            let mut read = reads(&op.a);
            read.extend(op.b.as_ref().map_or(vec![], &reads));
            let flags = closure(&need, read);
            need.push(flags);
        }
        let (mut needs_of, mut needs) = (Vec::new(), Vec::new());
        for (_, f) in &forms.rows {
            let flags = closure(&need, reads(f));
            let start = needs.len() as u32;
            needs.extend((0..n_nonlinear as u32).filter(|&c| flags[c as usize]));
            needs_of.push((start, needs.len() as u32));
        }
        PointForms {
            forms,
            outputs: n_outputs,
            place,
            needs_of,
            needs,
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

    /// The largest `S` (a power of 2 from 2^-1000 to 2^1000, or 0) such that every value the
    /// forms of `m` compute (every nonlinear result and every target) is finite, bounded below
    /// `limit`, whenever
    /// every state and input is at most `S` in magnitude: shown from bounds, without
    /// computing them, so that a communication point within it can leave the values until they
    /// are read (the FMU never returns with a non-finite output it has not checked).
    ///
    /// For a bound `S` on the states and inputs, the bound of each form is
    /// `|c| + Σ |a_v| bound(w_v)`; of a law `ko L(ki a, m)`, `|ko| (k s² + c)` with
    /// `s = max(|ki| bound(a), bound(m))` and `(k, c)` its declared value bound
    /// ([`super::NonlinearLaw::with_value_bound`], valid up to
    /// [`super::VALUE_BOUND_RANGE`]); of a product `k a b`, `|k| bound(a) bound(b)`; each raised
    /// by a factor 1 + 2^-20 for rounding. A quotient has none (its denominator is not shown
    /// away from zero), nor has a law without a declared bound: then `S` = 0, nothing is left.
    /// The bounds grow with `S`, so the largest `S` is found by bisection on its exponent.
    pub fn finite_radius(&self, m: &CompiledModel, limit: f64) -> f64 {
        let (mut lo, mut hi) = (-1000_i32, 1000_i32);
        let within = |e: i32| self.bounded_within(m, 2f64.powi(e), limit);
        if !within(lo) {
            return 0.0;
        }
        if within(hi) {
            return 2f64.powi(hi);
        }
        // within(lo) and not within(hi)
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if within(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        2f64.powi(lo)
    }

    /// Are all the forms' values below `limit` in magnitude whenever the states and inputs
    /// are at most `s` (see [`PointForms::finite_radius`])?
    pub fn bounded_within(&self, m: &CompiledModel, s: f64, limit: f64) -> bool {
        let f = &self.forms;
        let mut b = vec![s; f.known + f.nonlinear.len()];
        let form_bound = |b: &[f64], form: &Form| -> f64 {
            f.entries[form.start as usize..form.end as usize]
                .iter()
                .fold(form.c.abs(), |acc, &(v, a)| acc + a.abs() * b[v as usize])
                * ROUNDING_MARGIN
        };
        for (c, op) in f.nonlinear.iter().enumerate() {
            let a = form_bound(&b, &op.a);
            // The second operand: a law's modulator, a product's other factor.
            let second = op.b.as_ref().map_or(0.0, |form| form_bound(&b, form));
            let v = match op.kind {
                Kind::Law { law, ki, ko } => {
                    let arg = (ki.abs() * a * ROUNDING_MARGIN).max(second);
                    match m.laws[law as usize].value_bound {
                        Some((k, c)) if arg <= super::VALUE_BOUND_RANGE => {
                            ko.abs() * (k.abs() * arg * arg + c.abs()) * ROUNDING_MARGIN
                        }
                        _ => f64::INFINITY,
                    }
                }
                Kind::Mul { k } => k.abs() * a * second * ROUNDING_MARGIN,
                Kind::Div { .. } => f64::INFINITY,
            };
            // NaN bounds (0 × inf) fail too.
            if v.is_nan() || v >= limit {
                return false;
            }
            b[f.known + c] = v;
        }
        f.rows.iter().all(|(_, form)| form_bound(&b, form) < limit)
    }

    /// The output `k` (not affine) at the states `x` and inputs `u`: the value
    /// [`PointForms::for_each`] gives, to the bit (the same operations on the same operands),
    /// computing only the nonlinear results it needs and that `cache` does not hold for the
    /// point `stamp` (not 0). None if `k` is an affine output.
    pub fn output(
        &self,
        m: &CompiledModel,
        (x, u): (&[f64], &[f64]),
        k: usize,
        (cache, stamp): (&mut PointCache, u64),
    ) -> Option<f64> {
        (k < self.outputs as usize).then(|| self.target(m, (x, u), k, (cache, stamp)))?
    }

    /// The row `i` of f (not affine) at the states `x` and inputs `u`, like
    /// [`PointForms::output`]. None if the row is affine.
    pub fn derivative(
        &self,
        m: &CompiledModel,
        (x, u): (&[f64], &[f64]),
        i: usize,
        (cache, stamp): (&mut PointCache, u64),
    ) -> Option<f64> {
        self.target(m, (x, u), self.outputs as usize + i, (cache, stamp))
    }

    fn target(
        &self,
        m: &CompiledModel,
        (x, u): (&[f64], &[f64]),
        target: usize,
        (cache, stamp): (&mut PointCache, u64),
    ) -> Option<f64> {
        let p = (*self.place.get(target)?)? as usize;
        let f = &self.forms;
        assert_eq!(x.len() + u.len(), f.known, "state and input lengths");
        assert_ne!(stamp, 0, "a point's stamp is not 0");
        let len = f.known + f.nonlinear.len();
        if cache.stamp != stamp || cache.w.len() != len {
            cache.w.resize(len, 0.0);
            cache.done.clear();
            cache.done.resize(f.nonlinear.len(), false);
            cache.w[..x.len()].copy_from_slice(x);
            cache.w[x.len()..f.known].copy_from_slice(u);
            cache.stamp = stamp;
        }
        let (start, end) = self.needs_of[p];
        for &c in &self.needs[start as usize..end as usize] {
            let c = c as usize;
            if !cache.done[c] {
                cache.w[f.known + c] = f.nonlinear_value(m, &cache.w, c);
                cache.done[c] = true;
            }
        }
        Some(f.dot(&cache.w, &f.rows[p].1))
    }
}
