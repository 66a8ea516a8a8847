//! The folder of the draft FMI layered standard for WebAssembly, fmi-ls-wasm
//! (<https://github.com/modelica/fmi-ls-wasm>), in the FMI 3.0 FMU when it carries the component
//! `binaries/wasm32-wasip2/HydraulicSlewingPlate.wasm`: `extra/org.modelica.fmi-ls-wasm/manifest.xml`,
//! the manifest the draft requires, in FMI 3.0's layered-standard manifest form (the root
//! `fmiLayeredStandardManifest` with the `fmi-ls:` name, version and description attributes).

use super::Entry;

/// The layered standard's name, which is also its folder under `extra/`.
pub const NAME: &str = "org.modelica.fmi-ls-wasm";

/// The draft's version the component follows. The draft has no release yet; its text gives
/// "0.1.0" as the form of this attribute, and its WIT package is `fmi:fmi3@3.0.0`.
pub const VERSION: &str = "0.1.0";

/// The manifest's path in the FMU.
pub fn manifest_path() -> String {
    format!("extra/{NAME}/manifest.xml")
}

/// The manifest.
pub fn manifest() -> String {
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
         <!-- Written by hsp package (src/bin/hsp/ecosystem/ls_wasm.rs); docs/platforms.md -->\n\
         <fmiLayeredStandardManifest\n    \
         xmlns:fmi-ls=\"http://fmi-standard.org/fmi-ls-manifest\"\n    \
         fmi-ls:fmi-ls-name=\"{NAME}\"\n    \
         fmi-ls:fmi-ls-version=\"{VERSION}\"\n    \
         fmi-ls:fmi-ls-description=\"FMI Layered Standard for WebAssembly\"/>\n"
    )
}

/// The folder's files, for an FMI 3.0 FMU that carries the component.
pub fn entries() -> Vec<Entry> {
    vec![(manifest_path(), manifest().into_bytes())]
}
