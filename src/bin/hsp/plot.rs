//! Plots of `hsp`: the time histories of `hsp run`, the Bode plot of `hsp frf --plot` and the mode
//! shapes of `hsp modes --plot`, drawn with `plotters` into PNG and SVG.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (plotters' `ab_glyph` backend), so a
//! machine without system fonts still gets labels. Every figure is written by one generic drawing
//! function per kind, called once for the bitmap and once for the SVG backend, so both files
//! show the same thing.

use std::path::{Path, PathBuf};
use std::sync::Once;

use clap::Args;
use nalgebra::Complex;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

/// `--no-plot` of `hsp run`.
#[derive(Args, Clone, Debug, Default)]
pub struct PlotArgs {
    /// Do not write the PNG and SVG plots beside the CSV
    #[arg(long)]
    pub no_plot: bool,
}

/// Table 1 of the paper, second column: the resonance peaks of its FRF from the reference `r` to
/// the plate tip (Fig. 9b), Hz. Drawn as reference marks on Bode plots from `r` to a plate signal.
pub use hydraulic_slewing_plate::model::paper::TABLE1_FRF_HZ;

const FONT: &str = "sans-serif";
const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// Registers the embedded font under the family name the figures use (once per process).
fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font is a valid TrueType file; a failure here is a build defect.
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .map_err(|_| ())
            .expect("the embedded DejaVu Sans font is valid");
    });
}

fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("plot: {e:?}")
}

/// One curve: legend, values.
pub struct Series {
    pub name: String,
    pub values: Vec<f64>,
}

/// One subplot of a time-history figure: its axis label (with unit) and curves.
pub struct Panel {
    pub label: String,
    pub series: Vec<Series>,
}

/// Writes `stem.png` and `stem.svg` with `draw` on each backend; returns both paths.
fn write_both(
    stem: &Path,
    size: (u32, u32),
    png_then_svg: (
        impl Fn(DrawingArea<BitMapBackend, Shift>) -> Result<(), String>,
        impl Fn(DrawingArea<SVGBackend, Shift>) -> Result<(), String>,
    ),
) -> Result<Vec<PathBuf>, String> {
    register_font();
    if let Some(dir) = stem.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
    }
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    (png_then_svg.0)(BitMapBackend::new(&png, size).into_drawing_area())
        .map_err(|e| format!("{}: {e}", png.display()))?;
    (png_then_svg.1)(SVGBackend::new(&svg, size).into_drawing_area())
        .map_err(|e| format!("{}: {e}", svg.display()))?;
    Ok(vec![png, svg])
}

/// The range of the finite values of some series, padded by 5 % (a flat signal gets a unit-wide
/// band so that the axis still has ticks).
fn padded_range<'a>(values: impl Iterator<Item = &'a f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - pad, hi + pad);
    }
    (lo - 0.05 * span, hi + 0.05 * span)
}

fn draw_time<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    title: &str,
    t: &[f64],
    panels: &[Panel],
) -> Result<(), String> {
    area.fill(&WHITE).map_err(err)?;
    let area = area.titled(title, (FONT, 22)).map_err(err)?;
    let t0 = t.first().copied().unwrap_or(0.0);
    let t1 = t.last().copied().filter(|&v| v > t0).unwrap_or(t0 + 1.0);
    let rows = area.split_evenly((panels.len().max(1), 1));
    for (i, (panel, sub)) in panels.iter().zip(rows.iter()).enumerate() {
        let last = i + 1 == panels.len();
        let (lo, hi) = padded_range(panel.series.iter().flat_map(|s| s.values.iter()));
        let mut chart = ChartBuilder::on(sub)
            .margin(6)
            .margin_right(16)
            .x_label_area_size(if last { 40 } else { 18 })
            .y_label_area_size(80)
            .build_cartesian_2d(t0..t1, lo..hi)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(if last { "time [s]" } else { "" })
            .y_desc(panel.label.as_str())
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 14))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(err)?;
        for (k, s) in panel.series.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            chart
                .draw_series(LineSeries::new(
                    decimate(t, &s.values, MAX_POINTS),
                    color.stroke_width(2),
                ))
                .map_err(err)?
                .label(s.name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .label_font((FONT, 13))
            .draw()
            .map_err(err)?;
    }
    area.present().map_err(err)
}

/// Most points drawn per curve: beyond it a curve keeps the extremes of each of `MAX_POINTS / 2`
/// time buckets, which looks the same at figure resolution and keeps the SVG small.
const MAX_POINTS: usize = 3000;

/// The finite points of `(t, y)`, reduced to the minimum and maximum of each bucket (in time
/// order) when there are more than `max` of them.
fn decimate(t: &[f64], y: &[f64], max: usize) -> Vec<(f64, f64)> {
    let points: Vec<(f64, f64)> = t
        .iter()
        .zip(y)
        .filter(|(_, v)| v.is_finite())
        .map(|(a, b)| (*a, *b))
        .collect();
    if points.len() <= max {
        return points;
    }
    let per_bucket = points.len().div_ceil(max / 2);
    let mut out = Vec::with_capacity(max);
    for bucket in points.chunks(per_bucket) {
        let lo = bucket.iter().min_by(|a, b| a.1.total_cmp(&b.1)).copied();
        let hi = bucket.iter().max_by(|a, b| a.1.total_cmp(&b.1)).copied();
        if let (Some(lo), Some(hi)) = (lo, hi) {
            if lo.0 <= hi.0 {
                out.extend([lo, hi]);
            } else {
                out.extend([hi, lo]);
            }
        }
    }
    out
}

/// A figure of time histories, one panel under the other: writes `stem.png` and `stem.svg`.
pub fn time_histories(
    stem: &Path,
    title: &str,
    t: &[f64],
    panels: &[Panel],
) -> Result<Vec<PathBuf>, String> {
    if panels.is_empty() {
        return Err(format!("{}: nothing to plot", stem.display()));
    }
    let size = (1000, 170 * panels.len() as u32 + 80);
    write_both(
        stem,
        size,
        (
            |a| draw_time(a, title, t, panels),
            |a| draw_time(a, title, t, panels),
        ),
    )
}

/// How `hsp run`'s CSV columns are shown: column, panel, scale from SI, legend.
const CHANNELS: &[(&str, usize, f64, &str)] = &[
    ("controller.reference", 0, 1.0, "reference (r + move)"),
    ("y_pot", 0, 1.0, "potentiometer y_pot"),
    ("e_in", 0, 1.0, "coil drive e_in"),
    ("theta_motor", 1, 180.0 / std::f64::consts::PI, "motor"),
    ("theta_hub", 1, 180.0 / std::f64::consts::PI, "hub"),
    ("w_tip", 2, 1e3, "tip deflection w_tip"),
    ("p_load", 3, 1e-5, "load p_load"),
    ("servo_valve.p_1", 3, 1e-5, "chamber p_1"),
    ("servo_valve.p_2", 3, 1e-5, "chamber p_2"),
    ("servo_valve.x_v", 4, 1e3, "spool x_v"),
    ("q_valve", 5, 6e4, "valve flow q_valve"),
];
const PANEL_LABELS: [&str; 6] = [
    "command [V]",
    "angle [deg]",
    "tip deflection [mm]",
    "pressure [bar]",
    "spool position [mm]",
    "flow [L/min]",
];

/// A results table read from CSV: the header and the columns.
pub struct Table {
    pub names: Vec<String>,
    pub columns: Vec<Vec<f64>>,
}

impl Table {
    /// Reads a CSV of numbers with a header line (what `hsp run` writes).
    pub fn read_csv(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut lines = text.lines();
        let names: Vec<String> = lines
            .next()
            .ok_or_else(|| format!("{}: empty", path.display()))?
            .split(',')
            .map(|s| s.trim().to_string())
            .collect();
        let mut columns = vec![Vec::new(); names.len()];
        for (k, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
            let fields: Vec<&str> = line.split(',').collect();
            if fields.len() != names.len() {
                return Err(format!(
                    "{}: line {} has {} fields, the header {}",
                    path.display(),
                    k + 2,
                    fields.len(),
                    names.len()
                ));
            }
            for (c, f) in columns.iter_mut().zip(fields) {
                c.push(
                    f.trim()
                        .parse::<f64>()
                        .map_err(|e| format!("{}: line {}: '{f}': {e}", path.display(), k + 2))?,
                );
            }
        }
        Ok(Table { names, columns })
    }

    /// The column of a name.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.columns[i].as_slice())
    }
}

/// The panels of a results table: the known columns grouped by quantity, in display units.
pub fn experiment_panels(table: &Table) -> Vec<Panel> {
    let mut panels: Vec<Panel> = PANEL_LABELS
        .iter()
        .map(|l| Panel {
            label: l.to_string(),
            series: Vec::new(),
        })
        .collect();
    for &(name, panel, scale, legend) in CHANNELS {
        if let Some(c) = table.column(name) {
            panels[panel].series.push(Series {
                name: legend.to_string(),
                values: c.iter().map(|v| v * scale).collect(),
            });
        }
    }
    // The flow only when the spool is not recorded (the LOES has no spool).
    if !panels[4].series.is_empty() {
        panels[5].series.clear();
    }
    // A signal that stays at zero beside others (e_in when the built-in controller drives, the
    // spool of the LOES) only clutters its panel.
    for p in &mut panels {
        if p.series.iter().any(|s| s.values.iter().any(|v| *v != 0.0)) {
            p.series.retain(|s| s.values.iter().any(|v| *v != 0.0));
        }
    }
    panels.retain(|p| !p.series.is_empty());
    panels
}

/// The figures of an `hsp run` results file: `<csv stem>.png` and `.svg` beside it.
pub fn experiment(csv: &Path, title: &str) -> Result<Vec<PathBuf>, String> {
    let table = Table::read_csv(csv)?;
    let t = table
        .column("time")
        .ok_or_else(|| format!("{}: no time column", csv.display()))?;
    time_histories(
        &csv.with_extension(""),
        title,
        t,
        &experiment_panels(&table),
    )
}

/// `hsp run`'s hook: the figures of the results unless `--no-plot`; prints where they are.
pub fn after_run(csv: &Path, args: &PlotArgs) -> Result<(), String> {
    if args.no_plot {
        return Ok(());
    }
    let stem = csv
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("results");
    let paths = experiment(csv, &format!("Hydraulic slewing plate: {stem}"))?;
    let shown: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    println!("  plots   {}", shown.join(", "));
    Ok(())
}

/// What a Bode plot shows.
pub struct Bode<'a> {
    pub title: String,
    pub f_hz: &'a [f64],
    pub magnitude: &'a [f64],
    pub phase_deg: &'a [f64],
    /// Resonance peaks (f, |H|), marked and labelled.
    pub peaks: &'a [(f64, f64)],
    /// Reference frequencies drawn as dashed vertical lines, with their legend.
    pub reference: Option<(&'a str, &'a [f64])>,
}

/// A panel of a Bode plot: a log-frequency axis and a labelled y axis.
type BodePanel<'a, DB> = ChartContext<'a, DB, Cartesian2d<LogCoord<f64>, RangedCoordf64>>;

/// A Bode panel over the frequencies `f`; the lower panel carries the frequency axis' label.
fn bode_panel<'a, DB: DrawingBackend>(
    on: &'a DrawingArea<DB, Shift>,
    f: (f64, f64),
    y: std::ops::Range<f64>,
    y_desc: &str,
    lower: bool,
) -> Result<BodePanel<'a, DB>, String> {
    let mut chart = ChartBuilder::on(on)
        .margin(6)
        .margin_right(20)
        .x_label_area_size(if lower { 40 } else { 18 })
        .y_label_area_size(70)
        .build_cartesian_2d((f.0..f.1).log_scale(), y)
        .map_err(err)?;
    let mut mesh = chart.configure_mesh();
    if lower {
        mesh.x_desc("frequency [Hz]");
    }
    mesh.y_desc(y_desc)
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    Ok(chart)
}

/// The frequency span of a Bode plot's grid (a degenerate grid gets a decade).
fn frequency_span(f_hz: &[f64]) -> (f64, f64) {
    let f0 = f_hz.first().copied().unwrap_or(1.0);
    let f1 = f_hz
        .last()
        .copied()
        .filter(|&f| f > f0)
        .unwrap_or(f0 * 10.0);
    (f0, f1)
}

/// The legend of a Bode panel.
fn legend_box<'a, DB: DrawingBackend + 'a>(
    chart: &mut BodePanel<'a, DB>,
    position: SeriesLabelPosition,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .label_font((FONT, 13))
        .draw()
        .map_err(err)
}

fn draw_bode<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, b: &Bode) -> Result<(), String> {
    area.fill(&WHITE).map_err(err)?;
    let area = area.titled(&b.title, (FONT, 22)).map_err(err)?;
    let (top, bottom) = area.split_vertically((55).percent());
    let (f0, f1) = frequency_span(b.f_hz);
    let db: Vec<f64> = b
        .magnitude
        .iter()
        .map(|m| 20.0 * m.max(1e-300).log10())
        .collect();
    let (lo, hi) = padded_range(db.iter());
    let phase = unwrap_degrees(b.phase_deg);
    let (plo, phi) = padded_range(phase.iter());
    let gray = RGBColor(120, 120, 120);

    let top_of_range = hi + 0.08 * (hi - lo);
    let mut mag = bode_panel(&top, (f0, f1), lo..top_of_range, "magnitude [dB]", false)?;
    if let Some((legend, fs)) = b.reference {
        for (k, &f) in fs.iter().filter(|f| (f0..=f1).contains(*f)).enumerate() {
            let series = mag
                .draw_series(DashedLineSeries::new(
                    [(f, lo), (f, hi)],
                    6,
                    4,
                    gray.stroke_width(1),
                ))
                .map_err(err)?;
            if k == 0 {
                series.label(legend).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], gray.stroke_width(1))
                });
            }
        }
    }
    mag.draw_series(LineSeries::new(
        b.f_hz.iter().zip(&db).map(|(f, m)| (*f, *m)),
        COLORS[0].stroke_width(2),
    ))
    .map_err(err)?
    .label("|H|")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], COLORS[0].stroke_width(2)));
    let red = COLORS[1];
    mag.draw_series(b.peaks.iter().map(|&(f, m)| {
        let y = 20.0 * m.max(1e-300).log10();
        EmptyElement::at((f, y))
            + Circle::new((0, 0), 4, red.filled())
            + Text::new(format!("{f:.2} Hz"), (5, -16), (FONT, 12))
    }))
    .map_err(err)?
    .label("resonance peaks")
    .legend(move |(x, y)| Circle::new((x + 9, y), 4, red.filled()));
    legend_box(&mut mag, SeriesLabelPosition::LowerLeft)?;

    let mut ph = bode_panel(&bottom, (f0, f1), plo..phi, "phase [deg]", true)?;
    ph.draw_series(LineSeries::new(
        b.f_hz.iter().zip(&phase).map(|(f, p)| (*f, *p)),
        COLORS[0].stroke_width(2),
    ))
    .map_err(err)?;
    area.present().map_err(err)
}

/// The phase made continuous: jumps of more than 180 degrees between neighbours are taken as
/// wraps of 360 degrees.
fn unwrap_degrees(phase: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(phase.len());
    let mut shift = 0.0;
    for (i, &p) in phase.iter().enumerate() {
        if i > 0 {
            let d = p - phase[i - 1];
            shift -= 360.0 * (d / 360.0).round();
        }
        out.push(p + shift);
    }
    out
}

/// A Bode plot: writes `stem.png` and `stem.svg`.
pub fn bode(stem: &Path, b: &Bode) -> Result<Vec<PathBuf>, String> {
    write_both(
        stem,
        (1000, 700),
        (|a| draw_bode(a, b), |a| draw_bode(a, b)),
    )
}

/// A figure drawn into an SVG document held in memory (the validation report compares it with
/// the committed file, so it is written and checked from the same bytes).
fn svg_string(
    size: (u32, u32),
    draw: impl Fn(DrawingArea<SVGBackend, Shift>) -> Result<(), String>,
) -> Result<String, String> {
    register_font();
    let mut out = String::new();
    draw(SVGBackend::with_string(&mut out, size).into_drawing_area())?;
    Ok(out)
}

/// A Bode plot as an SVG document.
pub fn bode_svg(b: &Bode) -> Result<String, String> {
    svg_string((1000, 700), |a| draw_bode(a, b))
}

/// One curve of a comparison Bode plot: `|H|` (linear) and phase \[deg\] on the plot's grid.
pub struct BodeCurve {
    pub name: String,
    pub magnitude: Vec<f64>,
    pub phase_deg: Vec<f64>,
    /// Drawn dashed (a reference drawn over a model curve stays visible).
    pub dashed: bool,
}

impl BodeCurve {
    /// The curve of the complex response `h`.
    pub fn of_complex(name: &str, h: &[Complex<f64>], dashed: bool) -> BodeCurve {
        BodeCurve {
            name: name.into(),
            magnitude: h.iter().map(|z| z.norm()).collect(),
            phase_deg: h.iter().map(|z| z.arg().to_degrees()).collect(),
            dashed,
        }
    }
}

/// Several frequency responses on one Bode plot.
pub struct BodeComparison<'a> {
    pub title: String,
    pub f_hz: &'a [f64],
    pub curves: Vec<BodeCurve>,
}

fn draw_curve<DB: DrawingBackend>(
    chart: &mut BodePanel<'_, DB>,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
    legend: Option<&str>,
) -> Result<(), String> {
    let style = color.stroke_width(if dashed { 2 } else { 3 });
    let anno = if dashed {
        chart
            .draw_series(DashedLineSeries::new(points, 8, 5, style))
            .map_err(err)?
    } else {
        chart
            .draw_series(LineSeries::new(points, style))
            .map_err(err)?
    };
    if let Some(name) = legend {
        anno.label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
    }
    Ok(())
}

fn draw_bode_comparison<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    b: &BodeComparison,
) -> Result<(), String> {
    area.fill(&WHITE).map_err(err)?;
    let area = area.titled(&b.title, (FONT, 22)).map_err(err)?;
    let (top, bottom) = area.split_vertically((55).percent());
    let (f0, f1) = frequency_span(b.f_hz);
    let db: Vec<Vec<f64>> = b
        .curves
        .iter()
        .map(|c| {
            c.magnitude
                .iter()
                .map(|m| 20.0 * m.max(1e-300).log10())
                .collect()
        })
        .collect();
    let phase: Vec<Vec<f64>> = b
        .curves
        .iter()
        .map(|c| unwrap_degrees(&c.phase_deg))
        .collect();
    let (lo, hi) = padded_range(db.iter().flatten());
    let (plo, phi) = padded_range(phase.iter().flatten());
    let mut mag = bode_panel(&top, (f0, f1), lo..hi, "magnitude [dB]", false)?;
    for (k, (c, m)) in b.curves.iter().zip(&db).enumerate() {
        let points = b.f_hz.iter().copied().zip(m.iter().copied()).collect();
        draw_curve(
            &mut mag,
            points,
            COLORS[k % COLORS.len()],
            c.dashed,
            Some(&c.name),
        )?;
    }
    legend_box(&mut mag, SeriesLabelPosition::LowerLeft)?;
    let mut ph = bode_panel(&bottom, (f0, f1), plo..phi, "phase [deg]", true)?;
    for (k, (c, p)) in b.curves.iter().zip(&phase).enumerate() {
        let points = b.f_hz.iter().copied().zip(p.iter().copied()).collect();
        draw_curve(&mut ph, points, COLORS[k % COLORS.len()], c.dashed, None)?;
    }
    area.present().map_err(err)
}

/// Several frequency responses on one Bode plot, as an SVG document.
pub fn bode_comparison_svg(b: &BodeComparison) -> Result<String, String> {
    svg_string((1000, 700), |a| draw_bode_comparison(a, b))
}

/// One group of points of an agreement plot: `(paper, model, label)` in Hz.
pub struct AgreementGroup {
    pub name: String,
    pub points: Vec<(f64, f64, String)>,
}

fn draw_agreement<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    title: &str,
    groups: &[AgreementGroup],
) -> Result<(), String> {
    area.fill(&WHITE).map_err(err)?;
    let area = area.titled(title, (FONT, 20)).map_err(err)?;
    let all = || groups.iter().flat_map(|g| g.points.iter());
    let lo = all().map(|p| p.0.min(p.1)).fold(f64::INFINITY, f64::min) / 1.5;
    let hi = all().map(|p| p.0.max(p.1)).fold(0.0, f64::max) * 1.5;
    let (lo, hi) = if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        (1.0, 100.0)
    };
    let mut chart = ChartBuilder::on(&area)
        .margin(10)
        .margin_right(30)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((lo..hi).log_scale(), (lo..hi).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("the paper's value [Hz]")
        .y_desc("the model's value [Hz]")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    let gray = RGBColor(120, 120, 120);
    chart
        .draw_series(DashedLineSeries::new(
            [(lo, lo), (hi, hi)],
            6,
            4,
            gray.stroke_width(1),
        ))
        .map_err(err)?
        .label("model = paper")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], gray.stroke_width(1)));
    for (k, g) in groups.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        chart
            .draw_series(g.points.iter().map(|(x, y, label)| {
                EmptyElement::at((*x, *y))
                    + Circle::new((0, 0), 5, color.filled())
                    + Text::new(label.clone(), (7, 2 + 14 * k as i32 - 14), (FONT, 12))
            }))
            .map_err(err)?
            .label(g.name.as_str())
            .legend(move |(x, y)| Circle::new((x + 9, y), 5, color.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .label_font((FONT, 13))
        .draw()
        .map_err(err)?;
    area.present().map_err(err)
}

/// The model's values against the paper's on log-log axes (the diagonal is agreement), as an
/// SVG document.
pub fn agreement_svg(title: &str, groups: &[AgreementGroup]) -> Result<String, String> {
    svg_string((900, 800), |a| draw_agreement(a, title, groups))
}

/// Blue (-1) through white (0) to red (+1).
fn diverging(v: f64) -> RGBColor {
    let v = v.clamp(-1.0, 1.0);
    let mix = |a: f64, b: f64, t: f64| (a + (b - a) * t).round() as u8;
    if v < 0.0 {
        let t = -v;
        RGBColor(
            mix(255.0, 33.0, t),
            mix(255.0, 102.0, t),
            mix(255.0, 172.0, t),
        )
    } else {
        RGBColor(
            mix(255.0, 178.0, v),
            mix(255.0, 24.0, v),
            mix(255.0, 43.0, v),
        )
    }
}

fn draw_modes<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    title: &str,
    shapes: &[super::modeshape::ModeShape],
    columns: usize,
) -> Result<(), String> {
    area.fill(&WHITE).map_err(err)?;
    let area = area.titled(title, (FONT, 22)).map_err(err)?;
    let rows = shapes.len().div_ceil(columns);
    for (shape, cell) in shapes.iter().zip(area.split_evenly((rows, columns)).iter()) {
        let (nx, ny) = (shape.x.len(), shape.y.len());
        let (a, b) = (shape.x[nx - 1], shape.y[ny - 1]);
        let mut chart = ChartBuilder::on(cell)
            .caption(
                format!(
                    "({},{})  {:.2} Hz",
                    shape.label.0, shape.label.1, shape.f_hz
                ),
                (FONT, 16),
            )
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(0.0..a, 0.0..b)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x [m]")
            .y_desc("y [m]")
            .label_style((FONT, 11))
            .axis_desc_style((FONT, 12))
            .x_labels(4)
            .y_labels(3)
            .draw()
            .map_err(err)?;
        let (dx, dy) = (a / (nx - 1) as f64, b / (ny - 1) as f64);
        chart
            .draw_series((0..ny).flat_map(|iy| {
                (0..nx).map(move |ix| {
                    let (x0, y0) = (
                        (shape.x[ix] - dx / 2.0).max(0.0),
                        (shape.y[iy] - dy / 2.0).max(0.0),
                    );
                    let (x1, y1) = (
                        (shape.x[ix] + dx / 2.0).min(a),
                        (shape.y[iy] + dy / 2.0).min(b),
                    );
                    Rectangle::new([(x0, y0), (x1, y1)], diverging(shape.w[iy][ix]).filled())
                })
            }))
            .map_err(err)?;
    }
    area.present().map_err(err)
}

/// Mode shapes as colour maps, one per mode (red and blue: opposite deflections, white: nodal
/// lines), labelled (n,m) with the frequency: writes `stem.png` and `stem.svg`.
pub fn mode_shapes(
    stem: &Path,
    title: &str,
    shapes: &[super::modeshape::ModeShape],
) -> Result<Vec<PathBuf>, String> {
    if shapes.is_empty() {
        return Err("no elastic mode to draw".into());
    }
    let columns = shapes.len().min(3);
    let rows = shapes.len().div_ceil(columns) as u32;
    write_both(
        stem,
        (1100, 260 * rows + 60),
        (
            |a| draw_modes(a, title, shapes, columns),
            |a| draw_modes(a, title, shapes, columns),
        ),
    )
}

/// The stem of a `--plot FILE` argument: `FILE` without a `.png`/`.svg` extension (both are
/// written).
pub fn stem_of(file: &str) -> PathBuf {
    let p = PathBuf::from(file);
    match p.extension().and_then(|e| e.to_str()) {
        Some("png") | Some("svg") => p.with_extension(""),
        _ => p,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_the_extremes_in_time_order() {
        let t: Vec<f64> = (0..10_000).map(|i| i as f64 * 1e-3).collect();
        let y: Vec<f64> = t.iter().map(|t| (40.0 * t).sin() * (-t).exp()).collect();
        let d = decimate(&t, &y, 1000);
        assert!(d.len() <= 1000, "{}", d.len());
        assert!(d.windows(2).all(|w| w[0].0 <= w[1].0));
        let max = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(max(&mut d.iter().map(|p| p.1)), max(&mut y.iter().copied()));
        let short = decimate(&t[..10], &y[..10], 1000);
        assert_eq!(short.len(), 10);
    }

    #[test]
    fn padded_range_of_a_flat_signal_is_not_empty() {
        let (lo, hi) = padded_range([2.0, 2.0].iter());
        assert!(lo < 2.0 && hi > 2.0);
        assert_eq!(padded_range([].iter()), (-1.0, 1.0));
    }
}
