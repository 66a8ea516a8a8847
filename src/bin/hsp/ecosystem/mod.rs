//! The FMI ecosystem's own formats, written into the FMUs by `hsp package` and into the
//! repository by `hsp ssp`:
//! - [`ls_ref`]: the folder of the FMI layered standard for references
//!   (`extra/org.fmi-standard.fmi-ls-ref/`): its manifest, the default experiment's result and
//!   the presets' parameter sets, and its page `documentation/fmi-ls-ref.html`;
//! - [`ls_wasm`]: the folder of the draft layered standard for WebAssembly
//!   (`extra/org.modelica.fmi-ls-wasm/`), in the FMI 3.0 FMU when it carries the component;
//! - [`result`]: the default experiment's result, every output, in each FMU's layout;
//! - [`ssp`]: the presets of `src/model/presets.rs` as SSP 1.0 parameter sets (`.ssv`) and an
//!   example SSP system (`.ssd`, and the `.ssp` archive with the FMU);
//! - [`icon`]: a small picture of the rig, `model.png` (FMI 2.0) and `terminalsAndIcons/icon.png`
//!   (FMI 3.0);
//! - [`terminals`]: FMI 3.0's `terminalsAndIcons/terminalsAndIcons.xml`, the FMU's signals
//!   grouped as the rig's plugs.
//!
//! `docs/ecosystem.md` describes each file and the tests that check it.

pub mod icon;
pub mod ls_ref;
pub mod ls_wasm;
pub mod result;
pub mod ssp;
pub mod terminals;

/// A file of an archive: its name inside it and its bytes.
pub type Entry = (String, Vec<u8>);

/// The `<ModelVariables>` element of the parsed FMI 3.0 model description `doc` (the project's
/// reader, `tools/model_description.rs`, reads FMI 2.0 only).
fn fmi3_model_variables<'a>(
    doc: &'a roxmltree::Document<'a>,
) -> Result<roxmltree::Node<'a, 'a>, String> {
    doc.root_element()
        .children()
        .find(|n| n.has_tag_name("ModelVariables"))
        .ok_or_else(|| "FMI 3.0 XML: no <ModelVariables>".to_string())
}

/// What both FMUs carry beside the model description and binaries: the manifest and the
/// parameter sets in `extra/` and `documentation/fmi-ls-ref.html`. `xml` is the FMI 2.0 model
/// description (its default experiment names the settings).
pub fn extra(xml: &str) -> Result<Vec<Entry>, String> {
    ls_ref::entries(xml)
}

/// What only the FMI 2.0 FMU carries: `model.png` at the archive's root and the result in its
/// layout (one column per scalar output), from `recorded`.
pub fn fmi2_only(recorded: &result::Recorded) -> Result<Vec<Entry>, String> {
    Ok(vec![
        ("model.png".into(), icon::png()?),
        ls_ref::result_entry(recorded.fmi2_csv()),
    ])
}

/// What only the FMI 3.0 FMU carries: `terminalsAndIcons/` with the icon and the terminals, and
/// the result in its layout (an array one column), from `recorded`. `xml3` is the FMI 3.0 model
/// description, whose variables the terminals and the result's columns name.
pub fn fmi3_only(xml3: &str, recorded: &result::Recorded) -> Result<Vec<Entry>, String> {
    Ok(vec![
        ("terminalsAndIcons/icon.png".into(), icon::png()?),
        (
            "terminalsAndIcons/terminalsAndIcons.xml".into(),
            terminals::xml(xml3)?.into_bytes(),
        ),
        ls_ref::result_entry(recorded.fmi3_csv(xml3)?),
    ])
}
