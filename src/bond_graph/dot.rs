//! Graphviz DOT export.

use std::fmt::Write;

use super::causality;
use super::element::*;
use super::graph::BondGraph;
use super::validate::validate;

fn esc(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

fn fmt_law(l: &Law) -> String {
    match l {
        Law::Linear(v) => format!("{v:.4e}"),
        Law::Nonlinear(n) | Law::Conductance(n) => n.label.clone(),
    }
}

fn fmt_value(v: &SourceValue, g: &BondGraph) -> String {
    match v {
        SourceValue::Constant(c) => format!("{c:.4e}"),
        SourceValue::Signal(s) => g.signals[s.0].name.clone(),
    }
}

impl BondGraph {
    /// Graphviz DOT text of the graph: elements as nodes, bonds as edges with a half arrow at
    /// the head (power direction) and, when causality can be assigned, the causal stroke (a
    /// `tee`) at the end where the effort is an input; signals as dashed arrows. If causality
    /// assignment fails, the graph is drawn without strokes and the error is given in a
    /// comment and as the graph label.
    pub fn to_dot(&self) -> String {
        let caus = validate(self).and_then(|_| causality::assign(self));
        let mut s = String::new();
        let _ = writeln!(s, "digraph \"{}\" {{", esc(&self.name));
        let _ = writeln!(s, "  rankdir=LR;");
        let _ = writeln!(s, "  node [shape=plaintext, fontname=\"Helvetica\"];");
        if let Err(e) = &caus {
            let _ = writeln!(s, "  // causality: {}", esc(&e.to_string()));
            let _ = writeln!(s, "  label=\"{}\";", esc(&e.to_string()));
        }
        for (i, el) in self.elements.iter().enumerate() {
            let param = match &el.kind {
                ElementKind::Se(v) | ElementKind::Sf(v) => fmt_value(v, self),
                ElementKind::I(l) | ElementKind::C(l) | ElementKind::R(l, _) => fmt_law(l),
                ElementKind::Tf(v) | ElementKind::Gy(v) => fmt_value(v, self),
                ElementKind::IField(m) | ElementKind::CField(m, _) => {
                    format!("{}x{}", m.nrows(), m.ncols())
                }
                ElementKind::Zero | ElementKind::One => String::new(),
            };
            let label = match &el.kind {
                ElementKind::Zero | ElementKind::One => el.kind.label().to_string(),
                _ => format!("{}: {}\\n{}", el.kind.label(), el.name, param),
            };
            let _ = writeln!(
                s,
                "  e{i} [label=\"{}\", tooltip=\"{}\"];",
                esc(&label).replace("\\\\n", "\\n"),
                esc(&el.name)
            );
        }
        for (i, sg) in self.signals.iter().enumerate() {
            let extra = match &sg.kind {
                SignalKind::Gain(k, _) => format!("\\n{k:.4e}"),
                SignalKind::Constant(c) => format!("\\n{c:.4e}"),
                SignalKind::Function(law, _) => format!("\\n{}", esc(&law.label)),
                _ => String::new(),
            };
            let _ = writeln!(
                s,
                "  s{i} [shape=box, style=rounded, fontsize=10, label=\"{} {}{}\"];",
                sg.kind.label(),
                esc(&sg.name),
                extra
            );
        }
        for (i, b) in self.bonds.iter().enumerate() {
            let (head, tail) = match &caus {
                Ok(c) if c.effort_to_head[i] => ("teelnormal", "none"),
                Ok(_) => ("lnormal", "tee"),
                Err(_) => ("lnormal", "none"),
            };
            let _ = writeln!(
                s,
                "  e{} -> e{} [dir=both, arrowhead={head}, arrowtail={tail}, label=\"{}\", fontsize=9];",
                b.from.0,
                b.to.0,
                esc(&b.name)
            );
        }
        let edge = |s: &mut String, from: String, to: String| {
            let _ = writeln!(
                s,
                "  {from} -> {to} [style=dashed, arrowhead=normal, color=gray40];"
            );
        };
        for (i, sg) in self.signals.iter().enumerate() {
            let to = format!("s{i}");
            match &sg.kind {
                SignalKind::Gain(_, Some(x))
                | SignalKind::Function(_, Some(x))
                | SignalKind::Integrator(Some(x))
                | SignalKind::Port(Some(x)) => edge(&mut s, format!("s{}", x.0), to),
                SignalKind::Sum(t) => {
                    for (_, x) in t {
                        edge(&mut s, format!("s{}", x.0), to.clone());
                    }
                }
                SignalKind::Product(a, b) => {
                    edge(&mut s, format!("s{}", a.0), to.clone());
                    edge(&mut s, format!("s{}", b.0), to);
                }
                SignalKind::Sensor(Quantity::Effort(b)) | SignalKind::Sensor(Quantity::Flow(b)) => {
                    if let Some(bd) = self.bonds.get(b.0) {
                        edge(&mut s, format!("e{}", bd.to.0), to);
                    }
                }
                SignalKind::Sensor(Quantity::State(e, _)) => edge(&mut s, format!("e{}", e.0), to),
                _ => {}
            }
        }
        for (i, el) in self.elements.iter().enumerate() {
            let m = match &el.kind {
                ElementKind::Se(SourceValue::Signal(x))
                | ElementKind::Sf(SourceValue::Signal(x))
                | ElementKind::Tf(SourceValue::Signal(x))
                | ElementKind::Gy(SourceValue::Signal(x))
                | ElementKind::R(_, Some(x)) => Some(*x),
                _ => None,
            };
            if let Some(x) = m {
                edge(&mut s, format!("s{}", x.0), format!("e{i}"));
            }
        }
        s.push_str("}\n");
        s
    }
}
