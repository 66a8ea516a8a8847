//! `hsp info`: the size and structure of the assembled model for a parameter set: states,
//! inputs, outputs, the evaluation plan, and the Jacobian the integrator evaluates at every step
//! (its pattern, which entries vary with the state and inputs, and how many dual-number passes
//! one evaluation takes with and without the constant entries fixed).

use hydraulic_slewing_plate::model::assembly::Assembled;

/// The facts `hsp info` prints, as JSON.
pub fn facts(system: &Assembled) -> serde_json::Value {
    let m = system.compiled();
    let names = |cols: &[u32]| -> Vec<&str> {
        cols.iter()
            .map(|&j| m.state_names()[j as usize].as_str())
            .collect()
    };
    let nonzeros: usize = m.jacobian_pattern().iter().map(Vec::len).sum();
    let varying: usize = m.jacobian_varying_pattern().iter().map(Vec::len).sum();
    // What each step evaluates: the varying entries by the chain rule through the forms of the
    // rows that are not affine (`FormsJacobian`), a multiply-add per link.
    let forms = m.nonaffine_forms();
    let (_, chain_links) = forms
        .jacobian(m.n_states(), m.jacobian_varying_pattern())
        .size();
    let (nonlinear, coefficients) = forms.size();
    let (operations_in_lanes, rows_in_lanes, operations_shared) = forms.side_by_side();
    serde_json::json!({
        "states": m.n_states(),
        "inputs": m.input_names(),
        "outputs": m.n_outputs(),
        "plan_operations": m.plan_len(),
        "derivative_operations": m.derivative_plan_len(),
        "nonaffine_rows": m.nonaffine_rows().len(),
        "nonaffine_operations": m.nonaffine_plan_len(),
        "nonaffine_outputs": m.nonaffine_outputs().len(),
        "communication_point_operations": m.nonaffine_point_plan_len(),
        "forms": {
            "nonlinear_operations": nonlinear,
            "coefficients": coefficients,
            "operands_four_at_a_time": operations_in_lanes,
            "operands_reading_one_variable_per_lane": operations_shared,
            "rows_four_at_a_time": rows_in_lanes,
        },
        "jacobian": {
            "nonzeros": nonzeros,
            "varying_entries": varying,
            "varying_rows": m.jacobian_varying_pattern().iter().filter(|r| !r.is_empty()).count(),
            "variable_columns": names(&m.jacobian_variable_columns()),
            "constant": m.jacobian_is_constant(),
            "passes_full": m.jacobian_colours(),
            "passes_per_step": m.variable_jacobian_colours(),
            "operations_full": m.jacobian_colours() * m.derivative_plan_len(),
            "operations_per_step": m.variable_jacobian_ops(),
            "chain_links_per_step": chain_links,
            "constant_entries_fixed": m.constant_entries_fixed(),
        },
    })
}

/// The facts as text for people.
pub fn text(system: &Assembled) -> String {
    let m = system.compiled();
    let f = facts(system);
    let j = &f["jacobian"];
    let n = m.n_states();
    let variable: Vec<&str> = j["variable_columns"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|v| v.as_str())
        .collect();
    let mut s = format!(
        "states     {n}\ninputs     {} ({})\noutputs    {}\n",
        m.n_inputs(),
        m.input_names().join(", "),
        m.n_outputs()
    );
    s.push_str(&format!(
        "plan       {} operations, {} of them for the state derivatives\n",
        m.plan_len(),
        m.derivative_plan_len()
    ));
    s.push_str(&format!(
        "f          {} of {n} rows affine in x (a product with their constant gradients); {} \
         through the {} operations they need\n",
        n - m.nonaffine_rows().len(),
        m.nonaffine_rows().len(),
        m.nonaffine_plan_len()
    ));
    let forms = &f["forms"];
    s.push_str(&format!(
        "forms      the rows not affine: {} nonlinear operations and {} coefficients; {} \
         operands ({} of them in fours over the same variables, each loaded once) and {} rows \
         of one length summed four at a time\n",
        forms["nonlinear_operations"],
        forms["coefficients"],
        forms["operands_four_at_a_time"],
        forms["operands_reading_one_variable_per_lane"],
        forms["rows_four_at_a_time"]
    ));
    s.push_str(&format!(
        "points     {} of {} outputs affine in x (C x + y(0, u)); the others and the rows \
         above from {} operations at a communication point\n",
        m.n_outputs() - m.nonaffine_outputs().len(),
        m.n_outputs(),
        m.nonaffine_point_plan_len()
    ));
    s.push_str(&format!(
        "Jacobian   {} structural nonzeros of {}; {} vary with (x, u), in {} rows and {} \
         variable columns{}\n",
        j["nonzeros"],
        n * n,
        j["varying_entries"],
        j["varying_rows"],
        variable.len(),
        if m.jacobian_is_constant() {
            " (J is constant)"
        } else {
            ""
        }
    ));
    let full = format!(
        "{} dual-number passes of {} operations",
        m.jacobian_colours(),
        m.derivative_plan_len()
    );
    s.push_str(&if m.jacobian_is_constant() {
        format!("passes     {full}, once per parameter set\n")
    } else {
        format!(
            "passes     {full} for every entry; once the constant entries are fixed, one \
             value pass and tangent sweeps over {} column groups, {} operations in all; each \
             step: the varying entries by the chain rule through the forms of f, {} \
             multiply-adds\n",
            m.variable_jacobian_colours(),
            m.variable_jacobian_ops(),
            j["chain_links_per_step"]
        )
    });
    if !variable.is_empty() {
        s.push_str(&format!("variable   {}\n", variable.join(", ")));
    }
    s.trim_end().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use hydraulic_slewing_plate::fmu::{Experiment, Values};
    use hydraulic_slewing_plate::model::parameters::{set_by_name, Parameters};
    use hydraulic_slewing_plate::model::presets;
    use hydraulic_slewing_plate::model::variables::VARIABLES;

    #[test]
    fn info_of_the_complete_system_names_the_passes_and_the_variable_columns() {
        let mut values = Values::from_start(&VARIABLES);
        presets::apply(&mut values, presets::COMPLETE).unwrap();
        // Without the command generator's clock and the air drag, only the valve's columns vary,
        // and the pressure filter's, which feeds the current amplifier's compliance limit.
        set_by_name(&mut values, "reference.angle", "0").unwrap();
        set_by_name(&mut values, "plate.Cd", "0").unwrap();
        let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
        let system = Assembled::new(&p).unwrap();
        let m = system.compiled();
        let f = facts(&system);
        let j = &f["jacobian"];
        assert_eq!(j["passes_full"], m.jacobian_colours());
        assert_eq!(j["passes_per_step"], m.variable_jacobian_colours());
        assert_eq!(j["constant"], false);
        assert_eq!(j["constant_entries_fixed"], true);
        // The valve's rows are not affine, and need fewer operations than all the rows.
        let rows = f["nonaffine_rows"].as_u64().unwrap() as usize;
        assert!(rows > 0 && rows < m.n_states(), "{rows}");
        assert!(f["nonaffine_operations"].as_u64().unwrap() < m.derivative_plan_len() as u64);
        let cols = j["variable_columns"].as_array().unwrap();
        assert_eq!(cols.len(), m.jacobian_variable_columns().len());
        assert!(cols
            .iter()
            .all(|c| c.as_str().unwrap().starts_with("servo_valve.")
                || c.as_str().unwrap() == "controller.p_f"));
        let t = text(&system);
        assert!(t.contains(&format!("{} dual-number passes", m.jacobian_colours())));
        assert!(t.contains("forms      the rows not affine: "), "{t}");
        assert!(t.contains("variable   servo_valve."), "{t}");
    }

    /// The default plant's air drag gives runs of forms of one length: its points' operands
    /// (the air speeds over the same momenta) and the rows of the modes it reaches are summed
    /// four at a time.
    #[test]
    fn the_default_plants_drag_forms_are_summed_four_at_a_time() {
        let values = Values::from_start(&VARIABLES);
        let p = Parameters::from_values(&values, &Experiment::default()).unwrap();
        let system = Assembled::new(&p).unwrap();
        let forms = &facts(&system)["forms"];
        let operands = forms["operands_four_at_a_time"].as_u64().unwrap();
        assert!(operands >= 4, "{forms}");
        // The air speeds read the same momenta: loaded once, not gathered.
        let shared = forms["operands_reading_one_variable_per_lane"]
            .as_u64()
            .unwrap();
        assert!(shared >= 4, "{forms}");
        assert!(
            forms["rows_four_at_a_time"].as_u64().unwrap() >= 2,
            "{forms}"
        );
    }
}
