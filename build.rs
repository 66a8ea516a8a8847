//! Reads `modelDescription/modelDescription.xml`, the one source of truth for the FMU's variables,
//! through the project's one reader of it (`tools/model_description.rs`, shared with `hsp`),
//! checks the rules of FMI 2.0 that a typo would break, and writes the Rust variable table
//! (`$OUT_DIR/variables.rs`, included by `src/model/variables.rs`). Code and XML cannot drift: a
//! variable exists in Rust only because it exists in the XML.
//!
//! The GUID is derived from the XML itself (a hash of the file with the GUID left out), so that it
//! changes whenever the interface does; the build fails and names the new GUID when it is stale.

// The GUID rule, shared with the library and tools/guid.rs (which update.py runs).
#[path = "src/fnv1a.rs"]
#[allow(dead_code)]
mod fnv1a;
// The hash of the library's sources, written into the library (see the file).
#[path = "tools/source_hash.rs"]
mod source_hash;
// The one reader of the XML, shared with `hsp`'s documentation page.
#[path = "tools/model_description.rs"]
#[allow(dead_code)]
mod model_description;

use model_description::{get, EnumerationType, ModelDescription, Unit, Unknown};

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;
use std::path::Path;

const XML: &str = "modelDescription/modelDescription.xml";
/// The `<Tool>` of `<VendorAnnotations>` that carries the project's own rules on the variables.
const TOOL: &str = "hydraulic-slewing-plate";

fn main() {
    println!("cargo:rerun-if-changed={XML}");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src/fnv1a.rs");
    println!("cargo:rerun-if-changed=tools/model_description.rs");
    let text =
        std::fs::read_to_string(XML).unwrap_or_else(|e| fail(&format!("cannot read {XML}: {e}")));
    let (code, rules) = generate(&text).unwrap_or_else(|e| fail(&e));
    for (file, code) in [("variables.rs", code), ("rules.rs", rules)] {
        let out = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join(file);
        std::fs::write(&out, code)
            .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", out.display())));
    }
    write_source_hash();
}

/// Writes `$OUT_DIR/source_hash.rs` (included by `src/lib.rs`): the hash of the library's
/// sources and the marker the binary carries, rerun whenever one of those sources changes.
fn write_source_hash() {
    for dir in ["src", "tools", "Cargo.toml", "Cargo.lock"] {
        println!("cargo:rerun-if-changed={dir}");
    }
    let hash = source_hash::source_hash(Path::new("."));
    let code = format!(
        "/// The hash of the sources this library was built from (`tools/source_hash.rs`).\n\
         pub const SOURCE_HASH: &str = \"{hash}\";\n\
         /// `SOURCE_HASH` as the binary carries it (in the instantiation log line), for a test to\n\
         /// find in a packaged FMU's binary.\n\
         pub const SOURCE_MARKER: &str = \"hsp-source-hash:{hash}\";\n"
    );
    let out = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("source_hash.rs");
    std::fs::write(&out, code)
        .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", out.display())));
}

fn fail(message: &str) -> ! {
    eprintln!("error in {XML}: {message}");
    panic!("{XML}: {message}");
}

/// A Rust identifier for a variable name: `plate.f[1]` -> `PLATE_F_1`.
fn ident(name: &str) -> String {
    let mut s = String::new();
    for c in name.chars() {
        if c.is_ascii_alphanumeric() {
            s.push(c.to_ascii_uppercase());
        } else if !s.ends_with('_') {
            s.push('_');
        }
    }
    s.trim_end_matches('_').to_string()
}

fn opt_f64(v: Option<&str>, what: &str) -> Result<String, String> {
    match v {
        None => Ok("None".into()),
        Some(s) => s
            .parse::<f64>()
            .map(|x| format!("Some({x:?})"))
            .map_err(|_| format!("{what}: '{s}' is not a number")),
    }
}

fn opt_i32(v: Option<&str>, what: &str) -> Result<String, String> {
    match v {
        None => Ok("None".into()),
        Some(s) => s
            .parse::<i32>()
            .map(|x| format!("Some({x})"))
            .map_err(|_| format!("{what}: '{s}' is not an integer")),
    }
}

/// The generated code: the variable table (`variables.rs`, for the FMU's model) and the parameter
/// rules (`rules.rs`, for the fragments, which know nothing of the FMU).
fn generate(text: &str) -> Result<(String, String), String> {
    let md = ModelDescription::parse(text)?;
    if md.attribute("fmiVersion") != Some("2.0") {
        return Err("fmiVersion must be \"2.0\"".into());
    }
    let guid = md.attribute("guid").ok_or("the root has no guid")?;
    let expected = fnv1a::model_guid(text, guid);
    if guid != expected {
        return Err(format!(
            "the file changed, so its GUID must too: run python3 modelDescription/update.py, or set guid=\"{expected}\" (it is \"{guid}\")"
        ));
    }
    let cs = md
        .co_simulation
        .as_deref()
        .ok_or("no <CoSimulation> element")?;
    let model_identifier =
        get(cs, "modelIdentifier").ok_or("CoSimulation has no modelIdentifier")?;
    // Model Exchange, where offered, is the same binary: the same modelIdentifier.
    let me = md.model_exchange.as_deref();
    if let Some(me) = me {
        if get(me, "modelIdentifier") != Some(model_identifier) {
            return Err(format!(
                "ModelExchange's modelIdentifier must be CoSimulation's, {model_identifier:?}: one binary offers both"
            ));
        }
    }

    // Units and their display units.
    let mut units: HashMap<String, BTreeSet<String>> = HashMap::new();
    for u in &md.units {
        check_unit(u)?;
        let displays = u.display_units.iter().map(|d| d.name.clone()).collect();
        units.insert(u.name.clone(), displays);
    }

    let enums = enumerations(&md)?;
    let switches = switch_types(&md)?;

    let mut names = BTreeSet::new();
    let mut vrs = BTreeSet::new();
    // The numeric parameters' (position, min, max), for the rules table.
    let mut ranges: Vec<(usize, String, String)> = Vec::new();
    let mut table = String::new();
    let mut shown = String::new();
    let mut idx_consts = String::new();
    let mut vr_consts = String::new();
    let mut index_arms = String::new();
    let mut outputs = Vec::new();
    let mut initial_unknowns = Vec::new();
    let mut inputs = BTreeSet::new();
    let mut exact = BTreeSet::new();
    // (state position, derivative position), 1-based, in XML order of the derivatives.
    let mut derivatives: Vec<(usize, usize)> = Vec::new();
    for (i, sv) in md.variables.iter().enumerate() {
        let position = i + 1;
        let name = sv.name.as_str();
        let at = |what: &str| format!("variable '{name}': {what}");
        if !names.insert(name.to_string()) {
            return Err(at("duplicate name"));
        }
        let vr = sv.value_reference;
        if !vrs.insert(vr) {
            return Err(at(&format!("valueReference {vr} is used twice")));
        }
        let description = sv
            .description
            .as_deref()
            .ok_or(at("every variable needs a description"))?;
        let causality = sv.causality.as_str();
        let variability = sv.variability.as_str();
        let initial = sv.initial.as_deref();
        let start = sv.start.as_deref();
        let needs_start = matches!(causality, "input" | "parameter")
            || matches!(initial, Some("exact") | Some("approx"))
            || variability == "constant";
        if needs_start && start.is_none() {
            return Err(at(
                "an input, parameter or exact/approx variable needs a start value",
            ));
        }
        if initial == Some("calculated") && start.is_some() {
            return Err(at("a calculated variable must not have a start value"));
        }
        match (causality, variability) {
            ("parameter", "fixed" | "tunable")
            | ("calculatedParameter", "fixed" | "tunable")
            | ("input", "discrete" | "continuous")
            | ("output", _)
            | ("local", _)
            | ("independent", "continuous") => {}
            _ => {
                return Err(at(&format!(
                    "causality {causality} with variability {variability} is not legal"
                )))
            }
        }
        if variability == "continuous" && sv.kind != "Real" {
            return Err(at("only Real variables can be continuous"));
        }
        if let Some(unit) = sv.unit.as_deref() {
            let Some(displays) = units.get(unit) else {
                return Err(at(&format!("unit '{unit}' is not in <UnitDefinitions>")));
            };
            if let Some(d) = sv.display_unit.as_deref() {
                if !displays.contains(d) {
                    return Err(at(&format!(
                        "displayUnit '{d}' is not defined for unit '{unit}'"
                    )));
                }
            }
        }
        if causality == "output" {
            outputs.push(position);
        }
        if causality == "input" {
            inputs.insert(position);
        }
        if causality == "parameter" && initial != Some("calculated") {
            exact.insert(position);
        }
        if let Some(of) = sv.derivative.as_deref() {
            let of: usize = of
                .parse()
                .map_err(|_| at(&format!("bad derivative attribute '{of}'")))?;
            if of == 0 || of >= position {
                return Err(at(&format!(
                    "derivative=\"{of}\" must name an earlier variable"
                )));
            }
            derivatives.push((of, position));
        }
        if (causality == "output" && initial != Some("exact")) || causality == "calculatedParameter"
        {
            initial_unknowns.push(position);
        }
        let numeric =
            matches!(sv.kind.as_str(), "Real" | "Integer") && !switches.contains_key(name);
        if causality == "parameter" && numeric {
            ranges.push((
                position - 1,
                opt_f64(sv.min.as_deref(), &at("min"))?,
                opt_f64(sv.max.as_deref(), &at("max"))?,
            ));
        }
        let kind = match sv.kind.as_str() {
            "Real" => format!(
                "Kind::Real {{ start: {}, min: {}, max: {} }}",
                opt_f64(start, &at("start"))?,
                opt_f64(sv.min.as_deref(), &at("min"))?,
                opt_f64(sv.max.as_deref(), &at("max"))?
            ),
            "Integer" if switches.contains_key(name) => {
                // A switch: an Enumeration of its type everywhere but in this description.
                let declared = switches[name];
                let ty = md.enumeration(declared).ok_or(at(&format!(
                    "the switch's declaredType '{declared}' is not an enumeration of <TypeDefinitions>"
                )))?;
                let values: Vec<i32> = ty
                    .items
                    .iter()
                    .map(|i| i.value.parse::<i32>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| at(&format!("{declared}: an item's value is not an integer")))?;
                let (lo, hi) = (values.iter().min(), values.iter().max());
                let range = (
                    opt_i32(sv.min.as_deref(), &at("min"))?,
                    opt_i32(sv.max.as_deref(), &at("max"))?,
                );
                if range != (format!("{lo:?}"), format!("{hi:?}")) {
                    return Err(at(&format!(
                        "a switch of {declared} needs min=\"{}\" max=\"{}\" (its items' values)",
                        lo.unwrap_or(&0),
                        hi.unwrap_or(&0)
                    )));
                }
                let start = opt_i32(start, &at("start"))?;
                if let Some(s) = sv.start.as_deref() {
                    if !ty.items.iter().any(|i| i.value == s) {
                        return Err(at(&format!("start {s} is not an item of {declared}")));
                    }
                }
                format!("Kind::Enumeration {{ start: {start}, declared: &{declared}::TYPE }}")
            }
            "Integer" => format!(
                "Kind::Integer {{ start: {}, min: {}, max: {} }}",
                opt_i32(start, &at("start"))?,
                opt_i32(sv.min.as_deref(), &at("min"))?,
                opt_i32(sv.max.as_deref(), &at("max"))?
            ),
            "Boolean" => format!(
                "Kind::Boolean {{ start: {} }}",
                match start {
                    None => "None".to_string(),
                    Some("true") | Some("1") => "Some(true)".into(),
                    Some("false") | Some("0") => "Some(false)".into(),
                    Some(s) => return Err(at(&format!("'{s}' is not a Boolean"))),
                }
            ),
            "String" => format!("Kind::String {{ start: {:?} }}", start),
            "Enumeration" => {
                let declared = sv
                    .declared_type
                    .as_deref()
                    .ok_or(at("an Enumeration needs a declaredType"))?;
                let ty = md.enumeration(declared).ok_or(at(&format!(
                    "declaredType '{declared}' is not an enumeration of <TypeDefinitions>"
                )))?;
                if sv.min.is_some() || sv.max.is_some() {
                    return Err(at("an Enumeration's range is its items: no min or max"));
                }
                let start = opt_i32(start, &at("start"))?;
                if let Some(s) = sv.start.as_deref() {
                    if !ty.items.iter().any(|i| i.value == s) {
                        return Err(at(&format!("start {s} is not an item of {declared}")));
                    }
                }
                format!("Kind::Enumeration {{ start: {start}, declared: &{declared}::TYPE }}")
            }
            other => return Err(at(&format!("unknown type element <{other}>"))),
        };
        let rust_enum = |s: &str| {
            let mut c = s.chars();
            c.next()
                .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                .unwrap_or_default()
        };
        writeln!(
            table,
            "    Variable {{ name: {name:?}, value_reference: {vr}, causality: Causality::{}, variability: Variability::{}, kind: {kind}, unit: {:?}, description: {description:?} }},",
            rust_enum(causality),
            rust_enum(variability),
            sv.unit,
        )
        .unwrap();
        let display_unit = match md.display_unit(sv) {
            Some(d) => format!(
                "Some(DisplayUnit {{ name: {:?}, factor: {:?}, offset: {:?} }})",
                d.name, d.factor, d.offset
            ),
            None => "None".to_string(),
        };
        writeln!(
            shown,
            "    Shown {{ group: {:?}, display_unit: {display_unit} }},",
            sv.group.as_deref().unwrap_or("")
        )
        .unwrap();
        let id = ident(name);
        // Brackets in a description (plate.I[1]) would be read as intra-doc links.
        let doc_text = description.replace('[', "\\[").replace(']', "\\]");
        writeln!(
            idx_consts,
            "    /// `{name}`: {doc_text}\n    pub const {id}: usize = {i};"
        )
        .unwrap();
        writeln!(
            vr_consts,
            "    /// `{name}`\n    pub const {id}: u32 = {vr};"
        )
        .unwrap();
        writeln!(index_arms, "        {vr} => Some({i}),").unwrap();
    }

    let positive = positive_list(&md, &names)?;
    let rules = rules_table(&md, &ranges, &positive);

    // ModelStructure must list exactly the outputs and the initial unknowns, by 1-based position.
    let structure = &md.structure;
    let listed = |list: &[Unknown]| -> Vec<usize> { list.iter().map(|u| u.index).collect() };
    // The continuous states (each named by a derivative) are calculated at initialisation, like
    // their derivatives: both are initial unknowns (FMI 2.0.4, section 2.2.8).
    let states: BTreeSet<usize> = derivatives.iter().map(|&(x, _)| x).collect();
    if states.len() != derivatives.len() {
        return Err("two variables are the derivative of the same state".into());
    }
    if !derivatives.is_empty() && me.is_none() {
        return Err("the XML declares continuous states but no <ModelExchange>".into());
    }
    initial_unknowns.extend(derivatives.iter().flat_map(|&(x, d)| [x, d]));
    initial_unknowns.sort_unstable();
    // Every unknown declares its dependencies: the outputs and derivatives on inputs and states
    // (the knowns of a step), the initial unknowns on inputs and exact parameters (the knowns of
    // initialisation mode).
    for (tag, unknowns, knowns) in [
        ("Outputs", &structure.outputs, &inputs | &states),
        ("Derivatives", &structure.derivatives, &inputs | &states),
        (
            "InitialUnknowns",
            &structure.initial_unknowns,
            &inputs | &exact,
        ),
    ] {
        for u in unknowns {
            let index = u.index;
            let deps = u.dependencies.as_ref().ok_or(format!(
                "<{tag}> Unknown {index} has no dependencies attribute (without it, it depends on every known)"
            ))?;
            for &d in deps {
                if !knowns.contains(&d) {
                    return Err(format!(
                        "<{tag}> Unknown {index} depends on variable {d}, which is not a known there"
                    ));
                }
            }
        }
    }
    if listed(&structure.outputs) != outputs {
        return Err(format!(
            "<ModelStructure><Outputs> lists {:?}, but the outputs are at positions {outputs:?}",
            listed(&structure.outputs)
        ));
    }
    let derivative_positions: Vec<usize> = derivatives.iter().map(|&(_, d)| d).collect();
    if listed(&structure.derivatives) != derivative_positions {
        return Err(format!(
            "<ModelStructure><Derivatives> lists {:?}, but the derivatives are at positions {derivative_positions:?}",
            listed(&structure.derivatives)
        ));
    }
    if listed(&structure.initial_unknowns) != initial_unknowns {
        return Err(format!(
            "<ModelStructure><InitialUnknowns> lists {:?}, but they are at positions {initial_unknowns:?}",
            listed(&structure.initial_unknowns)
        ));
    }

    let n = names.len();
    let state_table: String = derivatives
        .iter()
        .map(|&(x, d)| format!("({}, {}), ", x - 1, d - 1))
        .collect();
    let n_states = derivatives.len();
    let (smallest, largest) = magnitudes(&md)?;
    let variables = format!(
        "// Generated by build.rs from {XML}. Do not edit.\n\
         /// The `modelIdentifier` of the co-simulation interface.\n\
         pub const MODEL_IDENTIFIER: &str = {model_identifier:?};\n\
         /// The GUID, derived from the XML's content.\n\
         pub const GUID: &str = {guid:?};\n\
         /// Every ScalarVariable, in XML order.\n\
         pub static VARIABLES: [Variable; {n}] = [\n{table}];\n\
         /// How each variable of [`VARIABLES`] is shown (same order): the group the XML puts it\n\
         /// in (the comment before it) and its display unit.\n\
         pub static SHOWN: [Shown; {n}] = [\n{shown}];\n\
         /// The magnitudes a nonzero Real parameter may have, in SI units: the `<Magnitudes>`\n\
         /// rule of the XML's `<VendorAnnotations>`.\n\
         pub const MAGNITUDES: core::ops::RangeInclusive<f64> = {smallest:?}..={largest:?};\n\
         {enums}\
         /// The continuous states as (state, derivative) positions in [`VARIABLES`], in the order\n\
         /// of `<ModelStructure><Derivatives>`.\n\
         pub static CONTINUOUS_STATES: [(usize, usize); {n_states}] = [{state_table}];\n\
         /// The position in [`VARIABLES`] of a value reference.\n\
         pub fn index_of(vr: u32) -> Option<usize> {{\n    match vr {{\n{index_arms}        _ => None,\n    }}\n}}\n\
         /// Positions in [`VARIABLES`], by variable name.\n\
         pub mod idx {{\n{idx_consts}}}\n\
         /// Value references, by variable name.\n\
         pub mod vr {{\n{vr_consts}}}\n"
    );
    Ok((variables, rules))
}

/// `rules.rs`: every numeric parameter's rule (`min`, `max`, and whether the `<Positive>` list
/// names it), sorted by name for a binary search.
fn rules_table(
    md: &ModelDescription,
    ranges: &[(usize, String, String)],
    positive: &[usize],
) -> String {
    let mut rows: Vec<(&str, String)> = ranges
        .iter()
        .map(|(i, min, max)| {
            let positive = positive.contains(i);
            let name = md.variables[*i].name.as_str();
            (
                name,
                format!(
                    "    ({name:?}, Rule {{ min: {min}, max: {max}, positive: {positive} }}),\n"
                ),
            )
        })
        .collect();
    rows.sort();
    let n = rows.len();
    let table: String = rows.into_iter().map(|(_, row)| row).collect();
    format!(
        "// Generated by build.rs from {XML}. Do not edit.\n\
         /// Every numeric parameter's rule, by name (sorted): the XML's `min` and `max` and its\n\
         /// `<Positive>` list.\n\
         pub static RULES: [(&str, Rule); {n}] = [\n{table}];\n"
    )
}

/// The strictly positive parameters: the `<Positive names="...">` element of the project's
/// `<Tool>` in `<VendorAnnotations>`, the one list of them. Each must be a Real parameter whose
/// `min` is 0 (the XML says what importers can check; the list adds that 0 itself is refused).
/// Returns 0-based positions.
fn positive_list(md: &ModelDescription, names: &BTreeSet<String>) -> Result<Vec<usize>, String> {
    let tool = md
        .vendor_annotations
        .iter()
        .find(|(name, _)| name == TOOL)
        .ok_or(format!("no <VendorAnnotations><Tool name=\"{TOOL}\">"))?;
    let list = tool
        .1
        .iter()
        .find(|(tag, _)| tag == "Positive")
        .and_then(|(_, a)| get(a, "names"))
        .ok_or(format!(
            "<Tool name=\"{TOOL}\"> has no <Positive names=\"...\"/>"
        ))?;
    let mut out = Vec::new();
    for name in list.split_whitespace() {
        if !names.contains(name) {
            return Err(format!("<Positive> names '{name}', which is no variable"));
        }
        let i = md.variables.iter().position(|v| v.name == name).unwrap();
        let v = &md.variables[i];
        if v.kind != "Real" || v.causality != "parameter" || v.min.as_deref() != Some("0") {
            return Err(format!(
                "<Positive> names '{name}': it must be a Real parameter with min=\"0\""
            ));
        }
        if out.contains(&i) {
            return Err(format!("<Positive> names '{name}' twice"));
        }
        out.push(i);
    }
    Ok(out)
}

/// The switches (`<Enumeration variable="..." declaredType="..."/>` of the project's `<Tool>`):
/// variable name -> its enumeration type. Each must be an Integer parameter, named once.
fn switch_types(md: &ModelDescription) -> Result<BTreeMap<&str, &str>, String> {
    let mut out = BTreeMap::new();
    for (name, declared) in md.switches(TOOL) {
        let v = md.variables.iter().find(|v| v.name == name).ok_or(format!(
            "<Enumeration variable=\"{name}\">: no such variable"
        ))?;
        if v.kind != "Integer" || v.causality != "parameter" {
            return Err(format!(
                "<Enumeration variable=\"{name}\">: a switch must be an Integer parameter"
            ));
        }
        if out.insert(name, declared).is_some() {
            return Err(format!("<Enumeration variable=\"{name}\"> twice"));
        }
    }
    Ok(out)
}

/// The `<Magnitudes smallest="..." largest="..."/>` rule of the project's `<Tool>`: positive,
/// finite, the smallest below the largest.
fn magnitudes(md: &ModelDescription) -> Result<(f64, f64), String> {
    let tool = md
        .vendor_annotations
        .iter()
        .find(|(name, _)| name == TOOL)
        .ok_or(format!("no <VendorAnnotations><Tool name=\"{TOOL}\">"))?;
    let a = tool
        .1
        .iter()
        .find(|(tag, _)| tag == "Magnitudes")
        .map(|(_, a)| a)
        .ok_or(format!("<Tool name=\"{TOOL}\"> has no <Magnitudes/>"))?;
    let number = |key: &str| -> Result<f64, String> {
        get(a, key)
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|v| v.is_finite() && *v > 0.0)
            .ok_or(format!(
                "<Magnitudes {key}=...> must be a positive finite number"
            ))
    };
    let (smallest, largest) = (number("smallest")?, number("largest")?);
    if smallest >= largest {
        return Err("<Magnitudes>: smallest must be below largest".into());
    }
    Ok((smallest, largest))
}

/// A Rust identifier for an enumeration item: `ServoValve` stays, `rodas5p` -> `Rodas5p`.
fn item_ident(name: &str) -> String {
    let mut c = name.chars();
    c.next()
        .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
        .unwrap_or_default()
}

/// The Rust enum of each enumeration type of `<TypeDefinitions>`, named as the type, with its
/// items as variants of their values, `TYPE` (the table's [`EnumerationType`]), `TryFrom<i32>`,
/// `value`, `name` and `description`.
fn enumerations(md: &ModelDescription) -> Result<String, String> {
    let mut out = String::new();
    for t in &md.enumerations {
        out += &enumeration(t)?;
    }
    Ok(out)
}

fn enumeration(t: &EnumerationType) -> Result<String, String> {
    let name = t.name.as_str();
    if !name.chars().all(|c| c.is_ascii_alphanumeric())
        || !name.starts_with(|c: char| c.is_ascii_uppercase())
    {
        return Err(format!(
            "type '{name}': an enumeration's name must be a Rust type name (CamelCase)"
        ));
    }
    let description = t
        .description
        .as_deref()
        .ok_or(format!("type '{name}' needs a description"))?;
    if t.items.is_empty() {
        return Err(format!("type '{name}' has no items"));
    }
    let mut variants = String::new();
    let mut items = String::new();
    let mut from = String::new();
    let mut values = BTreeSet::new();
    for item in &t.items {
        let at = |what: &str| format!("type '{name}', item '{}': {what}", item.name);
        let value: i32 = item
            .value
            .parse()
            .map_err(|_| at(&format!("value '{}' is not an integer", item.value)))?;
        if !values.insert(value) {
            return Err(at(&format!("value {value} is used twice")));
        }
        let d = item
            .description
            .as_deref()
            .ok_or(at("every item needs a description"))?;
        let v = item_ident(&item.name);
        if !v.chars().all(|c| c.is_ascii_alphanumeric()) {
            return Err(at("the name must be a Rust identifier"));
        }
        let doc = d.replace('[', "\\[").replace(']', "\\]");
        writeln!(variants, "    /// {value}: {doc}\n    {v} = {value},").unwrap();
        writeln!(
            items,
            "        Item {{ name: {:?}, value: {value}, description: {d:?} }},",
            item.name
        )
        .unwrap();
        writeln!(from, "            {value} => Ok({name}::{v}),").unwrap();
    }
    let doc = description.replace('[', "\\[").replace(']', "\\]");
    Ok(format!(
        "/// {doc} (the enumeration type `{name}` of the XML).\n\
         #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]\n\
         pub enum {name} {{\n{variants}}}\n\
         impl {name} {{\n\
         \x20   /// The type as the variable table holds it.\n\
         \x20   pub const TYPE: EnumerationType = EnumerationType {{\n\
         \x20       name: {name:?},\n\
         \x20       description: {description:?},\n\
         \x20       items: &[\n{items}        ],\n\
         \x20   }};\n\
         \x20   /// The item's value, as FMI gets and sets it.\n\
         \x20   pub fn value(self) -> i32 {{\n        self as i32\n    }}\n\
         \x20   /// The item of this value in [`Self::TYPE`].\n\
         \x20   pub fn item(self) -> &'static Item {{\n        Self::TYPE.item(self.value()).expect(\"every variant is an item\")\n    }}\n\
         \x20   /// The item's name in the XML.\n\
         \x20   pub fn name(self) -> &'static str {{\n        self.item().name\n    }}\n\
         \x20   /// The item's description in the XML.\n\
         \x20   pub fn description(self) -> &'static str {{\n        self.item().description\n    }}\n\
         }}\n\
         impl TryFrom<i32> for {name} {{\n\
         \x20   type Error = String;\n\
         \x20   /// The item of a value; the error lists the items.\n\
         \x20   fn try_from(value: i32) -> Result<Self, String> {{\n\
         \x20       match value {{\n{from}            other => Err(Self::TYPE.not_an_item(other)),\n        }}\n    }}\n\
         }}\n"
    ))
}

/// SI base-unit exponents in the order of `<BaseUnit>`'s attributes: kg, m, s, A, K, mol, cd, rad.
type Dims = [i32; 8];
const BASE: [&str; 8] = ["kg", "m", "s", "A", "K", "mol", "cd", "rad"];

/// What a unit symbol means in SI: factor and exponents. `g` is both the gram and standard gravity;
/// the dimensions decide which is meant.
fn symbol(sym: &str) -> Vec<(f64, Dims)> {
    let d = |e: [(usize, i32); 4]| {
        let mut dims = [0; 8];
        for (i, x) in e {
            dims[i] += x;
        }
        dims
    };
    let (kg, m, s, a, rad) = (0, 1, 2, 3, 7);
    let none = (0, 0);
    let pa = d([(kg, 1), (m, -1), (s, -2), none]);
    let v = d([(kg, 1), (m, 2), (s, -3), (a, -1)]);
    match sym {
        "1" => vec![(1.0, [0; 8])],
        "m" => vec![(1.0, d([(m, 1), none, none, none]))],
        "s" => vec![(1.0, d([(s, 1), none, none, none]))],
        "min" => vec![(60.0, d([(s, 1), none, none, none]))],
        "g" => vec![
            (1e-3, d([(kg, 1), none, none, none])),
            (9.80665, d([(m, 1), (s, -2), none, none])),
        ],
        "A" => vec![(1.0, d([(a, 1), none, none, none]))],
        "C" => vec![(1.0, d([(a, 1), (s, 1), none, none]))],
        "rad" => vec![(1.0, d([(rad, 1), none, none, none]))],
        "deg" => vec![(
            std::f64::consts::PI / 180.0,
            d([(rad, 1), none, none, none]),
        )],
        "rpm" => vec![(
            2.0 * std::f64::consts::PI / 60.0,
            d([(rad, 1), (s, -1), none, none]),
        )],
        "Hz" => vec![(1.0, d([(s, -1), none, none, none]))],
        "N" => vec![(1.0, d([(kg, 1), (m, 1), (s, -2), none]))],
        "J" => vec![(1.0, d([(kg, 1), (m, 2), (s, -2), none]))],
        "Pa" => vec![(1.0, pa)],
        "bar" => vec![(1e5, pa)],
        "L" => vec![(1e-3, d([(m, 3), none, none, none]))],
        "V" => vec![(1.0, v)],
        "ohm" => vec![(1.0, d([(kg, 1), (m, 2), (s, -3), (a, -2)]))],
        "H" => vec![(1.0, d([(kg, 1), (m, 2), (s, -2), (a, -2)]))],
        _ => vec![],
    }
}

/// An atom: optional SI prefix, symbol, optional integer exponent (`cm3`, `kg`, `mV`, `m5`).
fn atom(text: &str) -> Result<Vec<(f64, Dims)>, String> {
    let split = text
        .find(|c: char| c.is_ascii_digit() || c == '-')
        .filter(|&i| i > 0 || text == "1")
        .unwrap_or(text.len());
    let (name, exp) = if text == "1" {
        ("1", 1)
    } else {
        let exp = if split < text.len() {
            text[split..]
                .parse::<i32>()
                .map_err(|_| format!("bad exponent in '{text}'"))?
        } else {
            1
        };
        (&text[..split], exp)
    };
    let mut found = symbol(name);
    if found.is_empty() {
        let prefixes = [
            ("n", 1e-9),
            ("u", 1e-6),
            ("m", 1e-3),
            ("c", 1e-2),
            ("k", 1e3),
            ("M", 1e6),
        ];
        for (p, f) in prefixes {
            if let Some(rest) = name.strip_prefix(p) {
                found.extend(symbol(rest).into_iter().map(|(x, d)| (x * f, d)));
            }
        }
    }
    if found.is_empty() {
        return Err(format!("unknown unit symbol '{name}'"));
    }
    Ok(found
        .into_iter()
        .map(|(f, d)| (f.powi(exp), d.map(|x| x * exp)))
        .collect())
}

/// Every SI meaning of a unit expression such as `bar.min/L` or `m3/(s.V)`: `.` multiplies,
/// `/` divides by the next factor, parentheses group.
fn unit_meanings(expr: &str) -> Result<Vec<(f64, Dims)>, String> {
    fn product(s: &[u8], i: &mut usize) -> Result<Vec<(f64, Dims)>, String> {
        let mut acc = factor(s, i)?;
        while *i < s.len() && (s[*i] == b'.' || s[*i] == b'/') {
            let divide = s[*i] == b'/';
            *i += 1;
            let rhs = factor(s, i)?;
            let mut next = Vec::new();
            for (fa, da) in &acc {
                for (fb, db) in &rhs {
                    let sign = if divide { -1 } else { 1 };
                    let mut d = *da;
                    for k in 0..8 {
                        d[k] += sign * db[k];
                    }
                    next.push((if divide { fa / fb } else { fa * fb }, d));
                }
            }
            acc = next;
        }
        Ok(acc)
    }
    fn factor(s: &[u8], i: &mut usize) -> Result<Vec<(f64, Dims)>, String> {
        if s.get(*i) == Some(&b'(') {
            *i += 1;
            let inner = product(s, i)?;
            if s.get(*i) != Some(&b')') {
                return Err("missing ')'".into());
            }
            *i += 1;
            return Ok(inner);
        }
        let start = *i;
        while *i < s.len() && !matches!(s[*i], b'.' | b'/' | b'(' | b')') {
            *i += 1;
        }
        atom(std::str::from_utf8(&s[start..*i]).map_err(|e| e.to_string())?)
    }
    let bytes = expr.as_bytes();
    let mut i = 0;
    let meanings = product(bytes, &mut i)?;
    if i != bytes.len() {
        return Err(format!("cannot read the unit '{expr}'"));
    }
    Ok(meanings)
}

/// Checks a `<Unit>`: its name means what its `<BaseUnit>` says, and every `<DisplayUnit>`'s
/// factor converts to what its name means (so `bar.min/L` must have factor 1/6e9).
fn check_unit(u: &Unit) -> Result<(), String> {
    let name = u.name.as_str();
    let mut dims: Dims = [0; 8];
    let mut base_factor = 1.0;
    if let Some(b) = &u.base_unit {
        for (k, e) in BASE.iter().enumerate() {
            if let Some(x) = get(b, e) {
                dims[k] = x
                    .parse()
                    .map_err(|_| format!("unit '{name}': bad exponent {e}=\"{x}\""))?;
            }
        }
        if let Some(f) = get(b, "factor") {
            base_factor = f
                .parse()
                .map_err(|_| format!("unit '{name}': bad factor"))?;
        }
    }
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
    let means = |expr: &str, scale: f64| -> Result<bool, String> {
        Ok(unit_meanings(expr)?
            .iter()
            .any(|(f, d)| *d == dims && close(*f, scale)))
    };
    if !means(name, base_factor).map_err(|e| format!("unit '{name}': {e}"))? {
        return Err(format!(
            "unit '{name}' does not mean its <BaseUnit> (exponents {dims:?} of {BASE:?}, factor {base_factor})"
        ));
    }
    for du in &u.display_units {
        let (dname, factor) = (du.name.as_str(), du.factor);
        // display value = factor * value in the unit; one display unit is base_factor / factor
        // in SI.
        if !means(dname, base_factor / factor)
            .map_err(|e| format!("display unit '{dname}': {e}"))?
        {
            let right = unit_meanings(dname)?
                .iter()
                .find(|(_, d)| *d == dims)
                .map(|(f, _)| base_factor / f);
            return Err(format!(
                "display unit '{dname}' of unit '{name}' has factor {factor:e}, but its name gives {}",
                right.map_or("other dimensions".to_string(), |f| format!("{f:e}"))
            ));
        }
    }
    Ok(())
}
