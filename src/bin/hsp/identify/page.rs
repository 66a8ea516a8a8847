//! `hsp identify --report DIR`: a markdown page of the fit, `DIR/index.md`, with one Bode plot
//! per measured response (`DIR/frf_K.svg`: the measurement, the model at the start and fitted)
//! and the tables of the parameters, the correlations, the residuals before and after and the
//! measured resonance peaks against the model's.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::Fit;
use crate::docpage::text::escape;
use crate::plot::{bode_comparison_svg, BodeComparison, BodeCurve};

/// A number as the page prints it.
fn num(x: f64) -> String {
    format!("{x:.6e}")
}

/// Writes the page and its figures into `dir` (created if missing); the paths written.
pub fn write(fit: &Fit, starting: &str, dir: &Path) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let problem = &fit.problem;
    let start: Vec<f64> = problem.fitted.iter().map(|f| f.start).collect();
    let values = fit.values();
    let (before, after) = (problem.responses(&start)?, problem.responses(&values)?);
    let mut written = Vec::new();
    let mut s = format!(
        "# hsp identify: {} fitted from {} measured responses, {} sets of peaks and {} time \
         series\n\n\
         Starting configuration: {}. Cost (sum of the squared weighted residuals) {} after {} \
         iterations (stop: {:?}), {} residuals, residual variance {}. Sensitivities: {} \
         (docs/identify.md).\n\n\
         | parameter | start | fitted | 95 % interval |\n| --- | ---: | ---: | ---: |\n",
        values.len(),
        problem.frfs.len(),
        problem.peaks.len(),
        problem.series.len(),
        escape(starting),
        num(fit.cost),
        fit.iterations,
        fit.stop,
        problem.len(),
        num(fit.statistics.variance),
        super::report::sensitivities(fit),
    );
    for (j, f) in problem.fitted.iter().enumerate() {
        let ci = fit.statistics.ci95[j].map_or("none".into(), |(lo, hi)| {
            format!("[{}, {}]", num(lo), num(hi))
        });
        writeln!(
            s,
            "| `{}` | {} | {} | {ci} |",
            f.name,
            num(f.start),
            num(values[j])
        )
        .unwrap();
    }
    s.push_str("\n## Warnings\n\n");
    if fit.statistics.warnings.is_empty() {
        s.push_str("None.\n");
    }
    for w in &fit.statistics.warnings {
        writeln!(s, "- {}", escape(w)).unwrap();
    }
    s.push_str("\n## Correlations\n\n|  |");
    for f in &problem.fitted {
        write!(s, " `{}` |", f.name).unwrap();
    }
    s.push_str("\n| --- |");
    s.push_str(&" ---: |".repeat(problem.fitted.len()));
    s.push('\n');
    for (f, row) in problem.fitted.iter().zip(&fit.statistics.correlations) {
        write!(s, "| `{}` |", f.name).unwrap();
        for c in row {
            write!(s, " {} |", c.map_or("–".into(), |c| format!("{c:.4}"))).unwrap();
        }
        s.push('\n');
    }
    s.push_str(
        "\n## Responses\n\nRMS of the weighted relative error `|e_k|` over each response's \
         points.\n\n| response | file | points | RMS at the start | RMS fitted |\n\
         | --- | --- | ---: | ---: | ---: |\n",
    );
    for (d, (rms_before, rms_after)) in problem.frfs.iter().zip(&fit.rms) {
        writeln!(
            s,
            "| {} → {} | `{}` | {} | {} | {} |",
            d.input,
            d.output,
            escape(&d.file),
            d.f_hz.len(),
            num(*rms_before),
            num(*rms_after)
        )
        .unwrap();
    }
    for (d, (start_hz, fitted_hz)) in problem.peaks.iter().zip(&fit.model_peaks) {
        write!(
            s,
            "\n### Peaks of {} → {} (`{}`)\n\n| measured [Hz] | sigma [Hz] | model at the start \
             [Hz] | model fitted [Hz] |\n| ---: | ---: | ---: | ---: |\n",
            d.input,
            d.output,
            escape(&d.file)
        )
        .unwrap();
        for k in 0..d.f_hz.len() {
            writeln!(
                s,
                "| {} | {} | {:.4} | {:.4} |",
                d.f_hz[k], d.sigma_hz[k], start_hz[k], fitted_hz[k]
            )
            .unwrap();
        }
    }
    for (k, d) in problem.frfs.iter().enumerate() {
        let name = format!("frf_{}.svg", k + 1);
        let svg = bode_comparison_svg(&BodeComparison {
            title: format!("{} -> {}: measured, start, fitted", d.input, d.output),
            f_hz: &d.f_hz,
            curves: vec![
                BodeCurve::of_complex("model at the start", &before[k], false),
                BodeCurve::of_complex("model fitted", &after[k], false),
                BodeCurve::of_complex("measured", &d.h, true),
            ],
        })?;
        let path = dir.join(&name);
        std::fs::write(&path, svg).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(path);
        write!(
            s,
            "\n### {} → {}\n\n![{} -> {}: measured, start, fitted]({name})\n",
            d.input, d.output, d.input, d.output
        )
        .unwrap();
    }
    let index = dir.join("index.md");
    std::fs::write(&index, s).map_err(|e| format!("{}: {e}", index.display()))?;
    written.insert(0, index);
    Ok(written)
}
