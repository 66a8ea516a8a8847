//! Structural and parameter checks run before causality assignment.

use std::collections::HashSet;

use nalgebra::DMatrix;

use super::element::*;
use super::error::BondGraphError;
use super::graph::BondGraph;

fn param(element: &str, message: String) -> BondGraphError {
    BondGraphError::InvalidParameter {
        element: element.to_string(),
        message,
    }
}

fn structure(element: &str, message: impl Into<String>) -> BondGraphError {
    BondGraphError::Structure {
        element: element.to_string(),
        message: message.into(),
    }
}

fn positive(element: &str, what: &str, v: f64) -> Result<(), BondGraphError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(param(
            element,
            format!("{what} must be positive and finite, got {v:e}"),
        ))
    }
}

fn finite(element: &str, what: &str, v: f64) -> Result<(), BondGraphError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(param(element, format!("{what} must be finite, got {v}")))
    }
}

fn symmetric(element: &str, what: &str, m: &DMatrix<f64>, n: usize) -> Result<(), BondGraphError> {
    if m.nrows() != n || m.ncols() != n {
        return Err(structure(
            element,
            format!(
                "{what} is {}x{} but the field has {n} bond(s)",
                m.nrows(),
                m.ncols()
            ),
        ));
    }
    if m.iter().any(|v| !v.is_finite()) {
        return Err(param(element, format!("{what} must be finite")));
    }
    let scale = m.amax().max(f64::MIN_POSITIVE);
    for i in 0..n {
        for j in 0..i {
            if (m[(i, j)] - m[(j, i)]).abs() > 1e-12 * scale {
                return Err(param(
                    element,
                    format!(
                        "{what} must be symmetric, entry ({i},{j}) = {:e} but ({j},{i}) = {:e}",
                        m[(i, j)],
                        m[(j, i)]
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Checks names, connections and parameters.
pub(crate) fn validate(g: &BondGraph) -> Result<(), BondGraphError> {
    let mut names = HashSet::new();
    for n in g
        .elements
        .iter()
        .map(|e| &e.name)
        .chain(g.signals.iter().map(|s| &s.name))
    {
        if !names.insert(n.as_str()) {
            return Err(BondGraphError::DuplicateName { name: n.clone() });
        }
    }
    let mut onames = HashSet::new();
    for o in &g.outputs {
        if !onames.insert(o.name.as_str()) {
            return Err(BondGraphError::DuplicateName {
                name: o.name.clone(),
            });
        }
    }
    let mut bnames = HashSet::new();
    for b in &g.bonds {
        if !bnames.insert(b.name.as_str()) {
            return Err(BondGraphError::DuplicateName {
                name: b.name.clone(),
            });
        }
        if b.from == b.to {
            return Err(structure(
                &g.elements[b.from.0].name,
                format!("bond '{}' connects the element to itself", b.name),
            ));
        }
    }
    for (el, ports) in g.elements.iter().zip(g.port_table()) {
        let name = el.name.as_str();
        let one_port = |kind: &str| -> Result<(), BondGraphError> {
            if ports.len() != 1 {
                Err(structure(
                    name,
                    format!(
                        "a {kind} element needs exactly one bond, it has {}",
                        ports.len()
                    ),
                ))
            } else {
                Ok(())
            }
        };
        match &el.kind {
            ElementKind::Se(v) | ElementKind::Sf(v) => {
                one_port(el.kind.label())?;
                if let SourceValue::Constant(c) = v {
                    finite(name, "source value", c.v)?;
                }
            }
            ElementKind::I(law) | ElementKind::C(law) => {
                let what = if matches!(el.kind, ElementKind::I(_)) {
                    "inertance"
                } else {
                    "capacitance"
                };
                one_port(el.kind.label())?;
                match law {
                    Law::Linear(v) => positive(name, what, v.v)?,
                    Law::Nonlinear(_) => {}
                    Law::Conductance(_) => {
                        return Err(structure(
                            name,
                            "a conductance law is only allowed on an R element",
                        ))
                    }
                }
            }
            ElementKind::R(law, m) => {
                one_port("R")?;
                if let Law::Linear(v) = law {
                    positive(name, "resistance", v.v)?;
                    if m.is_some() {
                        return Err(structure(
                            name,
                            "a modulated R needs a nonlinear law (Law::Nonlinear or Law::Conductance)",
                        ));
                    }
                }
            }
            ElementKind::Tf(m) | ElementKind::Gy(m) => {
                let n_in = ports.iter().filter(|p| p.1 > 0.0).count();
                if ports.len() != 2 || n_in != 1 {
                    return Err(structure(
                        name,
                        format!(
                            "a {} needs exactly two bonds, one pointing in (port 1) and one pointing out (port 2); it has {} in, {} out",
                            el.kind.label(),
                            n_in,
                            ports.len() - n_in
                        ),
                    ));
                }
                if let SourceValue::Constant(c) = m {
                    if !c.v.is_finite() || c.v == 0.0 {
                        return Err(param(
                            name,
                            format!("modulus must be finite and non-zero, got {c:e}"),
                        ));
                    }
                }
            }
            ElementKind::Zero | ElementKind::One => {
                if ports.is_empty() {
                    return Err(structure(name, "junction has no bonds"));
                }
            }
            ElementKind::IField(mass) => {
                symmetric(name, "mass matrix", mass, ports.len())?;
                if ports.is_empty() || mass.clone().cholesky().is_none() {
                    return Err(param(name, "mass matrix must be positive definite".into()));
                }
            }
            ElementKind::CField(k, laws) => {
                symmetric(name, "stiffness matrix", k, ports.len())?;
                if ports.is_empty() {
                    return Err(structure(name, "field has no bonds"));
                }
                if !laws.is_empty() && laws.len() != ports.len() {
                    return Err(structure(
                        name,
                        format!("{} port laws for {} ports", laws.len(), ports.len()),
                    ));
                }
                let ev = k.clone().symmetric_eigenvalues();
                let tol = 1e-12 * k.amax();
                if let Some(min) = ev.iter().cloned().reduce(f64::min) {
                    if min < -tol {
                        return Err(param(
                            name,
                            format!(
                                "stiffness matrix must be positive semidefinite, has eigenvalue {min:e}"
                            ),
                        ));
                    }
                }
            }
        }
    }
    let storage_ports = |e: ElementId| -> Option<usize> {
        match &g.elements.get(e.0)?.kind {
            ElementKind::I(_) | ElementKind::C(_) => Some(1),
            ElementKind::IField(_) | ElementKind::CField(..) => Some(g.ports(e).len()),
            _ => None,
        }
    };
    let check_quantity = |name: &str, q: &Quantity| -> Result<(), BondGraphError> {
        match q {
            Quantity::Effort(b) | Quantity::Flow(b) => {
                if b.0 >= g.bonds.len() {
                    return Err(structure(name, "sensor of an unknown bond"));
                }
            }
            Quantity::State(e, port) => match storage_ports(*e) {
                Some(n) if *port < n => {}
                Some(n) => {
                    return Err(structure(
                        name,
                        format!("state port {port} out of range (the element has {n})"),
                    ))
                }
                None => {
                    return Err(structure(
                        name,
                        format!(
                            "state sensor of '{}', which is not a storage element",
                            g.elements.get(e.0).map(|x| x.name.as_str()).unwrap_or("?")
                        ),
                    ))
                }
            },
        }
        Ok(())
    };
    for s in &g.signals {
        let name = s.name.as_str();
        match &s.kind {
            SignalKind::Input => {}
            SignalKind::Constant(c) => finite(name, "constant", c.v)?,
            SignalKind::Gain(k, input) => {
                finite(name, "gain", k.v)?;
                if input.is_none() {
                    return Err(structure(name, "gain input is not connected"));
                }
            }
            SignalKind::Sum(terms) => {
                for (k, _) in terms {
                    finite(name, "sum coefficient", k.v)?;
                }
            }
            SignalKind::Product(..) => {}
            SignalKind::Integrator(input) => {
                if input.is_none() {
                    return Err(structure(name, "integrator input is not connected"));
                }
            }
            SignalKind::Function(_, input) => {
                if input.is_none() {
                    return Err(structure(name, "function input is not connected"));
                }
            }
            SignalKind::Sensor(q) => check_quantity(name, q)?,
            SignalKind::Port(src) => {
                if src.is_none() {
                    return Err(structure(name, "signal port is not connected"));
                }
            }
        }
    }
    for o in &g.outputs {
        if let OutputSource::Quantity(q) = &o.source {
            check_quantity(&o.name, q)?;
        }
    }
    Ok(())
}
