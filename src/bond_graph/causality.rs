//! Sequential causality assignment procedure (SCAP, Karnopp, Margolis & Rosenberg).
//!
//! Every bond gets a causal stroke: the end of the bond at which the effort is an *input* to the
//! element (that element computes the flow). The procedure:
//!
//! 1. sources: `Se` imposes the effort on its bond, `Sf` the flow; after each, the consequences
//!    are propagated through junctions and two-ports (0-junction: exactly one bond brings the
//!    effort in; 1-junction: exactly one bond brings the flow in; TF passes effort through, GY
//!    turns effort into flow);
//! 2. storage elements, in creation order, in integral causality (I receives the effort, C
//!    receives the flow), each followed by propagation. A storage element whose bond was already
//!    given the other causality by an earlier propagation is in derivative causality: this is an
//!    error ([`BondGraphError::DerivativeCausality`]) naming it and the element whose causality
//!    forced it;
//! 3. resistors not yet decided, in their preferred causality (linear: resistance form
//!    `e = R f`; nonlinear: the form the law is given in), each followed by propagation;
//! 4. any bond still undecided (junction-to-junction loops) arbitrarily, with propagation.
//!
//! Steps 3 and 4 can create algebraic loops; those are found when the equations are sorted
//! (see `compile`), and rejected with an error naming the elements on the loop.

use super::element::*;
use super::error::BondGraphError;
use super::graph::BondGraph;

/// Result of causality assignment: for every bond, whether the element at the head of the half
/// arrow (`to`) receives the effort as input (causal stroke at the head).
#[derive(Clone, Debug)]
pub(crate) struct Causality {
    pub effort_to_head: Vec<bool>,
}

impl Causality {
    /// Whether `elem` receives the effort on bond `b` (the causal stroke is at `elem`'s end).
    pub fn receives_effort(&self, g: &BondGraph, b: BondId, elem: ElementId) -> bool {
        let bond = &g.bonds[b.0];
        if bond.to == elem {
            self.effort_to_head[b.0]
        } else {
            !self.effort_to_head[b.0]
        }
    }
}

struct Scap<'a> {
    g: &'a BondGraph,
    ports: Vec<Vec<(BondId, f64)>>,
    head: Vec<Option<bool>>,
    cause: Vec<Option<ElementId>>,
    work: Vec<ElementId>,
}

impl<'a> Scap<'a> {
    fn name(&self, e: ElementId) -> String {
        self.g.elements[e.0].name.clone()
    }

    fn get(&self, b: BondId, elem: ElementId) -> Option<bool> {
        let bond = &self.g.bonds[b.0];
        self.head[b.0].map(|h| if bond.to == elem { h } else { !h })
    }

    /// Sets "elem receives the effort on b" = `receives`. `at` is the element applying the rule
    /// (for error messages), `cause` the element whose causality started the propagation.
    fn set(
        &mut self,
        b: BondId,
        elem: ElementId,
        receives: bool,
        at: ElementId,
        cause: ElementId,
    ) -> Result<(), BondGraphError> {
        let bond = &self.g.bonds[b.0];
        let h = if bond.to == elem { receives } else { !receives };
        match self.head[b.0] {
            Some(old) if old == h => Ok(()),
            Some(_) => {
                let mut involved = vec![];
                if let Some(c) = self.cause[b.0] {
                    involved.push(self.name(c));
                }
                for n in [self.name(cause), self.name(bond.from), self.name(bond.to)] {
                    if !involved.contains(&n) {
                        involved.push(n);
                    }
                }
                Err(BondGraphError::CausalConflict {
                    element: self.name(at),
                    involved,
                })
            }
            None => {
                self.head[b.0] = Some(h);
                self.cause[b.0] = Some(cause);
                self.work.push(bond.from);
                self.work.push(bond.to);
                Ok(())
            }
        }
    }

    fn causes(&self, bonds: impl Iterator<Item = BondId>) -> Vec<String> {
        let mut v: Vec<String> = Vec::new();
        for b in bonds {
            if let Some(c) = self.cause[b.0] {
                let n = self.name(c);
                if !v.contains(&n) {
                    v.push(n);
                }
            }
        }
        v
    }

    fn propagate(&mut self) -> Result<(), BondGraphError> {
        while let Some(e) = self.work.pop() {
            let kind = &self.g.elements[e.0].kind;
            let ports = self.ports[e.0].clone();
            match kind {
                ElementKind::Zero | ElementKind::One => {
                    // "special" = the one bond that brings the common variable in:
                    // 0-junction: the junction receives the effort; 1-junction: it does not.
                    let special_value = matches!(kind, ElementKind::Zero);
                    let special: Vec<BondId> = ports
                        .iter()
                        .filter(|(b, _)| self.get(*b, e) == Some(special_value))
                        .map(|(b, _)| *b)
                        .collect();
                    let open: Vec<BondId> = ports
                        .iter()
                        .filter(|(b, _)| self.get(*b, e).is_none())
                        .map(|(b, _)| *b)
                        .collect();
                    if special.len() > 1 {
                        return Err(BondGraphError::CausalConflict {
                            element: self.name(e),
                            involved: self.causes(special.into_iter()),
                        });
                    }
                    if special.len() == 1 {
                        let cause = self.cause[special[0].0].unwrap_or(e);
                        for b in open {
                            self.set(b, e, !special_value, e, cause)?;
                        }
                    } else if open.len() == 1 {
                        let cause = ports
                            .iter()
                            .rev()
                            .find_map(|(b, _)| self.cause[b.0])
                            .unwrap_or(e);
                        self.set(open[0], e, special_value, e, cause)?;
                    } else if open.is_empty() && !ports.is_empty() {
                        return Err(BondGraphError::CausalConflict {
                            element: self.name(e),
                            involved: self.causes(ports.iter().map(|p| p.0)),
                        });
                    }
                }
                ElementKind::Tf(_) | ElementKind::Gy(_) => {
                    if ports.len() != 2 {
                        continue;
                    }
                    let same = matches!(kind, ElementKind::Gy(_));
                    let (b0, b1) = (ports[0].0, ports[1].0);
                    match (self.get(b0, e), self.get(b1, e)) {
                        (Some(r0), None) => {
                            let c = self.cause[b0.0].unwrap_or(e);
                            self.set(b1, e, if same { r0 } else { !r0 }, e, c)?;
                        }
                        (None, Some(r1)) => {
                            let c = self.cause[b1.0].unwrap_or(e);
                            self.set(b0, e, if same { r1 } else { !r1 }, e, c)?;
                        }
                        (Some(r0), Some(r1)) => {
                            if (r0 == r1) != same {
                                return Err(BondGraphError::CausalConflict {
                                    element: self.name(e),
                                    involved: self.causes([b0, b1].into_iter()),
                                });
                            }
                        }
                        (None, None) => {}
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Integral causality for a storage port (`receives` = true for I, false for C).
    fn storage(&mut self, e: ElementId, receives: bool) -> Result<(), BondGraphError> {
        for (b, _) in self.ports[e.0].clone() {
            match self.get(b, e) {
                Some(r) if r != receives => {
                    let forced_by = self.causes(std::iter::once(b));
                    return Err(BondGraphError::DerivativeCausality {
                        element: self.name(e),
                        forced_by,
                    });
                }
                Some(_) => {}
                None => {
                    self.set(b, e, receives, e, e)?;
                    self.propagate()?;
                }
            }
        }
        Ok(())
    }
}

/// Runs SCAP on a structurally valid graph.
pub(crate) fn assign(g: &BondGraph) -> Result<Causality, BondGraphError> {
    let ports = g.port_table();
    let mut s = Scap {
        g,
        ports,
        head: vec![None; g.bonds.len()],
        cause: vec![None; g.bonds.len()],
        work: Vec::new(),
    };
    // 1. sources
    for (i, el) in g.elements.iter().enumerate() {
        let e = ElementId(i);
        let receives = match el.kind {
            ElementKind::Se(_) => false,
            ElementKind::Sf(_) => true,
            _ => continue,
        };
        for (b, _) in s.ports[i].clone() {
            s.set(b, e, receives, e, e)?;
        }
        s.propagate()?;
    }
    // 2. storage, integral causality, in creation order
    for (i, el) in g.elements.iter().enumerate() {
        let e = ElementId(i);
        match el.kind {
            ElementKind::I(_) | ElementKind::IField(_) => s.storage(e, true)?,
            ElementKind::C(_) | ElementKind::CField(..) => s.storage(e, false)?,
            _ => {}
        }
    }
    // 3. resistors in their preferred causality
    for (i, el) in g.elements.iter().enumerate() {
        let e = ElementId(i);
        if let ElementKind::R(law, _) = &el.kind {
            let receives = matches!(law, Law::Conductance(_));
            for (b, _) in s.ports[i].clone() {
                if s.get(b, e).is_none() {
                    s.set(b, e, receives, e, e)?;
                    s.propagate()?;
                }
            }
        }
    }
    // 4. remaining bonds, arbitrarily
    for b in 0..g.bonds.len() {
        if s.head[b].is_none() {
            let to = g.bonds[b].to;
            s.set(BondId(b), to, true, to, to)?;
            s.propagate()?;
        }
    }
    Ok(Causality {
        effort_to_head: s.head.into_iter().map(|h| h.unwrap_or(true)).collect(),
    })
}
