//! Errors of graph validation, causality assignment and compilation.

use std::fmt;

/// An error found while validating, assigning causality to, or compiling a bond graph. Every
/// variant names the elements involved.
#[derive(Debug, Clone, PartialEq)]
pub enum BondGraphError {
    /// A parameter is out of range, e.g. a non-positive capacitance.
    InvalidParameter {
        /// The element.
        element: String,
        /// What is wrong, e.g. "capacitance must be positive and finite, got -1e-11".
        message: String,
    },
    /// The graph is malformed around an element (wrong number of bonds, unconnected signal, ...).
    Structure {
        /// The element.
        element: String,
        /// What is wrong.
        message: String,
    },
    /// Two elements, signals or outputs share a name.
    DuplicateName {
        /// The name.
        name: String,
    },
    /// A storage element is forced into derivative causality (a dependent storage element).
    DerivativeCausality {
        /// The storage element in derivative causality.
        element: String,
        /// The elements whose causality, propagated through the junction structure, forces it.
        forced_by: Vec<String>,
    },
    /// Causality propagation meets a contradiction at an element (e.g. two effort sources on one
    /// 0-junction).
    CausalConflict {
        /// The element where the contradiction appears.
        element: String,
        /// The elements whose causality meets there.
        involved: Vec<String>,
    },
    /// The equations contain an algebraic loop (a cycle without integration).
    AlgebraicLoop {
        /// The elements and signal blocks whose equations form the loop.
        elements: Vec<String>,
    },
    /// A nonlinear law is needed in the inverse form from the one given.
    NonInvertibleLaw {
        /// The element.
        element: String,
        /// What is wrong.
        message: String,
    },
}

fn quoted(names: &[String]) -> String {
    names
        .iter()
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ")
}

impl fmt::Display for BondGraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BondGraphError::InvalidParameter { element, message } => {
                write!(f, "element '{element}': {message}")
            }
            BondGraphError::Structure { element, message } => {
                write!(f, "element '{element}': {message}")
            }
            BondGraphError::DuplicateName { name } => {
                write!(f, "duplicate name '{name}'")
            }
            BondGraphError::DerivativeCausality { element, forced_by } => {
                write!(
                    f,
                    "element '{element}' is forced into derivative causality (dependent storage)"
                )?;
                if !forced_by.is_empty() {
                    write!(f, " by {}", quoted(forced_by))?;
                }
                write!(f, "; combine it with the storage element(s) it depends on, or add compliance/inertia between them")
            }
            BondGraphError::CausalConflict { element, involved } => {
                write!(f, "causal conflict at element '{element}'")?;
                if !involved.is_empty() {
                    write!(f, " between {}", quoted(involved))?;
                }
                Ok(())
            }
            BondGraphError::AlgebraicLoop { elements } => {
                write!(f, "algebraic loop through {}", quoted(elements))
            }
            BondGraphError::NonInvertibleLaw { element, message } => {
                write!(f, "element '{element}': {message}")
            }
        }
    }
}

impl std::error::Error for BondGraphError {}
