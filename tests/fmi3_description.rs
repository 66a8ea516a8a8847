//! The FMI 3.0 `modelDescription.xml` cannot drift from the FMI 2.0 one nor from the FMI 3.0
//! layer: it is what `modelDescription/fmi3.py` writes from the FMI 2.0 file, and it declares
//! exactly the variables (names, value references, array sizes, types, causalities) that the
//! layer's table ([`Fmi3Table`]) serves.

use std::path::PathBuf;
use std::process::Command;

use hydraulic_slewing_plate::fmi3::variables::{fmi3_type_name, Fmi3Table, TIME_VALUE_REFERENCE};
use hydraulic_slewing_plate::fmu::Variability;
use hydraulic_slewing_plate::model::variables::{CONTINUOUS_STATES, GUID, VARIABLES};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn the_fmi3_description_is_generated_from_the_fmi2_one() {
    let out = Command::new("python3")
        .arg("modelDescription/fmi3.py")
        .arg("--check")
        .current_dir(root())
        .output()
        .expect("python3 is needed to check modelDescription/fmi3/modelDescription.xml");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn variability(v: Variability) -> &'static str {
    match v {
        Variability::Constant => "constant",
        Variability::Fixed => "fixed",
        Variability::Tunable => "tunable",
        Variability::Discrete => "discrete",
        Variability::Continuous => "continuous",
    }
}

#[test]
fn the_fmi3_description_declares_what_the_layer_serves() {
    let text =
        std::fs::read_to_string(root().join("modelDescription/fmi3/modelDescription.xml")).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let md = doc.root_element();
    assert_eq!(md.attribute("fmiVersion"), Some("3.0"));
    assert_eq!(md.attribute("instantiationToken"), Some(GUID));
    let variables = md
        .children()
        .find(|n| n.has_tag_name("ModelVariables"))
        .unwrap();
    let declared: Vec<_> = variables.children().filter(|n| n.is_element()).collect();

    let table = Fmi3Table::new(&VARIABLES, &CONTINUOUS_STATES);
    // time first, then the table in order.
    assert_eq!(declared.len(), table.variables().len() + 1);
    let time = declared[0];
    assert_eq!(time.attribute("name"), Some("time"));
    assert_eq!(time.attribute("causality"), Some("independent"));
    assert_eq!(time.attribute("unit"), Some("s"));
    assert_eq!(
        time.attribute("valueReference"),
        Some(TIME_VALUE_REFERENCE.to_string().as_str())
    );
    let mut arrays = Vec::new();
    for (node, v) in declared[1..].iter().zip(table.variables()) {
        let first = &VARIABLES[v.first];
        assert_eq!(node.attribute("name"), Some(v.name.as_str()));
        assert_eq!(
            node.attribute("valueReference"),
            Some(v.value_reference.to_string().as_str()),
            "{}",
            v.name
        );
        assert_eq!(
            node.tag_name().name(),
            fmi3_type_name(&first.kind),
            "{}",
            v.name
        );
        assert_eq!(
            node.attribute("causality"),
            Some(first.causality.xml_name()),
            "{}",
            v.name
        );
        assert_eq!(
            node.attribute("variability"),
            Some(variability(first.variability)),
            "{}",
            v.name
        );
        assert_eq!(node.attribute("unit"), first.unit, "{}", v.name);
        let dims: Vec<_> = node
            .children()
            .filter(|n| n.has_tag_name("Dimension"))
            .map(|d| d.attribute("start").unwrap().parse::<usize>().unwrap())
            .collect();
        if v.len > 1 {
            assert_eq!(dims, [v.len], "{}", v.name);
            arrays.push((v.name.clone(), v.len));
        } else {
            assert!(dims.is_empty(), "{}", v.name);
        }
    }
    // The arrays the issue names: the 12 accelerometers and the plate frequencies.
    assert_eq!(
        arrays,
        [("acc".to_string(), 12), ("plate.f".to_string(), 20)],
        "the FMI 3.0 arrays"
    );
}

#[test]
fn both_descriptions_state_the_rules_min_and_max_cannot() {
    // F6 of the fuzz round: only the FMI 2.0 file stated that the <Positive> parameters refuse 0,
    // and neither the magnitudes. The FMI 3.0 file's annotation now holds the same rules as the
    // FMI 2.0 file's vendor annotation, which build.rs turns into the table the checks read.
    use hydraulic_slewing_plate::fragments::rules::RULES;
    use hydraulic_slewing_plate::model::variables::MAGNITUDES;
    let text =
        std::fs::read_to_string(root().join("modelDescription/fmi3/modelDescription.xml")).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let rules = doc
        .descendants()
        .find(|n| {
            n.has_tag_name("Annotation") && n.attribute("type") == Some("hydraulic-slewing-plate")
        })
        .expect("the FMI 3.0 description's annotation of the rules");
    // The annotation's text: `positive = <names>` and `magnitudes = <smallest> <largest>`.
    let text = rules.text().expect("the rules as text");
    let rule = |name: &str| -> Vec<&str> {
        text.lines()
            .find_map(|l| l.trim().strip_prefix(name)?.trim().strip_prefix('='))
            .unwrap_or_else(|| panic!("no rule '{name}' in {text}"))
            .split_whitespace()
            .collect()
    };
    // The table is sorted by name.
    let table: Vec<&str> = RULES
        .iter()
        .filter(|(_, r)| r.positive)
        .map(|(name, _)| *name)
        .collect();
    let mut stated = rule("positive");
    stated.sort_unstable();
    assert_eq!(stated, table);
    let magnitudes: Vec<f64> = rule("magnitudes")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(magnitudes[0]..=magnitudes[1], MAGNITUDES);
}
