//! `hsp identify`: fits chosen parameters of the FMU to measured frequency responses and
//! resonance peaks, with 95 %
//! confidence intervals and a warning naming what the data cannot determine, and writes the
//! fitted configuration as an SSP parameter set (docs/identify.md). Split by job:
//! - [`data`]: the measured responses (`--frf`) and the fitted parameters (`--fit`), with their
//!   coordinates;
//! - [`peaks`]: measured resonance peaks (`--peaks`) and the model's peaks taken for them;
//! - [`series`]: measured time series (`--series`) and the FMU's simulation of them;
//! - [`residuals`]: the weighted residuals and their sensitivities;
//! - [`optimiser`]: the Levenberg–Marquardt solver;
//! - [`starts`]: multi-start (`--starts`), its points and the minima they reach;
//! - [`intervals`]: the intervals, correlations and identifiability warnings;
//! - [`report`]: the JSON, the text table and the `.ssv`;
//! - [`page`]: the markdown page with its Bode plots (`--report DIR`).
//!
//! Sensitivities are exact where the model gives them (dual numbers through its fragments),
//! central differences elsewhere and on request (`--sensitivities central`), each parameter's
//! way reported ([`residuals`], docs/identify.md).

mod data;
mod intervals;
mod optimiser;
mod page;
mod peaks;
mod report;
mod residuals;
mod series;
mod starts;

use std::path::Path;

use clap::Args;
use nalgebra::{DMatrix, DVector};

use data::{Fitted, Frf};
use optimiser::{LeastSquares, Stop, Tolerances};
use peaks::Peaks;
use residuals::Problem;
use series::Series;

#[derive(Args)]
pub struct IdentifyArgs {
    /// A measured frequency response, INPUT:OUTPUT:FILE.csv (repeatable): a CSV with a header
    /// and the columns f_Hz,re,im (the complex response of OUTPUT to INPUT in SI units) and
    /// optionally weight
    #[arg(
        long = "frf",
        value_name = "INPUT:OUTPUT:FILE.csv",
        required_unless_present_any = ["peaks", "series"]
    )]
    frf: Vec<String>,
    /// Measured resonance peaks of OUTPUT's response to INPUT, INPUT:OUTPUT:FILE.csv
    /// (repeatable): a CSV with a header and the columns f_Hz,sigma_Hz (each peak's frequency and
    /// its standard uncertainty); each is fitted by the model's peak nearest it
    #[arg(long = "peaks", value_name = "INPUT:OUTPUT:FILE.csv")]
    peaks: Vec<String>,
    /// A measured time series, FILE.csv (repeatable): a CSV with a header and the columns time
    /// (s) and any of the FMU's inputs (which drive it, held from row to row) and outputs (which
    /// are fitted)
    #[arg(long = "series", value_name = "FILE.csv")]
    series: Vec<String>,
    /// A parameter to fit, NAME or NAME:LOW:HIGH (repeatable); log-scaled where positive
    #[arg(long = "fit", value_name = "NAME[:LOW:HIGH]", required = true)]
    fit: Vec<String>,
    /// Write the starting configuration with the fitted values as an SSP 1.0 parameter set
    #[arg(long, value_name = "FILE.ssv")]
    out: Option<String>,
    /// Write a markdown page of the fit, DIR/index.md, with a Bode plot per measured response
    /// (measured, model at the start, fitted) and the residuals before and after
    #[arg(long, value_name = "DIR")]
    report: Option<String>,
    /// Print JSON: {"parameters": {NAME: {"value", "start", "ci95": [lo, hi] or null}}, "cost",
    /// "iterations", "correlations" (rows in the order of "fitted"), "fitted", "warnings", ...}
    #[arg(long)]
    json: bool,
    /// How the residuals' derivatives are computed: exact (dual numbers through the model, for
    /// the frequency responses of every parameter whose fragments carry them; central
    /// differences for the others, said in the report) or central (central differences for all,
    /// to cross-check or compare)
    #[arg(long, value_enum, default_value_t = residuals::Sensitivities::Exact)]
    sensitivities: residuals::Sensitivities,
    /// How a time series' derivatives are computed (with --sensitivities exact): central
    /// (central differences of the FMU's simulation) or forward (forward sensitivities
    /// integrated beside the states, exact to the integrator's tolerance, slower: docs/identify.md)
    #[arg(long, value_enum, default_value_t = residuals::SeriesSensitivities::Central)]
    series_sensitivities: residuals::SeriesSensitivities,
    /// The most Levenberg–Marquardt iterations (per start)
    #[arg(long, default_value_t = 200)]
    max_iterations: usize,
    /// Fit from N starting points and keep the lowest cost: the configuration's start and N - 1
    /// drawn in the --fit boxes (a Latin hypercube, log-uniform for positive parameters; every
    /// fitted parameter needs its box)
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    starts: u32,
    /// The seed of the drawn starting points (--starts)
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The starts run on this many threads [default: the machine's processors]
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    jobs: Option<u32>,
    /// Run start K (0 to N - 1) of --starts N alone and print where it ended as one JSON line,
    /// exact to the bit, for --ends (what tools/identify_dask.py runs on each Dask worker)
    #[arg(long, value_name = "K", conflicts_with_all = ["ends", "out", "report"])]
    start: Option<u32>,
    /// Take the ends of the --starts N from FILE (the JSON lines of --start K, one per start, in
    /// any order) instead of running them: the fit, its report and its minima are then those of
    /// the same starts run here
    #[arg(long, value_name = "FILE")]
    ends: Option<String>,
    /// The starting configuration: the FMU's start values, --preset, then --set
    #[command(flatten)]
    model: crate::ModelArgs,
}

/// The problem in the optimiser's unconstrained coordinates `t` (`data::Fitted::z_of_t`).
struct Unconstrained<'a>(&'a Problem);

impl Unconstrained<'_> {
    fn z(&self, t: &[f64]) -> Vec<f64> {
        self.0
            .fitted
            .iter()
            .zip(t)
            .map(|(f, &t)| f.z_of_t(t))
            .collect()
    }
}

impl LeastSquares for Unconstrained<'_> {
    fn residuals(&self, t: &[f64]) -> Result<DVector<f64>, String> {
        self.0.residuals_z(&self.z(t))
    }
    fn jacobian(&self, t: &[f64]) -> Result<DMatrix<f64>, String> {
        let mut jac = self.0.jacobian_z(&self.z(t))?;
        for (j, f) in self.0.fitted.iter().enumerate() {
            jac.column_mut(j).scale_mut(f.dz_dt(t[j]));
        }
        Ok(jac)
    }
}

/// The fit: the problem, the optimiser's outcome at `z`, the statistics.
pub struct Fit {
    pub problem: Problem,
    pub z: Vec<f64>,
    pub cost: f64,
    pub iterations: usize,
    pub stop: Stop,
    pub statistics: intervals::Statistics,
    /// Per measured response, the RMS weighted relative error at the start and fitted.
    pub rms: Vec<(f64, f64)>,
    /// Per `--peaks`, the model's peaks taken for the measured ones at the start and fitted.
    pub model_peaks: Vec<(Vec<f64>, Vec<f64>)>,
    /// With `--starts N > 1`: every start and where it ended (the fit is the best one's), and
    /// the distinct minima, lowest first.
    pub starts: Vec<starts::Start>,
    pub minima: Vec<starts::Minimum>,
}

impl Fit {
    /// The fitted values.
    pub fn values(&self) -> Vec<f64> {
        self.problem.p_of_z(&self.z)
    }

    /// `z` of the optimiser's coordinates `t`.
    pub fn z_of_t(&self, t: &[f64]) -> Vec<f64> {
        Unconstrained(&self.problem).z(t)
    }
}

/// Reads the data and the fitted parameters: the problem on the starting configuration.
fn problem(args: &IdentifyArgs) -> Result<Problem, String> {
    let base = args.model.values()?;
    let frfs = args
        .frf
        .iter()
        .map(|s| Frf::read(s))
        .collect::<Result<_, _>>()?;
    let peaks = args
        .peaks
        .iter()
        .map(|s| Peaks::read(s))
        .collect::<Result<_, _>>()?;
    let series = args
        .series
        .iter()
        .map(|s| Series::read(s))
        .collect::<Result<_, _>>()?;
    let fitted = args
        .fit
        .iter()
        .map(|s| Fitted::parse(s, &base))
        .collect::<Result<_, _>>()?;
    if (args.start.is_some() || args.ends.is_some()) && args.starts < 2 {
        return Err(
            "--start and --ends split the starts of --starts N (N > 1): give --starts".into(),
        );
    }
    Problem::new(
        base,
        frfs,
        peaks,
        series,
        fitted,
        args.sensitivities,
        args.series_sensitivities,
    )
}

/// Reads the data and fits.
fn fit(args: &IdentifyArgs) -> Result<Fit, String> {
    let problem = problem(args)?;
    let tolerances = tolerances(args);
    let unconstrained = Unconstrained(&problem);
    let (out, all_starts, minima) = if args.starts > 1 {
        let z0s = starts::points(&problem.fitted, args.starts as usize, args.seed)?;
        let jobs = args.jobs.map_or_else(
            || std::thread::available_parallelism().map_or(1, |n| n.get()),
            |n| n as usize,
        );
        let all = match &args.ends {
            Some(file) => starts::read_ends(file, z0s)?,
            None => starts::run(&unconstrained, z0s, tolerances, jobs),
        };
        let best = starts::best(&all).ok_or_else(|| {
            let why = all.iter().find_map(|s| s.end.as_ref().err());
            format!(
                "the model failed at every start{}",
                why.map_or(String::new(), |w| format!(" (the first: {w})"))
            )
        })?;
        let minima = starts::minima(&all, |t| unconstrained.z(t));
        let out = all[best].end.clone()?;
        (out, all, minima)
    } else {
        // One start, the configuration's: the same run, without the list of starts and minima.
        let z0 = problem.fitted.iter().map(|f| f.z_of(f.start)).collect();
        let mut one = starts::run(&unconstrained, vec![z0], tolerances, 1);
        (one.remove(0).end?, Vec::new(), Vec::new())
    };
    let z = unconstrained.z(&out.t);
    let jac = problem.jacobian_z(&z)?;
    let mut statistics = intervals::statistics(
        &problem.fitted,
        &z,
        &jac,
        out.cost,
        problem.known_variance(),
    )?;
    if out.stop == Stop::Iterations {
        statistics.warnings.insert(
            0,
            format!(
                "not converged in {} iterations (--max-iterations): the values and intervals \
                 are those of the last point",
                out.iterations
            ),
        );
    }
    if let Some(best) = minima.first() {
        let failed = all_starts.iter().filter(|s| s.end.is_err()).count();
        if best.reached == 1 && all_starts.len() > 1 {
            statistics.warnings.push(format!(
                "the lowest cost was reached from 1 of {} starts ({} distinct minima): a lower \
                 one may exist; more --starts or a narrower box would tell",
                all_starts.len(),
                minima.len()
            ));
        }
        if failed > 0 {
            statistics.warnings.push(format!(
                "the model failed at {failed} of {} starting points (listed in the starts)",
                all_starts.len()
            ));
        }
    }
    let start: Vec<f64> = problem.fitted.iter().map(|f| f.start).collect();
    let fitted_values = problem.p_of_z(&z);
    let rms = problem
        .rms(&start)?
        .into_iter()
        .zip(problem.rms(&fitted_values)?)
        .collect();
    let model_peaks = if problem.peaks.is_empty() {
        Vec::new()
    } else {
        problem
            .model_peaks(&start)?
            .into_iter()
            .zip(problem.model_peaks(&fitted_values)?)
            .collect()
    };
    Ok(Fit {
        problem,
        z,
        cost: out.cost,
        iterations: out.iterations,
        stop: out.stop,
        statistics,
        rms,
        model_peaks,
        starts: all_starts,
        minima,
    })
}

/// The optimiser's tolerances of the command.
fn tolerances(args: &IdentifyArgs) -> Tolerances {
    Tolerances {
        iterations: args.max_iterations,
        ..Tolerances::default()
    }
}

/// `--start K`: runs start K of `--starts N` alone and prints where it ended as one JSON line
/// ([`starts::end_line`]).
fn run_start(args: &IdentifyArgs, k: usize) -> Result<(), String> {
    let problem = problem(args)?;
    let z0s = starts::points(&problem.fitted, args.starts as usize, args.seed)?;
    let z0 = z0s
        .get(k)
        .cloned()
        .ok_or_else(|| format!("--start {k}: the starts are 0 to {}", z0s.len() - 1))?;
    let mut one = starts::run(&Unconstrained(&problem), vec![z0], tolerances(args), 1);
    println!("{}", starts::end_line(k, &one.remove(0).end));
    Ok(())
}

/// The starting configuration in words, for the report page.
fn starting(model: &crate::ModelArgs) -> String {
    let mut s = match &model.preset {
        Some(p) => format!("the FMU's start values with the preset {p}"),
        None => "the FMU's start values".to_string(),
    };
    if !model.set.is_empty() {
        s.push_str(&format!(", then --set {}", model.set.join(", ")));
    }
    s
}

pub fn main(args: &IdentifyArgs) -> Result<(), String> {
    if let Some(k) = args.start {
        return run_start(args, k as usize);
    }
    let fit = fit(args)?;
    if args.json {
        // The text table ends with them; the JSON holds them, and a reader of the terminal sees
        // them here.
        for w in &fit.statistics.warnings {
            eprintln!("hsp: warning: {w}");
        }
    }
    if let Some(file) = &args.out {
        std::fs::write(file, report::parameter_set(&fit, file)?)
            .map_err(|e| format!("{file}: {e}"))?;
        if !args.json {
            println!("wrote {file}");
        }
    }
    if let Some(dir) = &args.report {
        let written = page::write(&fit, &starting(&args.model), Path::new(dir))?;
        if !args.json {
            for p in written {
                println!("wrote {}", p.display());
            }
        }
    }
    if args.json {
        println!("{}", report::json(&fit));
    } else {
        print!("{}", report::text(&fit));
    }
    Ok(())
}
