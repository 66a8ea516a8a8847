//! What `hsp identify` writes: the JSON (`--json`), the text table, and the fitted
//! configuration as an SSP 1.0 parameter set (`--out FILE.ssv`, by the writer of `hsp ssp`).

use std::fmt::Write as _;
use std::sync::atomic::Ordering;

use hydraulic_slewing_plate::fmu::{Causality, Value, Variability};
use hydraulic_slewing_plate::model::variables::VARIABLES;
use serde_json::json;

use super::residuals::Method;
use super::Fit;
use crate::ecosystem::ssp::parameter_set_of;

/// `{"parameters": {NAME: {"value", "start", "ci95": [lo, hi] or null}}, "cost", "iterations",
/// "correlations", "fitted", "warnings", "residuals", "variance", "evaluations", "stop",
/// "sensitivities", "responses", "peaks"}`: the
/// correlations' rows and columns in the order of `fitted` (the `--fit` order), `null` for a
/// parameter the data do not see; `cost` is the sum of the squared weighted residuals, of which
/// there are `residuals`; `variance` is the residual variance `s^2`; `evaluations` counts the
/// model's linearisations, `derivatives` the exact derivatives of one with respect to one
/// parameter; `sensitivities` says how they were computed (and each parameter's
/// `sensitivity`, with a `sensitivity_reason` where it was central differences); `responses` gives, per
/// `--frf` in order, the RMS of the weighted relative error `|e_k|` at the start and fitted;
/// `peaks`, per `--peaks` in order, the measured peaks, their uncertainties and the model's peaks
/// taken for them at the start and fitted. With `--starts N > 1`, also `starts` (each start's
/// `start` and `value` by parameter, `cost`, `iterations`, `stop`, or its `error`) and `minima`
/// (the distinct minima, lowest cost first: the index of the best start that reached each,
/// `reached`, the number of starts that did, and `cost`).
pub fn json(fit: &Fit) -> serde_json::Value {
    let values = fit.values();
    let methods = fit.problem.methods();
    let mut parameters = serde_json::Map::new();
    for (j, f) in fit.problem.fitted.iter().enumerate() {
        let mut entry = json!({
            "value": values[j],
            "start": f.start,
            "ci95": fit.statistics.ci95[j].map(|(lo, hi)| [lo, hi]),
        });
        match &methods[j] {
            Method::Exact => entry["sensitivity"] = json!("exact"),
            Method::CentralDifferences(why) => {
                entry["sensitivity"] = json!("central differences");
                entry["sensitivity_reason"] = json!(why);
            }
        }
        parameters.insert(f.name.clone(), entry);
    }
    let mut out = json!({
        "parameters": parameters,
        "cost": fit.cost,
        "iterations": fit.iterations,
        "correlations": fit.statistics.correlations,
        "fitted": fit.problem.fitted.iter().map(|f| &f.name).collect::<Vec<_>>(),
        "warnings": fit.statistics.warnings,
        "residuals": fit.problem.len(),
        "variance": fit.statistics.variance,
        "evaluations": fit.problem.evaluations.load(Ordering::Relaxed),
        "derivatives": fit.problem.derivatives.load(Ordering::Relaxed),
        "stop": format!("{:?}", fit.stop).to_lowercase(),
        "sensitivities": sensitivities(fit),
        "responses": fit.problem.frfs.iter().zip(&fit.rms).map(|(d, (before, after))| json!({
            "input": d.input,
            "output": d.output,
            "file": d.file,
            "points": d.f_hz.len(),
            "rms_start": before,
            "rms_fitted": after,
        })).collect::<Vec<_>>(),
        "peaks": fit.problem.peaks.iter().zip(&fit.model_peaks).map(|(d, (before, after))| json!({
            "input": d.input,
            "output": d.output,
            "file": d.file,
            "measured_Hz": d.f_hz,
            "sigma_Hz": d.sigma_hz,
            "start_Hz": before,
            "fitted_Hz": after,
        })).collect::<Vec<_>>(),
    });
    if !fit.starts.is_empty() {
        out["starts"] = fit
            .starts
            .iter()
            .map(|s| {
                let by_name = |z: &[f64]| -> serde_json::Map<String, serde_json::Value> {
                    let p = fit.problem.p_of_z(z);
                    fit.problem
                        .fitted
                        .iter()
                        .zip(p)
                        .map(|(f, v)| (f.name.clone(), json!(v)))
                        .collect()
                };
                match &s.end {
                    Ok(end) => json!({
                        "start": by_name(&s.z0),
                        "value": by_name(&fit.z_of_t(&end.t)),
                        "cost": end.cost,
                        "iterations": end.iterations,
                        "stop": format!("{:?}", end.stop).to_lowercase(),
                    }),
                    Err(e) => json!({"start": by_name(&s.z0), "error": e}),
                }
            })
            .collect();
        out["minima"] = fit
            .minima
            .iter()
            .map(|m| {
                json!({
                    "start": m.start,
                    "reached": m.reached,
                    "cost": fit.starts[m.start].end.as_ref().map_or(f64::NAN, |e| e.cost),
                })
            })
            .collect();
    }
    out
}

/// How the sensitivities were computed, in words: exact (dual numbers through the model) for
/// the parameters that had them, central differences for the others
/// ([`super::residuals::Problem::methods`]).
pub fn sensitivities(fit: &Fit) -> String {
    let methods = fit.problem.methods();
    let names = |exact: bool| -> Vec<&str> {
        fit.problem
            .fitted
            .iter()
            .zip(&methods)
            .filter(|(_, m)| (**m == Method::Exact) == exact)
            .map(|(f, _)| f.name.as_str())
            .collect()
    };
    let differences = if fit.problem.series.is_empty() {
        "central differences of the exact linearisation"
    } else {
        "central differences of the exact linearisation and of the simulation"
    };
    let exactly = if fit.problem.series.is_empty() {
        "exact (dual numbers)"
    } else {
        "exact (dual numbers; forward sensitivities of the simulation)"
    };
    match (names(true), names(false)) {
        (exact, fd) if fd.is_empty() => format!("{exactly} for {}", exact.join(", ")),
        (exact, fd) if exact.is_empty() => format!("{differences} for {}", fd.join(", ")),
        (exact, fd) => format!(
            "{exactly} for {}; {differences} for {}",
            exact.join(", "),
            fd.join(", ")
        ),
    }
}

/// The table of the fit and its warnings.
pub fn text(fit: &Fit) -> String {
    let values = fit.values();
    let mut s = format!(
        "hsp identify: {} fitted, {} residuals, cost {:.6e} after {} iterations ({} model \
         evaluations)\n{:<28} {:>14} {:>14} {:>30}\n",
        values.len(),
        fit.problem.len(),
        fit.cost,
        fit.iterations,
        fit.problem.evaluations.load(Ordering::Relaxed),
        "parameter",
        "start",
        "fitted",
        "95 % interval"
    );
    for (j, f) in fit.problem.fitted.iter().enumerate() {
        let ci = fit.statistics.ci95[j].map_or("none".to_string(), |(lo, hi)| {
            format!("[{lo:.6e}, {hi:.6e}]")
        });
        writeln!(
            s,
            "{:<28} {:>14.6e} {:>14.6e} {ci:>30}",
            f.name, f.start, values[j]
        )
        .unwrap();
    }
    writeln!(s, "sensitivities: {}", sensitivities(fit)).unwrap();
    for (f, m) in fit.problem.fitted.iter().zip(fit.problem.methods()) {
        if let Method::CentralDifferences(why) = m {
            writeln!(s, "  {}: central differences ({why})", f.name).unwrap();
        }
    }
    for (d, (before, after)) in fit.problem.peaks.iter().zip(&fit.model_peaks) {
        writeln!(
            s,
            "peaks of {} to {} ({}):\n{:>14} {:>14} {:>14} {:>14}",
            d.output, d.input, d.file, "measured [Hz]", "sigma [Hz]", "start [Hz]", "fitted [Hz]"
        )
        .unwrap();
        for k in 0..d.f_hz.len() {
            writeln!(
                s,
                "{:>14} {:>14} {:>14.4} {:>14.4}",
                d.f_hz[k], d.sigma_hz[k], before[k], after[k]
            )
            .unwrap();
        }
    }
    if !fit.minima.is_empty() {
        writeln!(
            s,
            "{} starts ended in {} distinct minima (lowest cost first):",
            fit.starts.len(),
            fit.minima.len()
        )
        .unwrap();
        let names: Vec<&str> = fit.problem.fitted.iter().map(|f| f.name.as_str()).collect();
        writeln!(
            s,
            "{:>14} {:>8} {:>10} {}",
            "cost",
            "reached",
            "stop",
            names.join("  ")
        )
        .unwrap();
        for m in &fit.minima {
            if let Ok(end) = &fit.starts[m.start].end {
                let p = fit.problem.p_of_z(&fit.z_of_t(&end.t));
                let p: Vec<String> = p.iter().map(|v| format!("{v:.6e}")).collect();
                let stop = format!("{:?}", end.stop).to_lowercase();
                writeln!(
                    s,
                    "{:>14.6e} {:>8} {stop:>10} {}",
                    end.cost,
                    m.reached,
                    p.join("  ")
                )
                .unwrap();
            }
        }
        for st in &fit.starts {
            if let Err(e) = &st.end {
                writeln!(s, "a start failed: {e}").unwrap();
            }
        }
    }
    for w in &fit.statistics.warnings {
        writeln!(s, "warning: {w}").unwrap();
    }
    s
}

/// Every parameter of the FMU in the fitted configuration (the starting one with the fitted
/// values) as an SSP 1.0 parameter set named after `file`'s stem.
pub fn parameter_set(fit: &Fit, file: &str) -> Result<String, String> {
    let values = fit.problem.values_at(&fit.values())?;
    let settings: Vec<(&str, String)> = VARIABLES
        .iter()
        .enumerate()
        .filter(|(_, v)| {
            v.causality == Causality::Parameter && v.variability != Variability::Constant
        })
        .map(|(i, v)| {
            let text = match values.get(i) {
                Value::Real(x) => format!("{x:?}"),
                Value::Integer(n) => n.to_string(),
                Value::Boolean(b) => b.to_string(),
                Value::String(t) => t.clone(),
            };
            (v.name, text)
        })
        .collect();
    let name = std::path::Path::new(file)
        .file_stem()
        .map_or("identified".into(), |s| s.to_string_lossy().into_owned());
    let fitted: Vec<&str> = fit.problem.fitted.iter().map(|f| f.name.as_str()).collect();
    parameter_set_of(
        &name,
        &format!("fitted by hsp identify: {}", fitted.join(", ")),
        "hsp identify; docs/identify.md",
        settings.iter().map(|(n, v)| (*n, v.as_str())),
    )
}
