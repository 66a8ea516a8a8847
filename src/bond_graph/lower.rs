//! Lowering: from a causal bond graph to the equations of the plan, and on to a
//! [`CompiledModel`].
//!
//! [`BondGraph::compile`] validates the graph (`validate.rs`), assigns causality
//! (`causality.rs`), then `compile_causal` writes one equation per unknown: for each element,
//! the bond variable its causality makes it compute (a source its effort or flow, an I element
//! `f = phi(p)`, a C element `e = phi(q)`, an R element its law in resistance or conductance
//! form, a TF or GY one variable of each port from the other port's, a junction its common variable on every
//! other bond and the sum on the strong bond) and, for storage, the state derivative; then the
//! signal blocks and the outputs. It numbers the slots (`plan.rs` gives the layout), records the
//! storage elements and power terms for the energy balance (`energy.rs`), sorts the equations
//! (`sort.rs`), flattens them and eliminates the copies, and reads the structure of the result
//! (`structure.rs`). Signs follow the half arrows: `sg` is +1 for a bond pointing into the
//! element, -1 for one pointing out (see the module docs of `bond_graph`).

use super::causality::{self, Causality};
use super::compiled::CompiledModel;
use super::element::*;
use super::energy::{PowerTerm, Storage};
use super::error::BondGraphError;
use super::graph::{BondGraph, StateOwner};
use super::plan::{effort_slot, eliminate_copies, flatten, Equation, Expr, SlotNames};
use super::sort::sort_equations;
use super::structure::analyse;
use super::validate::validate;
use crate::math::dual::Dual;

/// A coefficient that does not move with the parameter (a sign, a one).
fn fixed(v: f64) -> Dual {
    Dual::from(v)
}

/// The equations written so far, and the slot numbering.
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
        effort_slot(self.n_states + self.n_inputs, b.0)
    }
    fn f(&self, b: BondId) -> usize {
        self.e(b) + 1
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
                    ElementKind::IField(m) | ElementKind::CField(m, _) => {
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
            SourceValue::Constant(c) => Expr::Const(*c * k),
            SourceValue::Signal(s) => Expr::Lin(vec![(fixed(k), sig_slot[s.0])]),
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
    let port_table = g.port_table();
    for (i, (el, ports)) in g.elements.iter().zip(port_table).enumerate() {
        let id = ElementId(i);
        let name = el.name.as_str();
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
                    Law::Linear(c) => Expr::Lin(vec![(ko / *c, st)]),
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
                    Expr::Lin(vec![(fixed(1.0), b.e(bd))])
                } else {
                    Expr::Lin(vec![(fixed(sg), b.f(bd))])
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
                        Law::Linear(r) => Expr::Lin(vec![(sg / *r, b.e(bd))]),
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
                        Law::Linear(r) => Expr::Lin(vec![(*r * sg, b.f(bd))]),
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
                            Expr::Lin(vec![(if divide { 1.0 / *c } else { *c }, x)])
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
                    b.eq(common_j, Expr::Lin(vec![(fixed(1.0), common_k)]), name);
                    terms.push((fixed(-sk * sj), sum_j));
                }
                b.eq(sum_k, Expr::Lin(terms), name);
            }
            ElementKind::IField(mm) | ElementKind::CField(mm, _) => {
                let is_i = matches!(el.kind, ElementKind::IField(_));
                let port_laws: &[Option<NonlinearLaw>] = match &el.kind {
                    ElementKind::CField(_, laws) => laws,
                    _ => &[],
                };
                let st0 = elem_state[i].unwrap();
                let w = if is_i {
                    mm.clone().cholesky().expect("validated").inverse()
                } else {
                    mm.clone()
                };
                // The derivative of W along the parameter: dK, or -M^-1 dM M^-1.
                let dw = g.field_derivative(id).map(|dm| {
                    if is_i {
                        -crate::math::product(&crate::math::product(&w, dm), &w)
                    } else {
                        dm.clone()
                    }
                });
                let dw_at = |r: usize, c: usize| dw.as_ref().map_or(0.0, |d| d[(r, c)]);
                let states: Vec<usize> = (0..ports.len()).map(|k| st0 + k).collect();
                let mut law_storages = Vec::new();
                for (r, &(bd, sg)) in ports.iter().enumerate() {
                    let ko = if is_i { sg } else { 1.0 };
                    let mut terms: Vec<(Dual, usize)> = states
                        .iter()
                        .enumerate()
                        .filter(|(c, _)| w[(r, *c)] != 0.0 || dw_at(r, *c) != 0.0)
                        .map(|(c, &s)| (Dual::new(w[(r, c)], dw_at(r, c)) * ko, s))
                        .collect();
                    // A port's own nonlinear law: phi_r(q_r) in a slot of its own, added to the
                    // row, and its energy a one-port storage on the same state.
                    if let Some(Some(law)) = port_laws.get(r) {
                        let slot = b.slot();
                        let expr = Expr::Law {
                            law: b.law(law),
                            arg: states[r],
                            ki: 1.0,
                            ko: 1.0,
                            modulator: None,
                        };
                        b.eq(slot, expr, name);
                        terms.push((fixed(1.0), slot));
                        law_storages.push(Storage::One {
                            name: format!("{name}.law[{}]", r + 1),
                            state: states[r],
                            law: Law::Nonlinear(law.clone()),
                        });
                    }
                    let (out, d) = if is_i {
                        (b.f(bd), Expr::Lin(vec![(fixed(1.0), b.e(bd))]))
                    } else {
                        (b.e(bd), Expr::Lin(vec![(fixed(sg), b.f(bd))]))
                    };
                    b.eq(out, Expr::Lin(terms), name);
                    b.eq(deriv_slots[states[r]], d, name);
                }
                storages.push(Storage::Field {
                    name: name.into(),
                    states,
                    w,
                });
                storages.append(&mut law_storages);
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
            SignalKind::Gain(gain, input) => b.eq(
                dst,
                Expr::Lin(vec![(*gain, sig_slot[input.unwrap().0])]),
                name,
            ),
            SignalKind::Sum(terms) => b.eq(
                dst,
                Expr::Lin(terms.iter().map(|(c, s)| (*c, sig_slot[s.0])).collect()),
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
                    Expr::Lin(vec![(fixed(1.0), sig_slot[input.unwrap().0])]),
                    name,
                )
            }
            SignalKind::Port(src) => b.eq(
                dst,
                Expr::Lin(vec![(fixed(1.0), sig_slot[src.unwrap().0])]),
                name,
            ),
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

    // --- what names the slots, for the plan listing (the names are written when it is asked for)
    let slot_names = SlotNames {
        derivatives: deriv_slots.clone(),
        signals: g
            .signals
            .iter()
            .enumerate()
            .map(|(k, sg)| (sig_slot[k] as u32, sg.name.clone()))
            .collect(),
    };

    // --- flatten, then alias the copies away (the listing shows the plan with its copies)
    let (ops, mut terms, derivatives) = flatten(&b.eqs, &order);
    let listing_ops = ops.clone();
    let listing_terms = terms.clone();
    let (ops, alias) = eliminate_copies(ops, &mut terms, n_slots);
    let al = |k: u32| alias[k as usize];
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
        &output_slots,
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
        constant_entries: None,
        constant_derivatives: (!derivatives.all_zero()).then_some(derivatives),
    })
}
