//! The documentation page itself: the template `page.html` filled with the model description's
//! facts, the figures' captions and the tables.

use std::fmt::Write as _;

use super::figures::BOND_GRAPH_FIGURE;
use super::tables;
use super::text::{escape, short_text};
use crate::model_description::{get, ModelDescription};

/// The page, with `{{name}}` where a value goes (see [`fill`]).
const TEMPLATE: &str = include_str!("page.html");

/// The paper the model reproduces, in full.
pub const PAPER: &str = "E. G. Barbosa and L. C. S. G&oacute;es, <em>Modeling system of a \
    flexible structure with hydraulic actuation using bond-graphs</em>, Proceedings of the II \
    National Congress of Mechanical Engineering (CONEM 2002), Jo&atilde;o Pessoa, Brazil, \
    August 2002. Instituto Tecnol&oacute;gico de Aeron&aacute;utica (ITA), S&atilde;o Jos&eacute; \
    dos Campos.";

/// The paragraph on external control, for a model with the input `e_in`.
const EXTERNAL: &str =
    "<h3>External control</h3>\n<p>Set the parameter <code>controller.external = true</code> \
    before initialisation and the input <code>e_in</code> [V] drives the servo valve's coil \
    in place of the built-in analog controller, so that your own controller (Simulink, \
    Modelica, Python) closes the loop on the outputs <code>y_pot</code>, \
    <code>theta_hub</code>, the torsion-bar torque and the accelerometers.</p>\n";

/// The section on the browser page, for an FMU that carries it in `documentation/web/`.
const WEB: &str = "<h2>Try it in the browser</h2>\n<p><a href=\"web/index.html\">The model live</a>: \
    this FMU's model and its integrator compiled to WebAssembly, in an interactive page (in \
    <code>documentation/web/</code> beside this page). Choose a preset, change the move, the loop \
    gains, the torsion bar, the damping or the motor, and watch the hub, the potentiometer, the \
    pressures and the plate bend, at real time or as fast as the browser goes. It runs offline; \
    nothing leaves your machine.</p>\n\n";

/// The page: `md` is the FMU's model description, `platforms` the `binaries/` folders of the FMI 2.0
/// and of the FMI 3.0 FMU (both carry the page), `summary` what `hsp run` printed for the default
/// experiment, `bode_caption` the Bode plot's caption, `web` whether the FMU carries the browser
/// page (`documentation/web/`; not when the toolchain lacks the WebAssembly target).
pub fn page(
    md: &ModelDescription,
    platforms: [&[String]; 2],
    summary: &str,
    bode_caption: &str,
    web: bool,
) -> Result<String, String> {
    let attr = |k: &str| escape(md.attribute(k).unwrap_or("?"));
    let model = attr("modelName");
    let mut capabilities = String::new();
    for (k, v) in md.co_simulation.iter().flatten() {
        if k != "modelIdentifier" {
            write!(capabilities, "<code>{k}=\"{}\"</code> ", escape(v)).unwrap();
        }
    }
    // The plate modes Model Exchange declares states for (x.plate.I[k].p, k = 1, 2, ...).
    let me_plate_modes = md
        .variables
        .iter()
        .filter(|v| v.name.starts_with("x.plate.I["))
        .count();
    let interfaces = if md.model_exchange.is_some() {
        "Co-Simulation and Model Exchange"
    } else {
        "Co-Simulation only (the FMU carries its own stiff solver)"
    };
    let folders = |list: &[String]| {
        list.iter()
            .map(|p| {
                let what = match p.as_str() {
                    "linux64" | "x86_64-linux" => "x86-64 Linux",
                    "aarch64-linux" => "aarch64 Linux",
                    "win64" | "x86_64-windows" => "x86-64 Windows 10 or later",
                    "darwin64" => "macOS, one universal binary for x86-64 and Apple silicon",
                    "x86_64-darwin" => "x86-64 macOS",
                    "aarch64-darwin" => "Apple silicon macOS",
                    _ => "",
                };
                let name = format!("<code>{}</code>", escape(p));
                if what.is_empty() {
                    name
                } else {
                    format!("{name} ({what})")
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let platform_list = format!(
        "FMI 2.0 FMU: {}. FMI 3.0 FMU: {}.",
        folders(platforms[0]),
        folders(platforms[1])
    );
    let de = |k: &str| {
        md.default_experiment
            .as_deref()
            .and_then(|d| get(d, k))
            .map(short_text)
    };
    let default_experiment = format!(
        "start {} s, stop {} s, step {} s, tolerance {}",
        de("startTime").unwrap_or_else(|| "0".into()),
        de("stopTime").unwrap_or_else(|| "?".into()),
        de("stepSize").unwrap_or_else(|| "?".into()),
        de("tolerance").unwrap_or_else(|| "?".into()),
    );
    let external = if has(md, "e_in") { EXTERNAL } else { "" };
    let fmu_version = attr("version");
    let guid = attr("guid");
    let fmi_version = attr("fmiVersion");
    let generation_tool = attr("generationTool");
    let today = date();
    let summary = escape(summary);
    let bond_graph_settings = BOND_GRAPH_FIGURE
        .iter()
        .map(|(k, v)| format!("<code>{k} = {v}</code>"))
        .collect::<Vec<_>>()
        .join(", ");
    fill(
        TEMPLATE,
        &[
            ("model", &model),
            ("fmi_version", &fmi_version),
            ("interfaces", interfaces),
            ("paper", PAPER),
            ("fmu_version", &fmu_version),
            ("today", &today),
            ("capabilities", &capabilities),
            ("platforms", &platform_list),
            ("default_experiment", &default_experiment),
            ("guid", &guid),
            ("generation_tool", &generation_tool),
            ("bond_graph_settings", &bond_graph_settings),
            ("summary", &summary),
            ("bode_caption", bode_caption),
            ("me_plate_modes", &me_plate_modes.to_string()),
            ("presets", &tables::presets()),
            ("external", external),
            ("web", if web { WEB } else { "" }),
            ("tables", &tables::variables(md)),
        ],
    )
}

/// `template` with each `{{name}}` replaced by the value of `name` in `values`, in one pass (a
/// value is not searched for placeholders). A name without a value is an error.
fn fill(template: &str, values: &[(&str, &str)]) -> Result<String, String> {
    let mut out = String::with_capacity(template.len());
    let mut rest = template;
    while let Some(at) = rest.find("{{") {
        out.push_str(&rest[..at]);
        let after = &rest[at + 2..];
        let end = after
            .find("}}")
            .ok_or("page template: a {{ without its }}")?;
        let name = &after[..end];
        let value = values
            .iter()
            .find(|(k, _)| *k == name)
            .ok_or_else(|| format!("page template: no value for {{{{{name}}}}}"))?
            .1;
        out.push_str(value);
        rest = &after[end + 2..];
    }
    out.push_str(rest);
    Ok(out)
}

/// Today's date (UTC), or that of `SOURCE_DATE_EPOCH` for reproducible packages.
fn date() -> String {
    let secs = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.parse::<i64>().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_secs() as i64)
                .unwrap_or(0)
        });
    // Days to civil date (H. Hinnant's algorithm).
    let z = secs.div_euclid(86_400) + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

fn has(md: &ModelDescription, name: &str) -> bool {
    md.variables.iter().any(|v| v.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_template_is_filled_in_one_pass() {
        let values = [("a", "1 {{b}}"), ("b", "2")];
        assert_eq!(fill("x{{a}}y{{b}}z{", &values).unwrap(), "x1 {{b}}y2z{");
        assert!(fill("{{c}}", &values).is_err());
        assert!(fill("{{a", &values).is_err());
    }

    #[test]
    fn every_placeholder_of_the_page_has_a_value() {
        let xml = include_str!("../../../../modelDescription/modelDescription.xml");
        let md = ModelDescription::parse(xml).unwrap();
        let page = page(
            &md,
            [&["linux64".into()], &["x86_64-linux".into()]],
            "summary",
            "caption",
            true,
        )
        .unwrap();
        assert!(!page.contains("{{"), "a placeholder is left");
        assert!(page.contains("href=\"web/index.html\""));
        let without = page_without_web(&md);
        assert!(!without.contains("{{") && !without.contains("web/index.html"));
        assert!(page.contains(md.attribute("guid").unwrap()));
        assert!(page.contains("<h3>Parameters</h3>"));
    }

    fn page_without_web(md: &ModelDescription) -> String {
        page(md, [&[], &[]], "summary", "caption", false).unwrap()
    }

    #[test]
    fn dates_are_civil() {
        std::env::set_var("SOURCE_DATE_EPOCH", "951782400"); // 2000-02-29
        assert_eq!(date(), "2000-02-29");
        std::env::remove_var("SOURCE_DATE_EPOCH");
    }
}
