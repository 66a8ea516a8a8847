//! Compilation of a causal bond graph into a flat evaluation plan, and the compiled model.

use std::cell::RefCell;

use nalgebra::DMatrix;

use super::causality::{self, Causality};
use super::dual::{Dual, Scalar};
use super::element::*;
use super::error::BondGraphError;
use super::graph::{BondGraph, StateOwner};
use super::structure::{analyse, Structure};
use super::validate::validate;

// ------------------------------------------------------------------ equations and plan

pub(super) const NONE: u32 = u32::MAX;

/// One equation `slot = expr`, before sorting.
#[derive(Clone, Debug)]
enum Expr {
    Const(f64),
    Lin(Vec<(f64, usize)>),
    Law {
        law: usize,
        arg: usize,
        ki: f64,
        ko: f64,
        modulator: Option<usize>,
    },
    /// `k a b`
    Mul {
        a: usize,
        b: usize,
        k: f64,
    },
    /// `k a / b`
    Div {
        a: usize,
        b: usize,
        k: f64,
    },
}

impl Expr {
    fn reads(&self) -> Vec<usize> {
        match self {
            Expr::Const(_) => vec![],
            Expr::Lin(t) => t.iter().map(|x| x.1).collect(),
            Expr::Law { arg, modulator, .. } => {
                let mut v = vec![*arg];
                v.extend(modulator.iter());
                v
            }
            Expr::Mul { a, b, .. } | Expr::Div { a, b, .. } => vec![*a, *b],
        }
    }
}

#[derive(Clone, Debug)]
struct Equation {
    dst: usize,
    expr: Expr,
    owner: String,
}

/// A flat operation of the evaluation plan.
#[derive(Clone, Copy, Debug)]
pub(super) enum Op {
    Const {
        dst: u32,
        c: f64,
    },
    Copy {
        dst: u32,
        src: u32,
    },
    Lin {
        dst: u32,
        start: u32,
        end: u32,
    },
    Law {
        dst: u32,
        law: u32,
        arg: u32,
        ki: f64,
        ko: f64,
        m: u32,
    },
    Mul {
        dst: u32,
        a: u32,
        b: u32,
        k: f64,
    },
    Div {
        dst: u32,
        a: u32,
        b: u32,
        k: f64,
    },
}

/// How a storage element contributes energy and power.
#[derive(Clone, Debug)]
enum Storage {
    /// One-port I or C: state index and law.
    One {
        name: String,
        state: usize,
        law: Law,
    },
    /// Field: energy `x' W x / 2` (W = M^-1 for an I-field, K for a C-field).
    Field {
        name: String,
        states: Vec<usize>,
        w: DMatrix<f64>,
    },
}

/// Power term of a source or resistor: `sign * e * f` (delivered for sources, dissipated for R).
#[derive(Clone, Debug)]
struct PowerTerm {
    name: String,
    e: usize,
    f: usize,
    sign: f64,
    source: bool,
}

/// Power balance of the model at a state: `stored_rate = source_power - dissipated_power`
/// (up to round-off), the bond-graph statement of energy conservation.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PowerBalance {
    /// `dE/dt`: rate of change of the total stored energy, `sum(dH/dx_i * dx_i/dt)` over the
    /// storage elements.
    pub stored_rate: f64,
    /// Power delivered by all sources (Se, Sf, modulated or not) into the graph.
    pub source_power: f64,
    /// Power dissipated in all resistors.
    pub dissipated_power: f64,
    /// `stored_rate - (source_power - dissipated_power)`; zero up to round-off.
    pub residual: f64,
    /// Per element: storage rate (I, C, fields), delivered power (sources), dissipated power (R).
    pub elements: Vec<(String, f64)>,
}

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
pub fn matrix_json(m: &DMatrix<f64>) -> serde_json::Value {
    serde_json::Value::Array(
        (0..m.nrows())
            .map(|i| serde_json::json!((0..m.ncols()).map(|j| m[(i, j)]).collect::<Vec<_>>()))
            .collect(),
    )
}

impl Linearization {
    /// JSON object `{state_names, input_names, output_names, x0, u0, a, b, c, d}` with the
    /// matrices as arrays of rows.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "state_names": self.state_names,
            "input_names": self.input_names,
            "output_names": self.output_names,
            "x0": self.x0,
            "u0": self.u0,
            "a": matrix_json(&self.a),
            "b": matrix_json(&self.b),
            "c": matrix_json(&self.c),
            "d": matrix_json(&self.d),
        })
    }
}

/// A compiled bond graph: state equations `dx/dt = f(x, u)` and outputs `y = g(x, u)` as a flat
/// plan of operations over slots, with exact derivatives.
///
/// States are the energy variables (momenta `p` of I elements, displacements `q` of C elements,
/// both for fields) and the integrator outputs, in creation order.
#[derive(Clone, Debug)]
pub struct CompiledModel {
    name: String,
    state_names: Vec<String>,
    input_names: Vec<String>,
    output_names: Vec<String>,
    bond_names: Vec<String>,
    n_slots: usize,
    ops: Vec<Op>,
    terms: Vec<(f64, u32)>,
    laws: Vec<NonlinearLaw>,
    deriv_slots: Vec<u32>,
    output_slots: Vec<u32>,
    bond_slots: Vec<(u32, u32)>,
    storages: Vec<Storage>,
    power_terms: Vec<PowerTerm>,
    effort_to_head: Vec<bool>,
    slot_names: Vec<String>,
    /// The plan before copy elimination, for [`CompiledModel::plan_listing`].
    listing_ops: Vec<Op>,
    listing_terms: Vec<(f64, u32)>,
    /// Derivative plan, Jacobian pattern and colouring, constancy of J.
    structure: Structure,
}

thread_local! {
    static WS_F64: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    static WS_DUAL: RefCell<Vec<Dual>> = const { RefCell::new(Vec::new()) };
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
        let nm = |k: u32| self.slot_names[k as usize].as_str();
        let mut out = String::new();
        for op in &self.listing_ops {
            let line = match *op {
                Op::Const { dst, c } => format!("{} = {c:e}", nm(dst)),
                Op::Copy { dst, src } => format!("{} = {}", nm(dst), nm(src)),
                Op::Lin { dst, start, end } => {
                    let t = &self.listing_terms[start as usize..end as usize];
                    let rhs = if t.is_empty() {
                        "0".to_string()
                    } else {
                        t.iter()
                            .enumerate()
                            .map(|(i, &(k, s))| {
                                let sign = if k < 0.0 {
                                    " - "
                                } else if i > 0 {
                                    " + "
                                } else {
                                    ""
                                };
                                let k = k.abs();
                                if k == 1.0 {
                                    format!("{sign}{}", nm(s))
                                } else {
                                    format!("{sign}{k:e}*{}", nm(s))
                                }
                            })
                            .collect::<String>()
                    };
                    format!("{} = {rhs}", nm(dst))
                }
                Op::Law {
                    dst,
                    law,
                    arg,
                    ki,
                    ko,
                    m,
                } => {
                    let l = &self.laws[law as usize].label;
                    let a = if ki == 1.0 {
                        nm(arg).to_string()
                    } else {
                        format!("{ki}*{}", nm(arg))
                    };
                    let mm = if m == NONE {
                        String::new()
                    } else {
                        format!(", {}", nm(m))
                    };
                    let k = if ko == 1.0 {
                        String::new()
                    } else {
                        format!("{ko}*")
                    };
                    format!("{} = {k}{l}({a}{mm})", nm(dst))
                }
                Op::Mul { dst, a, b, k } => {
                    format!("{} = {k}*{}*{}", nm(dst), nm(a), nm(b))
                }
                Op::Div { dst, a, b, k } => {
                    format!("{} = {k}*{}/{}", nm(dst), nm(a), nm(b))
                }
            };
            out.push_str(&line);
            out.push('\n');
        }
        out
    }
    /// Causality per bond: `true` if the causal stroke is at the head (the `to` element receives
    /// the effort).
    pub fn causal_strokes(&self) -> &[bool] {
        &self.effort_to_head
    }

    #[inline]
    fn run<T: Scalar>(&self, ops: &[Op], s: &mut [T]) {
        for op in ops {
            match *op {
                Op::Const { dst, c } => s[dst as usize] = T::cst(c),
                Op::Copy { dst, src } => s[dst as usize] = s[src as usize],
                Op::Lin { dst, start, end } => {
                    let mut acc = T::cst(0.0);
                    for &(k, src) in &self.terms[start as usize..end as usize] {
                        acc = acc + s[src as usize].scale(k);
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
                    let y = T::law(&self.laws[law as usize], s[arg as usize].scale(ki), mv);
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
    }

    fn check_dims(&self, x: &[f64], u: &[f64]) {
        assert_eq!(x.len(), self.n_states(), "state vector length");
        assert_eq!(u.len(), self.n_inputs(), "input vector length");
    }

    /// Runs the full plan (`ops`) or the derivative plan at `(x, u)` and hands the slots to `f`.
    fn with_f64<R>(&self, ops: &[Op], x: &[f64], u: &[f64], f: impl FnOnce(&[f64]) -> R) -> R {
        self.check_dims(x, u);
        WS_F64.with(|ws| {
            let mut ws = ws.borrow_mut();
            if ws.len() < self.n_slots {
                ws.resize(self.n_slots, 0.0);
            }
            let s = &mut ws[..self.n_slots];
            let n = x.len();
            s[..n].copy_from_slice(x);
            s[n..n + u.len()].copy_from_slice(u);
            self.run(ops, s);
            f(s)
        })
    }

    /// Evaluates `ops` with dual numbers seeded on the states and inputs `seeds` (index `i < n`
    /// is state `i`, `n + k` input `k`), ascending.
    fn with_dual<R>(
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
            self.run(ops, s);
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
    /// Entries outside [`CompiledModel::jacobian_pattern`] are zero.
    pub fn jacobian(&self, x: &[f64], u: &[f64], jac: &mut DMatrix<f64>) {
        let n = self.n_states();
        assert_eq!(jac.shape(), (n, n), "jacobian shape");
        jac.fill(0.0);
        let st = &self.structure;
        for (group, row_column) in st.colours.iter().zip(&st.row_column) {
            self.with_dual(&st.deriv_ops, x, u, group, |s| {
                for (i, &k) in self.deriv_slots.iter().enumerate() {
                    let j = row_column[i];
                    if j != NONE {
                        jac[(i, j as usize)] = s[k as usize].d;
                    }
                }
            });
        }
    }

    /// True if the Jacobian is the same at every `(x, u)`: the derivatives are affine in the
    /// states with constant coefficients (no product of two state-dependent quantities, of a
    /// state-dependent quantity and an input, no division by a state-dependent quantity, no
    /// nonlinear law of a state).
    pub fn jacobian_is_constant(&self) -> bool {
        self.structure.constant
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

    /// The states that hold energy (of I, C and field elements), ascending: those the stored
    /// energy depends on.
    pub fn storage_states(&self) -> Vec<usize> {
        let mut states: Vec<usize> = self
            .storages
            .iter()
            .flat_map(|st| match st {
                Storage::One { state, .. } => vec![*state],
                Storage::Field { states, .. } => states.clone(),
            })
            .collect();
        states.sort_unstable();
        states.dedup();
        states
    }

    /// Number of dual-number passes one Jacobian takes (groups of columns with no row in common).
    pub fn jacobian_colours(&self) -> usize {
        self.structure.colours.len()
    }

    /// Number of operations of the derivative plan (the full plan's is
    /// [`CompiledModel::plan_len`]).
    pub fn derivative_plan_len(&self) -> usize {
        self.structure.deriv_ops.len()
    }

    /// Exact linearisation at `(x, u)`.
    pub fn linearize(&self, x: &[f64], u: &[f64]) -> Linearization {
        let (n, m, p) = (self.n_states(), self.n_inputs(), self.n_outputs());
        let mut a = DMatrix::zeros(n, n);
        let mut b = DMatrix::zeros(n, m);
        let mut c = DMatrix::zeros(p, n);
        let mut d = DMatrix::zeros(p, m);
        for j in 0..n + m {
            self.with_dual(&self.ops, x, u, &[j as u32], |s| {
                for (i, &k) in self.deriv_slots.iter().enumerate() {
                    if j < n {
                        a[(i, j)] = s[k as usize].d;
                    } else {
                        b[(i, j - n)] = s[k as usize].d;
                    }
                }
                for (i, &k) in self.output_slots.iter().enumerate() {
                    if j < n {
                        c[(i, j)] = s[k as usize].d;
                    } else {
                        d[(i, j - n)] = s[k as usize].d;
                    }
                }
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

    /// Total energy stored in the I, C and field elements at state `x` (integrator states carry
    /// no energy). Nonlinear laws use their energy function if given
    /// ([`NonlinearLaw::with_energy`]), otherwise a Gauss-Legendre quadrature of the law from 0.
    pub fn stored_energy(&self, x: &[f64]) -> f64 {
        assert_eq!(x.len(), self.n_states(), "state vector length");
        self.storages.iter().map(|st| storage_energy(st, x)).sum()
    }

    /// Stored energy per storage element, in creation order.
    pub fn stored_energies(&self, x: &[f64]) -> Vec<(String, f64)> {
        self.storages
            .iter()
            .map(|st| {
                let name = match st {
                    Storage::One { name, .. } | Storage::Field { name, .. } => name.clone(),
                };
                (name, storage_energy(st, x))
            })
            .collect()
    }

    /// The derivative of the stored energy at `x` in the direction `v`, `sum(dH/dx_i v_i)`: the
    /// co-energy variables (efforts of C, flows of I elements) are the exact gradient of H.
    pub fn stored_energy_derivative(&self, x: &[f64], v: &[f64]) -> f64 {
        assert_eq!(x.len(), self.n_states(), "state vector length");
        assert_eq!(v.len(), self.n_states(), "direction length");
        self.storages.iter().map(|st| storage_rate(st, x, v)).sum()
    }

    /// Power balance at `(x, u)`.
    pub fn power_balance(&self, x: &[f64], u: &[f64]) -> PowerBalance {
        let mut dx = vec![0.0; self.n_states()];
        self.derivatives(x, u, &mut dx);
        self.with_f64(&self.ops, x, u, |s| {
            let mut elements = Vec::new();
            let mut stored_rate = 0.0;
            for st in &self.storages {
                let name = match st {
                    Storage::One { name, .. } | Storage::Field { name, .. } => name,
                };
                let r = storage_rate(st, x, &dx);
                stored_rate += r;
                elements.push((name.clone(), r));
            }
            let mut source_power = 0.0;
            let mut dissipated_power = 0.0;
            for t in &self.power_terms {
                let pw = t.sign * s[t.e] * s[t.f];
                if t.source {
                    source_power += pw;
                } else {
                    dissipated_power += pw;
                }
                elements.push((t.name.clone(), pw));
            }
            PowerBalance {
                stored_rate,
                source_power,
                dissipated_power,
                residual: stored_rate - (source_power - dissipated_power),
                elements,
            }
        })
    }
}

const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// `int_0^x phi(s) ds` by composite 8-point Gauss-Legendre on 16 panels.
fn quad_energy(law: &NonlinearLaw, x: f64) -> f64 {
    let panels = 16;
    let h = x / panels as f64;
    let mut sum = 0.0;
    for k in 0..panels {
        let a = k as f64 * h;
        for &(t, w) in &GL8 {
            sum += w * law.eval(a + 0.5 * h * (t + 1.0), 0.0).0;
        }
    }
    sum * 0.5 * h
}

/// `dH/dt` of one storage element at `x` when the states move at `v`: the co-energy variables
/// (`dH/dx`) dotted with `v`.
fn storage_rate(st: &Storage, x: &[f64], v: &[f64]) -> f64 {
    match st {
        Storage::One { state, law, .. } => {
            let co = match law {
                Law::Linear(k) => x[*state] / k,
                Law::Nonlinear(l) | Law::Conductance(l) => l.eval(x[*state], 0.0).0,
            };
            co * v[*state]
        }
        Storage::Field { states, w, .. } => {
            let mut r = 0.0;
            for (i, &si) in states.iter().enumerate() {
                let co: f64 = states
                    .iter()
                    .enumerate()
                    .map(|(j, &sj)| w[(i, j)] * x[sj])
                    .sum();
                r += co * v[si];
            }
            r
        }
    }
}

fn storage_energy(st: &Storage, x: &[f64]) -> f64 {
    match st {
        Storage::One { state, law, .. } => {
            let v = x[*state];
            match law {
                Law::Linear(k) => 0.5 * v * v / k,
                Law::Nonlinear(l) | Law::Conductance(l) => match &l.energy {
                    Some(e) => e(v),
                    None => quad_energy(l, v),
                },
            }
        }
        Storage::Field { states, w, .. } => {
            let mut e = 0.0;
            for (i, &si) in states.iter().enumerate() {
                for (j, &sj) in states.iter().enumerate() {
                    e += 0.5 * x[si] * w[(i, j)] * x[sj];
                }
            }
            e
        }
    }
}

// ------------------------------------------------------------------ compilation

struct Builder<'a> {
    g: &'a BondGraph,
    caus: Causality,
    eqs: Vec<Equation>,
    laws: Vec<NonlinearLaw>,
    n_states: usize,
    n_inputs: usize,
    next_slot: usize,
}

impl<'a> Builder<'a> {
    fn slot(&mut self) -> usize {
        self.next_slot += 1;
        self.next_slot - 1
    }
    fn e(&self, b: BondId) -> usize {
        self.n_states + self.n_inputs + 2 * b.0
    }
    fn f(&self, b: BondId) -> usize {
        self.n_states + self.n_inputs + 2 * b.0 + 1
    }
    fn eq(&mut self, dst: usize, expr: Expr, owner: &str) {
        self.eqs.push(Equation {
            dst,
            expr,
            owner: owner.to_string(),
        });
    }
    fn law(&mut self, l: &NonlinearLaw) -> usize {
        self.laws.push(l.clone());
        self.laws.len() - 1
    }
    fn receives(&self, b: BondId, e: ElementId) -> bool {
        self.caus.receives_effort(self.g, b, e)
    }
}

impl BondGraph {
    /// Validates the graph, assigns causality (SCAP) and compiles the state equations into a
    /// flat evaluation plan.
    pub fn compile(&self) -> Result<CompiledModel, BondGraphError> {
        validate(self)?;
        let caus = causality::assign(self)?;
        compile_causal(self, caus)
    }
}

fn compile_causal(g: &BondGraph, caus: Causality) -> Result<CompiledModel, BondGraphError> {
    // --- states
    let mut state_names = Vec::new();
    let mut elem_state: Vec<Option<usize>> = vec![None; g.elements.len()];
    let mut sig_state: Vec<Option<usize>> = vec![None; g.signals.len()];
    for owner in &g.state_order {
        match *owner {
            StateOwner::Element(e) => {
                let el = &g.elements[e.0];
                elem_state[e.0] = Some(state_names.len());
                match &el.kind {
                    ElementKind::I(_) => state_names.push(format!("{}.p", el.name)),
                    ElementKind::C(_) => state_names.push(format!("{}.q", el.name)),
                    ElementKind::IField(m) | ElementKind::CField(m) => {
                        let v = if matches!(el.kind, ElementKind::IField(_)) {
                            "p"
                        } else {
                            "q"
                        };
                        for k in 0..m.nrows() {
                            state_names.push(format!("{}.{v}[{}]", el.name, k + 1));
                        }
                    }
                    _ => unreachable!(),
                }
            }
            StateOwner::Integrator(s) => {
                sig_state[s.0] = Some(state_names.len());
                state_names.push(g.signals[s.0].name.clone());
            }
        }
    }
    let n = state_names.len();
    let input_names: Vec<String> = g
        .signals
        .iter()
        .filter(|s| matches!(s.kind, SignalKind::Input))
        .map(|s| s.name.clone())
        .collect();
    let m = input_names.len();
    let mut b = Builder {
        g,
        caus,
        eqs: Vec::new(),
        laws: Vec::new(),
        n_states: n,
        n_inputs: m,
        next_slot: n + m + 2 * g.bonds.len(),
    };

    // --- signal slots (inputs, integrators and sensors alias existing slots)
    let mut sig_slot = vec![usize::MAX; g.signals.len()];
    let mut input_k = 0;
    for (i, s) in g.signals.iter().enumerate() {
        sig_slot[i] = match &s.kind {
            SignalKind::Input => {
                input_k += 1;
                n + input_k - 1
            }
            SignalKind::Integrator(_) => sig_state[i].unwrap(),
            SignalKind::Sensor(Quantity::Effort(bd)) => b.e(*bd),
            SignalKind::Sensor(Quantity::Flow(bd)) => b.f(*bd),
            SignalKind::Sensor(Quantity::State(e, port)) => elem_state[e.0].unwrap() + port,
            _ => b.slot(),
        };
    }
    let value = |v: &SourceValue, k: f64| -> Expr {
        match v {
            SourceValue::Constant(c) => Expr::Const(k * c),
            SourceValue::Signal(s) => Expr::Lin(vec![(k, sig_slot[s.0])]),
        }
    };

    // --- derivative slots
    let mut deriv_slots = vec![0usize; n];
    for d in deriv_slots.iter_mut() {
        *d = b.slot();
    }

    // --- element equations
    let mut storages = Vec::new();
    let mut power_terms = Vec::new();
    for (i, el) in g.elements.iter().enumerate() {
        let id = ElementId(i);
        let name = el.name.as_str();
        let ports = g.ports(id);
        match &el.kind {
            ElementKind::Se(v) => {
                let (bd, sg) = ports[0];
                b.eq(b.e(bd), value(v, 1.0), name);
                power_terms.push(PowerTerm {
                    name: name.into(),
                    e: b.e(bd),
                    f: b.f(bd),
                    sign: -sg,
                    source: true,
                });
            }
            ElementKind::Sf(v) => {
                let (bd, sg) = ports[0];
                b.eq(b.f(bd), value(v, -sg), name);
                power_terms.push(PowerTerm {
                    name: name.into(),
                    e: b.e(bd),
                    f: b.f(bd),
                    sign: -sg,
                    source: true,
                });
            }
            ElementKind::I(law) | ElementKind::C(law) => {
                let is_i = matches!(el.kind, ElementKind::I(_));
                let (bd, sg) = ports[0];
                let st = elem_state[i].unwrap();
                // I: f_b = sigma phi(p), dp = e_b.  C: e_b = phi(q), dq = sigma f_b.
                let (out, ko) = if is_i { (b.f(bd), sg) } else { (b.e(bd), 1.0) };
                let expr = match law {
                    Law::Linear(k) => Expr::Lin(vec![(ko / k, st)]),
                    Law::Nonlinear(l) | Law::Conductance(l) => Expr::Law {
                        law: b.law(l),
                        arg: st,
                        ki: 1.0,
                        ko,
                        modulator: None,
                    },
                };
                b.eq(out, expr, name);
                let d = if is_i {
                    Expr::Lin(vec![(1.0, b.e(bd))])
                } else {
                    Expr::Lin(vec![(sg, b.f(bd))])
                };
                b.eq(deriv_slots[st], d, name);
                storages.push(Storage::One {
                    name: name.into(),
                    state: st,
                    law: law.clone(),
                });
            }
            ElementKind::R(law, modulator) => {
                let (bd, sg) = ports[0];
                let md = modulator.map(|s| sig_slot[s.0]);
                if b.receives(bd, id) {
                    // conductance causality: f_b = sigma phi(e_b)
                    let expr = match law {
                        Law::Linear(r) => Expr::Lin(vec![(sg / r, b.e(bd))]),
                        Law::Conductance(l) => Expr::Law {
                            law: b.law(l),
                            arg: b.e(bd),
                            ki: 1.0,
                            ko: sg,
                            modulator: md,
                        },
                        Law::Nonlinear(_) => {
                            return Err(BondGraphError::NonInvertibleLaw {
                                element: name.into(),
                                message: "causality requires the conductance form f = phi(e), but the law is given as e = phi(f) (Law::Nonlinear); give it as Law::Conductance or change the graph".into(),
                            })
                        }
                    };
                    b.eq(b.f(bd), expr, name);
                } else {
                    // resistance causality: e_b = phi(sigma f_b)
                    let expr = match law {
                        Law::Linear(r) => Expr::Lin(vec![(sg * r, b.f(bd))]),
                        Law::Nonlinear(l) => Expr::Law {
                            law: b.law(l),
                            arg: b.f(bd),
                            ki: sg,
                            ko: 1.0,
                            modulator: md,
                        },
                        Law::Conductance(_) => {
                            return Err(BondGraphError::NonInvertibleLaw {
                                element: name.into(),
                                message: "causality requires the resistance form e = phi(f), but the law is given as f = phi(e) (Law::Conductance); give it as Law::Nonlinear or change the graph".into(),
                            })
                        }
                    };
                    b.eq(b.e(bd), expr, name);
                }
                power_terms.push(PowerTerm {
                    name: name.into(),
                    e: b.e(bd),
                    f: b.f(bd),
                    sign: sg,
                    source: false,
                });
            }
            ElementKind::Tf(modulus) | ElementKind::Gy(modulus) => {
                let is_tf = matches!(el.kind, ElementKind::Tf(_));
                let p1 = ports.iter().find(|p| p.1 > 0.0).unwrap().0;
                let p2 = ports.iter().find(|p| p.1 < 0.0).unwrap().0;
                // y = m x  or  y = x / m
                let mul = |b: &mut Builder, dst: usize, x: usize, divide: bool| {
                    let expr = match modulus {
                        SourceValue::Constant(c) => {
                            Expr::Lin(vec![(if divide { 1.0 / c } else { *c }, x)])
                        }
                        SourceValue::Signal(s) => {
                            if divide {
                                Expr::Div {
                                    a: x,
                                    b: sig_slot[s.0],
                                    k: 1.0,
                                }
                            } else {
                                Expr::Mul {
                                    a: x,
                                    b: sig_slot[s.0],
                                    k: 1.0,
                                }
                            }
                        }
                    };
                    b.eq(dst, expr, name);
                };
                let r1 = b.receives(p1, id);
                let (e1, f1, e2, f2) = (b.e(p1), b.f(p1), b.e(p2), b.f(p2));
                if is_tf {
                    // e2 = m e1, f1 = m f2
                    if r1 {
                        mul(&mut b, e2, e1, false);
                        mul(&mut b, f1, f2, false);
                    } else {
                        mul(&mut b, e1, e2, true);
                        mul(&mut b, f2, f1, true);
                    }
                } else {
                    // e1 = r f2, e2 = r f1
                    if r1 {
                        mul(&mut b, f2, e1, true);
                        mul(&mut b, f1, e2, true);
                    } else {
                        mul(&mut b, e1, f2, false);
                        mul(&mut b, e2, f1, false);
                    }
                }
            }
            ElementKind::Zero | ElementKind::One => {
                let zero = matches!(el.kind, ElementKind::Zero);
                // the bond bringing the common variable in
                let k = ports
                    .iter()
                    .position(|(bd, _)| b.receives(*bd, id) == zero)
                    .expect("causality guarantees one strong bond");
                let (bk, sk) = ports[k];
                let (common_k, sum_k) = if zero {
                    (b.e(bk), b.f(bk))
                } else {
                    (b.f(bk), b.e(bk))
                };
                let mut terms = Vec::new();
                for (j, &(bj, sj)) in ports.iter().enumerate() {
                    if j == k {
                        continue;
                    }
                    let (common_j, sum_j) = if zero {
                        (b.e(bj), b.f(bj))
                    } else {
                        (b.f(bj), b.e(bj))
                    };
                    b.eq(common_j, Expr::Lin(vec![(1.0, common_k)]), name);
                    terms.push((-sk * sj, sum_j));
                }
                b.eq(sum_k, Expr::Lin(terms), name);
            }
            ElementKind::IField(mm) | ElementKind::CField(mm) => {
                let is_i = matches!(el.kind, ElementKind::IField(_));
                let st0 = elem_state[i].unwrap();
                let w = if is_i {
                    mm.clone().cholesky().expect("validated").inverse()
                } else {
                    mm.clone()
                };
                let states: Vec<usize> = (0..ports.len()).map(|k| st0 + k).collect();
                for (r, &(bd, sg)) in ports.iter().enumerate() {
                    let ko = if is_i { sg } else { 1.0 };
                    let terms = states
                        .iter()
                        .enumerate()
                        .filter(|(c, _)| w[(r, *c)] != 0.0)
                        .map(|(c, &s)| (ko * w[(r, c)], s))
                        .collect();
                    let (out, d) = if is_i {
                        (b.f(bd), Expr::Lin(vec![(1.0, b.e(bd))]))
                    } else {
                        (b.e(bd), Expr::Lin(vec![(sg, b.f(bd))]))
                    };
                    b.eq(out, Expr::Lin(terms), name);
                    b.eq(deriv_slots[states[r]], d, name);
                }
                storages.push(Storage::Field {
                    name: name.into(),
                    states,
                    w,
                });
            }
        }
    }

    // --- signal equations
    for (i, s) in g.signals.iter().enumerate() {
        let name = s.name.as_str();
        let dst = sig_slot[i];
        match &s.kind {
            SignalKind::Input | SignalKind::Sensor(_) => {}
            SignalKind::Constant(c) => b.eq(dst, Expr::Const(*c), name),
            SignalKind::Gain(k, input) => {
                b.eq(dst, Expr::Lin(vec![(*k, sig_slot[input.unwrap().0])]), name)
            }
            SignalKind::Sum(terms) => b.eq(
                dst,
                Expr::Lin(terms.iter().map(|(k, s)| (*k, sig_slot[s.0])).collect()),
                name,
            ),
            SignalKind::Product(a, c) => b.eq(
                dst,
                Expr::Mul {
                    a: sig_slot[a.0],
                    b: sig_slot[c.0],
                    k: 1.0,
                },
                name,
            ),
            SignalKind::Integrator(input) => {
                let st = sig_state[i].unwrap();
                b.eq(
                    deriv_slots[st],
                    Expr::Lin(vec![(1.0, sig_slot[input.unwrap().0])]),
                    name,
                )
            }
            SignalKind::Port(src) => {
                b.eq(dst, Expr::Lin(vec![(1.0, sig_slot[src.unwrap().0])]), name)
            }
            SignalKind::Function(law, input) => {
                let law = b.law(law);
                b.eq(
                    dst,
                    Expr::Law {
                        law,
                        arg: sig_slot[input.unwrap().0],
                        ki: 1.0,
                        ko: 1.0,
                        modulator: None,
                    },
                    name,
                )
            }
        }
    }

    // --- outputs
    let output_names = g.outputs.iter().map(|o| o.name.clone()).collect();
    let output_slots: Vec<u32> = g
        .outputs
        .iter()
        .map(|o| match o.source {
            OutputSource::Signal(s) => sig_slot[s.0],
            OutputSource::Quantity(Quantity::Effort(bd)) => b.e(bd),
            OutputSource::Quantity(Quantity::Flow(bd)) => b.f(bd),
            OutputSource::Quantity(Quantity::State(e, p)) => elem_state[e.0].unwrap() + p,
        } as u32)
        .collect();

    // --- sort
    let n_slots = b.next_slot;
    let order = sort_equations(&b.eqs, n_slots, n + m)?;

    // --- slot names, for the plan listing
    let mut slot_names = vec![String::new(); n_slots];
    for (k, nm) in state_names.iter().enumerate() {
        slot_names[k] = nm.clone();
        slot_names[deriv_slots[k]] = format!("d({nm})/dt");
    }
    for (k, nm) in input_names.iter().enumerate() {
        slot_names[n + k] = nm.clone();
    }
    for (k, bd) in g.bonds.iter().enumerate() {
        slot_names[b.e(BondId(k))] = format!("e({})", bd.name);
        slot_names[b.f(BondId(k))] = format!("f({})", bd.name);
    }
    for (k, sg) in g.signals.iter().enumerate() {
        if slot_names[sig_slot[k]].is_empty() {
            slot_names[sig_slot[k]] = sg.name.clone();
        }
    }

    // --- flatten
    let mut ops = Vec::with_capacity(order.len());
    let mut terms: Vec<(f64, u32)> = Vec::new();
    for &k in &order {
        let eq = &b.eqs[k];
        let dst = eq.dst as u32;
        ops.push(match &eq.expr {
            Expr::Const(c) => Op::Const { dst, c: *c },
            Expr::Lin(t) if t.len() == 1 && t[0].0 == 1.0 => Op::Copy {
                dst,
                src: t[0].1 as u32,
            },
            Expr::Lin(t) => {
                let start = terms.len() as u32;
                terms.extend(t.iter().map(|(k, s)| (*k, *s as u32)));
                Op::Lin {
                    dst,
                    start,
                    end: terms.len() as u32,
                }
            }
            Expr::Law {
                law,
                arg,
                ki,
                ko,
                modulator,
            } => Op::Law {
                dst,
                law: *law as u32,
                arg: *arg as u32,
                ki: *ki,
                ko: *ko,
                m: modulator.map(|x| x as u32).unwrap_or(NONE),
            },
            Expr::Mul { a, b, k } => Op::Mul {
                dst,
                a: *a as u32,
                b: *b as u32,
                k: *k,
            },
            Expr::Div { a, b, k } => Op::Div {
                dst,
                a: *a as u32,
                b: *b as u32,
                k: *k,
            },
        });
    }
    // --- copy elimination: a copied slot becomes an alias of its source. Every slot is written
    // once, before it is read, so the aliases are final as soon as they are set.
    let listing_ops = ops.clone();
    let listing_terms = terms.clone();
    let mut alias: Vec<u32> = (0..n_slots as u32).collect();
    let mut kept = Vec::with_capacity(ops.len());
    for op in ops {
        if let Op::Copy { dst, src } = op {
            alias[dst as usize] = alias[src as usize];
        } else {
            kept.push(op);
        }
    }
    let al = |k: u32| alias[k as usize];
    for op in kept.iter_mut() {
        match op {
            Op::Law { arg, m, .. } => {
                *arg = al(*arg);
                if *m != NONE {
                    *m = al(*m);
                }
            }
            Op::Mul { a, b, .. } | Op::Div { a, b, .. } => {
                *a = al(*a);
                *b = al(*b);
            }
            Op::Const { .. } | Op::Lin { .. } | Op::Copy { .. } => {}
        }
    }
    for t in terms.iter_mut() {
        t.1 = al(t.1);
    }
    let ops = kept;
    let deriv_slots: Vec<u32> = deriv_slots.iter().map(|&d| al(d as u32)).collect();
    let output_slots: Vec<u32> = output_slots.iter().map(|&d| al(d)).collect();
    for t in power_terms.iter_mut() {
        t.e = al(t.e as u32) as usize;
        t.f = al(t.f as u32) as usize;
    }
    let bond_slots = (0..g.bonds.len())
        .map(|i| (al(b.e(BondId(i)) as u32), al(b.f(BondId(i)) as u32)))
        .collect();
    let structure = analyse(
        &ops,
        &terms,
        n_slots,
        state_names.len(),
        input_names.len(),
        &deriv_slots,
    );
    Ok(CompiledModel {
        structure,
        name: g.name.clone(),
        state_names,
        input_names,
        output_names,
        bond_names: g.bonds.iter().map(|b| b.name.clone()).collect(),
        n_slots,
        ops,
        terms,
        laws: b.laws,
        deriv_slots,
        output_slots,
        bond_slots,
        storages,
        power_terms,
        effort_to_head: b.caus.effort_to_head,
        slot_names,
        listing_ops,
        listing_terms,
    })
}

/// Topological order of the equations; a cycle is an algebraic loop.
fn sort_equations(
    eqs: &[Equation],
    n_slots: usize,
    n_given: usize,
) -> Result<Vec<usize>, BondGraphError> {
    let mut producer = vec![usize::MAX; n_slots];
    for (k, eq) in eqs.iter().enumerate() {
        debug_assert!(
            producer[eq.dst] == usize::MAX,
            "slot written twice by '{}'",
            eq.owner
        );
        producer[eq.dst] = k;
    }
    let deps: Vec<Vec<usize>> = eqs
        .iter()
        .map(|eq| {
            eq.expr
                .reads()
                .into_iter()
                .filter(|&s| s >= n_given)
                .map(|s| {
                    let p = producer[s];
                    assert!(
                        p != usize::MAX,
                        "slot {s} read by '{}' is never computed",
                        eq.owner
                    );
                    p
                })
                .collect()
        })
        .collect();
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); eqs.len()];
    let mut indeg = vec![0usize; eqs.len()];
    for (k, d) in deps.iter().enumerate() {
        indeg[k] = d.len();
        for &p in d {
            users[p].push(k);
        }
    }
    let mut ready: Vec<usize> = (0..eqs.len()).filter(|&k| indeg[k] == 0).rev().collect();
    let mut order = Vec::with_capacity(eqs.len());
    while let Some(k) = ready.pop() {
        order.push(k);
        for &u in &users[k] {
            indeg[u] -= 1;
            if indeg[u] == 0 {
                ready.push(u);
            }
        }
    }
    if order.len() == eqs.len() {
        return Ok(order);
    }
    // Find a cycle among the unsorted equations: walk dependencies until one repeats.
    let left: Vec<bool> = indeg.iter().map(|&d| d > 0).collect();
    let start = (0..eqs.len()).find(|&k| left[k]).unwrap();
    let mut seen = vec![usize::MAX; eqs.len()];
    let mut path = Vec::new();
    let mut k = start;
    while seen[k] == usize::MAX {
        seen[k] = path.len();
        path.push(k);
        k = *deps[k].iter().find(|&&p| left[p]).unwrap();
    }
    let cycle = &path[seen[k]..];
    let mut elements: Vec<String> = Vec::new();
    for &c in cycle.iter().rev() {
        if !elements.contains(&eqs[c].owner) {
            elements.push(eqs[c].owner.clone());
        }
    }
    Err(BondGraphError::AlgebraicLoop { elements })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadrature_energy_is_accurate() {
        let law = NonlinearLaw::new("cubic", |q| (q + q * q * q, 1.0 + 3.0 * q * q));
        for q in [-2.0, -0.3, 0.0, 0.7, 5.0] {
            let exact = q * q / 2.0 + q * q * q * q / 4.0;
            assert!((quad_energy(&law, q) - exact).abs() <= 1e-13 * exact.abs().max(1.0));
        }
        let tanh = NonlinearLaw::new("tanh", |q: f64| (q.tanh(), 1.0 - q.tanh().powi(2)));
        let exact = 3.0f64.cosh().ln();
        assert!((quad_energy(&tanh, 3.0) - exact).abs() < 1e-12);
    }

    #[test]
    fn sorting_reports_the_cycle_only() {
        // slots: 0 = state; 1..=4 computed. 1 = x; 2 = 3 + 1; 3 = 2; 4 = 3 (downstream of the cycle)
        let eq = |dst, t: Vec<(f64, usize)>, o: &str| Equation {
            dst,
            expr: Expr::Lin(t),
            owner: o.into(),
        };
        let eqs = vec![
            eq(1, vec![(1.0, 0)], "a"),
            eq(2, vec![(1.0, 3), (1.0, 1)], "b"),
            eq(3, vec![(2.0, 2)], "c"),
            eq(4, vec![(1.0, 3)], "d"),
        ];
        match sort_equations(&eqs, 5, 1) {
            Err(BondGraphError::AlgebraicLoop { mut elements }) => {
                elements.sort();
                assert_eq!(elements, ["b", "c"]);
            }
            r => panic!("{r:?}"),
        }
        let ok = vec![
            eqs[0].clone(),
            eq(2, vec![(1.0, 1)], "b"),
            eq(3, vec![(1.0, 2)], "c"),
        ];
        assert_eq!(sort_equations(&ok, 5, 1).unwrap(), [0, 1, 2]);
    }
}
