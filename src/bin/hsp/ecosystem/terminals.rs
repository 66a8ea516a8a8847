//! FMI 3.0's `terminalsAndIcons/terminalsAndIcons.xml`: the FMU's signals grouped as the rig's
//! plugs, so that a tool can connect a whole group at once. Every member is a signal (FMI 3.0
//! `variableKind="signal"`) matched by name (`matchingRule="bus"`); the names are FMI 3.0's (the
//! accelerometers are the array `acc`), checked against the model description when written.

use std::fmt::Write as _;

use super::ssp::escape;

/// A terminal: its name, what it is, and its members' variable names.
struct Terminal {
    name: &'static str,
    description: &'static str,
    members: &'static [&'static str],
}

/// The terminals, in the order of the signal path: command, disturbances, sensors.
const TERMINALS: &[Terminal] = &[
    Terminal {
        name: "drive",
        description: "Command inputs: the reference r of the position loop and the external \
                      coil drive e_in (used with controller.external)",
        members: &["r", "e_in"],
    },
    Terminal {
        name: "shakers",
        description: "The shaker forces F1 and F2, normal to the plate",
        members: &["F1", "F2"],
    },
    Terminal {
        name: "accelerometers",
        description: "The 12 accelerometers of the 4 x 3 grid on the plate",
        members: &["acc"],
    },
    Terminal {
        name: "hub",
        description: "Hub sensors: angle and speed",
        members: &["theta_hub", "omega_hub"],
    },
    Terminal {
        name: "motor",
        description: "Actuator sensors: the potentiometer, the rotor's angle and speed, and the \
                      load pressure across the vane motor",
        members: &["y_pot", "theta_motor", "omega_motor", "p_load"],
    },
];

/// The variable names of the FMI 3.0 model description `xml3`.
fn variable_names(xml3: &str) -> Result<Vec<String>, String> {
    let doc = roxmltree::Document::parse(xml3).map_err(|e| format!("FMI 3.0 XML: {e}"))?;
    Ok(super::fmi3_model_variables(&doc)?
        .children()
        .filter_map(|n| n.attribute("name"))
        .map(str::to_string)
        .collect())
}

/// `terminalsAndIcons.xml` for the FMI 3.0 model description `xml3`; fails if a member is not
/// one of its variables.
pub fn xml(xml3: &str) -> Result<String, String> {
    let names = variable_names(xml3)?;
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    s.push_str(
        "<!-- Written by hsp package (src/bin/hsp/ecosystem/terminals.rs); docs/ecosystem.md -->\n",
    );
    s.push_str("<fmiTerminalsAndIcons fmiVersion=\"3.0\">\n  <Terminals>\n");
    for t in TERMINALS {
        writeln!(
            s,
            "    <Terminal name=\"{}\" matchingRule=\"bus\" description=\"{}\">",
            t.name,
            escape(t.description)
        )
        .unwrap();
        for m in t.members {
            if !names.iter().any(|n| n == m) {
                return Err(format!(
                    "terminal {}: {m} is not a variable of the FMI 3.0 model description",
                    t.name
                ));
            }
            writeln!(
                s,
                "      <TerminalMemberVariable variableName=\"{m}\" memberName=\"{m}\" \
                 variableKind=\"signal\"/>"
            )
            .unwrap();
        }
        s.push_str("    </Terminal>\n");
    }
    s.push_str("  </Terminals>\n</fmiTerminalsAndIcons>\n");
    Ok(s)
}
