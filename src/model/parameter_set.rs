//! The FMU's settings as an SSP 1.0 parameter set (`.ssv`, SSP 1.0 section 7,
//! `SystemStructureParameterValues`): one `<ssv:Parameter>` per setting, typed as its FMU
//! variable: `ssv:Real`, `ssv:Boolean`, and `ssv:Integer` for the Integers and for the switches
//! (Integers in the FMI 2.0 description, Enumerations in the FMI 3.0 one, which sets them as
//! integers too), with the item's name in a comment.
//!
//! The one writer: `hsp ssp` (the presets' sets), `hsp identify --out` (a fitted set) and the
//! browser page (its run's settings, through `hsp_parameter_set` of the `.wasm`) all call
//! [`parameter_set_of`]; `hsp run --ssv` reads what it writes.

use std::fmt::Write as _;

use crate::fmu::Kind;
use crate::model::variables::VARIABLES;

/// The namespace of SSP 1.0 parameter sets.
pub const SSV_NS: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterValues";

/// `s` as XML attribute text.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// An SSP 1.0 parameter set (`.ssv`) named `name` of the `(NAME, VALUE)` settings, each typed
/// as its FMU variable (module doc), with a comment saying it was written by `written_by`; an
/// error names a setting that is no variable or whose value is not of its type.
pub fn parameter_set_of<'a>(
    name: &str,
    description: &str,
    written_by: &str,
    settings: impl IntoIterator<Item = (&'a str, &'a str)>,
) -> Result<String, String> {
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    writeln!(s, "<!-- Written by {written_by} -->").unwrap();
    writeln!(
        s,
        "<ssv:ParameterSet version=\"1.0\" name=\"{}\" description=\"{}\"\n    \
         xmlns:ssv=\"{SSV_NS}\">",
        escape(name),
        escape(description)
    )
    .unwrap();
    s.push_str("  <ssv:Parameters>\n");
    for (name, value) in settings {
        let var = VARIABLES
            .iter()
            .find(|v| v.name == name)
            .ok_or_else(|| format!("no variable {name}"))?;
        let bad = || format!("{name} = {value} is not a {:?}", var.kind);
        let typed = match var.kind {
            Kind::Real { .. } => {
                value.parse::<f64>().map_err(|_| bad())?;
                format!("<ssv:Real value=\"{value}\"/>")
            }
            Kind::Integer { .. } => {
                value.parse::<i32>().map_err(|_| bad())?;
                format!("<ssv:Integer value=\"{value}\"/>")
            }
            Kind::Enumeration { declared, .. } => {
                let v = value.parse::<i32>().map_err(|_| bad())?;
                let item = declared
                    .items
                    .iter()
                    .find(|i| i.value == v)
                    .ok_or_else(bad)?;
                format!(
                    "<ssv:Integer value=\"{value}\"/><!-- {}.{} -->",
                    declared.name, item.name
                )
            }
            Kind::Boolean { .. } => {
                value.parse::<bool>().map_err(|_| bad())?;
                format!("<ssv:Boolean value=\"{value}\"/>")
            }
            Kind::String { .. } => format!("<ssv:String value=\"{}\"/>", escape(value)),
        };
        writeln!(
            s,
            "    <ssv:Parameter name=\"{}\">{typed}</ssv:Parameter>",
            escape(name)
        )
        .unwrap();
    }
    s.push_str("  </ssv:Parameters>\n</ssv:ParameterSet>\n");
    Ok(s)
}
