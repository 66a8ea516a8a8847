//! The presets as SSP 1.0 parameter sets, and an example SSP system.
//!
//! - `<preset>.ssv`: one `<ssv:ParameterSet>` per preset of `src/model/presets.rs` (the one
//!   definition), each setting typed as its FMU variable: `ssv:Real`, `ssv:Boolean`, and
//!   `ssv:Integer` for the Integers and for the switches (Integers in the FMI 2.0 description,
//!   Enumerations in the FMI 3.0 one, which sets them as integers too), with the item's name in
//!   a comment.
//! - `SystemStructure.ssd`: a system of one component, the FMU, with the parameter set of
//!   [`EXAMPLE`] bound to it, its inputs and main outputs as connectors of the component and of
//!   the system, connected, and a default experiment whose fixed communication step libcosim
//!   reads from its OSP annotation.
//! - `HydraulicSlewingPlate.ssp` (by `hsp package`, beside the FMUs): the `.ssd` with the FMI
//!   2.0 FMU and the parameter set under `resources/`.
//!
//! `hsp ssp` writes the `.ssd` and the `.ssv` files into `ssp/` of the repository (as the
//! archive lays them out: `ssp/SystemStructure.ssd`, `ssp/resources/*.ssv`);
//! `tests/ssp_files.rs` checks that the committed files are what it writes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use hydraulic_slewing_plate::model::presets::{Preset, PRESETS};
use hydraulic_slewing_plate::model::variables::{MODEL_IDENTIFIER, VARIABLES};

use super::Entry;
pub use crate::docpage::text::escape;

/// The preset the example system binds: the complete system and its 30 deg move, the FMU's
/// defaults (so that fmpy's SSP runner, which does not apply a system's parameter bindings,
/// runs the same model). Every shipped set applies in libcosim and ecos
/// (`tests/python/test_shipped_sets.py` binds each in turn).
pub const EXAMPLE: &str = "complete";

/// The example system's communication step and stop time, s.
const EXAMPLE_STEP: f64 = 0.01;
const EXAMPLE_STOP: f64 = 6.0;

/// The connectors of the example's component: (name, kind).
const CONNECTORS: &[(&str, &str)] = &[
    ("r", "input"),
    ("e_in", "input"),
    ("F1", "input"),
    ("F2", "input"),
    ("y_pot", "output"),
    ("theta_motor", "output"),
    ("p_load", "output"),
    ("theta_hub", "output"),
    ("acc_tip", "output"),
];

/// The file name of a preset's parameter set.
pub fn file_name(p: &Preset) -> String {
    format!("{}.ssv", p.name)
}

/// A preset as an SSP 1.0 parameter set (`.ssv`).
pub fn parameter_set(p: &Preset) -> Result<String, String> {
    parameter_set_of(
        p.name,
        &format!("{}: {}", p.paper, p.description),
        "hsp ssp from src/model/presets.rs; docs/ecosystem.md",
        p.settings.iter().copied(),
    )
    .map_err(|e| format!("preset {}: {e}", p.name))
}

/// The writer of SSP 1.0 parameter sets is the library's (the browser page writes them too).
pub use hydraulic_slewing_plate::model::parameter_set::{parameter_set_of, SSV_NS};

/// The `(NAME, VALUE)` settings of an SSP 1.0 parameter set (`.ssv`) in its order, each value as
/// its typed element (`ssv:Real`, `ssv:Integer`, `ssv:Boolean`, `ssv:String`) gives it: what
/// [`parameter_set_of`] writes, for `hsp run --ssv`. An error names a parameter without a typed
/// value; whether the names and values fit the FMU is for its set calls to say.
pub fn read_parameter_set(text: &str) -> Result<Vec<(String, String)>, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| e.to_string())?;
    let root = doc.root_element();
    if !root.has_tag_name((SSV_NS, "ParameterSet")) {
        return Err(format!(
            "not an SSP parameter set: the root is <{}>, not <ssv:ParameterSet> of {SSV_NS}",
            root.tag_name().name()
        ));
    }
    let parameters = root
        .children()
        .filter(|n| n.has_tag_name((SSV_NS, "Parameters")));
    let mut settings = Vec::new();
    for p in parameters
        .flat_map(|n| n.children())
        .filter(|n| n.is_element())
    {
        let name = p
            .attribute("name")
            .ok_or("an <ssv:Parameter> without a name")?;
        let value = p
            .children()
            .find(|n| {
                n.is_element()
                    && ["Real", "Integer", "Boolean", "String"]
                        .iter()
                        .any(|t| n.has_tag_name((SSV_NS, *t)))
            })
            .and_then(|n| n.attribute("value"))
            .ok_or_else(|| format!("parameter {name}: no typed value"))?;
        settings.push((name.to_string(), value.to_string()));
    }
    Ok(settings)
}

/// The two forms of the example system: SSP's own, whose system exposes the component's
/// connectors (fmpy's SSP runner needs every input connected), and the one libcosim 0.0.6 and
/// ecos 0.7.2 read, without system connectors (both refuse a connection without a
/// `startElement`: `No such node (<xmlattr>.startElement)`, `No element named: `).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// `SystemStructure.ssd` of `HydraulicSlewingPlate.ssp`: inputs and outputs at the system.
    Exposed,
    /// `osp/SystemStructure.ssd`, of `HydraulicSlewingPlate-osp.ssp`: the component alone.
    Osp,
}

impl Form {
    pub const ALL: [Form; 2] = [Form::Exposed, Form::Osp];

    /// The `.ssd`'s path in the repository's `ssp/`.
    pub fn ssd(self) -> &'static str {
        match self {
            Form::Exposed => "SystemStructure.ssd",
            Form::Osp => "osp/SystemStructure.ssd",
        }
    }
}

/// The example system, `SystemStructure.ssd`, in the given form.
pub fn system_description(form: Form) -> Result<String, String> {
    let p = PRESETS
        .iter()
        .find(|p| p.name == EXAMPLE)
        .ok_or_else(|| format!("no preset {EXAMPLE}"))?;
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    s.push_str("<!-- Written by hsp ssp (src/bin/hsp/ecosystem/ssp.rs); docs/ecosystem.md -->\n");
    writeln!(
        s,
        "<ssd:SystemStructureDescription version=\"1.0\" name=\"{MODEL_IDENTIFIER}-{EXAMPLE}\"\n    \
         xmlns:ssd=\"http://ssp-standard.org/SSP1/SystemStructureDescription\"\n    \
         xmlns:ssc=\"http://ssp-standard.org/SSP1/SystemStructureCommon\"\n    \
         xmlns:osp=\"http://opensimulationplatform.com/SSP/OSPAnnotations\">"
    )
    .unwrap();
    writeln!(
        s,
        "  <ssd:System name=\"rig\" description=\"{}\">",
        escape(&format!(
            "The hydraulic slewing plate with the parameter set {EXAMPLE} ({}: {})",
            p.paper, p.description
        ))
    )
    .unwrap();
    // The component's connectors again at the system's level, each connected to the
    // component's: a tool that runs the system (fmpy's SSP runner needs every input connected)
    // drives its inputs and reads its outputs there.
    let exposed = form == Form::Exposed;
    if exposed {
        s.push_str("    <ssd:Connectors>\n");
        for (name, kind) in CONNECTORS {
            writeln!(
                s,
                "      <ssd:Connector name=\"{name}\" kind=\"{kind}\"><ssc:Real/></ssd:Connector>"
            )
            .unwrap();
        }
        s.push_str("    </ssd:Connectors>\n");
    }
    s.push_str("    <ssd:Elements>\n");
    writeln!(
        s,
        "      <ssd:Component name=\"plate\" type=\"application/x-fmu-sharedlibrary\" \
         source=\"resources/{MODEL_IDENTIFIER}.fmu\">"
    )
    .unwrap();
    s.push_str("        <ssd:Connectors>\n");
    for (name, kind) in CONNECTORS {
        if !VARIABLES.iter().any(|v| v.name == *name) {
            return Err(format!("no variable {name}"));
        }
        writeln!(
            s,
            "          <ssd:Connector name=\"{name}\" kind=\"{kind}\"><ssc:Real/></ssd:Connector>"
        )
        .unwrap();
    }
    s.push_str("        </ssd:Connectors>\n");
    s.push_str("        <ssd:ParameterBindings>\n");
    writeln!(
        s,
        "          <ssd:ParameterBinding type=\"application/x-ssp-parameter-set\" \
         source=\"resources/{}\"/>",
        file_name(p)
    )
    .unwrap();
    s.push_str("        </ssd:ParameterBindings>\n      </ssd:Component>\n");
    s.push_str("    </ssd:Elements>\n");
    if exposed {
        s.push_str("    <ssd:Connections>\n");
        for (name, kind) in CONNECTORS {
            let (start, end) = if *kind == "input" {
                ("", " endElement=\"plate\"")
            } else {
                (" startElement=\"plate\"", "")
            };
            writeln!(
                s,
                "      <ssd:Connection{start} startConnector=\"{name}\"{end} endConnector=\"{name}\"/>"
            )
            .unwrap();
        }
        s.push_str("    </ssd:Connections>\n");
    }
    s.push_str("  </ssd:System>\n");
    writeln!(
        s,
        "  <ssd:DefaultExperiment startTime=\"0\" stopTime=\"{EXAMPLE_STOP}\">\n    \
         <ssd:Annotations>\n      \
         <ssc:Annotation type=\"com.opensimulationplatform\">\n        \
         <osp:Algorithm><osp:FixedStepAlgorithm baseStepSize=\"{EXAMPLE_STEP}\"/></osp:Algorithm>\n      \
         </ssc:Annotation>\n    </ssd:Annotations>\n  </ssd:DefaultExperiment>"
    )
    .unwrap();
    s.push_str("</ssd:SystemStructureDescription>\n");
    Ok(s)
}

/// The repository's `ssp/` files, by their path inside it (the archive's layout).
pub fn files() -> Result<Vec<(String, String)>, String> {
    let mut files = Vec::new();
    for form in Form::ALL {
        files.push((form.ssd().to_string(), system_description(form)?));
    }
    for p in PRESETS {
        files.push((format!("resources/{}", file_name(p)), parameter_set(p)?));
    }
    Ok(files)
}

/// `hsp ssp`: writes [`files`] into `dir`; returns the paths written.
pub fn write(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut written = Vec::new();
    for (name, text) in files()? {
        let path = dir.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
        }
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}

/// The entries of the example `.ssp` archive: the system, the FMU and the example's parameter
/// set.
pub fn archive(fmu: Vec<u8>, form: Form) -> Result<Vec<Entry>, String> {
    let p = PRESETS
        .iter()
        .find(|p| p.name == EXAMPLE)
        .ok_or_else(|| format!("no preset {EXAMPLE}"))?;
    Ok(vec![
        (
            "SystemStructure.ssd".into(),
            system_description(form)?.into_bytes(),
        ),
        (format!("resources/{MODEL_IDENTIFIER}.fmu"), fmu),
        (
            format!("resources/{}", file_name(p)),
            parameter_set(p)?.into_bytes(),
        ),
    ])
}

#[cfg(test)]
mod parameter_set_tests {
    use super::*;

    /// Every preset's parameter set reads back as the preset's settings, in order.
    #[test]
    fn a_written_parameter_set_reads_back_as_its_settings() {
        for p in PRESETS {
            let read = read_parameter_set(&parameter_set(p).unwrap()).unwrap();
            let want: Vec<(String, String)> = p
                .settings
                .iter()
                .map(|(n, v)| (n.to_string(), v.to_string()))
                .collect();
            assert_eq!(read, want, "{}", p.name);
        }
        let e = read_parameter_set("<a/>").unwrap_err();
        assert!(e.contains("not an SSP parameter set"), "{e}");
    }
}
