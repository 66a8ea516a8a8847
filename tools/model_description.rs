//! The one reader of `modelDescription/modelDescription.xml` (FMI 2.0): where each fact sits in
//! the XML and what an absent attribute means (FMI 2.0's defaults) are written here and nowhere
//! else in Rust. It reads; it does not judge: the project's rules on the content (units that mean
//! what they say, legal causality and variability, the GUID, `<ModelStructure>`) are `build.rs`'s.
//!
//! Included by path, with `roxmltree` as its only dependency, by `build.rs` (which writes the
//! library's variable table from it: `#[path = "tools/model_description.rs"]`) and by the `hsp`
//! tool (its documentation page). The FMU library itself reads no XML at run time.

/// An element's attributes, name and value, in document order.
pub type Attributes = Vec<(String, String)>;

/// The value of attribute `name` in `attributes`.
pub fn get<'a>(attributes: &'a [(String, String)], name: &str) -> Option<&'a str> {
    attributes
        .iter()
        .find(|(k, _)| k == name)
        .map(|(_, v)| v.as_str())
}

/// What `modelDescription.xml` declares.
#[derive(Debug)]
pub struct ModelDescription {
    /// The attributes of `<fmiModelDescription>` (`fmiVersion`, `modelName`, `guid`, ...).
    pub attributes: Attributes,
    /// The attributes of `<CoSimulation>`, if present.
    pub co_simulation: Option<Attributes>,
    /// The attributes of `<ModelExchange>`, if present.
    pub model_exchange: Option<Attributes>,
    /// The attributes of `<DefaultExperiment>`, if present.
    pub default_experiment: Option<Attributes>,
    /// `<UnitDefinitions>`, in order.
    pub units: Vec<Unit>,
    /// The enumeration types of `<TypeDefinitions>` (`<SimpleType>` with `<Enumeration>`), in
    /// order.
    pub enumerations: Vec<EnumerationType>,
    /// The `<Tool>` elements of `<VendorAnnotations>`, by their `name`, with the tag names and
    /// attributes of the elements inside (at any depth, in document order).
    pub vendor_annotations: Vec<(String, Vec<(String, Attributes)>)>,
    /// `<ModelVariables>`: the scalar variables in order (position `i` is FMI's index `i + 1`).
    pub variables: Vec<ScalarVariable>,
    /// `<ModelStructure>`.
    pub structure: ModelStructure,
}

/// A `<Unit>`.
#[derive(Debug)]
pub struct Unit {
    pub name: String,
    /// The attributes of its `<BaseUnit>` (exponents `kg`, `m`, ..., `factor`, `offset`), if any.
    pub base_unit: Option<Attributes>,
    pub display_units: Vec<DisplayUnit>,
}

/// A `<SimpleType>` whose type element is `<Enumeration>`.
#[derive(Debug)]
pub struct EnumerationType {
    pub name: String,
    pub description: Option<String>,
    pub items: Vec<Item>,
}

/// An `<Item>` of an `<Enumeration>` type (its `value` as text, as the other numbers here).
#[derive(Debug)]
pub struct Item {
    pub name: String,
    pub value: String,
    pub description: Option<String>,
}

/// A `<DisplayUnit>`: a value in it is `factor * value + offset`, the value in the unit.
#[derive(Debug, Clone)]
pub struct DisplayUnit {
    pub name: String,
    /// 1 when absent.
    pub factor: f64,
    /// 0 when absent.
    pub offset: f64,
}

/// A `<ScalarVariable>` and its type element. Numbers stay text: each reader parses them as the
/// type needs.
#[derive(Debug)]
pub struct ScalarVariable {
    pub name: String,
    pub value_reference: u32,
    pub description: Option<String>,
    /// `local` when absent.
    pub causality: String,
    /// `continuous` when absent.
    pub variability: String,
    pub initial: Option<String>,
    /// The type element's name: `Real`, `Integer`, `Boolean`, `String` or `Enumeration`.
    pub kind: String,
    pub start: Option<String>,
    pub min: Option<String>,
    pub max: Option<String>,
    pub unit: Option<String>,
    pub display_unit: Option<String>,
    /// `declaredType`: the name of a `<SimpleType>` (an Enumeration variable's type).
    pub declared_type: Option<String>,
    /// `nominal` (Real variables).
    pub nominal: Option<String>,
    /// `derivative`: the 1-based index of the variable this one is the derivative of.
    pub derivative: Option<String>,
    /// The group the XML puts it in: the text of the last comment before it in
    /// `<ModelVariables>` (`analog controller`, `servo valve (hydraulics.model = 2): ...`),
    /// whitespace collapsed; `None` before the first comment.
    pub group: Option<String>,
}

/// An `<Unknown>` of `<ModelStructure>`.
#[derive(Debug)]
pub struct Unknown {
    /// 1-based index into the variables.
    pub index: usize,
    /// 1-based indices of the knowns it depends on; `None` when the attribute is absent (FMI:
    /// it depends on every known).
    pub dependencies: Option<Vec<usize>>,
}

/// `<ModelStructure>`: each list is empty when its element is absent.
#[derive(Debug)]
pub struct ModelStructure {
    pub outputs: Vec<Unknown>,
    pub derivatives: Vec<Unknown>,
    pub initial_unknowns: Vec<Unknown>,
}

impl ModelDescription {
    /// Reads the text of `modelDescription.xml`. Errors name what is missing or unreadable.
    pub fn parse(text: &str) -> Result<Self, String> {
        let doc =
            roxmltree::Document::parse(text).map_err(|e| format!("not well-formed XML: {e}"))?;
        let root = doc.root_element();
        let child = |name: &str| root.children().find(|n| n.has_tag_name(name));
        let mut units = Vec::new();
        if let Some(defs) = child("UnitDefinitions") {
            for u in defs.children().filter(|n| n.has_tag_name("Unit")) {
                units.push(unit(u)?);
            }
        }
        let mut enumerations = Vec::new();
        if let Some(defs) = child("TypeDefinitions") {
            for t in defs.children().filter(|n| n.has_tag_name("SimpleType")) {
                if let Some(e) = t.children().find(|n| n.has_tag_name("Enumeration")) {
                    enumerations.push(enumeration(t, e)?);
                }
            }
        }
        let vendor_annotations = child("VendorAnnotations")
            .map(|v| {
                v.children()
                    .filter(|n| n.has_tag_name("Tool"))
                    .map(|tool| {
                        // FMI 2.0 allows one element in a <Tool>: the rules sit in a wrapper
                        // (<Rules>), read here at any depth.
                        let content = tool
                            .descendants()
                            .filter(|n| n.is_element() && *n != tool)
                            .map(|n| (n.tag_name().name().to_string(), attributes(n)))
                            .collect();
                        (tool.attribute("name").unwrap_or("").to_string(), content)
                    })
                    .collect()
            })
            .unwrap_or_default();
        // Each variable in the group of the last comment before it.
        let mut group: Option<String> = None;
        let mut variables = Vec::new();
        for n in child("ModelVariables")
            .ok_or("no <ModelVariables>")?
            .children()
        {
            if n.is_comment() {
                let text = n.text().unwrap_or("").split_whitespace();
                group = Some(text.collect::<Vec<_>>().join(" "));
            } else if n.has_tag_name("ScalarVariable") {
                let mut sv = variable(variables.len() + 1, n)?;
                sv.group = group.clone();
                variables.push(sv);
            }
        }
        let structure = child("ModelStructure").ok_or("no <ModelStructure>")?;
        let list = |tag: &str| -> Result<Vec<Unknown>, String> {
            match structure.children().find(|n| n.has_tag_name(tag)) {
                None => Ok(Vec::new()),
                Some(n) => n
                    .children()
                    .filter(|u| u.has_tag_name("Unknown"))
                    .map(|u| unknown(tag, u))
                    .collect(),
            }
        };
        Ok(ModelDescription {
            attributes: attributes(root),
            co_simulation: child("CoSimulation").map(attributes),
            model_exchange: child("ModelExchange").map(attributes),
            default_experiment: child("DefaultExperiment").map(attributes),
            units,
            enumerations,
            vendor_annotations,
            variables,
            structure: ModelStructure {
                outputs: list("Outputs")?,
                derivatives: list("Derivatives")?,
                initial_unknowns: list("InitialUnknowns")?,
            },
        })
    }

    /// The value of the root's attribute `name`.
    pub fn attribute(&self, name: &str) -> Option<&str> {
        get(&self.attributes, name)
    }

    /// The switches that `<Tool name="{tool}">` of `<VendorAnnotations>` declares with
    /// `<Enumeration variable="..." declaredType="..."/>`: `(variable, type)` pairs, in order.
    /// Such a variable is an `<Integer>` in the FMI 2.0 description (libcosim and ecos skip FMI
    /// 2.0 Enumerations) and an Enumeration of that type in FMI 3.0 and in the Rust table.
    pub fn switches(&self, tool: &str) -> Vec<(&str, &str)> {
        self.vendor_annotations
            .iter()
            .filter(|(name, _)| name == tool)
            .flat_map(|(_, content)| content.iter())
            .filter(|(tag, _)| tag == "Enumeration")
            .map(|(_, a)| {
                (
                    get(a, "variable").unwrap_or(""),
                    get(a, "declaredType").unwrap_or(""),
                )
            })
            .collect()
    }

    /// The enumeration type named `name`.
    pub fn enumeration(&self, name: &str) -> Option<&EnumerationType> {
        self.enumerations.iter().find(|t| t.name == name)
    }

    /// The unit named `name`.
    pub fn unit(&self, name: &str) -> Option<&Unit> {
        self.units.iter().find(|u| u.name == name)
    }

    /// The display unit a variable is shown in: its `displayUnit`, else its unit's first
    /// display unit (none when its unit has none).
    pub fn display_unit(&self, v: &ScalarVariable) -> Option<&DisplayUnit> {
        let list = &self.unit(v.unit.as_deref()?)?.display_units;
        match &v.display_unit {
            Some(d) => list.iter().find(|u| &u.name == d),
            None => list.first(),
        }
    }
}

fn attributes(node: roxmltree::Node) -> Attributes {
    node.attributes()
        .map(|a| (a.name().to_string(), a.value().to_string()))
        .collect()
}

fn unit(u: roxmltree::Node) -> Result<Unit, String> {
    let name = u.attribute("name").ok_or("a Unit has no name")?;
    let display_units = u
        .children()
        .filter(|n| n.has_tag_name("DisplayUnit"))
        .map(|d| {
            let dname = d
                .attribute("name")
                .ok_or(format!("unit '{name}': a DisplayUnit has no name"))?;
            let number = |key: &str, default: f64| match d.attribute(key) {
                None => Ok(default),
                Some(s) => s
                    .parse::<f64>()
                    .map_err(|_| format!("display unit '{dname}': bad {key}")),
            };
            Ok(DisplayUnit {
                name: dname.to_string(),
                factor: number("factor", 1.0)?,
                offset: number("offset", 0.0)?,
            })
        })
        .collect::<Result<_, String>>()?;
    Ok(Unit {
        name: name.to_string(),
        base_unit: u
            .children()
            .find(|n| n.has_tag_name("BaseUnit"))
            .map(attributes),
        display_units,
    })
}

fn enumeration(t: roxmltree::Node, e: roxmltree::Node) -> Result<EnumerationType, String> {
    let name = t.attribute("name").ok_or("a SimpleType has no name")?;
    let items = e
        .children()
        .filter(|n| n.has_tag_name("Item"))
        .map(|i| {
            Ok(Item {
                name: i
                    .attribute("name")
                    .ok_or(format!("type '{name}': an Item has no name"))?
                    .to_string(),
                value: i
                    .attribute("value")
                    .ok_or(format!("type '{name}': an Item has no value"))?
                    .to_string(),
                description: i.attribute("description").map(str::to_string),
            })
        })
        .collect::<Result<_, String>>()?;
    Ok(EnumerationType {
        name: name.to_string(),
        description: t.attribute("description").map(str::to_string),
        items,
    })
}

fn variable(position: usize, sv: roxmltree::Node) -> Result<ScalarVariable, String> {
    let name = sv
        .attribute("name")
        .ok_or(format!("variable {position} has no name"))?;
    let at = |what: &str| format!("variable '{name}': {what}");
    let value_reference = sv
        .attribute("valueReference")
        .and_then(|v| v.parse().ok())
        .ok_or(at("missing or bad valueReference"))?;
    let ty = sv
        .children()
        .find(|n| n.is_element())
        .ok_or(at("no type element"))?;
    let own = |k: &str| sv.attribute(k).map(str::to_string);
    let typed = |k: &str| ty.attribute(k).map(str::to_string);
    Ok(ScalarVariable {
        name: name.to_string(),
        value_reference,
        description: own("description"),
        causality: own("causality").unwrap_or_else(|| "local".into()),
        variability: own("variability").unwrap_or_else(|| "continuous".into()),
        initial: own("initial"),
        kind: ty.tag_name().name().to_string(),
        start: typed("start"),
        min: typed("min"),
        max: typed("max"),
        unit: typed("unit"),
        display_unit: typed("displayUnit"),
        declared_type: typed("declaredType"),
        nominal: typed("nominal"),
        derivative: typed("derivative"),
        group: None,
    })
}

fn unknown(tag: &str, u: roxmltree::Node) -> Result<Unknown, String> {
    let text = u.attribute("index").unwrap_or("?");
    let index = text
        .parse()
        .map_err(|_| format!("<{tag}> has an Unknown with index '{text}'"))?;
    let dependencies = u
        .attribute("dependencies")
        .map(|deps| {
            deps.split_whitespace()
                .map(|d| {
                    d.parse()
                        .map_err(|_| format!("<{tag}> Unknown {index}: bad dependency '{d}'"))
                })
                .collect::<Result<Vec<usize>, String>>()
        })
        .transpose()?;
    Ok(Unknown {
        index,
        dependencies,
    })
}
