//! The FMI 3.0 view of a model's variable table: scalar families `base[1]`, ..., `base[n]` with
//! consecutive value references and the same type, causality, variability, unit and range are one
//! array variable `base` with the value reference of `base[1]`, and value reference 0 is the
//! independent variable `time`. Continuous states and their derivatives stay scalars: an array
//! state would need an array derivative of its shape, and `der(x[k])` is no family.
//!
//! `modelDescription/fmi3.py` writes the FMI 3.0 XML from the FMI 2.0 XML by the same rule, and
//! `tests/fmi3_description.rs` checks that the XML declares exactly the arrays this table finds.
//! The values stay where the FMI 2.0 layer keeps them: an array is a run of FMI 2.0 scalars.

use std::collections::HashMap;

use crate::fmu::{Kind, Variable};

/// The value reference of `time`, the independent variable FMI 3.0 asks for. It is not in the
/// FMI 2.0 table; `modelDescription/fmi3.py` refuses a table that uses 0.
pub const TIME_VALUE_REFERENCE: u32 = 0;

/// One FMI 3.0 variable: a scalar or an array over FMI 2.0 table positions `first..first + len`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fmi3Variable {
    pub name: String,
    pub value_reference: u32,
    /// Position of the first element in the FMI 2.0 variable table.
    pub first: usize,
    /// 1 for a scalar.
    pub len: usize,
}

/// The FMI 3.0 type name (the XML's element) of an FMI 2.0 kind.
pub fn fmi3_type_name(kind: &Kind) -> &'static str {
    match kind {
        Kind::Real { .. } => "Float64",
        Kind::Integer { .. } => "Int32",
        Kind::Boolean { .. } => "Boolean",
        Kind::String { .. } => "String",
        Kind::Enumeration { .. } => "Enumeration",
    }
}

/// Whether the getter and setter of FMI 3.0 type `abi` (`fmi3GetInt64`: "Int64") reach a
/// variable of `kind`: its own type's, and for an Enumeration `fmi3GetInt64`/`fmi3SetInt64`
/// (FMI 3.0, 2.4.7) and, for importers written against the earlier Integer switches, the Int32
/// pair (the values are 32-bit integers either way).
pub fn fmi3_reaches(abi: &str, kind: &Kind) -> bool {
    match kind {
        Kind::Enumeration { .. } => matches!(abi, "Int64" | "Int32"),
        other => fmi3_type_name(other) == abi,
    }
}

/// `base[k]` -> (`base`, k).
fn family(name: &str) -> Option<(&str, usize)> {
    let open = name.rfind('[')?;
    let index = name.strip_suffix(']')?.get(open + 1..)?.parse().ok()?;
    Some((&name[..open], index))
}

/// The declared type of an Enumeration.
fn declared(k: &Kind) -> Option<&'static str> {
    match k {
        Kind::Enumeration { declared, .. } => Some(declared.name),
        _ => None,
    }
}

/// Whether two variables may be elements of one array: everything but the start value and the
/// description agrees.
fn same_signature(a: &Variable, b: &Variable) -> bool {
    let bounds = |k: &Kind| match *k {
        Kind::Real { min, max, .. } => (min.map(f64::to_bits), max.map(f64::to_bits)),
        Kind::Integer { min, max, .. } => (
            min.map(|v| i64::from(v) as u64),
            max.map(|v| i64::from(v) as u64),
        ),
        _ => (None, None),
    };
    fmi3_type_name(&a.kind) == fmi3_type_name(&b.kind)
        && a.causality == b.causality
        && a.variability == b.variability
        && a.unit == b.unit
        && bounds(&a.kind) == bounds(&b.kind)
        && declared(&a.kind) == declared(&b.kind)
}

/// The FMI 3.0 variables of a model, looked up by value reference.
#[derive(Clone, Debug)]
pub struct Fmi3Table {
    variables: Vec<Fmi3Variable>,
    by_value_reference: HashMap<u32, usize>,
}

impl Fmi3Table {
    /// Groups the FMI 2.0 table into FMI 3.0 variables (without `time`); `states` are the
    /// (state, derivative) positions of the Model Exchange states, which stay scalars.
    pub fn new(table: &[Variable], states: &[(usize, usize)]) -> Self {
        let state_related = |i: usize| states.iter().any(|&(x, d)| x == i || d == i);
        let mut variables = Vec::new();
        let mut i = 0;
        while i < table.len() {
            let first = &table[i];
            let mut len = 1;
            if let (Some((base, 1)), false) = (family(first.name), state_related(i)) {
                while let Some(next) = table.get(i + len) {
                    let follows = !state_related(i + len)
                        && family(next.name) == Some((base, len + 1))
                        && next.value_reference == first.value_reference + len as u32
                        && same_signature(first, next);
                    if !follows {
                        break;
                    }
                    len += 1;
                }
            }
            let name = match family(first.name) {
                Some((base, _)) if len > 1 => base.to_string(),
                _ => first.name.to_string(),
            };
            variables.push(Fmi3Variable {
                name,
                value_reference: first.value_reference,
                first: i,
                len,
            });
            i += len;
        }
        let by_value_reference = variables
            .iter()
            .enumerate()
            .map(|(k, v)| (v.value_reference, k))
            .collect();
        Fmi3Table {
            variables,
            by_value_reference,
        }
    }

    /// Every variable in table order (`time` is not among them).
    pub fn variables(&self) -> &[Fmi3Variable] {
        &self.variables
    }

    /// The variable of an FMI 3.0 value reference; `None` for an unknown one, and for the value
    /// reference of an array's second or later element, which FMI 3.0 does not know.
    pub fn get(&self, value_reference: u32) -> Option<&Fmi3Variable> {
        self.by_value_reference
            .get(&value_reference)
            .map(|&k| &self.variables[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmu::{Causality, Variability};

    fn real(name: &'static str, vr: u32) -> Variable {
        Variable {
            name,
            value_reference: vr,
            causality: Causality::Output,
            variability: Variability::Continuous,
            kind: Kind::Real {
                start: None,
                min: None,
                max: None,
            },
            unit: Some("m"),
            description: "",
        }
    }

    #[test]
    fn families_with_consecutive_references_become_arrays() {
        let mut other_unit = real("b[3]", 13);
        other_unit.unit = Some("s");
        let table = [
            real("x", 1),
            real("a[1]", 5),
            real("a[2]", 6),
            real("a[3]", 7),
            real("b[1]", 11),
            real("b[2]", 12),
            other_unit,
            real("c[1]", 20),
            real("c[2]", 22),
        ];
        let t = Fmi3Table::new(&table, &[]);
        let summary: Vec<_> = t
            .variables()
            .iter()
            .map(|v| (v.name.as_str(), v.value_reference, v.first, v.len))
            .collect();
        assert_eq!(
            summary,
            [
                ("x", 1, 0, 1),
                ("a", 5, 1, 3),
                ("b", 11, 4, 2),
                ("b[3]", 13, 6, 1),
                ("c[1]", 20, 7, 1),
                ("c[2]", 22, 8, 1),
            ]
        );
        assert!(t.get(6).is_none(), "a[2] has no FMI 3.0 value reference");
        assert_eq!(t.get(5).map(|v| v.len), Some(3));
    }

    #[test]
    fn states_and_derivatives_stay_scalars() {
        let table = [
            real("q[1]", 1),
            real("q[2]", 2),
            real("der(q[1])", 3),
            real("der(q[2])", 4),
            real("a[1]", 5),
            real("a[2]", 6),
        ];
        let t = Fmi3Table::new(&table, &[(0, 2), (1, 3)]);
        let names: Vec<_> = t.variables().iter().map(|v| v.name.as_str()).collect();
        assert_eq!(names, ["q[1]", "q[2]", "der(q[1])", "der(q[2])", "a"]);
    }

    #[test]
    fn family_names() {
        assert_eq!(family("plate.f[12]"), Some(("plate.f", 12)));
        assert_eq!(family("acc"), None);
        assert_eq!(family("x[a]"), None);
    }
}
