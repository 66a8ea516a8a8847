//! The compiled model: the flat plan and its evaluation.
//!
//! [`CompiledModel`] holds the plan that lowering (`lower.rs`) built: the operations over
//! numbered slots (`plan.rs`), the nonlinear laws they call, which slots hold the derivatives,
//! outputs and bond variables, and the structure read off the plan (`structure.rs`: the
//! derivative plan, the Jacobian's pattern and colouring). Evaluating is one loop over the
//! operations ([`CompiledModel::derivatives`] and the others), generic over the scalar so that the
//! same loop gives values (`f64`), exact derivatives (dual numbers, `dual.rs`) and the
//! linearisation's derivative along a parameter (hyper-dual numbers, `sensitivity.rs`). The slots live
//! in a per-thread scratch buffer, so running the plan allocates nothing once the buffer has
//! grown, and one model serves several threads at once. The energy and power balance are in `energy.rs`, the linearisation in
//! `linearization.rs`.

use std::cell::RefCell;

use nalgebra::DMatrix;

use super::dual::{Constants, Dual, Scalar, Values};
use super::element::NonlinearLaw;
use super::energy::{PowerTerm, Storage};
use super::plan::{Op, NONE};
use super::structure::Structure;
use super::tangent;

/// A compiled bond graph: state equations `dx/dt = f(x, u)` and outputs `y = g(x, u)` as a flat
/// plan of operations over slots, with exact derivatives.
///
/// States are the energy variables (momenta `p` of I elements, displacements `q` of C elements,
/// both for fields) and the integrator outputs, in creation order.
#[derive(Clone, Debug)]
pub struct CompiledModel {
    pub(super) name: String,
    pub(super) state_names: Vec<String>,
    pub(super) input_names: Vec<String>,
    pub(super) output_names: Vec<String>,
    pub(super) bond_names: Vec<String>,
    pub(super) n_slots: usize,
    pub(super) ops: Vec<Op>,
    pub(super) terms: Vec<(f64, u32)>,
    pub(super) laws: Vec<NonlinearLaw>,
    pub(super) deriv_slots: Vec<u32>,
    pub(super) output_slots: Vec<u32>,
    pub(super) bond_slots: Vec<(u32, u32)>,
    pub(super) storages: Vec<Storage>,
    pub(super) power_terms: Vec<PowerTerm>,
    pub(super) effort_to_head: Vec<bool>,
    /// What names the slots, for [`CompiledModel::plan_listing`].
    pub(super) slot_names: super::plan::SlotNames,
    /// The plan before copy elimination, for [`CompiledModel::plan_listing`].
    pub(super) listing_ops: Vec<Op>,
    pub(super) listing_terms: Vec<(f64, u32)>,
    /// Derivative plan, Jacobian pattern and colouring, constancy of J.
    pub(super) structure: Structure,
    /// The Jacobian's constant entries (zero elsewhere) once
    /// [`CompiledModel::fix_constant_entries`] has evaluated them.
    pub(super) constant_entries: Option<DMatrix<f64>>,
    /// The derivatives of the plan's constants with respect to the parameter the model was
    /// built for, when one is nonzero ([`CompiledModel::linearize_with_sensitivity`]).
    pub(super) constant_derivatives: Option<super::plan::ConstantDerivatives>,
}

/// The offsets `f_i(0, u)` of the affine rows and `y_k(0, u)` of the affine outputs as forms
/// ([`CompiledModel::affine_offset_forms`]).
#[derive(Clone, Debug, Default)]
pub struct AffineOffsets {
    rows: super::NonaffineForms,
    outputs: super::NonaffineForms,
}

impl AffineOffsets {
    /// The affine rows' offsets `f_i(0, u)` into their places in `dx` (the other entries left
    /// as they are), at the inputs `u` of `m`, the model the forms were made from.
    pub fn rows(&self, m: &CompiledModel, u: &[f64], dx: &mut [f64]) {
        assert_eq!(u.len(), m.n_inputs(), "input vector length");
        assert_eq!(dx.len(), m.n_states(), "derivative vector length");
        self.rows.evaluate(m, None, u, dx);
    }

    /// The affine outputs' offsets `y_k(0, u)` into their places in `y` (the other entries
    /// left as they are), at the inputs `u` of `m`, the model the forms were made from.
    pub fn outputs(&self, m: &CompiledModel, u: &[f64], y: &mut [f64]) {
        assert_eq!(u.len(), m.n_inputs(), "input vector length");
        assert_eq!(y.len(), m.n_outputs(), "output vector length");
        self.outputs.evaluate(m, None, u, y);
    }
}

thread_local! {
    static WS_F64: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    static WS_DUAL: RefCell<Vec<Dual>> = const { RefCell::new(Vec::new()) };
    static WS_SWEEP: RefCell<(Vec<f64>, Vec<tangent::Lanes>)> =
        const { RefCell::new((Vec::new(), Vec::new())) };
}

impl CompiledModel {
    /// Name of the graph it was compiled from.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Number of states.
    pub fn n_states(&self) -> usize {
        self.state_names.len()
    }
    /// Number of inputs.
    pub fn n_inputs(&self) -> usize {
        self.input_names.len()
    }
    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.output_names.len()
    }
    /// State names: `<I>.p`, `<C>.q`, `<field>.p[k]`, `<field>.q[k]` (1-based k), `<integrator>`.
    pub fn state_names(&self) -> &[String] {
        &self.state_names
    }
    /// Input names (the `add_input` signals, in creation order).
    pub fn input_names(&self) -> &[String] {
        &self.input_names
    }
    /// Output names, in creation order.
    pub fn output_names(&self) -> &[String] {
        &self.output_names
    }
    /// Bond names, in creation order.
    pub fn bond_names(&self) -> &[String] {
        &self.bond_names
    }
    /// Index of a state by name.
    pub fn state_index(&self, name: &str) -> Option<usize> {
        self.state_names.iter().position(|n| n == name)
    }
    /// Index of an input by name.
    pub fn input_index(&self, name: &str) -> Option<usize> {
        self.input_names.iter().position(|n| n == name)
    }
    /// Index of an output by name.
    pub fn output_index(&self, name: &str) -> Option<usize> {
        self.output_names.iter().position(|n| n == name)
    }
    /// Number of operations in the evaluation plan (after copy elimination).
    pub fn plan_len(&self) -> usize {
        self.ops.len()
    }

    /// The evaluation plan as text, one assignment per line in evaluation order, e.g.
    /// `d(loes.C3.q)/dt = f(loes.chamber->loes.C3)`: the state equations as derived from the
    /// graph, for people to read. `e(b)` and `f(b)` are the effort and flow of bond `b`.
    pub fn plan_listing(&self) -> String {
        super::plan::listing(
            &self.listing_ops,
            &self.listing_terms,
            &self.laws,
            &self.slot_names.names(
                self.n_slots,
                &self.state_names,
                &self.input_names,
                &self.bond_names,
            ),
        )
    }
    /// Causality per bond: `true` if the causal stroke is at the head (the `to` element receives
    /// the effort).
    pub fn causal_strokes(&self) -> &[bool] {
        &self.effort_to_head
    }

    /// Runs `ops` on the slots `s` (states and inputs set), the constants lifted by
    /// `constants`: the one loop of every pass, in values, dual and hyper-dual numbers.
    #[inline]
    pub(super) fn run<T: Scalar>(
        &self,
        ops: &[Op],
        constants: &impl Constants<T>,
        s: &mut [T],
    ) -> Result<(), T::Refusal> {
        for op in ops {
            match *op {
                Op::Const { dst, c } => s[dst as usize] = constants.constant(dst, c),
                Op::Copy { dst, src } => s[dst as usize] = s[src as usize],
                Op::Lin { dst, start, end } => {
                    let (start, end) = (start as usize, end as usize);
                    let mut acc = T::cst(0.0);
                    for (i, &(k, src)) in self.terms[start..end].iter().enumerate() {
                        acc = acc + constants.term(start + i, k, s[src as usize]);
                    }
                    s[dst as usize] = acc;
                }
                Op::Law {
                    dst,
                    law,
                    arg,
                    ki,
                    ko,
                    m,
                } => {
                    let mv = if m == NONE {
                        T::cst(0.0)
                    } else {
                        s[m as usize]
                    };
                    let y = T::law(&self.laws[law as usize], s[arg as usize].scale(ki), mv)?;
                    s[dst as usize] = y.scale(ko);
                }
                Op::Mul { dst, a, b, k } => {
                    s[dst as usize] = (s[a as usize] * s[b as usize]).scale(k)
                }
                Op::Div { dst, a, b, k } => {
                    s[dst as usize] = (s[a as usize] / s[b as usize]).scale(k)
                }
            }
        }
        Ok(())
    }

    fn check_dims(&self, x: &[f64], u: &[f64]) {
        assert_eq!(x.len(), self.n_states(), "state vector length");
        assert_eq!(u.len(), self.n_inputs(), "input vector length");
    }

    /// Runs the full plan (`ops`) or the derivative plan at `(x, u)` and hands the slots to `f`.
    pub(super) fn with_f64<R>(
        &self,
        ops: &[Op],
        x: &[f64],
        u: &[f64],
        f: impl FnOnce(&[f64]) -> R,
    ) -> R {
        self.check_dims(x, u);
        self.with_f64_slots(ops, Some(x), u, f)
    }

    /// [`CompiledModel::with_f64`] at the states `x`, or at x = 0 for `None`.
    fn with_f64_slots<R>(
        &self,
        ops: &[Op],
        x: Option<&[f64]>,
        u: &[f64],
        f: impl FnOnce(&[f64]) -> R,
    ) -> R {
        WS_F64.with(|ws| {
            let mut ws = ws.borrow_mut();
            if ws.len() < self.n_slots {
                ws.resize(self.n_slots, 0.0);
            }
            let s = &mut ws[..self.n_slots];
            let n = self.n_states();
            match x {
                Some(x) => s[..n].copy_from_slice(x),
                None => s[..n].fill(0.0),
            }
            s[n..n + u.len()].copy_from_slice(u);
            let Ok(()) = self.run(ops, &Values, s);
            f(s)
        })
    }

    /// Evaluates `ops` with dual numbers seeded on the states and inputs `seeds` (index `i < n`
    /// is state `i`, `n + k` input `k`), ascending.
    pub(super) fn with_dual<R>(
        &self,
        ops: &[Op],
        x: &[f64],
        u: &[f64],
        seeds: &[u32],
        f: impl FnOnce(&[Dual]) -> R,
    ) -> R {
        self.with_tangent(
            ops,
            x,
            u,
            |s| {
                for &k in seeds {
                    s[k as usize].d = 1.0;
                }
            },
            f,
        )
    }

    /// Evaluates `ops` with dual numbers whose tangents on the states and inputs `seed` sets
    /// (slot `i < n` is state `i`, `n + k` input `k`; all start at 0).
    fn with_tangent<R>(
        &self,
        ops: &[Op],
        x: &[f64],
        u: &[f64],
        seed: impl FnOnce(&mut [Dual]),
        f: impl FnOnce(&[Dual]) -> R,
    ) -> R {
        self.check_dims(x, u);
        WS_DUAL.with(|ws| {
            let mut ws = ws.borrow_mut();
            if ws.len() < self.n_slots {
                ws.resize(self.n_slots, Dual::default());
            }
            let s = &mut ws[..self.n_slots];
            for (i, v) in x.iter().chain(u.iter()).enumerate() {
                s[i] = Dual { v: *v, d: 0.0 };
            }
            seed(s);
            let Ok(()) = self.run(ops, &Values, s);
            f(s)
        })
    }

    /// State derivatives `dx = f(x, u)`.
    pub fn derivatives(&self, x: &[f64], u: &[f64], dx: &mut [f64]) {
        assert_eq!(dx.len(), self.n_states(), "derivative vector length");
        self.with_f64(&self.structure.deriv_ops, x, u, |s| {
            for (d, &k) in dx.iter_mut().zip(&self.deriv_slots) {
                *d = s[k as usize];
            }
        })
    }

    /// The derivatives of the rows that are not affine in x
    /// ([`CompiledModel::nonaffine_rows`]) into their places in `dx`, the other entries left as
    /// they are: one pass through the operations those rows need, with the same values as
    /// [`CompiledModel::derivatives`] gives them.
    pub fn nonaffine_derivatives(&self, x: &[f64], u: &[f64], dx: &mut [f64]) {
        assert_eq!(dx.len(), self.n_states(), "derivative vector length");
        let st = &self.structure;
        self.with_f64(&st.nonaffine_ops, x, u, |s| {
            for &i in &st.nonaffine_rows {
                let i = i as usize;
                dx[i] = s[self.deriv_slots[i] as usize];
            }
        })
    }

    /// The rows that are not affine ([`CompiledModel::nonaffine_rows`]) as sparse linear forms
    /// over the states, the inputs and the results of the nonlinear operations they need:
    /// [`super::NonaffineForms::derivatives`] gives the values of
    /// [`CompiledModel::nonaffine_derivatives`] to rounding, with a few dot products instead
    /// of a pass through the plan.
    pub fn nonaffine_forms(&self) -> super::NonaffineForms {
        let st = &self.structure;
        let rows: Vec<(u32, u32)> = st
            .nonaffine_rows
            .iter()
            .map(|&i| (i, self.deriv_slots[i as usize]))
            .collect();
        super::NonaffineForms::new(self, &st.nonaffine_ops, &rows)
    }

    /// The offsets of the affine rows and outputs as forms: [`AffineOffsets::rows`] and
    /// [`AffineOffsets::outputs`] give [`CompiledModel::affine_offsets`] and
    /// [`CompiledModel::affine_output_offsets`] to rounding, with a few dot products over the inputs and the nonlinear results they need
    /// instead of passes through the plan.
    pub fn affine_offset_forms(&self) -> AffineOffsets {
        let st = &self.structure;
        let affine = |slots: &[u32], nonaffine: &[u32]| -> Vec<(u32, u32)> {
            (0..slots.len() as u32)
                .filter(|i| nonaffine.binary_search(i).is_err())
                .map(|i| (i, slots[i as usize]))
                .collect()
        };
        AffineOffsets {
            rows: super::NonaffineForms::new(
                self,
                &st.affine_ops,
                &affine(&self.deriv_slots, &st.nonaffine_rows),
            ),
            outputs: super::NonaffineForms::new(
                self,
                &st.affine_output_ops,
                &affine(&self.output_slots, &st.nonaffine_outputs),
            ),
        }
    }

    /// The derivatives of the affine rows at x = 0, `f_i(0, u)`, into their places in `dx` (the
    /// entries of the other rows are left as they are): the offsets of `f_i = J_i x + f_i(0, u)`.
    pub fn affine_offsets(&self, u: &[f64], dx: &mut [f64]) {
        assert_eq!(dx.len(), self.n_states(), "derivative vector length");
        assert_eq!(u.len(), self.n_inputs(), "input vector length");
        let st = &self.structure;
        self.with_f64_slots(&st.affine_ops, None, u, |s| {
            for (i, (d, &k)) in dx.iter_mut().zip(&self.deriv_slots).enumerate() {
                if st.nonaffine_rows.binary_search(&(i as u32)).is_err() {
                    *d = s[k as usize];
                }
            }
        })
    }

    /// Calls `output(k, y_k)` for every output that is not affine in x
    /// ([`CompiledModel::nonaffine_outputs`]) and `derivative(i, dx_i/dt)` for every row that is
    /// not ([`CompiledModel::nonaffine_rows`]), from one pass through the operations they need
    /// (the same values as the full plan's).
    pub fn for_each_nonaffine_output_and_derivative(
        &self,
        x: &[f64],
        u: &[f64],
        mut output: impl FnMut(usize, f64),
        mut derivative: impl FnMut(usize, f64),
    ) {
        let st = &self.structure;
        self.with_f64(&st.nonaffine_point_ops, x, u, |s| {
            for &k in &st.nonaffine_outputs {
                output(k as usize, s[self.output_slots[k as usize] as usize]);
            }
            for &i in &st.nonaffine_rows {
                derivative(i as usize, s[self.deriv_slots[i as usize] as usize]);
            }
        })
    }

    /// The nonlinear laws the plan's `Law` operations call, in their order.
    pub fn laws(&self) -> &[NonlinearLaw] {
        &self.laws
    }

    /// The laws, to change one in a test (a law without its declared bound, say).
    #[cfg(test)]
    pub(crate) fn laws_mut(&mut self) -> &mut [NonlinearLaw] {
        &mut self.laws
    }

    /// The outputs and rows of [`CompiledModel::for_each_nonaffine_output_and_derivative`] as
    /// sparse linear forms ([`super::PointForms`]): the same values to rounding, with a few dot
    /// products instead of a pass through the plan.
    pub fn nonaffine_point_forms(&self) -> super::PointForms {
        let st = &self.structure;
        let outputs: Vec<(u32, u32)> = st
            .nonaffine_outputs
            .iter()
            .map(|&k| (k, self.output_slots[k as usize]))
            .collect();
        let rows: Vec<(u32, u32)> = st
            .nonaffine_rows
            .iter()
            .map(|&i| (i, self.deriv_slots[i as usize]))
            .collect();
        super::PointForms::new(self, &st.nonaffine_point_ops, &outputs, &rows)
    }

    /// The affine outputs at x = 0, `y_k(0, u)`, into their places in `y` (the others left as
    /// they are): the offsets of `y_k = C_k x + y_k(0, u)`.
    pub fn affine_output_offsets(&self, u: &[f64], y: &mut [f64]) {
        assert_eq!(y.len(), self.n_outputs(), "output vector length");
        assert_eq!(u.len(), self.n_inputs(), "input vector length");
        let st = &self.structure;
        self.with_f64_slots(&st.affine_output_ops, None, u, |s| {
            for (k, (d, &slot)) in y.iter_mut().zip(&self.output_slots).enumerate() {
                if st.nonaffine_outputs.binary_search(&(k as u32)).is_err() {
                    *d = s[slot as usize];
                }
            }
        })
    }

    /// Derivatives and outputs from one pass through the plan.
    pub fn evaluate(&self, x: &[f64], u: &[f64], dx: &mut [f64], y: &mut [f64]) {
        assert_eq!(dx.len(), self.n_states(), "derivative vector length");
        assert_eq!(y.len(), self.n_outputs(), "output vector length");
        self.with_f64(&self.ops, x, u, |s| {
            for (d, &k) in dx.iter_mut().zip(&self.deriv_slots) {
                *d = s[k as usize];
            }
            for (d, &k) in y.iter_mut().zip(&self.output_slots) {
                *d = s[k as usize];
            }
        })
    }

    /// Outputs `y = g(x, u)`, in [`CompiledModel::output_names`] order.
    pub fn outputs(&self, x: &[f64], u: &[f64], y: &mut [f64]) {
        assert_eq!(y.len(), self.n_outputs(), "output vector length");
        self.with_f64(&self.ops, x, u, |s| {
            for (d, &k) in y.iter_mut().zip(&self.output_slots) {
                *d = s[k as usize];
            }
        })
    }

    /// Calls `output(k, y_k)` for every output and `derivative(i, dx_i/dt)` for every state,
    /// from one pass through the plan (no allocation).
    pub fn for_each_output_and_derivative(
        &self,
        x: &[f64],
        u: &[f64],
        mut output: impl FnMut(usize, f64),
        mut derivative: impl FnMut(usize, f64),
    ) {
        self.with_f64(&self.ops, x, u, |s| {
            for (k, &slot) in self.output_slots.iter().enumerate() {
                output(k, s[slot as usize]);
            }
            for (i, &slot) in self.deriv_slots.iter().enumerate() {
                derivative(i, s[slot as usize]);
            }
        })
    }

    /// Exact directional derivatives at `(x, u)` in the direction `(vx, vu)`: `ddx = A vx + B vu`
    /// and `dy = C vx + D vu`, from one forward pass of dual numbers through the plan (the
    /// Jacobian is never formed).
    pub fn directional(
        &self,
        x: &[f64],
        u: &[f64],
        (vx, vu): (&[f64], &[f64]),
        ddx: &mut [f64],
        dy: &mut [f64],
    ) {
        assert_eq!(vx.len(), self.n_states(), "state direction length");
        assert_eq!(vu.len(), self.n_inputs(), "input direction length");
        assert_eq!(ddx.len(), self.n_states(), "derivative vector length");
        assert_eq!(dy.len(), self.n_outputs(), "output vector length");
        let seed = |s: &mut [Dual]| {
            for (slot, v) in s.iter_mut().zip(vx.iter().chain(vu)) {
                slot.d = *v;
            }
        };
        self.with_tangent(&self.ops, x, u, seed, |s| {
            for (d, &k) in ddx.iter_mut().zip(&self.deriv_slots) {
                *d = s[k as usize].d;
            }
            for (d, &k) in dy.iter_mut().zip(&self.output_slots) {
                *d = s[k as usize].d;
            }
        });
    }

    /// Calls `each(k, y_k)` for every output, in [`CompiledModel::output_names`] order (no
    /// allocation).
    pub fn for_each_output(&self, x: &[f64], u: &[f64], mut each: impl FnMut(usize, f64)) {
        self.with_f64(&self.ops, x, u, |s| {
            for (k, &slot) in self.output_slots.iter().enumerate() {
                each(k, s[slot as usize]);
            }
        })
    }

    /// Efforts and flows of all bonds (bond creation order), for inspection.
    pub fn bond_values(&self, x: &[f64], u: &[f64], e: &mut [f64], f: &mut [f64]) {
        self.with_f64(&self.ops, x, u, |s| {
            for (i, &(se, sf)) in self.bond_slots.iter().enumerate() {
                e[i] = s[se as usize];
                f[i] = s[sf as usize];
            }
        })
    }

    /// Exact Jacobian `df/dx`: forward-mode dual numbers through the derivative plan, one pass
    /// per group of structurally independent columns (see [`CompiledModel::jacobian_colours`]).
    /// Entries outside [`CompiledModel::jacobian_pattern`] are zero. After
    /// [`CompiledModel::fix_constant_entries`], the constant entries are copied and only the
    /// varying ones evaluated ([`CompiledModel::variable_jacobian_colours`] passes), with the
    /// same bits.
    pub fn jacobian(&self, x: &[f64], u: &[f64], jac: &mut DMatrix<f64>) {
        let n = self.n_states();
        assert_eq!(jac.shape(), (n, n), "jacobian shape");
        let st = &self.structure;
        match &self.constant_entries {
            None => {
                jac.fill(0.0);
                for (group, row_column) in st.colours.iter().zip(&st.row_column) {
                    self.jacobian_pass(&st.deriv_ops, group, row_column, x, u, jac);
                }
            }
            Some(fixed) => {
                jac.copy_from(fixed);
                self.varying_entries(x, u, jac);
            }
        }
    }

    /// The varying entries into `jac`: by the value pass and tangent sweeps of
    /// [`CompiledModel::jacobian_varying_by_sweeps`], or by the dual passes where that
    /// declines.
    fn varying_entries(&self, x: &[f64], u: &[f64], jac: &mut DMatrix<f64>) {
        if !self.jacobian_varying_by_sweeps(x, u, jac) {
            self.jacobian_varying_by_passes(x, u, jac);
        }
    }

    /// The varying entries into `jac` by one dual-number pass per group of the variable
    /// colouring, each through the operations the rows it reads need: the reference for
    /// [`CompiledModel::jacobian_varying_by_sweeps`].
    #[doc(hidden)]
    pub fn jacobian_varying_by_passes(&self, x: &[f64], u: &[f64], jac: &mut DMatrix<f64>) {
        let n = self.n_states();
        assert_eq!(jac.shape(), (n, n), "jacobian shape");
        let st = &self.structure;
        let passes = st.variable_colours.iter().zip(&st.variable_row_column);
        for ((group, row_column), ops) in passes.zip(&st.variable_ops) {
            self.jacobian_pass(ops, group, row_column, x, u, jac);
        }
    }

    /// The varying entries into `jac` with the bits of
    /// [`CompiledModel::jacobian_varying_by_passes`], from one value pass and tangent sweeps
    /// of [`LANES`](tangent::LANES) groups at a time (`tangent.rs`): the values and the laws' partial derivatives are
    /// computed once, and each sweep carries tangents only through the operations its seeds
    /// reach. Returns false, with `jac` as it was, where a zero tangent is NaN (a value that
    /// is not finite, or 0/0): then the dual passes must give the entries.
    #[doc(hidden)]
    pub fn jacobian_varying_by_sweeps(&self, x: &[f64], u: &[f64], jac: &mut DMatrix<f64>) -> bool {
        self.check_dims(x, u);
        let n = self.n_states();
        assert_eq!(jac.shape(), (n, n), "jacobian shape");
        let sw = &self.structure.tangents;
        let slots = self.n_slots;
        WS_SWEEP.with(|ws| {
            let mut ws = ws.borrow_mut();
            let (values, lanes) = &mut *ws;
            if values.len() < 3 * slots {
                values.resize(3 * slots, 0.0);
            }
            if lanes.len() < 2 * slots + 1 {
                lanes.resize(2 * slots + 1, [0.0; tangent::LANES]);
            }
            let (v, rest) = values.split_at_mut(slots);
            let (pdx, pdm) = rest.split_at_mut(slots);
            let pdm = &mut pdm[..slots];
            let t = &mut lanes[..2 * slots + 1];
            if !tangent::value_pass(&sw.value_ops, &self.terms, &self.laws, x, u, v, t, pdx, pdm) {
                return false;
            }
            for sweep in &sw.sweeps {
                tangent::run_sweep(sweep, &sw.terms, (v, pdx, pdm), t, |i, j, d| {
                    jac[(i, j)] = d;
                });
            }
            true
        })
    }

    /// Overwrites only the Jacobian's varying entries (the passes over the variable columns of
    /// [`CompiledModel::jacobian`]), for a `jac` that already holds the constant ones, as a
    /// `jac` written by [`CompiledModel::jacobian`] after [`CompiledModel::fix_constant_entries`]
    /// does: the same bits as a full evaluation, without its copy of the n × n constant part.
    /// Returns whether the varying entries are finite.
    ///
    /// # Panics
    /// If the constant entries have not been fixed.
    pub fn jacobian_varying(&self, x: &[f64], u: &[f64], jac: &mut DMatrix<f64>) -> bool {
        let n = self.n_states();
        assert_eq!(jac.shape(), (n, n), "jacobian shape");
        assert!(
            self.constant_entries.is_some(),
            "jacobian_varying before fix_constant_entries"
        );
        self.varying_entries(x, u, jac);
        self.structure
            .varying
            .iter()
            .enumerate()
            .all(|(i, row)| row.iter().all(|&j| jac[(i, j as usize)].is_finite()))
    }

    /// One dual-number pass through `ops` with the columns `group` seeded, writing the entry
    /// `(i, row_column[i])` of each row that has one.
    fn jacobian_pass(
        &self,
        ops: &[Op],
        group: &[u32],
        row_column: &[u32],
        x: &[f64],
        u: &[f64],
        jac: &mut DMatrix<f64>,
    ) {
        self.with_dual(ops, x, u, group, |s| {
            for (i, &k) in self.deriv_slots.iter().enumerate() {
                let j = row_column[i];
                if j != NONE {
                    jac[(i, j as usize)] = s[k as usize].d;
                }
            }
        });
    }

    /// Evaluates the Jacobian's constant entries at `(x, u)` and keeps them: afterwards
    /// [`CompiledModel::jacobian`] copies them and runs only the passes over the variable
    /// columns. Call it once per parameter set (any point with finite values will do).
    ///
    /// Why the bits are those of a full evaluation at any point: in the pass that delivers a
    /// constant entry `(i, j)`, the tangent reaching row `i` comes from column `j` alone (the
    /// colouring keeps the other seeds of the group off row `i`), along operations whose
    /// tangent coefficients do not depend on the point (the constant coefficients of `Lin`, a
    /// factor or divisor that depends on neither the states nor the inputs; see the rules in
    /// `structure.rs`). The same floating-point operations on the same numbers give the same
    /// result at every point. The point enters only as `v * 0`, where a state-dependent value
    /// `v` meets the zero tangent of such a constant factor, and adding a zero leaves a
    /// non-zero tangent as it is: only an entry that is exactly zero (a structural non-zero that
    /// cancels, or a zero parameter) could come out as `-0.0` at one point and `0.0` at another,
    /// which compare equal. At a point with a non-finite value the full evaluation may give NaN
    /// where the kept entry is finite (`inf * 0`). The varying entries are evaluated at every
    /// call, each by a pass restricted to the operations the rows it reads need (the same
    /// operations in the same order, so the same values and tangents).
    pub fn fix_constant_entries(&mut self, x: &[f64], u: &[f64]) {
        let n = self.n_states();
        let mut jac = DMatrix::zeros(n, n);
        self.constant_entries = None;
        self.jacobian(x, u, &mut jac);
        for (i, row) in self.structure.varying.iter().enumerate() {
            for &j in row {
                jac[(i, j as usize)] = 0.0;
            }
        }
        self.constant_entries = Some(jac);
    }

    /// True once [`CompiledModel::fix_constant_entries`] has kept the constant entries.
    pub fn constant_entries_fixed(&self) -> bool {
        self.constant_entries.is_some()
    }

    /// For each row `i` of the Jacobian, the columns `j` whose entry may vary with `(x, u)`
    /// (a subset of [`CompiledModel::jacobian_pattern`]; the others are the same everywhere).
    pub fn jacobian_varying_pattern(&self) -> &[Vec<u32>] {
        &self.structure.varying
    }

    /// The variable columns of the Jacobian (those with a varying entry), ascending.
    pub fn jacobian_variable_columns(&self) -> Vec<u32> {
        let mut cols: Vec<u32> = self.structure.varying.concat();
        cols.sort_unstable();
        cols.dedup();
        cols
    }

    /// True if the Jacobian is the same at every `(x, u)`: the derivatives are affine in the
    /// states with constant coefficients (no product of two state-dependent quantities, of a
    /// state-dependent quantity and an input, no division by a state-dependent quantity, no
    /// nonlinear law of a state).
    pub fn jacobian_is_constant(&self) -> bool {
        self.structure.constant
    }

    /// True if every output is affine in the states with coefficients independent of x and u
    /// (`y(x, u) = C x + y(0, u)`, by the rules of [`CompiledModel::jacobian_is_constant`]).
    pub fn outputs_are_affine(&self) -> bool {
        self.structure.nonaffine_outputs.is_empty()
    }

    /// For each row `i` of the Jacobian, the states `dx_i/dt` depends on structurally.
    pub fn jacobian_pattern(&self) -> &[Vec<u32>] {
        &self.structure.pattern
    }

    /// The structural dependencies of the derivatives and of the outputs: for each derivative
    /// (state order) and each output, the states `i < n` and inputs `n + k` it depends on
    /// through the plan, ascending. A superset of the non-zero pattern of the linearisation at
    /// any point.
    pub fn dependencies(&self) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
        let known = self.n_states() + self.n_inputs();
        let run = |targets: &[u32]| {
            super::structure::dependencies(&self.ops, &self.terms, self.n_slots, known, targets)
        };
        (run(&self.deriv_slots), run(&self.output_slots))
    }

    /// Number of dual-number passes a full Jacobian takes (groups of columns with no row in
    /// common): one evaluation without [`CompiledModel::fix_constant_entries`].
    pub fn jacobian_colours(&self) -> usize {
        self.structure.colours.len()
    }

    /// Number of dual-number passes a Jacobian takes once the constant entries are fixed
    /// ([`CompiledModel::fix_constant_entries`]): groups of the variable columns.
    pub fn variable_jacobian_colours(&self) -> usize {
        self.structure.variable_colours.len()
    }

    /// Number of operations a Jacobian runs once the constant entries are fixed: those of
    /// the value pass and of the tangent sweeps (one per group, each through the operations of
    /// the rows it reads that its seeds reach; see
    /// [`CompiledModel::jacobian_varying_by_sweeps`]); a full Jacobian runs
    /// [`CompiledModel::jacobian_colours`] times [`CompiledModel::derivative_plan_len`].
    pub fn variable_jacobian_ops(&self) -> usize {
        let sweeps = &self.structure.tangents;
        sweeps.value_ops.len() + sweeps.len()
    }

    /// Number of operations the dual passes over the variable columns run in all (each runs
    /// the operations the rows it reads need): the work the tangent sweeps replace.
    pub fn variable_jacobian_pass_ops(&self) -> usize {
        self.structure.variable_ops.iter().map(Vec::len).sum()
    }

    /// The rows `i` whose derivative `dx_i/dt` is not affine in x with constant coefficients
    /// (by the rules of [`CompiledModel::jacobian_is_constant`]), ascending: the servo valve's
    /// nonlinear orifices and laws; every other row is `J_i x + f_i(0, u)` with `J_i` among
    /// the constant entries.
    pub fn nonaffine_rows(&self) -> &[u32] {
        &self.structure.nonaffine_rows
    }

    /// The constant entries of the Jacobian (zero at the varying ones), once
    /// [`CompiledModel::fix_constant_entries`] has evaluated them.
    pub fn constant_entries(&self) -> Option<&DMatrix<f64>> {
        self.constant_entries.as_ref()
    }

    /// The outputs `k` that are not affine in x with constant coefficients, ascending (see
    /// [`CompiledModel::outputs_are_affine`]).
    pub fn nonaffine_outputs(&self) -> &[u32] {
        &self.structure.nonaffine_outputs
    }

    /// Number of operations [`CompiledModel::for_each_nonaffine_output_and_derivative`] runs.
    pub fn nonaffine_point_plan_len(&self) -> usize {
        self.structure.nonaffine_point_ops.len()
    }

    /// Number of operations [`CompiledModel::nonaffine_derivatives`] runs.
    pub fn nonaffine_plan_len(&self) -> usize {
        self.structure.nonaffine_ops.len()
    }

    /// Number of operations of the derivative plan (the full plan's is
    /// [`CompiledModel::plan_len`]).
    pub fn derivative_plan_len(&self) -> usize {
        self.structure.deriv_ops.len()
    }
}
