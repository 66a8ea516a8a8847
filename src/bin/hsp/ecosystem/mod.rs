//! The FMI ecosystem's own formats, written into the FMUs by `hsp package` and into the
//! repository by `hsp ssp`:
//! - [`ls_ref`]: the reference results of the default experiment in the layout of the FMI
//!   layered standard for references (`extra/org.fmi-standard.fmi-ls-ref/`), with the presets'
//!   parameter sets listed beside them;
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
pub mod ssp;
pub mod terminals;

/// A file of an archive: its name inside it and its bytes.
pub type Entry = (String, Vec<u8>);

/// What both FMUs carry beside the model description and binaries: the reference results and
/// the parameter sets in `extra/`. `csv` is the default experiment's result (`hsp run`'s CSV) and
/// `xml` the FMI 2.0 model description (its default experiment names the settings).
pub fn extra(csv: Vec<u8>, xml: &str) -> Result<Vec<Entry>, String> {
    ls_ref::entries(csv, xml)
}

/// What only the FMI 2.0 FMU carries: `model.png` at the archive's root.
pub fn fmi2_only() -> Result<Vec<Entry>, String> {
    Ok(vec![("model.png".into(), icon::png()?)])
}

/// What only the FMI 3.0 FMU carries: `terminalsAndIcons/` with the icon and the terminals.
/// `xml3` is the FMI 3.0 model description, whose variables the terminals name.
pub fn fmi3_only(xml3: &str) -> Result<Vec<Entry>, String> {
    Ok(vec![
        ("terminalsAndIcons/icon.png".into(), icon::png()?),
        (
            "terminalsAndIcons/terminalsAndIcons.xml".into(),
            terminals::xml(xml3)?.into_bytes(),
        ),
    ])
}
