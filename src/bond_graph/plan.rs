//! The evaluation plan: the equations lowering writes, and the flat operations they become.
//!
//! Lowering (`lower.rs`) turns every element and signal block of the causal graph into
//! equations `slot = expr` ([`Equation`], [`Expr`]) over numbered slots laid out as
//! `[states | inputs | effort, flow of each bond | signals, derivatives]`. Every slot is written
//! by one equation at most (states and inputs by none). Once the equations are sorted
//! (`sort.rs`), [`flatten`] turns them into [`Op`]s, with the terms of all linear combinations
//! in one shared array, and [`eliminate_copies`] drops the copies `a = b` (a junction's common
//! variable on each of its bonds, signal ports) by making each copied slot an alias of its
//! source. The compiled model (`compiled.rs`) runs the `Op`s in order, on `f64` or on dual
//! numbers; [`listing`] prints them for people to read.

use super::element::NonlinearLaw;
use crate::math::dual::Dual;

/// The slot of the effort of bond `b` in the layout above, `first` the number of states and
/// inputs before the bonds; its flow is the next slot.
pub(super) fn effort_slot(first: usize, b: usize) -> usize {
    first + 2 * b
}

/// "No slot" in an [`Op`] (a law without modulator) and in the structure's tables.
pub(super) const NONE: u32 = u32::MAX;

/// The right-hand side of an [`Equation`].
#[derive(Clone, Debug)]
pub(super) enum Expr {
    /// A constant, with its derivative along the parameter the model is built for.
    Const(Dual),
    /// `Σ k s`, each coefficient with its derivative.
    Lin(Vec<(Dual, usize)>),
    Law {
        law: usize,
        arg: usize,
        ki: f64,
        ko: f64,
        modulator: Option<usize>,
    },
    /// `k a b`
    Mul { a: usize, b: usize, k: f64 },
    /// `k a / b`
    Div { a: usize, b: usize, k: f64 },
}

impl Expr {
    /// The slots the expression reads.
    pub(super) fn reads(&self) -> Vec<usize> {
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

/// `dst = expr`, written by the element or signal block `owner` (named in errors).
#[derive(Clone, Debug)]
pub(super) struct Equation {
    pub(super) dst: usize,
    pub(super) expr: Expr,
    pub(super) owner: String,
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

/// The derivatives of the plan's constants with respect to the parameter the model was built
/// for (the [`Dual`] parts of the equations' constants), beside the plan's `f64` operations.
#[derive(Clone, Debug, Default)]
pub(super) struct ConstantDerivatives {
    /// `(dst, dc)` for each [`Op::Const`] whose constant has a nonzero derivative.
    pub(super) consts: Vec<(u32, f64)>,
    /// The derivative of each term's coefficient, in the order of the terms.
    pub(super) terms: Vec<f64>,
}

impl ConstantDerivatives {
    /// Whether every constant's derivative is zero (a model not built for a parameter).
    pub(super) fn all_zero(&self) -> bool {
        self.consts.is_empty() && self.terms.iter().all(|&d| d == 0.0)
    }
}

/// The sorted equations `eqs[order[..]]` as operations, the terms `(k, slot)` that the
/// [`Op::Lin`] operations index, and the constants' derivatives. A linear combination with the
/// single term `1 * src`, whose coefficient does not move with the parameter, becomes an
/// [`Op::Copy`].
pub(super) fn flatten(
    eqs: &[Equation],
    order: &[usize],
) -> (Vec<Op>, Vec<(f64, u32)>, ConstantDerivatives) {
    let mut ops = Vec::with_capacity(order.len());
    let mut terms: Vec<(f64, u32)> = Vec::new();
    let mut derivatives = ConstantDerivatives::default();
    for &k in order {
        let eq = &eqs[k];
        let dst = eq.dst as u32;
        ops.push(match &eq.expr {
            Expr::Const(c) => {
                if c.d != 0.0 {
                    derivatives.consts.push((dst, c.d));
                }
                Op::Const { dst, c: c.v }
            }
            Expr::Lin(t) if t.len() == 1 && t[0].0 == Dual::new(1.0, 0.0) => Op::Copy {
                dst,
                src: t[0].1 as u32,
            },
            Expr::Lin(t) => {
                let start = terms.len() as u32;
                terms.extend(t.iter().map(|(k, s)| (k.v, *s as u32)));
                derivatives.terms.extend(t.iter().map(|(k, _)| k.d));
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
    (ops, terms, derivatives)
}

/// Copy elimination: a copied slot becomes an alias of its source. Every slot is written once,
/// before it is read, so the aliases are final as soon as they are set. Returns the operations
/// without the copies, with the slots they and `terms` read renamed, and the alias of every slot
/// (for the slots the caller reads: derivatives, outputs, bonds, power terms).
pub(super) fn eliminate_copies(
    ops: Vec<Op>,
    terms: &mut [(f64, u32)],
    n_slots: usize,
) -> (Vec<Op>, Vec<u32>) {
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
    (kept, alias)
}

/// What names the slots of a plan besides the compiled model's states, inputs and bonds: the
/// slots of the state derivatives (before copy elimination) and of the signal blocks. The names
/// themselves are written only for the listing ([`SlotNames::names`]), not each time a model is
/// compiled.
#[derive(Clone, Debug)]
pub(super) struct SlotNames {
    /// The slot of each state's derivative, in state order.
    pub(super) derivatives: Vec<usize>,
    /// Each signal block's slot and name, in creation order.
    pub(super) signals: Vec<(u32, String)>,
}

impl SlotNames {
    /// The name of each of the `n_slots` slots: a state `x` and its derivative `d(x)/dt`, an
    /// input, the effort `e(b)` and flow `f(b)` of each bond `b` ([`effort_slot`]), then a signal
    /// block's name for a slot none of these names.
    pub(super) fn names(
        &self,
        n_slots: usize,
        states: &[String],
        inputs: &[String],
        bonds: &[String],
    ) -> Vec<String> {
        let mut names = vec![String::new(); n_slots];
        for (k, nm) in states.iter().enumerate() {
            names[k] = nm.clone();
            names[self.derivatives[k]] = format!("d({nm})/dt");
        }
        let n = states.len();
        for (k, nm) in inputs.iter().enumerate() {
            names[n + k] = nm.clone();
        }
        for (k, nm) in bonds.iter().enumerate() {
            let e = effort_slot(n + inputs.len(), k);
            names[e] = format!("e({nm})");
            names[e + 1] = format!("f({nm})");
        }
        for (slot, nm) in &self.signals {
            let name = &mut names[*slot as usize];
            if name.is_empty() {
                name.clone_from(nm);
            }
        }
        names
    }
}

/// The operations as text, one assignment per line, slots by their names (see
/// [`super::CompiledModel::plan_listing`]).
pub(super) fn listing(
    ops: &[Op],
    terms: &[(f64, u32)],
    laws: &[NonlinearLaw],
    slot_names: &[String],
) -> String {
    let nm = |k: u32| slot_names[k as usize].as_str();
    let mut out = String::new();
    for op in ops {
        let line = match *op {
            Op::Const { dst, c } => format!("{} = {c:e}", nm(dst)),
            Op::Copy { dst, src } => format!("{} = {}", nm(dst), nm(src)),
            Op::Lin { dst, start, end } => {
                let t = &terms[start as usize..end as usize];
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
                let l = &laws[law as usize].label;
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
