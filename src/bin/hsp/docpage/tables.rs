//! The tables of the documentation page: the variables, by causality, as the model description
//! declares them, and the named parameter sets.

use std::fmt::Write as _;

use hydraulic_slewing_plate::model::presets::PRESETS;

use super::text::{escape, short, short_text};
use crate::model_description::{ModelDescription, ScalarVariable};

/// The variable tables, one a causality present, each under its title and a note.
pub fn variables(md: &ModelDescription) -> String {
    let mut tables = String::new();
    for (title, causalities, note) in [
        (
            "Inputs",
            &["input"][..],
            "Set them between communication steps.",
        ),
        ("Outputs", &["output"][..], "Read-only."),
        (
            "Parameters",
            &["parameter"][..],
            "<em>fixed</em> parameters can be set only before initialisation (between \
             <code>fmi2Instantiate</code> and <code>fmi2ExitInitializationMode</code>); \
             <em>tunable</em> ones at any time. A value outside min/max is refused by \
             <code>fmi2SetReal</code>/<code>fmi2SetInteger</code> with a message naming the \
             variable.",
        ),
        (
            "Calculated parameters",
            &["calculatedParameter"][..],
            "Read-only: computed at initialisation from the parameters (for example the plate's \
             natural frequencies <code>plate.f[i]</code>).",
        ),
        (
            "Continuous states and their derivatives",
            &["local"][..],
            "Model Exchange integrates these: the storages' momenta <code>p</code> and \
             displacements <code>q</code> of the bond graph, set through \
             <code>fmi2SetContinuousStates</code>; a state the chosen configuration does not \
             have keeps its value with derivative 0. Co-Simulation reports them after each step.",
        ),
    ] {
        if !md
            .variables
            .iter()
            .any(|v| causalities.contains(&v.causality.as_str()))
        {
            continue;
        }
        writeln!(tables, "<h3>{title}</h3>\n<p>{note}</p>").unwrap();
        variable_table(md, causalities, &mut tables);
    }
    tables
}

/// When a variable may be set, in words.
fn settable(v: &ScalarVariable) -> &'static str {
    match (v.causality.as_str(), v.variability.as_str()) {
        ("input", _) => "any time (input)",
        ("parameter", "fixed") => "before initialisation only",
        ("parameter", "tunable") => "any time",
        ("calculatedParameter", _) | ("output", _) | ("local", _) => "read-only",
        (_, "constant") => "read-only",
        _ => "see the FMI standard",
    }
}

fn variable_table(md: &ModelDescription, causalities: &[&str], s: &mut String) {
    s.push_str(
        "<table>\n<tr><th>name</th><th>type</th><th>causality / variability</th><th>settable</th>\
         <th>start</th><th>min</th><th>max</th><th>unit</th><th>start in display unit</th>\
         <th>description</th></tr>\n",
    );
    for v in md
        .variables
        .iter()
        .filter(|v| causalities.contains(&v.causality.as_str()))
    {
        let display = match (
            md.display_unit(v),
            v.start.as_deref().map(str::parse::<f64>),
        ) {
            (Some(unit), Some(Ok(x))) => format!(
                "{} {}",
                short(x * unit.factor + unit.offset),
                escape(&unit.name)
            ),
            (Some(unit), _) => escape(&unit.name),
            _ => String::new(),
        };
        let opt = |o: &Option<String>| o.as_deref().map(short_text).unwrap_or_default();
        // An Enumeration's type with its items: `Enumeration PlateRoot (1 = Hub, 2 = Locked)`.
        let kind = match v.declared_type.as_deref().and_then(|t| md.enumeration(t)) {
            Some(t) => {
                let items: Vec<String> = t
                    .items
                    .iter()
                    .map(|i| format!("{} = {}", i.value, i.name))
                    .collect();
                format!(
                    "{} {} ({})",
                    v.kind,
                    escape(&t.name),
                    escape(&items.join(", "))
                )
            }
            None => v.kind.clone(),
        };
        writeln!(
            s,
            "<tr><td><code>{}</code></td><td>{}</td><td>{} / {}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&v.name),
            kind,
            v.causality,
            v.variability,
            settable(v),
            opt(&v.start),
            opt(&v.min),
            opt(&v.max),
            escape(v.unit.as_deref().unwrap_or("")),
            display,
            escape(v.description.as_deref().unwrap_or(""))
        )
        .unwrap();
    }
    s.push_str("</table>\n");
}

/// The named parameter sets (the paper's configurations) and their settings.
pub fn presets() -> String {
    let mut presets = String::from(
        "<table>\n<tr><th>name</th><th>in the paper</th><th>what</th><th>settings</th></tr>\n",
    );
    for p in PRESETS {
        let settings: Vec<String> = p
            .settings
            .iter()
            .map(|(k, v)| format!("<code>{k} = {}</code>", short_text(v)))
            .collect();
        writeln!(
            presets,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td></tr>",
            p.name,
            escape(p.paper),
            escape(p.description),
            settings.join(", ")
        )
        .unwrap();
    }
    presets.push_str("</table>\n");
    presets
}
